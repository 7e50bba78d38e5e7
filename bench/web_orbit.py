"""Frame rate of an orbit in the web page (`loudscape page`) in headless chromium.

Opens PAGE (a file written by `loudscape page`) from its file URL in Debian's chromium with
SwiftShader's WebGPU (the flags of tests/web/test_page.py), waits for the viewer, then drags
across the view in MOVES steps, each followed by the next animation frame, and prints the
frames a second and the mean milliseconds a frame (Playwright's round trip included, so an
upper bound on the page's own time). With --webgl2, a chromium without WebGPU (the flags of
tests/web/test_page.py's WebGL2 test): the page's WebGL2 Points view.

    .venv/bin/python bench/web_orbit.py song.html [--moves 60] [--webgl2]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

CHROMIUM_ARGS = [
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--enable-unsafe-webgpu",
    "--enable-features=Vulkan",
    "--use-vulkan=swiftshader",
]
WEBGL2_ARGS = [
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-features=WebGPU",
]
NEXT_FRAME = "new Promise(r => requestAnimationFrame(r))"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("page", type=Path)
    parser.add_argument("--moves", type=int, default=60)
    parser.add_argument("--chromium", default="/usr/bin/chromium")
    parser.add_argument("--webgl2", action="store_true", help="a browser without WebGPU")
    args = parser.parse_args()
    if not args.page.is_file():
        print(f"{args.page}: no such file", file=sys.stderr)
        return 1
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=args.chromium,
            headless=True,
            args=WEBGL2_ARGS if args.webgl2 else CHROMIUM_ARGS,
        )
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        page.goto(args.page.resolve().as_uri())
        page.wait_for_function("document.body.dataset.state !== 'loading'", timeout=120_000)
        state = page.evaluate("document.body.dataset.state")
        if state != "running":
            print(f"{args.page}: the viewer did not start ({state})", file=sys.stderr)
            return 1
        for _ in range(5):
            page.evaluate(NEXT_FRAME)
        box = page.locator("#loudscape-view").bounding_box()
        x, y = box["x"] + box["width"] * 0.3, box["y"] + box["height"] * 0.5
        page.mouse.move(x, y)
        page.mouse.down()
        page.evaluate(NEXT_FRAME)
        start = time.perf_counter()
        for step in range(1, args.moves + 1):
            page.mouse.move(x + 5 * step, y)
            page.evaluate(NEXT_FRAME)
        elapsed = time.perf_counter() - start
        page.mouse.up()
        browser.close()
    fps = args.moves / elapsed
    api = "WebGL2" if args.webgl2 else "WebGPU"
    print(
        f"orbit in headless chromium (SwiftShader {api}), 1280x800: {args.moves} frames in "
        f"{elapsed:.2f} s, {fps:.1f} fps, {1000 / fps:.0f} ms a frame"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
