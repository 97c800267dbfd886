"""Crafted JSON states: fusion_core's set_state and the pythonfmu FMUs' setFMUstate.

A state is JSON-ready data (get_state), so a crafted one is any JSON: values out of range,
non-finite numbers, wrong types and shapes, keys missing or unknown, nested estimators'
parameters that differ from their parent's, truncated or unreadable bytes. fusion_core refuses
each with a ValueError naming what is wrong and leaves the filter as it was; a state it takes
gives finite estimates on the next samples. The pythonfmu FMUs cannot return fmi2Error
(pythonfmu 0.7 turns a slave's answer into OK, Discard or Fatal), so they refuse with an error
log line, keep their state and step on.
"""

from __future__ import annotations

import copy
import json
import math
import random
from typing import Any

import numpy as np
import pytest
from native_fmu import NativeFmu

from fusion_core import ESTIMATORS
from fusion_core.sensor import ImuSensorModel

pytestmark = pytest.mark.heavy  # crafted states through every twin: seconds each

REPLACEMENTS: tuple[Any, ...] = (
    math.nan, math.inf, -math.inf, 1e300, -1e300, 1e80, -1.0, 0.0, 0.5, 2.5, 7, 2049, 2**70,
    -(2**63), True, False, None, "x", [], [1.0], {}, [[0.0, 1.0]], 3.2, -3.2, 1.6,
)
"""What a leaf of a state may be replaced with."""


def _leaves(node: Any, path: tuple = ()) -> list[tuple]:
    """Every path to a value or container in a JSON-ready structure."""
    out = [path]
    if isinstance(node, dict):
        for k, v in node.items():
            out += _leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _leaves(v, (*path, i))
    return out


def _set(node: Any, path: tuple, value: Any) -> Any:
    if not path:
        return value
    node[path[0]] = _set(node[path[0]], path[1:], value)
    return node


def mutate(state: dict, rng: random.Random) -> Any:
    """One mutation of a JSON-ready state: a leaf replaced, a key removed or added, a list
    shortened or lengthened."""
    state = copy.deepcopy(state)
    path = rng.choice(_leaves(state)[1:])
    parent = state
    for p in path[:-1]:
        parent = parent[p]
    kind = rng.random()
    if kind < 0.7:
        return _set(state, path, rng.choice(REPLACEMENTS))
    if kind < 0.8 and isinstance(parent, dict):
        del parent[path[-1]]
    elif kind < 0.9 and isinstance(parent, dict):
        parent["unknown_" + str(path[-1])] = 1.0
    elif isinstance(parent, list):
        if rng.random() < 0.5 and parent:
            parent.pop()
        else:
            parent.append(copy.deepcopy(parent[-1]) if parent else 0.0)
    else:
        return _set(state, path, rng.choice(REPLACEMENTS))
    return state


def _samples(n: int) -> tuple[np.ndarray, np.ndarray]:
    t = 0.01 * np.arange(n)
    roll, pitch = 0.6 * np.sin(0.7 * t), 0.4 * np.sin(0.45 * t + 0.3)
    acc = 9.80665 * np.stack([-np.sin(pitch), np.sin(roll) * np.cos(pitch),
                              np.cos(roll) * np.cos(pitch)], axis=1)
    acc[n // 2:] = (0.0, 0.0, 9.80665)  # then at rest (the position filter's queue)
    gyro = np.stack([0.42 * np.cos(0.7 * t), 0.18 * np.cos(0.45 * t), 0.1 + 0 * t], axis=1)
    gyro[n // 2:] = (0.01, -0.006, 0.004)
    return acc, gyro


@pytest.mark.parametrize("key", list(ESTIMATORS))
def test_a_crafted_state_is_refused_by_name_or_gives_finite_estimates(key: str) -> None:
    acc, gyro = _samples(400)
    rng = random.Random(key)
    snapshots = []
    est = ESTIMATORS[key]()
    for k in range(400):
        est.step(acc[k], gyro[k], 0.01)
        if k in (0, 30, 150, 260, 399):
            snapshots.append(json.loads(json.dumps(est.get_state())))
    tried = refused = 0
    for _ in range(1500):
        crafted = mutate(rng.choice(snapshots), rng)
        target = ESTIMATORS[key]()
        target.step(acc[0], gyro[0], 0.01)
        before = json.dumps(target.get_state())
        tried += 1
        try:
            target.set_state(crafted)
        except ValueError as err:
            refused += 1
            assert str(err)  # says what
            assert json.dumps(target.get_state()) == before  # the filter as it was
            continue
        for k in range(20):
            e = target.step(acc[k], gyro[k], 0.01)
            assert all(math.isfinite(v) for v in (e.roll, e.pitch, *e.bias)), crafted
    print(f"\n{key}: {tried} crafted states, {refused} refused")
    assert tried // 3 < refused < tried


def test_a_crafted_sensor_state_is_refused_by_name_or_gives_finite_samples() -> None:
    rng = random.Random(5)
    model = ImuSensorModel(dlpf_cfg=3)
    snapshots = []
    for k in range(200):
        model.sample((0.3, 0.1, 0.0), (0.0, 0.0, 9.8), 0.01)
        if k in (0, 99, 199):
            snapshots.append(json.loads(json.dumps(model.get_state())))
    refused = 0
    for _ in range(1000):
        crafted = mutate(rng.choice(snapshots), rng)
        target = ImuSensorModel(dlpf_cfg=3)
        before = json.dumps(target.get_state())
        try:
            target.set_state(crafted)
        except ValueError:
            refused += 1
            assert json.dumps(target.get_state()) == before
            continue
        for _ in range(5):
            acc, gyro, dt = target.sample((0.3, 0.1, 0.0), (0.0, 0.0, 9.8), 0.01)
            assert all(math.isfinite(v) for v in (*acc, *gyro, dt)), crafted
    assert 300 < refused < 1000


@pytest.mark.parametrize("name", ["AngleBiasKalmanFilter", "UnscentedKalmanFilter",
                                  "PositionKalmanFilter", "ImuSensor"])
def test_a_pythonfmu_fmu_refuses_crafted_state_bytes_with_a_log_line(built_fmus, name) -> None:
    fmu = NativeFmu(built_fmus.path(name))
    fmu.instantiate()
    fmu.start()
    inputs = (["acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt"]
              if name != "ImuSensor" else ["omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z"])
    sample = ([0.2, 0.1, 9.8, 0.05, -0.02, 0.01, 0.01] if name != "ImuSensor"
              else [0.05, -0.02, 0.01, 0.2, 0.1, 9.8])
    outputs = [n for n, v in fmu.vars.items() if v.causality == "output" and v.type == "Real"]

    now = [0.0]  # the FMU's time: a doStep must start there

    def step(k: int) -> list[float]:
        fmu.step(now[0], 0.01, **dict(zip(inputs, sample, strict=True)))
        now[0] += 0.01
        return [fmu.get(n) for n in outputs]

    for k in range(50):
        step(k)
    valid = json.loads(fmu.serialize(fmu.save()).decode())
    rng = random.Random(name)
    refused = 0
    crafted_bytes = [b"", b"{", b"\xff\xfe", b"[]", b"null", json.dumps({"fmu": name}).encode()]
    crafted_bytes += [json.dumps(mutate(valid, rng)).encode() for _ in range(150)]
    for i, blob in enumerate(crafted_bytes):
        errors = len([1 for status, _ in fmu.log if status >= 3])
        fmu.restore(fmu.deserialize(blob))
        if len([1 for status, _ in fmu.log if status >= 3]) > errors:
            refused += 1
        else:  # taken: the FMU is at the state's time
            now[0] = json.loads(blob)["time"]
        out = step(100 + i)
        assert all(math.isfinite(v) for v in out), (blob[:200], out)
    fmu.terminate()
    fmu.free()
    print(f"\n{name} (pythonfmu): {len(crafted_bytes)} crafted states, {refused} refused with "
          "a log line")
    assert len(crafted_bytes) // 3 < refused < len(crafted_bytes)
