"""Every value a parameter's range admits keeps every estimate finite (interface: no input of any
kind, a host's parameter value included, makes an output non-finite).

Each range is finite (fusion_core.types.UNIT_LIMITS where a parameter states no bound of its
own). The sweep sets each numeric parameter to each end of its range, then draws whole parameter
sets at random (each value at an end or log-uniform inside), and runs a recording of motion,
rest and rejected samples through both twins."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from helpers import KEYS, estimator_class

from fusion_core import native
from fusion_core.sensor import SENSOR_PARAMS, ImuSensorModel
from fusion_core.types import Param


def _numeric(specs) -> list[Param]:
    return [p for p in specs if p.choices is None and not isinstance(p.default, bool)
            and not isinstance(p.default, int)]


def _ends(p: Param) -> list[float]:
    """The extreme values the range admits: each bound, or the next double inside an open one."""
    out = []
    for bound, is_open, inward in ((p.low, p.low_open, math.inf), (p.high, p.high_open, -math.inf)):
        assert bound is not None
        out.append(math.nextafter(bound, inward) if is_open else bound)
    return out


def _recording(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Motion with vibration, rest (every 7 s, 2.5 s long) and a rejected sample every 53."""
    k = np.arange(n)
    t = 0.01 * k
    roll, pitch = 0.6 * np.sin(0.7 * t), 0.4 * np.sin(0.45 * t + 0.3)
    acc = np.stack([-9.80665 * np.sin(pitch) + 0.8 * np.sin(11.0 * t),
                    9.80665 * np.sin(roll) * np.cos(pitch), 9.80665 * np.cos(roll) * np.cos(pitch)],
                   axis=1)
    gyro = np.stack([0.42 * np.cos(0.7 * t) + 0.01, 0.18 * np.cos(0.45 * t + 0.3) - 0.006,
                     0.2 * np.sin(0.1 * t)], axis=1)
    rest = (k % 700 > 350) & (k % 700 < 600)
    acc[rest] = (0.0, 0.0, 9.80665)
    gyro[rest] = (0.01, -0.006, 0.004)
    acc[k % 53 == 7, 1] = np.nan
    return acc, gyro, np.full(n, 0.01)


def _finite(out: dict) -> bool:
    return all(np.isfinite(v).all() for k, v in out.items() if k != "rejected")


def test_every_numeric_parameter_has_a_finite_range() -> None:
    specs = [p for key in KEYS for p in estimator_class(key).param_specs().values()]
    for p in _numeric([*specs, *SENSOR_PARAMS]):
        assert p.low is not None and p.high is not None, p.name
        assert math.isfinite(p.low) and math.isfinite(p.high), p.name
        for v in (math.inf, -math.inf):
            with pytest.raises(ValueError):
                p.validate(v)


@pytest.mark.parametrize("backend", [
    "native", pytest.param("python", marks=pytest.mark.heavy)])  # Python: seconds per key
@pytest.mark.parametrize("key", KEYS)
def test_each_end_of_each_range_keeps_the_estimates_finite(key: str, backend: str) -> None:
    if backend == "native" and not native.available():
        pytest.skip(f"the C twin is unavailable: {native.reason()}")
    acc, gyro, dt = _recording(3000 if backend == "native" else 800)
    cls = estimator_class(key)
    bad = []
    for p in _numeric(cls.param_specs().values()):
        for value in _ends(p):
            with np.errstate(all="ignore"):
                out = cls(**{p.name: value}).run(acc, gyro, dt, backend=backend)
            if not _finite(out):
                bad.append(f"{p.name}={value!r}")
    assert not bad, bad


@pytest.mark.parametrize("key", KEYS)
def test_random_parameter_sets_in_range_keep_the_estimates_finite(key: str) -> None:
    backend = "native" if native.available() else "python"
    acc, gyro, dt = _recording(3000 if backend == "native" else 600)
    cls = estimator_class(key)
    rng = random.Random(key)
    tried = 0
    for _ in range(150 if backend == "native" else 15):
        params = {}
        for p in cls.param_specs().values():
            if p.choices is not None:
                params[p.name] = rng.choice(p.choices)
            elif isinstance(p.default, bool):
                params[p.name] = rng.random() < 0.5
            elif not isinstance(p.default, int):
                lo, hi = _ends(p)
                r = rng.random()
                params[p.name] = (lo if r < 0.15 else hi if r < 0.3
                                  else math.exp(rng.uniform(math.log(lo), math.log(hi)))
                                  if lo > 0.0 else rng.uniform(lo, hi))
        try:
            est = cls(**params)
        except ValueError:  # a combination the class refuses (several parameters together)
            continue
        tried += 1
        with np.errstate(all="ignore"):
            out = est.run(acc, gyro, dt, backend=backend)
        assert _finite(out), params
    assert tried > 0


def test_each_end_of_each_sensor_range_keeps_the_samples_finite() -> None:
    n = 500
    t = 0.01 * np.arange(n)
    omega = np.stack([0.4 * np.sin(t), 0.3 * np.cos(t), 0.1 + 0 * t], axis=1)
    f = np.stack([0.5 * np.sin(3 * t), 0.2 + 0 * t, 9.80665 + 0 * t], axis=1)
    bad = []
    for p in _numeric(SENSOR_PARAMS):
        for value in _ends(p):
            for backend in ("python", "native") if native.available() else ("python",):
                out = ImuSensorModel(**{p.name: value}).run(omega, f, 0.01, backend=backend)
                if not all(np.isfinite(v).all() for v in out.values()):
                    bad.append(f"{p.name}={value!r} ({backend})")
    assert not bad, bad
