"""The run list of a campaign: estimator x scenario x seed, and the varied parameters.

A variation is `NAME=LOW:HIGH` or `NAME=LOW:HIGH:log`: NAME a parameter of the sensor model
(fusion_core.sensor.SENSOR_PARAMS) or of the estimators (applied to each estimator that has
it). The N seeds of a campaign are paired with N points of a space-filling design over the
varied ranges (scipy.stats.qmc: Latin hypercube, or Sobol), drawn from the campaign's seed, so
that run i of every estimator and scenario sees the same sensor part (seed i) and the same
parameters: the estimators are compared on equal terms. Each run has a stable key, a hash of
everything that determines its result, which is how a campaign resumes. A Sobol sequence's
first N points are those of any longer one, so a Sobol campaign grows by its new seeds only; a
Latin hypercube of another size is another design.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fusion_core import ESTIMATORS
from fusion_core.sensor import SENSOR_PARAMS

DESIGNS = ("lhs", "sobol")


@dataclass(frozen=True)
class Variation:
    """One varied parameter: its name, range, scale and whose parameter it is."""

    name: str
    low: float
    high: float
    log: bool
    target: str  # "sensor" or "estimator"

    def value(self, u: float) -> float:
        """The parameter's value at u in [0, 1)."""
        if self.log:
            return math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        return self.low + u * (self.high - self.low)


def parse_variation(text: str) -> Variation:
    """NAME=LOW:HIGH[:log]; ValueError saying what is wrong and what is allowed."""
    sensor_names = {p.name: p for p in SENSOR_PARAMS}
    try:
        name, spec = text.split("=", 1)
        parts = spec.split(":")
        low, high = float(parts[0]), float(parts[1])
        log = len(parts) == 3 and parts[2] == "log"
        if len(parts) not in (2, 3) or (len(parts) == 3 and not log):
            raise ValueError
    except (ValueError, IndexError):
        raise ValueError(f"--vary {text!r}: expected NAME=LOW:HIGH or NAME=LOW:HIGH:log") from None
    if not low < high or (log and low <= 0.0):
        raise ValueError(f"--vary {text!r}: LOW must be below HIGH (and above 0 with :log)")
    if name in sensor_names:
        target = "sensor"
        spec_p = sensor_names[name]
    else:
        owners = [k for k, c in ESTIMATORS.items() if name in c.param_specs()]
        if not owners:
            raise ValueError(f"--vary {name}: neither a sensor parameter ("
                             f"{', '.join(sorted(sensor_names))}) nor an estimator's")
        target = "estimator"
        spec_p = ESTIMATORS[owners[0]].param_specs()[name]
    if spec_p.choices is not None or isinstance(spec_p.default, bool):
        raise ValueError(f"--vary {name}: only numeric parameters vary")
    for v in (low, high):
        spec_p.validate(int(v) if isinstance(spec_p.default, int) else v)
    return Variation(name, low, high, log, target)


@dataclass(frozen=True)
class Run:
    """One run of a campaign."""

    key: str
    estimator: str
    scenario: str
    seed: int
    duration: float | None
    sensor: dict[str, Any] = field(hash=False)
    params: dict[str, Any] = field(hash=False)
    varied: dict[str, float] = field(hash=False)
    fmu: bool = False
    calibrate_first: bool = False
    """The part is calibrated on its own calibration session first (testbenches.calibrate.part)
    and the run applies the result."""


def design(n: int, d: int, kind: str, seed: int) -> np.ndarray:
    """n points in [0, 1)^d of a seeded space-filling design."""
    from scipy.stats import qmc

    if d == 0:
        return np.zeros((n, 0))
    if kind == "lhs":
        return qmc.LatinHypercube(d=d, seed=seed).random(n)
    if kind == "sobol":
        with warnings.catch_warnings():  # any n is fine here: the points pair with seeds
            warnings.filterwarnings("ignore", message=".*balance properties.*")
            return qmc.Sobol(d=d, scramble=True, seed=seed).random(n)
    raise ValueError(f"design {kind!r}: allowed {', '.join(DESIGNS)}")


def run_key(spec: dict[str, Any]) -> str:
    """A stable key: the first 16 hex digits of the SHA-256 of the run's canonical JSON."""
    text = json.dumps(spec, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def plan(estimators: list[str], scenarios: list[str], seeds: int,
         variations: list[Variation] | None = None, duration: float | None = None,
         sensor: dict[str, Any] | None = None, preset: dict[str, dict[str, Any]] | None = None,
         kind: str = "lhs", campaign_seed: int = 0, fmu: bool = False,
         calibrate_first: bool = False) -> list[Run]:
    """Every run: estimator x scenario x seed, seed i with design point i."""
    variations = variations or []
    points = design(seeds, len(variations), kind, campaign_seed)
    runs = []
    for scenario in scenarios:  # the estimators of a seed side by side: they share its samples
        for seed in range(seeds):
            for estimator in estimators:
                specs = ESTIMATORS[estimator].param_specs()
                varied = {v.name: v.value(float(points[seed, j]))
                          for j, v in enumerate(variations)}
                s = {**(sensor or {}), **{v.name: varied[v.name] for v in variations
                                          if v.target == "sensor"}}
                for v in variations:  # integer sensor parameters (bits, dlpf_cfg) stay integers
                    if v.target == "sensor" and isinstance(
                            next(p for p in SENSOR_PARAMS if p.name == v.name).default, int):
                        s[v.name] = round(s[v.name])
                p = {**(preset or {}).get(estimator, {}),
                     **{v.name: varied[v.name] for v in variations
                        if v.target == "estimator" and v.name in specs}}
                spec = {"estimator": estimator, "scenario": scenario, "seed": seed,
                        "duration": duration, "sensor": s, "params": p, "fmu": fmu}
                if calibrate_first:  # (absent otherwise: the keys of earlier campaigns hold)
                    spec["calibrate_first"] = True
                runs.append(Run(run_key(spec), estimator, scenario, seed, duration, s, p,
                                varied, fmu, calibrate_first))
    return runs
