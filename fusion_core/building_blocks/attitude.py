"""Quaternion propagation of the Euler-angle filters (cf, kf). The papers integrate the Euler
rates (Duong Quoc eq. 2), whose tan(pitch) term is singular at pitch +-90 deg: a sensor that
turns through the vertical (every rotation trial of BROAD does) loses the attitude there, and the
innovation of roll, which the accelerometer cannot observe near pitch +-90 deg, cannot bring it
back. The recommended cf and kf keep an attitude quaternion q (yaw free, unobservable), turn it
by the bias-corrected rotation vector of each interval (the quaternion filters' rule,
kinematics.rotation_increment), take roll and pitch from it, apply their paper's correction to
roll and pitch, and rebuild q from the corrected roll and pitch with yaw 0 (quat_from_roll_pitch:
the free yaw does not change roll or pitch). The correction law, its gains and its covariance are
the paper's."""

from __future__ import annotations

from math import cos, sin


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
