"""Quaternion propagation of the Euler-angle filters (cf, kf). The papers integrate the Euler
rates (Duong Quoc eq. 2), whose tan(pitch) term is singular at pitch +-90 deg: a sensor that
turns through the vertical (every rotation trial of BROAD does) loses the attitude there, and the
innovation of roll, which the accelerometer cannot observe near pitch +-90 deg, cannot bring it
back. The recommended cf and kf keep an attitude quaternion q (yaw free, unobservable), turn it
by the bias-corrected rotation vector of each interval (the quaternion filters' rule,
kinematics.rotation_increment), take roll and pitch from it, apply their paper's correction to
roll and pitch, and turn q by that correction (corrected_quat; near the vertical q is rebuilt
from the corrected roll and pitch with yaw 0, quat_from_roll_pitch: the free yaw does not change
roll or pitch). The correction law, its gains and its covariance are the paper's.

The cf and kf correct without an arctangent, sine or cosine (libm calls, which the read-off
and the rebuild made a quarter of the kf's time): the innovation is the angle from q's tilt to
the accelerometer's (tilt_innovation) and the corrected q is q turned by the correction
(corrected_quat). Each is the round trip's angle, computed as the angle between two directions,
which for the innovation of a converged filter and its correction is a short series
(kinematics.angle_of, half_angle) exact to double precision; large angles take libm, and a tilt
near the vertical (cos(pitch) below STEP_MIN_COS) the rebuild. Roll and pitch are still read off
q every sample (quat_roll_pitch): advanced by their own increments they would be a second
attitude that only rounding parts from q, and in single precision (a microcontroller's float
build) an increment below half an ulp of the angle is lost each time, and over a long run
(`make embedded`'s 10^6 samples) the losses add up where reading off q does not."""

from __future__ import annotations

from math import cos, sin, sqrt
from typing import Final

from ..kinematics import angle_of, quat_turn_roll_pitch

STEP_MIN_COS: Final = 0.1
"""The smallest cos(pitch) at which q is turned by a correction (quat_turn_roll_pitch divides by
it): nearer the vertical q is rebuilt from the corrected roll and pitch (at cos(pitch) = 0 roll is
not defined; the kf's face switch keeps cos(pitch) above 0.5 in its frame)."""


def quat_from_roll_pitch(roll: float, pitch: float) -> tuple[float, float, float, float]:
    """The attitude quaternion (w, x, y, z) of roll and pitch with yaw 0 (the module docstring):
    kinematics.quat_from_roll_pitch_yaw(roll, pitch, 0.0), written without the yaw's terms (the
    same doubles, two sine-cosine pairs instead of three). The yaw of the filters' quaternion is
    free: a turn about world z changes only the first two rows of the rotation matrix, and roll
    and pitch are read from the third, so rebuilding q with yaw 0 leaves every later roll and
    pitch as it was."""
    cr, sr = cos(0.5 * roll), sin(0.5 * roll)
    cp, sp = cos(0.5 * pitch), sin(0.5 * pitch)
    return cr * cp, sr * cp, cr * sp, -(sr * sp)


def tilt_innovation(ax: float, ay: float, az: float, up: tuple[float, float, float, float]
                    ) -> tuple[float, float]:
    """The accelerometer's roll and pitch (kinematics.accel_roll_pitch: atan2(ay, az) and
    atan2(-ax, sqrt(ay^2 + az^2))) less those of the attitude whose up_terms are up: each the
    angle from the attitude's direction to the accelerometer's, in [-pi, pi]."""
    h = sqrt(ay * ay + az * az)
    return (angle_of(ay * up[1] - az * up[0], az * up[1] + ay * up[0]),
            angle_of(-ax * up[3] - h * up[2], h * up[3] - ax * up[2]))


def corrected_quat(q: tuple[float, float, float, float], up: tuple[float, float, float, float],
                   roll: float, pitch: float, dr: float, dp: float
                   ) -> tuple[float, float, float, float]:
    """The attitude q (up: its up_terms) after a correction by dr in roll and dp in pitch to
    roll and pitch: q turned by the correction (kinematics.quat_turn_roll_pitch), near the
    vertical rebuilt from roll and pitch (quat_from_roll_pitch)."""
    if up[3] > STEP_MIN_COS:
        return quat_turn_roll_pitch(q, up, dr, dp)
    return quat_from_roll_pitch(roll, pitch)
