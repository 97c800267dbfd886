"""The adaptive noise shared by cf, mgcf, kf and ukf (building_blocks.ADAPTIVE_NOISE_PARAMS): the
correction time of the complementary filters, the sweeps it is for, and what the UKF needs
besides (no unit-norm pseudo-measurement)."""

from __future__ import annotations

import math

import pytest

from fusion_core.building_blocks import CONSTANT_NOISE, correction_time
from fusion_core.registry import ATTITUDE_FILTERS
from testbenches.contract import accuracy_limits, compute_metrics
from testbenches.montecarlo.plan import Run
from testbenches.montecarlo.simulate import simulate
from testbenches.options import load_sensor


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


@pytest.mark.parametrize("key", ATTITUDE_FILTERS)
@pytest.mark.parametrize("scenario", ["roll_sweep", "pitch_sweep", "roll_pitch"])
def test_the_sweeps_pass_on_the_realistic_sensor(key: str, scenario: str) -> None:
    """Pure rotation with the realistic gyro (1 % scale, 0.67 % cross-axis, 0.16 deg/s of bias
    left): within the contract's 0.25 deg with the defaults, which measure the raw sample and
    correct faster while the sensor turns (the contract's seed 0)."""
    limit = accuracy_limits(key, scenario)
    roll, pitch = rmse(key, scenario, {})
    assert roll <= limit[0] and pitch <= limit[1], (roll, pitch)


@pytest.mark.parametrize("key", ATTITUDE_FILTERS)
def test_without_the_adaptive_noise_the_roll_sweep_fails(key: str) -> None:
    """The same filter with constant noise, as the papers have it, fails roll_sweep."""
    roll, pitch = rmse(key, "roll_sweep", CONSTANT_NOISE)
    assert max(roll, pitch) > 0.25, (roll, pitch)


@pytest.mark.parametrize("scenario", ["vibration", "high_dynamics"])
def test_the_ukf_passes_the_disturbed_scenarios_with_the_defaults(scenario: str) -> None:
    """vibration starts from a sample taken in 0.3 g of vibration, high_dynamics accelerates at
    0.73 g for seconds: the adaptive noise raises R, and X still converges (contract seed 0)."""
    limit = accuracy_limits("ukf", scenario)
    roll, pitch = rmse("ukf", scenario, {})
    assert roll <= limit[0] and pitch <= limit[1], (roll, pitch)


def test_the_unit_norm_row_shrinks_the_covariance_of_x() -> None:
    """Why the recommended UKF has no |X|^2 = 1 row (the paper's): the sigma points' spread off
    the unit sphere, read as information by that row, takes variance out of P_XX. From the
    recommended filter's state 3.5 s into vibration (X still off from its vibrating first
    sample), the same prediction updated with the same measured vector, with the row (the
    paper's norm_noise 0.01) and without: the variance of X across the vertical, P_00 + P_11,
    falls by more with the row, though the row measures nothing about X."""
    import numpy as np

    from fusion_core.papers.ukf import measurement_update, predicted_covariance, sigma_predict
    from fusion_core.ukf import UnscentedKalmanFilter
    from testbenches.montecarlo.simulate import scenario_samples

    _, _, s = scenario_samples("vibration", 0, load_sensor("realistic"))
    n = 351  # 3.5 s at 100 Hz
    f = UnscentedKalmanFilter()
    f.run(s["acc"][:n], s["gyro"][:n], s["dt"][:n])
    x, P, dt = list(f.x), f._P, float(s["dt"][n])
    acc = tuple(f.meas.f)
    traces = {}
    for r_norm in (None, 0.01**2):
        pred = sigma_predict(x, P, (0.0,) * 6, dt, f._gamma, f._w, f._w_mu, r_norm is not None)
        h = np.asarray(pred.X) / np.linalg.norm(pred.X)
        Pp = predicted_covariance(pred, P, tuple(h), f._q_gyro * dt, f._q_bias * dt)
        *_, Pn = measurement_update(pred, tuple(x[3:]), Pp, acc, f._r_acc, f._w, f._w_mu,
                                    r_norm, True)
        traces[r_norm] = Pn[0] + Pn[2]
    # one update takes 0.7 % of it (rounding would be 1e-16); over 3.5 s of updates 7 %
    assert traces[0.01**2] < (1.0 - 1e-3) * traces[None], traces


def test_the_slow_band_leaves_out_what_a_gyro_s_rate_error_turns_the_vectors_apart_by() -> None:
    """A sensor turning at 1 rad/s about x with no linear acceleration, its gyro reading
    sqrt(3) x 0.5 % too much (a scale and two cross-axis errors of gyro_scale_std 0.005 each):
    the short and the full-length low-pass, turned by that gyro, part by g sigma |w| times
    their delays' difference. Counted as disturbance, that raises the measurement noise
    fivefold; left out, it stays at one sample's. A translation (no rotation) counts in full
    either way."""
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import measure_constants, measure_start, measure_step
    from fusion_core.types import G

    dt, r, gyro_scale_std = 0.01, 0.005**2, 0.005
    error = 1.0 + math.sqrt(3.0) * gyro_scale_std

    def noise(discount: float, rate: float, sway: float) -> float:
        c = measure_constants(1.5, 3.0, 0.15, r, discount)
        m = measure_start((0.0, 0.0, G), c)
        r_k = r
        for k in range(1, 1000):  # 10 s: the vectors fill and the statistic settles
            t = k * dt
            a = (sway * math.sin(2.0 * math.pi * 0.3 * t),  # a 0.3 Hz sway along x
                 G * math.sin(rate * t), G * math.cos(rate * t))  # gravity, turning about x
            phi = (rate * error * dt, 0.0, 0.0)
            m, r_k, _ = measure_step(m, a, phi, rotvec_terms(*phi), dt, c)
        return r_k

    assert noise(0.0, 1.0, 0.0) > 5.0 * r  # the turn taken for disturbance
    assert noise(gyro_scale_std, 1.0, 0.0) < 1.1 * r  # left out
    assert noise(gyro_scale_std, 0.0, 2.0) == noise(0.0, 0.0, 2.0) > 100.0 * r  # in full


def test_a_swing_that_turns_back_is_discounted_by_what_it_turned_not_by_its_rate() -> None:
    """A hand turning the sensor +-60 deg at 0.5 Hz about x: the swing turns back within the
    vector's length, so the two low-passes part by the difference of their lags (the angle
    turned since their samples, measured_vector item 2), far less than the peak rate times
    their delays' difference. With a gyro 1 % off (sigma sqrt(3) x 1 %) that parting is left
    out and the noise stays at one sample's; with an exact gyro and a 0.15 Hz sway of 1 m/s^2
    along x (no rotation moves it) the sway still counts in full, where a discount by the rate
    takes a third of it away."""
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import measure_constants, measure_start, measure_step
    from fusion_core.types import G

    dt, r, gyro_scale_std = 0.01, 0.005**2, 0.01
    amp, freq = math.radians(60.0), 0.5

    def noise(discount: float, error: float, sway: float) -> float:
        c = measure_constants(1.5, 1.0, 0.15, r, discount)
        m = measure_start((0.0, 0.0, G), c)
        settled = []
        for k in range(1, 3000):
            t = k * dt
            angle = amp * math.sin(2.0 * math.pi * freq * t)
            rate = amp * 2.0 * math.pi * freq * math.cos(2.0 * math.pi * freq * (t - 0.5 * dt))
            a = (sway * math.sin(2.0 * math.pi * 0.15 * t), G * math.sin(angle),
                 G * math.cos(angle))
            phi = (rate * error * dt, 0.0, 0.0)
            m, r_k, _ = measure_step(m, a, phi, rotvec_terms(*phi), dt, c)
            if t > 10.0:  # the vectors full and the statistic settled
                settled.append(r_k)
        return sum(settled) / len(settled)

    off = 1.0 + math.sqrt(3.0) * gyro_scale_std
    assert noise(0.0, off, 0.0) > 5.0 * r  # the turn taken for disturbance
    assert noise(gyro_scale_std, off, 0.0) < 1.1 * r  # left out
    assert noise(gyro_scale_std, 1.0, 1.0) > 0.95 * noise(0.0, 1.0, 1.0) > 100.0 * r


def test_the_vector_grows_longer_for_slow_linear_acceleration_but_not_for_a_turn() -> None:
    """measured_vector.stretched: a 0.15 Hz sway of 1 m/s^2 (periods longer than the 1.5 s
    vector) with no rotation stretches the vector to its longest, and the vector's tilt error
    halves (1.4 against 2.7 deg RMS); a turn at 1 rad/s with the gyro's scale error and no
    linear acceleration leaves it at its length, and so does the sway while the sensor turns at
    6 rad/s, where the longer vector would carry more turn than the sway it averages away."""
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import (
        measure_constants,
        measure_start,
        measure_step,
        stretched,
        two_stage_noise,
    )
    from fusion_core.types import G

    dt, r, gyro_scale_std = 0.01, 0.005**2, 0.005
    error = 1.0 + math.sqrt(3.0) * gyro_scale_std

    def run(stretch: float, rate: float, sway: float) -> tuple[float, float]:
        """The stretch taken at the end and the vector's tilt error RMS [deg] after the fill."""
        c = measure_constants(1.5, 1.0, 0.15, r, gyro_scale_std, stretch)
        m = measure_start((0.0, 0.0, G), c)
        lag = 2.0 * (c.stage - c.band)
        err2 = []
        for k in range(1, 6000):  # 60 s
            t = k * dt
            g = (0.0, G * math.sin(rate * t), G * math.cos(rate * t))  # gravity, turning about x
            a = (g[0] + sway * math.sin(2.0 * math.pi * 0.15 * t), g[1], g[2])
            phi = (rate * error * dt, 0.0, 0.0)
            m, _, _ = measure_step(m, a, phi, rotvec_terms(*phi), dt, c, bias_measured=True)
            if t > 10.0:
                f = m.f
                cos = (f[0] * g[0] + f[1] * g[1] + f[2] * g[2]) / (math.hypot(*f) * G)
                err2.append(math.degrees(math.acos(min(1.0, cos))) ** 2)
        excess = m.slow - c.noise * two_stage_noise(dt / (c.band + dt))
        return stretched(c, excess, m.rate2, lag, 2.0 * c.stage), math.sqrt(sum(err2) / len(err2))

    longest, err_long = run(2.0, 0.0, 1.0)
    assert longest == 2.0
    assert err_long < 0.6 * run(1.0, 0.0, 1.0)[1]
    assert run(2.0, 1.0, 0.0)[0] == 1.0  # a turn alone
    assert run(2.0, 6.0, 1.0)[0] == 1.0  # the sway in a fast turn


def test_the_vector_keeps_its_length_until_a_rest_has_measured_the_bias() -> None:
    """A longer vector turns with the estimated bias for longer and hides a bias error from the
    correction (measured_vector, item 4): without a measured bias the sway of the test above
    leaves the vector exactly as long as acc_lowpass."""
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import measure_constants, measure_start, measure_step
    from fusion_core.types import G

    dt, zero = 0.01, (0.0, 0.0, 0.0)
    terms = rotvec_terms(*zero)
    runs = []
    for stretch, measured in ((2.0, False), (1.0, False), (2.0, True)):
        c = measure_constants(1.5, 1.0, 0.15, 0.005**2, 0.005, stretch)
        m = measure_start((0.0, 0.0, G), c)
        for k in range(1, 3000):
            a = (math.sin(2.0 * math.pi * 0.15 * k * dt), 0.0, G)
            m, _, _ = measure_step(m, a, zero, terms, dt, c, bias_measured=measured)
        runs.append(m.f)
    assert runs[0] == runs[1] != runs[2]


def test_a_fast_leak_through_the_slow_band_counts_less_a_slow_sway_still_counts() -> None:
    """measured_vector item 5: a running torso's bounce (1.1 g at 2.8 Hz along gravity), which
    the vector removes, leaks through the slow band; with the leak taken off (slow_band_leak 1)
    the measurement noise it adds falls by more than 40 % (the statistic's peak follower still
    catches the leak's ripple: a tone along one axis swings between none and twice its mean),
    while a 0.3 Hz sway of 2 m/s^2, which reaches the vector, keeps more than 90 % of it."""
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import measure_constants, measure_start, measure_step
    from fusion_core.types import G

    dt, r, zero = 0.01, 0.005**2, (0.0, 0.0, 0.0)
    terms = rotvec_terms(*zero)

    def added(leak: float, amp: float, freq: float) -> float:
        """The mean measurement noise over the last 10 s of 30, less one sample's [rad^2]."""
        c = measure_constants(1.5, 1.0, 0.15, r, 0.005, 1.0, leak)
        m = measure_start((0.0, 0.0, G), c)
        rs = []
        for k in range(1, 3000):
            a = (0.0, 0.0, G + amp * math.sin(2.0 * math.pi * freq * k * dt))
            m, r_k, _ = measure_step(m, a, zero, terms, dt, c)
            if k * dt > 20.0:
                rs.append(r_k - r)
        return sum(rs) / len(rs)

    assert added(1.0, 1.1 * G, 2.8) < 0.6 * added(0.0, 1.1 * G, 2.8)
    assert added(1.0, 2.0, 0.3) > 0.9 * added(0.0, 2.0, 0.3)


def test_absurd_samples_count_no_more_than_a_held_acceleration_a_real_move_in_full() -> None:
    """measured_vector item 6: after a second of absurd samples (uniform within an MPU-6050's
    16 g range, as the battery's glitching part has them) the measurement noise is at most a
    held acceleration's, tan^2 30 deg = 1/3 rad^2 over one sample's (held_acceleration
    g tan 30 deg), where uncapped it reaches more than five times that, and falls under
    0.1 rad^2 more than half a second sooner; a real slow move (a 0.3 Hz sway of 3 m/s^2, well
    under the cap) gives the same noise to the bit."""
    import numpy as np

    from fusion_core.building_blocks import GROSS_INNOVATION
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import (
        HELD_PARAM,
        measure_constants,
        measure_start,
        measure_step,
    )
    from fusion_core.types import G

    assert HELD_PARAM.default == G * math.tan(GROSS_INNOVATION)
    dt, r, zero = 0.01, 0.005**2, (0.0, 0.0, 0.0)
    terms = rotvec_terms(*zero)
    absurd = np.random.default_rng(0).uniform(-0.9, 0.9, (100, 3)) * 16.0 * G

    def noise(held: float, sample) -> np.ndarray:
        c = measure_constants(1.5, 1.0, 0.15, r, 0.005, 1.0, 1.0, held)
        m = measure_start((0.0, 0.0, G), c)
        rs = []
        for k in range(1, 3000):
            m, r_k, _ = measure_step(m, sample(k), zero, terms, dt, c)
            rs.append(r_k)
        return np.array(rs)

    def glitch(k: int) -> tuple[float, float, float]:
        return tuple(absurd[k - 1000]) if 1000 <= k < 1100 else (0.0, 0.0, G)

    def under(rs: np.ndarray, level: float) -> float:
        """Seconds after the glitch until the noise stays under level."""
        return (np.nonzero(rs > level)[0].max() + 1 - 1100) * dt

    capped, full = noise(HELD_PARAM.default, glitch), noise(0.0, glitch)
    held = math.tan(GROSS_INNOVATION) ** 2
    assert capped.max() <= r + held * (1.0 + 1e-12) < full.max() / 5.0
    assert under(capped, 0.1) < under(full, 0.1) - 0.5

    def sway(k: int) -> tuple[float, float, float]:
        return (3.0 * math.sin(2.0 * math.pi * 0.3 * k * dt), 0.0, G)

    assert list(noise(HELD_PARAM.default, sway)) == list(noise(0.0, sway))
