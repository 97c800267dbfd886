"""The `campaign` section: Monte Carlo throughput on Dask (testbenches.montecarlo).

samples_per_s: simulated IMU samples per second over a whole campaign (plant -> sensor ->
estimator through the native core, every run's samples counted, the LocalCluster's start and
the Parquet writes included) on this machine's cores (2 workers); samples_per_s_1_worker the
same campaign on one worker; scaling their ratio (target >= 1.7 on two cores).
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

SAMPLES_PER_S_TARGET = 5e6
SCALING_TARGET = 1.7


def _throughput(workers: int, seeds: int) -> tuple[float, int, float]:
    from testbenches.campaign import load_sensor
    from testbenches.montecarlo.plan import parse_variation, plan
    from testbenches.montecarlo.runner import execute
    from testbenches.montecarlo.store import read_rows

    runs = plan(["cf", "mgcf", "kf", "ukf", "poskf"], ["moderate_dynamics", "vibration"], seeds,
                [parse_variation("gyro_scale_std=0:0.03")], sensor=load_sensor("realistic"))
    with tempfile.TemporaryDirectory(prefix="bench_campaign_") as tmp:
        stats = execute(runs, Path(tmp), "local", workers, log=lambda s: None)
        samples = sum(r["samples"] for r in read_rows(Path(tmp)))
    return samples / stats["seconds"], len(runs), stats["seconds"]


def campaign_section(seeds: int) -> dict[str, Any]:
    """The campaign section of bench.json (see the module docstring)."""
    try:
        import distributed  # noqa: F401
    except ImportError as err:
        return {"available": False, "reason": f"ImportError: {err}"}
    two, runs, seconds = _throughput(2, seeds)
    one, _, seconds_1 = _throughput(1, seeds)
    return {"available": True, "runs": runs, "samples_per_s": two, "seconds": seconds,
            "samples_per_s_1_worker": one, "seconds_1_worker": seconds_1, "scaling": two / one}
