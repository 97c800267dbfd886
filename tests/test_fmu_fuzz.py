"""Garbage through every estimator FMU (fmpy): every doStep returns OK (fmpy raises otherwise),
every output stays finite, and invalid_samples counts exactly what the rules reject. 5,000
samples per FMU in `make test`; 100,000 in `make test-slow`."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_garbage_in import BAD_DT, EXTREMES, rejected_by_the_rules

from fmu_src.host import FmuInstance


def garbage(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n samples: each value an extreme (NaN, inf, +-1e300, subnormal, +-1e6, 0) with
    probability 0.2, else a plausible one (|acc| near g, rates within 10 rad/s); dt bad with
    probability 0.1."""
    rng = np.random.default_rng(seed)
    acc = rng.normal(0.0, 6.0, (n, 3)) + np.array([0.0, 0.0, 9.81])
    gyro = rng.normal(0.0, 3.0, (n, 3))
    extremes = np.array(EXTREMES)
    for a in (acc, gyro):
        mask = rng.random(a.shape) < 0.2
        a[mask] = rng.choice(extremes, size=int(mask.sum()))
    dt = np.full(n, 0.01)
    bad = rng.random(n) < 0.1
    dt[bad] = rng.choice(np.array(BAD_DT), size=int(bad.sum()))
    return acc, gyro, dt


def fuzz(fmu_path, n: int, seed: int) -> None:
    acc, gyro, dt = garbage(n, seed)
    with FmuInstance(fmu_path) as fmu:
        out = fmu.run_samples(acc, gyro, dt, h=0.01)
        errors = [m for m in fmu.messages if m.status not in ("OK", "WARNING")]
    for name in ("roll", "pitch", "bias", "pos", "vel"):
        if name in out:
            assert np.all(np.isfinite(out[name])), name
    expected = np.cumsum([rejected_by_the_rules(tuple(a), tuple(w), float(h))
                          for a, w, h in zip(acc, gyro, dt, strict=True)])
    assert np.array_equal(out["invalid_samples"], expected)
    assert not errors, errors[:3]
    assert 0 < expected[-1] < n  # both kinds were tried
    print(f"\n{fmu_path.stem}: {n} samples, {expected[-1]} rejected, outputs finite")


def test_fmu_survives_5000_garbage_samples(fmu_path) -> None:
    fuzz(fmu_path, 5000, seed=1)


@pytest.mark.slow
def test_fmu_survives_100000_garbage_samples(fmu_path) -> None:
    fuzz(fmu_path, 100_000, seed=2)


def test_the_rules_reject_what_the_contract_names() -> None:
    assert rejected_by_the_rules((0.0, 0.0, 9.81), (0.0, 0.0, 0.0), 0.0)
    assert rejected_by_the_rules((0.0, 0.0, 9.81), (2000.0, 0.0, 0.0), 0.01)
    assert rejected_by_the_rules((math.nan, 0.0, 9.81), (0.0, 0.0, 0.0), 0.01)
    assert not rejected_by_the_rules((1e300, 0.0, 1e-320), (0.0, 0.0, 0.0), 0.01)
