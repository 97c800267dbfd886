"""The complementary filters' start (building_blocks.alignment_time): over the pre-filter's first
time constant they take the tilt of the running mean of the turned samples, so a first sample
taken in vibration does not set the attitude for seconds. Both backends; the C twin must agree."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusion_core import ESTIMATORS, native
from fusion_core.building_blocks import alignment_time
from fusion_core.types import DEG, G

RATE = 100.0
BACKENDS = ["python", pytest.param("native", marks=pytest.mark.skipif(
    native.reason() is not None, reason=f"no C twin: {native.reason()}"))]


def vibrating_still(roll: float, pitch: float, seconds: float, amplitude: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sensor still at roll and pitch [rad] on a mount that shakes it along its x axis by
    +-amplitude [m/s^2] from one sample to the next (a tone at half the sample rate)."""
    n = round(seconds * RATE)
    f = G * np.array([-math.sin(pitch), math.sin(roll) * math.cos(pitch),
                      math.cos(roll) * math.cos(pitch)])
    acc = np.tile(f, (n, 1))
    acc[:, 0] += amplitude * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    return acc, np.zeros((n, 3)), np.full(n, 1.0 / RATE)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("key", ("cf", "mgcf"))
def test_a_first_sample_in_vibration_is_averaged_away_within_the_first_second(
        key: str, backend: str) -> None:
    roll, pitch = 10.0 * DEG, -5.0 * DEG
    acc, gyro, dt = vibrating_still(roll, pitch, 3.0, 0.3 * G)
    out = ESTIMATORS[key]().run(acc, gyro, dt, backend=backend)
    err = np.maximum(np.abs(out["roll"] - roll), np.abs(out["pitch"] - pitch))
    assert err[0] > 10.0 * DEG  # the first sample's tilt: 0.3 g off along x
    assert err[round(RATE):].max() < 0.2 * DEG  # from 1 s on (a low-pass from the first
    # sample, as before, is still 14 deg off there)
    if backend == "native":
        ref = ESTIMATORS[key]().run(acc, gyro, dt, backend="python")
        for name in ("roll", "pitch", "bias"):
            np.testing.assert_allclose(out[name], ref[name], rtol=0, atol=1e-12)


def test_the_pre_filter_is_the_running_mean_for_its_first_time_constant() -> None:
    dt = 0.01
    for n in (1, 2, 50, 99):
        tau, aligning = alignment_time(n, dt, 1.0)
        assert aligning and dt / (tau + dt) == pytest.approx(1.0 / (n + 1))
    assert alignment_time(100, dt, 1.0) == (1.0, False)
    assert alignment_time(10_000, dt, 1.0) == (1.0, False)
