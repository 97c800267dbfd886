"""The accelerometer and the gyro calibrated from static poses and the rotations between them
(Tedaldi, Pretto and Menegatti, "A Robust and Easy to Implement Method for IMU Calibration
without External Equipments", ICRA 2014).

Accelerometer (section III-B, eq. 8-10): calibrated = M (raw - b), M upper triangular (scale on
the diagonal, the misalignment of the y and z axes to the x axis and the xy plane off it: the
frame is the accelerometer's own, since the norm cannot see a rotation of it), 9 unknowns, chosen
so that |M (a_i - b)| = g at every static pose i (Levenberg-Marquardt on the residuals
|M (a_i - b)| - g).

Gyro (section III-C, eq. 11-14): calibrated = M_g (raw - b_g), M_g a full 3x3 matrix (scale and
misalignment to the accelerometer's frame), b_g the mean rate over the static intervals. Between
two consecutive poses the calibrated rate, integrated, must turn the first pose's gravity
direction into the second's (the direction of the calibrated accelerometer mean); M_g is the
least-squares fit of those predictions. The integration composes one exact rotation per sample
interval, of the mean of its two rates.

Each term's standard uncertainty comes from the fit's Jacobian and residual variance
(cov = s^2 (J^T J)^-1). A session that cannot determine the model is refused
(CalibrationRefused) with what to record instead.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fusion_core.types import G

from .detect import MULTIPLES, Static, noise_floor, static_intervals, variance_magnitude

MIN_POSES = 9
"""The accelerometer model's unknowns: fewer poses cannot determine it (12 or more are asked)."""
SAME_POSE_DEG = 15.0
"""Poses whose gravity directions are closer than this count as one: the accelerometer's model
needs distinct directions, not repeats of one (a turn about the vertical leaves it)."""
MIN_SPREAD = 0.05
"""The smallest eigenvalue of the poses' mean u u^T (1/3 for directions spread evenly over the
sphere, 0 for directions in one plane): below it the poses do not determine the three scales."""
MIN_TURN_DEG = 20.0
"""A rotation between two poses smaller than this tells the gyro fit too little to count."""
MIN_TURNS = 5
"""The gyro matrix's 9 unknowns need at least five turns (two equations each)."""
RAIL_MARGIN = 1e-3


class CalibrationRefused(ValueError):
    """The session cannot determine the calibration; the message says what to record."""


@dataclass
class Fit:
    """One sensor's calibration: matrix (3x3), offset (3), each term's standard uncertainty, and
    the residual per pose (accelerometer: | |a| - g | [m/s^2]) or per turn (gyro: the angle
    between predicted and measured gravity direction [rad]) before and after."""

    matrix: np.ndarray
    offset: np.ndarray
    matrix_std: np.ndarray
    offset_std: np.ndarray
    before: np.ndarray
    after: np.ndarray
    extra: dict[str, Any] = field(default_factory=dict)


def _upper(p: np.ndarray) -> np.ndarray:
    return np.array([[p[0], p[1], p[2]], [0.0, p[3], p[4]], [0.0, 0.0, p[5]]])


def fit_accelerometer(means: np.ndarray, g: float = G) -> Fit:
    """Tedaldi's accelerometer model from the static means [n, 3] (m/s^2)."""
    from scipy.optimize import least_squares

    def residuals(p: np.ndarray) -> np.ndarray:
        return np.linalg.norm((means - p[6:9]) @ _upper(p[:6]).T, axis=1) - g

    start = np.array([1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    sol = least_squares(residuals, start, method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    std = _standard_uncertainty(sol.jac, sol.fun, len(start))
    matrix_std = np.zeros((3, 3))
    for k, (i, j) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
        matrix_std[i, j] = std[k]
    return Fit(_upper(sol.x[:6]), sol.x[6:9].copy(), matrix_std, std[6:9],
               np.abs(np.linalg.norm(means, axis=1) - g), np.abs(sol.fun))


def _standard_uncertainty(jac: np.ndarray, fun: np.ndarray, p: int) -> np.ndarray:
    dof = max(len(fun) - p, 1)
    s2 = float(fun @ fun) / dof
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
    except np.linalg.LinAlgError:
        return np.full(p, math.inf)
    return np.sqrt(np.maximum(np.diag(cov), 0.0))


_IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    w2, x2, y2, z2 = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def _rotvec_quat(v: np.ndarray) -> np.ndarray:
    angle = np.linalg.norm(v, axis=-1)
    half = 0.5 * angle
    k = np.where(angle > 1e-12, np.sin(half) / np.where(angle > 1e-12, angle, 1.0), 0.5)
    return np.concatenate([np.cos(half)[..., None], v * k[..., None]], axis=-1)


def _rotate_back(q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """R(q)^T u for quaternions q [m, 4] and vectors u [m, 3]."""
    w, v = q[:, :1], q[:, 1:]
    t = 2.0 * np.cross(v, u)
    return u - w * t + np.cross(v, t)


@dataclass(frozen=True)
class Turn:
    """The motion between two consecutive poses: the raw rates and intervals of its samples and
    the two poses' calibrated gravity directions."""

    gyro: np.ndarray  # [k, 3] raw rates, the first pose's last sample to the next one's first
    dt: np.ndarray  # [k - 1] sample intervals
    up_from: np.ndarray
    up_to: np.ndarray
    span: tuple[int, int] = (0, 0)  # its samples in the session [start, stop)


class _Integrator:
    """All turns integrated at once (padded with zero rotations): the predicted gravity
    directions for a gyro matrix and bias."""

    def __init__(self, turns: list[Turn]) -> None:
        n = max(len(t.dt) for t in turns)
        self.mid = np.zeros((len(turns), n, 3))
        self.dt = np.zeros((len(turns), n))
        for i, t in enumerate(turns):
            self.mid[i, :len(t.dt)] = 0.5 * (t.gyro[:-1] + t.gyro[1:])
            self.dt[i, :len(t.dt)] = t.dt
        self.up_from = np.array([t.up_from for t in turns])
        self.up_to = np.array([t.up_to for t in turns])
        self.turns = len(turns)

    def predict(self, matrix: np.ndarray, bias: np.ndarray) -> np.ndarray:
        steps = ((self.mid - bias) @ matrix.T) * self.dt[..., None]
        dq = _rotvec_quat(steps)
        while dq.shape[1] > 1:  # the product dq_0 dq_1 ... in pairs, in order: log2(n) levels
            if dq.shape[1] % 2:
                dq = np.concatenate([dq, np.broadcast_to(_IDENTITY, (self.turns, 1, 4))], axis=1)
            dq = _quat_mul(dq[:, 0::2], dq[:, 1::2])
        return _rotate_back(dq[:, 0], self.up_from)

    def angles(self, matrix: np.ndarray, bias: np.ndarray) -> np.ndarray:
        pred = self.predict(matrix, bias)
        cos = np.clip(np.sum(pred * self.up_to, axis=1) / np.linalg.norm(pred, axis=1), -1, 1)
        return np.arccos(cos)


def fit_gyro(turns: list[Turn], bias: np.ndarray, bias_std: np.ndarray) -> Fit:
    """Tedaldi's gyro model: the full matrix that makes the integrated turns take each pose's
    gravity direction to the next one's."""
    from scipy.optimize import least_squares

    integ = _Integrator(turns)

    def residuals(p: np.ndarray) -> np.ndarray:
        return (integ.predict(p.reshape(3, 3), bias) - integ.up_to).ravel()

    start = np.eye(3).ravel()
    sol = least_squares(residuals, start, method="lm", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    m = sol.x.reshape(3, 3)
    std = _standard_uncertainty(sol.jac, sol.fun, 9).reshape(3, 3)
    return Fit(m, bias.copy(), std, bias_std, integ.angles(np.eye(3), bias),
               integ.angles(m, bias))


@dataclass
class Session:
    """What the detector and both fits found in one session."""

    statics: list[Static]
    threshold: float
    multiple: float
    floor: float
    acc: Fit
    gyro: Fit
    turn_degrees: np.ndarray
    turns: list[Turn] = field(default_factory=list)
    """The turns the gyro's fit used."""


def distinct_directions(statics: list[Static]) -> int:
    """How many of the poses' gravity directions differ by SAME_POSE_DEG or more from every
    other counted one."""
    kept: list[np.ndarray] = []
    cos_same = math.cos(math.radians(SAME_POSE_DEG))
    for s in statics:
        if all(float(s.up @ u) < cos_same for u in kept):
            kept.append(s.up)
    return len(kept)


def choose_threshold(acc: np.ndarray, gyro: np.ndarray, rate: float, g: float = G
                     ) -> tuple[float, float, float, list[Static], Fit]:
    """Tedaldi's criterion: of the thresholds k varsigma_0 (detect.MULTIPLES) that give poses
    in at least MIN_POSES distinct directions, the one whose poses the accelerometer model fits
    best (the smallest mean square residual). Returns (threshold, k, varsigma_0, poses,
    accelerometer fit)."""
    varsigma = variance_magnitude(acc, rate)
    floor = noise_floor(varsigma)
    best: tuple[float, float, float, list[Static], Fit] | None = None
    most, most_distinct = 0, 0
    for k in MULTIPLES:
        statics = static_intervals(acc, gyro, rate, k * floor, varsigma)
        distinct = distinct_directions(statics)
        most, most_distinct = max(most, len(statics)), max(most_distinct, distinct)
        if distinct < MIN_POSES:
            continue
        fit = fit_accelerometer(np.array([s.acc for s in statics]), g)
        score = float(np.mean(fit.after ** 2))
        if best is None or score < float(np.mean(best[4].after ** 2)):
            best = (k * floor, k, floor, statics, fit)
    if best is None:
        raise CalibrationRefused(
            f"found at most {most} static poses in {most_distinct} distinct directions (at "
            f"least {MIN_POSES} directions, {SAME_POSE_DEG:g} deg or more apart, are needed to "
            "determine the accelerometer's 9 terms): record 12 or more poses spread over the "
            "sphere, each held still for 3 s, with the sensor turned by hand between them")
    return best


def check_spread(statics: list[Static]) -> None:
    ups = np.array([s.up for s in statics])
    smallest = float(np.linalg.eigvalsh(ups.T @ ups / len(ups))[0])
    if smallest < MIN_SPREAD:
        raise CalibrationRefused(
            f"the {len(statics)} poses' gravity directions are not spread over the sphere (the "
            f"smallest eigenvalue of their mean u u^T is {smallest:.3f}, at least {MIN_SPREAD} "
            "is needed; 1/3 is even): hold the sensor with each axis pointing up and down at "
            "least once, and in some poses between")


def _turns(acc_fit: Fit, statics: list[Static], gyro: np.ndarray, dt: np.ndarray,
           gyro_range: float) -> tuple[list[Turn], np.ndarray]:
    calibrated_up = [acc_fit.matrix @ (s.acc - acc_fit.offset) for s in statics]
    calibrated_up = [u / np.linalg.norm(u) for u in calibrated_up]
    turns, degrees = [], []
    rail = gyro_range * (1.0 - RAIL_MARGIN)
    for k, (a, b) in enumerate(itertools.pairwise(statics)):
        ua, ub = calibrated_up[k], calibrated_up[k + 1]
        lo, hi = a.stop - 1, b.start + 1
        if np.any(np.abs(gyro[lo:hi]) >= rail):
            raise CalibrationRefused(
                f"between samples {lo} and {hi} the gyro reached its range "
                f"(+-{math.degrees(gyro_range):.0f} deg/s): the rate beyond it is lost; turn "
                "the sensor more slowly between poses (a turn of 90-180 deg in a second or two)")
        turns.append(Turn(gyro[lo:hi], dt[lo + 1:hi], ua, ub, (int(lo), int(hi))))
        degrees.append(math.degrees(math.acos(float(np.clip(ua @ ub, -1.0, 1.0)))))
    return turns, np.array(degrees)


def _check_turns(turns: list[Turn], degrees: np.ndarray, bias: np.ndarray) -> list[Turn]:
    used = [t for t, d in zip(turns, degrees, strict=True) if d >= MIN_TURN_DEG]
    if len(used) < MIN_TURNS:
        raise CalibrationRefused(
            f"only {len(used)} of the {len(turns)} moves between poses turn the gravity "
            f"direction by {MIN_TURN_DEG:g} deg or more (at least {MIN_TURNS} are needed to "
            "determine the gyro's 9 terms): turn the sensor by 90-180 deg between poses")
    axes = []
    for k, (t, d) in enumerate((t, d) for t, d in zip(turns, degrees, strict=True)
                               if d >= MIN_TURN_DEG):
        total = np.sum((0.5 * (t.gyro[:-1] + t.gyro[1:]) - bias) * t.dt[:, None], axis=0)
        seen = math.degrees(float(np.linalg.norm(total)))
        if seen < 0.5 * d:  # a turn of angle a moves the gravity direction by at most a
            raise CalibrationRefused(
                f"the gyro saw {seen:.0f} deg of rotation in move {k + 1}, where the gravity "
                f"direction turned by {d:.0f} deg: the recording must hold the turns between "
                "the poses, without gaps, at the rate it was sampled at")
        axes.append(total / max(np.linalg.norm(total), 1e-12))
    a = np.array(axes)
    smallest = float(np.linalg.eigvalsh(a.T @ a / len(a))[0])
    if smallest < MIN_SPREAD / 2:
        raise CalibrationRefused(
            f"the turns between poses are all about nearly one axis (the smallest eigenvalue of "
            f"their axes' mean a a^T is {smallest:.3f}, at least {MIN_SPREAD / 2:g} is needed): "
            "turn about mixed axes, so that each of the gyro's axes sees rotation")
    return used


def calibrate_session(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                      gyro_range: float = math.radians(2000.0), g: float = G) -> Session:
    """Tedaldi's calibration of one session in SI units; CalibrationRefused saying what to
    record where the session cannot determine it."""
    rate = 1.0 / float(np.median(dt))
    threshold, k, floor, statics, acc_fit = choose_threshold(acc, gyro, rate, g)
    check_spread(statics)
    gyro_means = np.array([s.gyro for s in statics])
    weights = np.array([s.stop - s.start for s in statics], dtype=float)
    bias = np.average(gyro_means, axis=0, weights=weights)
    bias_std = np.std(gyro_means, axis=0, ddof=1) / math.sqrt(len(statics))
    turns, degrees = _turns(acc_fit, statics, gyro, dt, gyro_range)
    used = _check_turns(turns, degrees, bias)
    gyro_fit = fit_gyro(used, bias, bias_std)
    return Session(statics, threshold, k, floor, acc_fit, gyro_fit, degrees, used)
