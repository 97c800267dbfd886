"""The samples the testbench gives a scenario: the plant's truth at every communication point
and a sensor part's samples of it (montecarlo.simulate's data flow, the FMU testbench's). A
process keeps the last scenarios' truth and the last parts' samples, read-only: campaign runs,
the peers, a part's calibration session and the embedded bench share them.
"""

from __future__ import annotations

import functools
import json
from typing import Any

import numpy as np

from fusion_core.scenarios import get_scenario
from fusion_core.sensor import ImuSensorModel

from .master import communication_steps

RATE = 100.0
"""The campaign's sample rate [Hz], the contract's."""


@functools.lru_cache(maxsize=16)
def _truth(scenario_id: int, duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steps, times and [N, 15] truth (TRUTH_NAMES' order) of a scenario: the plant's C twin,
    or the Python trajectory. The truth depends on the scenario and the duration only, so a
    worker computes it once for all its runs of that scenario (read-only arrays)."""
    steps = communication_steps(duration, RATE, 0.0, 0)
    t = np.cumsum(steps)
    truth = get_scenario(scenario_id).truth(t)
    for a in (steps, t, truth):
        a.setflags(write=False)
    return steps, t, truth


@functools.lru_cache(maxsize=4)
def _samples(scenario_id: int, duration: float, sensor_json: str) -> dict[str, np.ndarray]:
    """The sensor's samples of a scenario for one parameter set (with its seed): the same for
    every estimator of a seed, which the plan puts next to each other, so that a worker runs the
    sensor once for them."""
    steps, _, truth = _truth(scenario_id, duration)
    out = ImuSensorModel(**json.loads(sensor_json)).run(truth[:, 3:6], truth[:, 6:9], steps)
    for a in out.values():
        a.setflags(write=False)
    return out


def scenario_samples(
    scenario: str, seed: int, sensor: dict[str, Any], duration: float | None = None
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Times [N], truth [N, 15] (TRUTH_NAMES' order) and the sensor's samples (acc, gyro [N, 3],
    dt [N], gyro_bias [N, 3]) of a scenario for one sensor parameter set and seed: what the
    estimator FMUs get in the testbench for that seed (read-only arrays, shared by a worker's
    runs)."""
    sc = get_scenario(scenario)
    duration = sc.duration if duration is None else float(duration)
    _, t, truth = _truth(sc.id, duration)
    sample = _samples(sc.id, duration, json.dumps({**sensor, "seed": seed}, sort_keys=True))
    return t, truth, sample


def forget() -> None:
    """Drop the kept truth and samples (after a run of millions of samples)."""
    _truth.cache_clear()
    _samples.cache_clear()
