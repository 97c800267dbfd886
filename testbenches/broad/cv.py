"""Leave-one-group-out cross-validation of the defaults on BROAD: `python -m testbenches broad
PATH --cv`.

A default chosen by a scan on the same trials it is then scored on looks better than it is: on
recordings nobody here has seen, defaults that tied VQF in sample trailed it by 15-50 %. So every
parameter that a scan chooses (CV_GRID: those physics leaves open) is chosen again without one
group of trials and scored on that group, for each of the four motion folds (FOLDS: slow
rotation, fast rotation, translation, disturbed or combined motion). The cross-validated mean is
the mean over all trials of the error each trial got from a choice made without its fold; the
in-sample mean is the defaults' own. A default holds when the two are close; where the scan's
choice on a fold differs from the default, the fold says what the default costs there.

Every grid point runs once per trial (through the compiled twin where it loads: under a minute
per estimator). A fold chooses among the grid points that keep the contract's per-run accuracy
bounds (testbenches.broad.feasible: the realistic sensor's scenarios see a sensor class and
motions BROAD lacks, and a value they refuse is none a default could take; `--cv-unconstrained`
lets every point be chosen), and by the smallest regret (CHOICES): the point whose worst
training fold is least above that fold's best point. A user's mix of motions is not these
trials' (4 of the 13 shared trials are disturbed or combined, 8 of BROAD's 17 further trials are
combined), so a default has to be near the best on every kind of motion rather than best on the
mean of the mix these trials happen to have; the lowest mean over the training trials
(`--cv-choice mean`) lets the folds with most trials decide.

A mechanism is not left out on BROAD's folds alone either: where the synthetic battery keeps a
filter's longer vector (testbenches.mechanisms, run first by `--cv`), no choice takes a grid point
without it (PROCEDURES says why).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.registry import ATTITUDE_FILTERS, ESTIMATORS

from .data import BroadTrial
from .feasible import contract_failure
from .metric import gravity_from_quat, gravity_from_roll_pitch, inclination_rmse_deg
from .run import run_fusion_core

CV_GRID: dict[str, tuple[float, ...]] = {
    "acc_lowpass": (1.0, 1.5, 2.0),
    "slow_band_time": (0.05, 0.1, 0.15, 0.3),
    "scale_time": (0.25, 0.5, 1.0),
    "acc_lowpass_stretch": (1.0, 1.5, 2.0),
}
"""The parameters physics leaves open, with the values a scan tries. acc_lowpass: the measured
vector's length (VQF's 3 s time constant sits at the long end once its gain is counted);
slow_band_time: the corner between the disturbance the pre-filter removes and the one that
reaches the vector (measured_vector.BAND_PARAM); scale_time: how long a gyro's scale error adds
up in one direction, a property of the motion rather than of the sensor (ADAPTIVE_NOISE_PARAMS),
from 0.25 s: below it, where BROAD alone would go, the realistic sensor's high_dynamics
scenario leaves its 5-deg bound at most points (cv.json lists the refused points and why),
and the folds' choices are made among the points that keep the contract anyway
(cross_validate's constraint); acc_lowpass_stretch: how much longer the vector may grow where
slow linear acceleration reaches it (measured_vector.STRETCH_PARAM), from off (1) to VQF's
3 s at the default length (2).
Every other default comes from the sensor's physics (its noise densities, its scale-factor
class, its range) or is a bound (max_correction_time). `broad --cv-grid` takes another grid."""
CV_ESTIMATORS: tuple[str, ...] = ATTITUDE_FILTERS
"""The estimators with a measured vector (the position filter's attitude is the kf's)."""
FOLDS: tuple[str, ...] = ("slow_rotation", "fast_rotation", "translation", "disturbed_combined")
"""The motion folds, from BROAD's groups (fold_of)."""
Grid = Mapping[str, Sequence[float]]
"""Parameter name -> the values a scan tries."""
CHOICES: tuple[str, ...] = ("regret", "mean")
"""How a fold chooses among the allowed grid points from the training trials' errors. regret:
the smallest max over the training folds of m_f(p) / min_q m_f(q), m_f(p) the mean RMSE of
point p over fold f's trials and q the allowed points (ties: the lower training mean); mean: the
lowest mean over the training trials."""
CHOICE_PHRASES: dict[str, str] = {"regret": "by the smallest regret over the training folds",
                                  "mean": "by the lowest training mean"}
"""How cv.json's method and the printed table name each of CHOICES."""


def fold_of(groups: Sequence[str]) -> str:
    """The motion fold of a trial from its BROAD groups: disturbed, combined, mixed or office
    trials together (what the unseen recordings hold most of), then translation, then rotation
    by its speed."""
    g = set(groups)
    if g & {"disturbed", "combined", "mixed", "office_environment"}:
        return "disturbed_combined"
    if "translation" in g:
        return "translation"
    return "fast_rotation" if "fast" in g else "slow_rotation"


@dataclass
class EstimatorCv:
    """One estimator's cross-validation: the error per trial of the defaults and of each grid
    point, each fold's choice and what the held-out trials got from it."""

    key: str
    defaults: dict[str, float]
    in_sample: dict[str, float] = field(default_factory=dict)
    """trial -> RMSE [deg] of the defaults."""
    grid: list[dict[str, float]] = field(default_factory=list)
    errors: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    """[grid point, trial] RMSE [deg] (cv.json: grid_errors_deg, its columns cv.json's
    trials)."""
    chosen: dict[str, dict[str, float]] = field(default_factory=dict)
    """fold -> the grid point chosen without it."""
    held_out: dict[str, float] = field(default_factory=dict)
    """trial -> RMSE [deg] with its fold's choice."""
    scan_choice: dict[str, float] = field(default_factory=dict)
    """The grid point the choice takes on every trial (with choice "mean" the in-sample
    minimum) among those the constraint allows."""
    refused: dict[str, str] = field(default_factory=dict)
    """Grid points a fold or the scan ranked above its choice but the constraint refused (the
    point as NAME=V,... -> why: the first contract check it fails)."""
    nested: dict[str, float] = field(default_factory=dict)
    """trial -> RMSE [deg] under nested cross-validation (nested_cv): the procedure as well as
    the point chosen without the trial's fold."""
    nested_procedure: dict[str, str] = field(default_factory=dict)
    """fold -> the procedure (PROCEDURES) the other folds chose by their own inner
    cross-validation."""
    battery_keeps: str | None = None
    """Why the synthetic battery keeps the longer vector in this filter
    (testbenches.mechanisms.Worth.battery_keeps), None where it does not or was not run: where
    it does, no choice leaves the vector out on BROAD's folds alone (_Allowed)."""

    def in_sample_mean(self) -> float:
        return float(np.mean(list(self.in_sample.values())))

    def cv_mean(self) -> float:
        return float(np.mean(list(self.held_out.values())))

    def nested_mean(self) -> float:
        return float(np.mean(list(self.nested.values()))) if self.nested else float("nan")

    def scan_mean(self) -> float:
        return float(self.errors[self.grid.index(self.scan_choice)].mean())

    def as_dict(self) -> dict[str, Any]:
        return {"defaults": self.defaults, "in_sample_deg": self.in_sample,
                "cv_held_out_deg": self.held_out, "chosen_per_fold": self.chosen,
                "in_sample_mean_deg": self.in_sample_mean(), "cv_mean_deg": self.cv_mean(),
                "scan_choice": self.scan_choice, "scan_choice_mean_deg": self.scan_mean(),
                "nested_deg": self.nested, "nested_mean_deg": self.nested_mean(),
                "nested_procedure_per_fold": self.nested_procedure,
                "longer_vector_kept_by_battery": self.battery_keeps,
                "refused_by_contract": self.refused,
                "grid_points": self.grid,
                "grid_errors_deg": [[float(v) for v in row] for row in self.errors]}


@dataclass
class CvResult:
    trials: list[str]
    folds: dict[str, str]
    """trial -> fold."""
    estimators: dict[str, EstimatorCv]
    peers: dict[str, dict[str, float]] = field(default_factory=dict)
    """peer -> trial -> RMSE [deg] (nothing to fit: its in-sample and CV figures are one)."""
    grid: dict[str, list[float]] = field(default_factory=lambda: {k: list(v)
                                                                   for k, v in CV_GRID.items()})
    """The parameters chosen again per fold and their values (CV_GRID unless another was
    given)."""
    constrained: bool = True
    """Whether each choice was made among the grid points that keep the contract
    (testbenches.broad.feasible)."""
    choice: str = "regret"
    """How each fold chose (CHOICES)."""

    def fold_mean(self, values: dict[str, float], fold: str) -> float:
        picked = [v for t, v in values.items() if self.folds[t] == fold]
        return float(np.mean(picked)) if picked else float("nan")

    def cv_means(self) -> dict[str, float]:
        return {k: e.cv_mean() for k, e in self.estimators.items()}

    def nested_means(self) -> dict[str, float]:
        return {k: e.nested_mean() for k, e in self.estimators.items() if e.nested}

    def as_dict(self) -> dict[str, Any]:
        return {
            "method": "leave one motion fold out: each grid parameter chosen on the other "
                      "folds' trials, scored on the held-out fold's"
                      + (", among the grid points that keep the contract's per-run accuracy "
                         "bounds" if self.constrained else "")
                      + ", " + CHOICE_PHRASES[self.choice],
            "constrained_by_contract": self.constrained,
            "choice": self.choice,
            "grid": self.grid,  # each estimator: those it has
            "trials": self.trials,  # the columns of each grid_errors_deg
            "folds": self.folds,
            "estimators": {k: e.as_dict() for k, e in self.estimators.items()},
            "peers": self.peers,
        }


def _rmse(trial: BroadTrial, roll: np.ndarray, pitch: np.ndarray) -> float:
    return inclination_rmse_deg(gravity_from_roll_pitch(roll, pitch),
                                gravity_from_quat(trial.opt_quat), trial.movement)


def cross_validate(
    trials: Sequence[BroadTrial], groups: Sequence[Sequence[str]],
    estimators: Sequence[str] = CV_ESTIMATORS,
    peers: dict[str, Callable[..., np.ndarray]] | None = None,
    progress: Callable[[str], None] | None = None,
    measured: dict[str, dict[str, float]] | None = None,
    grid: Grid | None = None,
    constraint: Callable[[str, dict[str, float]], str | None] | None = contract_failure,
    choice: str = "regret",
    base: dict[str, float] | None = None,
    battery_keeps: Mapping[str, str | None] | None = None,
) -> CvResult:
    """The cross-validation of every estimator's grid parameters over the trials (groups: each
    trial's BROAD groups). peers: name -> f(acc, gyro, rate, delay) giving the up direction,
    scored on the same trials. progress(label) is called after each trial. measured: peer
    name -> trial -> RMSE already measured on these trials (the evaluation's own columns),
    which are not run again. grid: the parameters to choose again per fold and their values
    (CV_GRID; check_grid says whether one is valid); an estimator without a parameter of it
    leaves that one out. constraint(key, point): why the point may not be chosen, or None
    (testbenches.broad.feasible.contract_failure: the contract's per-run accuracy bounds; None:
    every point may be); a fold, and the scan, choose the best point it allows by choice
    (CHOICES: "regret" or "mean"). base: parameters every run takes, over the point's and
    the defaults' (a mechanism switched off: testbenches.mechanisms). battery_keeps:
    estimator -> why the battery keeps its longer vector, or None
    (testbenches.mechanisms.longer_vector_on_battery): where it does, no choice takes a point
    without the vector (acc_lowpass_stretch 1), unless base switches it itself."""
    if choice not in CHOICES:
        raise ValueError(f"choice {choice!r}: allowed {', '.join(CHOICES)}")
    measured = measured or {}
    grid = CV_GRID if grid is None else grid
    check_grid(grid, estimators)
    names = [t.name for t in trials]
    folds = {t.name: fold_of(g) for t, g in zip(trials, groups, strict=True)}
    present = [f for f in FOLDS if f in folds.values()]
    if len(present) < 2:
        raise ValueError(f"cross-validation needs trials of at least two motion folds "
                         f"({', '.join(FOLDS)}); these are all {present[0] if present else '-'}")
    out: dict[str, EstimatorCv] = {}
    for key in estimators:
        if key not in CV_ESTIMATORS:
            raise ValueError(f"--cv covers {', '.join(CV_ESTIMATORS)}, not {key}")
        specs = ESTIMATORS[key].param_specs()
        keys = [k for k in grid if k in specs]  # the mgcf has no slow band
        points = [dict(zip(keys, values, strict=True))
                  for values in itertools.product(*(grid[k] for k in keys))]
        defaults = {k: float(specs[k].default) for k in keys}
        keeps = None if "acc_lowpass_stretch" in (base or {}) else (battery_keeps or {}).get(key)
        cv = EstimatorCv(key, defaults, grid=points, errors=np.zeros((len(points), len(trials))),
                         battery_keeps=keeps)
        at_default = points.index(defaults) if defaults in points and not base else None
        for j, trial in enumerate(trials):
            for i, point in enumerate(points):
                r = run_fusion_core(key, {**point, **(base or {})}, trial)
                cv.errors[i, j] = _rmse(trial, r["roll"], r["pitch"])
            if at_default is None:  # defaults off the grid: run them too
                r = run_fusion_core(key, dict(base or {}), trial)
                cv.in_sample[trial.name] = _rmse(trial, r["roll"], r["pitch"])
            else:
                cv.in_sample[trial.name] = float(cv.errors[at_default, j])
            if progress is not None:
                progress(f"{key} {trial.name[:28]}")
        allowed = _Allowed(key, [{**p, **(base or {})} for p in points], constraint, keeps)
        columns = {f: [j for j, n in enumerate(names) if folds[n] == f] for f in present}

        cv.scan_choice = points[_choose(cv, list(columns.values()), allowed, choice)]
        for fold in present:
            chosen = _choose(cv, [c for f, c in columns.items() if f != fold], allowed, choice)
            cv.chosen[fold] = points[chosen]
            for j, n in enumerate(names):
                if folds[n] == fold:
                    cv.held_out[n] = float(cv.errors[chosen, j])
        nested_cv(cv, columns, allowed)
        out[key] = cv
    peer_rows: dict[str, dict[str, float]] = {}
    for name, peer in (peers or {}).items():
        if name in measured:
            peer_rows[name] = {t.name: measured[name][t.name] for t in trials}
            continue
        peer_rows[name] = {}
        for trial in trials:
            up = peer(trial.acc, trial.gyro, trial.rate, trial.sensor_delay)
            peer_rows[name][trial.name] = inclination_rmse_deg(
                up, gravity_from_quat(trial.opt_quat), trial.movement)
            if progress is not None:
                progress(f"{name} {trial.name[:28]}")
    return CvResult(names, folds, out, peer_rows, {k: [float(v) for v in grid[k]] for k in grid},
                    constraint is not None, choice)


NESTED_FOLDS = 3
"""The fewest motion folds a nested cross-validation needs: an outer one held out and two for
the inner split."""
PROCEDURES: tuple[tuple[str, str], ...] = (("regret", "grid"), ("mean", "grid"),
                                          ("regret", "no longer vector"),
                                          ("mean", "no longer vector"))
"""What the nested cross-validation chooses between, besides the point: the choice rule
(CHOICES) and the grid, whole or without the longer vector (its points with
acc_lowpass_stretch 1: the mechanism left out). An estimator without acc_lowpass_stretch has
the whole grid only, and so has one whose longer vector the battery keeps
(EstimatorCv.battery_keeps), whose grid then lacks the points without it too: the defaults
drop a mechanism only where BROAD's folds and the battery both let it go
(testbenches.mechanisms), and the nested cross-validation scores that procedure, not one that
decides on BROAD's folds alone. The battery holds none of BROAD's trials, so the outer fold
still enters no choice."""


def _pick(cv: EstimatorCv, folds: list[list[int]], points: list[int], allowed: _Allowed,
          choice: str, record: bool = False) -> int:
    """The grid point among `points` chosen on the training trials (folds: each training
    fold's columns) among those allowed lets be chosen, by choice (CHOICES); with record, the
    points the constraint refused ahead of it go to cv.refused."""
    idx = np.asarray(points)
    mean = cv.errors[np.ix_(idx, [j for cols in folds for j in cols])].mean(axis=1)
    if choice == "mean":
        return _first_allowed(idx[np.argsort(mean, kind="stable")], cv, allowed, record)
    per_fold = np.stack([cv.errors[np.ix_(idx, cols)].mean(axis=1) for cols in folds], axis=1)
    best = []
    for f in range(len(folds)):
        first = _first_allowed(idx[np.argsort(per_fold[:, f], kind="stable")], cv, allowed,
                               record=False)
        best.append(per_fold[points.index(first), f])
    # (a fold whose best is exact: the other points' regret is as large as a float's)
    regret = (per_fold / np.maximum(best, np.finfo(float).tiny)).max(axis=1)
    return _first_allowed(idx[np.lexsort((mean, regret))], cv, allowed, record)


def nested_cv(cv: EstimatorCv, columns: dict[str, list[int]], allowed: _Allowed) -> None:
    """Nested leave-one-fold-out: for each outer fold, each procedure (PROCEDURES) is scored by
    an inner leave-one-fold-out over the other folds alone, the best one (ties: the first) then
    chooses its point on all of them, and the outer fold is scored with that point. The outer
    fold is seen by no choice: neither the point's, nor the rule's, nor the grid's. Fills
    cv.nested and cv.nested_procedure (nothing with fewer than three folds: an inner split
    needs two)."""
    present = list(columns)
    if len(present) < NESTED_FOLDS:
        return
    names = list(cv.in_sample)
    n_points = len(cv.grid)
    grids = {"grid": list(range(n_points))}
    if "acc_lowpass_stretch" in cv.defaults and cv.battery_keeps is None:
        grids["no longer vector"] = [i for i, p in enumerate(cv.grid)
                                     if p["acc_lowpass_stretch"] == 1.0]
    procedures = [p for p in PROCEDURES if p[1] in grids and grids[p[1]]]
    for outer in present:
        training = [f for f in present if f != outer]
        scores = []
        for choice, grid in procedures:
            errors = []
            try:
                for inner in training:
                    rest = [columns[f] for f in training if f != inner]
                    chosen = _pick(cv, rest, grids[grid], allowed, choice)
                    errors += [float(cv.errors[chosen, j]) for j in columns[inner]]
            except ValueError:  # the constraint allows no point of this grid
                errors = [float("inf")]
            scores.append(float(np.mean(errors)))
        choice, grid = procedures[int(np.argmin(scores))]
        chosen = _pick(cv, [columns[f] for f in training], grids[grid], allowed, choice)
        cv.nested_procedure[outer] = f"{choice}, {grid}"
        for j in columns[outer]:
            cv.nested[names[j]] = float(cv.errors[chosen, j])


def _point_label(point: dict[str, float]) -> str:
    return ", ".join(f"{k}={v:g}" for k, v in point.items())


@dataclass
class _Allowed:
    """Why grid point i of an estimator may not be chosen (None: it may), each point judged
    once."""

    key: str
    points: list[dict[str, float]]
    constraint: Callable[[str, dict[str, float]], str | None] | None
    battery_keeps: str | None = None
    """Why the battery keeps the longer vector (EstimatorCv.battery_keeps): a point without it
    may not be chosen."""
    verdicts: dict[int, str | None] = field(default_factory=dict)

    def __call__(self, i: int) -> str | None:
        if self.battery_keeps and self.points[i].get("acc_lowpass_stretch") == 1.0:
            return f"leaves out the longer vector, which the battery keeps ({self.battery_keeps})"
        if self.constraint is None:
            return None
        if i not in self.verdicts:
            self.verdicts[i] = self.constraint(self.key, self.points[i])
        return self.verdicts[i]


def _first_allowed(order: np.ndarray, cv: EstimatorCv, allowed: _Allowed,
                   record: bool = True) -> int:
    """The first grid point of order that allowed lets be chosen; with record, the refused ones
    before it go to cv.refused with the reason."""
    for i in order:
        why = allowed(int(i))
        if why is None:
            return int(i)
        if record:
            cv.refused[_point_label(allowed.points[int(i)])] = why
    raise ValueError(f"no grid point of {allowed.key} keeps the contract (e.g. "
                     f"{allowed(int(order[0]))}): give values nearer its defaults")


def _choose(cv: EstimatorCv, folds: list[list[int]], allowed: _Allowed, choice: str) -> int:
    """The grid point chosen on the training trials among every point of the grid (_pick),
    the refused ones ahead of it recorded."""
    return _pick(cv, folds, list(range(len(cv.grid))), allowed, choice, record=True)


def check_grid(grid: Grid, estimators: Sequence[str]) -> None:
    """ValueError saying what is wrong unless every parameter of grid belongs to at least one
    of the estimators and each of its values (at least one) is inside its range there."""
    for name, values in grid.items():
        owners = [k for k in estimators if name in ESTIMATORS[k].param_specs()]
        if not owners:
            allowed = sorted({n for k in estimators for n in ESTIMATORS[k].param_specs()})
            raise ValueError(f"--cv-grid: {name} is no parameter of {', '.join(estimators)}; "
                             f"allowed: {', '.join(allowed)}")
        if not values:
            raise ValueError(f"--cv-grid: {name} needs at least one value")
        for key in owners:
            spec = ESTIMATORS[key].param_specs()[name]
            for v in values:
                try:
                    spec.validate(v)
                except ValueError as err:
                    raise ValueError(f"--cv-grid: {key}: {err}") from None


def parse_grid(entries: Sequence[str]) -> dict[str, list[float]]:
    """--cv-grid's NAME=V1,V2,... entries as a grid; ValueError naming the entry that is not of
    that form."""
    grid: dict[str, list[float]] = {}
    for entry in entries:
        name, sep, values = entry.partition("=")
        try:
            if not sep or not name.strip():
                raise ValueError
            parsed = [float(v) for v in values.split(",") if v.strip()]
        except ValueError:
            raise ValueError(f"--cv-grid {entry!r}: expected NAME=V1,V2,... with numbers, e.g. "
                             f"acc_lowpass=1,1.5,2") from None
        if name.strip() in grid:
            raise ValueError(f"--cv-grid: {name.strip()} is given twice; give its values once, "
                             f"comma-separated")
        grid[name.strip()] = parsed
    return grid


def cv_table(result: CvResult) -> str:
    """Per estimator and fold: in-sample (the defaults), cross-validated, and the peers on the
    same trials; then the mean over all trials."""
    present = [f for f in FOLDS if f in result.folds.values()]
    head = f"{'estimator':10s} {'figure':10s} " + " ".join(f"{f[:18]:>18s}" for f in present) \
        + f" {'mean':>7s}"
    lines = ["BROAD inclination RMSE [deg], leave one motion fold out (testbenches.broad.cv)",
             head, "-" * len(head)]
    for key, e in result.estimators.items():
        for label, values in (("in-sample", e.in_sample), ("cv", e.held_out),
                              ("nested cv", e.nested)):
            if not values:
                continue
            cells = " ".join(f"{result.fold_mean(values, f):18.3f}" for f in present)
            lines.append(f"{key:10s} {label:10s} {cells} {np.mean(list(values.values())):7.3f}")
    for name, values in result.peers.items():
        cells = " ".join(f"{result.fold_mean(values, f):18.3f}" for f in present)
        lines.append(f"{name:10s} {'(no fit)':10s} {cells} {np.mean(list(values.values())):7.3f}")
    lines.append("")
    lines.append("chosen without each fold (" + ", ".join(result.grid) + " where the "
                 "estimator has it" + ("; among the points that keep the contract's accuracy "
                                       "bounds" if result.constrained else "")
                 + "; " + CHOICE_PHRASES[result.choice] + "):")
    for key, e in result.estimators.items():
        chosen = "; ".join(f"{f}: " + "/".join(f"{v:g}" for v in e.chosen[f].values())
                           for f in present)
        default = "/".join(f"{v:g}" for v in e.defaults.values())
        scan = "/".join(f"{v:g}" for v in e.scan_choice.values())
        lines.append(f"  {key:5s} default {default}; on all trials {scan} "
                     f"({e.scan_mean():.3f}); {chosen}")
        for point, why in e.refused.items():
            lines.append(f"        refused {point}: {why}")
    if any(e.nested_procedure for e in result.estimators.values()):
        lines.append("")
        lines.append("nested: the procedure (choice rule, grid) each fold's training folds chose "
                     "by their own inner cross-validation:")
        for key, e in result.estimators.items():
            lines.append(f"  {key:5s} " + "; ".join(f"{f}: {p}"
                                                   for f, p in e.nested_procedure.items()))
    kept = {key: e.battery_keeps for key, e in result.estimators.items() if e.battery_keeps}
    if kept:
        lines.append("")
        lines.append("no choice above takes a point without the longer vector "
                     "(acc_lowpass_stretch 1) where the battery keeps it (testbenches.mechanisms):")
        lines += [f"  {key:5s} {why}" for key, why in kept.items()]
    return "\n".join(lines)


def plot_cv(result: CvResult, path: Path) -> None:
    """Bars per motion fold and over all trials: each estimator's in-sample figure (light) and
    cross-validated one (dark) side by side, each peer's as a dashed line across its group."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    present = [f for f in FOLDS if f in result.folds.values()]
    groups = [*present, "all"]

    def figure(values: dict[str, float], group: str) -> float:
        return (float(np.mean(list(values.values()))) if group == "all"
                else result.fold_mean(values, group))

    keys = list(result.estimators)
    x = np.arange(len(groups))
    width = 0.8 / max(1, 2 * len(keys))
    fig, ax = plt.subplots(figsize=(3.0 + 1.6 * len(groups), 4.5))
    for i, key in enumerate(keys):
        e = result.estimators[key]
        color = plt.cm.tab10(i % 10)
        base = x + (2 * i - (2 * len(keys) - 1) / 2) * width
        ax.bar(base, [figure(e.in_sample, g) for g in groups], width, color=color, alpha=0.35,
               label=f"{key} in sample")
        ax.bar(base + width, [figure(e.held_out, g) for g in groups], width, color=color,
               label=f"{key} cross-validated")
    for j, (name, values) in enumerate(result.peers.items()):
        for k, g in enumerate(groups):
            ax.hlines(figure(values, g), x[k] - 0.42, x[k] + 0.42, colors="k",
                      linestyles="--" if j == 0 else ":", label=name if k == 0 else None)
    ax.set_xticks(x, [g.replace("_", " ") for g in groups], fontsize=8)
    ax.set_ylabel("mean inclination RMSE [deg]")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7, ncol=4, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    ax.set_title("BROAD, leave one motion fold out: in sample against cross-validated")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


__all__ = ["CHOICES", "CV_ESTIMATORS", "CV_GRID", "FOLDS", "CvResult", "EstimatorCv", "Grid",
           "check_grid", "cross_validate", "cv_table", "fold_of", "parse_grid", "plot_cv"]
