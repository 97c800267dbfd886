"""measured_vector item 7: a burst of samples of no motion (the slow band parted from the
reference by more than burst_acceleration, with fast power as white as independent samples')
reaches neither the measured vector nor, through it, the attitude, and the vector fills again
from the samples after it; nothing a body does is taken for one (a fast translation parting the
slow band as far, the contract's scenarios, the battery's motions on parts that do not glitch,
BROAD's trials: the same outputs to the bit with the mechanism off)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from fusion_core.measured_vector import BURST_PARAM
from fusion_core.registry import ATTITUDE_FILTERS, create
from fusion_core.scenarios import ESTIMATION_SCENARIOS
from fusion_core.sensor import sensor_preset
from fusion_core.types import G
from testbenches.battery import GLITCH_AFTER_S, MOTIONS, SENSOR_CLASSES, filter_params, part_samples
from testbenches.broad.metric import gravity_from_roll_pitch
from testbenches.samples import scenario_samples

OFF = {"burst_acceleration": 0.0}
BROAD = Path(os.environ.get("BROAD_DIR",
                            Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"))


def _same(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> bool:
    return all(np.array_equal(a[k], b[k]) for k in ("roll", "pitch", "bias"))


def _glitch_error(key: str, params: dict[str, float], backend: str = "native"
                  ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Times after the glitch's start [s], the inclination error [deg] and the outputs of one
    filter on the battery's glitching part (hand-held, slow; seed 0)."""
    t, truth, sample = part_samples("handheld_slow", "mpu6050_glitch", 0)
    given = {**filter_params(SENSOR_CLASSES["mpu6050_glitch"], False)[key], **params}
    out = create(key, given).run(sample["acc"], sample["gyro"], sample["dt"], backend=backend)
    up = gravity_from_roll_pitch(out["roll"], out["pitch"])
    true_up = gravity_from_roll_pitch(truth["roll"], truth["pitch"])
    cos = np.clip(np.sum(up * true_up, axis=1), -1.0, 1.0)
    return t - (MOTIONS["handheld_slow"].rest + GLITCH_AFTER_S), np.degrees(np.arccos(cos)), out


def test_burst_acceleration_is_g() -> None:
    assert BURST_PARAM.default == G


def _measured(sample, seconds: float = 20.0) -> tuple[list[float], list[float], list[bool]]:
    """The slow band's distance from the reference [m/s^2], `fresh` [s] and whether a burst was
    taken, sample by sample, of the measured vector alone (100 Hz, no rotation)."""
    from fusion_core.kinematics import rotvec_terms
    from fusion_core.measured_vector import measure_constants, measure_start, measure_step

    dt, zero = 0.01, (0.0, 0.0, 0.0)
    c = measure_constants(1.5, 1.0, 0.15, 0.005**2, 0.005, 1.0, 1.0, 0.0, G)
    m = measure_start(sample(0), c)
    apart, fresh, burst = [], [], []
    for k in range(1, round(seconds / dt)):
        before = m.f
        m, _, _ = measure_step(m, sample(k), zero, rotvec_terms(*zero), dt, c)
        s, ref = np.array(m.s), np.array(m.ref)
        apart.append(float(np.linalg.norm(s - ref)))
        fresh.append(m.fresh)
        burst.append(m.fresh == 0.0 and m.f == before)
    return apart, fresh, burst


def test_a_fast_translation_parting_the_slow_band_as_far_is_no_burst() -> None:
    """A hand's fast translation (1.5 Hz, 4 g of amplitude along x) parts the slow band from the
    reference by more than g, but its fast power is smooth: no burst. A second of independent
    samples within 16 g parts them as far, and is one: the vector holds none of it."""
    rng = np.random.default_rng(0)
    absurd = rng.uniform(-0.9, 0.9, (100, 3)) * 16.0 * G

    def hand(k: int) -> tuple[float, float, float]:
        return (4.0 * G * math.sin(2.0 * math.pi * 1.5 * k * 0.01), 0.0, G)

    def glitch(k: int) -> tuple[float, float, float]:
        return tuple(absurd[k - 1000]) if 1000 <= k < 1100 else (0.0, 0.0, G)

    apart, fresh, burst = _measured(hand)
    assert max(apart[300:]) > G and min(fresh) > 0.0 and not any(burst)
    apart, fresh, burst = _measured(glitch)
    assert max(apart) > G and sum(burst) > 50 and fresh[-1] == 1.5


@pytest.mark.parametrize("key", ATTITUDE_FILTERS)
def test_after_a_second_of_absurd_samples_the_attitude_is_back_within_two_seconds(key) -> None:
    """One second of samples anywhere in the MPU-6050's ranges throws every filter tens of
    degrees off. With the burst taken for one, one to four seconds after it ends the attitude
    is within 3 deg (RMS) of the truth; left in the vector, it is still more than 10 deg off,
    following the burst's samples back to gravity over the vector's length. The Python class and
    its C twin agree to the bit."""
    after, error, out = _glitch_error(key, {})
    window = (after >= 2.0) & (after < 5.0)
    assert np.sqrt(np.mean(error[window] ** 2)) < 3.0
    _, error_off, _ = _glitch_error(key, OFF)
    assert np.sqrt(np.mean(error_off[window] ** 2)) > 10.0
    assert _same(out, _glitch_error(key, {}, backend="python")[2])


@pytest.mark.parametrize("scenario", ESTIMATION_SCENARIOS)
def test_no_contract_scenario_holds_a_burst(scenario) -> None:
    """The contract's scenarios (shaking that starts at 2.6 g, high_dynamics' seconds of 0.7 g)
    on two parts: every attitude filter's outputs with and without the mechanism are the
    same."""
    sensor = sensor_preset("realistic")
    for seed in (0, 1):
        _, _, out = scenario_samples(scenario, seed, {**sensor, "seed": seed})
        for key in ATTITUDE_FILTERS:
            a = create(key).run(out["acc"], out["gyro"], out["dt"])
            assert _same(a, create(key, OFF).run(out["acc"], out["gyro"], out["dt"])), key


@pytest.mark.parametrize("sensor", [s for s in SENSOR_CLASSES if s != "mpu6050_glitch"])
def test_no_battery_motion_holds_a_burst(sensor) -> None:
    """Every motion of the battery (running's 1.1 g bounce, the pendulum, clipping, a
    vehicle's held accelerations) on one part of each sensor class that does not glitch."""
    for motion in MOTIONS:
        _, _, sample = part_samples(motion, sensor, 0)
        params = filter_params(SENSOR_CLASSES[sensor], False)
        for key in ATTITUDE_FILTERS:
            a = create(key, params[key]).run(sample["acc"], sample["gyro"], sample["dt"])
            b = create(key, {**params[key], **OFF}).run(sample["acc"], sample["gyro"],
                                                        sample["dt"])
            assert _same(a, b), (motion, key)


@pytest.mark.heavy
@pytest.mark.skipif(not BROAD.is_dir() or not any(BROAD.glob("*.hdf5")),
                    reason=f"no BROAD trials in {BROAD} (set BROAD_DIR)")
def test_no_broad_trial_holds_a_burst() -> None:
    """BROAD's trials, the disturbed ones too (rates to 800 deg/s, the specific force 20 m/s2
    off g): the same outputs with and without the mechanism."""
    from testbenches.broad.data import load_trial
    from testbenches.broad.run import with_sensor

    paths = sorted(p for p in BROAD.iterdir() if p.suffix.lower() in (".mat", ".hdf5"))
    for path in paths:
        trial = load_trial(path)
        for key in ATTITUDE_FILTERS:
            params = with_sensor({}, trial)
            a = create(key, params).run(trial.acc, trial.gyro, trial.dt)
            b = create(key, {**params, **OFF}).run(trial.acc, trial.gyro, trial.dt)
            assert _same(a, b), (path.name, key)
