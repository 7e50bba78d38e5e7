"""`loudscape page`: the song's web page in a real browser.

Debian's chromium, headless, driven by Playwright (``executable_path``: Playwright downloads no
browser here). SwiftShader gives the headless browser a WebGPU adapter on the CPU. The page is
opened from a ``file://`` URL, as someone who was sent the file would open it. The binary is
``$LOUDSCAPE_BIN`` (``make test-web`` builds it and the viewer's wasm, ``make web``).

Two more browsers: one without WebGPU (WebGL2 through SwiftShader's GLES: the page's Points
view, and its Surface view made on the CPU), and one with neither WebGPU nor WebGL2 (the
page's message).
"""

from __future__ import annotations

import io
import os
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[2]
SONG = ROOT / "data" / "demo_song.ply"
TIMELINE = ROOT / "data" / "demo_timeline.ply"
BINARY = Path(os.environ.get("LOUDSCAPE_BIN", ROOT / "target" / "debug" / "loudscape")).absolute()
CHROMIUM = os.environ.get("LOUDSCAPE_CHROMIUM", "/usr/bin/chromium")
# SwiftShader's WebGPU adapter; the Vulkan feature makes headless chromium composite the WebGPU
# canvas into screenshots (without it the canvas shows blank, though the page draws).
CHROMIUM_ARGS = [
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--enable-unsafe-webgpu",
    "--enable-features=Vulkan",
    "--use-vulkan=swiftshader",
]
# No WebGPU: without --enable-unsafe-webgpu chromium's navigator.gpu offers no adapter on
# SwiftShader (the test checks), and the feature is turned off besides. WebGL2 stays.
WEBGL2_ARGS = [
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-features=WebGPU",
]
# Neither WebGPU nor WebGL (1 or 2).
NO_GPU_ARGS = [*WEBGL2_ARGS, "--disable-webgl", "--disable-webgl2"]
# What the browser offers the page: a WebGPU adapter, a WebGL2 context.
OFFERS_JS = """async () => ({
  webgpu: !!navigator.gpu && !!(await navigator.gpu.requestAdapter().catch(() => null)),
  webgl2: !!document.createElement("canvas").getContext("webgl2"),
})"""
# The budget for a page without audio.
PAGE_BUDGET_BYTES = 12_000_000
# How long the browser may take to start the viewer and draw (software WebGPU on a small machine).
DEADLINE_S = 120.0
VIEWPORT = {"width": 1000, "height": 640}
# Where the screenshots are kept for a look (make test-web prints the folder).
SHOTS = ROOT / "tests" / "output" / "web"


@pytest.fixture(scope="module")
def page_file(tmp_path_factory) -> Path:
    if not BINARY.is_file():
        pytest.fail(f"{BINARY} does not exist: run `cargo build` (or set LOUDSCAPE_BIN)")
    out = tmp_path_factory.mktemp("page") / "demo_song.html"
    run = subprocess.run(
        [str(BINARY), "page", str(SONG), "-o", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert "wrote" in run.stderr
    return out


@pytest.fixture(scope="module")
def playwright():
    if not Path(CHROMIUM).is_file():
        pytest.fail(f"{CHROMIUM} does not exist: install chromium (or set LOUDSCAPE_CHROMIUM)")
    with sync_playwright() as playwright:
        yield playwright


def _launch(playwright, args: list[str]):
    return playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=args)


@pytest.fixture(scope="module")
def browser(playwright):
    browser = _launch(playwright, CHROMIUM_ARGS)
    yield browser
    browser.close()


def _view_pixels(page) -> np.ndarray:
    """The 3D view's part of the canvas (left of the legend panel) as RGB."""
    # A page screenshot clipped to the canvas: a locator's waits for the element to be
    # "stable", which a slow software frame (the volume, on a loaded machine) can outlast.
    box = page.locator("#loudscape-view").bounding_box()
    png = page.screenshot(clip=box, timeout=DEADLINE_S * 1000)
    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    return rgb[:, : rgb.shape[1] * 6 // 10]


def _point_colours(rgb: np.ndarray) -> tuple[int, int]:
    """Pixels of the warm (percussive) and of the cool (harmonic) end of the points' colours."""
    r, b = rgb[..., 0], rgb[..., 2]
    warm = int(np.count_nonzero((r > b + 60) & (r > 120)))
    cool = int(np.count_nonzero((b > r + 60) & (b > 120)))
    return warm, cool


def _pixels_changed(rgb: np.ndarray, before: np.ndarray) -> int:
    """Pixels of `rgb` that differ from `before` by more than 30 in their summed channels."""
    return int(np.count_nonzero(np.abs(rgb - before).sum(axis=2) > 30))


def _next_frames(page):
    """Returns once the page has drawn two more animation frames."""
    page.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")


def _wait_for(predicate, what: str):
    """Polls `predicate` until it returns something other than None, up to the deadline."""
    deadline = time.monotonic() + DEADLINE_S
    while True:
        value = predicate()
        if value is not None:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"after {DEADLINE_S:.0f} s: {what}")
        time.sleep(0.2)


def _open(browser, url: str):
    """A new page at `url` that collects its console errors and uncaught exceptions; returns
    the page and that list once the viewer has left its loading state."""
    page = browser.new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    page.wait_for_function("document.body.dataset.state !== 'loading'", timeout=DEADLINE_S * 1000)
    return page, errors


def _points_shown(page, what: str = "the view never showed the points") -> np.ndarray:
    """The 3D view once it shows the points' warm and cool colours (polled to the deadline)."""

    def coloured():
        rgb = _view_pixels(page)
        return rgb if min(_point_colours(rgb)) > 200 else None

    return _wait_for(coloured, what)


def _drag_turns_the_view(page, before: np.ndarray) -> np.ndarray:
    """Drags across the view; returns the picture once it differs from `before`."""
    box = page.locator("#loudscape-view").bounding_box()
    x, y = box["x"] + box["width"] * 0.3, box["y"] + box["height"] * 0.5
    page.mouse.move(x, y)
    page.mouse.down()
    _next_frames(page)
    for step in range(1, 11):
        page.mouse.move(x + 20 * step, y + 4 * step)
        _next_frames(page)
    page.mouse.up()

    def turned():
        rgb = _view_pixels(page)
        changed = _pixels_changed(rgb, before)
        return (rgb, changed) if changed > 0.01 * rgb.shape[0] * rgb.shape[1] else None

    after, changed = _wait_for(turned, "a drag over the view did not change the picture")
    print(f"pixels changed by the drag: {changed}")
    return after


def _pointer_to_panel(page):
    """The pointer onto the side panel, so no hover read-out covers the view."""
    box = page.locator("#loudscape-view").bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.9, box["y"] + box["height"] * 0.9)


def _unchanged(page, before: np.ndarray) -> np.ndarray | None:
    """The view when it shows `before` again (under 0.1 % of its pixels changed), else None."""
    rgb = _view_pixels(page)
    changed = _pixels_changed(rgb, before)
    return rgb if changed < 0.001 * rgb.shape[0] * rgb.shape[1] else None


def _reset_brings_back(page, before: np.ndarray) -> np.ndarray:
    """R resets the camera and fits it again: the first picture, `before`, comes back."""
    _pointer_to_panel(page)
    page.keyboard.press("r")
    return _wait_for(lambda: _unchanged(page, before), "R did not bring back the first view")


def _hover_opens_a_readout(page, before: np.ndarray):
    """Over the empty background nothing opens; over a warm point in the middle of the cloud
    (in `before`, the view at rest) the read-out box opens at the cursor."""
    box = page.locator("#loudscape-view").bounding_box()
    h, w = before.shape[:2]

    def region(rgb, x, y):
        return rgb[y + 8 : min(y + 100, h), x + 8 : min(x + 200, w)]

    def hover(x, y):
        page.mouse.move(box["x"] + x, box["y"] + y)
        _next_frames(page)
        page.mouse.move(box["x"] + x + 1, box["y"] + y)
        _next_frames(page)

    # Over the empty background (the darkest corner of the view): nothing opens.
    hover(10, 10)
    _next_frames(page)
    assert (
        np.abs(region(_view_pixels(page), 10, 10) - region(before, 10, 10)).sum(axis=2).max() < 30
    )

    r, b = before[..., 0], before[..., 2]
    ys, xs = np.nonzero((r > b + 60) & (r > 120))
    middle = np.argmin((ys - ys.mean()) ** 2 + (xs - xs.mean()) ** 2)
    x, y = int(xs[middle]), int(ys[middle])
    hover(x, y)

    def opened():
        now = region(_view_pixels(page), x, y)
        changed = np.count_nonzero(np.abs(now - region(before, x, y)).sum(axis=2) > 30)
        return changed if changed > 0.3 * now.shape[0] * now.shape[1] else None

    _wait_for(opened, f"no read-out opened over the point at ({x}, {y})")


def _readout_over_the_grid(page, shown: np.ndarray, what: str) -> str:
    """Hovers the lit pixel of `shown` (the Surface or Volume view at rest) nearest the middle
    of its lit part; returns the read-out's text (the canvas's `data-readout`) once it reads a
    voxel there: its density and mean hp, and its place in the axes' units."""
    box = page.locator("#loudscape-view").bounding_box()
    ys, xs = np.nonzero(shown.max(axis=2) > 100)
    middle = np.argmin((ys - ys.mean()) ** 2 + (xs - xs.mean()) ** 2)
    x, y = box["x"] + int(xs[middle]), box["y"] + int(ys[middle])

    def read():
        page.mouse.move(x, y)
        _next_frames(page)
        page.mouse.move(x + 1, y)
        _next_frames(page)
        text = page.locator("#loudscape-view").get_attribute("data-readout") or ""
        return text if "density: " in text else None

    text = _wait_for(read, f"{what}: no read-out of a voxel under the cursor")
    print(f"{what} read-out: {text!r}")
    # And the read-out's box opens at the cursor.
    cx, cy = int(xs[middle]), int(ys[middle])
    h, w = shown.shape[:2]

    def opened():
        now = _view_pixels(page)[cy + 8 : min(cy + 100, h), cx + 8 : min(cx + 200, w)]
        then = shown[cy + 8 : min(cy + 100, h), cx + 8 : min(cx + 200, w)]
        changed = np.count_nonzero(np.abs(now - then).sum(axis=2) > 30)
        return changed if changed > 0.3 * now.shape[0] * now.shape[1] else None

    _wait_for(opened, f"{what}: the read-out's box did not open at the cursor")
    lines = dict(line.split(": ", 1) for line in text.splitlines())
    assert lines["time"].endswith(" s"), lines
    assert "Hz" in lines["frequency"], lines
    assert lines["bin level"].endswith(" dB"), lines
    assert float(lines["density"]) > 0.0, lines
    assert "(" in lines["mean hp"], lines
    return text


def test_the_page_stays_in_its_budget(page_file):
    size = page_file.stat().st_size
    print(f"\npage of {SONG.name}: {size / 1e6:.2f} MB (budget {PAGE_BUDGET_BYTES / 1e6:.0f} MB)")
    assert size <= PAGE_BUDGET_BYTES
    text = page_file.read_text()
    # Self-contained: no file or address is fetched besides the page itself.
    for ref in ('src="', "href=", "fetch("):
        assert ref not in text.replace("fetch(module_or_path)", ""), ref


def test_the_song_shows_and_turns_from_a_file_url(browser, page_file):
    page, errors = _open(browser, page_file.as_uri())
    state = page.evaluate("document.body.dataset.state")
    assert state == "running", page.inner_text("#message")

    before = _points_shown(page, "the view never showed the points' warm and cool colours")
    SHOTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(before.astype(np.uint8)).save(SHOTS / "page_before_drag.png")
    page.screenshot(path=SHOTS / "page.png")
    warm, cool = _point_colours(before)
    print(f"\nwarm pixels {warm}, cool pixels {cool}")

    after = _drag_turns_the_view(page, before)
    Image.fromarray(after.astype(np.uint8)).save(SHOTS / "page_after_drag.png")
    assert min(_point_colours(after)) > 200, "the points left the view after the drag"

    _reset_brings_back(page, before)
    assert errors == [], errors
    page.close()


def test_the_volume_view_builds_its_grid_in_the_browser(browser, page_file):
    """V shows the Volume view: the window's voxelize compute passes and ray march on WebGPU."""
    page, errors = _open(browser, page_file.as_uri())

    points = _points_shown(page)
    page.locator("#loudscape-view").focus()
    page.keyboard.press("v")

    def volume():
        rgb = _view_pixels(page)
        changed = _pixels_changed(rgb, points)
        lit = np.count_nonzero(rgb.max(axis=2) > 100)
        whole = rgb.shape[0] * rgb.shape[1]
        return (rgb, changed, lit) if changed > 0.05 * whole and lit > 0.05 * whole else None

    shown, changed, lit = _wait_for(volume, "V did not show a volume")
    SHOTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(shown.astype(np.uint8)).save(SHOTS / "page_volume.png")
    print(f"\nvolume: {changed} pixels changed from the points, {lit} lit")
    # The read-out over the volume: the first voxel along the cursor's ray at the window's pick
    # density, from the grid read back from the GPU.
    readout = _readout_over_the_grid(page, shown, "Volume")
    page.screenshot(path=SHOTS / "page_volume_hover.png")
    assert float(dict(x.split(": ", 1) for x in readout.splitlines())["density"]) >= 0.1

    # The transfer functions, chosen as in the window: Ember draws the same grid in its colours.
    presets = dict(
        part.split(":")
        for part in page.locator("#loudscape-view").get_attribute("data-volume-transfer").split(";")
    )
    assert sorted(presets) == ["classic", "ember", "glacial"], presets
    box = page.locator("#loudscape-view").bounding_box()
    x, y, width, height = (float(v) for v in presets["ember"].split(","))
    page.mouse.click(box["x"] + x + width / 2, box["y"] + y + height / 2)
    _pointer_to_panel(page)

    def recoloured():
        rgb = _view_pixels(page)
        moved = _pixels_changed(rgb, shown)
        return (rgb, moved) if moved > 0.05 * rgb.shape[0] * rgb.shape[1] else None

    ember, moved = _wait_for(recoloured, "Ember did not recolour the volume")
    Image.fromarray(ember.astype(np.uint8)).save(SHOTS / "page_volume_ember.png")
    print(f"Ember: {moved} pixels changed")
    assert errors == [], errors
    page.close()


def test_hovering_a_point_shows_its_values(browser, page_file):
    """The read-out box opens at the cursor over a point (time, frequency, level, hp with their
    units, as the window's), and not over the empty background."""
    page = browser.new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(page_file.as_uri())
    page.wait_for_function("document.body.dataset.state !== 'loading'", timeout=DEADLINE_S * 1000)

    before = _points_shown(page)
    _hover_opens_a_readout(page, before)
    page.screenshot(path=SHOTS / "page_hover.png")
    assert errors == [], errors
    page.close()


@pytest.fixture(scope="module")
def webgl2_browser(playwright):
    """A browser without WebGPU: WebGL2 only."""
    browser = _launch(playwright, WEBGL2_ARGS)
    yield browser
    browser.close()


def test_a_browser_without_webgpu_shows_the_points_on_webgl2(webgl2_browser, page_file):
    """No WebGPU adapter, WebGL2 only: the points drawn with their hp colours, a drag turns
    them, a hover shows the read-out."""
    page, errors = _open(webgl2_browser, page_file.as_uri())
    assert page.evaluate(OFFERS_JS) == {"webgpu": False, "webgl2": True}
    assert page.evaluate("document.body.dataset.state") == "running", page.inner_text("#message")

    before = _points_shown(page, "WebGL2: the view never showed the points' warm and cool colours")
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SHOTS / "page_webgl2.png")
    print(f"\nWebGL2: warm and cool pixels {_point_colours(before)}")
    after = _drag_turns_the_view(page, before)
    Image.fromarray(after.astype(np.uint8)).save(SHOTS / "page_webgl2_after_drag.png")
    assert min(_point_colours(after)) > 200, "the points left the view after the drag"

    rest = _reset_brings_back(page, before)
    _hover_opens_a_readout(page, rest)
    page.screenshot(path=SHOTS / "page_webgl2_hover.png")
    assert errors == [], errors
    page.close()


def _surface_colours(rgb: np.ndarray) -> tuple[int, int]:
    """Pixels of the surface's light neutral (its warm-to-cool map's middle, lit: a warm white)
    and of the points' red (their five-stop palette's percussive end, redder than the
    surface's warm end)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    neutral = int(np.count_nonzero((b > 120) & (r > b + 8) & (r < b + 60) & (g > b)))
    points_red = int(np.count_nonzero((r > 120) & (g * 100 < 27 * r)))
    return neutral, points_red


def _surface_timing(page) -> tuple[float, float, int, str] | None:
    """The page's `data-surface-timing` on WebGL2: milliseconds of the grid's build and of the
    last extraction, its triangles and its grid ("full", or "coarse" while the slider is
    dragged); None before the first surface."""
    timing = page.locator("#loudscape-view").get_attribute("data-surface-timing")
    if not timing:
        return None
    grid_ms, extract_ms, triangles, level = timing.split(",")
    return float(grid_ms), float(extract_ms), int(triangles), level


def test_the_surface_view_on_webgl2(webgl2_browser, page_file):
    """No WebGPU: S shows the Surface view, its grid and isosurface made on the CPU in the page
    (voxelize's CPU mirror, the CPU engine's marching tetrahedra on one thread), drawn with the
    surface's colours where the points' were; a click on the isovalue slider extracts another
    surface and changes the picture; no console errors."""
    page, errors = _open(webgl2_browser, page_file.as_uri())
    points = _points_shown(page)
    neutral, red = _surface_colours(points)
    assert red > 5000 and neutral < 2000, (neutral, red)

    _pointer_to_panel(page)
    page.keyboard.press("s")

    def surface_shown():
        rgb = _view_pixels(page)
        neutral, red = _surface_colours(rgb)
        timing = _surface_timing(page)
        return (rgb, timing) if timing and neutral > 5000 and red < 500 else None

    surface, (grid_ms, first_ms, first_triangles, _) = _wait_for(
        surface_shown, "WebGL2: S did not show the surface's colours in place of the points"
    )
    SHOTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(surface.astype(np.uint8)).save(SHOTS / "page_webgl2_surface.png")
    print(
        f"\nWebGL2 surface: grid {grid_ms:.0f} ms, {first_triangles} triangles in {first_ms:.0f} ms"
        f" (surface colours {_surface_colours(surface)})"
    )

    place = page.locator("#loudscape-view").get_attribute("data-iso-slider")
    assert place, "the page did not say where the isovalue slider is"
    x, y, width, height = (float(v) for v in place.split(","))
    box = page.locator("#loudscape-view").bounding_box()
    # The slider dragged from the default isovalue (0.5) to near the high end: while it moves,
    # the coarse grid's surface (the full one's extraction took longer than a moving frame);
    # once let go, the full grid's, a smaller surface than the first.
    knob = box["x"] + x + width * (0.5 - 0.01) / 0.98
    rail_y = box["y"] + y + height / 2
    page.mouse.move(knob, rail_y)
    page.mouse.down()
    for step in range(1, 6):
        page.mouse.move(knob + step * 0.06 * width, rail_y)
        _next_frames(page)

    def coarse():
        timing = _surface_timing(page)
        return timing if timing and timing[3] == "coarse" else None

    _, coarse_ms, coarse_triangles, _ = _wait_for(
        coarse, "WebGL2: no coarse surface while the slider was dragged"
    )
    Image.fromarray(_view_pixels(page).astype(np.uint8)).save(
        SHOTS / "page_webgl2_surface_dragging.png"
    )
    print(f"while dragging: {coarse_triangles} triangles (coarse grid) in {coarse_ms:.0f} ms")
    page.mouse.up()
    _pointer_to_panel(page)

    def changed():
        timing = _surface_timing(page)
        if timing is None or timing[2] == first_triangles or timing[3] != "full":
            return None
        rgb = _view_pixels(page)
        moved = _pixels_changed(rgb, surface)
        return (rgb, timing, moved) if moved > 0.01 * rgb.shape[0] * rgb.shape[1] else None

    higher, (_, ms, triangles, _), moved = _wait_for(
        changed, "WebGL2: the isovalue slider did not change the surface"
    )
    Image.fromarray(higher.astype(np.uint8)).save(SHOTS / "page_webgl2_surface_higher.png")
    print(f"isovalue raised: {triangles} triangles in {ms:.0f} ms, {moved} pixels changed")
    assert triangles < first_triangles

    # Dual contouring, chosen as in the window: another mesh (one vertex a cell, two triangles
    # a crossing edge) and another picture of the same isovalue.
    methods = dict(
        part.split(":")
        for part in page.locator("#loudscape-view").get_attribute("data-surface-method").split(";")
    )
    x, y, width, height = (float(v) for v in methods["dc"].split(","))
    page.mouse.click(box["x"] + x + width / 2, box["y"] + y + height / 2)
    _pointer_to_panel(page)

    def dual_contoured():
        timing = _surface_timing(page)
        if timing is None or timing[2] == triangles:
            return None
        rgb = _view_pixels(page)
        moved = _pixels_changed(rgb, higher)
        return (rgb, timing, moved) if moved > 0.002 * rgb.shape[0] * rgb.shape[1] else None

    dual, (_, dc_ms, dc_triangles, _), moved = _wait_for(
        dual_contoured, "WebGL2: dual contouring did not change the surface"
    )
    Image.fromarray(dual.astype(np.uint8)).save(SHOTS / "page_webgl2_surface_dc.png")
    print(f"dual contouring: {dc_triangles} triangles in {dc_ms:.0f} ms, {moved} pixels changed")

    # The read-out over the surface, from the grid built in the page.
    readout = _readout_over_the_grid(page, dual, "WebGL2 surface")
    page.screenshot(path=SHOTS / "page_webgl2_surface_hover.png")
    assert float(dict(x.split(": ", 1) for x in readout.splitlines())["density"]) >= 0.7
    assert errors == [], errors
    page.close()


def test_a_browser_without_webgpu_and_webgl2_gets_a_message(playwright, page_file):
    browser = _launch(playwright, NO_GPU_ARGS)
    page, errors = _open(browser, page_file.as_uri())
    assert page.evaluate(OFFERS_JS) == {"webgpu": False, "webgl2": False}
    assert page.evaluate("document.body.dataset.state") == "no-gpu"
    message = page.locator("#message")
    assert message.is_visible()
    assert "WebGPU or WebGL2" in message.inner_text()
    assert errors == [], errors
    browser.close()


def _longest_run(flags: np.ndarray) -> int:
    """The longest run of True in a 1-D array."""
    padded = np.concatenate(([0], flags.astype(np.int8), [0]))
    edges = np.flatnonzero(np.diff(padded))
    return int((edges[1::2] - edges[::2]).max(initial=0))


def test_a_timeline_page_shows_its_whole_box(browser, tmp_path):
    """A timeline's box is long: the camera is fitted to the view the side panel leaves (the
    panel settles its width after the first frame), so no line of the box runs out of the
    view's left, top or bottom edge (a tick's end may touch it: the fit is to the box); and the
    page speaks of a timeline."""
    out = tmp_path / "timeline.html"
    run = subprocess.run(
        [str(BINARY), "page", str(TIMELINE), "-o", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert "Every point of the timeline" in out.read_text()
    page, errors = _open(browser, out.as_uri())

    def framed():
        rgb = _view_pixels(page)
        if _point_colours(rgb)[1] < 200:
            return None
        lit = rgb.max(axis=2) > 60
        # Lines along each edge strip (columns at the left, rows at the top and bottom).
        strips = [lit[:, :3].T, lit[:3, :], lit[-3:, :]]
        return rgb if max(_longest_run(line) for s in strips for line in s) <= 3 else None

    rgb = _wait_for(framed, "the timeline's box or points touch the view's edge")
    SHOTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(rgb.astype(np.uint8)).save(SHOTS / "page_timeline.png")
    assert not errors, errors
    page.close()


def test_a_three_minute_song_is_thinned_into_the_budget(tmp_path):
    """180 s at the demo song's density (points a second), random values (which pack worse
    than music), written as a PLY without metadata."""
    with SONG.open("rb") as f:
        header = f.read(1 << 20).split(b"end_header\n")[0].decode("ascii", "replace")
    demo_points = int(
        next(x for x in header.splitlines() if x.startswith("element vertex")).split()[2]
    )
    count = demo_points * 6
    rng = np.random.default_rng(38)
    points = np.empty((count, 5), dtype="<f4")
    points[:, :3] = rng.uniform(-1, 1, (count, 3))
    points[:, 3:] = rng.uniform(0, 1, (count, 2))
    ply = tmp_path / "three_minutes.ply"
    with ply.open("wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\n")
        f.write(f"element vertex {count}\n".encode())
        for name in ("x", "y", "z", "scalar", "hp"):
            f.write(f"property float {name}\n".encode())
        f.write(b"end_header\n")
        f.write(points.tobytes())
    out = tmp_path / "three_minutes.html"
    run = subprocess.run(
        [str(BINARY), "page", str(ply), "-o", str(out)], capture_output=True, text=True, check=False
    )
    assert run.returncode == 0, run.stderr
    size = out.stat().st_size
    print(f"\npage of {count} points (3 minutes): {size / 1e6:.2f} MB; {run.stderr.strip()}")
    assert size <= PAGE_BUDGET_BYTES
    assert f"of the song's {count} points" in out.read_text()


def test_the_surface_view_and_its_isovalue_slider(browser, page_file):
    """S shows the Surface view (the grid built by the voxelize passes, the isosurface by the
    marching tetrahedra passes, on WebGPU); the read-out over it; a click on the isovalue
    slider's rail changes it, and so does dual contouring."""
    page, errors = _open(browser, page_file.as_uri())

    points = _points_shown(page)
    whole = points.shape[0] * points.shape[1]
    page.locator("#loudscape-view").focus()
    pressed = time.monotonic()
    page.keyboard.press("s")

    def differs_from(reference, share):
        def check():
            rgb = _view_pixels(page)
            changed = _pixels_changed(rgb, reference)
            lit = np.count_nonzero(rgb.max(axis=2) > 100)
            return (rgb, changed) if changed > share * whole and lit > 0.02 * whole else None

        return check

    surface, changed = _wait_for(differs_from(points, 0.05), "S did not show a surface")
    shown_s = time.monotonic() - pressed
    SHOTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(surface.astype(np.uint8)).save(SHOTS / "page_surface.png")
    print(f"\nsurface: {changed} pixels changed from the points, seen {shown_s:.1f} s after S")
    # The surface is lit and hp-coloured: both ends of the palette are on it.
    assert min(_point_colours(surface)) > 200, _point_colours(surface)
    # The read-out over the surface: the first voxel at the isovalue along the cursor's ray.
    readout = _readout_over_the_grid(page, surface, "WebGPU surface")
    assert float(dict(x.split(": ", 1) for x in readout.splitlines())["density"]) >= 0.5

    place = page.locator("#loudscape-view").get_attribute("data-iso-slider")
    assert place, "the page did not say where the isovalue slider is"
    x, y, width, height = (float(v) for v in place.split(","))
    box = page.locator("#loudscape-view").bounding_box()
    # From the default isovalue (0.5) to near the low end (0.05 here): a larger surface, more
    # than the first mesh buffers hold (1.4 M triangles), so they grow and it is extracted again.
    clicked = time.monotonic()
    page.mouse.click(box["x"] + x + 0.1 * width, box["y"] + y + height / 2)
    lower, changed = _wait_for(
        differs_from(surface, 0.02), "the isovalue slider did not change the surface"
    )
    changed_s = time.monotonic() - clicked
    Image.fromarray(lower.astype(np.uint8)).save(SHOTS / "page_surface_lower.png")
    page.screenshot(path=SHOTS / "page_surface_panel.png")
    print(f"isovalue lowered: {changed} pixels changed, seen {changed_s:.1f} s after the click")

    # Dual contouring, by the window's compute passes: another picture of the same isovalue.
    methods = dict(
        part.split(":")
        for part in page.locator("#loudscape-view").get_attribute("data-surface-method").split(";")
    )
    x, y, width, height = (float(v) for v in methods["dc"].split(","))
    page.mouse.click(box["x"] + x + width / 2, box["y"] + y + height / 2)
    _pointer_to_panel(page)
    dual, changed = _wait_for(
        differs_from(lower, 0.01), "dual contouring did not change the surface"
    )
    Image.fromarray(dual.astype(np.uint8)).save(SHOTS / "page_surface_dc.png")
    print(f"dual contouring: {changed} pixels changed")
    assert errors == [], errors
    page.close()


@pytest.fixture(scope="module")
def audio_page_file(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("page_audio") / "demo_song_audio.html"
    run = subprocess.run(
        [str(BINARY), "page", str(SONG), "-o", str(out), "--audio"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    print(f"\n{run.stderr.strip()}")
    return out


def test_the_song_plays_with_a_playhead_and_seeks_where_clicked(browser, audio_page_file):
    """--audio: the page plays the song's sound (Opus); the playhead follows it, on the bar and
    as the plane in the view, and a click on the bar plays from that point of the song."""
    page, errors = _open(browser, audio_page_file.as_uri())
    assert page.locator("#player").is_visible()
    page.wait_for_function(
        "document.getElementById('loudscape-sound').readyState >= 1", timeout=DEADLINE_S * 1000
    )
    duration = page.evaluate("document.getElementById('loudscape-sound').duration")
    assert 1.0 < duration < 600.0, duration
    minutes, seconds = divmod(int(duration), 60)
    assert page.inner_text("#clock") == f"0:00 / {minutes}:{seconds:02d}"

    page.click("#play")
    page.wait_for_function(
        "document.getElementById('loudscape-sound').currentTime > 0.3", timeout=DEADLINE_S * 1000
    )
    assert page.inner_text("#play") == "Pause"
    page.click("#play")
    assert page.evaluate("document.getElementById('loudscape-sound').paused")
    # The button says so when the pause event comes.
    page.wait_for_function(
        "document.getElementById('play').textContent === 'Play'", timeout=DEADLINE_S * 1000
    )

    near_start = _points_shown(page)
    bar = page.locator("#bar").bounding_box()
    page.mouse.click(bar["x"] + bar["width"] * 0.75, bar["y"] + bar["height"] / 2)
    at = page.evaluate("document.getElementById('loudscape-sound').currentTime")
    assert abs(at / duration - 0.75) < 0.02, (at, duration)
    head = page.locator("#playhead").bounding_box()
    assert abs((head["x"] + 1 - bar["x"]) / bar["width"] - 0.75) < 0.02

    # The playhead plane moved through the song in the view (above the player's bar).
    def moved():
        rgb = _view_pixels(page)
        top = slice(0, int(rgb.shape[0] * 0.8))
        changed = np.count_nonzero(np.abs(rgb[top] - near_start[top]).sum(axis=2) > 30)
        return changed if changed > 500 else None

    changed = _wait_for(moved, "the playhead plane did not move in the view")
    print(f"\nthe playhead's move changed {changed} pixels of the view")
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SHOTS / "page_audio.png")
    assert errors == [], errors
    page.close()


def test_the_notebook_cell_turns_the_song_in_its_iframe(browser, tmp_path, monkeypatch):
    """``loudscape.show(song, inline=True)`` as a notebook shows it: the cell's HTML (the
    page in an ``<iframe srcdoc>``) inside a host page; the viewer starts in the iframe and
    draws the points."""
    import loudscape

    monkeypatch.setenv("LOUDSCAPE_BIN", str(BINARY))
    cell = loudscape.show(SONG, inline=True)._repr_html_()
    notebook = tmp_path / "notebook.html"
    notebook.write_text(
        "<!doctype html><html><body><h1>In [1]:</h1>"
        f"<div class='output'>{cell}</div></body></html>",
        encoding="utf-8",
    )
    page = browser.new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(notebook.as_uri())
    frame = page.locator("iframe").element_handle().content_frame()
    frame.wait_for_function("document.body.dataset.state !== 'loading'", timeout=DEADLINE_S * 1000)
    assert frame.evaluate("document.body.dataset.state") == "running", frame.inner_text("#message")

    def coloured():
        box = page.locator("iframe").bounding_box()
        png = page.screenshot(clip=box, timeout=DEADLINE_S * 1000)
        rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
        rgb = rgb[:, : rgb.shape[1] * 6 // 10]
        return rgb if min(_point_colours(rgb)) > 200 else None

    shown = _wait_for(coloured, "the iframe never showed the points")
    SHOTS.mkdir(parents=True, exist_ok=True)
    Image.fromarray(shown.astype(np.uint8)).save(SHOTS / "page_notebook_cell.png")
    page.screenshot(path=SHOTS / "page_notebook.png")
    assert errors == [], errors
    page.close()


@pytest.fixture(scope="module")
def compare_page_file(tmp_path_factory) -> Path:
    """``page A --compare B --offset 0.5``: A the demo, B the demo 0.5 s later and 6 dB louder
    (its axes' ends moved, its points as they are), written by the extractor's writer; 30,000
    points of each (a software frame of both whole is slow on a loaded machine)."""
    from loudscape_extract.ply import read_ply, write_ply

    folder = tmp_path_factory.mktemp("compare")
    points, meta = read_ply(SONG)
    for axis, by in (("x", 0.5), ("y", 6.0), ("scalar", 6.0)):
        meta["axes"][axis]["min"] += by
        meta["axes"][axis]["max"] += by
        meta["axes"][axis].pop("ticks", None)
    later = folder / "later.ply"
    write_ply(later, points=points, metadata=meta)
    out = folder / "ab.html"
    run = subprocess.run(
        [
            str(BINARY),
            "page",
            str(SONG),
            "--compare",
            str(later),
            "--offset",
            "0.5",
            "--max-points",
            "60000",
            "-o",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert "compare: A 29550 of 147750 points, B 29550 of 147750 points" in run.stderr
    return out


def _compare_halves(page) -> list[np.ndarray] | None:
    """A's and B's halves of the view as RGB, from the places the viewer writes on the canvas
    (``data-compare-halves``); None before it has."""
    places = page.locator("#loudscape-view").get_attribute("data-compare-halves")
    if not places:
        return None
    box = page.locator("#loudscape-view").bounding_box()
    png = page.screenshot(clip=box, timeout=DEADLINE_S * 1000)
    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    halves = []
    for place in places.split(";"):
        x, y, w, h = (round(float(v)) for v in place.split(","))
        halves.append(rgb[y : y + h, x : x + w])
    return halves


@pytest.mark.parametrize("device", ["webgpu", "webgl2"])
def test_the_compare_page_shows_a_and_b_side_by_side_and_turns_both(
    playwright, browser, compare_page_file, device
):
    """A left, B right, each with the points' warm and cool colours, on WebGPU and on WebGL2;
    a drag over A's half turns both halves (one camera); S shows both halves' surfaces (their
    grids on one scale), and V their volumes on WebGPU; no console errors."""
    own = _launch(playwright, WEBGL2_ARGS) if device == "webgl2" else None
    page, errors = _open(own or browser, compare_page_file.as_uri())
    assert page.evaluate(OFFERS_JS)["webgpu"] == (device == "webgpu")
    assert page.evaluate("document.body.dataset.state") == "running", page.inner_text("#message")

    def both_coloured():
        halves = _compare_halves(page)
        if halves is None or min(min(_point_colours(h)) for h in halves) <= 200:
            return None
        return halves

    before = _wait_for(both_coloured, f"{device}: the halves never both showed the points")
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SHOTS / f"page_compare_{device}.png")
    print(
        f"\n{device}: warm and cool pixels, A {_point_colours(before[0])}, B "
        f"{_point_colours(before[1])}"
    )

    box = page.locator("#loudscape-view").bounding_box()
    x, y = box["x"] + box["width"] * 0.15, box["y"] + box["height"] * 0.5
    page.mouse.move(x, y)
    page.mouse.down()
    _next_frames(page)
    for step in range(1, 11):
        page.mouse.move(x + 12 * step, y + 4 * step)
        _next_frames(page)
    page.mouse.up()

    def both_turned():
        halves = _compare_halves(page)
        changed = [
            np.count_nonzero(np.abs(now - then).sum(axis=2) > 30) / now[..., 0].size
            for now, then in zip(halves, before, strict=True)
        ]
        return changed if min(changed) > 0.01 else None

    changed = _wait_for(both_turned, f"{device}: a drag over A did not turn both halves")
    print(f"{device}: share of pixels changed by the drag, A {changed[0]:.3f}, B {changed[1]:.3f}")
    page.screenshot(path=SHOTS / f"page_compare_{device}_after_drag.png")

    # S: both grids built in the page in one box and on one scale, each half's surface drawn in
    # the surface's colours where its points were.
    turned = _compare_halves(page)
    _pointer_to_panel(page)
    page.keyboard.press("s")

    def both_surfaces():
        timing = page.locator("#loudscape-view").get_attribute("data-surface-timing") or ""
        fields = timing.split(",")
        if len(fields) != 5 or not all(fields[3:]):
            return None
        halves = _compare_halves(page)
        neutral = [_surface_colours(h)[0] for h in halves]
        moved = [
            np.count_nonzero(np.abs(now - then).sum(axis=2) > 30) / now[..., 0].size
            for now, then in zip(halves, turned, strict=True)
        ]
        if min(neutral) < 1000 or min(moved) < 0.03:
            return None
        return fields, neutral, moved

    fields, neutral, moved = _wait_for(
        both_surfaces, f"{device}: S did not show both halves' surfaces"
    )
    page.screenshot(path=SHOTS / f"page_compare_{device}_surface.png")
    print(
        f"{device} surfaces: grids {float(fields[0]):.0f} ms, triangles A {fields[3]}, B "
        f"{fields[4]}; extraction ms {fields[1] or '-'}, {fields[2] or '-'}; neutral {neutral}, "
        f"moved {moved[0]:.3f}, {moved[1]:.3f}"
    )
    if device == "webgpu":
        # V: the volume of each half's grid (WebGL2 has no volume).
        surfaces = _compare_halves(page)
        page.keyboard.press("v")

        def both_volumes():
            halves = _compare_halves(page)
            moved = [
                np.count_nonzero(np.abs(now - then).sum(axis=2) > 30) / now[..., 0].size
                for now, then in zip(halves, surfaces, strict=True)
            ]
            lit = [np.count_nonzero(h.max(axis=2) > 100) / h[..., 0].size for h in halves]
            return (moved, lit) if min(moved) > 0.05 and min(lit) > 0.05 else None

        moved, lit = _wait_for(both_volumes, "webgpu: V did not show both halves' volumes")
        page.screenshot(path=SHOTS / "page_compare_webgpu_volume.png")
        print(f"volumes: moved {moved[0]:.3f}, {moved[1]:.3f}; lit {lit[0]:.3f}, {lit[1]:.3f}")
    assert errors == [], errors
    page.close()
    if own:
        own.close()
