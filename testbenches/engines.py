"""The testbench chain in the co-simulation engines users run: DNV's libcosim (libcosimpy, FMI
2.0) and NTNU's Ecos (ecospy, FMI 2.0 and 3.0).

`run_engine` wires ImuPlant -> ImuSensor -> one estimator FMU in the engine, as an integrator
would (the plant's truth to the sensor's inputs, the sensor's sample to the estimator's
inputs, the parameters set by name), steps it at a fixed step and records every output after
every step. Both engines are Jacobi masters: every FMU steps on the others' outputs of the
previous step. So the result is aligned as the project's own Jacobi master aligns its runs
(master.aligned_result), the contract's checks apply unchanged, and a run equals
`run_testbench(..., master="jacobi")` bit for bit (tests/test_engines.py).

Neither engine is a dependency of the estimators: the `engines` extra installs both
(`pip install '.[engines]'`); Ecos needs the TBB runtime (Debian's libtbb12). `engine_reason`
says what is missing and how to install it.
"""

from __future__ import annotations

import contextlib
import ctypes.util
import functools
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.scenarios import get_scenario
from fusion_core.synthetic import TRUTH_NAMES
from fusion_core.types import DEG

from .fmus import DEFAULT_FMU_DIR, ESTIMATOR_FMUS, PLANT_FMU, SENSOR_FMU, fmu_path
from .master import (
    ESTIMATE,
    POSITION,
    SAMPLE,
    SENSOR_IN,
    TestbenchResult,
    aligned_result,
    communication_steps,
)

ENGINES = {"libcosim": (2,), "ecos": (2, 3)}
"""Each engine and the FMI versions it runs."""
INSTALL = "pip install '.[engines]' (libcosimpy, ecospy); Ecos also needs apt-get install libtbb12"


def engine_reason(engine: str) -> str | None:
    """Why `engine` cannot run here (a missing package or library, with the install line), or
    None when it can."""
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}: allowed {', '.join(ENGINES)}")
    module = {"libcosim": "libcosimpy", "ecos": "ecospy"}[engine]
    if engine == "ecos" and ctypes.util.find_library("tbb") is None:
        return f"Ecos needs the TBB runtime (libtbb.so.12), not found: {INSTALL}"
    try:
        __import__(module)
    except (ImportError, OSError) as err:
        return f"{module} cannot be imported ({err}): {INSTALL}"
    return None


def chain_fmus(estimator: str, fmu_dir: Path | str, fmi: int) -> dict[str, Path]:
    """The three FMUs of the chain by component name, native FMI `fmi` ones under fmu_dir
    (build_fmu.py --out fmu_dir: fmu_dir/native/fmi2, fmu_dir/native/fmi3)."""
    folder = Path(fmu_dir) / "native" / f"fmi{fmi}"
    names = {"plant": PLANT_FMU, "sensor": SENSOR_FMU, "estimator": ESTIMATOR_FMUS[estimator]}
    return {component: fmu_path(name, folder) for component, name in names.items()}


WIRES = [("plant", n, "sensor", n) for n in SENSOR_IN] + [
    ("sensor", n, "estimator", n) for n in SAMPLE]
"""The chain's connections: (from component, variable, to component, variable)."""


def run_engine(
    engine: str,
    estimator: str,
    scenario: str | int,
    seed: int = 0,
    *,
    fmi: int = 2,
    duration: float | None = None,
    rate: float = 100.0,
    params: Mapping[str, Any] | None = None,
    sensor_params: Mapping[str, Any] | None = None,
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
    evaluate: bool = True,
) -> TestbenchResult:
    """Run plant -> sensor -> estimator in `engine` (ENGINES) with the native FMI `fmi` FMUs.

    params and sensor_params are FMU parameters by name (Real, Integer, Boolean values);
    the sensor's seed is set from `seed`. Returns the traces aligned by the Jacobi chain's
    delay, and with evaluate=True the contract's metrics and checks (T3 measures the whole
    engine step, not the estimator alone, and is left out)."""
    if fmi not in ENGINES[engine]:
        raise ValueError(f"{engine} runs FMI {', '.join(map(str, ENGINES[engine]))}, not {fmi}")
    if estimator not in ESTIMATOR_FMUS:
        raise ValueError(f"unknown estimator {estimator!r}: allowed {', '.join(ESTIMATOR_FMUS)}")
    values: dict[str, dict[str, Any]] = {
        "plant": {"scenario": get_scenario(scenario).id},
        # a Jacobi engine hands the sensor the plant's outputs of the step before
        "sensor": {**(sensor_params or {}), "seed": seed, "inputs_at": 2},
        "estimator": dict(params or {}),
    }
    return _run(engine, f"FMI {fmi}.0", chain_fmus(estimator, fmu_dir, fmi), values, estimator,
                scenario, seed, duration, rate, evaluate)


Rows = dict[str, np.ndarray]


def run_ssp(engine: str, ssp: Path | str, estimator: str, scenario: str | int, seed: int = 0,
            *, duration: float | None = None, rate: float = 100.0, evaluate: bool = True
            ) -> TestbenchResult:
    """Run an SSP of testbenches.ssp.export_ssp in `engine` as the engine loads it (its
    parameters from its own parameter sets); estimator, scenario and seed say what it was
    exported with, for the result's labels and the truth at the start. The result is aligned
    and evaluated as run_engine's."""
    return _run(engine, "SSP", Path(ssp), {}, estimator, scenario, seed, duration, rate,
                evaluate)


def _run(engine: str, how: str, source: Mapping[str, Path] | Path,
         values: Mapping[str, Mapping[str, Any]], estimator: str, scenario: str | int, seed: int,
         duration: float | None, rate: float, evaluate: bool) -> TestbenchResult:
    """The chain of `source` (FMUs by component, set to `values`, or an SSP file) stepped in
    `engine` at `rate` over the scenario's duration, as a result aligned and evaluated."""
    why = engine_reason(engine)
    if why:
        raise RuntimeError(why)
    sc = get_scenario(scenario)
    duration = sc.duration if duration is None else float(duration)
    n = len(communication_steps(duration, rate, 0.0, seed))
    outputs = {"plant": TRUTH_NAMES, "sensor": SAMPLE,
               "estimator": ESTIMATE + (POSITION if estimator == "poskf" else ())}
    run = {"libcosim": _run_libcosim, "ecos": _run_ecos}[engine]
    t0 = time.process_time()
    rows, invalid = run(source, values, outputs, 1.0 / rate, n)
    return _result(engine, how, estimator, sc.id, seed, rate,
                   dict(values.get("estimator", {})), dict(values.get("sensor", {"seed": seed})),
                   rows, invalid, time.process_time() - t0, evaluate)


def _result(engine: str, how: str, estimator: str, scenario: int, seed: int, rate: float,
            params: dict[str, Any], sensor_params: dict[str, Any], rows: Rows, invalid: int,
            cpu: float, evaluate: bool) -> TestbenchResult:
    n = len(rows["plant"])
    sc = get_scenario(scenario)
    truth_start = np.array(sc.trajectory().truth_at(0.0))
    result = aligned_result(
        estimator, sc.name, seed, rate, 0.0, params, sensor_params, "jacobi",
        np.arange(1, n + 1) / rate, truth_start, rows["plant"], rows["sensor"],
        rows["estimator"], invalid, np.full(n, cpu / n * 1e6), (0.0, 0.0, 0.0))
    result.engine = f"{engine} {how}"
    result.cpu_s = cpu
    if evaluate:
        from .contract import evaluate as evaluate_contract

        evaluate_contract(result, timing=False)
    return result


def _run_libcosim(fmus: Mapping[str, Path] | Path, values: Mapping[str, Mapping[str, Any]],
                  outputs: Mapping[str, tuple[str, ...]], step: float, n: int
                  ) -> tuple[Rows, int]:
    """The chain of `fmus` (by component) with `values` set, or an SSP file as libcosim loads
    it, stepped n times; every output recorded after every step."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    nanoseconds = round(step * 1e9)
    if isinstance(fmus, Path):
        ex = CosimExecution.from_ssp_file(str(fmus), step_size=nanoseconds)
        index = {c: ex.slave_index_from_instance_name(c) for c in outputs}
    else:
        ex = CosimExecution.from_step_size(step_size=nanoseconds)
        index = {c: ex.add_local_slave(CosimLocalSlave(fmu_path=str(p), instance_name=c))
                 for c, p in fmus.items()}
    refs = {c: {v.name.decode(): (v.reference, CosimVariableType(v.type))
                for v in ex.slave_variables(i)} for c, i in index.items()}
    for c, params in values.items():
        for name, value in params.items():
            if name not in refs[c]:
                raise ValueError(f"libcosim: the {c} has no parameter {name!r} it can set "
                                 "(libcosim ignores FMI 2.0 Enumeration variables)")
            vr, kind = refs[c][name]
            setter = {CosimVariableType.REAL: ex.real_initial_value,
                      CosimVariableType.INTEGER: ex.integer_initial_value,
                      CosimVariableType.BOOLEAN: ex.boolean_initial_value}[kind]
            if not setter(index[c], vr, value):
                raise ValueError(f"libcosim refused {c}.{name} = {value!r}")
    if not isinstance(fmus, Path):
        for a, va, b, vb in WIRES:
            ex.connect_real_variables(index[a], refs[a][va][0], index[b], refs[b][vb][0])
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    vrs = {c: [refs[c][v][0] for v in names] for c, names in outputs.items()}
    rows = {c: np.empty((n, len(names))) for c, names in outputs.items()}
    for k in range(n):
        if not ex.step(1):
            raise RuntimeError(f"libcosim: step {k} failed")
        for c in outputs:
            rows[c][k] = observer.last_real_values(index[c], vrs[c])
    invalid = observer.last_integer_values(index["estimator"],
                                           [refs["estimator"]["invalid_samples"][0]])[0]
    return rows, int(invalid)


def _run_ecos(fmus: Mapping[str, Path] | Path, values: Mapping[str, Mapping[str, Any]],
              outputs: Mapping[str, tuple[str, ...]], step: float, n: int
              ) -> tuple[Rows, int]:
    """As _run_libcosim, in Ecos (an SSP's parameter sets named ssp.PARAMETER_SET applied)."""
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    from .ssp import PARAMETER_SET

    EcosLib.set_log_level("warn")
    if isinstance(fmus, Path):
        sim = EcosSimulation(ssp_path=str(fmus), step_size=step)
    else:
        structure = EcosSimulationStructure()
        for c, p in fmus.items():
            structure.add_model(c, str(p))
        for a, va, b, vb in WIRES:
            structure.make_real_connection(f"{a}::{va}", f"{b}::{vb}")
        structure.add_parameter_set(PARAMETER_SET, {
            f"{c}::{k}": v for c, params in values.items() for k, v in params.items()})
        sim = EcosSimulation(structure=structure, step_size=step)
    try:
        sim.init(parameter_set=PARAMETER_SET)
        _check_ecos_parameters(sim, values)
        rows = {c: np.empty((n, len(names))) for c, names in outputs.items()}
        for k in range(n):
            sim.step(1)
            for c, names in outputs.items():
                row = rows[c][k]
                for i, name in enumerate(names):
                    row[i] = sim.get_real(f"{c}::{name}")
        invalid = sim.get_integer("estimator::invalid_samples")
    finally:
        with contextlib.suppress(Exception):
            sim.terminate()
        sim.free()
    return rows, int(invalid)


def _check_ecos_parameters(sim: Any, values: Mapping[str, Mapping[str, Any]]) -> None:
    """Ecos skips a parameter it cannot set with a warning only: read each back."""
    for c, params in values.items():
        for name, value in params.items():
            ident = f"{c}::{name}"
            try:
                back = (sim.get_bool(ident) if isinstance(value, bool) else
                        sim.get_integer(ident) if isinstance(value, int) else
                        sim.get_real(ident))
            except Exception as err:  # ecospy raises a bare Exception for an unknown name
                raise ValueError(f"Ecos did not set {ident} = {value!r}: {err}") from None
            if back != value:
                raise ValueError(f"Ecos did not set {ident} = {value!r} (it reads {back!r})")


# ----- the table: every estimator in every engine beside the project's own master ---------------
ENGINE_TABLE_SCENARIO = "moderate_dynamics"
EARLY_WINDOW = (0.03, 0.5)
"""Where a false start shows (docs/guide/engines.md): the largest error in it is a column."""


def early_error_deg(r: TestbenchResult) -> float:
    """The largest attitude error [deg] over EARLY_WINDOW, where a false start shows."""
    early = (r.t >= EARLY_WINDOW[0]) & (r.t <= EARLY_WINDOW[1])
    err = np.maximum(np.abs(r.estimate["roll"] - r.truth["roll"]),
                     np.abs(r.estimate["pitch"] - r.truth["pitch"])) / DEG
    return float(err[early].max())


def velocity_error(r: TestbenchResult, at_s: float = 10.0) -> float:
    """The position filter's velocity error [m/s] at the sample nearest at_s."""
    k = int(np.argmin(np.abs(r.t - at_s)))
    return float(np.linalg.norm([r.estimate[f"vel_{a}"][k] - r.truth[f"vel_{a}"][k]
                                 for a in "xyz"]))


@functools.cache
def engine_runs(fmu_dir: Path, scenario: str, seed: int, key: str
                ) -> tuple[tuple[str, int, TestbenchResult, float], ...]:
    """The estimator's chain under the project's own Jacobi master (on the native FMI 2.0 FMUs)
    and in every engine and FMI version that can run here: (engine, FMI version, result, CPU
    seconds), the own master first. Made once per process: the engines table and the checks of
    the same runs take them instead of simulating again."""
    from .master import run_testbench

    t0 = time.process_time()
    own = run_testbench(key, scenario, seed, master="jacobi", fmu_dir=fmu_dir / "native" / "fmi2")
    runs = [("own Jacobi master", 2, own, time.process_time() - t0)]
    for engine, versions in ENGINES.items():
        if engine_reason(engine):
            continue
        for fmi in versions:
            r = run_engine(engine, key, scenario, seed, fmi=fmi, fmu_dir=fmu_dir)
            runs.append((engine, fmi, r, r.cpu_s))
    return tuple(runs)


def engine_rows(fmu_dir: Path | str = DEFAULT_FMU_DIR, scenario: str = ENGINE_TABLE_SCENARIO,
                seed: int = 0, estimators: list[str] | None = None
                ) -> list[dict[str, Any]]:
    """Per engine x FMI version x estimator (and the project's own Jacobi master): whether the
    contract's accuracy checks pass, the largest attitude error over EARLY_WINDOW, the largest
    difference from the project's Jacobi master, the position filter's velocity error at 10 s
    and the speed in simulated seconds per CPU second. Engines that cannot run here are left
    out (engine_reason says why)."""
    rows = []
    for key in estimators or list(ESTIMATOR_FMUS):
        runs = engine_runs(Path(fmu_dir), scenario, seed, key)
        own = runs[0][2]
        for name, fmi, r, cpu in runs:
            rows.append({
                "engine": name, "fmi": fmi, "estimator": key,
                "accuracy": all(c.passed for c in r.checks if c.name.startswith("accuracy")),
                "rmse": (r.metrics["rmse_roll_deg"], r.metrics["rmse_pitch_deg"]),
                "early_max_deg": early_error_deg(r),
                "max_diff": max(float(np.max(np.abs(r.estimate[k] - own.estimate[k])))
                                for k in r.estimate),
                "vel_err_10s": velocity_error(r) if key == "poskf" else None,
                "speed": float(r.t[-1] / cpu) if cpu > 0 else None,
            })
    return rows


def engine_table(rows: list[dict[str, Any]], speed: bool = True) -> str:
    """The rows as a Markdown table (speed: with the machine-dependent speed column)."""
    head = ["engine", "FMI", "estimator", "accuracy checks", "RMSE roll/pitch [deg]",
            "max error 0.03-0.5 s [deg]", "max abs(engine - own Jacobi)",
            "vel. error at 10 s [m/s]"]
    if speed:
        head.append("simulated s per CPU s")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["engine"], f"{r['fmi']}.0", r["estimator"],
                 "PASS" if r["accuracy"] else "FAIL", "{:.3f}/{:.3f}".format(*r["rmse"]),
                 f"{r['early_max_deg']:.3f}", f"{r['max_diff']:.1e}" if r["max_diff"] else "0",
                 "-" if r["vel_err_10s"] is None else f"{r['vel_err_10s']:.3f}"]
        if speed:
            cells.append("-" if r["speed"] is None else f"{r['speed']:.0f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def add_engines_parser(sub: Any) -> None:
    p = sub.add_parser("engines", help="the testbench chain of every estimator in libcosim and "
                       "Ecos beside the project's Jacobi master: contract accuracy, start, "
                       "differences, speed")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR,
                   help="built FMUs (dist; the native ones under DIR/native)")
    p.add_argument("--seed", type=int, default=0, help="sensor part (0)")
    p.set_defaults(func=cmd_engines)


def cmd_engines(args: Any) -> int:
    for engine in ENGINES:
        why = engine_reason(engine)
        if why:
            print(f"{engine}: left out: {why}")
    rows = engine_rows(args.fmu_dir, seed=args.seed)
    print(f"{ENGINE_TABLE_SCENARIO}, seed {args.seed}, step 0.01 s, Jacobi stepping (the truth "
          "aligned by the chain's 2 steps)\n")
    print(engine_table(rows))
    return 0 if all(r["accuracy"] and r["max_diff"] == 0.0 for r in rows) else 1
