"""`python -m testbenches campaign ...`: the Monte Carlo campaign's command line."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from fusion_core.scenarios import ESTIMATION_SCENARIOS

from ..fmus import ESTIMATOR_FMUS
from ..options import (
    add_calibration,
    add_cluster,
    add_no_plots,
    add_preset,
    add_sensor,
    non_negative_int,
    out_folder,
    positive_float,
    positive_int,
    with_calibration,
)
from .plan import DESIGNS


def add_campaign_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "campaign", help="a Monte Carlo campaign of seeded runs on Dask (a local cluster or "
        "your own scheduler), resumable, with percentiles and confidence intervals")
    p.set_defaults(func=cmd_campaign)
    p.add_argument("--estimator", default="all",
                   help=f"all or a comma list of {', '.join(ESTIMATOR_FMUS)}")
    p.add_argument("--scenario", default="moderate_dynamics",
                   help=f"all or a comma list of {', '.join(ESTIMATION_SCENARIOS)} "
                   "(moderate_dynamics)")
    p.add_argument("--seeds", type=positive_int, default=100,
                   help="runs per estimator and scenario: seed i, design point i (100)")
    p.add_argument("--duration", type=positive_float, default=None,
                   help="seconds per run instead of each scenario's own duration")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=LOW:HIGH[:log]",
                   help="a sensor or estimator parameter drawn over the runs (repeatable)")
    p.add_argument("--design", choices=DESIGNS, default="lhs",
                   help="the space-filling design of the variations (lhs)")
    p.add_argument("--campaign-seed", type=int, default=0, help="seed of the design (0)")
    add_sensor(p)
    add_preset(p)
    add_calibration(p)
    p.add_argument("--calibrate-first", action="store_true",
                   help="calibrate each run's sensor part on its own calibration session first "
                   "(the calibrate command's code) and apply its matrices")
    add_cluster(p)
    p.add_argument("--batch-size", type=positive_int, default=None,
                   help="runs per Dask task (default: about 8 tasks per worker, at most 200)")
    p.add_argument("--retries", type=non_negative_int, default=2,
                   help="tries of a failing run after the first, before it is recorded as "
                   "failed (2)")
    p.add_argument("--fmu", action="store_true",
                   help="run the FMUs through fmpy (FMU-in-the-loop) instead of fusion_core")
    p.add_argument("--fmu-dir", type=Path, default=Path("dist"), help="built FMUs (dist)")
    p.add_argument("--out", type=out_folder, default=Path("reports/campaign"),
                   help="folder: runs/*.parquet, summary.json, summary.md, plots")
    add_no_plots(p, "the plots")


def cmd_campaign(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from fusion_core.presets import load_preset

    from ..options import choose, load_sensor
    from .plan import parse_variation, plan
    from .runner import execute
    from .store import read_rows
    from .summary import write

    estimators = choose(args.estimator, list(ESTIMATOR_FMUS), "estimator")
    scenarios = choose(args.scenario, list(ESTIMATION_SCENARIOS), "scenario")
    variations = [parse_variation(v) for v in args.vary]
    runs = plan(estimators, scenarios, args.seeds, variations, args.duration,
                load_sensor(args.sensor),
                with_calibration(load_preset(args.preset), args.calibration), args.design,
                args.campaign_seed, args.fmu, args.calibrate_first)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "campaign.json").write_text(json.dumps(
        {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()
         if k != "func"}, indent=1))
    with tqdm(total=len(runs), unit="run", file=sys.stderr) as bar:
        def log(text: str) -> None:
            bar.write(text, file=sys.stderr)

        keys = {r.key for r in runs}
        bar.update(sum(1 for row in read_rows(args.out) if row["key"] in keys))
        stats = execute(runs, args.out, args.scheduler, args.workers, args.batch_size,
                        args.retries, str(args.fmu_dir), bar.update, log)
    rows = [row for row in read_rows(args.out) if row["key"] in keys]
    samples = sum(r["samples"] for r in rows if r["status"] == "ok")
    write(rows, args.out, f"Campaign: {len(estimators)} estimator(s) x {len(scenarios)} "
          f"scenario(s) x {args.seeds} seeds", [v.name for v in variations], not args.no_plots)
    print((args.out / "summary.md").read_text())
    rate = f", {samples / stats['seconds']:.3g} samples/s" if stats["ran"] and \
        stats["seconds"] else ""
    print(f"{stats['ran']} run(s) now ({stats['failed']} failed), {stats['already_done']} "
          f"already in {args.out}; {stats['seconds']:.1f} s{rate}")
    print(f"wrote {args.out}/runs/*.parquet, summary.json, summary.md"
          + ("" if args.no_plots else ", errors.png"))
    return 0
