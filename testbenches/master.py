"""The testbench master: plant -> sensor -> estimator FMUs on fmpy's FMU2Slave, Gauss-Seidel
(the default) or Jacobi.

Gauss-Seidel, per communication step [t, t+h] (docs/interface.md, Timing):
  1. plant.doStep(t, h): the plant's outputs are the truth at t+h;
  2. sensor inputs := plant outputs; sensor.doStep(t, h): the IMU sample taken at t+h, dt = h;
  3. estimator inputs := sensor outputs; estimator.doStep(t, h): the estimate at t+h.
Jacobi, as libcosim, Ecos and parallel containers step: every FMU's inputs := the outputs the
others had before the step (after initialisation: the plant's truth at the start time, the
sensor's start values with dt = 0, which the estimator refuses and counts), then every FMU
steps. Each link adds one step: after doStep(t, h) the estimator's outputs are the estimate of
the sample of the truth at t - h. CHAIN_DELAY gives each master's delay in steps; the result's
traces are aligned by it (each estimate beside the truth and the sample it is of), so the
contract scores what the estimator did, and measured_delay measures what the chain did.
With jitter > 0 the communication steps are h_k = (1 + jitter u_k) / rate, u_k uniform in
[-1, 1] from the run's seed, so dt follows. Every FMI call's status is checked (a status of
fmi2Discard or worse raises FMICallException naming the FMU and the step); the CPU time (of
this thread) of set-inputs + doStep + get-outputs of the estimator is recorded per step for
contract check T3.

The step loop is the hot path of every campaign (at 1 kHz the FMUs are called 8000 times per
simulated second), so it calls the FMUs' fmi2SetReal/fmi2DoStep/fmi2GetReal as the plain ctypes
functions fmpy loaded (testbenches.fmus.direct_calls: without fmpy's Python wrapper around each
call, the statuses checked in the loop) on ctypes arrays allocated once, instead of
setReal/getReal, which build new arrays from Python lists on every call. The arrays are views of
one row of doubles laid out like the recording (truth, sample, estimate): the plant writes the
truth into it, the sensor reads its inputs from the truth part and writes the sample, the
estimator reads the sample and writes the estimate, and each step ends with one copy of the row
into the preallocated record. The values are the same doubles the list-based calls passed on.
"""

from __future__ import annotations

import time
from ctypes import sizeof
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from fmpy.fmi2 import fmi2Real, fmi2True, fmi2ValueReference

from fusion_core.scenarios import get_scenario
from fusion_core.synthetic import TRUTH_NAMES

from .fmus import (
    DEFAULT_FMU_DIR,
    ESTIMATOR_FMUS,
    PLANT_FMU,
    SENSOR_FMU,
    FmuHandle,
    direct_calls,
    estimator_parameters,
    failed,
    fmu_path,
)

TRUTH = TRUTH_NAMES
"""The plant's outputs, recorded in this order."""
MASTERS = ("gauss-seidel", "jacobi")
LINK_LAG = {"gauss-seidel": 0, "jacobi": 1}
"""Steps each link of the chain (plant -> sensor, sensor -> estimator) lags under a master."""
CHAIN_DELAY = {m: 2 * lag for m, lag in LINK_LAG.items()}
"""Steps from a truth to the estimate of it at the end of the plant -> sensor -> estimator
chain, as each master declares it (docs/interface.md, Timing)."""
START_REFUSED = dict(LINK_LAG)
"""Samples the estimator refuses at the start under each master: under Jacobi its first step
reads the sensor's start values, which dt = 0 marks as no sample."""
SENSOR_IN = ("omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z")
SAMPLE = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt")
ESTIMATE = ("roll", "pitch", "bias_x", "bias_y", "bias_z")
POSITION = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z")
SET_STEP_GET = ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal")
"""The calls of a step whose statuses `failed` names."""
_SENSOR_IN_AT = TRUTH.index(SENSOR_IN[0])
"""Where the sensor's inputs start among the plant outputs (they are consecutive there)."""
assert TRUTH[_SENSOR_IN_AT:_SENSOR_IN_AT + len(SENSOR_IN)] == SENSOR_IN


def _refs(value_references: list[int]) -> Any:
    """The value references as a ctypes array (made once per run, passed on every call)."""
    return (fmi2ValueReference * len(value_references))(*value_references)


def _view(row: Any, start: int, count: int) -> Any:
    """count doubles of the ctypes array row from index start on, sharing its memory."""
    return (fmi2Real * count).from_buffer(row, start * sizeof(fmi2Real))


@dataclass
class TestbenchResult:
    """Traces of one run (arrays of length N, one row per communication point t_k > 0) and,
    once contract.evaluate has run, its metrics and checks."""

    estimator: str
    scenario: str
    seed: int
    rate: float
    jitter: float
    params: dict[str, Any]
    sensor_params: dict[str, Any]
    t: np.ndarray
    truth: dict[str, np.ndarray]
    sample: dict[str, np.ndarray]
    estimate: dict[str, np.ndarray]
    invalid_samples: int
    step_us: np.ndarray
    true_gyro_bias: tuple[float, float, float]
    master: str = "gauss-seidel"
    measured_delay: int = 0
    """The delay in steps at which the estimate best matches the truth (measured_delay)."""
    engine: str = "the testbench master (fmpy)"
    """What ran the chain (testbenches.engines runs it in libcosim and Ecos)."""
    cpu_s: float = 0.0
    """The CPU time the whole run took, where measured (testbenches.engines)."""
    metrics: dict[str, float] = field(default_factory=dict)
    checks: list[Any] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    @property
    def delay(self) -> int:
        """The chain's declared delay in steps (CHAIN_DELAY), by which the traces are aligned."""
        return CHAIN_DELAY[self.master]

    @property
    def start_refused(self) -> int:
        """Samples the master's start makes the estimator refuse (START_REFUSED)."""
        return START_REFUSED[self.master]


def measured_delay(truth_all: np.ndarray, estimate: np.ndarray, max_delay: int = 4) -> int:
    """The delay in steps at which an estimate trace best matches the truth.

    truth_all[j] is the truth at t_j (j = 0 the start), estimate[k] the raw output after step k
    (time t_{k + 1}); a delay d pairs estimate[k] with truth_all[k + 1 - d]. Scored
    by the RMSE over the second half of the run (after convergence), all columns together; -1
    where the run has no step after max_delay to score (a run of a step or two, as a benchmark
    times its setup by)."""
    n = len(estimate)
    start = max(n // 2, max_delay)
    if start >= n:
        return -1
    errors = []
    for d in range(max_delay + 1):
        k = np.arange(start, n)
        diff = estimate[k] - truth_all[k + 1 - d]
        errors.append(float(np.sqrt(np.mean(diff * diff))))
    return int(np.argmin(errors))


def aligned_result(
    estimator: str, scenario: str, seed: int, rate: float, jitter: float,
    params: dict[str, Any], sensor_params: dict[str, Any], master: str, t_points: np.ndarray,
    truth_start: np.ndarray, truth_rows: np.ndarray, sample_rows: np.ndarray,
    estimate_rows: np.ndarray, invalid: int, step_us: np.ndarray,
    true_bias: tuple[float, float, float],
) -> TestbenchResult:
    """A run's result from its raw rows (row k: the outputs after step k, at t_points[k]) with
    each estimate beside the truth and the sample it is of, by the master's delay: estimate
    row k is of the truth at t_{k + 1 - CHAIN_DELAY} (truth_start: at t_0) and of the sample
    the sensor gave LINK_LAG steps before. Under Jacobi the first row, the estimate of no
    sample (the sensor's start values), is left out. Every engine's run goes through here."""
    lag = LINK_LAG[master]
    n = len(t_points)
    first = max(0, 2 * lag - 1)
    truth_all = np.vstack([truth_start, truth_rows])
    t_all = np.concatenate([[0.0], t_points])
    rows = np.arange(first, n)
    truth = truth_all[rows + 1 - 2 * lag]
    sample = sample_rows[rows - lag]
    out = estimate_rows[rows]
    names = ESTIMATE + (POSITION if estimate_rows.shape[1] > len(ESTIMATE) else ())
    attitude = [TRUTH.index("roll"), TRUTH.index("pitch")]
    # Each part as its own C-ordered array, the layout the traces always had.
    return TestbenchResult(
        estimator=estimator, scenario=scenario, seed=seed, rate=rate, jitter=jitter,
        params=params, sensor_params=sensor_params, t=t_all[rows + 1 - 2 * lag],
        truth={name: truth[:, i].copy() for i, name in enumerate(TRUTH)},
        sample={name: sample[:, i].copy() for i, name in enumerate(SAMPLE)},
        estimate={name: out[:, i].copy() for i, name in enumerate(names)},
        invalid_samples=invalid, step_us=step_us[rows], true_gyro_bias=true_bias,
        master=master,
        measured_delay=measured_delay(truth_all[:, attitude], estimate_rows[:, :2]),
    )


def communication_steps(duration: float, rate: float, jitter: float, seed: int) -> np.ndarray:
    """Step sizes covering [0, duration]: 1/rate each, or jittered by +-jitter (uniform)."""
    n = round(duration * rate)
    h = np.full(n, 1.0 / rate)
    if jitter > 0.0:
        rng = np.random.default_rng([seed, 7919])  # a stream of its own, apart from the sensor's
        h *= 1.0 + jitter * rng.uniform(-1.0, 1.0, n)
    return h


def run_testbench(
    estimator: str,
    scenario: str | int,
    seed: int = 0,
    duration: float | None = None,
    rate: float = 100.0,
    jitter: float = 0.0,
    params: dict[str, Any] | None = None,
    sensor_params: dict[str, Any] | None = None,
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
    evaluate: bool = True,
    master: str = "gauss-seidel",
) -> TestbenchResult:
    """Couple ImuPlant -> ImuSensor -> the estimator FMU and run one scenario.

    estimator: a fusion_core.ESTIMATORS key; scenario: a name or id of fusion_core.scenarios;
    params: estimator FMU parameters; sensor_params: ImuSensor parameters (seed is set from
    `seed`); master: one of MASTERS (the module docstring). Returns the traces aligned by the
    master's CHAIN_DELAY, and with evaluate=True the contract's metrics and checks.
    """
    if estimator not in ESTIMATOR_FMUS:
        raise ValueError(f"unknown estimator {estimator!r}: allowed {', '.join(ESTIMATOR_FMUS)}")
    if master not in MASTERS:
        raise ValueError(f"unknown master {master!r}: allowed {', '.join(MASTERS)}")
    jacobi = master == "jacobi"
    sc = get_scenario(scenario)
    duration = sc.duration if duration is None else float(duration)
    if not rate > 0.0 or not 0.0 <= jitter < 1.0:
        raise ValueError(f"rate={rate!r} must be > 0 and jitter={jitter!r} in [0, 1)")
    # the sensor's inputs hold at the step's end (Gauss-Seidel) or its start (Jacobi)
    sensor_params = {"inputs_at": "start" if jacobi else "end", **(sensor_params or {}),
                     "seed": seed}
    # The estimator integrates the gyro by the rule the sensor's samples call for
    params = {"gyro_sampling": sensor_params.get("gyro_sampling", "point"), **(params or {})}
    steps = communication_steps(duration, rate, jitter, seed)
    n = len(steps)
    position = estimator == "poskf"

    tag = f"{estimator}-{sc.name}-{seed}-{time.perf_counter_ns()}"
    plant = FmuHandle(fmu_path(PLANT_FMU, fmu_dir), f"plant-{tag}")
    sensor = FmuHandle(fmu_path(SENSOR_FMU, fmu_dir), f"sensor-{tag}")
    est = FmuHandle(fmu_path(ESTIMATOR_FMUS[estimator], fmu_dir), f"est-{tag}")
    try:
        stop = float(np.sum(steps))
        plant.start({"scenario": sc.id}, stop)
        sensor.start(sensor_params, stop)
        est.start(estimator_parameters(est, estimator, params), stop)
        truth_vr = plant.vrs(TRUTH)
        sensor_in_vr = sensor.vrs(SENSOR_IN)
        sample_vr = sensor.vrs(SAMPLE)
        est_in_vr = est.vrs(SAMPLE)
        est_out_vr = est.vrs(ESTIMATE + (POSITION if position else ()))
        invalid_vr = est.vrs(["invalid_samples"])
        bias_vr = sensor.vrs([f"true_bias_{a}" for a in "xyz"])

        # The row (see the module docstring): truth | sample | estimate, and views of its parts.
        n_truth, n_in, n_sample, n_out = len(TRUTH), len(SENSOR_IN), len(SAMPLE), len(est_out_vr)
        row = (fmi2Real * (n_truth + n_sample + n_out))()
        truth_buf = _view(row, 0, n_truth)
        sensor_in_buf = _view(row, _SENSOR_IN_AT, n_in)
        sample_buf = _view(row, n_truth, n_sample)
        out_buf = _view(row, n_truth + n_sample, n_out)
        row_np = np.frombuffer(row, dtype=np.float64)  # the same memory, for the record
        # What the outputs read before the first step (a Jacobi master passes them on): the
        # plant's truth at the start time, the sensor's start values
        truth_start = plant.fmu.getReal(truth_vr)
        truth_buf[:] = truth_start
        sample_buf[:] = sensor.fmu.getReal(sample_vr)
        record = np.empty((n, len(row)))
        step_ns = np.empty(n, dtype=np.int64)
        t_points = np.empty(n)

        p_fmu, s_fmu, e_fmu = plant.fmu, sensor.fmu, est.fmu
        p_c, s_c, e_c = p_fmu.component, s_fmu.component, e_fmu.component
        p_step, p_get = direct_calls(p_fmu, "fmi2DoStep", "fmi2GetReal")
        s_set, s_step, s_get = direct_calls(s_fmu, "fmi2SetReal", "fmi2DoStep", "fmi2GetReal")
        e_set, e_step, e_get = direct_calls(e_fmu, "fmi2SetReal", "fmi2DoStep", "fmi2GetReal")
        truth_refs, sample_refs = _refs(truth_vr), _refs(sample_vr)
        sensor_in_refs, est_in_refs = _refs(sensor_in_vr), _refs(est_in_vr)
        est_out_refs = _refs(est_out_vr)
        # T3 counts this thread's CPU time, not wall time: what the three calls cost, whatever
        # else the machine is running (a busy machine preempts the thread, it does not make
        # the calls dearer)
        perf = time.thread_time_ns
        t = 0.0
        set_ns = 0  # Jacobi: the estimator's set-inputs, timed apart from its step and get
        for k, h in enumerate(steps.tolist()):
            # Statuses are ints: fmi2OK 0, fmi2Warning 1 (a rejected sample), failures above.
            if jacobi:  # every FMU's inputs: the others' outputs before this step
                a = s_set(s_c, sensor_in_refs, n_in, sensor_in_buf)
                t0 = perf()
                b = e_set(e_c, est_in_refs, n_sample, sample_buf)
                set_ns = perf() - t0
                if a > 1 or b > 1:
                    failed(sensor if a > 1 else est, ("fmi2SetReal",), (max(a, b),), t, h)
            a = p_step(p_c, t, h, fmi2True)
            b = p_get(p_c, truth_refs, n_truth, truth_buf)
            if a > 1 or b > 1:
                failed(plant, ("fmi2DoStep", "fmi2GetReal"), (a, b), t, h)
            a = 0 if jacobi else s_set(s_c, sensor_in_refs, n_in, sensor_in_buf)
            b = s_step(s_c, t, h, fmi2True)
            c = s_get(s_c, sample_refs, n_sample, sample_buf)
            if a > 1 or b > 1 or c > 1:
                failed(sensor, SET_STEP_GET, (a, b, c), t, h)
            t0 = perf()
            a = 0 if jacobi else e_set(e_c, est_in_refs, n_sample, sample_buf)
            b = e_step(e_c, t, h, fmi2True)
            c = e_get(e_c, est_out_refs, n_out, out_buf)
            step_ns[k] = perf() - t0 + set_ns
            if a > 1 or b > 1 or c > 1:
                failed(est, SET_STEP_GET, (a, b, c), t, h)
            record[k] = row_np
            t += h
            t_points[k] = t
        invalid = int(e_fmu.getInteger(invalid_vr)[0])
        true_bias = tuple(s_fmu.getReal(bias_vr))  # at the last sample
    finally:
        for handle in (est, sensor, plant):
            handle.free()

    result = aligned_result(
        estimator, sc.name, seed, rate, jitter, params, sensor_params, master, t_points,
        np.array(truth_start), record[:, :n_truth], record[:, n_truth:n_truth + n_sample],
        record[:, n_truth + n_sample:], invalid, step_ns / 1e3, true_bias)  # type: ignore[arg-type]
    if evaluate:
        from .contract import evaluate as evaluate_contract

        evaluate_contract(result)
    return result
