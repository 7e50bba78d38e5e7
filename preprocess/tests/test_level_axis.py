"""The timeline's y axis as loudness (docs/DYNAMICS.md, "The level axis"): per-frame momentary
loudness against libebur128, infrasound that does not count as level, and the y measures."""

import numpy as np
import pytest
import soundfile
from test_dynamics import dynamic_stereo

from loudscape_extract import read_ply_metadata, track_features
from loudscape_extract.audio import decode_audio
from loudscape_extract.loudness import integrated_loudness
from loudscape_extract.stream import stream_track
from loudscape_extract.timeline import (
    LEVEL_MAX_DBFS,
    LEVEL_MIN_DBFS,
    Y_MEASURES,
    SongEntry,
    build_timeline,
    compute_song_frames,
    timeline_points,
)

RATE = 48000


def _momentary_reference(samples, rate):
    """libebur128's momentary loudness after each 100 ms fed: entry i covers segments i..i+3."""
    pyebur128 = pytest.importorskip("pyebur128")
    modes = pyebur128.MeasurementMode
    state = pyebur128.R128State(samples.shape[1], rate, modes.MODE_M)
    hop = rate // 10
    loudness = []
    for i, start in enumerate(range(0, samples.shape[0] - hop + 1, hop)):
        block = np.ascontiguousarray(samples[start : start + hop], dtype=np.float64)
        state.add_frames(block.ravel(), hop)
        if i >= 3:
            loudness.append(pyebur128.get_loudness_momentary(state))
    return np.array(loudness)


def test_momentary_loudness_per_frame_matches_libebur128(tmp_path):
    x = dynamic_stereo(5, duration_s=12.0)
    wav = tmp_path / "dynamic.wav"
    soundfile.write(wav, x, RATE, subtype="FLOAT")
    reference = _momentary_reference(x, RATE)
    streamed = stream_track(str(wav), n_fft=2048, hop_length=1024)
    in_memory = track_features(decode_audio(str(wav)), n_fft=2048, hop_length=1024)
    for frames in (streamed.frames, in_memory.frames):
        block = np.round((frames.times_s - 0.2) / 0.1).astype(int)
        inside = (block >= 0) & (block < reference.shape[0])
        assert inside.sum() > 500
        ours = frames.momentary_lufs[inside]
        np.testing.assert_allclose(ours, reference[block[inside]], atol=0.1)
        # each frame's block is centred within 50 ms of the frame
        centre = (block[inside] + 2) * 0.1
        assert np.max(np.abs(centre - frames.times_s[inside])) <= 0.05 + 1e-9


def _tone(freq, dbfs, seconds=8.0, rate=RATE):
    t = np.arange(int(seconds * rate)) / rate
    return (10 ** (dbfs / 20) * np.sqrt(2) * np.sin(2 * np.pi * freq * t))[:, None]


def _pink(seconds, rate, seed=0):
    rng = np.random.default_rng(seed)
    n = int(seconds * rate)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, 1 / rate)
    spectrum[1:] /= np.sqrt(f[1:])
    spectrum[0] = 0
    return np.fft.irfft(spectrum, n)


def _energy_mean_y(tmp_path, tracks, y_measure="momentary"):
    """The energy mean (dB) of each track's y, in order, through a real timeline."""
    entries, songs = [], {}
    for i, samples in enumerate(tracks):
        path = tmp_path / f"t{i}.wav"
        soundfile.write(path, samples, RATE, subtype="FLOAT")
        entries.append(SongEntry(path=str(path), year=2000 + i, title=f"t{i}", artist=""))
        songs[str(path)] = compute_song_frames(str(path), n_fft=2048, hop_length=1024)
    points, layout = timeline_points(entries, songs, frames_per_song=256, y_measure=y_measure)
    out = []
    for song in layout["songs"]:
        y = points[song["point_offset"] : song["point_offset"] + song["point_count"], 1]
        level = (y.astype(float) + 1) / 2 * (LEVEL_MAX_DBFS - LEVEL_MIN_DBFS) + LEVEL_MIN_DBFS
        out.append(10 * np.log10(np.mean(10 ** (level / 10))))
    return out, layout


def test_a_strong_10hz_rumble_does_not_place_a_quiet_tone(tmp_path):
    # the rumble carries 15 dB more energy than the tone (K-weighting takes ~24 dB off at 10 Hz)
    quiet = _tone(1000, -40)
    rumble = _tone(10, -25) + quiet
    louder = _tone(1000, -30)
    (y_quiet, y_rumble, y_louder), layout = _energy_mean_y(tmp_path, [quiet, rumble, louder])
    assert layout["axes"]["y"]["unit"] == "LUFS"
    assert layout["axes"]["y"]["measure"] == "momentary"
    assert y_rumble == pytest.approx(y_quiet, abs=0.6)  # placed by the tone
    assert y_rumble < y_louder - 9
    # the paper's RMS puts the rumble 15 dB above the tone it carries, above the louder tone
    (r_quiet, r_rumble, r_louder), rms = _energy_mean_y(
        tmp_path, [quiet, rumble, louder], y_measure="rms"
    )
    assert rms["axes"]["y"]["unit"] == "dBFS" and "RMS" in rms["axes"]["y"]["label"]
    assert r_rumble > r_quiet + 14 and r_rumble > r_louder + 4


def test_pink_noise_with_and_without_infrasound_lands_together(tmp_path):
    noise = _pink(10.0, RATE)
    noise *= 10 ** ((-20 - integrated_loudness(noise, sample_rate=RATE)) / 20)
    assert integrated_loudness(noise, sample_rate=RATE) == pytest.approx(-20.0, abs=0.01)
    noise_rms = 20 * np.log10(np.sqrt(np.mean(noise**2)))
    sine = _tone(10, noise_rms + 10, seconds=10.0)[:, 0]
    (alone, with_sine), _ = _energy_mean_y(tmp_path, [noise[:, None], (noise + sine)[:, None]])
    assert alone == pytest.approx(-20.0, abs=0.5)
    assert with_sine == pytest.approx(alone, abs=0.5)


@pytest.mark.parametrize("y_measure", Y_MEASURES)
def test_every_y_measure_is_named_on_the_axis_and_in_the_metadata(tmp_path, y_measure):
    path = tmp_path / "a.wav"
    soundfile.write(path, _tone(440, -20, seconds=3.0), RATE, subtype="FLOAT")
    manifest = tmp_path / "songs.csv"
    manifest.write_text("path,year\na.wav,1999\n")
    out = tmp_path / "t.ply"
    build_timeline([], str(out), manifest=str(manifest), y_measure=y_measure, cache_dir=None)
    meta = read_ply_metadata(str(out))
    assert meta["extraction"]["y_measure"] == y_measure
    assert meta["axes"]["y"]["measure"] == y_measure
    assert meta["axes"]["y"]["label"] and meta["axes"]["y"]["unit"] in ("LUFS", "dBFS", "dB")
