"""Accuracy on real recordings: every estimator on BROAD trials, beside public 6D filters.

`python -m testbenches broad PATH...` is a thin layer over `plan_columns`, `evaluate` and
`report.write_reports`:

- each trial file (HDF5 or MATLAB v5, `data.load_trial`) is run through every selected
  estimator with every selected preset (`fusion_core.presets`), on `imu_acc`, `imu_gyr` and
  dt = 1/sampling_rate, either in fusion_core (`Estimator.run`) or, with `fmu=True`, through the
  built FMUs in fmpy, one doStep per sample (the same numbers: the FMUs are bit-identical to
  fusion_core);
- the trial's sensor properties (gyro_sampling, sensor_delay) are the estimators' unless the
  preset sets them;
- with peers, VQF, Madgwick and Mahony run on the same samples (`peers`), and VQF turned ahead
  over the trial's sensor delay as our outputs are (`vqf-ahead`);
- every run is scored by BROAD's inclination RMSE over the `movement` samples
  (`metric`), and the per-trial numbers are averaged over the given trials and over
  BROAD's groups (trials.json beside the files, or the groups in the trial names).

A column is one (estimator or peer, preset) pair; its name is the estimator key for the default
preset ("kf"), key-preset otherwise ("kf-broad"), and the peer's name for a peer ("vqf").
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core import ESTIMATORS
from fusion_core.presets import load_preset
from fusion_core.registry import create

from ..fmus import DEFAULT_FMU_DIR, ESTIMATOR_FMUS, FmuHandle, estimator_parameters, fmu_path
from ..peers import AHEAD_PEERS, PEERS
from .data import (
    GROUP_ORDER,
    BroadTrial,
    find_trials_json,
    load_trial,
    load_trials_json,
    trial_groups,
)
from .metric import gravity_from_quat, gravity_from_roll_pitch, inclination_rmse_deg

TRIAL_SUFFIXES = (".hdf5", ".h5", ".mat")
"""File endings collected from a directory given as PATH."""

SAMPLE_IN = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt")


@dataclass(frozen=True)
class Column:
    """One column of the table: an estimator with a preset (in fusion_core or as FMU), or a peer."""

    name: str
    kind: str
    """'fusion_core', 'fmu' or 'peer'."""
    key: str
    """fusion_core.ESTIMATORS key, or peers.PEERS name."""
    preset: str | None = None
    params: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "estimator": self.key,
                "preset": self.preset, "params": dict(self.params)}


@dataclass
class TrialResult:
    """One trial's inclination RMSE per column (NaN: no movement sample with a reference)."""

    name: str
    path: str
    groups: list[str]
    samples: int
    movement_samples: int
    duration_s: float
    rmse_deg: dict[str, float] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    rejected: dict[str, int] = field(default_factory=dict)


@dataclass
class BroadResult:
    columns: list[Column]
    trials: list[TrialResult]
    fmu_dir: str | None = None

    @property
    def names(self) -> list[str]:
        return [c.name for c in self.columns]

    def means(self, trials: Sequence[TrialResult] | None = None) -> dict[str, float]:
        """Mean inclination RMSE [deg] per column over the trials (all by default)."""
        trials = self.trials if trials is None else trials
        return {n: _mean(t.rmse_deg.get(n, float("nan")) for t in trials) for n in self.names}

    def groups(self) -> dict[str, list[TrialResult]]:
        """BROAD group -> its trials among these, in the dataset's group order (empty groups left
        out)."""
        found = {g for t in self.trials for g in t.groups}
        order = [g for g in GROUP_ORDER if g in found] + sorted(found - set(GROUP_ORDER))
        return {g: [t for t in self.trials if g in t.groups] for g in order}

    def group_means(self) -> dict[str, dict[str, float]]:
        return {g: self.means(ts) for g, ts in self.groups().items()}


def _mean(values: Iterable[float]) -> float:
    v = np.array(list(values), dtype=float)
    return float(np.mean(v)) if v.size else float("nan")


# ----- what to run -------------------------------------------------------------------------------
def column_name(key: str, preset: str) -> str:
    """kf for the recommended preset, kf-paper for another, kf-NAME for a file NAME.json."""
    if preset == "recommended":
        return key
    return f"{key}-{Path(preset).stem if preset.endswith('.json') else preset}"


def plan_columns(
    estimators: Sequence[str], presets: Sequence[str], peers: Sequence[str] = (),
    fmu: bool = False, calibration: Path | None = None,
) -> list[Column]:
    """Columns for estimators x presets (in that order), then the peers; a calibration file's
    parameters on top of every estimator's (testbenches.options.with_calibration)."""
    bad = [k for k in estimators if k not in ESTIMATORS]
    if bad:
        raise ValueError(f"unknown estimator(s) {', '.join(bad)}: allowed {', '.join(ESTIMATORS)}")
    from ..options import with_calibration

    # ValueError for an unknown preset or a bad calibration file
    loaded = {p: with_calibration(load_preset(p), calibration) for p in presets}
    allowed = [*PEERS, *AHEAD_PEERS]
    bad = [p for p in peers if p not in allowed]
    if bad:
        raise ValueError(f"unknown peer(s) {', '.join(bad)}: allowed {', '.join(allowed)}")
    cols = [
        Column(column_name(k, p), "fmu" if fmu else "fusion_core", k, p, loaded[p][k])
        for k in estimators for p in presets
    ]
    return cols + [Column(p, "peer", p) for p in peers]


def collect_paths(paths: Iterable[str | Path]) -> list[Path]:
    """The trial files: files as given, directories expanded to their .hdf5/.h5/.mat files."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out += sorted(f for f in p.iterdir() if f.suffix.lower() in TRIAL_SUFFIXES)
        else:
            out.append(p)
    return out


# ----- running one column on one trial ------------------------------------------------------------
def with_sensor(params: dict[str, Any], trial: BroadTrial) -> dict[str, Any]:
    """params with the properties of the trial's sensor (gyro_sampling, sensor_delay) unless
    they set them themselves."""
    return {"gyro_sampling": trial.gyro_sampling, "sensor_delay": trial.sensor_delay, **params}


def run_fusion_core(key: str, params: dict[str, Any], trial: BroadTrial) -> dict[str, np.ndarray]:
    """roll, pitch [N] (and rejected) of fusion_core's estimator on the trial (integrating the
    gyro by the trial's sampling property and turning its outputs ahead over the sensor's delay
    unless params say otherwise)."""
    return create(key, with_sensor(params, trial)).run(trial.acc, trial.gyro, trial.dt)


def run_fmu(
    key: str, params: dict[str, Any], trial: BroadTrial, fmu_dir: Path | str = DEFAULT_FMU_DIR
) -> dict[str, np.ndarray]:
    """roll, pitch [N] (and rejected) of the estimator's FMU on the trial, in fmpy: one
    set-inputs / doStep / get-outputs per sample, communication step = dt (docs/interface.md)."""
    path = fmu_path(ESTIMATOR_FMUS[key], fmu_dir)
    params = with_sensor(params, trial)
    fmu = FmuHandle(path, f"broad-{key}-{time.perf_counter_ns()}")
    n, h = trial.n, trial.dt
    out = np.empty((n, 2))
    rejected = np.zeros(n, dtype=bool)
    try:
        fmu.start(estimator_parameters(fmu, key, params), n * h)
        in_vr = fmu.vrs(SAMPLE_IN)
        out_vr = fmu.vrs(("roll", "pitch"))
        (bad_vr,) = fmu.vrs(("invalid_samples",))
        slave = fmu.fmu
        samples = np.column_stack([trial.acc, trial.gyro, np.full(n, h)]).tolist()
        bad_before = 0
        for k, sample in enumerate(samples):
            slave.setReal(in_vr, sample)
            slave.doStep(k * h, h)
            out[k] = slave.getReal(out_vr)
            bad = slave.getInteger([bad_vr])[0]
            rejected[k] = bad != bad_before
            bad_before = bad
    finally:
        fmu.free()
    return {"roll": out[:, 0], "pitch": out[:, 1], "rejected": rejected}


def column_gravity(
    col: Column, trial: BroadTrial, fmu_dir: Path | str = DEFAULT_FMU_DIR
) -> tuple[np.ndarray, int]:
    """The column's estimated up direction [N, 3] on the trial, and its rejected-sample count."""
    if col.kind == "peer" and col.key in AHEAD_PEERS:
        return AHEAD_PEERS[col.key](trial.acc, trial.gyro, trial.rate, trial.sensor_delay), 0
    if col.kind == "peer":
        return PEERS[col.key](trial.acc, trial.gyro, trial.rate), 0
    if col.kind == "fmu":
        out = run_fmu(col.key, col.params, trial, fmu_dir)
    else:
        out = run_fusion_core(col.key, col.params, trial)
    return gravity_from_roll_pitch(out["roll"], out["pitch"]), int(np.sum(out["rejected"]))


def evaluate_trial(
    trial: BroadTrial, columns: Sequence[Column], groups: list[str],
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
    progress: Callable[[str, str], None] | None = None,
) -> TrialResult:
    """Every column on one trial, scored by the inclination RMSE over its movement samples."""
    g_ref = gravity_from_quat(trial.opt_quat)
    res = TrialResult(
        name=trial.name, path=str(trial.path), groups=groups, samples=trial.n,
        movement_samples=int(np.sum(trial.movement & np.all(np.isfinite(trial.opt_quat), 1))),
        duration_s=trial.duration,
    )
    for col in columns:
        t0 = time.perf_counter()
        g_est, rejected = column_gravity(col, trial, fmu_dir)
        res.seconds[col.name] = time.perf_counter() - t0
        res.rmse_deg[col.name] = inclination_rmse_deg(g_est, g_ref, trial.movement)
        res.rejected[col.name] = rejected
        if progress is not None:
            progress(trial.name, col.name)
    return res


def evaluate(
    paths: Iterable[str | Path | BroadTrial],
    columns: Sequence[Column],
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
    trials_json: str | Path | None = None,
    progress: Callable[[str, str], None] | None = None,
    head_seconds: float | None = None,
) -> BroadResult:
    """Run every column on every trial (see the module docstring).

    paths: trial files, folders of them, or already loaded trials.

    trials_json: BROAD's trials.json for the groups (default: the one beside the files, if any;
    otherwise the groups in the trial names). progress(trial, column) is called after each run.
    head_seconds: use only the first seconds of every trial (quick looks, tests).
    Raises NotABroadTrial (ValueError) for a file that is not a BROAD trial, before any run.
    """
    trials: list[BroadTrial] = []
    for item in paths:  # every file is loaded, and so checked, before the long runs start
        if isinstance(item, BroadTrial):
            trials.append(item)
        else:
            trials += [load_trial(f) for f in collect_paths([item])]
    if not trials:
        raise ValueError("no trial files given")
    if head_seconds is not None:
        trials = [t.head(head_seconds) for t in trials]
    tj_path = Path(trials_json) if trials_json is not None else find_trials_json(
        [t.path for t in trials])
    tj = load_trials_json(tj_path) if tj_path is not None else None
    results = [
        evaluate_trial(t, columns, trial_groups(t.name, tj), fmu_dir, progress) for t in trials
    ]
    fmu = any(c.kind == "fmu" for c in columns)
    return BroadResult(list(columns), results, str(fmu_dir) if fmu else None)


__all__ = [
    "BroadResult",
    "Column",
    "TrialResult",
    "collect_paths",
    "column_gravity",
    "evaluate",
    "evaluate_trial",
    "plan_columns",
    "run_fmu",
    "run_fusion_core",
]
