"""The contract run behind `python -m testbenches run`: estimator x scenario x seed runs through
the FMUs (testbenches.master), plus the contract's T1, T2, T4 and position checks.

Not to be confused with the Monte Carlo campaign of `python -m testbenches campaign`
(testbenches.montecarlo: thousands of seeded runs in fusion_core, on Dask, for statistics)."""

from __future__ import annotations

import contextlib
import functools
import tempfile
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fusion_core.scenarios import ESTIMATION_SCENARIOS

from . import contract
from .fmus import DEFAULT_FMU_DIR, ESTIMATOR_FMUS, extract_under
from .master import TestbenchResult, run_testbench


@dataclass
class ContractResult:
    runs: list[TestbenchResult] = field(default_factory=list)
    checks: list[contract.Check] = field(default_factory=list)
    """Campaign-level checks (T1, T2, T4, position); per-run checks live on each run."""

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks) and all(r.passed for r in self.runs)


@dataclass(frozen=True)
class Job:
    kind: str  # "run"; contract extras: "t1", "t2_fixed", "t2_jitter", "t4"
    estimator: str
    scenario: str
    seed: int
    jitter: float = 0.0
    sensor_params: tuple[tuple[str, Any], ...] = ()


def contract_jobs(
    estimators: Sequence[str], scenarios: Sequence[str], *, seeds: int = 1, jitter: float = 0.0,
    contract_checks: bool = True,
) -> list[Job]:
    """The runs of a contract run: every estimator x scenario x seed, then the contract's
    extras."""
    jobs = [Job("run", e, s, seed, jitter) for s in scenarios for e in estimators
            for seed in range(seeds)]
    if not contract_checks:
        return jobs
    noise_free = tuple(contract.NOISE_FREE.items())
    for e in estimators:
        jobs += [Job("t1", e, s, 0, 0.0, noise_free) for s in contract.T1_SCENARIOS]
        jobs.append(Job("t2_fixed", e, contract.T2_SCENARIO, 0, 0.0, noise_free))
        jobs.append(Job("t2_jitter", e, contract.T2_SCENARIO, 0, contract.T2_JITTER, noise_free))
        jobs += [Job("t4", e, contract.T4_SCENARIO, 0)] * 2
    if "poskf" in estimators:
        done = {j.seed for j in jobs if j.kind == "run" and j.estimator == "poskf"
                and j.scenario == "translation_2m" and j.jitter == 0.0}
        jobs += [Job("position", "poskf", "translation_2m", seed)
                 for seed in range(contract.POSITION_SEEDS) if seed not in done]
    return jobs


def run_contract(
    *,
    estimators: Sequence[str] = tuple(ESTIMATOR_FMUS),
    scenarios: Sequence[str] = ESTIMATION_SCENARIOS,
    seeds: int = 1,
    jitter: float = 0.0,
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
    progress: Callable[[Job], None] | None = None,
    contract_checks: bool = True,
    params: dict[str, Any] | None = None,
    duration: float | None = None,
    timing: bool = True,
    jobs: int = 1,
    preset: dict[str, dict[str, Any]] | None = None,
    sensor: dict[str, Any] | None = None,
    calibrate_first: bool = False,
    master: str = "gauss-seidel",
    parts: int = 0,
    parts_progress: Callable[[], None] | None = None,
) -> ContractResult:
    """Run the runs and evaluate the contract; `progress` is called after each run; `params`
    are estimator FMU parameters for every run (each estimator must have them); `duration`
    replaces each scenario's own duration in the runs (not in the contract's extras); timing=False
    leaves the wall-clock check T3 out of the verdict (its figures are still reported); jobs > 1
    runs that many worker processes (one run per process at a time, so T3 stays per core);
    `preset` holds each estimator's parameters (presets.load_preset; `params` go on top) and
    `sensor` the ImuSensor parameters of every run but the contract's noise-free ones;
    calibrate_first: each seed's part is calibrated on its own calibration session first, and
    its runs apply the result (testbenches.calibrate.part; not the noise-free extras, whose
    sensor has no part errors); master: how every run steps its FMUs (master.MASTERS); parts:
    with the contract's checks, each accuracy check also over that many sensor parts, as
    delivered and calibrated first (testbenches.parts; 0: none)."""
    out = ContractResult()
    extra: dict[tuple[str, str], list[TestbenchResult]] = {}
    jobs_list = contract_jobs(estimators, scenarios, seeds=seeds, jitter=jitter,
                              contract_checks=contract_checks)
    part: dict[int, dict[str, float]] = {}
    if calibrate_first:
        from .calibrate.part import part_calibration

        part = {seed: part_calibration(sensor or {}, seed)
                for seed in sorted({j.seed for j in jobs_list if j.kind == "run"})}
    run_one = functools.partial(_run_job, params=params, fmu_dir=fmu_dir, duration=duration,
                                timing=timing, preset=preset or {}, sensor=sensor or {},
                                part=part, master=master)
    with contextlib.ExitStack() as stack:
        if jobs > 1:
            root = stack.enter_context(tempfile.TemporaryDirectory(prefix="campaign_"))
            pool = stack.enter_context(ProcessPoolExecutor(
                jobs, initializer=extract_under, initargs=(root,)))
            results = pool.map(run_one, jobs_list)
        else:
            results = map(run_one, jobs_list)
        for job, r in zip(jobs_list, results, strict=True):
            _collect(out, extra, job, r)
            if progress:
                progress(job)
    if not contract_checks:
        return out
    for e in estimators:
        out.checks.append(contract.check_t1(extra[("t1", e)]))
        out.checks.append(contract.check_delay(extra[("t1", e)]))
        out.checks.append(contract.check_t2(extra[("t2_fixed", e)][0],
                                            extra[("t2_jitter", e)][0]))
        out.checks.append(contract.check_t4(*extra[("t4", e)]))
    if "poskf" in estimators:
        pos = [r for r in out.runs if r.estimator == "poskf" and r.scenario == "translation_2m"
               and r.jitter == 0.0] + extra.get(("position", "poskf"), [])
        out.checks += contract.check_position(pos)
    if parts:
        from .parts import part_rmse, parts_checks

        out.checks += parts_checks(part_rmse(estimators, scenarios, preset or {}, sensor or {},
                                             parts, params, parts_progress, bounded_only=True))
    return out


def _run_job(job: Job, params: dict[str, Any] | None, fmu_dir: Path | str,
             duration: float | None, timing: bool, preset: dict[str, dict[str, Any]],
             sensor: dict[str, Any], part: dict[int, dict[str, float]],
             master: str) -> TestbenchResult:
    sensor_params = dict(job.sensor_params) if job.sensor_params else dict(sensor)
    calibration = part.get(job.seed, {}) if job.kind == "run" else {}
    run_params = {**preset.get(job.estimator, {}), **calibration, **(params or {})}
    r = run_testbench(job.estimator, job.scenario, seed=job.seed, jitter=job.jitter,
                      params=run_params, sensor_params=sensor_params, fmu_dir=fmu_dir,
                      duration=duration if job.kind == "run" else None, evaluate=False,
                      master=master)
    return contract.evaluate(r, timing)


def _collect(out: ContractResult, extra: dict[tuple[str, str], list[TestbenchResult]],
             job: Job, r: TestbenchResult) -> None:
    """File a finished run: a campaign run, or one of the contract's extras."""
    if job.kind == "run":
        out.runs.append(r)
    else:
        extra.setdefault((job.kind, job.estimator), []).append(r)
