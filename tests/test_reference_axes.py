"""The laws a reference is checked by (testbenches.reference_axes) over the synthetic battery:
every motion and sensor class's true reference meets both, and one in other axes breaks one of
them wherever the motion shows it."""

from __future__ import annotations

import numpy as np
import pytest

from testbenches.battery import MOTIONS, SENSOR_CLASSES, part_samples
from testbenches.broad.metric import gravity_from_roll_pitch
from testbenches.reference_axes import (
    MIN_WINDOWS,
    TURN_MISS_MAX,
    VERTICAL_TOLERANCE,
    turn_miss,
    vertical_share,
)

FIRST = 6000
"""Samples of each part checked, as a recording's first block is (a minute at 100 Hz)."""
TURN_X = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""A body's frame turned by 90 deg about x against the sensor's."""


@pytest.mark.parametrize("motion", sorted(MOTIONS))
def test_a_true_reference_meets_both_laws_and_one_in_other_axes_breaks_one(motion):
    """Each sensor class's part of the motion (seed 0), its first minute: the truth's up
    direction averages 1 g of specific force to within VERTICAL_TOLERANCE and the gyro misses
    its turns by at most TURN_MISS_MAX of them (the clipping gyro and an uncalibrated part's
    bias the furthest). Turned by 90 deg, its mean is a fraction of g; with the pitch's sign
    turned or roll and pitch swapped, the gyro misses it by more than TURN_MISS_MAX wherever the
    motion tilts in pitch or in roll by much (a pendulum's swing about x alone is its own
    mirror in pitch, and is no evidence)."""
    for sensor in SENSOR_CLASSES:
        _, truth, sample = part_samples(motion, sensor, 0)
        acc, gyro, dt = (sample[k][:FIRST] for k in ("acc", "gyro", "dt"))
        roll, pitch = truth["roll"][:FIRST], truth["pitch"][:FIRST]
        up = gravity_from_roll_pitch(roll, pitch)
        assert abs(vertical_share(acc, up) - 1.0) <= VERTICAL_TOLERANCE, sensor
        windows, miss = turn_miss(up, gyro, dt)
        assert windows < MIN_WINDOWS or miss <= TURN_MISS_MAX, sensor
        assert abs(vertical_share(acc, up @ TURN_X.T) - 1.0) > VERTICAL_TOLERANCE, sensor
        for other in ((roll, -pitch), (pitch, roll)):
            if np.ptp(other[1] - pitch) > np.radians(10.0) or np.ptp(other[0] - roll) > \
                    np.radians(10.0):
                windows, miss = turn_miss(gravity_from_roll_pitch(*other), gyro, dt)
                assert windows < MIN_WINDOWS or miss > TURN_MISS_MAX, sensor
