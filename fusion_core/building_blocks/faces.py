"""The nearest face: per-axis tilt filters run in the sensor frame turned by the right-angle
rotation that brings the axis nearest to up onto z, so that a sensor resting on any face is the
level case for them."""

from __future__ import annotations

from typing import Final

from ..linalg import Mat9

FACES: Final[tuple[Mat9, ...]] = (
    (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),  # z up: the identity
    (1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0),  # -z up: roll 180 deg
    (0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0),  # x up: the axes cycled, (y, z, x)
    (0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0),  # -x up
    (0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0),  # y up: (z, x, y)
    (0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0),  # -y up
)
"""The six faces a sensor can rest on, each as the rotation C (row by row) from the sensor frame
to a face frame whose z axis is that face's up axis: v_face = C v_sensor. Every C is a signed
permutation with determinant +1, so turning a vector into a face frame and back is exact."""

FACE_SWITCH_COS: Final = 0.5
"""A filter on a face moves to the nearest face once up is more than 60 deg from the face's z
axis (its z component below cos 60 deg). The nearest face is then at most 54.7 deg away (the
cube's diagonal), so the switch has a margin and cannot chatter, and the filter's pitch and roll
stay within 60 deg of level, far from the Euler angles' singularity at 90 deg."""


def nearest_face(ux: float, uy: float, uz: float) -> int:
    """Index into FACES of the face whose up axis is nearest the direction (ux, uy, uz)
    (sensor frame, any length); z up where the direction is zero."""
    ax, ay, az = abs(ux), abs(uy), abs(uz)
    if az >= ax and az >= ay:
        return 0 if uz >= 0.0 else 1
    if ax >= ay:
        return 2 if ux > 0.0 else 3
    return 4 if uy > 0.0 else 5
