"""fusion_core.kinematics and the truth of fusion_core.synthetic against the frame conventions."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fusion_core import G, synthetic
from fusion_core.kinematics import (
    _SERIES_A2,
    accel_roll_pitch,
    euler_rates,
    quat_from_roll_pitch_yaw,
    quat_gravity_body,
    quat_roll_pitch,
    rotvec_terms,
)

roll = st.floats(-math.pi + 1e-9, math.pi)
pitch = st.floats(-math.pi / 2 + 1e-3, math.pi / 2 - 1e-3)
yaw = st.floats(-math.pi, math.pi)


def resting_acc(phi: float, theta: float, scale: float = G) -> tuple[float, float, float]:
    """INTERFACE.md: acc = g (-sin(theta), sin(phi) cos(theta), cos(phi) cos(theta)) at rest."""
    return (
        -scale * math.sin(theta),
        scale * math.sin(phi) * math.cos(theta),
        scale * math.cos(phi) * math.cos(theta),
    )


def angle_gap(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2.0 * math.pi))


@given(phi=roll, theta=pitch, scale=st.floats(0.1 * G, 16 * G))
def test_accel_roll_pitch_inverts_the_resting_accelerometer_formula(
    phi: float, theta: float, scale: float
) -> None:
    est_phi, est_theta = accel_roll_pitch(*resting_acc(phi, theta, scale))
    assert angle_gap(est_phi, phi) < 1e-12
    assert abs(est_theta - theta) < 1e-12


@given(phi=roll, theta=pitch, psi=yaw)
def test_quaternion_roll_pitch_round_trip(phi: float, theta: float, psi: float) -> None:
    """|pitch| <= 90 deg - 1 mrad: asin loses digits as cos(pitch) -> 0, hence 1e-9 rad."""
    est_phi, est_theta = quat_roll_pitch(*quat_from_roll_pitch_yaw(phi, theta, psi))
    assert angle_gap(est_phi, phi) < 1e-9
    assert abs(est_theta - theta) < 1e-9


@given(phi=roll, theta=pitch, psi=yaw)
def test_quaternion_gravity_direction_is_the_resting_accelerometer_over_g(
    phi: float, theta: float, psi: float
) -> None:
    v = quat_gravity_body(*quat_from_roll_pitch_yaw(phi, theta, psi))
    assert v == pytest.approx(resting_acc(phi, theta, 1.0), abs=1e-12)


def test_synthetic_body_rates_give_the_analytic_euler_angle_rates() -> None:
    """euler_rates(phi, theta, omega) of the recorded body rates equals d(phi)/dt and
    d(theta)/dt of the trajectory's signals, to 1e-12 rad/s (demo_motion: roll, pitch, yaw and
    translation all moving)."""
    traj = synthetic.demo_motion()
    t = np.arange(0.0, 20.0, 0.01)
    truth = traj.truth(t)
    _, dphi, _ = traj.roll(t)
    _, dtheta, _ = traj.pitch(t)
    rates = np.array(
        [
            euler_rates(a, b, *w)
            for a, b, w in zip(truth["roll"], truth["pitch"], truth["omega"], strict=True)
        ]
    )
    assert np.abs(rates[:, 0] - dphi).max() < 1e-12
    assert np.abs(rates[:, 1] - dtheta).max() < 1e-12


def rotating_in_place() -> dict[str, np.ndarray]:
    """Large roll, pitch and yaw motion, no translation, 20 s at 100 Hz."""
    traj = synthetic.Trajectory(
        roll=synthetic.sine(1.2, 0.4),
        pitch=synthetic.sine(0.8, 0.3, 0.5),
        yaw=synthetic.sine(2.0, 0.1),
    )
    return traj.truth(np.arange(0.0, 20.0, 0.01))


def test_specific_force_norm_is_g_without_linear_acceleration() -> None:
    f = rotating_in_place()["f"]
    assert np.abs(np.linalg.norm(f, axis=1) / G - 1.0).max() < 1e-12


def test_specific_force_without_linear_acceleration_is_the_resting_formula() -> None:
    truth = rotating_in_place()
    expected = np.array(
        [resting_acc(a, b) for a, b in zip(truth["roll"], truth["pitch"], strict=True)]
    )
    assert np.abs(truth["f"] - expected).max() < 1e-12 * G


def exact_rotvec_terms(a2: float) -> list[float]:
    """cos(a/2), sin(a/2)/a, sin(a)/a, (1 - cos a)/a^2 of the squared angle a2, correctly
    rounded for angles up to 0.5 rad: their power series in exact rational arithmetic, summed
    far past double precision."""
    x = Fraction(a2)
    denominators = (
        lambda k: 4**k * math.factorial(2 * k), lambda k: 2 * 4**k * math.factorial(2 * k + 1),
        lambda k: math.factorial(2 * k + 1), lambda k: math.factorial(2 * k + 2),
    )
    return [float(sum(Fraction((-1) ** k, d(k)) * x**k for k in range(24))) for d in denominators]


@given(log_angle=st.floats(-12.0, -0.3), direction=st.tuples(*[st.floats(-1.0, 1.0)] * 3))
def test_rotvec_terms_series_are_as_exact_as_the_trigonometric_form(
    log_angle: float, direction: tuple[float, float, float]
) -> None:
    """Below the bound the series replace the trigonometry (the sigma-point filter's hot path):
    within an ulp of the exact value there, where the sine-cosine form above the bound, with
    its rounded square root and three more roundings, keeps within a few (4 seen; 8 allowed)."""
    n = math.sqrt(sum(c * c for c in direction))
    if n < 1e-3:
        return
    v = [c / n * 10.0**log_angle for c in direction]
    a2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    ulps = 1 if a2 < _SERIES_A2 else 8
    for value, exact in zip(rotvec_terms(*v), exact_rotvec_terms(a2), strict=True):
        assert abs(value - exact) <= ulps * math.ulp(exact), (a2, value, exact)
