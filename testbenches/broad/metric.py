"""BROAD's 6D error metric: the inclination error and its RMSE over the movement samples.

Laidig et al. (BROAD, Data 2021, sec. 4) split the orientation error into a heading part and an
inclination part; a 6D estimator (no magnetometer) is judged by the inclination alone. The
inclination error of one sample is the angle between the estimated and the reference direction of
gravity, both expressed in the sensor frame, so it does not depend on heading. Per trial the
figure is the RMSE of that angle over the samples marked `movement`, where samples without a
reference (NaN in `opt_quat`) are left out.

Frames. A quaternion q (w first) that rotates sensor coordinates into a global frame whose z axis
points up has the world up axis, seen from the sensor, as R(q)^T e_z. With our convention (body
x forward, y left, z up; the accelerometer reads +g along up, docs/interface.md) the estimate's
direction from roll phi and pitch theta is (-sin theta, sin phi cos theta, cos phi cos theta).
At rest the normalised accelerometer agrees with both (tests/test_broad.py checks it on a trial).
"""

from __future__ import annotations

import numpy as np


def gravity_from_quat(q: np.ndarray) -> np.ndarray:
    """Up direction in the sensor frame, R(q)^T e_z, for quaternions q [N, 4] (w, x, y, z) that
    rotate sensor coordinates into a z-up global frame. q need not be normalised; NaN rows give
    NaN rows."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z], axis=-1
    )


def gravity_from_roll_pitch(roll: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Up direction in the sensor frame from Z-Y-X roll and pitch [rad] (docs/interface.md):
    (-sin pitch, sin roll cos pitch, cos roll cos pitch)."""
    roll = np.asarray(roll, dtype=float)
    pitch = np.asarray(pitch, dtype=float)
    cp = np.cos(pitch)
    return np.stack([-np.sin(pitch), np.sin(roll) * cp, np.cos(roll) * cp], axis=-1)


def inclination_error(g_est: np.ndarray, g_ref: np.ndarray) -> np.ndarray:
    """Angle [rad] between two direction vectors per row (any lengths); NaN where either is NaN.

    atan2(|a x b|, a . b) keeps full precision for small angles, where arccos of the dot product
    loses it.
    """
    a = np.asarray(g_est, dtype=float)
    b = np.asarray(g_ref, dtype=float)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.einsum("...i,...i->...", a, b)
    return np.arctan2(cross, dot)


def rmse_deg(error: np.ndarray, mask: np.ndarray | None = None) -> float:
    """RMSE [deg] of angles [rad] over the mask's samples, NaN samples left out (BROAD's rule).
    NaN when no sample counts."""
    e = np.asarray(error, dtype=float)
    if mask is not None:
        e = e[np.asarray(mask, dtype=bool)]
    e = e[np.isfinite(e)]
    if e.size == 0:
        return float("nan")
    return float(np.degrees(np.sqrt(np.mean(e * e))))


def inclination_rmse_deg(g_est: np.ndarray, g_ref: np.ndarray, movement: np.ndarray) -> float:
    """BROAD's inclination RMSE [deg] of one trial: estimate and reference up directions [N, 3],
    over the `movement` samples with a reference."""
    return rmse_deg(inclination_error(g_est, g_ref), movement)


__all__ = [
    "gravity_from_quat",
    "gravity_from_roll_pitch",
    "inclination_error",
    "inclination_rmse_deg",
    "rmse_deg",
]
