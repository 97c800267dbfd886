"""Shared helpers of the fusion_core tests: the estimator keys, recordings and angle errors."""

from __future__ import annotations

import numpy as np
import pytest

import fusion_core
from fusion_core import synthetic
from fusion_core.base import Estimator
from fusion_core.registry import KEYS  # noqa: F401  (every estimator; tests import it from here)

RATE = 100.0
"""Sample rate of the synthetic recordings [Hz] (the contract's T1 rate)."""


def estimator_class(key: str) -> type[Estimator]:
    """The class registered under key; the test fails (not skips) while it is missing."""
    cls = fusion_core.ESTIMATORS.get(key)
    if cls is None:
        have = sorted(fusion_core.ESTIMATORS)
        pytest.fail(f"estimator {key!r} is not in fusion_core.ESTIMATORS (it has {have})")
    return cls


def paper(key: str, **params: object) -> dict:
    """The parameters of estimator key's paper filter (fusion_core.papers; "filter": "paper",
    for make) with the point-sample rule (gyro_sampling="point", the rule for the synthetic
    recordings' point samples) and the given parameters on top: the tests of the papers'
    equations run the papers' filters on exact samples."""
    from fusion_core.registry import FILTER

    return {FILTER: "paper", "gyro_sampling": "point", **params}


def make(key: str, **params: object) -> Estimator:
    """A new estimator of kind key (its paper filter where params say "filter": "paper")."""
    from fusion_core.registry import create

    estimator_class(key)
    return create(key, dict(params))


def run_recording(estimator: Estimator, rec: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Feed a synthetic.record() recording through estimator.run()."""
    return estimator.run(rec["acc_meas"], rec["gyro_meas"], rec["dt"])


def angle_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a - b wrapped to [-pi, pi) [rad] (roll wraps at +-180 deg)."""
    return np.remainder(np.asarray(a) - np.asarray(b) + np.pi, 2.0 * np.pi) - np.pi


def noisy_two_axis_recording(duration: float, seed: int = 0) -> dict[str, np.ndarray]:
    """two_axis_motion() with MPU-6050 noise and a gyro bias, for tests that need a busy state."""
    noise = synthetic.ImuNoise(gyro_bias=(0.01, -0.006, 0.004))
    return synthetic.record(synthetic.two_axis_motion(), duration, RATE, noise=noise, seed=seed)


def state_numbers(value: object) -> list:
    """A state field's numbers in order: a number, a vector, or a Measure (vectors, then
    numbers) as one flat list."""
    if isinstance(value, (list, tuple)):
        return [x for v in value for x in state_numbers(v)]
    return [value]


def with_number(value: object, index: int, new: float) -> object:
    """value (a number or nested lists/tuples of them) with its index-th number replaced."""
    numbers = state_numbers(value)
    numbers[index] = new
    it = iter(numbers)

    def shaped(template: object) -> object:
        if isinstance(template, (list, tuple)):
            return [shaped(t) for t in template]
        return next(it)

    return shaped(value)
