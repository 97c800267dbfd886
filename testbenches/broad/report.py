"""Reports of a BROAD evaluation: trial x estimator table, report.json, report.md, bar chart."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from fusion_core.presets import load_preset

from .run import BroadResult

METRIC = (
    "BROAD inclination error (Laidig et al., Data 2021): angle between the estimated and the "
    "reference (opt_quat) up direction in the sensor frame; RMSE over the trial's movement "
    "samples that have a reference, in degrees"
)


def _fmt(x: float, width: int) -> str:
    return f"{x:>{width}.3f}" if math.isfinite(x) else f"{'-':>{width}}"


def table(result: BroadResult) -> str:
    """Trials x columns, then the mean over the given trials and the mean per BROAD group."""
    names = result.names
    w = max(7, *(len(n) for n in names)) + 1
    first = max(24, *(len(t.name) for t in result.trials), 6 + max(
        (len(g) for g in result.groups()), default=0))
    head = f"{'trial':<{first}}" + "".join(f"{n:>{w}}" for n in names)
    lines = ["inclination RMSE [deg] over the movement samples", head, "-" * len(head)]
    for t in result.trials:
        lines.append(f"{t.name:<{first}}" + "".join(_fmt(t.rmse_deg[n], w) for n in names))
    lines.append("-" * len(head))
    means = result.means()
    lines.append(f"{'mean (' + str(len(result.trials)) + ' trials)':<{first}}"
                 + "".join(_fmt(means[n], w) for n in names))
    for g, trials in result.groups().items():
        m = result.means(trials)
        lines.append(f"{'  ' + g + ' (' + str(len(trials)) + ')':<{first}}"
                     + "".join(_fmt(m[n], w) for n in names))
    return "\n".join(lines)


def _finite(x: float) -> float | None:
    return round(x, 6) if math.isfinite(x) else None


def report_dict(result: BroadResult) -> dict[str, Any]:
    """The report.json content: metric, columns (with parameters), means, groups, trials."""
    presets = sorted({c.preset for c in result.columns if c.preset})
    return {
        "metric": METRIC,
        "mean_inclination_rmse_deg": {k: _finite(v) for k, v in result.means().items()},
        "trial_count": len(result.trials),
        "columns": [c.as_dict() for c in result.columns],
        "presets": {p: load_preset(p) for p in presets},
        "fmu_dir": result.fmu_dir,
        "groups": {
            g: {
                "trials": [t.name for t in trials],
                "mean_inclination_rmse_deg": {
                    k: _finite(v) for k, v in result.means(trials).items()},
            }
            for g, trials in result.groups().items()
        },
        "trials": [
            {
                "name": t.name,
                "file": t.path,
                "groups": t.groups,
                "samples": t.samples,
                "movement_samples": t.movement_samples,
                "duration_s": round(t.duration_s, 3),
                "inclination_rmse_deg": {k: _finite(v) for k, v in t.rmse_deg.items()},
                "rejected_samples": t.rejected,
                "run_seconds": {k: round(v, 3) for k, v in t.seconds.items()},
            }
            for t in result.trials
        ],
    }


def plot_bars(result: BroadResult, path: Path) -> None:
    """Grouped bar chart: mean inclination RMSE per column, over all trials and per BROAD group of
    two or more trials (log scale: the papers' defaults and the peers span two decades)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    sets = {"all": result.trials, **{g: ts for g, ts in result.groups().items() if len(ts) > 1}}
    names = result.names
    x = np.arange(len(sets))
    width = 0.85 / max(1, len(names))
    fig, ax = plt.subplots(figsize=(min(16.0, 3.0 + 0.12 * len(names) * len(sets)), 5.0))
    top = 0.0
    for i, n in enumerate(names):
        vals = [result.means(ts)[n] for ts in sets.values()]
        top = max([top, *(v for v in vals if math.isfinite(v))])
        ax.bar(x + (i - (len(names) - 1) / 2) * width, vals, width, label=n,
               color=plt.cm.tab20(i % 20))
    ax.set_xticks(x, [f"{k}\n({len(v)})" for k, v in sets.items()], fontsize=8)
    ax.set_ylabel("mean inclination RMSE [deg]")
    if top > 0.0:
        ax.set_yscale("log")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=min(len(names), 7), loc="upper center",
              bbox_to_anchor=(0.5, -0.12))
    ax.set_title(f"BROAD inclination RMSE over the movement samples, {len(result.trials)} trials")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def write_reports(result: BroadResult, out_dir: Path, plot: bool = True,
                  extra: dict[str, Any] | None = None) -> dict[str, Path]:
    """report.json (with the entries of extra beside the evaluation's), report.md and (with
    plot) broad_inclination_rmse.png under out_dir."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {"json": out_dir / "report.json", "md": out_dir / "report.md"}
    paths["json"].write_text(json.dumps({**report_dict(result), **(extra or {})}, indent=1))
    md = [
        "# BROAD: inclination error on real recordings", "",
        METRIC + ".", "",
        "```", table(result), "```", "",
        "Columns: " + "; ".join(
            f"`{c.name}` = {c.key}"
            + (f" ({c.kind}, preset {c.preset})" if c.kind != "peer" else " (peer)")
            for c in result.columns) + ".", "",
    ]
    if plot:
        paths["png"] = out_dir / "broad_inclination_rmse.png"
        plot_bars(result, paths["png"])
        md += [f"![mean inclination RMSE]({paths['png'].name})", ""]
    paths["md"].write_text("\n".join(md))
    return paths


__all__ = ["METRIC", "plot_bars", "report_dict", "table", "write_reports"]
