"""get_state / set_state: a restored filter continues bit-identically."""

from __future__ import annotations

import json
import math
from collections.abc import Callable

import numpy as np
import pytest
from helpers import KEYS, make, noisy_two_axis_recording

from fusion_core import synthetic

N_REST = 200
N = 400
SPLITS = {"at_rest": 150, "moving": 300}


def recording_with_bad_samples() -> dict[str, np.ndarray]:
    """2 s at rest, then 2 s of two-axis motion: MPU-6050 noise, gyro bias, jittered dt, and
    rejected samples on both sides of each split (the rejection counter is state too).
    Splitting at rest catches state that only exists while stationary (zero-velocity update)."""
    rest = synthetic.record(
        synthetic.Trajectory(roll=synthetic.constant(0.2)), 2.0, 100.0,
        noise=synthetic.ImuNoise(gyro_bias=(0.01, -0.006, 0.004)), seed=4,
    )
    moving = noisy_two_axis_recording(2.0, seed=3)
    acc = np.vstack([rest["acc_meas"][:N_REST], moving["acc_meas"][: N - N_REST]])
    gyro = np.vstack([rest["gyro_meas"][:N_REST], moving["gyro_meas"][: N - N_REST]])
    rng = np.random.default_rng(3)
    dt = 0.01 * (1.0 + 0.2 * rng.uniform(-1.0, 1.0, N))
    acc[70, 0] = math.nan
    gyro[220, 1] = math.inf
    dt[330] = -0.01
    return {"acc": acc, "gyro": gyro, "dt": dt}


def json_round_trip(state: dict) -> dict:
    return json.loads(json.dumps(state, allow_nan=False))


def same_object(state: dict) -> dict:
    return state


def check_continues_bit_identically(
    key: str, split: int, transport: Callable[[dict], dict]
) -> None:
    seq = recording_with_bad_samples()
    first = slice(0, split)
    rest = slice(split, N)
    original = make(key)
    original.run(seq["acc"][first], seq["gyro"][first], seq["dt"][first])
    snapshot = original.get_state()
    expected = original.run(seq["acc"][rest], seq["gyro"][rest], seq["dt"][rest])

    restored = make(key)
    restored.set_state(transport(snapshot))
    got = restored.run(seq["acc"][rest], seq["gyro"][rest], seq["dt"][rest])

    assert expected.keys() == got.keys()
    for name in expected:
        assert np.array_equal(expected[name], got[name]), name
    assert restored.get_state() == original.get_state()


@pytest.mark.parametrize("split", list(SPLITS))
@pytest.mark.parametrize("key", KEYS)
def test_restored_state_continues_bit_identically(key: str, split: str) -> None:
    check_continues_bit_identically(key, SPLITS[split], same_object)


@pytest.mark.parametrize("split", list(SPLITS))
@pytest.mark.parametrize("key", KEYS)
def test_state_survives_json_and_continues_bit_identically(key: str, split: str) -> None:
    check_continues_bit_identically(key, SPLITS[split], json_round_trip)
