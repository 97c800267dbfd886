"""ComplementaryFilter: the steady-state error that a constant gyro bias leaves."""

from __future__ import annotations

import pytest
from helpers import make, paper

from fusion_core import DEG
from fusion_core.synthetic import ImuNoise, Trajectory, constant, record

BIAS = 1.0 * DEG  # rad/s
TILT = 20.0 * DEG  # rad


@pytest.mark.parametrize(
    ("axis", "trajectory", "gyro_bias"),
    [
        ("roll", Trajectory(roll=constant(TILT)), (BIAS, 0.0, 0.0)),
        ("pitch", Trajectory(pitch=constant(TILT)), (0.0, BIAS, 0.0)),
    ],
)
def test_static_tilt_with_gyro_bias_settles_at_bias_times_tau(
    axis: str, trajectory: Trajectory, gyro_bias: tuple[float, float, float]
) -> None:
    """angle = a (angle + (w + b) dt) + (1 - a) acc_angle, a = tau / (tau + dt), settles at
    e = a b dt / (1 - a) = b tau exactly: 0.75 deg for b = 1 deg/s and the default tau = 0.75 s.
    30 s is 40 tau, so the transient is gone (e^-40)."""
    cf = make("cf", **paper("cf"))
    noise = ImuNoise(gyro_density=0.0, acc_density=0.0, gyro_bias=gyro_bias)
    rec = record(trajectory, 30.0, 100.0, noise=noise)
    out = cf.run(rec["acc_meas"], rec["gyro_meas"], rec["dt"])
    error = out[axis][-1] - rec[axis][-1]
    ratio = error / (BIAS * cf.params["tau"])
    print(f"\nCF {axis}: steady-state error {error / DEG:.5f} deg, ratio to b*tau {ratio:.6f}")
    assert ratio == pytest.approx(1.0, abs=0.01)
