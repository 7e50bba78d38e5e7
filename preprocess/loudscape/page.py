"""An interactive loudscape page for a notebook cell: the HTML ``loudscape page`` writes, shown
in an ``<iframe srcdoc>`` (no server, no file beside the notebook)."""

from __future__ import annotations

import html
import os
from collections.abc import Sequence

from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import write_atomically

__all__ = ["Page"]

#: The iframe's height in CSS pixels (its width is the cell's).
FRAME_HEIGHT = 600


class Page:
    """The song's web page (``loudscape page``): the app's viewer built for the web, with the
    cloud inside, in one self-contained HTML document.

    Jupyter shows it inline (:meth:`_repr_html_`): an ``<iframe>`` of fixed height whose
    ``srcdoc`` is the page, so the view turns in the cell without a server. The page needs a
    browser with WebGPU (current Chrome, Edge, Safari) and says so where there is none.

    Parameters
    ----------
    html : str
        The page, as ``loudscape page`` wrote it.
    warnings : sequence of str
        What was found wrong or odd about the input, ``"FILE: MESSAGE"`` each.

    Attributes
    ----------
    html : str
    warnings : tuple of str

    Examples
    --------
    >>> page = Page("<p>a & b</p>")
    >>> page._repr_html_()[:60]
    '<iframe srcdoc="&lt;p&gt;a &amp; b&lt;/p&gt;" style="width: '
    """

    def __init__(self, html: str, *, warnings: Sequence[str] = ()) -> None:
        self.html = str(html)
        self.warnings = tuple(str(text) for text in warnings)

    def __repr__(self) -> str:
        said = f", {len(self.warnings)} warning(s)" if self.warnings else ""
        return f"<loudscape.Page {len(self.html) / 1e6:.1f} MB{said}>"

    def _repr_html_(self) -> str:
        # Every character that could end the attribute or start markup is escaped (& < > " ').
        return (
            f'<iframe srcdoc="{html.escape(self.html, quote=True)}" '
            f'style="width: 100%; height: {FRAME_HEIGHT}px; border: 0" '
            'title="loudscape" allow="fullscreen"></iframe>'
        )

    def save(self, path: str | os.PathLike) -> None:
        """Write the page, atomically (a temporary file beside ``path``, then a rename).

        Parameters
        ----------
        path : str or os.PathLike
            A ``.html`` file; its folder must exist.

        Raises
        ------
        ExtractError
            ``path`` does not end in ``.html`` or ``.htm``, or cannot be written.
        """
        name = os.fspath(path)
        if not name.lower().endswith((".html", ".htm")):
            raise ExtractError("a page is saved as .html", path=name)
        write_atomically(name, [self.html.encode("utf-8")])
