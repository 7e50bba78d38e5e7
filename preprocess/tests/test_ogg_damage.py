"""Mid-stream damage in Ogg Vorbis and Opus is found (page CRCs, page sequence, bytes that are
no page) and reported like truncation: a ``corrupt`` warning in the metadata and on stderr, an
error with --strict. Tested on a real Ogg Vorbis track and an Opus made from it."""

import os
import shutil

import numpy as np
import pytest
import scipy.signal
import soundfile

from loudscape_extract.audio import decode_audio
from loudscape_extract.cli import main
from loudscape_extract.ogg import ogg_crc, ogg_damage
from loudscape_extract.ply import read_ply

REAL = os.path.join(os.path.dirname(__file__), "..", "..", "data", "real-music")
VORBIS = os.path.join(REAL, "rrootage-data", "stg_b.ogg")
needs_real = pytest.mark.skipif(
    not os.path.exists(VORBIS), reason="real music not fetched (scripts/fetch-real-music.sh)"
)


def run(argv, capsys):
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def reference_crc(data: bytes) -> int:
    """RFC 3533's CRC bit by bit: polynomial 0x04C11DB7, not reflected, init 0, no final xor."""
    crc = 0
    for byte in data:
        crc ^= byte << 24
        for _ in range(8):
            crc = ((crc << 1) ^ 0x04C11DB7) if crc & 0x80000000 else crc << 1
            crc &= 0xFFFFFFFF
    return crc


def test_ogg_crc_matches_the_bitwise_definition():
    # CRC-32/POSIX (same polynomial, init 0) checks "123456789" to 0x765E7680 after its final
    # xor with 0xFFFFFFFF, which Ogg does not apply.
    assert ogg_crc(b"123456789") == 0x765E7680 ^ 0xFFFFFFFF == reference_crc(b"123456789")
    rng = np.random.default_rng(3)
    for n in (0, 1, 27, 300, 4096):
        data = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        assert ogg_crc(data) == reference_crc(data)


@pytest.fixture
def vorbis(tmp_path):
    path = tmp_path / "real.ogg"
    shutil.copyfile(VORBIS, path)
    return path


@pytest.fixture
def opus(tmp_path):
    """The real track re-encoded as Opus (libsndfile), 20 s at 48 kHz."""
    samples, rate = soundfile.read(VORBIS, dtype="float32", frames=20 * 44100)
    assert rate == 44100
    resampled = scipy.signal.resample_poly(samples, 160, 147, axis=0).astype(np.float32)
    path = tmp_path / "real.opus"
    soundfile.write(path, np.clip(resampled, -1, 1), 48000, format="OGG", subtype="OPUS")
    return path


def flip_middle(path, n=64):
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    data[middle : middle + n] = bytes(b ^ 0xFF for b in data[middle : middle + n])
    path.write_bytes(bytes(data))


@needs_real
def test_every_real_ogg_is_intact():
    found = [
        os.path.join(root, name)
        for root, _, names in os.walk(REAL)
        for name in names
        if name.endswith(".ogg")
    ]
    assert found
    for path in found:
        assert ogg_damage(path) == "", path


@needs_real
@pytest.mark.parametrize("kind", ["vorbis", "opus"])
def test_flipped_bytes_mid_file_are_corrupt_warned_and_strict_refused(
    tmp_path, capsys, request, kind
):
    source = request.getfixturevalue(kind)
    intact = decode_audio(source)
    assert intact.warning == "" and ogg_damage(str(source)) == ""
    flip_middle(source)
    damaged = decode_audio(source)
    assert damaged.warning.startswith("corrupt audio: ")
    assert "1 of " in damaged.warning and "Ogg pages fail their CRC check" in damaged.warning
    assert "s in)" in damaged.warning  # where: the last good page's granule position
    # What the warning is about: the decoders lose or misread that audio, without an error.
    n = min(damaged.n_samples, intact.n_samples)
    assert damaged.n_samples < intact.n_samples or not np.array_equal(
        damaged.samples[:n], intact.samples[:n]
    )

    out = tmp_path / "c.ply"
    status, err = run(["song", source, "-o", out, "--n-fft", "1024", "--hop", "512"], capsys)
    assert status == 0, err
    warnings = read_ply(out)[1]["warnings"]
    # The real track also clips (decoded peaks of +1.1): that is said too, after the damage.
    assert [w["kind"] for w in warnings][0] == "corrupt"
    assert f"warning: {source}: corrupt audio: " in err
    out.unlink()
    status, err = run(["song", source, "-o", out, "--strict"], capsys)
    assert status == 1 and not out.exists()
    assert err.count("\n") == 1 and "fail their CRC" in err and "--strict" in err


@needs_real
def test_a_page_cut_out_and_junk_between_pages_are_reported(vorbis):
    data = vorbis.read_bytes()
    middle = data.index(b"OggS", len(data) // 2)
    following = data.index(b"OggS", middle + 4)
    vorbis.write_bytes(data[:middle] + data[following:])  # one whole page gone
    assert "1 Ogg page(s) missing from the sequence" in ogg_damage(str(vorbis))
    vorbis.write_bytes(data[:middle] + b"x" * 100 + data[middle:])
    report = ogg_damage(str(vorbis))
    assert "100 bytes between Ogg pages are not Ogg data" in report
    assert f"at byte {middle}" in report


def test_not_ogg_and_empty_files_say_nothing(tmp_path):
    (tmp_path / "a.ogg").write_bytes(b"")
    (tmp_path / "b.ogg").write_bytes(b"RIFF" + b"\0" * 100)
    assert ogg_damage(str(tmp_path / "a.ogg")) == ""
    assert "not Ogg data" in ogg_damage(str(tmp_path / "b.ogg"))
    assert ogg_damage(str(tmp_path / "missing.ogg")) == ""
