"""The `native` section: fusion_core's C twin against the Python core and VQF's C++ batch.

run_us_per_sample: Estimator.run(backend="native") over the recording repeated to at least
MIN_SAMPLES samples (BenchConfig.native_samples; the C batch run, chunked by the binding), per
sample, median of the passes; python_run_us_per_sample: run(backend="python") over a slice of
PYTHON_SAMPLES (BenchConfig.python_samples), the core this process imported (the Python
reference); speedup_vs_python their ratio; vqf_batch_us_per_sample: VQF's C++ updateBatch on the
same samples (the fastest public 6D filter's own batch loop), when the vqf package is installed.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from fusion_core import ESTIMATORS, native
from fusion_core.registry import KEYS, REGISTRY

from .config import MIN_SAMPLES, PYTHON_SAMPLES

NATIVE_TARGETS_US = {e.key: e.bench.native_us for e in REGISTRY}
"""Per-sample targets of the native batch run [us] (the registry's Bench)."""
VQF_RATIO_TARGETS = {e.key: e.bench.vqf_ratio for e in REGISTRY}
"""Each twin's batch run per sample as a multiple of VQF's C++ `updateBatch` in the same run,
at most (the registry's Bench; one pass moves by up to 15 % on a busy machine: `python -m
benchmarks.batch_ratio` gives the median over rounds)."""


def _median_seconds(fn: Any, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def tiled(rec: dict[str, np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    idx = np.arange(n) % len(rec["dt"])
    return (np.ascontiguousarray(rec["acc_meas"][idx]),
            np.ascontiguousarray(rec["gyro_meas"][idx]), np.ascontiguousarray(rec["dt"][idx]))


def vqf_batch_us(rec: dict[str, np.ndarray], repeats: int, samples: int = MIN_SAMPLES
                 ) -> float | str:
    """VQF's updateBatch per sample [us] over the recording repeated to `samples`, or why it
    could not run."""
    try:
        from vqf import VQF
    except ImportError as err:
        return f"ImportError: {err}"
    acc, gyro, dt = tiled(rec, samples)
    seconds = _median_seconds(lambda: VQF(float(dt[0])).updateBatch(gyro, acc), repeats)
    return seconds / len(dt) * 1e6


def native_section(rec: dict[str, np.ndarray], repeats: int, samples: int = MIN_SAMPLES,
                   python_samples: int = PYTHON_SAMPLES) -> dict[str, Any]:
    """The native section of bench.json (see the module docstring)."""
    if not native.available():
        return {"available": False, "reason": native.reason()}
    acc, gyro, dt = tiled(rec, max(samples, len(rec["dt"])))
    n = len(dt)
    out: dict[str, Any] = {"available": True, "samples": n, "run_us_per_sample": {},
                           "python_run_us_per_sample": {}, "speedup_vs_python": {},
                           "no_twin_yet": []}
    for key in KEYS:
        cls = ESTIMATORS[key]
        if not native.has_twin(cls()):
            out["no_twin_yet"].append(key)
            continue
        cls().run(acc[:100], gyro[:100], dt[:100], backend="native")  # first-call costs
        c = _median_seconds(lambda cls=cls: cls().run(acc, gyro, dt, backend="native"),
                            repeats) / n * 1e6
        m = python_samples
        py = _median_seconds(
            lambda cls=cls, m=m: cls().run(acc[:m], gyro[:m], dt[:m], backend="python"),
            max(1, repeats // 2)) / m * 1e6
        out["run_us_per_sample"][key] = c
        out["python_run_us_per_sample"][key] = py
        out["speedup_vs_python"][key] = py / c
    vqf = vqf_batch_us(rec, repeats, samples)
    out["vqf_batch_us_per_sample"] = vqf if isinstance(vqf, float) else None
    if not isinstance(vqf, float):
        out["vqf_unavailable"] = vqf
    return out
