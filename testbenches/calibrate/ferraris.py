"""Ferraris, Grimaldi and Parvis (1995): the calibration from six static poses and three turns of
a known angle, for sessions recorded that way (imucal's method, and its section list).

The poses are x_p, x_a, y_p, y_a, z_p, z_a (the named axis pointing up, p, or down, a); the
turns x_rot, y_rot, z_rot are full turns about the named axis. With U_p and U_a the pose means
as columns (x, y, z) and g the gravity:

- accelerometer: offset b_a = the diagonal of (U_p + U_a) / 2 (eq. 19-20), and as the columns of
  U_d = U_p - U_a are 2 g times the inverse calibration's columns (eq. 21-23), the matrix is
  2 g U_d^-1 (the product of the paper's inverse rotation and scale);
- gyro: offset b_g the mean rate over the six poses; its sensitivity to the specific force
  K_ga = (G_p - G_a) / 2 g (eq. 9) from the same poses' mean rates; each turn's rate less
  b_g + K_ga a (a the calibrated specific force) integrated is the column W_s of the turned axis
  (eq. 13-14), and as each is the turn's angle times the inverse calibration's column, the
  matrix is theta W_s^-1 (eq. 12, 15). The angle's sign is the integral's (a turn of -360 or
  +360 deg, whichever way it was made).

The estimators' calibration has no sensitivity of the gyro to the specific force: K_ga is
reported beside the result, not applied.

Sections come from imucal's section list ({"x_p": {"start": i, "end": j}, ...}, sample
indices) or from the session's own static intervals and turns (`sections_from_session`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.types import G

from .detect import Static
from .tedaldi import CalibrationRefused, Fit

POSES = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
TURNS = ("x_rot", "y_rot", "z_rot")
SECTIONS = (*POSES, *TURNS)
TURN_ANGLE = 2.0 * math.pi


def read_sections(path: Path) -> dict[str, tuple[int, int]]:
    """imucal's section list: {name: (start, end)} for all nine sections; ValueError naming what
    is missing."""
    try:
        doc = json.loads(Path(path).read_text())
        out = {name: (int(doc[name]["start"]), int(doc[name]["end"])) for name in SECTIONS}
    except FileNotFoundError:
        raise
    except (json.JSONDecodeError, KeyError, TypeError, ValueError) as err:
        raise ValueError(f"{path}: a section list needs {', '.join(SECTIONS)}, each "
                         f"{{\"start\": sample, \"end\": sample}} ({type(err).__name__}: {err})"
                         ) from None
    for name, (start, end) in out.items():
        if not end > start >= 0:
            raise ValueError(f"{path}: section {name} ends ({end}) before it starts ({start})")
    return out


def ferraris(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
             sections: dict[str, tuple[int, int]], g: float = G) -> tuple[Fit, Fit]:
    """The Ferraris calibration of both sensors from the sections (SI units)."""
    n = len(acc)
    for name, (_, end) in sections.items():
        if end > n:
            raise ValueError(f"section {name} ends at sample {end}, after the recording's {n}")
    pose_acc = {p: acc[slice(*sections[p])].mean(axis=0) for p in POSES}
    pose_gyro = {p: gyro[slice(*sections[p])].mean(axis=0) for p in POSES}
    u_p = np.column_stack([pose_acc[f"{a}_p"] for a in "xyz"])
    u_a = np.column_stack([pose_acc[f"{a}_a"] for a in "xyz"])
    offset = np.diag((u_p + u_a) / 2.0).copy()
    acc_matrix = 2.0 * g * np.linalg.inv(u_p - u_a)
    before = np.array([abs(np.linalg.norm(pose_acc[p]) - g) for p in POSES])
    after = np.array([abs(np.linalg.norm(acc_matrix @ (pose_acc[p] - offset)) - g)
                      for p in POSES])
    acc_fit = Fit(acc_matrix, offset, np.full((3, 3), np.nan), np.full(3, np.nan), before, after)

    static = np.vstack([gyro[slice(*sections[p])] for p in POSES])
    gyro_offset = static.mean(axis=0)
    k_ga = (np.column_stack([pose_gyro[f"{a}_p"] for a in "xyz"])
            - np.column_stack([pose_gyro[f"{a}_a"] for a in "xyz"])) / (2.0 * g)
    w_s = np.zeros((3, 3))
    for i, name in enumerate(TURNS):
        lo, hi = sections[name]
        a_cal = (acc[lo:hi] - offset) @ acc_matrix.T
        rate = gyro[lo:hi] - gyro_offset - a_cal @ k_ga.T
        w_s[:, i] = np.sum(rate * dt[lo:hi, None], axis=0)
    angles = np.sign(np.diag(w_s)) * TURN_ANGLE
    if np.any(angles == 0.0):
        raise CalibrationRefused("a turn section holds no rotation about its axis")
    gyro_matrix = np.linalg.inv(w_s / angles[None, :])
    turn_error = np.abs(np.linalg.norm(w_s, axis=0) - TURN_ANGLE)
    turn_after = np.abs(np.linalg.norm(gyro_matrix @ w_s, axis=0) - TURN_ANGLE)
    gyro_fit = Fit(gyro_matrix, gyro_offset, np.full((3, 3), np.nan), np.full(3, np.nan),
                   turn_error, turn_after, {"g_sensitivity": k_ga.tolist()})
    return acc_fit, gyro_fit


def sections_from_session(statics: list[Static], gyro: np.ndarray, dt: np.ndarray,
                          bias: np.ndarray) -> dict[str, tuple[int, int]]:
    """The nine sections from a session's own static intervals: for each pose the longest
    interval whose gravity direction is within 30 deg of that axis up (p) or down (a); for each
    turn the shortest stretch between two static intervals whose integrated rate (less the bias)
    is a full turn (300-420 deg) about that axis, with under a quarter of it about the others.
    CalibrationRefused naming the sections it could not find."""
    out: dict[str, tuple[int, int]] = {}
    cos30 = math.cos(math.radians(30.0))
    for name in POSES:
        axis = "xyz".index(name[0])
        sign = 1.0 if name[2] == "p" else -1.0
        fitting = [s for s in statics if sign * s.up[axis] >= cos30]
        if fitting:
            best = max(fitting, key=lambda s: s.stop - s.start)
            out[name] = (best.start, best.stop)
    increments = (gyro - bias) * dt[:, None]
    cumulative = np.vstack([np.zeros(3), np.cumsum(increments, axis=0)])
    for name in TURNS:
        axis = "xyz".index(name[0])
        best_span: tuple[int, int] | None = None
        for i, a in enumerate(statics):
            for b in statics[i + 1:]:
                total = cumulative[b.start] - cumulative[a.stop]
                about = abs(total[axis])
                others = math.hypot(*np.delete(total, axis))
                if (math.radians(300.0) <= about <= math.radians(420.0)
                        and others < 0.25 * about
                        and (best_span is None or b.start - a.stop < best_span[1] - best_span[0])):
                    best_span = (a.stop, b.start)
        if best_span is not None:
            out[name] = best_span
    missing = [s for s in SECTIONS if s not in out]
    if missing:
        raise CalibrationRefused(
            f"the session's own intervals hold no {', '.join(missing)}: Ferraris's method needs "
            "each axis held up and down still, and a full turn about each axis between two "
            "still poses")
    return out


def summary(acc_fit: Fit, gyro_fit: Fit) -> dict[str, Any]:
    """The scale factors and misalignment angles of both sensors' matrices (for side-by-side
    tables): the inverse calibration's column norms are the scales, the angles between its
    columns and the axes the misalignments."""
    out: dict[str, Any] = {}
    for sensor, fit in (("acc", acc_fit), ("gyro", gyro_fit)):
        scales, angles = scales_and_misalignment(fit.matrix)
        out[sensor] = {"scale": scales, "misalignment_deg": angles}
    return out


def scales_and_misalignment(matrix: Any) -> tuple[list[float], list[float]]:
    """A calibration matrix's scale factors (its inverse's column norms) and misalignments
    [deg] (the angle of each of those columns from its axis)."""
    inverse = np.linalg.inv(np.asarray(matrix, dtype=float))
    scales = np.linalg.norm(inverse, axis=0)
    angles = [math.degrees(math.acos(min(1.0, abs(inverse[i, i]) / scales[i])))
              for i in range(3)]
    return scales.tolist(), angles
