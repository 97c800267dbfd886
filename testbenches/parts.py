"""The accuracy contract over sensor parts (interface v4): a user's part is any part.

Every estimator on every scenario runs on PARTS parts of the sensor (seeds 0 to PARTS - 1:
each draws its own bias, bias instability, scale and cross-axis errors), as delivered and
calibrated first by the project's own calibration (testbenches.calibrate.part: the part's
calibration session, Tedaldi's method, its matrices applied). The runs go through the C twins
of the plant, the sensor and the estimator (testbenches.montecarlo.simulate), which give what
the FMUs give to the bit (tests/test_montecarlo.py), so the check costs seconds, not the
FMUs' minutes.

The rule (docs/interface.md): per estimator and scenario, as delivered the typical part meets
the bound (a share of at least RAW_SHARE of the parts: the median part), and calibrated first
at least CALIBRATED_SHARE of them. A part meets it where both its roll and its pitch RMSE are
within the scenario's bounds (testbenches.contract.accuracy_limits).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .contract import Check, accuracy_limits, bound, compute_metrics

PARTS = 20
"""Sensor parts (seeds) each accuracy check is stated over."""
RAW_SHARE = 0.5
"""As delivered, the typical part (the median) within the bound."""
CALIBRATED_SHARE = 0.95
"""Calibrated first, all but one part in twenty within the bound."""
HOW = {False: ("as delivered", RAW_SHARE), True: ("calibrated first", CALIBRATED_SHARE)}

_RMSE: dict[str, tuple[float, float]] = {}
"""Each part's run, by its Run: a run is seeded, so it gives the same RMSE every time. The
commands that state the contract over parts in one process (`imu-fusion run`, the docs' tables
built together) share the runs they have in common instead of making them again."""


def part_rmse(estimators: Sequence[str], scenarios: Sequence[str], preset: dict[str, Any],
              sensor: dict[str, Any], parts: int = PARTS, params: dict[str, Any] | None = None,
              progress: Callable[[], None] | None = None,
              calibrated_first: Sequence[bool] = (False, True), bounded_only: bool = False,
              ) -> dict[tuple[bool, str, str], np.ndarray]:
    """Roll and pitch RMSE [deg] per part [parts, 2], keyed (calibrated first, estimator,
    scenario), as delivered and (or) calibrated first; with bounded_only only the pairs the
    contract has an accuracy bound for (what parts_checks and parts_table take)."""
    from .montecarlo.plan import Run
    from .montecarlo.simulate import simulate

    out: dict[tuple[bool, str, str], np.ndarray] = {}
    for calibrated in calibrated_first:
        for scenario in scenarios:
            keys = [e for e in estimators
                    if not bounded_only or accuracy_limits(e, scenario) is not None]
            rows: dict[str, list[tuple[float, float]]] = {e: [] for e in keys}
            for seed in range(parts):  # a part's samples made once for every estimator
                for estimator in keys:
                    run = Run("part", estimator, scenario, seed, None, sensor,
                              {**preset.get(estimator, {}), **(params or {})}, {},
                              calibrate_first=calibrated)
                    rows[estimator].append(_part(run, simulate))
                    if progress:
                        progress()
            for estimator in keys:
                out[(calibrated, estimator, scenario)] = np.array(rows[estimator])
    return out


def _part(run: Any, simulate: Callable[[Any], Any]) -> tuple[float, float]:
    """The run's roll and pitch RMSE [deg], made once per process (_RMSE)."""
    key = json.dumps(dataclasses.asdict(run), sort_keys=True, default=repr)
    if key not in _RMSE:
        m = compute_metrics(simulate(run))
        _RMSE[key] = (m["rmse_roll_deg"], m["rmse_pitch_deg"])
    return _RMSE[key]


def vqf_rmse(scenario: str, sensor: dict[str, Any], parts: int = PARTS,
             calibrate_first: bool = False) -> np.ndarray:
    """VQF's roll and pitch RMSE [deg] per part [parts, 2] on the same samples (the peer runs of
    `imu-fusion run --peers vqf`, testbenches.peer_runs)."""
    from .peer_runs import run_peers
    from .peers import PEERS

    rows = run_peers({"vqf": PEERS["vqf"]}, [scenario], parts, sensor,
                     calibrate_first=calibrate_first)
    return np.array([(r.rmse_roll_deg, r.rmse_pitch_deg) for r in rows])


def share_within(values: np.ndarray, bound: tuple[float, float]) -> float:
    """The share of parts (rows: roll, pitch RMSE) whose roll and pitch are both within the
    bound."""
    return float(np.mean((values[:, 0] <= bound[0]) & (values[:, 1] <= bound[1])))


def parts_checks(rmse: dict[tuple[bool, str, str], np.ndarray]) -> list[Check]:
    """One check per (as delivered or calibrated first, estimator, scenario): the share of
    parts within the bound against the rule's share."""
    checks = []
    for (calibrated, estimator, scenario), values in rmse.items():
        label, needed = HOW[calibrated]
        lim = bound(estimator, scenario)
        within = share_within(values, lim)
        median = np.median(values, axis=0)
        checks.append(Check(
            f"accuracy over {len(values)} parts, {label}: {estimator} {scenario}",
            within >= needed, 100.0 * within, 100.0 * needed, "% of parts",
            f"within {lim[0]:g}/{lim[1]:g} deg; median part {median[0]:.3f}/{median[1]:.3f}, "
            f"worst {values[:, 0].max():.3f}/{values[:, 1].max():.3f}", at_least=True))
    return checks


def parts_table(rmse: dict[tuple[bool, str, str], np.ndarray]) -> str:
    """Markdown: per estimator and scenario the bound and, as delivered and calibrated first,
    the share of parts within it, the median part's and the worst part's roll/pitch RMSE."""
    rows = ["| estimator | scenario | bound [deg] | as delivered: within | median | worst | "
            "calibrated first: within | median | worst |", "|---|---|---|---|---|---|---|---|---|"]
    keys = sorted({(e, s) for _, e, s in rmse}, key=lambda k: (k[1], k[0]))
    for estimator, scenario in keys:
        lim = bound(estimator, scenario)
        cells = [estimator, scenario, f"{lim[0]:.3g} / {lim[1]:.3g}"]
        for calibrated in (False, True):
            v = rmse[(calibrated, estimator, scenario)]
            within = share_within(v, lim)
            mark = "" if within >= HOW[calibrated][1] else " **(not met)**"
            med, worst = np.median(v, axis=0), v.max(axis=0)
            cells += [f"{100 * within:.0f} %{mark}", f"{med[0]:.3f} / {med[1]:.3f}",
                      f"{worst[0]:.3f} / {worst[1]:.3f}"]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)
