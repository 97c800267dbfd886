"""One campaign run: plant -> sensor -> estimator, scored by the contract's metrics.

By default through fusion_core: the scenario's truth (fusion_core.native.plant_truth, the C
twin of the plant FMU, or the Python trajectory where there is no twin), the sensor model's
batch run and the estimator's batch run (the C twins where built). A worker keeps the last
scenarios' truth and the last seeds' samples (testbenches.samples): they do not depend on the
estimator, and the plan puts the estimators of one seed next to each other. The data flow is the
testbench master's (docs/interface.md, Timing): the truth at t_k, the sensor's sample at t_k
with dt = h, the estimate for that sample; so a run gives what the three FMUs give for the same
seed, at the C twins' speed (tests/test_montecarlo.py compares them). With fmu=True the run is
the FMU testbench itself (testbenches.master.run_testbench through fmpy).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.registry import create
from fusion_core.scenarios import get_scenario
from fusion_core.synthetic import TRUTH_NAMES

from ..contract import compute_metrics
from ..master import ESTIMATE, POSITION, SAMPLE, TestbenchResult
from ..samples import RATE, scenario_samples
from .plan import Run

METRICS = ("rmse_roll_deg", "rmse_pitch_deg", "max_err_deg", "bias_err_dps", "invalid_samples",
           "samples")
"""The contract metrics each row keeps."""


def _calibration(run: Run) -> dict[str, float]:
    """The part's calibration where the run calibrates first, else none."""
    if not run.calibrate_first:
        return {}
    from ..calibrate.part import part_calibration

    return part_calibration(run.sensor, run.seed)


def simulate(run: Run) -> TestbenchResult:
    """The run's traces, as the FMU testbench's result (metrics not yet computed)."""
    sc = get_scenario(run.scenario)
    t, truth, sample = scenario_samples(sc.name, run.seed, run.sensor, run.duration)
    sensor_params = {**run.sensor, "seed": run.seed}
    params = {"gyro_sampling": sensor_params.get("gyro_sampling", "point"),
              **_calibration(run), **run.params}
    est = create(run.estimator, params)
    out = est.run(sample["acc"], sample["gyro"], sample["dt"])
    # the master's names, as views of the runs' own arrays (nothing is copied)
    estimate = dict(zip(ESTIMATE, (out["roll"], out["pitch"], *out["bias"].T), strict=True))
    if est.HAS_POSITION:
        estimate.update(zip(POSITION, (*out["pos"].T, *out["vel"].T), strict=True))
    samples = (*sample["acc"].T, *sample["gyro"].T, sample["dt"])
    return TestbenchResult(
        estimator=run.estimator, scenario=sc.name, seed=run.seed, rate=RATE, jitter=0.0,
        params=params, sensor_params=sensor_params, t=t,
        truth={n: truth[:, i] for i, n in enumerate(TRUTH_NAMES)},
        sample=dict(zip(SAMPLE, samples, strict=True)),
        estimate=estimate, invalid_samples=int(np.sum(out["rejected"])),
        step_us=np.zeros(len(t)), true_gyro_bias=tuple(sample["gyro_bias"][-1].tolist()),
    )


def run_row(run: Run, fmu_dir: Path | str | None = None) -> dict[str, Any]:
    """One Parquet row: the run's identity, its varied parameters and its metrics."""
    t0 = time.perf_counter()
    if run.fmu:
        from ..fmus import kind_dir
        from ..master import run_testbench

        result = run_testbench(run.estimator, run.scenario, seed=run.seed,
                               duration=run.duration, rate=RATE,
                               params={**_calibration(run), **run.params},
                               sensor_params=run.sensor, fmu_dir=kind_dir(fmu_dir or "dist"),
                               evaluate=False)
    else:
        result = simulate(run)
    m = compute_metrics(result)
    row: dict[str, Any] = {"key": run.key, "estimator": run.estimator,
                           "scenario": run.scenario, "seed": run.seed, "status": "ok",
                           "error": "", "attempts": 1}
    row.update({f"vary_{k}": float(v) for k, v in run.varied.items()})
    row.update({k: float(m[k]) for k in METRICS})
    row["seconds"] = time.perf_counter() - t0
    return row

