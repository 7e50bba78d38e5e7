"""Shared helpers for the extractor tests: short synthetic signals at low sample rates."""

from __future__ import annotations

import numpy as np
import pytest


def sine(*, frequency: float, sample_rate: int, duration_s: float, amplitude: float = 1.0):
    """Sine of shape (n,), float64, starting at phase 0."""
    t = np.arange(int(round(duration_s * sample_rate))) / sample_rate
    return amplitude * np.sin(2 * np.pi * frequency * t)


def musical_signal(*, sample_rate: int = 8000, duration_s: float = 2.0, seed: int = 0):
    """Chord + bass + kick/hat clicks: a small spectrogram with both kinds of structure."""
    rng = np.random.default_rng(seed)
    n = int(duration_s * sample_rate)
    t = np.arange(n) / sample_rate
    y = np.zeros(n)
    for f in (220.0, 277.2, 329.6, 110.0):
        y += 0.15 * np.sin(2 * np.pi * f * t) * (1 + 0.3 * np.sin(2 * np.pi * 0.7 * t))
    for start in np.arange(0, duration_s, 0.25):
        i = int(start * sample_rate)
        length = min(400, n - i)
        y[i : i + length] += 0.5 * rng.standard_normal(length) * np.exp(-np.arange(length) / 60)
    return y


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
