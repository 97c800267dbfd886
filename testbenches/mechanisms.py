"""`imu-fusion mechanisms DIR`: what each mechanism of the recommended attitude filters is
worth on recordings it was not chosen on.

A mechanism (MECHANISMS: the accelerometer pre-filter, its adaptive noise, the fast leak taken
off its slow band and the band's cap at a held acceleration, the longer vector, the
scale-error process noise, rest detection and its turn-on rule, the bias gates, the variance
after a gross innovation, the accelerometer gate) on
by default is switched off by the parameter values that turn it off, and one this test dropped
from a filter's defaults is switched on again by the values it has where it is on
(Mechanism.on), everything else at the recommended values; the filter is scored with and
without it three ways:

- **BROAD, leave one motion fold out** (testbenches.broad.cv.FOLDS): whether to keep it is decided
  on three folds' trials, by the rule `broad --cv` chooses grid points with (the smallest regret
  over the training folds), and scored on the fourth fold's; the cross-validated mean is over
  every trial's error under the decision made without its fold. Keeping or dropping is then the
  one value chosen by data, and its worth is the cross-validated mean of always dropping it
  minus that of deciding per fold.
- **The battery** (testbenches.battery): every motion class x sensor class on PARTS parts, with
  and without it; the geometric mean over the cells of the ratio of the mean RMSE without to
  with (above 1: the mechanism helps) and the worst cell.

- **The contract over parts** (testbenches.parts, as delivered): the accuracy checks that pass
  with it and fail without. A mechanism the contract needs keeps its place whatever the rest;
  its scenarios count as cells of a battery too (the mean RMSE over the parts without / with).

Otherwise a mechanism keeps its place where BROAD and the battery's mean both say it lowers the
error, or where neither does but one of the battery's cells or the contract's scenarios needs it
(MOTION_CLASS_GAIN); where nothing does, it is a candidate to drop; else the table says which
way each points. A dropped mechanism is judged by the same rules with it switched on: where
they would keep it, it is a candidate to come back. Mechanisms can cover for each other (the two
gates on bias learning did): one switched off at a time shows only what the other leaves, so
they change one at a time and the rest are scored again after each.

The grid values of the other parameters were chosen with the mechanisms as they are. Dropping
one, or taking a dropped one back, changes what the folds choose as well, so a candidate to
change is scored once more with the grid chosen again per fold, without it and with it, as
`broad --cv` chooses it (grid_worth): cross-validated and nested-cross-validated. A filter's
set of mechanisms changes only where both agree: a mechanism on stays where either finds the
folds so chosen worse without it, and a dropped one comes back only where both find them
better with it.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from fusion_core.building_blocks.gate import BIAS_GATE, BIAS_INNOVATION, GROSS_INNOVATION
from fusion_core.measured_vector import BURST_PARAM, HELD_PARAM, LEAK_PARAM
from fusion_core.papers.common import PAPER_GATE

T = TypeVar("T")
TIE = 0.005
"""Relative differences below this count as level (half a percent of the error)."""
MOTION_CLASS_GAIN = 1.1
"""A mechanism that neither BROAD nor the battery's mean keeps still keeps its place where on one
of the battery's cells (a motion class on a sensor class, 20 parts) the error without it is this
many times the error with it: a mechanism made for one kind of motion."""


@dataclass(frozen=True)
class Mechanism:
    """A mechanism of the recommended filters, the parameter values that switch it off and
    those that switch it on again in a filter whose defaults dropped it (none: never dropped)."""

    name: str
    what: str
    off: dict[str, float]
    on: dict[str, float] = field(default_factory=dict)

    def _at_off(self, key: str) -> list[bool] | None:
        """For each parameter that switches it off, whether estimator `key`'s default is
        already its off value; None where the estimator lacks one of them."""
        from fusion_core.registry import ESTIMATORS

        specs = ESTIMATORS[key].param_specs()
        if not all(p in specs for p in self.off):
            return None
        return [specs[p].default == v for p, v in self.off.items()]

    def applies(self, key: str) -> bool:
        """Whether estimator `key` has it on by default: every parameter that switches it off,
        none of them at its off value already (a mechanism dropped from the defaults, or a pair
        of which one is dropped, is not scored again)."""
        at_off = self._at_off(key)
        return at_off is not None and not any(at_off)

    def dropped(self, key: str) -> bool:
        """Whether estimator `key` has its parameters with every one at its off value by
        default: a mechanism this test dropped from its defaults."""
        at_off = self._at_off(key)
        return at_off is not None and all(at_off)

    def switch(self, key: str) -> dict[str, float] | None:
        """The parameter values that change estimator `key`'s mechanism: `off` where its
        defaults have it on, `on` where they dropped it, None where it is not scored (neither,
        or dropped with no `on`)."""
        if self.applies(key):
            return self.off
        if self.dropped(key) and self.on:
            return self.on
        return None


MECHANISMS: tuple[Mechanism, ...] = (
    Mechanism("prefilter", "the accelerometer pre-filter in a frame turning with the gyro, with "
              "the adaptive noise and slow band that ride on it (acc_lowpass 0)",
              {"acc_lowpass": 0.0, "disturbance_time": 0.0}),
    Mechanism("adaptive_noise", "measurement noise and pre-filter length that follow the "
              "measured linear acceleration (disturbance_time 0)", {"disturbance_time": 0.0}),
    Mechanism("band_leak", "the fast disturbance that leaks through the slow band taken off "
              "its statistic (slow_band_leak 0)", {"slow_band_leak": 0.0},
              {"slow_band_leak": float(LEAK_PARAM.default)}),
    Mechanism("held_acceleration", "the slow band's statistic counts no more than a held "
              "linear acceleration, g tan 30 deg (held_acceleration 0)",
              {"held_acceleration": 0.0}, {"held_acceleration": float(HELD_PARAM.default)}),
    Mechanism("burst", "a burst of white samples far from any motion kept out of the measured "
              "vector, which fills again after it (burst_acceleration 0)",
              {"burst_acceleration": 0.0}, {"burst_acceleration": float(BURST_PARAM.default)}),
    Mechanism("longer_vector", "the vector grows where slow linear acceleration reaches it "
              "(acc_lowpass_stretch 1)", {"acc_lowpass_stretch": 1.0}),
    Mechanism("scale_noise", "process noise for the gyro's scale error while it turns "
              "(gyro_scale_std 0)", {"gyro_scale_std": 0.0}),
    Mechanism("rest", "rest detection and its zero-rate update (rest_time 0)", {"rest_time": 0.0}),
    Mechanism("turn_on_rest", "before the first rest, a rest may start within the turn-on bias "
              "bound of the estimate (rest_bias_bound 0: VQF's rule)", {"rest_bias_bound": 0.0}),
    Mechanism("motion_bias", "the complementary filters' bias learned in motion until the "
              "first rest (motion_bias_gain 0)", {"motion_bias_gain": 0.0}),
    Mechanism("bias_gate", "no bias learning while linear acceleration reaches the vector "
              "(bias_gate 0)", {"bias_gate": 0.0}, {"bias_gate": BIAS_GATE}),
    Mechanism("bias_innovation", "no bias learning from a tilt innovation beyond 10 deg "
              "(bias_innovation pi)", {"bias_innovation": math.pi},
              {"bias_innovation": BIAS_INNOVATION}),
    Mechanism("gross_innovation", "the angle's variance raised to a tilt innovation beyond 30 "
              "deg, an attitude grossly off (gross_innovation pi)", {"gross_innovation": math.pi},
              {"gross_innovation": GROSS_INNOVATION}),
    Mechanism("acc_gate", "no correction from a sample whose norm is outside gate_low-gate_high "
              "g (gate_low 0, gate_high 1000)", {"gate_low": 0.0, "gate_high": 1000.0},
              {p.name: float(p.default) for p in PAPER_GATE}),
)
"""Every mechanism the recommended attitude filters have on top of their paper's filter that a
parameter switches off, and those this test dropped (off by default, Mechanism.dropped; their
parameters kept for a user's own values, and `on` the values it has where it is on: another
filter's default or its parameter's own (a gate on the innovation at 10 deg, BIAS_INNOVATION),
or the papers' 0.9-1.1 g for the accelerometer gate, papers.common.PAPER_GATE)."""
BY_NAME = {m.name: m for m in MECHANISMS}


def _vote(gain: float) -> str:
    """keep, level or drop for a relative gain from the mechanism (TIE)."""
    return "keep" if gain > TIE else ("drop" if gain < -TIE else "level")


@dataclass
class Worth:
    """One mechanism of one estimator: BROAD with and without, the folds' decisions and the
    battery's ratio. Every figure is with it and without it, whichever the defaults have."""

    key: str
    mechanism: str
    broad_on: dict[str, float]
    broad_off: dict[str, float]
    kept_in: list[str]
    """The folds whose training trials decided to keep it."""
    cv_decided: dict[str, float]
    """trial -> RMSE [deg] under the decision made without its fold."""
    battery_ratio: float = math.nan
    """Geometric mean over the battery's cells of mean RMSE without / with."""
    battery_worst: tuple[str, float] = ("", math.nan)
    """The cell where dropping it helps most: (motion/class, ratio without / with)."""
    battery_best: tuple[str, float] = ("", math.nan)
    """The cell where it helps most: (motion/class, ratio without / with)."""
    contract_lost: list[str] | None = None
    """The contract's checks over parts (as delivered) that pass with it and fail without
    (None: not run)."""
    contract_best: tuple[str, float] = ("", math.nan)
    """The contract's scenario where it helps most: (scenario, mean RMSE over the parts
    without / with): the contract's scenarios are a battery of motions too."""
    grid_cv: tuple[float, float] | None = None
    """For a candidate to change (would_change): BROAD's cross-validated mean [deg] with the
    grid parameters chosen again per fold (testbenches.broad.cv), without it and with it (None:
    not a candidate, or BROAD's folds not measured so)."""
    grid_nested: tuple[float, float] = (math.nan, math.nan)
    """With grid_cv: the nested cross-validation's mean [deg] of the same runs, without it and
    with it (NaN: fewer than three folds)."""
    dropped: bool = False
    """Whether the estimator's defaults have it off (Mechanism.dropped): `with` is then the
    mechanism switched on again (Mechanism.on)."""

    def broad_gain(self) -> float:
        """Cross-validated mean of always dropping it minus that of deciding per fold [deg]."""
        return float(np.mean(list(self.broad_off.values()))
                     - np.mean(list(self.cv_decided.values())))

    def _battery_vote(self) -> str | None:
        """What the battery's mean says: keep, level or drop (TIE); None where not run."""
        return _vote(self.battery_ratio - 1.0) if math.isfinite(self.battery_ratio) else None

    def _needed_by(self) -> tuple[str, float] | None:
        """The battery cell that needs it (MOTION_CLASS_GAIN times the error without it), or
        None."""
        cell, ratio = self.battery_best
        return (cell, ratio) if ratio >= MOTION_CLASS_GAIN else None

    def battery_keeps(self) -> str | None:
        """Why the battery alone keeps it (its mean lowered by more than the tie, or one cell
        MOTION_CLASS_GAIN times the error without it), None where it does not or was not run:
        BROAD's folds alone then never drop it (_at_point, testbenches.broad.cv.nested_cv)."""
        if self._battery_vote() == "keep":
            return f"its mean error {self.battery_ratio:.3f} times as large without it"
        needed = self._needed_by()
        return f"its {needed[0]} error {needed[1]:.2f} times as large without it" if needed \
            else None

    def _at_point(self) -> str:
        """The verdict at the recommended grid point: keep, mixed or drop."""
        if self.contract_lost:
            n = len(self.contract_lost)
            return f"keeps its place: the contract needs it ({n} check{'s' if n != 1 else ''})"
        broad = self.broad_gain() / float(np.mean(list(self.broad_off.values())))
        says = {"BROAD": _vote(broad)}
        battery = self._battery_vote()
        if battery is not None:
            says["battery"] = battery
        votes = set(says.values())
        if votes == {"keep"} or votes == {"keep", "level"}:
            return "keeps its place"
        if "keep" in votes:
            return "mixed: " + ", ".join(f"{k} {v}" for k, v in says.items())
        needed = self._needed_by()
        if needed is not None:
            return f"keeps its place for {needed[0]}"
        scenario, ratio = self.contract_best
        if ratio >= MOTION_CLASS_GAIN:
            return f"keeps its place for the contract's {scenario} ({ratio:.2f}x without)"
        return "drop: no gain out of sample"

    def _grid_helps(self) -> tuple[bool, bool]:
        """Whether, with the grid chosen again, the cross-validated and the nested means are
        lower with it than without by more than the tie."""
        assert self.grid_cv is not None
        (cv_off, cv_on), (nested_off, nested_on) = self.grid_cv, self.grid_nested
        return (cv_off - cv_on) / cv_off > TIE, (nested_off - nested_on) / nested_off > TIE

    def verdict(self) -> str:
        """What the test does with it: the verdict at the recommended point, and for a
        candidate to change, what the grid chosen again says (the set of mechanisms changes
        only where the cross-validation and the nested one agree)."""
        at_point = self._at_point()
        if not self.dropped:
            if at_point.startswith("drop") and self.grid_cv is not None and any(
                    self._grid_helps()):
                return "keeps its place: with the grid chosen again, BROAD's folds need it"
            return at_point
        if at_point.startswith("drop"):
            return "stays dropped: no gain out of sample"
        if at_point.startswith("mixed"):
            return f"stays dropped: {at_point}"
        would = at_point.replace("keeps its place", "it would keep a place", 1)
        if self.grid_cv is None:
            return f"would come back: at the recommended point {would}"
        if all(self._grid_helps()):
            return f"comes back: at the recommended point {would}, and with the grid chosen again"
        return (f"stays dropped: at the recommended point {would}, but with the grid chosen "
                "again the two cross-validations do not both gain")

    def would_change(self) -> bool:
        """Whether the verdict at the recommended grid point changes the defaults (drops a
        mechanism on, or takes a dropped one back): the candidates whose grid is chosen again
        (grid_worth) first."""
        return self.grid_cv is None and self.verdict().startswith(("drop", "would come back"))


def with_without(dropped: bool, as_is: T, switched: T) -> tuple[T, T]:
    """A figure of the filter as it is and one with the mechanism switched, as (with it,
    without it): the switched one is "with" where the defaults dropped the mechanism."""
    return (switched, as_is) if dropped else (as_is, switched)


def decide(on: dict[str, float], off: dict[str, float], folds: dict[str, str],
           training: Sequence[str]) -> bool:
    """Whether the training folds keep the mechanism: the smaller regret (each training fold's
    mean RMSE over the better of the two on it, the worst fold's), ties to the lower training
    mean, and a level outcome to dropping it (the simpler filter)."""
    def fold_mean(values: dict[str, float], fold: str) -> float:
        return float(np.mean([v for t, v in values.items() if folds[t] == fold]))

    regret = {}
    for name, values in (("on", on), ("off", off)):
        regret[name] = max(fold_mean(values, f) / min(fold_mean(on, f), fold_mean(off, f))
                           for f in training)
    if abs(regret["on"] - regret["off"]) > 1e-12:
        return regret["on"] < regret["off"]
    mean_on = np.mean([v for t, v in on.items() if folds[t] in training])
    mean_off = np.mean([v for t, v in off.items() if folds[t] in training])
    return bool(mean_on < mean_off)


def broad_worth(trials: Sequence[Any], groups: Sequence[Sequence[str]], estimators: Sequence[str],
                mechanisms: Sequence[Mechanism] = MECHANISMS,
                progress: Callable[[], None] | None = None) -> dict[tuple[str, str], Worth]:
    """Each (estimator, mechanism it has or dropped, Mechanism.switch): its BROAD errors with
    and without and the folds' decisions."""
    from .broad.cv import FOLDS, _rmse, fold_of
    from .broad.run import run_fusion_core

    folds = {t.name: fold_of(g) for t, g in zip(trials, groups, strict=True)}
    present = [f for f in FOLDS if f in folds.values()]
    if len(present) < 2:
        raise ValueError("the mechanisms' cross-validation needs trials of at least two motion "
                         f"folds ({', '.join(FOLDS)})")

    def errors(key: str, params: dict[str, float]) -> dict[str, float]:
        out = {}
        for trial in trials:
            r = run_fusion_core(key, params, trial)
            out[trial.name] = _rmse(trial, r["roll"], r["pitch"])
            if progress:
                progress()
        return out

    worth = {}
    for key in estimators:
        as_is = errors(key, {})
        for m in mechanisms:
            switch = m.switch(key)
            if switch is None:
                continue
            dropped = not m.applies(key)
            on, off = with_without(dropped, as_is, errors(key, switch))
            kept, decided = [], {}
            for fold in present:
                keep = decide(on, off, folds, [f for f in present if f != fold])
                kept += [fold] if keep else []
                decided.update({t: (on if keep else off)[t] for t in on if folds[t] == fold})
            worth[(key, m.name)] = Worth(key, m.name, on, off, kept, decided, dropped=dropped)
    return worth


def battery_worth(worth: dict[tuple[str, str], Worth], parts: int, scheduler: str | None,
                  workers: int, progress: Callable[[], None] | None = None) -> None:
    """Fill each Worth's battery ratio: the battery with every filter at its defaults and once
    per mechanism with it switched (Mechanism.switch: off where it is on, on where it was
    dropped) in the filters that score it."""
    from .battery import MOTIONS, SENSOR_CLASSES, run_variants, stats

    keys = sorted({k for k, _ in worth}, key=list(dict.fromkeys(k for k, _ in worth)).index)
    names = list(dict.fromkeys(m for _, m in worth))
    variants: dict[str, dict[str, dict[str, Any]]] = {"": {}}
    for name in names:
        variants[name] = {k: BY_NAME[name].switch(k) or {} for k in keys if (k, name) in worth}
    results = run_variants(variants, list(MOTIONS), list(SENSOR_CLASSES), parts, scheduler,
                           workers, progress, keys)
    for (key, name), w in worth.items():
        ratios = {}
        with_it, without = with_without(w.dropped, "", name)
        for motion in MOTIONS:
            for sensor in SENSOR_CLASSES:
                on = stats(results[with_it][motion][sensor][key])[0]
                off = stats(results[without][motion][sensor][key])[0]
                ratios[f"{motion}/{sensor}"] = off / on
        w.battery_ratio = float(np.exp(np.mean(np.log(list(ratios.values())))))
        cell = min(ratios, key=lambda c: ratios[c])
        w.battery_worst = (cell, ratios[cell])
        cell = max(ratios, key=lambda c: ratios[c])
        w.battery_best = (cell, ratios[cell])


def longer_vector_on_battery(keys: Sequence[str], parts: int, scheduler: str | None,
                             workers: int, progress: Callable[[], None] | None = None
                             ) -> dict[str, str | None]:
    """estimator -> why the battery keeps its longer vector (Worth.battery_keeps), or None:
    the battery with and without it in each filter of `keys` that has it on, as battery_worth
    runs it. For `broad --cv`'s nested cross-validation (testbenches.broad.cv.PROCEDURES)."""
    m = BY_NAME["longer_vector"]
    worth = {(k, m.name): Worth(k, m.name, {}, {}, [], {}) for k in keys if m.applies(k)}
    if worth:
        battery_worth(worth, parts, scheduler, workers, progress)
    return {k: w.battery_keeps() for (k, _), w in worth.items()}


def grid_worth(worth: dict[tuple[str, str], Worth], trials: Sequence[Any],
               groups: Sequence[Sequence[str]],
               progress: Callable[[str], None] | None = None) -> None:
    """Fill grid_cv and grid_nested of every candidate to change (Worth.would_change): `broad
    --cv`'s cross-validation of the grid parameters (CV_GRID, among the points that keep the
    contract, by the smallest regret) and its nested cross-validation, with the filter as it is
    and with the mechanism switched (Mechanism.switch). At the recommended point a mechanism may
    look level while the choices the folds make without it are worse: the slow band's fast
    leak keeps the band's statistic from counting a bounce, and without it the folds that
    never saw a disturbed trial take a longer band."""
    from .broad.cv import cross_validate

    kept = {k: w.battery_keeps() for (k, name), w in worth.items() if name == "longer_vector"}

    def means(key: str, base: dict[str, float] | None) -> tuple[float, float]:
        e = cross_validate(trials, groups, [key], progress=progress, base=base,
                           battery_keeps=kept).estimators[key]
        return e.cv_mean(), e.nested_mean()

    as_is: dict[str, tuple[float, float]] = {}
    for (key, name), w in worth.items():
        if not w.would_change():
            continue
        if key not in as_is:
            as_is[key] = means(key, None)
        switched = means(key, BY_NAME[name].switch(key))
        on, off = with_without(w.dropped, as_is[key], switched)
        w.grid_cv, w.grid_nested = (off[0], on[0]), (off[1], on[1])


def contract_worth(worth: dict[tuple[str, str], Worth], parts: int,
                   progress: Callable[[], None] | None = None) -> None:
    """Fill each Worth's contract_lost: the contract's accuracy checks over `parts` parts (as
    delivered, the realistic sensor; testbenches.parts) with the filter at its defaults and
    with the mechanism off."""
    from fusion_core.scenarios import ESTIMATION_SCENARIOS

    from .contract import bound
    from .parts import HOW, part_rmse, share_within

    def passing(key: str, params: dict[str, float]) -> tuple[set[str], dict[str, float]]:
        rmse = part_rmse([key], ESTIMATION_SCENARIOS, {}, {}, parts, params,
                         calibrated_first=(False,))
        if progress:
            progress()
        return ({s for (_, _, s), v in rmse.items()
                 if share_within(v, bound(key, s)) >= HOW[False][1]},
                {s: float(np.mean(v)) for (_, _, s), v in rmse.items()})

    base = {key: passing(key, {}) for key in dict.fromkeys(k for k, _ in worth)}
    for (key, name), w in worth.items():
        switched = passing(key, BY_NAME[name].switch(key) or {})
        (passed, on), (failed, off) = with_without(w.dropped, base[key], switched)
        w.contract_lost = sorted(passed - failed)
        w.contract_best = max(((s, off[s] / on[s]) for s in off if on[s] > 0.0),
                              key=lambda c: c[1], default=("", math.nan))


def worth_table(worth: dict[tuple[str, str], Worth]) -> str:
    """Markdown: per estimator and mechanism (those its defaults dropped marked so), BROAD's
    means with and without, the folds that keep it, the cross-validated gain, the battery's
    ratio, the contract, the grid chosen again and the verdict."""
    rows = ["| estimator | mechanism | BROAD with | without | folds keeping it | CV gain [deg] "
            "| battery without / with | cell it helps most | cell it costs most | contract checks "
            "lost without | grid chosen again: CV without / with; nested [deg] | verdict |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (key, name), w in worth.items():
        lost = "-" if w.contract_lost is None else (", ".join(w.contract_lost) or "none")
        worst, best = ((f"{c} {r:.2f}" if math.isfinite(r) else "-")
                       for c, r in (w.battery_worst, w.battery_best))
        ratio = f"{w.battery_ratio:.3f}" if math.isfinite(w.battery_ratio) else "-"
        grid = "-" if w.grid_cv is None else "; ".join(
            f"{off:.3f} / {on:.3f}" for off, on in (w.grid_cv, w.grid_nested))
        label = f"{name} (dropped)" if w.dropped else name
        rows.append(
            f"| {key} | {label} | {np.mean(list(w.broad_on.values())):.3f} | "
            f"{np.mean(list(w.broad_off.values())):.3f} | {len(w.kept_in)} of 4 | "
            f"{w.broad_gain():+.3f} | {ratio} | {best} | {worst} | {lost} | {grid} | "
            f"{w.verdict()} |")
    return "\n".join(rows)


def add_mechanisms_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    from .options import add_cluster, out_folder

    p = sub.add_parser(
        "mechanisms", help="what each mechanism of the recommended attitude filters is worth "
        "out of sample: BROAD's folds and the battery", description=__doc__.split("\n\n")[0])
    p.add_argument("paths", nargs="+", type=Path, help="BROAD trial files or folders")
    p.add_argument("--estimator", default="all", help="all, or some of cf, mgcf, kf, ukf")
    p.add_argument("--mechanism", default="all",
                   help=f"all, or some of {', '.join(m.name for m in MECHANISMS)}")
    p.add_argument("--parts", type=int, default=None,
                   help="parts of each sensor class in the battery and of the contract's checks "
                   "(default: the battery's; 0 leaves both out)")
    p.add_argument("--trials-json", type=Path, default=None,
                   help="BROAD's trials.json (default: beside the files)")
    add_cluster(p)
    p.add_argument("--out", type=out_folder, default=Path("reports/mechanisms"),
                   help="where mechanisms.json and mechanisms.md go")
    p.set_defaults(func=cmd_mechanisms)


def load_trials(paths: Sequence[Path], trials_json: Path | None = None
                ) -> tuple[list[Any], list[list[str]]]:
    """The BROAD trials of the files and folders and each one's groups (from trials.json, given
    or found beside them, else from the names)."""
    from .broad.data import find_trials_json, load_trial, load_trials_json, trial_groups
    from .broad.run import collect_paths

    files = collect_paths(paths)
    if not files:
        raise ValueError(f"no trial files in {', '.join(map(str, paths))}")
    trials = [load_trial(f) for f in files]
    found = trials_json or find_trials_json(paths)
    info = load_trials_json(found) if found else None
    return trials, [trial_groups(t.name, info) for t in trials]


def measure(trials: Sequence[Any], groups: Sequence[Sequence[str]], estimators: Sequence[str],
            mechanisms: Sequence[Mechanism], parts: int, scheduler: str | None = "local",
            workers: int = 2, bar: Callable[..., Any] | None = None
            ) -> dict[tuple[str, str], Worth]:
    """Every Worth of the estimators' mechanisms: BROAD's, and with parts > 0 the contract's
    and the battery's. bar(total=, desc=, unit=): a progress bar per stage (tqdm's
    signature), or None."""
    import contextlib

    def stage(total: int, desc: str, unit: str) -> Any:
        return bar(total=total, desc=desc, unit=unit) if bar else contextlib.nullcontext()

    def step(b: Any) -> Callable[[], None] | None:
        return b.update if b is not None else None

    runs = sum(len(trials) * (1 + sum(m.switch(k) is not None for m in mechanisms))
               for k in estimators)
    with stage(runs, "BROAD", "run") as b:
        worth = broad_worth(trials, groups, estimators, mechanisms, step(b))
    if parts > 0:
        from .battery import MOTIONS, SENSOR_CLASSES

        with stage(len(worth) + len(estimators), "contract", "filter") as b:
            contract_worth(worth, parts, step(b))
        cells = (1 + len({m for _, m in worth})) * len(MOTIONS) * len(SENSOR_CLASSES)
        with stage(cells, "battery", "cell") as b:
            battery_worth(worth, parts, scheduler, workers, step(b))
    candidates = {k for (k, _), w in worth.items() if w.would_change()}
    runs = len(trials) * (len(candidates) + sum(w.would_change() for w in worth.values()))
    with stage(runs, "BROAD's grid", "trial") as b:
        grid_worth(worth, trials, groups, (lambda _: b.update()) if b is not None else None)
    return worth


def cmd_mechanisms(args: argparse.Namespace) -> int:
    import functools
    import json

    from tqdm import tqdm

    from fusion_core.registry import ATTITUDE_FILTERS

    from .battery import PARTS
    from .options import choose

    keys = choose(args.estimator, list(ATTITUDE_FILTERS), "estimator")
    chosen = [BY_NAME[n] for n in choose(args.mechanism, list(BY_NAME), "mechanism")]
    parts = PARTS if args.parts is None else args.parts
    trials, groups = load_trials(args.paths, args.trials_json)
    worth = measure(trials, groups, keys, chosen, parts, args.scheduler, args.workers,
                    functools.partial(tqdm, disable=None))
    table = worth_table(worth)
    print(table)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "mechanisms.md").write_text(table + "\n")
    (args.out / "mechanisms.json").write_text(json.dumps({
        "parts": parts, "tie": TIE,
        "mechanisms": {m.name: {"what": m.what, "off": m.off} for m in chosen},
        "worth": [{"estimator": w.key, "mechanism": w.mechanism, "broad_on_deg": w.broad_on,
                   "broad_off_deg": w.broad_off, "folds_keeping": w.kept_in,
                   "cv_decided_deg": w.cv_decided, "cv_gain_deg": w.broad_gain(),
                   "battery_off_over_on": w.battery_ratio,
                   "battery_worst_cell": list(w.battery_worst),
                   "battery_best_cell": list(w.battery_best),
                   "contract_checks_lost": w.contract_lost,
                   "contract_best": list(w.contract_best),
                   "grid_cv_without_with_deg": w.grid_cv,
                   "grid_nested_without_with_deg": w.grid_nested if w.grid_cv else None,
                   "dropped": w.dropped, "verdict": w.verdict()}
                  for w in worth.values()]}, indent=1))
    print(f"written: {args.out}/mechanisms.md, mechanisms.json")
    return 0
