"""How good a calibration is, judged on data its fit did not see.

A fit's own residuals cannot show that: Ferraris's six poses are met exactly by construction,
and Tedaldi's nine terms bend towards the poses they are fitted to. So each pose and each turn
is judged under a fit that left it out:

- Tedaldi's method (testbenches.calibrate.tedaldi): the accelerometer refitted without pose i
  gives pose i's | |a| - g |, and the gyro refitted without turn j gives turn j's angle between
  the predicted and the measured gravity direction (leave one out);
- Ferraris's method (testbenches.calibrate.ferraris) needs all six of its poses and its three
  full turns, so the held-out data are the session's other static poses (the detector's, away
  from the six sections) and the moves between consecutive poses (away from the three turns),
  judged under the calibration as fitted.

Either way a residual near the fit's own says the calibration holds beyond its data; one far
above it says the model does not describe the part (or the session moved while "still").
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .detect import MULTIPLES, Static, noise_floor, static_intervals, variance_magnitude
from .tedaldi import Fit, Session, Turn, _Integrator, fit_accelerometer, fit_gyro


@dataclass(frozen=True)
class HeldOut:
    """Per pose | |a| - g | [m/s^2] and per turn the gravity direction's miss [rad], each
    under a fit that did not use it, with the samples each spans (start, stop)."""

    acc: np.ndarray
    acc_spans: list[tuple[int, int]]
    gyro: np.ndarray
    gyro_spans: list[tuple[int, int]]


def tedaldi_held_out(session: Session, g: float) -> HeldOut:
    """Leave one out, for the accelerometer's poses and the gyro's turns."""
    gyro_turns = session.turns
    means = np.array([s.acc for s in session.statics])
    acc = np.empty(len(means))
    for i in range(len(means)):
        fit = fit_accelerometer(np.delete(means, i, axis=0), g)
        acc[i] = abs(np.linalg.norm(fit.matrix @ (means[i] - fit.offset)) - g)
    bias, bias_std = session.gyro.offset, session.gyro.offset_std
    gyro = np.empty(len(gyro_turns))
    for j, turn in enumerate(gyro_turns):
        others = gyro_turns[:j] + gyro_turns[j + 1:]
        fit = fit_gyro(others, bias, bias_std)
        gyro[j] = _Integrator([turn]).angles(fit.matrix, bias)[0]
    return HeldOut(acc, [(s.start, s.stop) for s in session.statics], gyro,
                   [t.span for t in gyro_turns])


def session_poses(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> list[Static]:
    """The session's static poses at the detector's threshold that finds the most of them
    (the lower threshold where two find as many)."""
    rate = 1.0 / float(np.median(dt))
    varsigma = variance_magnitude(acc, rate)
    floor = noise_floor(varsigma)
    best: list[Static] = []
    for k in MULTIPLES:
        found = static_intervals(acc, gyro, rate, k * floor, varsigma)
        if len(found) > len(best):
            best = found
    return best


def _overlaps(lo: int, hi: int, spans: list[tuple[int, int]]) -> bool:
    return any(lo < b and a < hi for a, b in spans)


def ferraris_held_out(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                      sections: dict[str, tuple[int, int]], acc_fit: Fit, gyro_fit: Fit,
                      g: float) -> HeldOut:
    """The session's poses and moves that are not Ferraris's sections, under its calibration."""
    from .ferraris import POSES, TURNS

    poses = session_poses(acc, gyro, dt)
    fitted = [sections[p] for p in POSES]
    held = [s for s in poses if not _overlaps(s.start, s.stop, fitted)]
    acc_res = np.array([abs(np.linalg.norm(acc_fit.matrix @ (s.acc - acc_fit.offset)) - g)
                        for s in held])
    up = [acc_fit.matrix @ (s.acc - acc_fit.offset) for s in poses]
    up = [u / np.linalg.norm(u) for u in up]
    turns = [sections[t] for t in TURNS]
    moves, spans = [], []
    for k, (a, b) in enumerate(itertools.pairwise(poses)):
        lo, hi = a.stop - 1, b.start + 1
        if _overlaps(lo, hi, turns):
            continue
        moves.append(Turn(gyro[lo:hi], dt[lo + 1:hi], up[k], up[k + 1], (lo, hi)))
        spans.append((lo, hi))
    gyro_res = np.empty(0)
    if moves:
        # the fit's gyro model: calibrated = matrix (raw - offset), the matrix acting on
        # (raw - offset) as Tedaldi's integrator takes it
        gyro_res = _Integrator(moves).angles(gyro_fit.matrix, gyro_fit.offset)
    return HeldOut(acc_res, [(s.start, s.stop) for s in held], gyro_res, spans)
