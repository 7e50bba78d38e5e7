"""Decoding: any audio file soundfile (libsndfile) reads -> float32 samples, channels kept."""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import soundfile

from loudscape_extract.errors import ExtractError

__all__ = [
    "MAX_SAMPLE_RATE",
    "MIN_SAMPLE_RATE",
    "SUPPORTED_EXTENSIONS",
    "Audio",
    "AudioInfo",
    "audio_info",
    "decode_audio",
    "mix_to_mono",
    "read_blocks",
]

MIN_SAMPLE_RATE = 8_000
MAX_SAMPLE_RATE = 192_000
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
    """

    samples: np.ndarray
    sample_rate: int
    path: str
    format: str = ""
    subtype: str = ""

    @property
    def n_samples(self) -> int:
        return int(self.samples.shape[0])

    @property
    def n_channels(self) -> int:
        return int(self.samples.shape[1])

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate


def decode_audio(path: str | os.PathLike) -> Audio:
    """Read an audio file with soundfile, keeping its channels and sample rate.

    Parameters
    ----------
    path : str or os.PathLike
        Audio file: wav, flac, ogg/vorbis, opus, mp3, aiff (anything libsndfile reads).

    Returns
    -------
    audio : Audio
        ``audio.samples`` has shape (n_samples, n_channels), dtype float32.

    Raises
    ------
    ExtractError
        Missing file, unsupported format, undecodable data, a sample rate outside
        8 kHz - 192 kHz, no samples at all, or NaN / infinite samples.
    """
    name = os.fspath(path)
    _check_readable(name)
    try:
        info = soundfile.info(name)
        samples, sample_rate = soundfile.read(name, dtype="float32", always_2d=True)
    except (soundfile.LibsndfileError, RuntimeError, TypeError, ValueError) as exc:
        raise _decode_error(exc, name) from exc
    except OSError as exc:
        raise ExtractError(f"cannot read file ({_one_line(exc)})", path=name) from exc

    _check_sample_rate(sample_rate, name)
    if samples.shape[0] == 0:
        raise ExtractError("zero-length audio: the file holds no samples", path=name)
    finite = np.isfinite(samples)
    if not finite.all():
        first = int(np.argmin(finite.all(axis=1)))
        raise ExtractError(
            f"NaN or infinite sample at sample {first} ({first / sample_rate:.3f} s)", path=name
        )
    return Audio(
        samples=np.ascontiguousarray(samples),
        sample_rate=int(sample_rate),
        path=name,
        format=str(info.format),
        subtype=str(info.subtype),
    )


def _check_readable(name: str) -> None:
    if not os.path.exists(name):
        raise ExtractError("no such file", path=name)
    if os.path.isdir(name):
        raise ExtractError("is a directory, not an audio file", path=name)
    if not os.access(name, os.R_OK):
        raise ExtractError("permission denied", path=name)


def _decode_error(exc: BaseException, name: str) -> ExtractError:
    reason = _one_line(exc)
    extension = os.path.splitext(name)[1].lower()
    if extension not in SUPPORTED_EXTENSIONS and "recogni" in reason.lower():
        supported = ", ".join(SUPPORTED_EXTENSIONS)
        return ExtractError(
            f"unsupported format {extension or '(no extension)'!r} "
            f"(libsndfile: {reason}); supported: {supported}",
            path=name,
        )
    return ExtractError(f"cannot decode audio, corrupt or unreadable ({reason})", path=name)


def _check_sample_rate(sample_rate: int, name: str) -> None:
    if not MIN_SAMPLE_RATE <= sample_rate <= MAX_SAMPLE_RATE:
        raise ExtractError(
            f"sample rate {sample_rate} Hz is outside the supported "
            f"{MIN_SAMPLE_RATE}-{MAX_SAMPLE_RATE} Hz",
            path=name,
        )


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


def audio_info(path: str | os.PathLike) -> AudioInfo:
    """Open a file as :func:`decode_audio` would (same checks and messages) and read its header.

    Raises
    ------
    ExtractError
        As :func:`decode_audio`, for everything visible without decoding.
    """
    name = os.fspath(path)
    _check_readable(name)
    try:
        info = soundfile.info(name)
    except (soundfile.LibsndfileError, RuntimeError, TypeError, ValueError) as exc:
        raise _decode_error(exc, name) from exc
    except OSError as exc:
        raise ExtractError(f"cannot read file ({_one_line(exc)})", path=name) from exc
    _check_sample_rate(int(info.samplerate), name)
    return AudioInfo(
        path=name,
        sample_rate=int(info.samplerate),
        n_channels=int(info.channels),
        n_samples=int(info.frames),
        format=str(info.format),
        subtype=str(info.subtype),
    )


def read_blocks(info: AudioInfo, *, block: int) -> Iterator[tuple[int, np.ndarray]]:
    """Decode a file block by block, front to back (no seeking, so any format works).

    Parameters
    ----------
    info : AudioInfo
        From :func:`audio_info`.
    block : int
        Samples per block (the last one may be shorter).

    Yields
    ------
    start : int
        Index of the block's first sample.
    samples : np.ndarray [shape=(n, n_channels), dtype=float32]
        The samples :func:`decode_audio` returns for ``[start, start + n)``.

    Raises
    ------
    ExtractError
        Undecodable data, NaN or infinite samples (naming the first), no samples at all.
    """
    name = info.path
    start = 0
    try:
        with soundfile.SoundFile(name) as handle:
            while True:
                samples = handle.read(block, dtype="float32", always_2d=True)
                if samples.shape[0] == 0:
                    break
                finite = np.isfinite(samples)
                if not finite.all():
                    first = start + int(np.argmin(finite.all(axis=1)))
                    raise ExtractError(
                        f"NaN or infinite sample at sample {first} "
                        f"({first / info.sample_rate:.3f} s)",
                        path=name,
                    )
                yield start, samples
                start += samples.shape[0]
    except (soundfile.LibsndfileError, RuntimeError, TypeError, ValueError) as exc:
        raise _decode_error(exc, name) from exc
    except OSError as exc:
        raise ExtractError(f"cannot read file ({_one_line(exc)})", path=name) from exc
    if start == 0:
        raise ExtractError("zero-length audio: the file holds no samples", path=name)


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
    return samples.mean(axis=1, dtype=np.float32)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__
