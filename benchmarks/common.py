"""Shared pieces: the benchmark recording, the timing loop, machine information."""

from __future__ import annotations

import gc
import os
import platform
import statistics
import sys
import sysconfig
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from importlib import metadata
from typing import Any

import numpy as np

from fusion_core import synthetic
from fusion_core.scenarios import get_scenario

SCENARIO = "moderate_dynamics"
RATE_HZ = 100.0
SEED = 0


def recording(duration_s: float) -> dict[str, np.ndarray]:
    """The benchmark's 100 Hz recording: moderate_dynamics with MPU-6050 noise, seed 0."""
    trajectory = get_scenario(SCENARIO).trajectory()
    return synthetic.record(trajectory, duration_s, RATE_HZ, noise=synthetic.MPU6050, seed=SEED)


def samples(rec: dict[str, np.ndarray]) -> list[tuple[list[float], list[float], float]]:
    """The recording as (acc, gyro, dt) per sample, in plain Python floats."""
    return list(zip(rec["acc_meas"].tolist(), rec["gyro_meas"].tolist(), rec["dt"].tolist(),
                    strict=True))


@contextmanager
def gc_off() -> Iterator[None]:
    """The garbage collector off while timing (as timeit does), back on afterwards."""
    was_on = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        if was_on:
            gc.enable()


def time_interleaved(
    factories: dict[str, Callable[[], Callable[[], int]]], repeats: int
) -> dict[str, dict[str, Any]]:
    """Time `repeats` passes of each candidate, taken in turn (a, b, c, a, b, c, ...): a slow
    spell of the machine (other processes) then hits every candidate alike, which keeps their
    ratios and differences meaningful. A factory builds a pass (set-up, not timed); the pass
    returns how many calls it made. Returns, per candidate, the median, min and max us per call
    and every pass's figure."""
    per_call: dict[str, list[float]] = {name: [] for name in factories}
    for _ in range(repeats):
        for name, make_pass in factories.items():
            run_pass = make_pass()
            with gc_off():
                t0 = time.perf_counter()
                calls = run_pass()
                elapsed = time.perf_counter() - t0
            per_call[name].append(elapsed / max(calls, 1) * 1e6)
    return {name: summary(values) for name, values in per_call.items()}


def summary(values_us: list[float]) -> dict[str, Any]:
    return {
        "median_us": statistics.median(values_us),
        "min_us": min(values_us),
        "max_us": max(values_us),
        "passes_us": [round(v, 4) for v in values_us],
    }


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def load_average() -> list[float] | None:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return None


def calibration_ns(iterations: int = 200_000, repeats: int = 5) -> float:
    """ns per iteration of a fixed pure-Python float loop (3 float operations and a loop step):
    a yardstick for comparing timings taken on different machines or at different loads."""
    def loop() -> float:
        x, a, b = 0.5, 0.999, 1e-3
        for _ in range(iterations):
            x = x * a + b - 1e-9
        return x

    times = []
    for _ in range(repeats):
        with gc_off():
            t0 = time.perf_counter()
            loop()
            times.append(time.perf_counter() - t0)
    return statistics.median(times) / iterations * 1e9


def machine_info() -> dict[str, Any]:
    """What the timings depend on: CPU, cores, interpreter and its build, package versions, and
    the load average (other processes on the machine slow the measurement down)."""
    config_args = sysconfig.get_config_var("CONFIG_ARGS") or ""
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    return {
        "cpu": _cpu_model(),
        "cpu_count": os.cpu_count(),
        "usable_cpus": usable,
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "implementation": platform.python_implementation(),
        "python_pgo_lto": "--enable-optimizations" in config_args or "--with-lto" in config_args,
        "python_config_args": config_args,
        "packages": {
            name: _version(name)
            for name in ("numpy", "scipy", "fmpy", "pythonfmu", "filterpy", "ahrs", "imufusion",
                         "vqf")
        },
        "load_average_start": load_average(),
        "calibration_ns_per_loop": calibration_ns(),
    }
