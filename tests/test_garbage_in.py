"""Garbage in, nothing breaks (interface v2, "Bad input"): for any input at all an estimator
either rejects the sample (InvalidSample, counted) or processes it, its outputs stay finite, and
once valid samples return it comes back to the truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import KEYS, make
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fusion_core import DEG, G
from fusion_core.presets import preset_params
from testbenches.recovery import RECOVERY_BOUND_S, absurd_then_tilt

pytestmark = pytest.mark.heavy  # accuracy after garbage, hypothesis recordings

EXTREMES = [math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-320, -1e-320, 1e6, -1e6, 0.0]
BAD_DT = [0.0, -1.0, 1e-12, 2.0, math.nan, math.inf]

value = st.one_of(st.sampled_from(EXTREMES), st.floats(-50.0, 50.0), st.floats(allow_nan=True))
dt_value = st.one_of(st.sampled_from(BAD_DT), st.just(0.01), st.floats(1e-4, 0.5))
sample = st.tuples(st.tuples(value, value, value), st.tuples(value, value, value), dt_value)


def rejected_by_the_rules(acc: tuple, gyro: tuple, dt: float, max_rate: float = 1000.0) -> bool:
    """What the contract rejects: a non-finite value, dt outside (0, max_dt = 1 s], a rate above
    max_rate. Any finite accelerometer reading is processed."""
    values = (*acc, *gyro, dt)
    if not all(math.isfinite(v) for v in values):
        return True
    return not 0.0 < dt <= 1.0 or not math.hypot(*gyro) <= max_rate


@pytest.mark.parametrize("preset", ["recommended", "paper"])
@pytest.mark.parametrize("key", KEYS)
def test_garbage_never_raises_and_never_gives_a_non_finite_estimate(key: str, preset: str) -> None:
    params = preset_params(preset, key)

    @settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.lists(sample, min_size=1, max_size=60))
    def check(samples: list) -> None:
        est = make(key, **params)
        acc = np.array([s[0] for s in samples], dtype=float)
        gyro = np.array([s[1] for s in samples], dtype=float)
        dt = np.array([s[2] for s in samples], dtype=float)
        out = est.run(acc, gyro, dt)  # raises nothing (InvalidSample is caught by run)
        for name in ("roll", "pitch", "bias", "pos", "vel"):
            if name in out:
                assert np.all(np.isfinite(out[name])), name
        expected = [rejected_by_the_rules(tuple(a), tuple(w), float(h))
                    for a, w, h in zip(acc, gyro, dt, strict=True)]
        assert out["rejected"].tolist() == expected
        state = est.get_state()["state"]
        assert all(math.isfinite(v) for v in _floats(state)), state

    check()


def _floats(value: object) -> list[float]:
    if isinstance(value, float):
        return [value]
    if isinstance(value, (list, tuple)):
        return [f for v in value for f in _floats(v)]
    if isinstance(value, dict):
        return [f for v in value.values() for f in _floats(v)]
    return []


@pytest.mark.parametrize("key", KEYS)
def test_after_garbage_a_clean_static_tilt_brings_the_error_back_under_1_deg(key: str) -> None:
    """2 s of garbage (every kind above, and finite absurd samples that are processed), then
    20 s of a clean static tilt (roll 20 deg, pitch -10 deg): error back under 1 deg."""
    rng = np.random.default_rng(7)
    n_bad = 200
    choices = np.array(EXTREMES)
    acc = rng.choice(choices, size=(n_bad, 3))
    gyro = rng.choice(choices, size=(n_bad, 3))
    dt = rng.choice(np.array([*BAD_DT, 0.01]), size=n_bad)
    roll, pitch = 20 * DEG, -10 * DEG
    level = np.array([-G * math.sin(pitch), G * math.sin(roll) * math.cos(pitch),
                      G * math.cos(roll) * math.cos(pitch)])
    n_good = 2000
    acc = np.vstack([np.tile(level, (5, 1)), acc, np.tile(level, (n_good, 1))])
    gyro = np.vstack([np.zeros((5, 3)), gyro, np.zeros((n_good, 3))])
    dt = np.concatenate([np.full(5, 0.01), dt, np.full(n_good, 0.01)])
    out = make(key).run(acc, gyro, dt)
    err = max(abs(out["roll"][-1] - roll), abs(out["pitch"][-1] - pitch)) / DEG
    assert np.all(np.isfinite(out["roll"])) and err < 1.0, err


@pytest.mark.parametrize("key", KEYS)
def test_after_absurd_but_accepted_samples_the_error_is_back_under_1_deg_within_40_s(key: str
                                                                                   ) -> None:
    """1 s of samples that pass every rule but are absurd (rates up to 300 rad/s, specific force
    up to 100 g) throws the attitude more than ten degrees off; then a clean static tilt brings
    the error under 1 deg for good within RECOVERY_BOUND_S (testbenches.recovery, whose table
    docs/results/robustness.md shows)."""
    got = absurd_then_tilt(key)
    assert got["rejected"] == 0.0
    assert got["thrown_deg"] > 10.0  # the garbage did throw it off, ten times the bound
    assert got["back_after_s"] <= RECOVERY_BOUND_S, got
