"""docs/notebook.ipynb runs from top to bottom (nbclient, the venv's own kernel) and its
pictures are real: every image/png output decodes to the asked size and is not blank.

The binary is ``$LOUDSCAPE_BIN`` as for the other tests here (``target/debug/loudscape``).
"""

from __future__ import annotations

import base64
import io
import os
from pathlib import Path

import nbformat
import numpy as np
import pytest
from nbclient import NotebookClient
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "docs" / "notebook.ipynb"
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape"))


def test_the_example_notebook_runs_and_draws(monkeypatch):
    if not BINARY.is_file():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    monkeypatch.setenv("LOUDSCAPE_BIN", str(BINARY.resolve()))
    # The kernel imports this checkout's packages, whatever the venv has installed.
    path = os.pathsep.join(filter(None, [str(ROOT / "preprocess"), os.environ.get("PYTHONPATH")]))
    monkeypatch.setenv("PYTHONPATH", path)
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(
        notebook,
        timeout=300,
        kernel_name="python3",
        resources={"metadata": {"path": NOTEBOOK.parent}},
    ).execute()

    pictures = [
        output["data"]["image/png"]
        for cell in notebook.cells
        if cell.cell_type == "code"
        for output in cell.get("outputs", [])
        if "image/png" in output.get("data", {})
    ]
    assert len(pictures) == 3
    for encoded in pictures:
        with Image.open(io.BytesIO(base64.b64decode(encoded))) as image:
            pixels = np.asarray(image.convert("RGBA"))
        assert pixels.shape == (360, 640, 4)
        assert len(np.unique(pixels.reshape(-1, 4), axis=0)) > 100
    printed = "".join(
        output.get("text", "")
        for cell in notebook.cells
        if cell.cell_type == "code"
        for output in cell.get("outputs", [])
    )
    assert "(360, 640, 4) uint8" in printed
