"""A rendered picture: PNG bytes that Jupyter shows inline."""

from __future__ import annotations

import io
import os

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

    Attributes
    ----------
    png : bytes
    width, height : int
        Size in pixels, from the PNG header.
    """

    def __init__(self, png: bytes) -> None:
        if not png.startswith(PNG_SIGNATURE) or len(png) < 24 or png[12:16] != b"IHDR":
            raise ExtractError("the renderer's output is not a PNG file")
        self.png = bytes(png)
        self.width = int.from_bytes(png[16:20], "big")
        self.height = int.from_bytes(png[20:24], "big")

    def __repr__(self) -> str:
        return f"<loudscape.Picture {self.width}x{self.height}>"

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
