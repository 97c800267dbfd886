"""`python -m testbenches tune`: an estimator's tunable parameters fitted to recordings with a
reference, and checked on others.

By default it fits the parameters physics leaves open (the class's Estimator.SCANNED); --params
names others. The objective is the mean inclination RMSE [deg] over the fit recordings (BROAD's
metric: the angle between the estimated and the reference up direction, over the samples that
count), each run through fusion_core (the C twin where it is built). Each parameter stays
within its allowed range and is searched in log space where the range reaches decades above the
start (noise densities, time constants: a factor matters, not a difference).

Method: scipy.optimize.minimize(method="Powell") with bounds. Powell's method needs no
derivatives (the RMSE of a filter run has none to offer, and is a little rough in its
parameters), honours bounds, and moves one direction at a time with line searches, so that a
few parameters converge in tens of runs each. The objective is the mean plus PENALTY times any fit
recording's excess over MAX_WORSE above its start; the best point evaluated is kept, the start
included: the fit never ends worse than its start on the fit set.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core import ESTIMATORS
from fusion_core.base import Estimator
from fusion_core.registry import create, estimator_class
from fusion_core.types import Param

from ..broad.metric import gravity_from_roll_pitch, inclination_rmse_deg
from .recording import Recording, RecordingError

MAX_WORSE = 0.03
"""No fit recording may end more than 3 % worse than at the start: a parameter set that buys
the mean by trading one recording (one kind of motion) for another is what does not carry over
to other recordings (the validation recordings show it)."""
PENALTY = 10.0
"""The objective adds PENALTY times every fit recording's excess over its bound [deg]."""
SPAN = 100.0
"""An unbounded side of a log-space parameter is searched up to this factor from its start."""


@dataclass(frozen=True)
class Dimension:
    """One fitted parameter: its name, search bounds and whether the search is in log space."""

    name: str
    low: float
    high: float
    log: bool

    def to_search(self, value: float) -> float:
        return math.log(value) if self.log else value

    def from_search(self, x: float) -> float:
        return math.exp(x) if self.log else x

    @property
    def bounds(self) -> tuple[float, float]:
        return (self.to_search(self.low), self.to_search(self.high))


def tunable(key: str, names: Sequence[str] | None = None,
            cls: type[Estimator] | None = None) -> list[Param]:
    """The parameters to fit of estimator key's class cls (the recommended one unless given):
    the named ones (["all"]: every tunable float parameter of the class's PARAMS, not the sample
    rules or the mounting), by default the class's SCANNED (where it scans none, as a paper's
    filter: all); ValueError
    naming an unknown or untunable one."""
    cls = cls or ESTIMATORS[key]
    specs = cls.param_specs()
    allowed = [p for p in cls.PARAMS
               if p.tunable and isinstance(p.default, float) and p.choices is None]
    if names is not None and list(names) == ["all"]:
        return allowed
    if not names:  # a paper's filter, or a class at its paper's values, scans nothing: all
        names = (cls.SCANNED if cls is ESTIMATORS[key] else ()) or [p.name for p in allowed]
    out = []
    for name in names:
        if name not in specs:
            raise ValueError(f"{key} has no parameter {name!r}: its tunable ones are "
                             f"{', '.join(p.name for p in allowed)}")
        if specs[name] not in allowed:
            raise ValueError(f"{key}.{name} cannot be fitted (not a tunable number): the tunable "
                             f"ones are {', '.join(p.name for p in allowed)}")
        out.append(specs[name])
    return out


def dimension(p: Param, start: float) -> Dimension:
    """The search range of parameter p from its start value: in log space, SPAN either side of
    the start, where the allowed range is positive and reaches more than SPAN above it (open
    above: noise densities, time constants); else the allowed range itself, linear, at most
    ten times the start's size either side."""
    low = -math.inf if p.low is None else float(p.low)
    high = math.inf if p.high is None else float(p.high)
    log = start > 0.0 and low >= 0.0 and high / start > SPAN
    if log:
        lo = max(low, start / SPAN) if low > 0.0 else start / SPAN
        hi = min(high, start * SPAN)
        # open bounds: stay a hair inside
        lo = lo * (1 + 1e-9) if p.low_open and lo == low else lo
        hi = hi * (1 - 1e-9) if p.high_open and hi == high else hi
        return Dimension(p.name, lo, hi, True)
    span = max(abs(start), 1.0) * 10.0
    lo, hi = max(low, start - span), min(high, start + span)
    eps = 1e-9 * max(abs(lo), abs(hi), 1.0)
    lo = lo + eps if p.low_open and lo == low else lo
    hi = hi - eps if p.high_open and hi == high else hi
    return Dimension(p.name, lo, hi, False)


def require_reference(rec: Recording, params: dict[str, Any] | None = None) -> None:
    """RecordingError where rec has no reference to score against; with `params` (the
    estimator's, whose calibration and mounting condition the samples), also where its
    reference does not describe the sensor in its axes (testbenches.reference_axes): fitted to
    a reference of another convention, parameters would be fitted to nothing."""
    if rec.up_ref is None:
        raise RecordingError(f"{rec.name}: no reference (q_w, q_x, q_y, q_z or roll, pitch "
                             "columns, or a BROAD trial): tune cannot score it")
    if params is not None:
        from ..estimate import conditioned
        from ..reference_axes import check_axes
        from .recording import PREFIX_ROWS

        n = PREFIX_ROWS  # as a recording's units and estimate's reference are checked
        seen = conditioned(rec.acc[:n], rec.gyro[:n], params)
        check_axes(Path(rec.name), *seen, rec.dt[:n], rec.up_ref[:n],
                   getattr(rec, "ref_quat", None) is None)


def score(key: str, params: dict[str, Any], rec: Recording) -> float:
    """Inclination RMSE [deg] of the estimator with params on one recording."""
    require_reference(rec)
    est = create(key, {**rec.sensor, **params})
    out = est.run(rec.acc, rec.gyro, rec.dt)
    g = gravity_from_roll_pitch(out["roll"], out["pitch"])
    return inclination_rmse_deg(g, rec.up_ref, rec.counted)


@dataclass
class TuneResult:
    """What tune.json holds (as_dict) and the per-recording scores for the plot."""

    estimator: str
    method: str
    start: dict[str, Any]
    fitted: dict[str, Any]
    dimensions: list[Dimension]
    start_fit_rmse_deg: float
    fit_rmse_deg: float
    start_validation_rmse_deg: float | None
    validation_rmse_deg: float | None
    evaluations: int
    seconds: float
    per_recording: dict[str, dict[str, float]]
    fmu_fit_rmse_deg: float | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "estimator": self.estimator, "method": self.method,
            "start_fit_rmse_deg": self.start_fit_rmse_deg, "fit_rmse_deg": self.fit_rmse_deg,
            "start_validation_rmse_deg": self.start_validation_rmse_deg,
            "validation_rmse_deg": self.validation_rmse_deg,
            "params_before": self.start, "params_after": self.fitted,
            "search": [{"name": d.name, "low": d.low, "high": d.high,
                        "space": "log" if d.log else "linear"} for d in self.dimensions],
            "evaluations": self.evaluations, "seconds": self.seconds,
            "per_recording_rmse_deg": self.per_recording,
            "fmu_fit_rmse_deg": self.fmu_fit_rmse_deg,
        }


def tune(key: str, fit_recs: Sequence[Recording], validate_recs: Sequence[Recording] = (),
         start: dict[str, Any] | None = None, names: Sequence[str] | None = None,
         max_evaluations: int = 300, progress: Callable[[float], None] | None = None,
         max_worse: float = MAX_WORSE) -> TuneResult:
    """Fit key's parameters (see the module docstring); start: the parameters to start from
    (the recommended values where it says nothing); max_worse: how much worse than at the start
    (a fraction) any one fit recording may end."""
    from scipy.optimize import minimize

    if not fit_recs:
        raise ValueError("tune needs at least one recording with a reference to fit")
    t0 = time.perf_counter()
    start = dict(start or {})
    cls = estimator_class(key, start)
    defaults = cls.param_specs()
    params = tunable(key, names, cls)
    dims = [dimension(p, float(start.get(p.name, defaults[p.name].default))) for p in params]
    x0 = np.array([d.to_search(float(start.get(d.name, defaults[d.name].default)))
                   for d in dims])
    x0 = np.clip(x0, [d.bounds[0] for d in dims], [d.bounds[1] for d in dims])

    def values(x: np.ndarray) -> dict[str, Any]:
        return {**start, **{d.name: d.from_search(float(v)) for d, v in zip(dims, x,
                                                                           strict=True)}}

    start_scores = np.array([score(key, start, r) for r in fit_recs])
    limits = start_scores * (1.0 + max_worse)
    start_f = float(np.mean(start_scores))
    best = {"x": x0, "f": start_f, "mean": start_f}
    count = [1]

    def objective(x: np.ndarray) -> float:
        scores = np.array([score(key, values(x), r) for r in fit_recs])
        mean = float(np.mean(scores))
        f = mean + PENALTY * float(np.sum(np.maximum(scores - limits, 0.0)))
        count[0] += 1
        if f < best["f"]:
            best["x"], best["f"], best["mean"] = np.array(x), f, mean
        if progress is not None:
            progress(best["mean"])
        return f

    minimize(objective, x0, method="Powell", bounds=[d.bounds for d in dims],
             options={"maxfev": max_evaluations, "xtol": 1e-3, "ftol": 1e-4})
    fitted = values(best["x"] if best["f"] < start_f else x0)
    per = {r.name: {"before": score(key, start, r), "after": score(key, fitted, r),
                    "set": "fit"} for r in fit_recs}
    per.update({r.name: {"before": score(key, start, r), "after": score(key, fitted, r),
                         "set": "validation"} for r in validate_recs})
    val = [r.name for r in validate_recs]
    return TuneResult(
        key, "scipy.optimize.minimize(method='Powell', bounds)", start, fitted, dims,
        start_f, best["mean"],
        float(np.mean([per[n]["before"] for n in val])) if val else None,
        float(np.mean([per[n]["after"] for n in val])) if val else None,
        count[0], time.perf_counter() - t0, per,
    )


def fmu_score(key: str, params: dict[str, Any], recs: Sequence[Recording],
              fmu_dir: Path | str) -> float:
    """The mean inclination RMSE of the estimator's FMU with params (testbenches' FmuHandle,
    one sample per doStep): the fitted preset confirmed through the FMU."""
    from ..fmus import ESTIMATOR_FMUS, FmuHandle, estimator_parameters, fmu_path

    scores = []
    for rec in recs:
        fmu = FmuHandle(fmu_path(ESTIMATOR_FMUS[key], fmu_dir), f"tune-{key}-{rec.name}")
        out = np.empty((len(rec.dt), 2))
        try:
            fmu.start(estimator_parameters(fmu, key, {**rec.sensor, **params}),
                      float(np.sum(rec.dt)))
            in_vr = fmu.vrs(("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt"))
            out_vr = fmu.vrs(("roll", "pitch"))
            t = 0.0
            for k, sample in enumerate(np.column_stack([rec.acc, rec.gyro, rec.dt]).tolist()):
                fmu.fmu.setReal(in_vr, sample)
                fmu.fmu.doStep(t, sample[6])
                out[k] = fmu.fmu.getReal(out_vr)
                t += sample[6]
        finally:
            fmu.free()
        scores.append(inclination_rmse_deg(gravity_from_roll_pitch(out[:, 0], out[:, 1]),
                                           rec.up_ref, rec.counted))
    return float(np.mean(scores))


def plot(result: TuneResult, path: Path) -> None:
    """tune.png: each recording's RMSE before and after, fit and validation sets."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(result.per_recording)
    before = [result.per_recording[n]["before"] for n in names]
    after = [result.per_recording[n]["after"] for n in names]
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(names) + 2), 4.5))
    ax.bar(x - 0.2, before, 0.4, label="start")
    ax.bar(x + 0.2, after, 0.4, label="fitted")
    ax.set_xticks(x, [f"{n}\n({result.per_recording[n]['set']})" for n in names], rotation=30,
                  ha="right", fontsize=7)
    ax.set_ylabel("inclination RMSE [deg]")
    ax.set_title(f"tune {result.estimator}: fit {result.start_fit_rmse_deg:.3f} -> "
                 f"{result.fit_rmse_deg:.3f} deg"
                 + (f", validation {result.start_validation_rmse_deg:.3f} -> "
                    f"{result.validation_rmse_deg:.3f} deg"
                    if result.validation_rmse_deg is not None else ""))
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write(result: TuneResult, out_dir: Path, plots: bool = True) -> None:
    """DIR/preset.json (loadable by --preset FILE.json), DIR/tune.json and DIR/tune.png."""
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "preset.json").write_text(json.dumps({result.estimator: result.fitted},
                                                    indent=1))
    (out_dir / "tune.json").write_text(json.dumps(result.as_dict(), indent=1))
    if plots:
        plot(result, out_dir / "tune.png")
