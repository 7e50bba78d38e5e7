"""loudscape in Python: draw a loudscape in a notebook with the same renderer the app uses.

::

    import loudscape

    picture = loudscape.render("song.flac", view="surface")   # shown inline by Jupyter
    pixels = picture.to_numpy()                                # (H, W, 4) uint8
    cloud = loudscape.read_cloud("song.ply")                   # points and metadata
    loudscape.show(cloud)                                      # the window
    loudscape.show("song.ply", inline=True)                    # the view in the cell

Every picture is drawn by the ``loudscape render`` command (the binary installed with this
package, or a checkout's ``target/`` build): there is no second renderer. Audio is extracted by
``loudscape-extract``, installed beside it.

Errors: every function raises one exception type, :class:`ExtractError` (the extractor's),
whose message names the bad argument or file and the reason. Warnings: what is found wrong or
odd about an input (a truncated file, channels that cancel...) is raised as a
:class:`LoudscapeWarning` and kept on the picture (``picture.warnings``).
"""

from loudscape.api import Cloud, LoudscapeWarning, read_cloud, render, show
from loudscape.binary import find_binary
from loudscape.page import Page
from loudscape.picture import Picture
from loudscape_extract.errors import ExtractError
from loudscape_extract.version import __version__

__all__ = [
    "Cloud",
    "ExtractError",
    "LoudscapeWarning",
    "Page",
    "Picture",
    "__version__",
    "find_binary",
    "read_cloud",
    "render",
    "show",
]
