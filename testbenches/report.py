"""Reports of a campaign: a contract table for the terminal, report.json, report.md, PNG plots."""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.types import DEG

from . import contract
from .contract_runs import ContractResult
from .master import TestbenchResult
from .peer_runs import PeerRun, peer_table


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def run_record(r: TestbenchResult, plot: str | None = None) -> dict[str, Any]:
    return {
        "estimator": r.estimator,
        "scenario": r.scenario,
        "seed": r.seed,
        "rate_hz": r.rate,
        "jitter": r.jitter,
        "params": r.params,
        "metrics": {k: _finite(v) for k, v in r.metrics.items()},
        "checks": [c.as_dict() for c in r.checks],
        "passed": r.passed,
        "plot": plot,
    }


def contract_table(result: ContractResult) -> str:
    """One line per run (RMSE roll/pitch against the limit, p99 step time, verdict) and the
    campaign checks."""
    head = (f"{'estimator':<9} {'scenario':<18} {'seed':>4} {'RMSE roll':>10} {'RMSE pitch':>10} "
            f"{'limit':>11} {'max err':>8} {'p99 us':>7}  verdict")
    lines = [f"contract v{contract.CONTRACT_VERSION}", head, "-" * len(head)]
    for r in result.runs:
        m = r.metrics
        lim = contract.accuracy_limits(r.estimator, r.scenario)
        shown = f"{lim[0]:>5.2f}/{lim[1]:<5.2f}" if lim is not None else f"{'(none)':^11}"
        failed = [c.name for c in r.checks if not c.passed]
        verdict = "PASS" if not failed else "FAIL: " + ", ".join(failed)
        lines.append(
            f"{r.estimator:<9} {r.scenario:<18} {r.seed:>4} {m['rmse_roll_deg']:>10.3f} "
            f"{m['rmse_pitch_deg']:>10.3f} {shown} {m['max_err_deg']:>8.2f} "
            f"{m['step_p99_us']:>7.0f}  {verdict}"
        )
    if result.checks:
        lines.append("")
        lines += [c.line() for c in result.checks]
    n_fail = sum(not c.passed for r in result.runs for c in r.checks) + sum(
        not c.passed for c in result.checks)
    n_all = sum(len(r.checks) for r in result.runs) + len(result.checks)
    lines.append("")
    lines.append(f"{n_all - n_fail} of {n_all} checks PASS" + (
        "" if not n_fail else f", {n_fail} FAIL"))
    return "\n".join(lines)


@dataclass(frozen=True)
class SeedSummary:
    """One estimator or peer on one scenario over the campaign's seeds (sensor parts): roll and
    pitch RMSE [deg] as mean, median and 95th percentile, and the share of seeds within the
    scenario's bound (None where there is none: a peer on moderate_dynamics)."""

    name: str
    peer: bool
    scenario: str
    seeds: int
    mean: tuple[float, float]
    median: tuple[float, float]
    p95: tuple[float, float]
    within: float | None

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _summary(name: str, peer: bool, scenario: str, rmse: np.ndarray,
             bound: tuple[float, float] | None) -> SeedSummary:
    def pair(values: np.ndarray) -> tuple[float, float]:
        return float(values[0]), float(values[1])

    within = None if bound is None else float(np.mean(
        (rmse[:, 0] <= bound[0]) & (rmse[:, 1] <= bound[1])))
    return SeedSummary(name, peer, scenario, len(rmse), pair(rmse.mean(axis=0)),
                       pair(np.median(rmse, axis=0)), pair(np.percentile(rmse, 95, axis=0)),
                       within)


def seed_summaries(result: ContractResult, peers: list[PeerRun] | None = None
                   ) -> list[SeedSummary]:
    """Each estimator (and peer) on each scenario over its seeds: one seed is one sensor part,
    and the tails over parts are what one seed cannot show. The estimators' bound is their
    accuracy check's (contract.accuracy_limits), the peers' their PeerRun's."""
    groups: dict[tuple[str, bool, str], list[tuple[float, float]]] = {}
    bounds: dict[tuple[str, bool, str], tuple[float, float] | None] = {}
    for r in result.runs:
        key = (r.estimator, False, r.scenario)
        groups.setdefault(key, []).append((r.metrics["rmse_roll_deg"],
                                           r.metrics["rmse_pitch_deg"]))
        bounds[key] = contract.accuracy_limits(r.estimator, r.scenario)
    for p in peers or []:
        key = (p.peer, True, p.scenario)
        groups.setdefault(key, []).append((p.rmse_roll_deg, p.rmse_pitch_deg))
        bounds[key] = p.allowed
    return [_summary(*key, np.array(v, dtype=float), bounds[key]) for key, v in groups.items()]


def over_several_seeds(rows: list[SeedSummary]) -> bool:
    """Whether the summaries say more than the per-run rows: some run had a second seed."""
    return any(s.seeds > 1 for s in rows)


def seed_summary_table(rows: list[SeedSummary]) -> str:
    """The summaries as a text table: RMSE roll/pitch [deg] over the seeds."""
    head = (f"{'':<11} {'scenario':<18} {'seeds':>5} {'mean':>11} {'median':>11} {'p95':>11} "
            f" within bound")
    lines = ["Over the seeds (each seed another sensor part): RMSE roll/pitch [deg]", head,
             "-" * len(head)]
    for s in rows:
        within = "-" if s.within is None else f"{100.0 * s.within:.0f} %"
        name = f"{s.name} (peer)" if s.peer else s.name
        lines.append(f"{name:<11} {s.scenario:<18} {s.seeds:>5} "
                     + " ".join(f"{a:>5.2f}/{b:<5.2f}" for a, b in (s.mean, s.median, s.p95))
                     + f"  {within}")
    return "\n".join(lines)


def plot_run(r: TestbenchResult, path: Path) -> None:
    """Truth vs estimate, error, and gyro bias of one run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    t = r.t
    for name, color in (("roll", "C0"), ("pitch", "C1")):
        ax[0].plot(t, r.truth[name] / DEG, color=color, lw=2.0, alpha=0.4, label=f"{name} truth")
        ax[0].plot(t, r.estimate[name] / DEG, color=color, lw=0.8, label=f"{name} estimate")
        err = contract.wrap_angles(r.estimate[name] - r.truth[name])
        ax[1].plot(t, err / DEG, color=color, lw=0.8, label=f"{name} error")
    for i, a in enumerate("xyz"):
        ax[2].plot(t, r.estimate[f"bias_{a}"] / DEG, color=f"C{i + 2}", lw=0.8,
                   label=f"bias_{a} estimate")
        ax[2].axhline(r.true_gyro_bias[i] / DEG, color=f"C{i + 2}", ls="--", lw=0.8)
    ax[0].set_ylabel("angle [deg]")
    ax[1].set_ylabel("error [deg]")
    ax[2].set_ylabel("gyro bias [deg/s]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(loc="upper right", fontsize=7, ncol=3)
    m = r.metrics
    fig.suptitle(f"{r.estimator} on {r.scenario} (seed {r.seed}): RMSE roll "
                 f"{m['rmse_roll_deg']:.3f} deg, pitch {m['rmse_pitch_deg']:.3f} deg")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def write_reports(result: ContractResult, out_dir: Path, plots: bool = True,
                  peers: list[PeerRun] | None = None,
                  summaries: list[SeedSummary] | None = None) -> None:
    """report.json, report.md and, with plots, a PNG per run under out_dir/plots; with peers,
    the public filters' rows on the same samples (peer_runs) in both; with several seeds, the
    summaries over them (seed_summaries, unless given)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    records = []
    for r in result.runs:
        name = None
        if plots:
            (out_dir / "plots").mkdir(exist_ok=True)
            name = f"plots/{r.estimator}_{r.scenario}_{r.seed}.png"
            plot_run(r, out_dir / name)
        records.append(run_record(r, name))
    report = {
        "contract_version": contract.CONTRACT_VERSION,
        "passed": result.passed,
        "runs": records,
        "checks": [c.as_dict() for c in result.checks],
    }
    if peers is not None:
        report["peers"] = [r.as_dict() for r in peers]
    if summaries is None:
        summaries = seed_summaries(result, peers)
    several = over_several_seeds(summaries)
    if several:
        report["over_seeds"] = [sm.as_dict() for sm in summaries]
    (out_dir / "report.json").write_text(json.dumps(report, indent=1))
    md = ["# Testbench report", "", f"Contract v{contract.CONTRACT_VERSION}: "
          f"{'PASS' if result.passed else 'FAIL'}", "", "```", contract_table(result), "```", ""]
    if peers is not None:
        md += ["```", peer_table(peers), "```", ""]
    if several:
        md += ["```", seed_summary_table(summaries), "```", ""]
    for rec in records:
        if rec["plot"]:
            md += [f"## {rec['estimator']} on {rec['scenario']} (seed {rec['seed']})", "",
                   f"![{rec['estimator']} {rec['scenario']}]({rec['plot']})", ""]
    (out_dir / "report.md").write_text("\n".join(md))
