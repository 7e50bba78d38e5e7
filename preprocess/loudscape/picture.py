"""A rendered picture: PNG bytes that Jupyter shows inline."""

from __future__ import annotations

import io
import os
from collections.abc import Sequence

import numpy as np

from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import write_atomically

__all__ = ["Picture"]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Picture:
    """A picture drawn by ``loudscape render``.

    Jupyter shows it inline (:meth:`_repr_png_`).

    Parameters
    ----------
    png : bytes
        The PNG file's bytes.
    warnings : sequence of str
        What was found wrong or odd about the input, ``"FILE: MESSAGE"`` each.

    Attributes
    ----------
    png : bytes
    width, height : int
        Size in pixels, from the PNG header.
    warnings : tuple of str
        The input's warnings (a truncated or corrupt file, cancelling channels...), each
        once; empty when there is nothing to say. :func:`loudscape.render` also raises each as
        a :class:`loudscape.LoudscapeWarning`.
    """

    def __init__(self, png: bytes, *, warnings: Sequence[str] = ()) -> None:
        if not png.startswith(PNG_SIGNATURE) or len(png) < 24 or png[12:16] != b"IHDR":
            raise ExtractError("the renderer's output is not a PNG file")
        self.png = bytes(png)
        self.warnings = tuple(str(text) for text in warnings)
        self.width = int.from_bytes(png[16:20], "big")
        self.height = int.from_bytes(png[20:24], "big")

    def __repr__(self) -> str:
        said = f", {len(self.warnings)} warning(s)" if self.warnings else ""
        return f"<loudscape.Picture {self.width}x{self.height}{said}>"

    def _repr_png_(self) -> bytes:
        return self.png

    def to_numpy(self) -> np.ndarray:
        """The pixels.

        Returns
        -------
        np.ndarray [shape=(height, width, 4), dtype=uint8]
            RGBA, rows from the top.
        """
        from PIL import Image

        with Image.open(io.BytesIO(self.png)) as image:
            return np.asarray(image.convert("RGBA"), dtype=np.uint8).copy()

    def save(self, path: str | os.PathLike) -> None:
        """Write the PNG file, atomically (a temporary file beside ``path``, then a rename).

        Parameters
        ----------
        path : str or os.PathLike
            A ``.png`` file; its folder must exist.

        Raises
        ------
        ExtractError
            ``path`` does not end in ``.png``, or cannot be written.
        """
        name = os.fspath(path)
        if not name.lower().endswith(".png"):
            raise ExtractError("a picture is saved as .png", path=name)
        write_atomically(name, [self.png])
