"""Static intervals of a calibration session, found by Tedaldi's detector.

Tedaldi, Pretto and Menegatti (ICRA 2014, section IV-A): the variance magnitude of the
accelerometer over a short window,

    varsigma(t) = |(var a_x, var a_y, var a_z)| over [t - t_w / 2, t + t_w / 2],

is small while the sensor is still; a sample is static where varsigma is below k times the
floor varsigma_0 that noise alone gives. The paper takes the floor from a static period at the
start of the session and chooses the multiple k by its own criterion: the one whose static
intervals the accelerometer's model fits best (testbenches.calibrate.tedaldi.choose_threshold).
Here the floor is a low quantile of varsigma over the whole session, which holds for any session
that is still for more than a tenth of its time, wherever that time is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WINDOW_S = 1.0
"""t_w: the variance window [s]. Shorter than the poses (3 s), long enough for a variance of
about a hundred samples at 100 Hz."""
MIN_STATIC_S = 1.0
"""The shortest interval taken as a pose [s]."""
TRIM_S = 0.25
"""Cut from both ends of an interval before its mean: the window's half-width reaches into the
motion around it."""
FLOOR_QUANTILE = 0.05
"""varsigma_0: this quantile of varsigma over the session (noise alone)."""
MULTIPLES = (2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0)
"""The thresholds tried, as multiples k of varsigma_0 (Tedaldi et al. try k = 1..10 times the
initial variance; these span the same decades and beyond for hand-held sessions)."""


@dataclass(frozen=True)
class Static:
    """One static interval: its samples [start, stop) after trimming, and its means."""

    start: int
    stop: int
    acc: np.ndarray  # mean specific force [m/s^2]
    gyro: np.ndarray  # mean rate [rad/s]

    @property
    def up(self) -> np.ndarray:
        """The direction of the measured specific force (up, in the sensor's frame)."""
        return self.acc / np.linalg.norm(self.acc)


def variance_magnitude(acc: np.ndarray, rate: float, window_s: float = WINDOW_S) -> np.ndarray:
    """varsigma per sample: the norm of the per-axis variances over a centred window."""
    n = len(acc)
    w = max(3, round(window_s * rate) | 1)
    half = w // 2
    padded = np.pad(acc, ((half, half), (0, 0)), mode="edge")
    c1 = np.cumsum(np.vstack([np.zeros((1, 3)), padded]), axis=0)
    c2 = np.cumsum(np.vstack([np.zeros((1, 3)), padded * padded]), axis=0)
    s1 = c1[w:w + n] - c1[:n]
    s2 = c2[w:w + n] - c2[:n]
    var = np.maximum(s2 / w - (s1 / w) ** 2, 0.0)
    return np.linalg.norm(var, axis=1)


def noise_floor(varsigma: np.ndarray) -> float:
    """varsigma_0 (FLOOR_QUANTILE), kept above zero for a quantised signal that does not move."""
    floor = float(np.quantile(varsigma, FLOOR_QUANTILE))
    return floor if floor > 0.0 else float(np.min(varsigma[varsigma > 0.0], initial=1e-12))


def static_intervals(acc: np.ndarray, gyro: np.ndarray, rate: float, threshold: float,
                     varsigma: np.ndarray | None = None) -> list[Static]:
    """The intervals where varsigma < threshold for at least MIN_STATIC_S, trimmed, with their
    means."""
    if varsigma is None:
        varsigma = variance_magnitude(acc, rate)
    still = np.concatenate([[False], varsigma < threshold, [False]])
    edges = np.flatnonzero(np.diff(still.astype(np.int8)))
    trim = round(TRIM_S * rate)
    out = []
    for start, stop in zip(edges[0::2], edges[1::2], strict=True):
        start, stop = start + trim, stop - trim
        if (stop - start) / rate >= MIN_STATIC_S - 2 * TRIM_S and stop > start:
            out.append(Static(int(start), int(stop), acc[start:stop].mean(axis=0),
                              gyro[start:stop].mean(axis=0)))
    return out
