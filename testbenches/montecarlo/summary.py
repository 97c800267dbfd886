"""A campaign's summary: statistics with bootstrap confidence intervals, the contract's verdict
on them, plots.

Per estimator and scenario, for each error metric (roll and pitch RMSE, max error, bias error):
the mean, median, 95th and 99th percentiles over the runs, each with a 95 % bootstrap confidence
interval (scipy.stats.bootstrap, percentile method, 999 resamples, seeded); the contract's
verdict: the per-run accuracy limit of testbenches.contract against the mean and against the
95th percentile, and the share of runs within it. Failed runs are counted, not scored.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..contract import accuracy_limits

ERRORS = ("rmse_roll_deg", "rmse_pitch_deg", "max_err_deg", "bias_err_dps")
STATISTICS = {
    "mean": np.mean,
    "median": np.median,
    "p95": lambda x, axis=-1: np.percentile(x, 95, axis=axis),
    "p99": lambda x, axis=-1: np.percentile(x, 99, axis=axis),
}
RESAMPLES = 999


def _stat(x: np.ndarray, name: str) -> dict[str, float | None]:
    """A statistic of x and its 95 % bootstrap confidence interval."""
    from scipy.stats import bootstrap

    fn = STATISTICS[name]
    value = float(fn(x, axis=-1)) if name in ("p95", "p99") else float(fn(x))
    if len(x) < 3 or np.ptp(x) == 0.0:
        return {"value": value, "low": None, "high": None}

    def statistic(sample: np.ndarray, axis: int = -1) -> np.ndarray:
        return fn(sample, axis=axis)

    ci = bootstrap((x,), statistic, confidence_level=0.95, n_resamples=RESAMPLES,
                   method="percentile", vectorized=True, random_state=0).confidence_interval
    return {"value": value, "low": float(ci.low), "high": float(ci.high)}


def summarise(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """summary.json's content for the rows of a campaign."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["estimator"], row["scenario"]), []).append(row)
    out: dict[str, Any] = {"runs": len(rows), "groups": []}
    for (estimator, scenario), group in sorted(groups.items()):
        ok = [r for r in group if r["status"] == "ok"]
        entry: dict[str, Any] = {"estimator": estimator, "scenario": scenario,
                                 "runs": len(group), "failed": len(group) - len(ok)}
        for metric in ERRORS:
            x = np.array([r[metric] for r in ok], dtype=float)
            x = x[np.isfinite(x)]
            entry[metric] = {name: _stat(x, name) for name in STATISTICS} if len(x) else None
        limits = accuracy_limits(estimator, scenario)
        if ok and limits is not None:
            lim_roll, lim_pitch = limits
            roll = np.array([r["rmse_roll_deg"] for r in ok])
            pitch = np.array([r["rmse_pitch_deg"] for r in ok])
            within = float(np.mean((roll <= lim_roll) & (pitch <= lim_pitch)))
            entry["contract"] = {
                "limit_roll_deg": lim_roll, "limit_pitch_deg": lim_pitch,
                "mean_pass": bool(roll.mean() <= lim_roll and pitch.mean() <= lim_pitch),
                "p95_pass": bool(np.percentile(roll, 95) <= lim_roll
                                 and np.percentile(pitch, 95) <= lim_pitch),
                "share_within": within,
            }
        out["groups"].append(entry)
    return out


def _fmt(s: dict[str, float | None] | None) -> str:
    if s is None or s["value"] is None or not math.isfinite(s["value"]):
        return "-"
    if s["low"] is None:
        return f"{s['value']:.3f}"
    return f"{s['value']:.3f} [{s['low']:.3f}, {s['high']:.3f}]"


def markdown(summary: dict[str, Any], title: str) -> str:
    """summary.md: one table of roll/pitch RMSE statistics and the verdict per group."""
    lines = [f"# {title}", "", f"{summary['runs']} runs. RMSE [deg] after the contract's "
             "settling time; value [95 % bootstrap CI]. Verdict: the contract's per-run limit "
             "against the mean and the 95th percentile; within: the share of runs within it.",
             "", "| estimator | scenario | runs | failed | roll mean | roll p95 | roll p99 | "
             "pitch mean | pitch p95 | pitch p99 | limit | mean | p95 | within |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for g in summary["groups"]:
        r, p, c = g["rmse_roll_deg"], g["rmse_pitch_deg"], g.get("contract")
        cells = [g["estimator"], g["scenario"], str(g["runs"]), str(g["failed"])]
        cells += [_fmt(r and r[s]) for s in ("mean", "p95", "p99")]
        cells += [_fmt(p and p[s]) for s in ("mean", "p95", "p99")]
        if c:
            cells += [f"{c['limit_roll_deg']:g}/{c['limit_pitch_deg']:g}",
                      "PASS" if c["mean_pass"] else "FAIL", "PASS" if c["p95_pass"] else "FAIL",
                      f"{100 * c['share_within']:.1f} %"]
        else:
            cells += ["-", "-", "-", "-"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plots(rows: Sequence[dict[str, Any]], out_dir: Path, varied: Sequence[str]) -> list[Path]:
    """errors.png (the distribution of each run's worse RMSE, per scenario) and, per varied
    parameter, vary_<name>.png (that error against the parameter)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok"]
    if not ok:
        return []
    scenarios = sorted({r["scenario"] for r in ok})
    estimators = sorted({r["estimator"] for r in ok})
    worse = {id(r): max(r["rmse_roll_deg"], r["rmse_pitch_deg"]) for r in ok}
    paths = []
    fig, axes = plt.subplots(1, len(scenarios), figsize=(5 * len(scenarios), 4), squeeze=False)
    for ax, sc in zip(axes[0], scenarios, strict=True):
        for est in estimators:
            x = [worse[id(r)] for r in ok if r["scenario"] == sc and r["estimator"] == est]
            if x:
                ax.hist(x, bins=40, histtype="step", label=est)
        ax.set_title(sc)
        ax.set_xlabel("max(roll, pitch) RMSE [deg]")
        ax.set_ylabel("runs")
        ax.legend(fontsize=8)
    fig.tight_layout()
    paths.append(out_dir / "errors.png")
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    for name in varied:
        fig, axes = plt.subplots(1, len(scenarios), figsize=(5 * len(scenarios), 4),
                                 squeeze=False)
        for ax, sc in zip(axes[0], scenarios, strict=True):
            for est in estimators:
                sel = [r for r in ok if r["scenario"] == sc and r["estimator"] == est]
                ax.scatter([r[f"vary_{name}"] for r in sel], [worse[id(r)] for r in sel], s=4,
                           label=est, alpha=0.5)
            ax.set_title(sc)
            ax.set_xlabel(name)
            ax.set_ylabel("max(roll, pitch) RMSE [deg]")
            ax.legend(fontsize=8)
        fig.tight_layout()
        paths.append(out_dir / f"vary_{name}.png")
        fig.savefig(paths[-1], dpi=100)
        plt.close(fig)
    return paths


def write(rows: Sequence[dict[str, Any]], out_dir: Path, title: str, varied: Sequence[str],
          with_plots: bool = True) -> dict[str, Any]:
    """DIR/summary.json, DIR/summary.md and the plots; return the summary."""
    summary = summarise(rows)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=1))
    (out_dir / "summary.md").write_text(markdown(summary, title))
    if with_plots:
        plots(rows, out_dir, varied)
    return summary
