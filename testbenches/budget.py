"""`python -m testbenches budget`: the error budget of the sensor model, per estimator and scenario.

Which error of the IMU costs how much accuracy: every run is repeated with one group of the
sensor's errors switched off at a time (SOURCES), on the same seeds, so the other errors, the
motion and the noise draws stay the same. A row gives the roll/pitch RMSE [deg] with the full
sensor, without each source, and with every source off ("motion only": what the estimator makes
of the motion itself from perfect samples). The source whose removal brings the RMSE down the
most is the one that dominates it; where "motion only" already exceeds the contract's bound,
the estimator's design is the limit, not the sensor.

Runs go through fusion_core (the C twins where built), as `campaign` does
(testbenches.montecarlo.simulate), and are scored with the contract's metric
(contract.compute_metrics). Writes DIR/budget.json, DIR/budget.md and DIR/budget.png.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.registry import keys_help
from fusion_core.scenarios import ESTIMATION_SCENARIOS

from .contract import accuracy_limits
from .options import (
    add_calibration,
    add_no_plots,
    add_preset,
    add_sensor,
    choose,
    out_folder,
    positive_int,
    with_calibration,
)

SOURCES: dict[str, tuple[str, dict[str, Any]]] = {
    "gyro_scale": ("gyro scale-factor error", {"gyro_scale_std": 0.0}),
    "gyro_cross": ("gyro cross-axis sensitivity", {"gyro_cross_axis_std": 0.0}),
    "calibration": ("turn-on biases left by the calibration", {"calibration": "perfect"}),
    "bias_drift": ("bias instability and random walk",
                   {"gyro_bias_instability": 0.0, "acc_bias_instability": 0.0,
                    "gyro_bias_psd": 0.0, "acc_bias_psd": 0.0}),
    "dlpf": ("digital low-pass filter", {"dlpf_cfg": -1}),
    "noise": ("white noise", {"gyro_psd": 0.0, "acc_psd": 0.0}),
    "quantisation": ("16-bit quantisation", {"bits": 0}),
}
"""Source name -> (what it is, the sensor parameters that switch it off)."""

MOTION_ONLY = {k: v for _, off in SOURCES.values() for k, v in off.items()}
"""Every source off: perfect samples of the motion (saturation and the sampling rule stay)."""

VARIANTS = {"full": {}, **{n: off for n, (_, off) in SOURCES.items()}, "motion only": MOTION_ONLY}
"""The sensor variants of one budget row, by name: the changes to the full sensor."""


@dataclass
class BudgetRow:
    """The budget of one estimator on one scenario: RMSE roll/pitch [deg], mean over the seeds."""

    estimator: str
    scenario: str
    limit: tuple[float, float]
    full: tuple[float, float]
    without: dict[str, tuple[float, float]]
    motion_only: tuple[float, float]

    def worst(self, rmse: tuple[float, float]) -> float:
        """A roll/pitch RMSE pair as the worse axis's fraction of its limit."""
        return max(rmse[0] / self.limit[0], rmse[1] / self.limit[1])

    def dominant(self) -> str:
        """The source whose removal lowers the worse axis (relative to its limit) the most."""
        return min(self.without, key=lambda s: self.worst(self.without[s]))


def _rmse(estimator: str, scenario: str, seeds: int, sensor: dict[str, Any],
          params: dict[str, Any]) -> tuple[float, float]:
    """The mean roll and pitch RMSE over the seeds (the parts of testbenches.parts)."""
    from .parts import part_rmse

    runs = part_rmse([estimator], [scenario], {estimator: params}, sensor, seeds,
                     calibrated_first=(False,))
    roll, pitch = runs[(False, estimator, scenario)].mean(axis=0)
    return float(roll), float(pitch)


def error_budget(estimators: list[str], scenarios: list[str], seeds: int,
                 sensor: dict[str, Any], preset: dict[str, dict[str, Any]],
                 progress: Any = None) -> list[BudgetRow]:
    """The budget rows of every estimator x scenario (progress() after each sensor variant's
    seeds, if given)."""
    rows = []
    for scenario in scenarios:
        for est in estimators:
            limit = accuracy_limits(est, scenario)
            if limit is None:  # no bound to budget against
                continue
            params = dict(preset.get(est, {}))
            rmse = {}
            for name, off in VARIANTS.items():
                rmse[name] = _rmse(est, scenario, seeds, {**sensor, **off}, params)
                if progress:
                    progress()
            rows.append(BudgetRow(est, scenario, limit, rmse["full"],
                                  {n: rmse[n] for n in SOURCES}, rmse["motion only"]))
    return rows


def _pair(v: tuple[float, float]) -> str:
    return f"{v[0]:.2f}/{v[1]:.2f}"


def budget_table(rows: list[BudgetRow]) -> str:
    """The budget as a fixed-width text table (roll/pitch RMSE in deg)."""
    names = list(SOURCES)
    head = (f"{'estimator':9} {'scenario':17} {'limit':>9} {'full':>9} "
            + " ".join(f"{'-' + n[:10]:>11}" for n in names)
            + f" {'motion only':>11}  dominant")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.estimator:9} {r.scenario:17} {_pair(r.limit):>9} {_pair(r.full):>9} "
                     + " ".join(f"{_pair(r.without[n]):>11}" for n in names)
                     + f" {_pair(r.motion_only):>11}  {r.dominant()}")
    return "\n".join(lines)


def _markdown(rows: list[BudgetRow], command: str) -> str:
    names = list(SOURCES)
    out = ["# Sensor error budget", "",
           "Roll/pitch RMSE [deg] with the full sensor, without one source at a time, and with "
           "every source off (motion only). `dominant`: the source whose removal helps most.",
           "", f"Reproduce: `{command}`", "", "Sources: "
           + "; ".join(f"`{n}` {SOURCES[n][0]}" for n in names) + ".", "",
           "| estimator | scenario | limit | full | " + " | ".join(f"-{n}" for n in names)
           + " | motion only | dominant |",
           "|" + "---|" * (len(names) + 6)]
    for r in rows:
        out.append(f"| {r.estimator} | {r.scenario} | {_pair(r.limit)} | {_pair(r.full)} | "
                   + " | ".join(_pair(r.without[n]) for n in names)
                   + f" | {_pair(r.motion_only)} | {r.dominant()} |")
    return "\n".join(out) + "\n"


def _plot(rows: list[BudgetRow], path: Path) -> None:
    """Per row, the worse axis's RMSE over its limit: full, without each source, motion only."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = ["full", *(f"-{n}" for n in SOURCES), "motion only"]
    data = np.array([[r.worst(r.full), *(r.worst(r.without[n]) for n in SOURCES),
                      r.worst(r.motion_only)] for r in rows])
    fig, ax = plt.subplots(figsize=(max(6.0, 0.55 * len(rows) * len(labels) / 4), 4.5))
    x = np.arange(len(rows))
    width = 0.85 / len(labels)
    for i, label in enumerate(labels):
        ax.bar(x + (i - len(labels) / 2 + 0.5) * width, data[:, i], width, label=label)
    ax.axhline(1.0, color="k", lw=1, ls="--", label="contract bound")
    ax.set_xticks(x, [f"{r.estimator}\n{r.scenario}" for r in rows], fontsize=7)
    ax.set_ylabel("worse axis RMSE / its bound")
    ax.set_title("Sensor error budget: RMSE with each source switched off")
    ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_budget(rows: list[BudgetRow], out: Path, command: str, plot: bool = True) -> None:
    """DIR/budget.json, DIR/budget.md and (plot) DIR/budget.png."""
    out.mkdir(parents=True, exist_ok=True)
    doc = {"command": command,
           "sources": {n: {"what": w, "off": off} for n, (w, off) in SOURCES.items()},
           "rows": [{**asdict(r), "dominant": r.dominant()} for r in rows]}
    (out / "budget.json").write_text(json.dumps(doc, indent=1))
    (out / "budget.md").write_text(_markdown(rows, command))
    if plot:
        _plot(rows, out / "budget.png")


def add_budget_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register the `budget` subcommand on the subparsers of `python -m testbenches`."""
    p = sub.add_parser("budget", help="which sensor error costs how much accuracy",
                       description=__doc__.split("\n\n")[1])
    p.set_defaults(func=cmd_budget)
    p.add_argument("--estimator", default="all",
                   help=f"all or a comma list of {keys_help()} (all)")
    p.add_argument("--scenario", default="all",
                   help=f"all or a comma list of {', '.join(ESTIMATION_SCENARIOS)} (all)")
    p.add_argument("--seeds", type=positive_int, default=3, help="seeds per row, averaged (3)")
    add_preset(p)
    add_calibration(p)
    add_sensor(p)
    p.add_argument("--out", type=out_folder, default=Path("reports/budget"),
                   help="report folder (reports/budget)")
    add_no_plots(p, "the bar chart")


def cmd_budget(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from fusion_core import ESTIMATORS
    from fusion_core.presets import load_preset

    from .options import load_sensor

    estimators = choose(args.estimator, list(ESTIMATORS), "estimator")
    scenarios = choose(args.scenario, list(ESTIMATION_SCENARIOS), "scenario")
    preset = with_calibration(load_preset(args.preset), args.calibration)
    sensor = load_sensor(args.sensor)
    total = len(estimators) * len(scenarios) * len(VARIANTS)
    with tqdm(total=total, unit="set", file=sys.stderr) as bar:
        rows = error_budget(estimators, scenarios, args.seeds, sensor, preset, bar.update)
    print(budget_table(rows))
    command = (f"python -m testbenches budget --estimator {args.estimator} --scenario "
               f"{args.scenario} --seeds {args.seeds} --preset {args.preset} --sensor "
               f"{args.sensor}")
    write_budget(rows, args.out, command, plot=not args.no_plots)
    print(f"\nreports: {args.out / 'budget.md'}, {args.out / 'budget.json'}")
    return 0
