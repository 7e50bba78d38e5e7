#!/usr/bin/env bash
# The pip way, end to end: build the wheel (`pip wheel .`: setuptools-rust builds the app in
# release), install it into a fresh venv, and from that venv alone (no variable set, no checkout
# on PATH, an empty cloud cache, a folder outside the checkout) run `loudscape render` on an
# audio file: the app must find `loudscape-extract` beside itself, extract and draw. The PNG must
# exist, have the asked size and not be blank. Usage: scripts/test-wheel.sh [PYTHON]
# SETUPTOOLS_RUST_CARGO_PROFILE=dev builds the app with cargo's dev profile instead of release
# (`make test` does, to link the binary its Rust tests built).
set -euo pipefail
python=${1:-python3}
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/loudscape-wheel.XXXXXX")
trap 'rm -rf "$work"' EXIT

start=$(date +%s)
"$python" -m venv "$work/venv"
"$work/venv/bin/python" -m pip wheel -q --no-deps -w "$work/wheels" "$root"
built=$(date +%s)
wheel=$(ls "$work"/wheels/loudscape-*.whl)
echo "test-wheel: built $(basename "$wheel") ($(du -h "$wheel" | cut -f1)), the app in cargo's ${SETUPTOOLS_RUST_CARGO_PROFILE:-release} profile, in $((built - start)) s"

"$work/venv/bin/python" -m pip install -q "$wheel"
installed=$(date +%s)
echo "test-wheel: installed into a fresh venv in $((installed - built)) s"

bin="$work/venv/bin"
mkdir "$work/home"
for command in loudscape loudscape-extract; do
    [ -x "$bin/$command" ] || { echo "test-wheel: the wheel installed no $command" >&2; exit 1; }
done
# The extractor of the wheel loads its compiled running median (crates/median), from the venv.
(cd "$work" && env -i PATH=/usr/bin:/bin HOME="$work/home" "$bin/python" -c '
import os
import sys

from loudscape_extract import native

path = native.library_path()
assert native.available(), f"the compiled running median is not loaded (file: {path})"
assert path.startswith(sys.prefix), path
print("test-wheel: the extractor loads", os.path.basename(path))
')
cp "$root/data/demo_song.flac" "$work/song.flac"
mkdir "$work/cache"
(cd "$work" && env -i PATH=/usr/bin:/bin HOME="$work/home" LOUDSCAPE_CACHE_DIR="$work/cache" \
    ${XDG_RUNTIME_DIR:+XDG_RUNTIME_DIR="$XDG_RUNTIME_DIR"} \
    "$bin/loudscape" render song.flac --size 640x360 --output picture.png)
rendered=$(date +%s)
echo "test-wheel: extracted and rendered in $((rendered - installed)) s"
ls "$work"/cache/*.ply >/dev/null || { echo "test-wheel: nothing was extracted" >&2; exit 1; }

"$bin/python" - "$work/picture.png" <<'PY'
import sys

import numpy as np
from PIL import Image

with Image.open(sys.argv[1]) as image:
    pixels = np.asarray(image.convert("RGBA"))
colours = len(np.unique(pixels.reshape(-1, 4), axis=0))
assert pixels.shape == (360, 640, 4), pixels.shape
assert colours > 100 and pixels[..., :3].std() > 5, f"a blank picture ({colours} colours)"
print(f"test-wheel: {sys.argv[1].rsplit('/', 1)[-1]} 640x360, {colours} colours")
PY

# The notebook API from the same venv, on the same song: the picture object and its pixels.
(cd "$work" && env -i PATH=/usr/bin:/bin HOME="$work/home" LOUDSCAPE_CACHE_DIR="$work/cache" \
    ${XDG_RUNTIME_DIR:+XDG_RUNTIME_DIR="$XDG_RUNTIME_DIR"} "$bin/python" -c '
import loudscape
picture = loudscape.render("song.flac", size=(320, 180))
pixels = picture.to_numpy()
assert pixels.shape == (180, 320, 4) and pixels.dtype.name == "uint8", pixels.shape
assert picture._repr_png_().startswith(b"\x89PNG")
print("test-wheel: loudscape.render from the venv:", picture)
')
echo "test-wheel: passed in $(($(date +%s) - start)) s"
