# loudscape: the two commands a user needs are `make run` and `make test`.
# Each does its own set-up: system packages (Debian, when root), the Python venv, the Rust build.

VENV    ?= .venv
PYTHON  ?= python3
PY      := $(VENV)/bin/python
CARGO   ?= cargo
OUT     ?= out
DEMO_SONG     := data/demo_song.ply
DEMO_TIMELINE := data/demo_timeline.ply

# Vulkan's window-system probing wants a runtime folder; give it one where the session has none.
export XDG_RUNTIME_DIR ?= $(shell d=/tmp/loudscape-runtime-$$(id -u); mkdir -p $$d && chmod 700 $$d && echo $$d)

# Run under a virtual X server when there is no display (CI, ssh sessions), so the window tests run.
# Headroom of X clients (Xvfb's default is 256): in a full run a late window test has once
# failed to connect ("Failed to open connection to X server"), cause not found; the test
# processes were checked not to hold connections of their own.
XVFB := $(if $(DISPLAY)$(WAYLAND_DISPLAY),,xvfb-run -a -s "-screen 0 1600x1000x24 -maxclients 2048 -noreset")

.PHONY: run test system venv native build lint-rust test-rust lint-py test-py test-mesh real-music fuzz fuzz-smoke fuzz-py demo clean bench-window bench-surface check-platforms test-wheel bench-peers web test-web

system:
	@bash scripts/setup-system.sh

$(VENV)/.installed: preprocess/pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --no-cache-dir --upgrade pip
	$(PY) -m pip install -q --no-cache-dir -e './preprocess[dev]'
	touch $@

venv: $(VENV)/.installed

# The extractor's compiled running median (crates/median, loaded by
# preprocess/loudscape_extract/native.py) built into the package the venv installs editable;
# without it the extractor falls back to scipy (the same medians, slower). Copied through a
# temporary name so that a running extractor keeps the file it loaded.
NATIVE_TARGET_DIR := $(or $(CARGO_TARGET_DIR),target)
NATIVE_SUFFIX     := $(if $(filter Darwin,$(shell uname -s)),.dylib,.so)
NATIVE_LIB        := preprocess/loudscape_extract/_median$(NATIVE_SUFFIX)
native:
	$(CARGO) build --release -p loudscape-median
	cp $(NATIVE_TARGET_DIR)/release/libloudscape_median$(NATIVE_SUFFIX) $(NATIVE_LIB).tmp
	mv -f $(NATIVE_LIB).tmp $(NATIVE_LIB)

build: system
	$(CARGO) build --release

# Opens the demo in a window; with no display, renders every view of the demo to PNG files.
# The venv holds the extractor the app runs when it is given a song instead of a cloud.
run: build venv native
	@if [ -n "$(DISPLAY)$(WAYLAND_DISPLAY)" ] || [ "$$(uname -s)" = Darwin ]; then \
		./target/release/loudscape $(DEMO_SONG) $(wildcard $(DEMO_TIMELINE)); \
	else \
		echo "No display found: rendering the demo to PNG files instead."; \
		./target/release/loudscape render-demo --out-dir $(OUT) $(DEMO_SONG) $(wildcard $(DEMO_TIMELINE)); \
	fi

lint-rust:
	$(CARGO) fmt --all --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings

# Xvfb runs with -noreset: by default it resets whenever its last client leaves, and a window
# opened during the reset failed with "Failed to open connection to X server" (the window tests
# open and close one window after another, so now and then one fell into that gap).
# The window tests (every test named "window...") run after the others, one at a time, with the
# machine to themselves: they drive real windows on one screen, and in full runs on 2 cores with
# the GPU tests beside them a window now and then failed to appear (each passes alone).
test-rust: system venv
	$(XVFB) $(CARGO) test -- --skip window
	$(XVFB) $(CARGO) test window -- --test-threads=1
	$(CARGO) test -q -p loudscape-shader-msl
	$(CARGO) test -q -p loudscape-median

lint-py: venv
	$(VENV)/bin/ruff check preprocess bench tests/python tests/web docs
	$(VENV)/bin/ruff format --check preprocess bench tests/python tests/web docs

# Freely licensed game soundtracks from Debian packages (cached in data/real-music/) for
# preprocess/tests/test_real_music.py; fails with one line if a download fails.
real-music:
	@bash scripts/fetch-real-music.sh data/real-music

# The tests, and the `>>>` examples in the docstrings of both packages (they run as written).
# The extractor's suite runs in PYTEST_JOBS processes (pytest-xdist), each test file in one of
# them, so a file's module fixtures are built once; PYTEST_JOBS=0 runs it in this process.
# tests/python stays in one process: its window test (an Xvfb screen of its own) once failed to
# open its window with another file's tests beside it (that screen now runs with -noreset, as
# the window tests' does: bench/bench_window.py). LOUDSCAPE_REQUIRE_NATIVE=1: the
# compiled running median must be the one in use (preprocess/tests/test_hpss_native.py).
PYTEST_JOBS ?= auto
PYTEST_PARALLEL = $(if $(filter 0,$(PYTEST_JOBS)),,-n $(PYTEST_JOBS) --dist loadfile)
test-py: export LOUDSCAPE_REQUIRE_NATIVE = 1
test-py: venv native real-music
	$(VENV)/bin/pytest -q $(PYTEST_PARALLEL) preprocess/tests
	$(VENV)/bin/pytest -q --doctest-modules preprocess/loudscape_extract preprocess/loudscape

# The app's isosurfaces against scikit-image, through the `loudscape` binary (the one the Rust
# tests use: `cargo build` would rebuild with other features).
test-mesh: system venv native
	$(CARGO) test --no-run -q
	LOUDSCAPE_BIN=target/debug/loudscape $(VENV)/bin/pytest -q tests/python

# The fuzzers (docs/RELIABILITY.md): examples/fuzz_ply.rs mutates PLY bytes against the loader,
# its metadata parser and the axes/read-outs; examples/fuzz_formats.rs builds version-2
# metadata parts, streams of unknown length, .npy arrays and their .json descriptions from
# their structure. Each input has a memory and time limit (an amplification is a finding).
# `make test` runs a few seconds of each in the overflow-checked debug build the tests already
# built (a release build only for this would double CI's compile time); `make fuzz N=5000000`
# runs N inputs of each in release. Findings are saved under fuzz-crashes/.
FUZZ_SECONDS ?= 3
N ?= 1000000
fuzz-smoke:
	$(CARGO) run -q --example fuzz_ply -- --seconds $(FUZZ_SECONDS)
	$(CARGO) run -q --example fuzz_formats -- --seconds $(FUZZ_SECONDS)

# `make fuzz` also runs the Python fuzzers (fuzz-py below).
fuzz: fuzz-py
	$(CARGO) run -q --release --example fuzz_ply -- --inputs $(N)
	$(CARGO) run -q --release --example fuzz_formats -- --inputs $(N)

# The Python readers of untrusted files (manifest parser, PLY readers, read_cloud on any kind of
# path) and the notebook API's arguments, fuzzed with hypothesis,
# each input under a time and memory limit (preprocess/tests/fuzz_py.py); a few seconds of it
# run in test-py. FUZZ_PY_SECONDS=3600 for a long run.
FUZZ_PY_SECONDS ?= 300
fuzz-py: venv
	OPENBLAS_NUM_THREADS=1 PYTHONPATH=preprocess $(VENV)/bin/python preprocess/tests/fuzz_py.py --seconds $(FUZZ_PY_SECONDS)

# macOS and Windows kept building: the code checked for both (all targets, warnings as errors) in
# a target folder of its own, so the host build is left alone; one cargo run for both targets,
# so the build scripts and proc-macros they share are compiled once. The web page's viewer is built for
# wasm32 by `make web` (warnings as errors too) and tested in a browser by `make test-web`, both
# in `make test`. Needs rustup (downloads each target's standard library once).
PLATFORMS ?= aarch64-apple-darwin x86_64-pc-windows-msvc
check-platforms: system
	rustup target add $(PLATFORMS)
	RUSTFLAGS="-D warnings" CARGO_TARGET_DIR=target/platforms $(CARGO) check --all-targets $(addprefix --target ,$(PLATFORMS))
	RUSTFLAGS="-D warnings" CARGO_TARGET_DIR=target/platforms $(CARGO) check -p loudscape-median --all-targets $(addprefix --target ,$(PLATFORMS))

# The pip way: build the wheel, install it into a fresh venv, render a song from it. pip builds
# the app in release (about 6 minutes from clean); `make test` builds the wheel with the dev
# profile instead (WHEEL_PROFILE=dev), which links the binary the Rust tests already built, so
# the same packaging, install and render are tested without a second build of the whole
# dependency tree (CI's time budget). No code differs between the two profiles (no
# debug_assertions in src/).
WHEEL_PROFILE ?= release
test-wheel: system
	SETUPTOOLS_RUST_CARGO_PROFILE=$(WHEEL_PROFILE) bash scripts/test-wheel.sh $(PYTHON)

test: system lint-rust lint-py test-rust test-py test-mesh fuzz-smoke
test: check-platforms test-web test-wheel
test: WHEEL_PROFILE = dev

# Benchmarks, not part of `make test` (minutes each; figures in docs/PERFORMANCE.md).
# 1,000 short songs cold (process pool, two-worker Dask LocalCluster) and the warm rebuild of a
# 10,000-song timeline, kept in out/bench-timeline/timeline_10000.ply.
bench-timeline: venv native
	$(PY) bench/bench_timeline.py

# Peak memory of Song extraction on 5, 20 and 60-minute tracks.
bench-memory: venv native
	$(PY) bench/bench_memory.py

# Isosurfaces, both engines (GPU passes, CPU extraction) against VTK's flying edges and
# scikit-image's marching cubes on the same fields, in the same run.
bench-surface: build venv native
	$(PY) bench/bench_surface.py --loudscape target/release/loudscape --runs 9

# loudscape against its peers, in the same run, alternated, medians and ratios (issue 37;
# figures in docs/PERFORMANCE.md): the volume against VTK's CPU ray caster on the same grid,
# camera and ramp; song extraction against librosa's stft+hpss and ffmpeg's ebur128; an 8-track
# timeline against ffmpeg two at a time; the isosurfaces against VTK's flying edges; videos
# (points and volume, still and orbiting camera) against ffmpeg's showcqt spectrum video.
bench-peers: build venv native real-music
	$(PY) bench/peers_volume.py --loudscape target/release/loudscape
	$(PY) bench/peers_extract.py
	$(PY) bench/bench_surface.py --loudscape target/release/loudscape --runs 9
	$(PY) bench/peers_video.py --loudscape target/release/loudscape

# The window's frame loop under recorded input, release build under Xvfb at 1280x720: orbit
# frame rates per view, hover read-out latency, isovalue sweep rate, on the demo and a ~5 M-point
# real song (extracted once into out/bench-window/). BEFORE=path/to/loudscape adds its column.
bench-window: venv native real-music
	$(CARGO) build --release
	$(PY) bench/bench_window.py --loudscape target/release/loudscape $(if $(BEFORE),--vs $(BEFORE))

# The web page's viewer (`loudscape page`, src/web/): the library built for wasm32 with the `web`
# profile (warnings as errors), then wasm-bindgen's glue, into target/web where `loudscape page`
# looks for it. Rebuilt only when a source, a shader or the manifest changed. The rustup target
# is added, and wasm-bindgen's command line of the version in Cargo.lock (the glue must match
# the library) is the one on PATH when it is that version, else built once into
# target/tools/ (`cargo install`, a few minutes).
WEB_OUT        := target/web
WEB_TARGET_DIR := $(or $(CARGO_TARGET_DIR),target)
WASM_BINDGEN_VERSION := $(shell sed -n '/^name = "wasm-bindgen"$$/{n;s/version = "\(.*\)"/\1/p}' Cargo.lock)
WASM_BINDGEN_ROOT    := target/tools/wasm-bindgen-$(WASM_BINDGEN_VERSION)
WASM_BINDGEN   := $(shell command -v wasm-bindgen >/dev/null 2>&1 && wasm-bindgen --version 2>/dev/null | grep -q " $(WASM_BINDGEN_VERSION)$$" && echo wasm-bindgen || echo $(WASM_BINDGEN_ROOT)/bin/wasm-bindgen)
WEB_SOURCES    := $(shell find src shaders -type f) Cargo.toml Cargo.lock

$(WASM_BINDGEN_ROOT)/bin/wasm-bindgen:
	$(CARGO) install -q wasm-bindgen-cli --version $(WASM_BINDGEN_VERSION) --root $(WASM_BINDGEN_ROOT)

$(WEB_OUT)/loudscape_bg.wasm: $(WEB_SOURCES) | $(filter-out wasm-bindgen,$(WASM_BINDGEN))
	@rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown || rustup target add wasm32-unknown-unknown
	$(CARGO) rustc --lib --crate-type cdylib --target wasm32-unknown-unknown --profile web -- -D warnings
	$(WASM_BINDGEN) --target no-modules --no-typescript --remove-name-section --remove-producers-section --out-dir $(WEB_OUT) \
		$(WEB_TARGET_DIR)/wasm32-unknown-unknown/web/loudscape.wasm
	touch $@

web: system $(WEB_OUT)/loudscape_bg.wasm

# The page in a real browser: Debian's chromium headless (scripts/setup-system.sh installs it)
# through Playwright (the venv's dev extras), on the binary the Rust tests use (as test-mesh).
test-web: web venv
	$(CARGO) test --no-run -q
	LOUDSCAPE_BIN=$(WEB_TARGET_DIR)/debug/loudscape $(VENV)/bin/pytest -q tests/web

clean:
	$(CARGO) clean
	rm -rf $(VENV) $(OUT) $(NATIVE_LIB)
