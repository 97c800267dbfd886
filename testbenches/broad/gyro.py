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


def fit_gyro(trial: BroadTrial, window_s: float = WINDOW_S, min_turn: float = MIN_TURN
             ) -> GyroFit:
    """Fit the trial's gyro against its reference orientation (see the module docstring).
    ValueError when fewer than 100 windows turn by min_turn (nothing to fit: a recording at rest
    measures the bias only)."""
    w = max(1, round(window_s * trial.rate))
    q = trial.opt_quat
    ok = np.all(np.isfinite(q), axis=1)
    a = np.arange(trial.n - w)
    a = a[ok[a] & ok[a + w]]
    b = a + w
    dphi = _rotvec_between(q[a], q[b])
    # the gyro's integral over (t_a, t_b]: mean samples a+1..b, or the trapezoid of point samples
    c = np.vstack([np.zeros(3), np.cumsum(trial.gyro, axis=0)]) * trial.dt
    if trial.gyro_sampling == "mean":
        g_int = c[b + 1] - c[a + 1]
    else:
        g_int = c[b + 1] - c[a + 1] - 0.5 * trial.dt * (trial.gyro[b] - trial.gyro[a])
    turning = np.linalg.norm(dphi, axis=1) >= min_turn
    if int(turning.sum()) < 100:
        raise ValueError(f"{trial.name}: {int(turning.sum())} windows of {w} samples turn by "
                         f"{np.degrees(min_turn):.1f} deg or more; at least 100 are needed to fit "
                         "the gyro's scale and cross-axis errors")
    x = np.column_stack([dphi[turning], np.full(int(turning.sum()), w * trial.dt)])
    sol, *_ = np.linalg.lstsq(x, g_int[turning], rcond=None)
    residual = g_int[turning] - x @ sol
    return GyroFit(matrix=sol[:3].T.copy(), bias=sol[3].copy(), windows=int(turning.sum()),
                   residual=float(np.sqrt(np.mean(residual**2))))


def scale_oracle(trial: BroadTrial, fit: GyroFit, columns: list[Column], groups: list[str]
                 ) -> TrialResult:
    """The columns on the trial with its fitted scale-factor errors divided out of the gyro. An
    oracle (the trial's own reference calibrates its gyro): the most an in-run estimate of the
    scale factors could give."""
    return evaluate_trial(replace(trial, gyro=trial.gyro / np.diag(fit.matrix)), columns, groups)
