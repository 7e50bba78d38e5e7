"""Fuzzing the Python readers of untrusted files (the manifest parser, the PLY readers,
``loudscape.read_cloud``) and the notebook API's arguments.

    python preprocess/tests/fuzz_py.py --seconds 600 [--target manifest|ply|read_cloud|api|all]
                                       [--round N] [--json]

Inputs come from hypothesis strategies, built structurally (a manifest's header, rows, cells
with quotes, commas, line breaks, BOMs, odd years; a PLY's header lines, both metadata
layouts with their parts split and numbered right or wrong, generated JSON nested at will,
property lines, bodies of any length) and as byte mutations of valid files. Each input runs
under limits, and breaking one is a finding, as is any exception but :class:`ExtractError`:

- time: :data:`TIME_LIMIT_S` per input (``SIGALRM`` interrupts a runaway parse);
- memory: the tracemalloc peak of one input must stay under :data:`MEMORY_BASE` +
  :data:`MEMORY_FACTOR` x its size (an amplification is caught, not just a crash), and the
  process runs under ``RLIMIT_AS`` (:data:`ADDRESS_SPACE`), so a runaway allocation fails
  instead of taking the machine;
- consistency: the PLY readers (``read_ply``, ``map_ply``, ``read_ply_metadata``) agree on
  what they all accept, and a manifest's entries are files that exist, with plausible years
  and one-line values;
- ``read_cloud`` gets the PLY inputs as a regular file or behind what is not one (a FIFO, a
  link to /dev/zero, a directory, a missing name, a name that is no path at all): it answers
  at once with ExtractError or the same cloud as ``read_ply``;
- ``api``: ``loudscape.render`` with every argument drawn from good values and junk (NaN,
  strings, tuples of any length, bools, bytes; point arrays of any shape and dtype; metadata
  with NaN, non-string keys, odd types; file names starting with ``-``). The binary is a
  stand-in (``_run`` replaced in-process) that checks the command it would run: options only
  as ``--name=value`` with finite numbers, the source an absolute path after ``--``, the
  temporary cloud readable and equal to the points given. Anything but a picture or one
  one-line ExtractError is a finding, as is a temporary folder left behind.

Prints one line (or a JSON object): inputs run, seconds, findings (each with its input,
shortened). Exit status 1 when there is a finding.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import sys
import tempfile
import time
import tracemalloc

TARGETS = ("manifest", "ply", "read_cloud", "api")
TIME_LIMIT_S = 2.0
MEMORY_BASE = 32 << 20
MEMORY_FACTOR = 20
ADDRESS_SPACE = 6 << 30
_SONGS = ("s0.wav", "sub/s1.flac", "s 2.ogg")
_VALID_PLY = (
    b"ply\nformat binary_little_endian 1.0\n"
    b'comment loudscape-meta {"format_version":1,"mode":"song","point_count":1,"axes":{'
    b'"x":{"min":0,"max":1},"y":{"min":0,"max":1},"z":{"min":0,"max":1},'
    b'"scalar":{"min":0,"max":1},"hp":{"min":0,"max":1}}}\n'
    b"element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
    b"property float scalar\nproperty float hp\nend_header\n" + b"\x00" * 20
)


class _Timeout(Exception):
    pass


def _alarm(_signum, _frame):
    raise _Timeout


def _limited(call, size: int) -> str:
    """Run ``call()``; a finding (str) if it broke the time or memory limit or raised anything
    but ExtractError, else ``""``."""
    from loudscape_extract.errors import ExtractError

    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    start = time.perf_counter()
    signal.setitimer(signal.ITIMER_REAL, TIME_LIMIT_S)
    try:
        call()
    except ExtractError:
        pass
    except _Timeout:
        return f"took over {TIME_LIMIT_S:g} s"
    except MemoryError:
        return "ran out of memory (RLIMIT_AS)"
    except Exception as exc:  # noqa: BLE001 - every other exception is the finding
        return f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    peak = tracemalloc.get_traced_memory()[1] - before
    if peak > MEMORY_BASE + MEMORY_FACTOR * size:
        return f"peak {peak:,} bytes for a {size:,}-byte input"
    if time.perf_counter() - start > TIME_LIMIT_S:
        return f"took over {TIME_LIMIT_S:g} s"
    return ""


# --- targets -----------------------------------------------------------------------------


def manifest_target(data: bytes, folder: str) -> None:
    """Parse ``data`` as a manifest in ``folder`` (which holds the files of ``_SONGS``)."""
    from loudscape_extract.timeline.inputs import manifest_entries, plausible_years

    path = os.path.join(folder, "songs.csv")
    with open(path, "wb") as handle:
        handle.write(data)
    for need_year in (True, False):
        try:
            entries = manifest_entries(path, need_year=need_year)
        except Exception:
            raise
        low, high = plausible_years()
        for entry, line in entries:
            assert os.path.isfile(entry.path), entry
            assert entry.year is None or low <= entry.year <= high, entry
            assert need_year is False or entry.year is not None, entry
            for text in (entry.title, entry.artist):
                assert "\n" not in text and "\r" not in text, entry
            assert 1 <= line <= data.count(b"\n") + 1 + data.count(b"\r"), (line, entry)


def ply_target(data: bytes, folder: str) -> None:
    """Read ``data`` as a PLY with every Python reader; those that accept it must agree."""
    import numpy as np

    from loudscape_extract.contract import check_loadable
    from loudscape_extract.errors import ExtractError
    from loudscape_extract.ply import map_ply, read_ply, read_ply_metadata

    path = os.path.join(folder, "cloud.ply")
    with open(path, "wb") as handle:
        handle.write(data)
    results = {}
    for name, reader in (("read_ply", read_ply), ("map_ply", map_ply)):
        try:
            results[name] = reader(path)
        except ExtractError:
            pass
    try:
        header_meta = read_ply_metadata(path)
    except ExtractError:
        header_meta = None
    for points, metadata in results.values():
        assert points.ndim == 2 and points.shape[1] == 5
        assert header_meta == metadata, "read_ply_metadata disagrees"
        try:
            check_loadable(points, metadata)
        except ExtractError:
            pass
    if len(results) == 2:
        (a, meta_a), (b, meta_b) = results.values()
        assert meta_a == meta_b and np.array_equal(a, b, equal_nan=True), "readers disagree"


_KINDS = ("file", "fifo", "dev_zero", "directory", "missing", "not_a_path")


def read_cloud_target(case, folder: str) -> None:
    """``loudscape.read_cloud`` on ``data`` behind a path of the given kind; accepted files
    must read as ``read_ply`` reads them."""
    import numpy as np

    import loudscape
    from loudscape_extract.errors import ExtractError
    from loudscape_extract.ply import read_ply

    data, kind = case
    path = os.path.join(folder, f"read_cloud-{kind}.ply")
    if kind == "file":
        with open(path, "wb") as handle:
            handle.write(data)
    elif not os.path.lexists(path):
        if kind == "fifo":
            os.mkfifo(path)
        elif kind == "dev_zero":
            os.symlink("/dev/zero", path)
        elif kind == "directory":
            os.mkdir(path)
    argument = {"not_a_path": data, "missing": path + ".gone"}.get(kind, path)
    cloud = loudscape.read_cloud(argument)  # ExtractError is the expected answer
    assert kind == "file", f"read_cloud accepted a {kind}"
    try:
        points, metadata = read_ply(path)
    except ExtractError as exc:
        raise AssertionError(f"read_cloud accepted what read_ply refuses: {exc}") from None
    assert np.array_equal(cloud.points, points, equal_nan=True) and cloud.metadata == metadata


_API_RUNS: list[list[str]] = []


def _stand_in_run(command: list[str], *, timeout) -> str:
    """``loudscape.api._run`` for the fuzzer: checks the command, writes a small PNG."""
    import numpy as np

    from loudscape_extract.ply import read_ply

    assert all(isinstance(part, str) and "\n" not in part for part in command), command
    assert command[1:3] == ["--quiet", "render"] and command[-2] == "--", command
    name = command[-1]
    assert os.path.isabs(name) and os.path.isfile(name), name
    for option in command[3:-2]:
        key, equals, value = option.partition("=")
        assert key.startswith("--") and (equals or key in ("--no-labels", "--no-legend")), option
        for number in value.replace("x", ",").split(","):
            try:
                assert np.isfinite(float(number)), option
            except ValueError:
                pass  # a name (view, colour map...) or a path
    assert timeout is None or (timeout > 0 and np.isfinite(timeout)), timeout
    if os.path.basename(name) == "cloud.ply":
        read_ply(name)  # the temporary cloud of arrays is a valid file
    output = next(o.split("=", 1)[1] for o in command if o.startswith("--output="))
    with open(output, "wb") as handle:
        handle.write(_PNG)
    _API_RUNS.append(command)
    return ""


# A 1x1 PNG (signature, IHDR, IDAT, IEND): enough for Picture.
_PNG = bytes.fromhex(
    "89504e470d0a1a0a0000000d49484452000000010000000108060000001f15c489"
    "0000000d4944415478da63f8ffff3f0005fe02fea7d6a4f20000000049454e44ae426082"
)


def api_target(case, folder: str) -> None:
    """``loudscape.render`` (and ``read_cloud``) with the drawn arguments, the binary a
    stand-in; a picture or one one-line ExtractError, and no temporary folder left."""
    import tempfile as tempfile_module

    import loudscape
    import loudscape.api as api
    from loudscape_extract.errors import ExtractError

    source, kwargs, junk = case
    if isinstance(source, str):
        source = os.path.join(folder, "api", source)  # "-i.ply" and friends: real files
    api._run = _stand_in_run
    os.environ["LOUDSCAPE_BIN"] = sys.executable  # found, never run
    previous = tempfile_module.tempdir
    private = os.path.join(folder, "api-tmp")
    os.makedirs(private, exist_ok=True)
    tempfile_module.tempdir = private
    try:
        for call in (
            lambda: loudscape.render(source, **kwargs),
            lambda: loudscape.read_cloud(junk),
        ):
            try:
                picture = call()
            except ExtractError as exc:
                message = str(exc)
                assert message and "\n" not in message, message
                continue
            if isinstance(picture, loudscape.Picture):
                assert picture.width == 1 and picture.warnings == ()
        assert os.listdir(private) == [], f"left behind: {os.listdir(private)}"
    finally:
        tempfile_module.tempdir = previous


# --- strategies --------------------------------------------------------------------------


def strategies():
    """``{"manifest": ..., "ply": ...}``: hypothesis strategies of input bytes."""
    from hypothesis import strategies as st

    tokens = list('ab ,"\n\r\t;\\xé\ufeff\x00') + ["19", "20", "0", "\udcff"]
    cell_text = st.lists(st.sampled_from(tokens), max_size=12).map("".join)
    path_cell = st.one_of(st.sampled_from(_SONGS), st.sampled_from(["", "missing.wav", "sub"]))
    year_cell = st.one_of(
        st.integers(1800, 2100).map(str),
        st.sampled_from(["", " ", "abc", "1e3", "-1", "2000.0", "99999999999999999999"]),
    )

    def quoted(cell):
        return st.sampled_from([cell, f'"{cell}"', f'"{cell}', f'{cell}"', cell.replace('"', '""')])

    row = st.tuples(path_cell, year_cell, cell_text, cell_text).flatmap(
        lambda cells: st.tuples(*(quoted(c) for c in cells))
    )
    header = st.sampled_from(
        ["path,year", "path,year,title,artist", "\ufeffpath,year,title", "year,path,", "file,when"]
    )
    ending = st.sampled_from(["\n", "\r\n", "\r"])
    manifest_text = st.builds(
        lambda head, rows, end, cut: (
            head + end + end.join(",".join(r[: 2 + cut]) for r in rows) + end
        ),
        header,
        st.lists(row, max_size=8),
        ending,
        st.integers(0, 2),
    )
    manifest = st.one_of(
        manifest_text.map(lambda text: text.encode("utf-8", "surrogatepass")),
        st.binary(max_size=300),
    )

    json_values = st.recursive(
        st.one_of(
            st.none(),
            st.booleans(),
            st.integers(-(2**70), 2**70),
            st.floats(allow_nan=True, allow_infinity=True),
            st.text(max_size=8),
        ),
        lambda inner: st.one_of(
            st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=4)
        ),
        max_leaves=40,
    )
    axis = st.fixed_dictionaries(
        {"min": st.sampled_from([0.0, -1.0, 1.0, float("nan")]), "max": st.sampled_from([1.0, 2.0])}
    )
    metadata = st.fixed_dictionaries(
        {
            "format_version": st.sampled_from([1, 2, 3, "2", 2.0, None]),
            "mode": st.sampled_from(["song", "timeline", "x"]),
            "point_count": st.integers(-1, 6),
            "axes": st.dictionaries(
                st.sampled_from(["x", "y", "z", "scalar", "hp"]), axis, max_size=5
            ),
        },
        optional={"extra": json_values, "source": st.fixed_dictionaries({"path": st.text()})},
    )
    ply = _ply_strategy(st, metadata)
    return {
        "manifest": manifest,
        "ply": ply,
        "read_cloud": st.tuples(
            st.one_of(ply, st.just(_VALID_PLY)),
            st.sampled_from(_KINDS),
        ),
        "api": _api_strategy(st, json_values),
    }


def _api_strategy(st, json_values):
    import numpy as np

    junk = st.one_of(
        st.none(),
        st.booleans(),
        st.integers(-(2**70), 2**70),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=12),
        st.binary(max_size=6),
        st.lists(st.one_of(st.floats(allow_nan=True), st.integers(-5, 5000)), max_size=4).flatmap(
            lambda items: st.sampled_from([items, tuple(items), np.array(items, dtype=object)])
        ),
        st.builds(object),
        st.floats(allow_nan=True, allow_infinity=True, width=32).map(np.float32),
        st.integers(-(2**63), 2**63 - 1).map(np.int64),
        st.booleans().map(np.bool_),
    )

    def argument(good):
        return st.one_of(good, good, good, junk)  # mostly good: a junk one refuses the call

    number = st.floats(-2, 2000, allow_nan=False)
    names = {
        "view": st.sampled_from(["points", "surface", "volume", "-x", "sideways"]),
        "size": st.tuples(st.integers(-1, 9000), st.integers(-1, 9000)),
        "camera": st.tuples(number, number, number),
        "point_size": st.one_of(st.floats(0.5, 64), st.sampled_from([-1, 0, 0.49, 65])),
        "iso": st.floats(-0.5, 1.5),
        "method": st.sampled_from(["mt", "dc", "--help"]),
        "colormap": st.sampled_from(["classic", "viridis", "jet"]),
        "background": st.sampled_from(["dark", "light", ""]),
        "freq_axis": st.sampled_from(["linear", "log", "mel", "bark"]),
        "labels": st.booleans(),
        "legend": st.booleans(),
        "timeout": st.sampled_from([None, 30, 0.5, 0, -1]),
        "metadata": st.one_of(
            st.none(),
            st.dictionaries(st.text(max_size=6), json_values, max_size=3),
            st.dictionaries(st.text(max_size=6), junk, max_size=2),
            junk,
        ),
    }
    kwargs = st.fixed_dictionaries({}, optional={k: argument(v) for k, v in names.items()})

    dtypes = st.sampled_from(["f4", "f8", "i4", "u1", "f2", "U3", "c8", "?", "O"])
    shapes = st.tuples(st.integers(0, 6), st.integers(0, 7)) | st.tuples(st.integers(0, 3))
    values = st.sampled_from([0.5, 0.0, 1.0, float("nan"), 1e39, -3, "0.5", "x"])

    def array(dtype, shape, value):
        try:
            with np.errstate(all="ignore"):
                return np.full(shape, value, dtype=dtype)
        except (ValueError, TypeError, OverflowError):
            return np.zeros(shape, dtype=dtype)

    good_points = st.builds(
        array,
        st.sampled_from(["f4", "f8", "i4"]),
        st.tuples(st.integers(1, 6), st.just(5)),
        st.sampled_from([0.5, 0.0, 1.0]),
    )
    points = st.one_of(good_points, st.builds(array, dtypes, shapes, values))
    pair = st.tuples(points, st.one_of(kwargs.map(lambda k: k.get("metadata")), junk))
    files = st.sampled_from(["-i.ply", "--help.ply", "good.ply", "missing.ply", "-"])
    source = st.one_of(files, points, pair, points.map(lambda p: p.tolist()), junk)
    return st.tuples(source, kwargs, junk)


def _ply_strategy(st, metadata):
    def meta_lines(meta_json: str, layout: int, splits: list, renumber: int) -> list[str]:
        if layout == 1:
            return [f"comment loudscape-meta {meta_json}"]
        text = meta_json.replace(" ", "\\u0020")
        cuts = sorted({min(max(c, 0), len(text)) for c in splits})
        bounds = zip([0, *cuts], [*cuts, len(text)], strict=True)
        parts = [text[a:b] for a, b in bounds if text[a:b]] or [""]
        n = len(parts)
        lines = [f"comment loudscape-meta-v2 {i + 1}/{n} {p}" for i, p in enumerate(parts)]
        if renumber == 1 and n > 1:
            lines[0], lines[1] = lines[1], lines[0]
        elif renumber == 2:
            lines = lines[:-1]
        return lines

    def build(meta, layout, splits, renumber, n, props, fmt, body_delta, nested, junk):
        meta_json = json.dumps(meta, separators=(",", ":"))
        if nested:
            meta_json = meta_json[:-1] + ',"deep":' + "[" * nested + "]" * nested + "}"
        lines = ["ply", fmt, *meta_lines(meta_json, layout, splits, renumber)]
        lines += [f"element vertex {n}", *(f"property float {p}" for p in props)]
        lines += [*junk, "end_header"]
        body = b"\x00\x00\x00\x3f" * max(5 * (n if isinstance(n, int) else 0) + body_delta, 0)
        return ("\n".join(lines) + "\n").encode("utf-8", "surrogatepass") + body

    structured = st.builds(
        build,
        metadata,
        st.sampled_from([1, 2]),
        st.lists(st.integers(0, 200), max_size=4),
        st.integers(0, 2),
        st.one_of(st.integers(-1, 6), st.sampled_from(["x", "99999999999999999999", "1e3"])),
        st.sampled_from(
            [
                ["x", "y", "z", "scalar", "hp"],
                ["x", "y", "z"],
                ["x", "y", "z", "scalar", "hp", "hp"],
                ["y", "x", "z", "scalar", "hp"],
            ]
        ),
        st.sampled_from(
            ["format binary_little_endian 1.0", "format ascii 1.0", "format binary_big_endian 1.0"]
        ),
        st.integers(-6, 6),
        st.sampled_from([0, 0, 0, 50, 5000]),
        st.lists(st.sampled_from(["comment x", "element face 1", "", "obj_info q"]), max_size=2),
    )
    return st.one_of(structured, st.builds(_mutate, structured, st.randoms()))


def _mutate(data: bytes, rng) -> bytes:
    """Flip, drop, repeat or insert bytes of a generated file."""
    data = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if not data:
            break
        at = rng.randrange(len(data))
        choice = rng.randrange(4)
        if choice == 0:
            data[at] ^= 1 << rng.randrange(8)
        elif choice == 1:
            del data[at : at + rng.randint(1, 16)]
        elif choice == 2:
            data[at:at] = data[at : at + rng.randint(1, 64)] * rng.randint(1, 8)
        else:
            data[at:at] = bytes([rng.choice(b'\n\r "[{}]0\\')]) * rng.randint(1, 4)
    return bytes(data)


# --- the run -----------------------------------------------------------------------------


def _input_size(case) -> int:
    """The bytes of an input, for the memory limit (the file's bytes; 0 for arguments)."""
    if isinstance(case, bytes):
        return len(case)
    if isinstance(case, tuple) and case and isinstance(case[0], bytes):
        return len(case[0])
    return 0


def _round(target, name: str, folder: str, counts: dict, findings: list):
    def one(data):
        counts[name] += 1
        problem = _limited(lambda: target(data, folder), _input_size(data))
        if problem:
            findings.append({"target": name, "problem": problem, "input": data[:300]})
            raise AssertionError(problem)

    return one


def run(seconds: float, targets: list[str], *, examples_per_round: int = 200) -> dict:
    """Fuzz ``targets`` for about ``seconds``; the figures (inputs, seconds, findings)."""
    from hypothesis import HealthCheck, given, seed, settings

    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
    signal.signal(signal.SIGALRM, _alarm)
    found = strategies()
    functions = {
        "manifest": manifest_target,
        "ply": ply_target,
        "read_cloud": read_cloud_target,
        "api": api_target,
    }
    counts = dict.fromkeys(targets, 0)
    findings: list[dict] = []
    start = time.perf_counter()
    round_number = 0
    with tempfile.TemporaryDirectory() as folder:
        os.makedirs(os.path.join(folder, "sub"))
        for song in _SONGS:
            with open(os.path.join(folder, song), "wb") as handle:
                handle.write(b"RIFF")
        os.makedirs(os.path.join(folder, "api"))
        for name in ("-i.ply", "--help.ply", "good.ply", "-"):
            with open(os.path.join(folder, "api", name), "wb") as handle:
                handle.write(_VALID_PLY)
        # Warm up (imports, caches) before measuring: only the inputs' own memory counts.
        manifest_target(b"path,year\ns0.wav,1990\n", folder)
        ply_target(_VALID_PLY, folder)
        read_cloud_target((_VALID_PLY, "file"), folder)
        api_target(("-i.ply", {}, None), folder)
        assert _API_RUNS and _API_RUNS[-1][-1].endswith("/-i.ply"), "-i.ply was not drawn"
        tracemalloc.start()
        # Every target gets one round at least, however short the run.
        while time.perf_counter() - start < seconds or round_number < len(targets):
            name = targets[round_number % len(targets)]
            round_number += 1
            target = functions[name]

            one = _round(target, name, folder, counts, findings)
            one = given(found[name])(one)
            one = settings(
                max_examples=examples_per_round,
                deadline=None,
                database=None,
                suppress_health_check=list(HealthCheck),
            )(one)
            try:
                seed(round_number)(one)()
            except Exception:  # noqa: BLE001 - one failure or a group of them, all recorded
                pass  # recorded (hypothesis shrinks it first: the last one recorded is minimal)
    tracemalloc.stop()
    unique = {(f["target"], f["problem"]): f for f in findings}
    return {
        "inputs": counts,
        "seconds": round(time.perf_counter() - start, 1),
        "findings": [
            {"target": t, "problem": p, "input": repr(f["input"])} for (t, p), f in unique.items()
        ],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--target", choices=(*TARGETS, "all"), default="all")
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")
    parser.add_argument(
        "--round", type=int, default=200, help="inputs per hypothesis run, targets alternate"
    )
    args = parser.parse_args(argv)
    targets = list(TARGETS) if args.target == "all" else [args.target]
    report = run(args.seconds, targets, examples_per_round=args.round)
    if args.json:
        print(json.dumps(report))
    else:
        counts = ", ".join(f"{n:,} {t}" for t, n in report["inputs"].items())
        print(
            f"fuzz-py: {counts} inputs in {report['seconds']} s, "
            f"{len(report['findings'])} finding(s)"
        )
        for item in report["findings"]:
            print(f"  {item['target']}: {item['problem']}: {item['input']}")
    return 1 if report["findings"] else 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    sys.exit(main())
