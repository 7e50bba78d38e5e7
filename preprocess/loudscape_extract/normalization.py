"""How many dB streaming services would turn a song down (or up) at playback.

Each service plays a track at ``gain = target - integrated loudness`` (BS.1770, LUFS), except
that positive gain is limited by its turn-up rule:

- ``"peak"``: turned up only as far as the true peak stays at or below ``ceiling_dbtp``
  (never turned up when the true peak is already above it);
- ``"free"``: turned up to the target whatever the peak (the service limits the peaks);
- ``"never"``: only turned down.

The rules and their public sources are in docs/DYNAMICS.md ("Streaming normalization"); only
what a public source documents is here. The presets are read from ``normalization_presets.json``
beside this module, the one table the app's ``src/data/normalize.rs`` is tested against.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources

__all__ = [
    "BROADCAST",
    "NORMALIZE_CHOICES",
    "PRESETS",
    "SERVICES",
    "Service",
    "normalization_gain",
    "preset_gain",
    "streaming_gains",
]


@dataclass(frozen=True)
class Service:
    """A playback normalization rule.

    Attributes
    ----------
    key : str
        Metadata key (``streaming.<key>``) and CSV column stem.
    name : str
        As shown in the app and the report.
    target_lufs : float
    turn_up : {"peak", "free", "never"}
    ceiling_dbtp : float or None
        The true-peak ceiling of ``"peak"``.
    """

    key: str
    name: str
    target_lufs: float
    turn_up: str
    ceiling_dbtp: float | None = None


def _load_presets(name: str = "normalization_presets.json") -> dict:
    """The presets file's ``services`` and ``broadcast`` lists as :class:`Service` tuples."""
    table = json.loads(resources.files(__package__).joinpath(name).read_text(encoding="utf-8"))
    return {
        group: tuple(Service(**entry) for entry in table[group])
        for group in ("services", "broadcast")
    }


_PRESETS_FILE = _load_presets()
#: Streaming services, in the app's order.
SERVICES = _PRESETS_FILE["services"]
#: Broadcast loudness standards: programmes are brought to the target both ways, the true
#: peak kept under the standard's ceiling by a limiter (modelled as ``"free"`` turn-up).
BROADCAST = _PRESETS_FILE["broadcast"]
#: Every normalization preset by key (``--normalize``): the services, then broadcast.
PRESETS = {service.key: service for service in SERVICES + BROADCAST}
#: ``--normalize`` choices: ``none`` (the files as they are) and :data:`PRESETS`.
NORMALIZE_CHOICES = ("none", *PRESETS)


def normalization_gain(
    service: Service, *, integrated_lufs: float | None, true_peak_dbtp: float | None
) -> float | None:
    """The playback gain in dB (negative: turned down) of ``service`` for a song.

    Returns
    -------
    gain_db : float or None
        None without an integrated loudness (silence, or too short to gate).
    """
    if integrated_lufs is None or not math.isfinite(integrated_lufs):
        return None
    gain = service.target_lufs - integrated_lufs
    if gain <= 0.0 or service.turn_up == "free":
        return gain
    if service.turn_up == "never":
        return 0.0
    if true_peak_dbtp is None or not math.isfinite(true_peak_dbtp):
        return None
    return max(0.0, min(gain, service.ceiling_dbtp - true_peak_dbtp))


def streaming_gains(metrics: dict) -> dict[str, float | None]:
    """``{service.key: gain_db}`` for every service of :data:`SERVICES`.

    Parameters
    ----------
    metrics : dict
        With ``integrated_lufs`` and ``true_peak_dbtp`` (the song metadata's ``metrics``).
    """
    integrated, peak = metrics.get("integrated_lufs"), metrics.get("true_peak_dbtp")
    return {
        s.key: normalization_gain(s, integrated_lufs=integrated, true_peak_dbtp=peak)
        for s in SERVICES
    }


def preset_gain(preset: str, metrics: dict) -> float | None:
    """The gain in dB a ``--normalize`` preset applies to a song (0 for ``"none"``).

    Parameters
    ----------
    preset : str
        One of :data:`NORMALIZE_CHOICES`.
    metrics : dict
        With ``integrated_lufs`` and ``true_peak_dbtp``.

    Returns
    -------
    gain_db : float or None
        None when the song's loudness (or, for a peak-limited turn-up, its true peak) is
        unknown.

    Raises
    ------
    KeyError
        An unknown preset.
    """
    if preset == "none":
        return 0.0
    return normalization_gain(
        PRESETS[preset],
        integrated_lufs=metrics.get("integrated_lufs"),
        true_peak_dbtp=metrics.get("true_peak_dbtp"),
    )
