"""The extraction's cheaper paths give what the paths they replace give (issue 37, item 2):
bit for bit where the old path's values are kept, the file bytes where a file is copied."""

from __future__ import annotations

import errno
import io
import os
import subprocess
import sys

import numpy as np
import pytest

from loudscape_extract import ply, stream_decode
from loudscape_extract.audio import mix_rows_to_mono, mix_to_mono
from loudscape_extract.errors import ExtractError
from loudscape_extract.ply import copy_rest, write_atomically
from loudscape_extract.stream import spectral_blocks
from loudscape_extract.stream_decode import _StreamTruePeak

from conftest import musical_signal


@pytest.mark.parametrize("channels", [1, 2, 3, 6])
def test_the_mono_mix_of_rows_is_that_of_the_interleaved_samples_bit_for_bit(channels):
    rng = np.random.default_rng(3)
    samples = rng.standard_normal((4096, channels)).astype(np.float32)
    samples[0] = -0.0
    samples[1, 0] = -0.0
    samples[2] = 1e-45  # the smallest subnormal
    samples[3, 0] = np.float32(1) / 3
    samples[3, -1] = np.float32(2) / 3
    expected = mix_to_mono(samples)
    mono = mix_rows_to_mono(np.ascontiguousarray(samples.T))
    assert mono.dtype == np.float32
    assert np.array_equal(mono.view(np.uint32), expected.view(np.uint32))


def test_the_mono_mix_of_rows_refuses_a_flat_array():
    with pytest.raises(ExtractError, match=r"shape \(n_channels, n_samples\)"):
        mix_rows_to_mono(np.zeros(5, np.float32))


def _offset_maxima(blocks, offsets, *, maximum_only):
    meter = _StreamTruePeak(2, offsets=offsets, offset_maximum_only=maximum_only)
    peaks, maxima = [], []
    for block in blocks:
        _, peak, offset_peak = meter.feed(block)
        peaks.append(peak)
        maxima.append(offset_peak.max() if offset_peak.size else None)
        if maximum_only:
            assert offset_peak.shape == ((1,) if peak.size else (0,))
    return np.concatenate(peaks), maxima


@pytest.mark.parametrize("short", [False, True], ids=["fft-phases", "shifted-sums"])
def test_the_offset_peak_from_the_extremes_is_the_largest_shifted_peak_bit_for_bit(
    monkeypatch, short
):
    """The decoded signal's true peak (the DC-free one plus the channel means) from each
    phase's maximum and minimum equals the largest of the per-position peaks, block by block,
    the first block's partial windows included; the clean peaks do not change."""
    if short:
        monkeypatch.setattr(stream_decode, "_SHORT_PEAK", 1 << 30)
    rng = np.random.default_rng(8)
    signal = (0.3 * rng.standard_normal((2, 120_000))).astype(np.float32)
    signal[0, :5] = 0.9  # the partial windows at the start hold the first block's peak
    signal[1, 60_000] = -1.3  # a negative peak that the offset makes the largest
    offsets = np.array([0.25, -0.4], dtype=np.float32)
    cuts = [0, 3, 40_000, 40_010, 100_000, 120_000]  # a block too short to give any position
    blocks = [signal[:, a:b] for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
    peaks, expected = _offset_maxima(blocks, offsets, maximum_only=False)
    fast_peaks, maxima = _offset_maxima(blocks, offsets, maximum_only=True)
    assert np.array_equal(fast_peaks, peaks)
    assert expected[0] is None and maxima[0] is None
    for got, want in zip(maxima[1:], expected[1:], strict=True):
        assert np.float32(got).view(np.uint32) == np.float32(want).view(np.uint32)
    assert max(maxima[1:]) > 1.6  # -1.3 - 0.4 interpolated: the offsets count


@pytest.mark.parametrize("block_frames, hpss_frames", [(7, 50), (16, 16), (9, 1000)])
def test_wider_hpss_spans_cut_into_blocks_give_the_same_blocks_bit_for_bit(
    block_frames, hpss_frames
):
    y = musical_signal(sample_rate=8000, duration_s=4.0).astype(np.float32)
    kwargs = {"n_fft": 256, "hop_length": 128, "hpss": True, "block_frames": block_frames}
    plain = list(spectral_blocks(y, **kwargs))
    wide = list(spectral_blocks(y, hpss_frames=hpss_frames, **kwargs))
    assert [(b.start, b.stop) for b in wide] == [(b.start, b.stop) for b in plain]
    assert len(plain) > 3
    for a, b in zip(plain, wide, strict=True):
        assert b.magnitude.flags.c_contiguous and b.hp.flags.c_contiguous
        assert np.array_equal(a.magnitude.view(np.uint32), b.magnitude.view(np.uint32))
        assert np.array_equal(a.hp.view(np.uint32), b.hp.view(np.uint32))
        assert np.array_equal(a.decoded_peak, b.decoded_peak)


def _copied(tmp_path, name: str) -> bytes:
    source = tmp_path / f"{name}.src"
    source.write_bytes(bytes(range(256)) * 4099)
    target = tmp_path / f"{name}.out"
    with open(source, "rb") as reading, open(target, "w+b") as writing:
        reading.read(1000)  # from the source's position on
        writing.write(b"header\n")  # after what the target holds, buffered
        copy_rest(reading, writing)
        assert reading.read() == b""
        writing.write(b"!")  # the buffered object knows where the copy ended
    return target.read_bytes()


def test_copy_rest_appends_the_rest_of_the_source(tmp_path):
    expected = b"header\n" + (bytes(range(256)) * 4099)[1000:] + b"!"
    assert _copied(tmp_path, "kernel") == expected


@pytest.mark.parametrize("declined", ["missing", errno.EXDEV, errno.EINVAL])
def test_copy_rest_goes_through_user_space_where_the_kernel_declines(
    tmp_path, monkeypatch, declined
):
    if declined == "missing":
        monkeypatch.delattr(os, "copy_file_range", raising=False)
    else:

        def refuse(*_args):
            raise OSError(declined, os.strerror(declined))

        monkeypatch.setattr(os, "copy_file_range", refuse)
    expected = b"header\n" + (bytes(range(256)) * 4099)[1000:] + b"!"
    assert _copied(tmp_path, "user") == expected


def test_a_full_disk_while_copying_reads_as_a_full_disk(tmp_path, monkeypatch):
    def full(*_args):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "copy_file_range", full, raising=False)
    body = tmp_path / "body.bin"
    body.write_bytes(b"x" * 100)
    out = tmp_path / "out" / "a.ply"
    out.parent.mkdir()
    with open(body, "rb") as handle, pytest.raises(ExtractError) as caught:
        write_atomically(out, [b"head", handle])
    assert "no space left on the device" in str(caught.value)
    assert os.listdir(out.parent) == []  # no temporary left


def test_write_atomically_still_writes_bytes_and_arrays(tmp_path):
    out = tmp_path / "a.bin"
    write_atomically(out, [b"ab", np.arange(3, dtype="<u2"), io.BytesIO(b"cd")])
    assert out.read_bytes() == b"ab\x00\x00\x01\x00\x02\x00cd"
    assert ply.copy_rest is copy_rest


_REUSE_CHILD = """
import resource, numpy as np
from loudscape_extract.memory import keep_freed_memory
assert keep_freed_memory()
def blocks():
    for n in (3_000_000, 2_100_000, 1_500_000, 2_600_000):  # 6-24 MB arrays, freed each block
        a = np.ones(n, np.float32); b = np.ones(n, np.float64); c = a * 2; del a, b, c
blocks(); blocks()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(4):
    blocks()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def test_freed_blocks_are_reused_without_fresh_pages():
    """After keep_freed_memory, block after block of large arrays takes no new pages from
    the kernel (glibc's defaults give the 6-24 MB arrays back and fault about 12,000 pages
    in again over the four rounds here)."""
    done = subprocess.run(
        [sys.executable, "-c", _REUSE_CHILD], capture_output=True, text=True, check=True
    )
    assert int(done.stdout) < 500


def test_the_song_and_timeline_commands_keep_freed_memory(monkeypatch, tmp_path):
    from loudscape_extract import cli

    calls = []
    monkeypatch.setattr(cli, "keep_freed_memory", lambda: calls.append(1) or True)
    monkeypatch.setattr(cli, "one_blas_thread", lambda: 0)  # not this process's BLAS
    missing = str(tmp_path / "missing.wav")
    assert cli.main(["song", missing, "-o", str(tmp_path / "x.ply"), "--quiet"]) == 1
    assert calls == [1]
    assert cli.main(["export", str(tmp_path / "x.ply"), "-o", str(tmp_path / "x.vtp")]) == 1
    assert calls == [1]  # not for the other commands


_BLAS_CHILD = """
import ctypes, numpy as np
from loudscape_extract.blas_threads import one_blas_thread
paths = {l.split()[-1] for l in open("/proc/self/maps") if "openblas" in l.lower()}
numpy_blas = ctypes.CDLL(next(p for p in sorted(paths) if "numpy" in p))
before = numpy_blas.scipy_openblas_get_num_threads64_()
count = one_blas_thread()
print(before, count, numpy_blas.scipy_openblas_get_num_threads64_())
"""


def test_one_blas_thread_sets_numpys_openblas_to_one_thread():
    done = subprocess.run(
        [sys.executable, "-c", _BLAS_CHILD],
        capture_output=True,
        text=True,
        check=True,
        env=dict(os.environ, OPENBLAS_NUM_THREADS="2"),  # as on a machine with two cores
    )
    before, count, after = (int(word) for word in done.stdout.split())
    assert before == 2
    assert count >= 1
    assert after == 1


def test_the_song_command_runs_blas_on_one_thread(monkeypatch, tmp_path):
    from loudscape_extract import cli

    calls = []
    monkeypatch.setattr(cli, "one_blas_thread", lambda: calls.append(1) or 1)
    monkeypatch.setattr(cli, "keep_freed_memory", lambda: True)  # nor its allocator
    assert cli.main(["song", str(tmp_path / "no.wav"), "-o", str(tmp_path / "x.ply")]) == 1
    assert calls == [1]
