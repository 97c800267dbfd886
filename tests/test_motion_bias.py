"""The complementary filters' bias learned in motion until the first rest
(building_blocks.motion_bias)."""

from __future__ import annotations

import numpy as np
import pytest

from fusion_core.registry import create
from testbenches import battery
from testbenches.calibrate.part import part_calibration
from testbenches.parts import part_rmse


@pytest.mark.parametrize("key", ["cf", "mgcf"])
def test_parts_shaken_from_power_up_learn_their_bias_in_motion(key: str) -> None:
    """The contract's shaking starts in motion: no rest measures the bias a start-up calibration
    leaves, and without the mechanism the parts with the largest biases leave the bound (the
    contract asks 95 % of 20 parts, calibrated first); with it they stay within."""
    from fusion_core.presets import load_preset
    from testbenches.contract import accuracy_limits
    from testbenches.parts import CALIBRATED_SHARE, PARTS

    preset = load_preset("recommended")
    limit = np.array(accuracy_limits(key, "shaking")[:2])
    share = {}
    for gain in (0.0, None):
        params = {} if gain is None else {"motion_bias_gain": gain}
        got = part_rmse([key], ["shaking"], preset, {}, PARTS, params, calibrated_first=(True,))
        share[gain] = float(np.mean(np.all(got[(True, key, "shaking")] <= limit, axis=1)))
    assert share[0.0] < CALIBRATED_SHARE <= share[None]


@pytest.mark.parametrize("key", ["cf", "mgcf"])
def test_after_a_rest_the_bias_is_the_rests_alone(key: str) -> None:
    """A recording that starts at rest (the battery's hand-held motion, 3 s still): the rest
    detector measures the bias within its first rest_time, and what the mechanism learns before
    that is from innovations of a sensor at rest, next to nothing. The run is the same within
    0.01 deg with it and without it."""
    _, _, sample = battery.part_samples("handheld_slow", "mpu6050", 0)
    calibration = part_calibration({}, 0)
    runs = [create(key, {**calibration, **extra}).run(sample["acc"], sample["gyro"], sample["dt"])
            for extra in ({}, {"motion_bias_gain": 0.0})]
    for name in ("roll", "pitch"):
        assert np.max(np.abs(runs[0][name] - runs[1][name])) < np.radians(0.01), name


CORRECTION_TIMES = [("cf", 1e-4), ("cf", 0.02), ("cf", 1.0), ("mgcf", None)]
"""The cf's tau down to a fraction of a sample; the mgcf's correction time is its w0 and zeta."""


@pytest.mark.parametrize(("key", "tau"), CORRECTION_TIMES)
def test_the_loop_is_stable_at_the_largest_gain_and_any_correction_time(key: str,
                                                                         tau: float | None) -> None:
    """The loop's Ki = gain / tau^2 with tau no shorter than a stage of the measured vector's
    low-pass: at the largest allowed gain (1, damping 0.5), the bias it learns on the contract's
    shaking (which starts in motion) stays within 2 deg/s, where a loop on tau alone learns
    hundreds of degrees per second at the shortest tau."""
    from testbenches.samples import scenario_samples

    _, _, sample = scenario_samples("shaking", 3, {})
    params = {"motion_bias_gain": 1.0} if tau is None else {"motion_bias_gain": 1.0, "tau": tau}
    out = create(key, params).run(sample["acc"], sample["gyro"], sample["dt"])
    assert np.max(np.abs(out["bias"])) < np.radians(2.0)
