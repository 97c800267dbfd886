"""The complementary filters' start (measured_vector: while the vector fills): over the pre-filter's
first length they take the tilt of the running mean of the turned samples, so a first sample
taken in vibration does not set the attitude for seconds. Both backends; the C twin must agree."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusion_core import ESTIMATORS, native
from fusion_core.measured_vector import measure_constants, measure_start, measure_step
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
            np.testing.assert_array_equal(out[name], ref[name])  # the twins, bit for bit


def test_the_measured_vector_is_a_mean_of_the_samples_while_it_fills() -> None:
    """Without rotation, after n samples of the fill the vector is a weighted mean of them
    (weights summing to 1) in which no sample weighs more than 1.5 / n: never one sample's tilt.
    (Two stages each of half the time since the start weigh the middle samples most.)"""
    dt = 0.01
    c = measure_constants(1.0, 0.0, 0.15, 1e-5)
    zero, terms = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
    for n in (2, 5, 20, 60, 99):
        weights = []
        for j in range(n):  # the vector is linear in the samples: each one's weight alone
            samples = [(1.0 if i == j else 0.0, 0.0, 0.0) for i in range(n)]
            m = measure_start(samples[0], c)
            for a in samples[1:]:
                m, _, filling = measure_step(m, a, zero, terms, dt, c)
                assert filling
            weights.append(m.f[0])
        assert sum(weights) == pytest.approx(1.0, abs=1e-12)
        assert min(weights) > 0.0 and max(weights) <= 1.5 / n, (n, max(weights) * n)
