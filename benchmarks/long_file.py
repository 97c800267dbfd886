"""`imu-fusion estimate` on a long recording: seconds and peak memory beside pyarrow reading
the same file in the same run (the floor: what reading alone costs on this machine).

The recording is written by `long_recording`: ROWS samples at 100 Hz of a sensor turning in
roll and pitch, six significant digits per value as a logger writes them, seeded. The command
runs in a child process of its own (every estimator, the plot, each output format) so that its
peak resident memory is its own.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROWS = 2_000_000
RATE_HZ = 100.0
ESTIMATE_VS_READ = 10.0
"""The aim: estimate with every estimator and the plot in at most this many times pyarrow's
read of the same file."""
PEAK_MB = 600.0
"""The aim: the command's peak resident memory at most this [MB], whatever the length."""

_CHILD = """
import json, resource, sys, time
from testbenches.cli import main
t0 = time.perf_counter()
status = main(sys.argv[1:])
seconds = time.perf_counter() - t0
try:  # this process's own peak: ru_maxrss would carry the parent's over the exec
    with open("/proc/self/status") as f:
        peak_mb = next(int(l.split()[1]) for l in f if l.startswith("VmHWM:")) / 1024.0
except (OSError, StopIteration):
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({"status": status, "seconds": seconds, "peak_mb": peak_mb}))
"""


def long_recording(path: Path, rows: int = ROWS, seed: int = 0) -> Path:
    """A CSV of `rows` samples (time [s], acc [m/s^2], gyro [rad/s]) as a logger writes it."""
    import pyarrow as pa
    import pyarrow.csv as pc

    rng = np.random.default_rng(seed)
    t = np.arange(rows) / RATE_HZ
    roll = 0.6 * np.sin(2 * np.pi * 0.2 * t) * np.sin(2 * np.pi * 0.011 * t)
    pitch = 0.4 * np.sin(2 * np.pi * 0.13 * t + 1.0)
    g = 9.80665
    acc = np.column_stack([-g * np.sin(pitch), g * np.cos(pitch) * np.sin(roll),
                           g * np.cos(pitch) * np.cos(roll)]) + rng.normal(0, 0.05, (rows, 3))
    gyro = np.column_stack([np.gradient(roll, t), np.gradient(pitch, t), np.zeros(rows)])
    gyro += rng.normal(0.0, 0.005, (rows, 3))
    columns = {"time": np.round(t, 2)}
    columns.update({f"acc_{a}": np.round(acc[:, i], 4) for i, a in enumerate("xyz")})
    columns.update({f"gyro_{a}": np.round(gyro[:, i], 6) for i, a in enumerate("xyz")})
    pc.write_csv(pa.table(columns), path)
    return path


_READ_CHILD = """
import sys, time
import pyarrow.csv as pc
best = float("inf")
for _ in range(int(sys.argv[2])):
    t0 = time.perf_counter()
    pc.read_csv(sys.argv[1])
    best = min(best, time.perf_counter() - t0)
print(best)
"""


def _pyarrow_read_s(path: Path, repeats: int) -> float:
    """pyarrow's read of the file [s], best of `repeats`, in a child process of its own as each
    of the command's runs is: neither side of the ratio then carries the state the suite's
    other sections leave in its own process (a Dask cluster started and stopped, FMUs loaded,
    threads of several libraries)."""
    proc = subprocess.run([sys.executable, "-c", _READ_CHILD, str(path), str(repeats)],
                          capture_output=True, text=True, check=True)
    return float(proc.stdout.strip().splitlines()[-1])


def _estimators_alone_s(path: Path) -> dict[str, float]:
    """Seconds of each estimator's C twin the command runs, on the file's samples already in
    memory (no reading, conditioning, writing or plot): what the command cannot go below but by
    running them on more cores. An estimator whose outputs another's run gives is not run
    there, nor here (testbenches.estimate.runs.shared_runs)."""
    import pyarrow.csv as pc

    from fusion_core import native
    from fusion_core.registry import REGISTRY
    from testbenches.estimate import shared_runs

    table = pc.read_csv(path)
    acc = np.column_stack([table[f"acc_{a}"].to_numpy() for a in "xyz"])
    gyro = np.column_stack([table[f"gyro_{a}"].to_numpy() for a in "xyz"])
    dt = np.full(len(acc), 1.0 / RATE_HZ)
    seconds = {}
    given = shared_runs({entry.key: entry.cls() for entry in REGISTRY})
    for entry in REGISTRY:
        if not native.available() or entry.twin is None or entry.key in given:
            continue
        t0 = time.perf_counter()
        native.run(entry.cls(), acc, gyro, dt)
        seconds[entry.key] = time.perf_counter() - t0
    return seconds


def _estimate(path: Path, out: Path, *extra: str) -> dict[str, Any]:
    """One run of the command in a child process into a folder of its own (a file replaced in
    place would be flushed first), removed afterwards: a run writes several times the input."""
    try:
        proc = subprocess.run([sys.executable, "-c", _CHILD, "estimate", str(path), "--out",
                               str(out), *extra], capture_output=True, text=True, check=False)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    got = json.loads(proc.stdout.strip().splitlines()[-1]) if proc.returncode == 0 else {}
    if got.get("status") != 0:
        raise RuntimeError(f"imu-fusion estimate failed: {proc.stderr.strip()[-400:]}")
    return dict(got)


def estimate_section(tmp: Path, rows: int = ROWS, repeats: int = 3,
                     runs_per_format: int = 2) -> dict[str, Any]:
    """Seconds and peak MB of `imu-fusion estimate` (every estimator and the plot) per output
    format, each beside pyarrow's read of the same file (best of `repeats`) timed just before
    it, and the estimators' C twins alone on its samples, in the same run. A read timed once
    for all three would compare runs with a machine whose load has changed since: pyarrow's
    read takes every core and slows twice over where another process holds one, the command
    by less, and the ratio then flatters it. The command's seconds are the best of
    `runs_per_format` runs (its peak the largest), as the read's are the best of its: a best
    of three against a single run would charge the command with whatever else ran then."""
    path = long_recording(tmp / "long.csv", rows)
    alone = _estimators_alone_s(path)
    runs = {}
    for fmt in ("csv", "parquet", "hdf5"):
        read = _pyarrow_read_s(path, repeats)
        tries = [_estimate(path, tmp / f"out_{fmt}_{i}", "--format", fmt)
                 for i in range(max(1, runs_per_format))]
        got = min(tries, key=lambda run: run["seconds"])
        got["peak_mb"] = max(run["peak_mb"] for run in tries)
        got["runs_s"] = [run["seconds"] for run in tries]
        got["pyarrow_read_s"] = read
        got["vs_pyarrow_read"] = got["seconds"] / read
        runs[fmt] = got
    read_s = min(run["pyarrow_read_s"] for run in runs.values())
    return {"rows": rows, "file_mb": path.stat().st_size / 1e6, "pyarrow_read_s": read_s,
            "estimators_alone_s": alone, "estimators_alone_sum_s": sum(alone.values()),
            "estimators_alone_vs_pyarrow_read": sum(alone.values()) / read_s, "runs": runs}
