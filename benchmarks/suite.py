"""run_benchmarks: every section of the benchmark, in one process, into one JSON-ready dict."""

from __future__ import annotations

import datetime
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.base import Estimator
from fusion_core.types import Estimate

from .campaign import campaign_section
from .common import (
    RATE_HZ,
    SCENARIO,
    load_average,
    machine_info,
    recording,
    samples,
    time_interleaved,
)
from .config import BenchConfig, estimator_keys
from .estimators import STREAM, step_factories, stream_factories
from .fmu import build_fmus, fmu_steps
from .long_file import estimate_section
from .native import native_section
from .native_fmu import native_fmu_section
from .peers import PEERS, available_peers
from .report import evaluate_targets
from .scaling import scaling
from .testbench import testbench_throughput

SCHEMA = 1


FLOOR = "(step API floor)"


class _NoOpEstimator(Estimator):
    """An estimator whose update does nothing: what the step API itself costs."""

    def _reset(self) -> None:
        pass

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        pass

    def _estimate(self) -> Estimate:
        return _ZERO

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        return _ZERO  # the one hook the step API calls per sample, as every estimator has it


_ZERO = Estimate(0.0, 0.0, (0.0, 0.0, 0.0))


def _noop_pass(data: list[tuple[list[float], list[float], float]]) -> Any:
    step = _NoOpEstimator().step

    def run() -> int:
        for acc, gyro, dt in data:
            step(acc, gyro, dt)
        return len(data)

    return run


def core_info() -> dict[str, Any]:
    """What this process runs: fusion_core's Python step, and whether the C twin is loaded
    (run() and the pythonfmu FMUs' steps go through it then)."""
    from fusion_core import native

    return {"kind": "python", "native": native.available(), "native_reason": native.reason()}


def run_benchmarks(config: BenchConfig, log: Any = print) -> dict[str, Any]:
    """Run the sections named in config.sections; return the results (see benchmarks/__init__)."""
    keys = estimator_keys()
    rec = recording(config.duration_s)
    data = samples(rec)
    n = len(data)
    results: dict[str, Any] = {
        "schema": SCHEMA,
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "quick": config.quick,
        "repeats": config.repeats,
        "recording": {"scenario": SCENARIO, "rate_hz": RATE_HZ, "samples": n,
                      "noise": "MPU-6050", "seed": 0},
        "machine": machine_info(),
        "core": core_info(),
    }
    if "per_sample" in config.sections:
        log(f"per-sample timing: {len(keys)} estimators and the peers, {n} samples x "
            f"{config.repeats} passes, in turn")
        factories = step_factories(keys, data)
        factories.update(stream_factories(keys, data))
        unavailable = {name: "not run (peers switched off)" for name in PEERS}
        if config.peers:
            peer_factories, unavailable = available_peers(rec)
            factories.update(peer_factories)
        factories[FLOOR] = lambda: _noop_pass(data)
        detail = time_interleaved(factories, config.repeats)
        floor = detail.pop(FLOOR)
        results["per_sample_us"] = {
            key: (detail[key]["median_us"] if key in detail else None)
            for key in (*keys, *PEERS)
        }
        results["per_sample_us_stream"] = {
            key: (detail[key + STREAM]["median_us"] if key + STREAM in detail else None)
            for key in keys
        }
        results["per_sample_detail"] = detail
        results["peers_unavailable"] = unavailable
        results["step_floor_us"] = floor["median_us"]
    native_fmus: dict[str, Any] = {}
    if {"fmu", "testbench", "native"} & set(config.sections):
        with tempfile.TemporaryDirectory(prefix="bench_fmus_") as tmp:
            fmu_dir = config.fmu_dir
            if fmu_dir is None:
                log("building the FMUs (build_fmu.py)")
                fmu_dir = build_fmus(Path(tmp))
            results["fmu_dir"] = str(config.fmu_dir) if config.fmu_dir else "(built, temporary)"
            if "fmu" in config.sections:
                log("FMU step timing (fusion_core, fmpy API and low-level host in turn)")
                fmu_data = np.column_stack(
                    [rec["acc_meas"], rec["gyro_meas"], rec["dt"]]).tolist()
                timings = fmu_steps(keys, fmu_dir, fmu_data, data, config.repeats)
                results["fmu_step_detail"] = timings
                med = {k: {h: v[h]["median_us"] for h in v} for k, v in timings.items()}
                results["fmu_step_us"] = {k: m["api"] for k, m in med.items()}
                results["fmu_step_lowlevel_us"] = {k: m["lowlevel"] for k, m in med.items()}
                results["fmu_core_us"] = {k: m["core"] for k, m in med.items()}
                results["fmu_overhead_us"] = {k: m["api"] - m["core"] for k, m in med.items()}
                results["fmu_overhead_lowlevel_us"] = {
                    k: m["lowlevel"] - m["core"] for k, m in med.items()}
                # The floor FMU (benchmarks/fmu.py) timed beside each estimator: what fmpy and
                # pythonfmu's wrapper cost per step with no slave work behind them.
                results["fmu_floor_us"] = {
                    k: {"api": m.get("floor_api"), "lowlevel": m.get("floor_lowlevel")}
                    for k, m in med.items()}
            if "native" in config.sections:
                fmu_data = np.column_stack(
                    [rec["acc_meas"], rec["gyro_meas"], rec["dt"]]).tolist()
                native_fmus = native_fmu_section(
                    keys, Path(fmu_dir), fmu_data, config.repeats,
                    config.testbench_s.get(1000.0, 1.0), config.testbench_repeats, log)
            if "testbench" in config.sections:
                log("testbench throughput")
                results["testbench"] = testbench_throughput(
                    estimator_keys(config.testbench_estimators), config.testbench_s, fmu_dir,
                    config.testbench_repeats)
    if "native" in config.sections:
        log("native batch runs (the C twin), the Python core and VQF's C++ batch")
        results["native"] = native_section(rec, config.repeats, config.native_samples,
                                           config.python_samples)
        results["native"].update(native_fmus)
        host, twin = native_fmus.get("c_host_step_us", {}), results["native"].get(
            "run_us_per_sample", {})
        results["native"]["c_host_vs_twin"] = {
            key: host["fmi2"][key] / twin[key] for key in twin if key in host.get("fmi2", {})}
    if "campaign" in config.sections:
        log("campaign throughput on a local Dask cluster (2 workers, then 1)")
        results["campaign"] = campaign_section(config.campaign_seeds, config.campaign_passes)
    if "scaling" in config.sections:
        log(f"scaling of run(): N = {', '.join(f'{s:g}' for s in config.scaling_sizes)}")
        results["scaling"] = scaling(estimator_keys(config.scaling_estimators),
                                     config.scaling_sizes, rec)
    if "estimate_2e6" in config.sections:
        log(f"imu-fusion estimate on a {config.long_rows}-row CSV, beside pyarrow's read of it")
        with tempfile.TemporaryDirectory(prefix="bench_long_") as tmp:
            results["estimate_2e6"] = estimate_section(Path(tmp), config.long_rows)
    results["machine"]["load_average_end"] = load_average()
    results["targets"] = evaluate_targets(results)
    return results
