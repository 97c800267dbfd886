"""Contract check T1 as a unit test: noise-free two-axis motion is tracked within 0.05 deg."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from helpers import KEYS, RATE, angle_difference, make, run_recording

from fusion_core import DEG, synthetic

TOL_DEG = 0.05
SETTLE_S = 5.0
DURATION_S = 20.0  # 10 roll periods, 7 pitch periods


@functools.cache
def two_axis_recording() -> dict[str, np.ndarray]:
    """Roll 0.5 rad at 0.5 Hz and pitch 0.35 rad at 0.35 Hz (body rates up to 1.6 rad/s from the
    Euler kinematics), no linear acceleration, no sensor noise, 100 Hz."""
    return synthetic.record(synthetic.two_axis_motion(), DURATION_S, RATE)


@pytest.mark.parametrize("key", KEYS)
def test_noise_free_two_axis_motion_is_tracked_within_0p05_deg_after_5_s(key: str) -> None:
    rec = two_axis_recording()
    out = run_recording(make(key), rec)
    after = rec["t"] >= SETTLE_S
    roll_err = np.abs(angle_difference(out["roll"], rec["roll"]))[after].max() / DEG
    pitch_err = np.abs(out["pitch"] - rec["pitch"])[after].max() / DEG
    print(f"\n{key}: max error after {SETTLE_S} s: roll {roll_err:.4f}, pitch {pitch_err:.4f} deg")
    assert not out["rejected"].any()
    assert max(roll_err, pitch_err) < TOL_DEG, (roll_err, pitch_err)
