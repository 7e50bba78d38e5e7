"""``loudscape.show(song, inline=True)``: the song's web page (``loudscape page``) in a notebook
cell, as an ``<iframe srcdoc>``, without a server.

A stand-in viewer (``$LOUDSCAPE_WEB_DIR``) keeps these tests free of the wasm build (``make
web``); its glue holds every character the iframe's attribute must escape. The page turning in
a real browser is tests/web/test_page.py.
"""

from __future__ import annotations

import base64
import gzip
import os
import re
import tempfile
from html.parser import HTMLParser
from pathlib import Path

import pytest

import loudscape
from loudscape_extract import ExtractError, read_ply

ROOT = Path(__file__).resolve().parents[2]
SONG = ROOT / "data" / "demo_song.ply"
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape")).absolute()
WASM = b"\0asm\x01\0\0\0 stand-in viewer"
GLUE = "/* stand-in glue: \"quoted\" & 'single' <b>bold</b> &amp; </p> */ var wasm_bindgen;"


@pytest.fixture(autouse=True)
def _binary(monkeypatch, tmp_path):
    if not BINARY.is_file():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    monkeypatch.setenv("LOUDSCAPE_BIN", str(BINARY))
    # Temporary folders go here, so the tests see that none is left behind.
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    return scratch


@pytest.fixture
def viewer(monkeypatch, tmp_path) -> Path:
    web = tmp_path / "web"
    web.mkdir()
    (web / "loudscape_bg.wasm").write_bytes(WASM)
    (web / "loudscape.js").write_text(GLUE)
    monkeypatch.setenv("LOUDSCAPE_WEB_DIR", str(web))
    return web


class _Frames(HTMLParser):
    """The iframes of an HTML fragment, their attributes unescaped as a browser reads them."""

    def __init__(self) -> None:
        super().__init__()
        self.frames: list[dict[str, str | None]] = []
        self.tags: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "iframe":
            self.frames.append(dict(attrs))


def _script(page: str, element: str) -> bytes:
    """The gzip-in-base64 contents of the page's ``<script id=element>``, unpacked."""
    match = re.search(rf'id="{element}">([^<]*)</script>', page)
    assert match, element
    return gzip.decompress(base64.b64decode(match.group(1)))


def _header(page: str) -> str:
    """The PLY header of the page's cloud (``LSPC1``, its length, the header)."""
    cloud = _script(page, "loudscape-cloud")
    return cloud[9 : 9 + int.from_bytes(cloud[5:9], "little")].decode()


def test_the_inline_page_carries_the_viewer_and_every_point(viewer, _binary):
    page = loudscape.show(SONG, inline=True)
    assert isinstance(page, loudscape.Page)
    assert _script(page.html, "loudscape-wasm") == WASM
    assert GLUE in page.html
    cloud = _script(page.html, "loudscape-cloud")
    assert cloud.startswith(b"LSPC1")
    points, _ = read_ply(SONG)
    header = _header(page.html)
    assert f"element vertex {len(points)}\n" in header
    # 5 values of 2 bytes a point after the header.
    assert len(cloud) == 9 + len(header.encode()) + 10 * len(points)
    assert list(_binary.iterdir()) == [], "the temporary page was left behind"


def test_the_iframe_holds_the_whole_page_escaped(viewer):
    page = loudscape.show(SONG, inline=True)
    shown = page._repr_html_()
    parser = _Frames()
    parser.feed(shown)
    parser.close()
    # One element: nothing of the page leaks out of the attribute as markup.
    assert parser.tags == ["iframe"]
    (frame,) = parser.frames
    assert frame["srcdoc"] == page.html
    assert re.search(r"height: \d+px", frame["style"] or "")
    assert shown.endswith("</iframe>") and shown.count('"') == 2 * len(frame)


def test_without_the_viewer_one_line_says_to_build_it(monkeypatch, tmp_path, _binary):
    empty = tmp_path / "no-viewer"
    empty.mkdir()
    monkeypatch.setenv("LOUDSCAPE_WEB_DIR", str(empty))
    with pytest.raises(ExtractError) as raised:
        loudscape.show(SONG, inline=True)
    message = str(raised.value)
    assert "make web" in message and "\n" not in message
    assert list(_binary.iterdir()) == []


def test_arrays_and_a_saved_page(viewer, tmp_path):
    points, metadata = read_ply(SONG)
    page = loudscape.show((points[::10], metadata), inline=True)
    assert f"element vertex {len(points[::10])}\n" in _header(page.html)
    out = tmp_path / "song.html"
    page.save(out)
    assert out.read_text(encoding="utf-8") == page.html
    with pytest.raises(ExtractError, match="html"):
        page.save(tmp_path / "song.png")


@pytest.mark.parametrize(
    ("kwargs", "named"),
    [({"view": "surface"}, "view='surface'"), ({"inline": "yes"}, "inline")],
)
def test_inline_arguments_are_checked(viewer, kwargs, named):
    with pytest.raises(ExtractError, match=re.escape(named)):
        loudscape.show(SONG, **({"inline": True} | kwargs))
