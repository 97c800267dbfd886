"""Throughput of the three-FMU testbench (ImuPlant -> ImuSensor -> estimator, testbenches.master).

Wall time of run_testbench(evaluate=False) over the benchmark scenario, less that of a one-step
run (instantiation, initialisation and freeing are not stepping): steps per second and the
real-time factor (simulated seconds per wall second) at each rate. The master's own per-step
time of the estimator FMU (set + doStep + get) shows how much of a step is the estimator's.
The process's CPU time per step is reported beside the wall time: on a busy machine the wall
time also counts the time other processes held the CPU, the CPU time does not.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import Any

from testbenches.master import run_testbench

from .common import SCENARIO, gc_off


def _timed_run(
    key: str, duration: float, rate: float, fmu_dir: Path
) -> tuple[float, float, Any]:
    """Wall and CPU seconds of one run, and its result."""
    with gc_off():
        t0, c0 = time.perf_counter(), time.process_time()
        result = run_testbench(key, SCENARIO, duration=duration, rate=rate, fmu_dir=fmu_dir,
                               evaluate=False)
        return time.perf_counter() - t0, time.process_time() - c0, result


def testbench_rate(
    key: str, rate: float, duration: float, fmu_dir: Path, repeats: int
) -> dict[str, Any]:
    """Steps per second and real-time factor of one estimator's testbench at one rate."""
    setups = [_timed_run(key, 1.0 / rate, rate, fmu_dir)[:2] for _ in range(2)]
    setup_s, setup_cpu_s = min(s[0] for s in setups), min(s[1] for s in setups)
    steps_per_s = []
    cpu_us = []
    estimator_us = []
    n = 0
    for _ in range(repeats):
        wall, cpu, result = _timed_run(key, duration, rate, fmu_dir)
        n = len(result.t)
        steps_per_s.append((n - 1) / max(wall - setup_s, 1e-9))
        cpu_us.append(max(cpu - setup_cpu_s, 0.0) / max(n - 1, 1) * 1e6)
        estimator_us.append(float(statistics.median(result.step_us)))
    sps = statistics.median(steps_per_s)
    return {
        "steps": n,
        "simulated_s": n / rate,
        "steps_per_s": sps,
        "real_time_factor": sps / rate,
        "us_per_step": 1e6 / sps,
        "cpu_us_per_step": statistics.median(cpu_us),
        "estimator_fmu_us_per_step": statistics.median(estimator_us),
        "setup_s": setup_s,
        "passes_steps_per_s": [round(v, 1) for v in steps_per_s],
    }


def testbench_throughput(
    keys: tuple[str, ...], durations: dict[float, float], fmu_dir: Path, repeats: int
) -> dict[str, dict[str, Any]]:
    """{estimator: {"100Hz": {...}, "1000Hz": {...}}} for every rate in durations."""
    return {
        key: {
            f"{rate:g}Hz": testbench_rate(key, rate, duration, fmu_dir, repeats)
            for rate, duration in durations.items()
        }
        for key in keys
    }
