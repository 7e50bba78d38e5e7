"""Decoding: any audio file soundfile (libsndfile) reads -> float32 samples, channels kept."""

from __future__ import annotations

import contextlib
import math
import os
import struct
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import soundfile

from loudscape_extract.errors import ExtractError
from loudscape_extract.messages import shorten
from loudscape_extract.ogg import ogg_damage
from loudscape_extract.paths import check_regular_input

__all__ = [
    "MAX_SAMPLE_MAGNITUDE",
    "MAX_SAMPLE_RATE",
    "MIN_SAMPLE_RATE",
    "SUPPORTED_EXTENSIONS",
    "Audio",
    "AudioInfo",
    "BlockReport",
    "audio_info",
    "check_analysable",
    "check_decoded",
    "decode_audio",
    "mix_rows_to_mono",
    "mix_to_mono",
    "read_blocks",
]

MIN_SAMPLE_RATE = 8_000
MAX_SAMPLE_RATE = 192_000
#: Float files may exceed full scale, but not by more than this (+60 dBFS): beyond it the
#: file is corrupt or not audio, and levels would overflow.
MAX_SAMPLE_MAGNITUDE = 1000.0
_BLOCK_FRAMES = 1 << 15
SUPPORTED_EXTENSIONS = (".wav", ".flac", ".ogg", ".oga", ".opus", ".mp3", ".aif", ".aiff")


@dataclass(frozen=True)
class Audio:
    """Decoded audio.

    Attributes
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels), dtype=float32]
        Samples in [-1, 1] full scale (float files may exceed it), channels as in the file.
    sample_rate : int
        Sample rate in Hz.
    path : str
        The path as given by the caller (recorded verbatim in the metadata).
    format : str
        libsndfile's container name, e.g. ``"WAV"``, ``"MP3"``.
    subtype : str
        libsndfile's encoding name, e.g. ``"PCM_16"``, ``"VORBIS"``.
    frames_expected : int or None
        Frames the container promises, when it says.
    warning : str
        Non-empty when the file is truncated or corrupt: how much was decoded, and why.
    """

    samples: np.ndarray
    sample_rate: int
    path: str
    format: str = ""
    subtype: str = ""
    frames_expected: int | None = None
    warning: str = ""

    @property
    def n_samples(self) -> int:
        return int(self.samples.shape[0])

    @property
    def n_channels(self) -> int:
        return int(self.samples.shape[1])

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate


def decode_audio(path: str | os.PathLike, *, strict: bool = False) -> Audio:
    """Read an audio file with soundfile, keeping its channels and sample rate.

    Decoding runs block by block and is checked against what the container promises (the
    frame count of FLAC's STREAMINFO, an mp3's Xing/Info header or libsndfile's count, the
    ``data`` / ``SSND`` chunk size of WAV and AIFF, the end-of-stream page of Ogg Vorbis and
    Opus, and every Ogg page's CRC and sequence number, :func:`ogg.ogg_damage`, since the Ogg
    decoders pass over damaged pages in silence); a decoder error mid-stream keeps what was
    decoded before it. A short or damaged file is then decoded as far as it goes and
    ``audio.warning`` says how far (or, with ``strict``, it is an error). The decoder
    libraries' own chatter on file descriptor 2 (libmpg123's ``Note:`` lines) is captured;
    its error lines become part of the warning.

    Parameters
    ----------
    path : str or os.PathLike
        Audio file: wav, flac, ogg/vorbis, opus, mp3, aiff (anything libsndfile reads).
    strict : bool
        Refuse truncated or corrupt files instead of warning.

    Returns
    -------
    audio : Audio
        ``audio.samples`` has shape (n_samples, n_channels), dtype float32.

    Raises
    ------
    ExtractError
        Missing or non-regular file, unsupported format, undecodable data, a sample rate
        outside 8 kHz - 192 kHz, no samples at all, NaN / infinite samples, float samples
        beyond +/- :data:`MAX_SAMPLE_MAGNITUDE`, or (``strict``) a truncated or corrupt file.
    """
    name = os.fspath(path)
    check_regular_input(name)
    extension = os.path.splitext(name)[1].lower()
    with _captured_fd2() as chatter:
        try:
            with soundfile.SoundFile(os.fsencode(name)) as handle:
                sample_rate = int(handle.samplerate)
                if not MIN_SAMPLE_RATE <= sample_rate <= MAX_SAMPLE_RATE:
                    raise ExtractError(
                        f"sample rate {sample_rate} Hz is outside the supported "
                        f"{MIN_SAMPLE_RATE}-{MAX_SAMPLE_RATE} Hz",
                        path=name,
                    )
                file_format, subtype = str(handle.format), str(handle.subtype)
                samples, stream_error = _read_blocks(handle)
        except ExtractError:
            raise
        except (soundfile.LibsndfileError, RuntimeError, TypeError, ValueError) as exc:
            raise _open_error(name, extension, exc) from exc
        except OSError as exc:
            raise ExtractError(f"cannot read file ({_one_line(exc)})", path=name) from exc
    decoder_errors = [line for line in chatter if "error" in line.lower()]
    promised, container_problem = _promised_frames(name, file_format, subtype, samples.shape[1])
    decoded = samples.shape[0]
    problem = _decode_problem(
        decoded=decoded,
        promised=promised,
        sample_rate=sample_rate,
        container_problem=container_problem,
        stream_error=stream_error,
        decoder_errors=decoder_errors,
    )
    if problem and (strict or decoded == 0):
        hint = "" if decoded == 0 else "; without --strict it is decoded as far as it goes"
        raise ExtractError(f"{problem}{hint}", path=name)
    if decoded == 0:
        raise ExtractError("zero-length audio: the file holds no samples", path=name)
    finite = np.isfinite(samples)
    if not finite.all():
        first = int(np.argmin(finite.all(axis=1)))
        raise ExtractError(
            f"NaN or infinite sample at sample {first} ({first / sample_rate:.3f} s)", path=name
        )
    if max(float(samples.max()), -float(samples.min())) > MAX_SAMPLE_MAGNITUDE:
        peak_index = int(np.argmax(np.abs(samples).max(axis=1)))
        peak = float(np.abs(samples[peak_index]).max())
        raise ExtractError(
            f"sample value {peak:.3g} at {peak_index / sample_rate:.3f} s is beyond "
            f"+/-{MAX_SAMPLE_MAGNITUDE:g} ({20 * math.log10(MAX_SAMPLE_MAGNITUDE):+.0f} dBFS): "
            "a float file this hot is corrupt or not audio",
            path=name,
        )
    return Audio(
        samples=np.ascontiguousarray(samples),
        sample_rate=sample_rate,
        path=name,
        format=file_format,
        subtype=subtype,
        frames_expected=promised,
        warning=problem or "",
    )


def _read_blocks(handle: soundfile.SoundFile) -> tuple[np.ndarray, str]:
    """Every frame the decoder gives, block by block; a mid-stream error ends the read and is
    returned as its reason (``""`` when the stream ended normally)."""
    capacity = max(int(handle.frames), 0)
    out = np.empty((capacity, handle.channels), dtype=np.float32)
    done = 0
    error = ""
    while True:
        if done == out.shape[0]:
            grown = np.empty((max(2 * done, _BLOCK_FRAMES), handle.channels), dtype=np.float32)
            grown[:done] = out[:done]
            out = grown
        want = min(_BLOCK_FRAMES, out.shape[0] - done)
        try:
            block = handle.read(want, dtype="float32", always_2d=True, out=out[done : done + want])
        except (soundfile.LibsndfileError, RuntimeError) as exc:
            error = _one_line(exc).removeprefix("Error : ")
            break
        if block.shape[0] == 0:
            break
        done += block.shape[0]
    return out[:done], error


def _decode_problem(
    *,
    decoded: int,
    promised: int | None,
    sample_rate: int,
    container_problem: str,
    stream_error: str,
    decoder_errors: list[str],
) -> str:
    """One sentence when the decode is short or damaged, else ``""``."""
    reasons = []
    if stream_error:
        reasons.append(f"decoder error: {stream_error}")
    if container_problem:
        reasons.append(container_problem)
    short = promised is not None and decoded < promised
    if not (short or reasons):
        return ""  # libmpg123 prints errors for complete files too: alone they prove nothing
    if decoder_errors:
        reasons.append("decoder reported: " + shorten(decoder_errors[0], 120))
    if decoded == 0:
        how_much = "nothing could be decoded"
    elif short:
        share = math.floor(1000.0 * decoded / promised) / 10
        how_much = (
            f"decoded {decoded / sample_rate:.2f} s of the {promised / sample_rate:.2f} s "
            f"the file promises ({share:.1f} %)"
        )
    else:
        how_much = f"decoded {decoded / sample_rate:.2f} s"
    reason = f" ({'; '.join(reasons)})" if reasons else ""
    # Pages failing their CRC are damage, not a missing end: say so first.
    crc = "fail their CRC" in container_problem
    head = "corrupt audio" if crc else "truncated or corrupt audio"
    return f"{head}: {how_much}{reason}"


def _promised_frames(
    name: str, file_format: str, subtype: str, channels: int
) -> tuple[int | None, str]:
    """Frames the container promises (None when it does not say) and a container problem."""
    try:
        with open(name, "rb") as handle:
            head = handle.read(1 << 16)
            size = os.fstat(handle.fileno()).st_size
            handle.seek(max(size - (1 << 16), 0))
            tail = handle.read()
    except OSError:
        return None, ""
    if file_format == "WAV":
        return _riff_frames(head, size), ""
    if file_format == "AIFF":
        return _aiff_frames(head), ""
    if file_format == "OGG":
        # libsndfile counts an Ogg's frames from its last granule position: a decoder that
        # drops damaged pages (Opus) decodes less than that, which is then said.
        problems = [ogg_damage(name), _ogg_end_problem(tail, size)]
        promised = _libsndfile_frames(name)
        return promised, "; ".join(problem for problem in problems if problem)
    if file_format == "MP3":
        return (_libsndfile_frames(name) if _mp3_has_frame_count(head) else None), ""
    return _libsndfile_frames(name), ""


def _libsndfile_frames(name: str) -> int | None:
    with _captured_fd2():
        try:
            frames = int(soundfile.info(os.fsencode(name)).frames)
        except (soundfile.LibsndfileError, RuntimeError):
            return None
    return frames if frames > 0 else None


def _riff_frames(head: bytes, size: int) -> int | None:
    """WAV: the ``data`` chunk's size / block align (None for streaming sizes or no chunk)."""
    if head[:4] != b"RIFF" or head[8:12] != b"WAVE":
        return None
    offset, block_align = 12, 0
    while offset + 8 <= len(head):
        chunk, length = head[offset : offset + 4], struct.unpack_from("<I", head, offset + 4)[0]
        if chunk == b"fmt " and offset + 22 <= len(head):
            block_align = struct.unpack_from("<H", head, offset + 20)[0]
        elif chunk == b"data":
            if block_align == 0 or length in (0, 0xFFFFFFFF):
                return None
            return length // block_align
        offset += 8 + length + (length & 1)
    return None


def _aiff_frames(head: bytes) -> int | None:
    """AIFF / AIFF-C: ``numSampleFrames`` of the COMM chunk."""
    if head[:4] != b"FORM" or head[8:12] not in (b"AIFF", b"AIFC"):
        return None
    offset = 12
    while offset + 8 <= len(head):
        chunk, length = head[offset : offset + 4], struct.unpack_from(">I", head, offset + 4)[0]
        if chunk == b"COMM" and offset + 14 <= len(head):
            frames = struct.unpack_from(">I", head, offset + 10)[0]
            return frames or None
        offset += 8 + length + (length & 1)
    return None


def _ogg_end_problem(tail: bytes, size: int) -> str:
    """Ogg: the last page must be complete, end the file and carry the end-of-stream flag."""
    start = tail.rfind(b"OggS")
    if start < 0 or start + 27 > len(tail):
        return "the Ogg stream's last page is missing or cut"
    segments = tail[start + 26]
    if start + 27 + segments > len(tail):
        return "the Ogg stream's last page is cut short"
    body = sum(tail[start + 27 : start + 27 + segments])
    if start + 27 + segments + body > len(tail):
        return "the Ogg stream's last page is cut short"
    if not tail[start + 5] & 0x04:
        return "the Ogg stream ends without its end-of-stream page"
    return ""


def _mp3_has_frame_count(head: bytes) -> bool:
    """True when the first mp3 frame is a Xing/Info/VBRI header (an exact frame count)."""
    offset = 0
    if head[:3] == b"ID3" and len(head) >= 10:
        tag = head[6:10]
        offset = 10 + ((tag[0] << 21) | (tag[1] << 14) | (tag[2] << 7) | tag[3])
    window = head[offset : offset + 4096]
    return any(marker in window[:200] for marker in (b"Xing", b"Info", b"VBRI"))


def _open_error(name: str, extension: str, exc: BaseException) -> ExtractError:
    reason = _one_line(exc).removeprefix("Error opening ").strip()
    if "not a regular file" in reason or "does not exist" in reason:
        # libsndfile says this of any regular file whose format it cannot recognize.
        reason = "libsndfile does not recognize the data as audio"
    if extension not in SUPPORTED_EXTENSIONS and "recogni" in reason.lower():
        supported = ", ".join(SUPPORTED_EXTENSIONS)
        return ExtractError(
            f"unsupported format {extension or '(no extension)'!r} ({reason}); "
            f"supported: {supported}",
            path=name,
        )
    return ExtractError(f"cannot decode audio, corrupt or unreadable ({reason})", path=name)


@contextlib.contextmanager
def _captured_fd2(sink=None):
    """Redirect file descriptor 2 to a temporary file; yields the list of lines written there,
    filled in when the block ends (C libraries such as libmpg123 print straight to fd 2).

    ``sink``, an open temporary file, is emptied and used instead of a new one (a decoding
    loop captures each piece it reads: one file for all of them)."""
    lines: list[str] = []
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield lines
        return
    with contextlib.ExitStack() as stack:
        if sink is None:
            sink = stack.enter_context(tempfile.TemporaryFile())
        else:
            sink.seek(0)
            sink.truncate()
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            text = sink.read(1 << 16).decode("utf-8", errors="replace")
            lines.extend(line.strip() for line in text.splitlines() if line.strip())


@dataclass(frozen=True)
class AudioInfo:
    """What :func:`audio_info` reads from a file's header (no samples decoded).

    Attributes
    ----------
    path : str
    sample_rate, n_channels : int
    n_samples : int
        As the header states it (:func:`read_blocks` checks it while decoding).
    format, subtype : str
    """

    path: str
    sample_rate: int
    n_channels: int
    n_samples: int
    format: str
    subtype: str

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate


@dataclass
class BlockReport:
    """What :func:`read_blocks` saw go wrong while decoding (empty when nothing did).

    Attributes
    ----------
    stream_error : str
        The decoder error that ended the read early, ``""`` when the stream ended normally.
    decoder_errors : list of str
        Error lines the decoder libraries printed on file descriptor 2 (libmpg123).
    """

    stream_error: str = ""
    decoder_errors: list[str] = field(default_factory=list)


def audio_info(path: str | os.PathLike) -> AudioInfo:
    """Open a file as :func:`decode_audio` would (same checks and messages) and read its header.

    Raises
    ------
    ExtractError
        As :func:`decode_audio`, for everything visible without decoding.
    """
    name = os.fspath(path)
    check_regular_input(name)
    extension = os.path.splitext(name)[1].lower()
    with _captured_fd2():
        try:
            info = soundfile.info(os.fsencode(name))
        except (soundfile.LibsndfileError, RuntimeError, TypeError, ValueError) as exc:
            raise _open_error(name, extension, exc) from exc
        except OSError as exc:
            raise ExtractError(f"cannot read file ({_one_line(exc)})", path=name) from exc
    sample_rate = int(info.samplerate)
    if not MIN_SAMPLE_RATE <= sample_rate <= MAX_SAMPLE_RATE:
        raise ExtractError(
            f"sample rate {sample_rate} Hz is outside the supported "
            f"{MIN_SAMPLE_RATE}-{MAX_SAMPLE_RATE} Hz",
            path=name,
        )
    return AudioInfo(
        path=name,
        sample_rate=sample_rate,
        n_channels=int(info.channels),
        n_samples=max(int(info.frames), 0),
        format=str(info.format),
        subtype=str(info.subtype),
    )


def read_blocks(
    info: AudioInfo, *, block: int, report: BlockReport | None = None
) -> Iterator[tuple[int, np.ndarray]]:
    """Decode a file block by block, front to back (no seeking, so any format works).

    A decoder error mid-stream ends the iteration, as in :func:`decode_audio`: what decoded
    before it is yielded, and the error goes into ``report`` (with the decoder libraries' error
    lines on file descriptor 2, which is captured only while the decoder runs).
    :func:`check_decoded` turns the report into the warning or the ``--strict`` error.

    Parameters
    ----------
    info : AudioInfo
        From :func:`audio_info`.
    block : int
        Samples per block (the last one may be shorter).
    report : BlockReport, optional
        Filled in with what went wrong.

    Yields
    ------
    start : int
        Index of the block's first sample.
    samples : np.ndarray [shape=(n, n_channels), dtype=float32]
        The samples :func:`decode_audio` returns for ``[start, start + n)``.

    Raises
    ------
    ExtractError
        A file that cannot be opened, NaN or infinite samples (naming the first), float samples
        beyond +/- :data:`MAX_SAMPLE_MAGNITUDE`.
    """
    name = info.path
    report = report if report is not None else BlockReport()
    extension = os.path.splitext(name)[1].lower()
    start = 0
    with _captured_fd2() as chatter:
        try:
            handle = soundfile.SoundFile(os.fsencode(name))
        except (soundfile.LibsndfileError, RuntimeError, TypeError, ValueError) as exc:
            raise _open_error(name, extension, exc) from exc
        except OSError as exc:
            raise ExtractError(f"cannot read file ({_one_line(exc)})", path=name) from exc
    report.decoder_errors += [line for line in chatter if "error" in line.lower()]
    # Read in pieces of at most _BLOCK_FRAMES, at the offsets decode_audio reads: a decoder
    # error loses the piece being read, so a damaged file decodes as far as it does there.
    piece = min(block, _BLOCK_FRAMES)
    ended = False
    with handle, tempfile.TemporaryFile() as sink:
        while not ended:
            samples = np.empty((block, info.n_channels), dtype=np.float32)
            filled = 0
            while filled < block:
                want = min(piece, block - filled)
                with _captured_fd2(sink) as chatter:
                    try:
                        got = handle.read(
                            want,
                            dtype="float32",
                            always_2d=True,
                            out=samples[filled : filled + want],
                        ).shape[0]
                    except (soundfile.LibsndfileError, RuntimeError) as exc:
                        report.stream_error = _one_line(exc).removeprefix("Error : ")
                        got = 0
                    except OSError as exc:
                        raise ExtractError(
                            f"cannot read file ({_one_line(exc)})", path=name
                        ) from exc
                report.decoder_errors += [line for line in chatter if "error" in line.lower()]
                if got == 0:
                    ended = True
                    break
                filled += got
            if filled == 0:
                break
            samples = samples[:filled]
            high, low = float(samples.max()), float(samples.min())
            finite = np.isfinite(samples) if not math.isfinite(high - low) else None
            if finite is not None and not finite.all():
                first = start + int(np.argmin(finite.all(axis=1)))
                raise ExtractError(
                    f"NaN or infinite sample at sample {first} ({first / info.sample_rate:.3f} s)",
                    path=name,
                )
            if max(high, -low) > MAX_SAMPLE_MAGNITUDE:
                peak_index = int(np.argmax(np.abs(samples).max(axis=1)))
                peak = float(np.abs(samples[peak_index]).max())
                raise ExtractError(
                    f"sample value {peak:.3g} at {(start + peak_index) / info.sample_rate:.3f} s "
                    f"is beyond +/-{MAX_SAMPLE_MAGNITUDE:g} "
                    f"({20 * math.log10(MAX_SAMPLE_MAGNITUDE):+.0f} dBFS): "
                    "a float file this hot is corrupt or not audio",
                    path=name,
                )
            yield start, samples
            start += samples.shape[0]


def check_analysable(
    *, n_samples: int, sample_rate: int, n_fft: int, any_sample: bool, mono: np.ndarray, path: str
) -> None:
    """Refuse decoded audio that gives no STFT frame or no sound (the streamed pipeline and the
    whole-track reference say the same).

    Raises
    ------
    ExtractError
        Shorter than one STFT frame, every sample 0, or a mono mix that is 0 (channels cancel).
    """
    if n_samples < n_fft:
        raise ExtractError(
            f"audio of {n_samples} samples ({n_samples / sample_rate * 1000:.1f} ms) is shorter "
            f"than one STFT frame (n_fft={n_fft})",
            path=path,
        )
    if not any_sample:
        raise ExtractError("audio is entirely silent (every sample is 0)", path=path)
    if not np.any(mono):
        raise ExtractError("the mono mix is entirely silent (channels cancel)", path=path)


def check_decoded(
    info: AudioInfo, *, decoded: int, report: BlockReport, strict: bool = False
) -> str:
    """After a streamed decode of ``decoded`` frames: the truncation warning, as
    :attr:`Audio.warning` (``""`` for a complete file), checked against what the container
    promises exactly as :func:`decode_audio` does.

    Raises
    ------
    ExtractError
        ``strict`` and the file is truncated or corrupt; or nothing decoded at all.
    """
    promised, container_problem = _promised_frames(
        info.path, info.format, info.subtype, info.n_channels
    )
    problem = _decode_problem(
        decoded=decoded,
        promised=promised,
        sample_rate=info.sample_rate,
        container_problem=container_problem,
        stream_error=report.stream_error,
        decoder_errors=report.decoder_errors,
    )
    if problem and (strict or decoded == 0):
        hint = "" if decoded == 0 else "; without --strict it is decoded as far as it goes"
        raise ExtractError(f"{problem}{hint}", path=info.path)
    if decoded == 0:
        raise ExtractError("zero-length audio: the file holds no samples", path=info.path)
    return problem or ""


def mix_to_mono(samples: np.ndarray) -> np.ndarray:
    """Average the channels.

    Parameters
    ----------
    samples : np.ndarray [shape=(n_samples, n_channels) or (n_samples,)]

    Returns
    -------
    mono : np.ndarray [shape=(n_samples,), dtype=float32]
    """
    samples = np.asarray(samples, dtype=np.float32)
    if samples.ndim == 1:
        return samples
    if samples.ndim != 2:
        raise ExtractError(f"samples must have shape (n_samples, n_channels), got {samples.shape}")
    if samples.shape[1] == 1:
        return samples[:, 0].copy()
    # samples.mean(axis=1, dtype=np.float32) bit for bit (the channels summed in order from
    # +0.0, then divided), without numpy's slow reduction across a short strided axis.
    mono = np.add(samples[:, 0], np.float32(0.0))
    for channel in range(1, samples.shape[1]):
        mono += samples[:, channel]
    mono /= np.float32(samples.shape[1])
    return mono


def mix_rows_to_mono(channels: np.ndarray) -> np.ndarray:
    """:func:`mix_to_mono` of the channels laid out as rows, bit for bit.

    Parameters
    ----------
    channels : np.ndarray [shape=(n_channels, n_samples), dtype=float32]
        One channel a row (C-contiguous rows: the sums run over contiguous memory, about
        twice as fast as over the decoder's interleaved columns).

    Returns
    -------
    mono : np.ndarray [shape=(n_samples,), dtype=float32]

    Examples
    --------
    >>> samples = np.array([[0.5, -0.25], [1.0, 0.0]], dtype=np.float32)
    >>> mix_rows_to_mono(samples.T.copy()).tolist()
    [0.125, 0.5]
    """
    channels = np.asarray(channels, dtype=np.float32)
    if channels.ndim != 2:
        raise ExtractError(
            f"channels must have shape (n_channels, n_samples), got {channels.shape}"
        )
    if channels.shape[0] == 1:
        return channels[0].copy()
    mono = np.add(channels[0], np.float32(0.0))
    for row in channels[1:]:
        mono += row
    mono /= np.float32(channels.shape[0])
    return mono


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__
