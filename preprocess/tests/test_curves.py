"""Loudness over time in the song metadata: short-term loudness against libebur128, PSR
lower where a real limiter works, overs, and a 60-minute song's curves well under 1 MB."""

import json

import numpy as np
import pytest
import soundfile
from test_dynamics import RATE, dynamic_stereo, ebur128

from loudscape_extract.curves import MAX_CURVE_POINTS, MAX_OVERS, _merged, loudness_curves
from loudscape_extract.dynamics import dynamics_from_segments
from loudscape_extract.song import extract_song


def _curves(tmp_path, samples, name):
    wav = tmp_path / f"{name}.wav"
    soundfile.write(wav, samples, RATE, subtype="FLOAT")
    metadata = extract_song(str(wav), str(tmp_path / f"{name}.ply"), n_fft=1024, hop_length=512)
    return metadata["loudness"]


def test_short_term_curve_matches_libebur128(tmp_path):
    x = dynamic_stereo(4, duration_s=20.0)
    curves = _curves(tmp_path, x, "song")
    reference, _ = ebur128(x, RATE, short_term=True)
    ours = np.array(curves["short_term_lufs"], dtype=float)
    assert curves["rate_hz"] == 10.0 and curves["short_term_start_s"] == 1.5
    assert ours.shape == reference.shape
    np.testing.assert_allclose(ours, reference, atol=0.1)
    momentary = np.array(curves["momentary_lufs"], dtype=float)
    assert momentary.shape[0] == reference.shape[0] + 26  # 400 ms windows, every 100 ms
    assert momentary.max() > ours.max()  # shorter windows swing wider


def test_a_limited_copy_shows_lower_psr_where_the_limiter_works(tmp_path):
    pedalboard = pytest.importorskip("pedalboard")
    # a quiet verse (peaks near -20 dBFS, under the threshold) and a loud chorus
    x = dynamic_stereo(5, duration_s=24.0, depth=0.0).astype(np.float32)
    x[: 12 * RATE] *= np.float32(0.1)
    board = pedalboard.Pedalboard([pedalboard.Limiter(threshold_db=-14.0, release_ms=100.0)])
    limited = board(x.T.copy(), RATE).T
    original = _curves(tmp_path, x, "original")
    squashed = _curves(tmp_path, limited, "limited")
    psr_a = np.array(original["psr_db"], dtype=float)
    psr_b = np.array(squashed["psr_db"], dtype=float)
    # where the limiter works: JUCE's limiter adds make-up gain (threshold to 0 dBFS) and
    # cuts the peaks above it, so its gain reduction is the make-up minus the gain it applied
    hop = RATE // 10
    n_seg = x.shape[0] // hop
    rms = lambda s: np.sqrt((s[: n_seg * hop].reshape(n_seg, hop, -1) ** 2).mean(axis=(1, 2)))  # noqa: E731
    gain = 20 * np.log10(rms(limited) / rms(x))
    reduction = gain.max() - gain
    per_window = np.array([reduction[i : i + 30].max() for i in range(psr_a.shape[0])])
    working, idle = per_window > 3.0, per_window < 0.5
    working, idle = per_window > 3.0, per_window < 0.1
    assert working.sum() > 20 and idle.sum() > 20
    assert np.median(psr_a[working] - psr_b[working]) > 2.0
    assert np.median(np.abs(psr_a[idle] - psr_b[idle])) < 0.3


def test_overs_mark_the_segments_above_0_and_minus_1_dbtp():
    n = 100
    boundaries = np.arange(n + 1) * 4800
    energy = np.full(n, 1e-3 * 4800)
    peak = np.full(n, 0.5)
    peak[10:13] = 1.2  # +1.6 dBTP
    peak[50] = 0.95  # -0.45 dBTP: over -1 only
    dynamics = dynamics_from_segments(
        energy, boundaries, segment_peak=peak, true_peak=1.2,
        mono_squares=energy, mono_peaks=peak, sample_rate=48000,
    )  # fmt: skip
    curves = loudness_curves(
        energy, boundaries, segment_peak=peak, dynamics=dynamics, sample_rate=48000
    )
    assert curves["overs_0dbtp"] == [[1.0, 1.3]] and curves["overs_0dbtp_count"] == 1
    assert curves["overs_1dbtp"] == [[1.0, 1.3], [5.0, 5.1]]


def test_a_60_minute_songs_curves_stay_well_under_a_megabyte():
    n = 36000
    rng = np.random.default_rng(0)
    boundaries = np.arange(n + 1) * 4410
    energy = 4410 * 10 ** (rng.uniform(-4, -1, n))
    peak = rng.uniform(0.3, 1.05, n)
    dynamics = dynamics_from_segments(
        energy, boundaries, segment_peak=peak, true_peak=1.05,
        mono_squares=energy, mono_peaks=peak, sample_rate=44100,
    )  # fmt: skip
    curves = loudness_curves(
        energy, boundaries, segment_peak=peak, dynamics=dynamics, sample_rate=44100
    )
    assert len(curves["momentary_lufs"]) <= MAX_CURVE_POINTS
    assert curves["rate_hz"] == pytest.approx(10.0 / 3.0)
    size = len(json.dumps(curves))
    assert size < 400_000, size


def test_whole_track_and_streamed_curves_agree(tmp_path):
    from loudscape_extract import decode_audio, track_features

    x = dynamic_stereo(6, duration_s=8.0)
    streamed = _curves(tmp_path, x, "song")
    whole = track_features(decode_audio(str(tmp_path / "song.wav"))).curves
    assert whole.keys() == streamed.keys()
    for key in ("momentary_lufs", "short_term_lufs", "psr_db"):
        a, b = np.array(whole[key], dtype=float), np.array(streamed[key], dtype=float)
        np.testing.assert_allclose(a, b, atol=0.11, err_msg=key)
    assert whole["overs_1dbtp"] == streamed["overs_1dbtp"]


def test_past_the_cap_overs_are_merged_not_cut_off():
    # 5,000 one-segment overs spread over an hour, every 0.72 s, with wider gaps every tenth.
    intervals = []
    t = 0.0
    for i in range(5000):
        intervals.append([round(t, 3), round(t + 0.1, 3)])
        t += 2.0 if i % 10 == 9 else 0.5
    merged = _merged(intervals, MAX_OVERS)
    assert len(merged) == MAX_OVERS
    # Every over is inside one merged interval, and the merged ones are in order, disjoint.
    starts = np.array([a for a, _ in merged])
    ends = np.array([b for _, b in merged])
    assert np.all(starts[1:] > ends[:-1])
    for a, b in intervals:
        k = np.searchsorted(starts, a, side="right") - 1
        assert starts[k] <= a and b <= ends[k]
    # The whole song is still covered: the last over is kept, not cut off at the cap.
    assert merged[-1][1] == intervals[-1][1] and merged[0][0] == intervals[0][0]
    # Only the narrow gaps were closed: every wide (1.9 s) gap is still open.
    gaps = starts[1:] - ends[:-1]
    assert np.sum(gaps > 1.8) == 499
    assert _merged(intervals[:10], MAX_OVERS) == intervals[:10]
