"""The command line, end to end: good runs, every kind of bad input, and decodable formats."""

import os
import subprocess
import sys

import numpy as np
import pytest
import soundfile

from loudscape_extract import ExtractError, decode_audio
from loudscape_extract.cli import main
from loudscape_extract.format import METRIC_KEYS

from conftest import musical_signal, sine
from test_ply import tiny_read

RATE = 8000


def run(argv, capsys):
    status = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return status, captured.err


def write_music(path, *, sample_rate=RATE, channels=2, duration_s=1.0, subtype=None):
    y = musical_signal(sample_rate=sample_rate, duration_s=duration_s) * 0.5
    data = np.stack([y, 0.8 * y][:channels], axis=1) if channels > 1 else y
    soundfile.write(path, data.astype(np.float32), sample_rate, subtype=subtype)


def test_song_end_to_end(tmp_path, capsys):
    source = tmp_path / "track.wav"
    write_music(source)
    out = tmp_path / "track.ply"
    status, err = run(["song", source, "-o", out, "--n-fft", 256, "--hop", 128], capsys)
    header, metadata, records = tiny_read(out)
    # stderr is not a TTY under pytest: no progress lines, only the one-line summary.
    assert status == 0 and err.startswith(f"loudscape-extract: wrote {out} ({len(records)} points")
    assert err.count("\n") == 1
    assert metadata["mode"] == "song" and metadata["format_version"] == 2
    assert metadata["point_count"] == records.shape[0] > 0
    assert metadata["source"] == {
        "path": str(source),
        "format": "WAV/PCM_16",
        "sample_rate": RATE,
        "channels": 2,
        "duration_s": 1.0,
    }
    assert metadata["stft"]["n_fft"] == 256 and metadata["stft"]["hop_length"] == 128
    # Every metric of the format's list but hp_mean, which only a timeline's songs carry.
    assert set(metadata["metrics"]) == set(METRIC_KEYS) - {"hp_mean"}
    assert np.all(np.abs(records[:, :3]) <= 1) and np.all(
        (records[:, 3:] >= 0) & (records[:, 3:] <= 1)
    )
    assert records[:, 0].min() == -1 and records[:, 0].max() == 1
    assert records[:, 1].max() == 1
    axes = metadata["axes"]
    assert axes["y"]["max"] - axes["y"]["min"] == pytest.approx(80.0)
    assert axes["z"] | {"ticks": None} == {
        "label": "frequency",
        "unit": "Hz",
        "min": 0.0,
        "max": 4000.0,
        "scale": "linear",
        "ticks": None,
    }


def test_floor_drops_bins_and_zero_disables_it(tmp_path, capsys):
    source = tmp_path / "t.wav"
    write_music(source)
    counts = {}
    for floor in (0, 30, 80):
        out = tmp_path / f"f{floor}.ply"
        assert (
            run(
                ["song", source, "-o", out, "--n-fft", 128, "--hop", 64, "--floor-db", floor],
                capsys,
            )[0]
            == 0
        )
        _, metadata, records = tiny_read(out)
        counts[floor] = records.shape[0]
        if floor:
            assert metadata["axes"]["y"]["max"] - metadata["axes"]["y"]["min"] == pytest.approx(
                floor
            )
    frames = tiny_read(tmp_path / "f0.ply")[1]["stft"]["frames_kept"]
    assert counts[0] == frames * 65 > counts[80] > counts[30]


def test_log_frequency_scale_drops_dc(tmp_path, capsys):
    source = tmp_path / "t.wav"
    write_music(source)
    out = tmp_path / "log.ply"
    argv = ["song", source, "-o", out, "--n-fft", 128, "--hop", 64, "--floor-db", 0]
    argv += ["--freq-scale", "log"]
    assert run(argv, capsys)[0] == 0
    _, metadata, records = tiny_read(out)
    assert metadata["axes"]["z"]["scale"] == "log"
    assert metadata["axes"]["z"]["min"] == pytest.approx(RATE / 128)
    assert records.shape[0] == metadata["stft"]["frames_kept"] * 64  # 65 bins minus DC
    assert records[:, 2].min() == -1 and records[:, 2].max() == 1


def test_sine_lands_on_its_z(tmp_path, capsys):
    source = tmp_path / "sine.wav"
    soundfile.write(
        source, sine(frequency=1000, sample_rate=RATE, duration_s=1, amplitude=0.5), RATE
    )
    out = tmp_path / "sine.ply"
    assert run(["song", source, "-o", out, "--n-fft", 256, "--hop", 128], capsys)[0] == 0
    _, metadata, records = tiny_read(out)
    loudest = records[records[:, 1] == records[:, 1].max()]
    bin_z = 2 * 32 / 128 - 1  # bin 32 of 129 is 1 kHz
    assert np.allclose(loudest[:, 2], bin_z)
    assert metadata["axes"]["y"]["max"] == pytest.approx(-6.02, abs=0.05)  # amplitude 0.5


def test_installed_entry_point_runs(tmp_path):
    source = tmp_path / "t.wav"
    write_music(source, duration_s=0.5)
    out = tmp_path / "t.ply"
    script = os.path.join(os.path.dirname(sys.executable), "loudscape-extract")
    command = (
        [script] if os.path.exists(script) else [sys.executable, "-m", "loudscape_extract.cli"]
    )
    result = subprocess.run(
        [*command, "song", str(source), "-o", str(out), "--quiet"], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    assert out.exists()


# ---- bad input: one line on stderr naming the file, exit 1 (2 for flags), no output file ----


def assert_clean_failure(status, err, *, names, reason, out, expected_status=1):
    assert status == expected_status
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert str(names) in lines[0]
    assert reason in lines[0]
    assert "Traceback" not in err
    assert not os.path.exists(out)
    directory = os.path.dirname(out) or "."
    if os.path.isdir(directory):
        assert not [p for p in os.listdir(directory) if p.endswith(".tmp")]


def test_missing_file(tmp_path, capsys):
    out = tmp_path / "o.ply"
    status, err = run(["song", tmp_path / "nope.wav", "-o", out], capsys)
    assert_clean_failure(status, err, names=tmp_path / "nope.wav", reason="no such file", out=out)


def test_corrupt_file(tmp_path, capsys):
    source = tmp_path / "broken.wav"
    source.write_bytes(b"RIFF\x24\x00\x00\x00WAVEfmt garbage" + bytes(range(256)))
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(status, err, names=source, reason="cannot decode", out=out)


def test_truncated_flac(tmp_path, capsys):
    source = tmp_path / "cut.flac"
    write_music(source, duration_s=1.0)
    source.write_bytes(source.read_bytes()[:60])
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    # 60 bytes hold the FLAC header and no audio frame: nothing decodes, so it is refused.
    assert_clean_failure(status, err, names=source, reason="cannot decode", out=out)


def test_unsupported_format(tmp_path, capsys):
    source = tmp_path / "notes.txt"
    source.write_text("this is not audio\n" * 20)
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(status, err, names=source, reason="unsupported format '.txt'", out=out)


def test_zero_length_audio(tmp_path, capsys):
    source = tmp_path / "empty.wav"
    soundfile.write(source, np.zeros((0, 2), dtype=np.float32), RATE)
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(status, err, names=source, reason="zero-length", out=out)


def test_shorter_than_one_frame(tmp_path, capsys):
    source = tmp_path / "blip.wav"
    soundfile.write(source, sine(frequency=440, sample_rate=RATE, duration_s=0.1) * 0.5, RATE)
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)  # 800 samples < n_fft 2048
    assert_clean_failure(status, err, names=source, reason="shorter than one STFT frame", out=out)
    assert "800 samples" in err and "n_fft=2048" in err


def test_all_silent(tmp_path, capsys):
    source = tmp_path / "silence.wav"
    soundfile.write(source, np.zeros((RATE, 2), dtype=np.int16), RATE)
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(status, err, names=source, reason="entirely silent", out=out)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_samples(tmp_path, capsys, bad):
    y = sine(frequency=440, sample_rate=RATE, duration_s=1.0).astype(np.float32) * 0.5
    y[1234] = bad
    source = tmp_path / "nan.wav"
    soundfile.write(source, y, RATE, subtype="FLOAT")
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(
        status, err, names=source, reason="NaN or infinite sample at sample 1234", out=out
    )


def test_output_in_missing_directory(tmp_path, capsys):
    source = tmp_path / "t.wav"
    write_music(source)
    out = tmp_path / "no" / "such" / "dir" / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(status, err, names=out, reason="does not exist", out=out)


@pytest.mark.parametrize(
    "flags",
    [
        ["--n-fft", "3"],
        ["--n-fft", "abc"],
        ["--hop", "0"],
        ["--floor-db", "-1"],
        ["--freq-scale", "mel"],
        ["--hop", "4096"],
    ],
)
def test_bad_flags_exit_2(tmp_path, capsys, flags):
    source = tmp_path / "t.wav"
    write_music(source)
    out = tmp_path / "o.ply"
    with pytest.raises(SystemExit) as exit_info:
        main(["song", str(source), "-o", str(out), *flags])
    assert exit_info.value.code == 2
    assert "Traceback" not in capsys.readouterr().err
    assert not out.exists()


def test_debug_shows_the_exception(tmp_path):
    with pytest.raises(ExtractError, match="no such file"):
        main(["song", str(tmp_path / "nope.wav"), "--debug"])


# ---- formats ----

FORMATS = [
    ("wav", "WAV", "PCM_16", 44100),
    ("flac", "FLAC", "PCM_24", 96000),
    ("ogg", "OGG", "VORBIS", 22050),
    ("opus", "OGG", "OPUS", 48000),
    ("mp3", "MP3", "MPEG_LAYER_III", 44100),
    ("aiff", "AIFF", "PCM_16", 8000),
]


def _writable(container, subtype):
    return container in soundfile.available_formats() and subtype in soundfile.available_subtypes(
        container
    )


def _format_id(entry):
    extension, container, subtype, _ = entry
    if _writable(container, subtype):
        return f"{extension}-decodes"
    return f"{extension}-not-writable-by-this-libsndfile-expects-clear-error"


@pytest.mark.parametrize("entry", FORMATS, ids=[_format_id(f) for f in FORMATS])
def test_format(tmp_path, entry):
    extension, container, subtype, sample_rate = entry
    source = tmp_path / f"tone.{extension}"
    if not _writable(container, subtype):
        # Cannot make a real file here: a fake one must still give one clear error.
        source.write_bytes(b"\xff\xfb\x90\x00" + bytes(1000))
        with pytest.raises(ExtractError, match=f"tone.{extension}"):
            decode_audio(source)
        return
    y = sine(frequency=1000, sample_rate=sample_rate, duration_s=0.5, amplitude=0.5)
    soundfile.write(
        source, np.stack([y, y], axis=1), sample_rate, subtype=subtype, format=container
    )
    audio = decode_audio(source)
    assert audio.sample_rate == sample_rate and audio.n_channels == 2
    assert audio.format == container
    spectrum = np.abs(np.fft.rfft(audio.samples[:, 0]))
    peak_hz = np.argmax(spectrum) * sample_rate / audio.n_samples
    assert abs(peak_hz - 1000) < 10


def test_any_sample_rate_and_multichannel(tmp_path, capsys):
    for sample_rate, channels in ((8000, 1), (192000, 6)):
        source = tmp_path / f"r{sample_rate}.wav"
        write_music(source, sample_rate=sample_rate, channels=channels, duration_s=0.5)
        if channels == 6:
            data, _ = soundfile.read(source)
            soundfile.write(source, np.tile(data, (1, 3)), sample_rate)
        out = tmp_path / f"r{sample_rate}.ply"
        assert run(["song", source, "-o", out, "--n-fft", 1024, "--hop", 512], capsys)[0] == 0
        metadata = tiny_read(out)[1]
        assert metadata["source"]["sample_rate"] == sample_rate
        assert metadata["source"]["channels"] == channels
        assert metadata["metrics"]["integrated_lufs"] is not None


def test_sample_rate_outside_supported_range(tmp_path, capsys):
    source = tmp_path / "low.wav"
    soundfile.write(source, sine(frequency=100, sample_rate=4000, duration_s=1) * 0.5, 4000)
    out = tmp_path / "o.ply"
    status, err = run(["song", source, "-o", out], capsys)
    assert_clean_failure(status, err, names=source, reason="4000 Hz", out=out)


def test_progress_only_on_a_tty_and_not_with_quiet(tmp_path, capsys, monkeypatch):
    source = tmp_path / "t.wav"
    write_music(source, duration_s=0.5)
    out = tmp_path / "t.ply"
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    status, err = run(["song", source, "-o", out, "--n-fft", 256, "--hop", 128], capsys)
    assert status == 0
    for stage in ("decoding", "spectrogram", "harmonic-percussive", "loudness", "writing"):
        assert stage in err
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    status, err = run(["song", source, "-o", out, "--n-fft", 256, "--hop", 128, "-q"], capsys)
    assert status == 0 and err == ""


def test_song_warns_about_a_dc_offset_and_keeps_quiet_bass_off_zero(tmp_path, capsys):
    source = tmp_path / "dc.wav"
    t = np.arange(RATE * 2) / RATE
    # A quiet track: bass at 60 Hz far below -100 dB A-weighted, plus a DC offset.
    y = 1e-4 * np.sin(2 * np.pi * 60 * t) + 0.002 * np.sin(2 * np.pi * 1000 * t) + 0.2
    soundfile.write(source, y.astype(np.float32), RATE, subtype="FLOAT")
    out = tmp_path / "dc.ply"
    status, err = run(["song", source, "-o", out, "--n-fft", 256, "--hop", 128], capsys)
    lines = err.splitlines()
    assert status == 0 and len(lines) == 2  # the warning, then the "wrote" summary
    assert "warning:" in lines[0] and "DC offset 0.200" in lines[0]
    header, metadata, records = tiny_read(out)
    assert metadata["metrics"]["dc_offset"] == pytest.approx(0.2, abs=1e-3)
    frequency = (records[:, 2] + 1) / 2 * (RATE / 2)
    bass = records[(frequency > 20) & (frequency < 100)]
    assert bass.shape[0] > 0 and np.all(bass[:, 3] > 0)  # no cliff: none clipped to 0
    assert metadata["axes"]["scalar"]["min"] < -100
