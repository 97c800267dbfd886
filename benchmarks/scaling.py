"""Scaling of `run` with the number of samples: time per sample and peak memory.

Each (estimator, N) runs in a fresh interpreter (`python -m benchmarks.scaling KEY N FILE`), so
that one measurement's memory cannot hide another's: the benchmark recording is tiled to N
samples, the peak-RSS mark is reset (Linux /proc/self/clear_refs; elsewhere the process's
maximum RSS is used) and run() is timed once (several times for N <= 1e4, median). Peak memory
is the growth of the peak RSS over the RSS before run(); the output arrays (roll, pitch, bias,
rejected, and pos, vel for the position filter) must account for nearly all of it: the excess
should not grow with N. (The excess can be slightly negative: `rejected` is allocated zeroed and
its pages stay untouched while no sample is rejected.)
"""

from __future__ import annotations

import gc
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FLAT_FRACTION = 0.05
"""Flat: between the two largest N, the memory beyond the output arrays grows by at most this
fraction of the output arrays' bytes per sample (run() holding one Python object per sample
would grow by several times the outputs)."""


def _status_bytes(field: str) -> int | None:
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def _reset_peak_rss() -> bool:
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as f:
            f.write("5")
        return True
    except OSError:
        return False


def measure(key: str, n: int, recording_file: Path) -> dict[str, Any]:
    """In this process: time and peak memory of ESTIMATORS[key]().run over n tiled samples."""
    import fusion_core

    data = np.load(recording_file)
    idx = np.arange(n) % len(data["dt"])
    acc = np.ascontiguousarray(data["acc"][idx])
    gyro = np.ascontiguousarray(data["gyro"][idx])
    dt = np.ascontiguousarray(data["dt"][idx])
    cls = fusion_core.ESTIMATORS[key]
    cls().run(acc[:100], gyro[:100], dt[:100])  # imports and first-call costs, not timed
    gc.collect()
    exact = _reset_peak_rss()
    rss_before = _status_bytes("VmRSS")
    maxrss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    t0 = time.perf_counter()
    out = cls().run(acc, gyro, dt)
    times = [time.perf_counter() - t0]
    peak = _status_bytes("VmHWM") if exact else None
    if peak is None or rss_before is None:
        exact = False
        rss_before = maxrss_before
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    output_bytes = sum(v.nbytes for v in out.values())
    del out
    for _ in range(4 if n <= 10_000 else 0):
        t0 = time.perf_counter()
        cls().run(acc, gyro, dt)
        times.append(time.perf_counter() - t0)
    growth = max(peak - rss_before, 0)
    return {
        "n": n,
        "us_per_sample": statistics.median(times) / n * 1e6,
        "peak_bytes": growth,
        "output_bytes": output_bytes,
        "excess_bytes": growth - output_bytes,
        "peak_exact": exact,
    }


def scaling(
    keys: tuple[str, ...], sizes: tuple[int, ...], rec: dict[str, np.ndarray]
) -> dict[str, dict[str, Any]]:
    """{estimator: {"runs": [measure() per size], "flat": bool, ...}}, one subprocess each."""
    results: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory(prefix="bench_scaling_") as tmp:
        path = Path(tmp) / "recording.npz"
        np.savez(path, acc=rec["acc_meas"], gyro=rec["gyro_meas"], dt=rec["dt"])
        for key in keys:
            runs = [_measure_in_subprocess(key, n, path) for n in sizes]
            results[key] = {"runs": runs, **flatness(runs)}
    return results


def flatness(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Whether the memory beyond the output arrays stays flat: its growth per extra sample
    between the two largest N (where run()'s fixed-size chunk buffers are full) against
    FLAT_FRACTION of the outputs' bytes per sample."""
    if len(runs) < 2:
        return {"excess_growth_bytes_per_sample": None, "flat": None}
    prev, last = runs[-2], runs[-1]
    growth = (last["excess_bytes"] - prev["excess_bytes"]) / (last["n"] - prev["n"])
    allowed = FLAT_FRACTION * last["output_bytes"] / last["n"]
    return {
        "excess_growth_bytes_per_sample": growth,
        "allowed_growth_bytes_per_sample": allowed,
        "flat": growth <= allowed,
        "time_ratio_largest_to_smallest": last["us_per_sample"] / runs[0]["us_per_sample"],
    }


def _measure_in_subprocess(key: str, n: int, path: Path) -> dict[str, Any]:
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks.scaling", key, str(n), str(path)],
        cwd=REPO, capture_output=True, text=True, timeout=3600,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"scaling run {key} n={n} failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1], int(sys.argv[2]), Path(sys.argv[3]))))
