"""Gyro-bias estimation: the final estimate after 60 s of motion, bias (0.5, -0.3, 0.2) deg/s.

Which motion makes which bias observable:
- The 2-state Kalman filter models no z bias; on wide tilts a z bias leaks into the roll and pitch
  rates through tan(pitch) (Euler kinematics) and its x/y bias states absorb it (measured: about
  0.25 deg/s of error with 60/45 deg tilts). Its test motion is two_axis_motion (tilts to 30 deg),
  where that leak stays below the noise.
- MGCF and UKF estimate all three biases. A z bias shows only through the part of it that is
  perpendicular to gravity, so their motion tilts widely (roll 60 deg, pitch 45 deg).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from helpers import RATE, make, paper, run_recording

from fusion_core import DEG, synthetic

TRUE_BIAS = (0.5 * DEG, -0.3 * DEG, 0.2 * DEG)  # rad/s
TOL = 0.05 * DEG  # rad/s
DURATION_S = 60.0
AXES = {"x": 0, "y": 1, "z": 2}

MGCF_TUNED = {"schedule": "fixed", "w0": 0.5}
"""MGCF with the paper's gains (w0 = 0.1 rad/s, zeta = 2) is a PI loop whose slow pole is at
-zeta w0 + w0 sqrt(zeta^2 - 1) = -0.027 1/s: a 37 s time constant, so after 60 s about 20 % of
the bias remains (measured: 0.12 deg/s on x). This test checks the bias estimator itself with
w0 = 0.5 rad/s (7.5 s time constant); test_mgcf_paper_gains_learn_the_bias_in_300_s checks the
paper's gains over a horizon their time constant allows."""


def wide_tilt_motion() -> synthetic.Trajectory:
    return synthetic.Trajectory(
        roll=synthetic.sine(60 * DEG, 0.1),
        pitch=synthetic.sine(45 * DEG, 0.07, 0.5),
        yaw=synthetic.sine(30 * DEG, 0.03),
    )


@functools.cache
def biased_recording(motion: str, duration: float = DURATION_S, noisy: bool = True) -> dict:
    """60 s at 100 Hz, MPU-6050 white noise (0.005 deg/s/sqrt(Hz), 400 ug/sqrt(Hz)) plus the
    constant gyro bias, seed 0."""
    trajectory = synthetic.two_axis_motion() if motion == "two_axis" else wide_tilt_motion()
    noise = synthetic.ImuNoise(gyro_bias=TRUE_BIAS)
    if not noisy:
        noise = synthetic.ImuNoise(gyro_density=0.0, acc_density=0.0, gyro_bias=TRUE_BIAS)
    return synthetic.record(trajectory, duration, RATE, noise=noise, seed=0)


CASES = {
    "kf": ("two_axis", {}),
    "ukf": ("wide", {}),
    "mgcf": ("wide", MGCF_TUNED),
}


@functools.cache
def final_bias(key: str) -> np.ndarray:
    """The estimator's bias estimate at the last sample [rad/s]."""
    motion, params = CASES[key]
    out = run_recording(make(key, **paper(key, **params)), biased_recording(motion))
    assert not out["rejected"].any()
    return out["bias"][-1]


@pytest.mark.parametrize(
    ("key", "axis"),
    [
        ("kf", "x"), ("kf", "y"),
        ("mgcf", "x"), ("mgcf", "y"), ("mgcf", "z"),
        ("ukf", "x"), ("ukf", "y"), ("ukf", "z"),
    ],
)
def test_final_bias_estimate_within_0p05_deg_per_s_after_60_s(key: str, axis: str) -> None:
    """No averaging: the estimate at the last sample, seed 0. (For kf the accelerometer noise
    alone gives the converged bias estimate a standard deviation of 0.029 deg/s at 100 Hz, from
    the steady-state gain of the papers' Q and R, so 0.05 deg/s is a 1.7-sigma bound for it.)"""
    i = AXES[axis]
    estimate = final_bias(key)[i]
    error = estimate - TRUE_BIAS[i]
    print(
        f"\n{key} bias_{axis}: estimate {estimate / DEG:+.4f} deg/s, "
        f"true {TRUE_BIAS[i] / DEG:+.4f}, error {error / DEG:+.4f} deg/s"
    )
    assert abs(error) < TOL


def test_ukf_estimates_every_bias_on_the_small_tilt_motion_too() -> None:
    """UKF defaults on two_axis_motion (tilts to 30 deg): x, y within 0.05 deg/s, z within 0.05."""
    out = run_recording(make("ukf", **paper("ukf")), biased_recording("two_axis"))
    error = (out["bias"][-1] - TRUE_BIAS) / DEG
    print(f"\nukf two_axis bias error {error} deg/s")
    assert np.all(np.abs(error) < 0.05)


def test_mgcf_paper_gains_learn_the_bias_in_300_s() -> None:
    """Default (simulation-table) gains, noise-free, wide tilts: after 300 s, eight of the 37 s
    time constants, the x and y biases are within 0.05 deg/s."""
    out = run_recording(make("mgcf", **paper("mgcf")), biased_recording("wide", 300.0, noisy=False))
    error = (out["bias"][-1] - TRUE_BIAS) / DEG
    print(f"\nmgcf paper gains, 300 s, bias error {error} deg/s")
    assert np.all(np.abs(error[:2]) < 0.05)


def test_kalman_z_bias_output_is_always_zero() -> None:
    """The 2-state filter cannot see a z bias (it does not change the tilt): it outputs 0."""
    out = run_recording(make("kf", **paper("kf")), biased_recording("two_axis"))
    assert np.all(out["bias"][:, 2] == 0.0)
