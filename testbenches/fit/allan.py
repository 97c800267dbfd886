"""Allan deviation of a static recording and the usual fits (IEEE Std 952, Annex C).

The overlapping Allan deviation (allantools.oadev) of a rate signal x sampled at `rate` shows
each noise as a slope in log-log: white noise ("angle random walk" for a gyro, "velocity random
walk" for an accelerometer) as sigma(tau) = N / sqrt(tau), slope -1/2, where N is the white-noise
density [unit/sqrt(Hz)], its line's value at tau = 1 s; the bias instability as the flat floor,
B = min sigma / 0.664; the rate random walk as sigma(tau) = K sqrt(tau / 3), slope +1/2, K the
random-walk density [unit/sqrt(s)]. Each line is fitted (scipy.optimize.curve_fit, the slope
fixed) over the taus whose local slope is near its own; a part the recording does not reach
(too short for the floor or the random walk) is None.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

INSTABILITY_FACTOR = 0.664
"""sigma at the flat floor = 0.664 B for a 1/f bias instability (IEEE Std 952, Annex C)."""
SLOPE_BAND = 0.25
"""A tau belongs to a line where the local slope is within this of the line's slope."""
WHITE_TAU_MAX = 10.0
"""White noise is fitted at taus up to 10 s, where it dominates a MEMS sensor."""


@dataclass(frozen=True)
class AllanFit:
    """One signal's Allan deviation and its fitted noise terms."""

    taus: np.ndarray
    adev: np.ndarray
    white: float
    """N: the white-noise density [unit/sqrt(Hz)] (the -1/2 line at tau = 1 s)."""
    white_taus: tuple[float, float]
    instability: float | None
    """B [unit]: the floor / 0.664, None when the recording does not reach it."""
    instability_tau: float | None
    random_walk: float | None
    """K [unit/sqrt(s)]: the +1/2 line at tau = 3 s, None when the recording does not show it."""


def allan_deviation(x: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of x (a rate, sampled at `rate` Hz) at log-spaced taus from
    one sample to a tenth of the recording (below which too few clusters average)."""
    import allantools

    n = len(x)
    top = max(n // 10, 2)
    m = np.unique(np.round(np.logspace(0, np.log10(top), 60)).astype(int))
    taus, adev, _, _ = allantools.oadev(np.asarray(x, dtype=float), rate=rate,
                                        data_type="freq", taus=m / rate)
    keep = np.isfinite(adev) & (adev > 0)
    return np.asarray(taus)[keep], np.asarray(adev)[keep]


def _fixed_slope(taus: np.ndarray, adev: np.ndarray, slope: float) -> float:
    """exp(a) of the least-squares line log adev = a + slope log tau (scipy's curve_fit)."""
    from scipy.optimize import curve_fit

    lt, la = np.log(taus), np.log(adev)
    if len(lt) == 1:
        return float(np.exp(la[0] - slope * lt[0]))
    (a,), _ = curve_fit(lambda t, a: a + slope * t, lt, la, p0=[float(np.mean(la - slope * lt))])
    return float(np.exp(a))


def fit(taus: np.ndarray, adev: np.ndarray) -> AllanFit:
    """The noise terms of one Allan deviation curve (see the module docstring)."""
    lt, la = np.log(taus), np.log(adev)
    slope = np.gradient(la, lt)
    white = (np.abs(slope + 0.5) < SLOPE_BAND) & (taus <= WHITE_TAU_MAX)
    if not np.any(white):  # no clean -1/2 stretch: the point nearest 1 s
        white = np.abs(lt) == np.min(np.abs(lt))
    n = _fixed_slope(taus[white], adev[white], -0.5)
    i_min = int(np.argmin(adev))
    floor_reached = i_min < len(adev) - 3  # a minimum with rising taus after it
    instability = float(adev[i_min] / INSTABILITY_FACTOR) if floor_reached else None
    rising = (np.abs(slope - 0.5) < SLOPE_BAND) & (np.arange(len(taus)) > i_min)
    k = _fixed_slope(taus[rising], adev[rising], 0.5) * np.sqrt(3.0) if rising.sum() >= 3 else None
    # (the +1/2 line a + 0.5 log tau evaluated at tau = 3 s gives K: K sqrt(3/3) = exp(a) sqrt(3))
    return AllanFit(taus, adev, n, (float(taus[white].min()), float(taus[white].max())),
                    instability, float(taus[i_min]) if floor_reached else None, k)
