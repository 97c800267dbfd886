"""The adaptive noise shared by cf, mgcf, kf and ukf (building_blocks.ADAPTIVE_NOISE_PARAMS): the
correction time of the complementary filters, the sweeps it is for, and what the UKF needs
besides (no unit-norm pseudo-measurement)."""

from __future__ import annotations

import math

import pytest

from fusion_core.building_blocks import CONSTANT_NOISE, correction_time
from fusion_core.presets import PRESETS
from testbenches.campaign import load_sensor
from testbenches.contract import accuracy_limits, compute_metrics
from testbenches.montecarlo.plan import Run
from testbenches.montecarlo.simulate import simulate


def test_the_correction_time_is_the_kalman_balance_and_never_longer_than_tau() -> None:
    """tau = sqrt(r dt / q): with r grown by r_ratio and q by q_rotation w^2, the time constant
    scales by sqrt(r_ratio / q_ratio), up to the longest allowed (or tau, if that is longer)."""
    tau, r, dt = 1.0, 0.005**2, 0.01
    assert correction_time(tau, 1.0, 0.0, 0.0, r, dt, 3.0) == tau
    assert correction_time(tau, 4.0, 0.0, 0.0, r, dt, 3.0) == 2.0 * tau
    assert correction_time(tau, 50.0, 0.0, 0.0, r, dt, 3.0) == 3.0
    assert correction_time(tau, 50.0, 0.0, 0.0, r, dt, 0.5) == tau
    q_rotation, w2 = 0.005**2 * 0.5, 2.0**2
    q_ratio = 1.0 + q_rotation * w2 * tau * tau / (r * dt)
    assert correction_time(tau, 1.0, q_rotation, w2, r, dt, 3.0) == pytest.approx(
        tau / math.sqrt(q_ratio), rel=1e-12)


def rmse(key: str, scenario: str, params: dict) -> tuple[float, float]:
    m = compute_metrics(simulate(Run("t", key, scenario, 0, None, load_sensor("realistic"),
                                     params, {})))
    return m["rmse_roll_deg"], m["rmse_pitch_deg"]


@pytest.mark.parametrize("key", ["cf", "mgcf", "kf", "ukf"])
@pytest.mark.parametrize("scenario", ["roll_sweep", "pitch_sweep", "roll_pitch"])
def test_the_sweeps_pass_on_the_realistic_sensor(key: str, scenario: str) -> None:
    """Pure rotation with the realistic gyro (1 % scale, 0.67 % cross-axis, 0.16 deg/s of bias
    left): within the contract's 0.25 deg with the defaults, which measure the raw sample and
    correct faster while the sensor turns (the contract's seed 0)."""
    limit = accuracy_limits(key, scenario)
    roll, pitch = rmse(key, scenario, {})
    assert roll <= limit[0] and pitch <= limit[1], (roll, pitch)


@pytest.mark.parametrize("key", ["cf", "mgcf", "kf", "ukf"])
def test_without_the_adaptive_noise_the_roll_sweep_fails(key: str) -> None:
    """The same filter with constant noise, as the papers' presets have it, fails roll_sweep."""
    roll, pitch = rmse(key, "roll_sweep", CONSTANT_NOISE)
    assert max(roll, pitch) > 0.25, (roll, pitch)
    assert {k: PRESETS["paper"][key][k] for k in CONSTANT_NOISE} == CONSTANT_NOISE


@pytest.mark.parametrize("scenario", ["vibration", "high_dynamics"])
def test_the_ukf_passes_the_disturbed_scenarios_with_the_defaults(scenario: str) -> None:
    """vibration starts from a sample taken in 0.3 g of vibration, high_dynamics accelerates at
    0.73 g for seconds: the adaptive noise raises R, and X still converges (contract seed 0)."""
    limit = accuracy_limits("ukf", scenario)
    roll, pitch = rmse("ukf", scenario, {})
    assert roll <= limit[0] and pitch <= limit[1], (roll, pitch)


def test_the_unit_norm_pseudo_measurement_costs_the_ukf_on_vibration() -> None:
    """With the paper's |X|^2 = 1 row (norm_noise 0.01) the sigma points' spread off the unit
    sphere is read as information: P_XX shrinks, and X, set off by the first vibrating sample,
    converges more slowly (ukf's docstring): at least twice the pitch RMSE of the defaults."""
    _, pitch = rmse("ukf", "vibration", {})
    roll_norm, pitch_norm = rmse("ukf", "vibration", {"norm_noise": 0.01})
    assert pitch_norm > 2.0 * pitch, (roll_norm, pitch_norm, pitch)
    assert PRESETS["paper"]["ukf"]["norm_noise"] == 0.01


def test_the_unit_norm_row_shrinks_the_covariance_of_x() -> None:
    """The mechanism behind the test above: the sigma points' spread off the unit sphere, read as
    information by the |X|^2 = 1 row, takes variance out of P_XX. 3.5 s into vibration (X still
    off from its vibrating first sample) the variance of X across the vertical, P_00 + P_11, is
    0.93 of what the same filter without the row holds (the vibration itself no longer raises R:
    the second-order pre-filter removes it, measured_vector)."""
    from fusion_core.ukf import UnscentedKalmanFilter
    from testbenches.montecarlo.simulate import scenario_samples

    _, _, s = scenario_samples("vibration", 0, load_sensor("realistic"))
    n = 351  # 3.5 s at 100 Hz
    traces = {}
    for norm_noise in (0.0, 0.01):
        f = UnscentedKalmanFilter(norm_noise=norm_noise)
        f.run(s["acc"][:n], s["gyro"][:n], s["dt"][:n])
        P = f.P
        traces[norm_noise] = P[0][0] + P[1][1]
    assert traces[0.01] < 0.95 * traces[0.0], traces
