"""The calibrated axes turned onto the housing's level (`calibrate --level`).

A calibration from still poses and turns alone fixes its frame on the accelerometer's own axes:
the norm of a specific force, and the turns between poses, look the same whatever way the
sensor's triad is tilted in its housing, so that tilt (a chip soldered a tenth of a degree off
its board, a board screwed into its case) is left in every calibrated sample, and at rest no
filter can tell it from the housing's own tilt. One pose held with the housing level (on a level
surface, z up) shows it: the calibrated specific force of that pose is what a level housing
reads. Both calibrated sensors are turned about x and y by the rotation that makes that pose
read level (fusion_core.base.mounting_matrix of its roll and pitch: no turn about z, which
gravity cannot show), the gyro's with the accelerometer's, as its frame is the accelerometer's.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from fusion_core.base import mounting_matrix
from fusion_core.kinematics import accel_roll_pitch

from .tedaldi import Fit

MAX_LEVEL_DEG = 20.0
"""The still pose nearest z up is taken as the level one only within this of it: a session
without a pose that near z up was not held level there."""


def level_turn(up: np.ndarray) -> tuple[float, float, np.ndarray]:
    """The roll and pitch [rad] that a level housing's calibrated specific force `up` shows,
    and the rotation (3x3) that takes it onto +z."""
    roll, pitch = accel_roll_pitch(float(up[0]), float(up[1]), float(up[2]))
    return roll, pitch, np.array(mounting_matrix(roll, pitch, 0.0)).reshape(3, 3)


def levelled(acc_fit: Fit, gyro_fit: Fit, raw_mean: np.ndarray
             ) -> tuple[Fit, Fit, dict[str, Any]]:
    """Both fits turned so that a pose whose raw mean specific force is raw_mean reads level,
    and what was turned (for calibration.json): ValueError where that pose is more than
    MAX_LEVEL_DEG from z up."""
    up = acc_fit.matrix @ (np.asarray(raw_mean, dtype=float) - acc_fit.offset)
    off = float(np.degrees(np.arccos(np.clip(up[2] / np.linalg.norm(up), -1.0, 1.0))))
    if off > MAX_LEVEL_DEG:
        raise ValueError(f"the pose taken as level reads {off:.1f} deg from z up (at most "
                         f"{MAX_LEVEL_DEG:g} allowed): hold the housing level, z up, for one "
                         "still pose of the session")
    roll, pitch, turn = level_turn(up)
    said = {"roll_deg": float(np.degrees(roll)), "pitch_deg": float(np.degrees(pitch))}
    return (dataclasses.replace(acc_fit, matrix=turn @ acc_fit.matrix),
            dataclasses.replace(gyro_fit, matrix=turn @ gyro_fit.matrix), said)


def level_pose(means: list[np.ndarray]) -> np.ndarray:
    """Of still poses' raw mean specific forces, the one nearest z up (the pose a session
    holds level)."""
    return max(means, key=lambda m: float(m[2] / np.linalg.norm(m)))
