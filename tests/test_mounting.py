"""The mounting rotation (interface v2): a sensor resting in any of the 24 right-angle
orientations, with the matching mount_roll/pitch/yaw, gives every estimator the same estimate
as the sensor mounted along the body axes."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from helpers import KEYS, make, noisy_two_axis_recording

from fusion_core.base import mounting_matrix


def right_angle_rotations() -> list[np.ndarray]:
    """The 24 proper rotations that permute the axes with signs (det +1)."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            m = np.zeros((3, 3))
            for row, (col, sign) in enumerate(zip(perm, signs, strict=True)):
                m[row, col] = sign
            if np.linalg.det(m) > 0:
                out.append(m)
    return out


def zyx_angles(m: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of R = Rz(yaw) Ry(pitch) Rx(roll); yaw 0 at pitch +-90 deg."""
    pitch = math.asin(max(-1.0, min(1.0, -m[2, 0])))
    if abs(m[2, 0]) > 1.0 - 1e-12:
        return math.atan2(-m[1, 2], m[1, 1]), pitch, 0.0
    return math.atan2(m[2, 1], m[2, 2]), pitch, math.atan2(m[1, 0], m[0, 0])


def test_there_are_24_and_the_angles_give_each_matrix_back_exactly() -> None:
    rotations = right_angle_rotations()
    assert len(rotations) == 24
    for m in rotations:
        assert np.array_equal(np.array(mounting_matrix(*zyx_angles(m))).reshape(3, 3), m)


@pytest.mark.parametrize("key", KEYS)
def test_every_right_angle_mounting_gives_the_body_mounted_estimate(key: str) -> None:
    rec = noisy_two_axis_recording(10.0)
    acc, gyro, dt = rec["acc_meas"], rec["gyro_meas"], rec["dt"]
    body = make(key).run(acc, gyro, dt)
    for m in right_angle_rotations():
        # the sensor's axes are m^T of the body's: it reads m^T v for a body vector v
        roll, pitch, yaw = zyx_angles(m)
        out = make(key, mount_roll=roll, mount_pitch=pitch, mount_yaw=yaw).run(
            acc @ m, gyro @ m, dt)
        for name in ("roll", "pitch", "bias"):
            assert np.array_equal(out[name], body[name]), (name, m.tolist())


def test_mounting_is_the_identity_by_default_and_refused_out_of_range() -> None:
    assert make("kf").params["mount_roll"] == 0.0
    with pytest.raises(ValueError, match="mount_pitch"):
        make("kf", mount_pitch=4.0)


def inclination_rmse_deg(out: dict[str, np.ndarray], up: np.ndarray) -> float:
    """RMSE [deg] of the angle between the estimate's up direction and the true one (both in
    the sensor frame), after the first second."""
    roll, pitch = out["roll"], out["pitch"]
    cp = np.cos(pitch)
    est = np.stack([-np.sin(pitch), np.sin(roll) * cp, np.cos(roll) * cp], axis=1)
    err = np.arctan2(np.linalg.norm(np.cross(est, up), axis=1), np.einsum("ij,ij->i", est, up))
    return float(np.degrees(np.sqrt(np.mean(err[RATE_HZ:] ** 2))))


RATE_HZ = 285


@pytest.mark.parametrize("key", KEYS)
def test_a_sensor_resting_on_any_face_without_a_mounting_is_as_accurate(key: str) -> None:
    """No mounting set: the sensor itself rests x-up, upside down, ..., in each of the 24
    right-angle orientations (moving about that rest as the recording does, with a gyro bias on
    every axis). The inclination error is the level sensor's within 10 %: the Kalman filters'
    roll and pitch filters run on the face nearest to up (tilt_axes), and a bias on an axis that
    lies horizontal is learned whichever axis it is."""
    rec = noisy_two_axis_recording(30.0)
    acc, gyro, dt = rec["acc_meas"], rec["gyro_meas"], rec["dt"]
    roll, pitch = rec["roll"], rec["pitch"]
    cp = np.cos(pitch)
    up = np.stack([-np.sin(pitch), np.sin(roll) * cp, np.cos(roll) * cp], axis=1)
    level = inclination_rmse_deg(make(key).run(acc, gyro, dt), up)
    for m in right_angle_rotations():
        turned = inclination_rmse_deg(make(key).run(acc @ m, gyro @ m, dt), up @ m)
        assert turned <= 1.1 * level + 0.005, (key, m.tolist(), turned, level)
