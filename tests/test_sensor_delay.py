"""sensor_delay: the outputs are the estimate turned ahead by the bias-corrected rate over the
sensor's delay, the filter's state is untouched, and a delay of 0 changes nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import KEYS, make, state_numbers

from fusion_core import G
from fusion_core.kinematics import roll_pitch_ahead

DELAY = 2.4e-3


def test_a_roll_rate_turns_roll_ahead_by_rate_times_delay() -> None:
    roll, pitch = roll_pitch_ahead(0.3, 0.0, 0.5, 0.0, 0.0, 0.01)
    assert roll == pytest.approx(0.3 + 0.005, abs=1e-15)
    assert pitch == pytest.approx(0.0, abs=1e-15)


def test_a_pitch_rate_at_zero_roll_turns_pitch_ahead() -> None:
    roll, pitch = roll_pitch_ahead(0.0, 0.2, 0.0, -0.4, 0.0, 0.02)
    assert roll == pytest.approx(0.0, abs=1e-15)
    assert pitch == pytest.approx(0.2 - 0.008, abs=1e-15)


def test_a_yaw_rate_does_not_change_a_level_attitude() -> None:
    assert roll_pitch_ahead(0.0, 0.0, 0.0, 0.0, 3.0, 0.05) == pytest.approx((0.0, 0.0), abs=1e-15)


def rolling_recording(rate: float = 0.8, n: int = 400, dt: float = 0.01
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A constant roll rate about x at zero pitch, exact samples (point samples of the rate)."""
    t = np.arange(n) * dt
    roll = rate * t
    acc = np.column_stack([np.zeros(n), G * np.sin(roll), G * np.cos(roll)])
    gyro = np.column_stack([np.full(n, rate), np.zeros(n), np.zeros(n)])
    return acc, gyro, np.full(n, dt)


@pytest.mark.parametrize("key", KEYS)
def test_the_outputs_lead_the_undelayed_ones_by_the_corrected_rate(key: str) -> None:
    acc, gyro, dt = rolling_recording()
    plain = make(key, gyro_sampling="point")
    ahead = make(key, gyro_sampling="point", sensor_delay=DELAY)
    out0 = plain.run(acc, gyro, dt, backend="python")
    out1 = ahead.run(acc, gyro, dt, backend="python")
    # the state is the same: the delay only changes what the outputs show
    assert np.array_equal(out0["bias"], out1["bias"])
    for name, value in plain.get_state()["state"].items():
        assert state_numbers(value) == state_numbers(ahead.get_state()["state"][name]), name
    # at zero pitch a rate about x turns roll by (rate - bias_x) * delay and leaves pitch
    lead = (gyro[:, 0] - out0["bias"][:, 0]) * DELAY
    gap = np.remainder(out1["roll"] - out0["roll"] - lead + math.pi, 2 * math.pi) - math.pi
    assert np.max(np.abs(gap[1:])) < 1e-9
    assert gap[0] == 0.0  # the first sample only initialises: no rate measured yet to turn by
    assert np.max(np.abs(out1["pitch"] - out0["pitch"])) < 1e-6


@pytest.mark.parametrize("key", KEYS)
def test_the_delayed_output_is_closer_to_the_truth_when_the_samples_lag(key: str) -> None:
    """Samples read DELAY late (every sample shows the attitude DELAY ago): turning the output
    ahead by DELAY takes the lag's error (rate * DELAY = 0.11 deg) out. The error is measured
    against the same filter on samples that do not lag, so that what the filter does on its own
    (the normalised gradient step of Madgwick's filter) is not counted as the lag's."""
    rate, n, dt = 0.8, 600, 0.01
    t = np.arange(n) * dt
    gyro = np.column_stack([np.full(n, rate), np.zeros(n), np.zeros(n)])

    def acc(lag: float) -> np.ndarray:  # what the sensor reports at t
        seen = rate * (t - lag)
        return np.column_stack([np.zeros(n), G * np.sin(seen), G * np.cos(seen)])

    on_time = make(key, gyro_sampling="point").run(acc(0.0), gyro, np.full(n, dt),
                                                   backend="python")
    errors = {}
    for delay in (0.0, DELAY):
        out = make(key, gyro_sampling="point", sensor_delay=delay).run(
            acc(DELAY), gyro, np.full(n, dt), backend="python")
        err = np.remainder(out["roll"] - on_time["roll"] + math.pi, 2 * math.pi) - math.pi
        errors[delay] = float(np.sqrt(np.mean(err[n // 2:] ** 2)))
    assert errors[0.0] == pytest.approx(rate * DELAY, rel=0.05)
    assert errors[DELAY] < 0.1 * errors[0.0]


@pytest.mark.parametrize("key", KEYS)
def test_a_rejected_first_sample_leaves_the_output_unturned(key: str) -> None:
    est = make(key, sensor_delay=DELAY)
    first = est.step((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 0.01)  # no gravity direction: no init
    assert not est.initialized
    assert (first.roll, first.pitch) == (est.output().roll, est.output().pitch)
    assert math.isfinite(first.roll) and math.isfinite(first.pitch)


def test_sensor_delay_takes_only_a_physical_range() -> None:
    with pytest.raises(ValueError, match="sensor_delay"):
        make("cf", sensor_delay=-0.001)
    with pytest.raises(ValueError, match="sensor_delay"):
        make("cf", sensor_delay=1.0)
