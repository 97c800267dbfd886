"""The gyro against the reference: its scale-factor, cross-axis and bias errors in a recording.

A 6D filter cannot see the gyro's scale-factor and cross-axis errors: it integrates them, and
the accelerometer corrects what they leave only as fast as the correction's time constant allows.
In fast rotation that is the dominant error (a 0.5 % error over a 180 deg swing is 0.9 deg), so
this module measures them wherever a reference orientation exists (BROAD's optical motion
capture): over short windows the reference's rotation dphi [rad] and the gyro's integral over the
same interval are fitted, by least squares over the windows that turn, as

    integral(gyro) = M dphi + b T

with M the gyro's 3x3 sensitivity matrix (identity for a perfect gyro: its diagonal minus one is
the scale-factor error of each axis, its off-diagonal the cross-axis sensitivity, including any
misalignment of the reference's frame to the sensor's) and b the bias [rad/s], T the window's
length. Over a window of a few tens of milliseconds the rotation vector of R_a^T R_b equals the
integral of the body rate up to the coning term, which is of second order in the window's
rotation; windows turning less than MIN_TURN are left out (there the reference's noise
dominates).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .data import BroadTrial
from .run import Column, TrialResult, evaluate_trial

WINDOW_S = 0.035
"""Window length [s]: 10 samples at BROAD's 285.7 Hz; short enough that the coning term is
negligible at a few hundred deg/s, long enough that the reference's noise averages."""
MIN_TURN = 0.05
"""Smallest rotation of a window that enters the fit [rad] (2.9 deg)."""


@dataclass(frozen=True)
class GyroFit:
    """The gyro's errors in one recording, fitted against the reference."""

    matrix: np.ndarray
    """M [3, 3]: gyro = M omega + b."""
    bias: np.ndarray
    """b [3], rad/s."""
    windows: int
    """Windows that entered the fit."""
    residual: float
    """RMS of the fit's residual per window [rad]."""

    @property
    def scale_error(self) -> np.ndarray:
        """Scale-factor error of each axis (diagonal of M minus one)."""
        return np.diag(self.matrix) - 1.0

    @property
    def cross_axis(self) -> np.ndarray:
        """The six off-diagonal entries of M, row by row."""
        return self.matrix[~np.eye(3, dtype=bool)]

    def as_dict(self) -> dict[str, Any]:
        return {
            "scale_error_pct": (100.0 * self.scale_error).tolist(),
            "cross_axis_pct": (100.0 * self.cross_axis).tolist(),
            "max_abs_cross_axis_pct": float(100.0 * np.max(np.abs(self.cross_axis))),
            "bias_dps": np.degrees(self.bias).tolist(),
            "windows": self.windows,
            "residual_deg": float(np.degrees(self.residual)),
        }


def _rotvec_between(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """Rotation vectors [N, 3] of R(qa)^T R(qb) for quaternions (w, x, y, z) that rotate the
    sensor frame into the global one: the body-frame rotation from a to b."""
    from scipy.spatial.transform import Rotation

    def rot(q: np.ndarray) -> Rotation:
        return Rotation.from_quat(q[:, [1, 2, 3, 0]])

    return np.asarray((rot(qa).inv() * rot(qb)).as_rotvec())


def _turning_windows(trial: BroadTrial, window_s: float, min_turn: float, margin: int,
                     fitted: str) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """The window length w [samples], and the start and end samples a, b = a + w and the
    reference's rotation dphi of every window that has a reference at both ends, lies at least
    margin samples from either end of the trial and turns by min_turn or more. ValueError,
    naming what was to be fitted, when fewer than 100 windows turn (a recording at rest measures
    the bias only)."""
    w = max(1, round(window_s * trial.rate))
    q = trial.opt_quat
    ok = np.all(np.isfinite(q), axis=1)
    a = np.arange(margin, trial.n - w - margin)
    a = a[ok[a] & ok[a + w]]
    dphi = _rotvec_between(q[a], q[a + w])
    turning = np.linalg.norm(dphi, axis=1) >= min_turn
    if int(turning.sum()) < 100:
        raise ValueError(f"{trial.name}: {int(turning.sum())} windows of {w} samples turn by "
                         f"{np.degrees(min_turn):.1f} deg or more; at least 100 are needed to fit "
                         f"{fitted}")
    a = a[turning]
    return w, a, a + w, dphi[turning]


def _gyro_cumulative(trial: BroadTrial) -> np.ndarray:
    """The gyro's integral [N, 3] from the first sample's instant to each sample's [rad], by the
    rule its sampling property gives: a mean sample k holds the interval (t_k-1, t_k] (the first
    one's interval lies before the recording and is left out), point samples are joined by the
    trapezoid rule."""
    g = trial.gyro
    steps = g[1:] if trial.gyro_sampling == "mean" else 0.5 * (g[1:] + g[:-1])
    return np.vstack([np.zeros(3), np.cumsum(steps, axis=0)]) * trial.dt


def _window_integrals(trial: BroadTrial, cum: np.ndarray, a: np.ndarray, b: np.ndarray,
                      shift: float) -> np.ndarray:
    """The gyro's integral [K, 3] over (t_a + shift h, t_b + shift h] from its cumulative
    integral cum (_gyro_cumulative), linear between samples (exact for mean samples, whose rate
    is constant over each interval)."""
    if shift == 0.0:
        return cum[b] - cum[a]
    index = np.arange(trial.n, dtype=float)
    return np.column_stack([np.interp(b + shift, index, cum[:, k]) -
                            np.interp(a + shift, index, cum[:, k]) for k in range(3)])


def fit_gyro(trial: BroadTrial, window_s: float = WINDOW_S, min_turn: float = MIN_TURN,
             delay: float | None = None) -> GyroFit:
    """Fit the trial's gyro against its reference orientation (see the module docstring), the
    gyro's windows taken delay [s] later than the reference's (default: the trial's
    sensor_delay; fit_delay measures it), so that its lag is not read as scale errors.
    ValueError when fewer than 100 windows turn by min_turn (nothing to fit: a recording at rest
    measures the bias only)."""
    shift = (trial.sensor_delay if delay is None else delay) / trial.dt
    w, a, b, dphi = _turning_windows(trial, window_s, min_turn, int(np.ceil(abs(shift))) + 1,
                                     "the gyro's scale and cross-axis errors")
    g_int = _window_integrals(trial, _gyro_cumulative(trial), a, b, shift)
    x = np.column_stack([dphi, np.full(a.size, w * trial.dt)])
    sol, *_ = np.linalg.lstsq(x, g_int, rcond=None)
    residual = g_int - x @ sol
    return GyroFit(matrix=sol[:3].T.copy(), bias=sol[3].copy(), windows=int(a.size),
                   residual=float(np.sqrt(np.mean(residual**2))))


@dataclass(frozen=True)
class GyroDelay:
    """How far the gyro's samples lag the reference orientation in one recording."""

    samples: float
    """The lag in sample periods (positive: the gyro shows a rotation later than the reference)."""
    seconds: float
    """The same lag [s]."""
    shifts: np.ndarray
    """The shifts tried [samples]."""
    residuals: np.ndarray
    """The fit's RMS residual per window [rad] at each shift."""

    def as_dict(self) -> dict[str, Any]:
        return {"delay_samples": float(self.samples), "delay_ms": float(1e3 * self.seconds),
                "residual_deg_at_delay": float(np.degrees(np.min(self.residuals))),
                "residual_deg_at_zero": float(np.degrees(np.interp(0.0, self.shifts,
                                                                   self.residuals)))}


def fit_delay(trial: BroadTrial, window_s: float = WINDOW_S, min_turn: float = MIN_TURN,
              max_shift: float = 2.0, step: float = 0.25) -> GyroDelay:
    """The gyro's lag behind the reference: the shift s [samples] of the gyro's integration
    window, (t_a + s h, t_b + s h] against the reference's (t_a, t_b], at which the fit of
    fit_gyro leaves the least residual (_window_integrals); shifts from -max_shift to max_shift
    in steps of step, the minimum refined by the parabola through it and its neighbours. The
    lag is the sensor's: its internal low-pass filters' group delay and the time-stamping of its
    samples against the reference, which an estimator's output shares (sensor_delay turns the
    output ahead over it)."""
    w, a, b, dphi = _turning_windows(trial, window_s, min_turn, int(np.ceil(max_shift)) + 1,
                                     "the gyro's delay")
    x = np.column_stack([dphi, np.full(a.size, w * trial.dt)])
    cum = _gyro_cumulative(trial)
    shifts = np.arange(-max_shift, max_shift + 0.5 * step, step)
    residuals = np.empty(shifts.size)
    for i, s in enumerate(shifts):
        g_int = _window_integrals(trial, cum, a, b, float(s))
        sol, *_ = np.linalg.lstsq(x, g_int, rcond=None)
        residuals[i] = np.sqrt(np.mean((g_int - x @ sol) ** 2))
    i = int(np.argmin(residuals))
    best = float(shifts[i])
    if 0 < i < shifts.size - 1:
        y0, y1, y2 = residuals[i - 1:i + 2]
        best += step * 0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2)
    return GyroDelay(samples=best, seconds=best * trial.dt, shifts=shifts, residuals=residuals)


def scale_oracle(trial: BroadTrial, fit: GyroFit, columns: list[Column], groups: list[str]
                 ) -> TrialResult:
    """The columns on the trial with its fitted scale-factor errors divided out of the gyro. An
    oracle (the trial's own reference calibrates its gyro): the most an in-run estimate of the
    scale factors could give."""
    return evaluate_trial(replace(trial, gyro=trial.gyro / np.diag(fit.matrix)), columns, groups)
