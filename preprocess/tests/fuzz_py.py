"""Fuzzing the Python readers of untrusted files: the manifest parser and the PLY reader.

    python preprocess/tests/fuzz_py.py --seconds 600 [--target manifest|ply|all] [--round N]
                                       [--json]

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
  and one-line values.

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
    return {"manifest": manifest, "ply": _ply_strategy(st, metadata)}


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


def _round(target, name: str, folder: str, counts: dict, findings: list):
    def one(data):
        counts[name] += 1
        problem = _limited(lambda: target(data, folder), len(data))
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
    functions = {"manifest": manifest_target, "ply": ply_target}
    counts = dict.fromkeys(targets, 0)
    findings: list[dict] = []
    start = time.perf_counter()
    round_number = 0
    with tempfile.TemporaryDirectory() as folder:
        os.makedirs(os.path.join(folder, "sub"))
        for song in _SONGS:
            with open(os.path.join(folder, song), "wb") as handle:
                handle.write(b"RIFF")
        # Warm up (imports, caches) before measuring: only the inputs' own memory counts.
        manifest_target(b"path,year\ns0.wav,1990\n", folder)
        ply_target(_VALID_PLY, folder)
        tracemalloc.start()
        while time.perf_counter() - start < seconds:
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
    parser.add_argument("--target", choices=("manifest", "ply", "all"), default="all")
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")
    parser.add_argument(
        "--round", type=int, default=200, help="inputs per hypothesis run, targets alternate"
    )
    args = parser.parse_args(argv)
    targets = ["manifest", "ply"] if args.target == "all" else [args.target]
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
