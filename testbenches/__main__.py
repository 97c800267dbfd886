"""`python -m testbenches run ...`: the command line over testbenches' functions.

  run         estimator x scenario x seed campaign with the contract checks; prints the contract
              table, writes DIR/report.json, DIR/report.md and plots; exit status 1 on any FAIL.
  export-ssp  the plant, sensor and estimator FMUs and their connections as an SSP file.
  broad       accuracy on BROAD's real recordings beside VQF, Madgwick, Mahony (testbenches.broad).
  noise       noise densities of a static recording (Allan deviation), a preset for every
              estimator and the sensor FMU's parameters for that sensor (testbenches.fit).
  tune        an estimator's tunable parameters fitted to recordings with a reference, validated
              on others (testbenches.fit).
  campaign    a Monte Carlo campaign of seeded runs on Dask, resumable, with percentiles and
              confidence intervals (testbenches.montecarlo).
  budget      the sensor's error budget: each scenario's RMSE with one group of the IMU's
              errors switched off at a time (testbenches.budget).
"""

from __future__ import annotations

import sys

from . import INSTALL_HINT, missing_modules

if missing_modules():  # one line instead of a traceback from deep inside a command
    print(f"python -m testbenches needs the testbench extra ({INSTALL_HINT}); not installed: "
          f"{', '.join(missing_modules())}", file=sys.stderr)
    sys.exit(2)

import argparse
from pathlib import Path
from typing import Any

from fusion_core.scenarios import SCENARIOS

from .broad.cli import add_broad_parser
from .budget import add_budget_parser
from .fit.cli import add_fit_parsers
from .fmus import DEFAULT_FMU_DIR, ESTIMATOR_FMUS, KINDS, kind_dir
from .montecarlo.cli import add_campaign_parser
from .options import add_preset, add_sensor, choose, jitter_fraction, positive_float, positive_int


def check_params(params: dict[str, object], estimators: list[str],
                 preset: dict[str, dict[str, Any]]) -> None:
    """--param values go to every chosen estimator: each must have them, in range, on top of
    its preset (a ValueError that names the estimator, before any run starts)."""
    from fusion_core.registry import create

    if not params:
        return
    for key in estimators:
        try:
            create(key, {**preset.get(key, {}), **params})
        except ValueError as err:
            raise ValueError(f"--param, {key}: {err}") from None


def parse_params(items: list[str]) -> dict[str, object]:
    """NAME=VALUE strings to a dict: numbers as float or int, true/false, else the string."""
    out: dict[str, object] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name:
            raise ValueError(f"--param {item!r}: expected NAME=VALUE")
        value: object = text
        if text.lower() in ("true", "false"):
            value = text.lower() == "true"
        else:
            for kind in (int, float):
                try:
                    value = kind(text)
                    break
                except ValueError:
                    pass
        out[name] = value
    return out


def cmd_run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from .campaign import plan, run_campaign
    from .report import (
        contract_table,
        over_several_seeds,
        seed_summaries,
        seed_summary_table,
        write_reports,
    )

    estimators = choose(args.estimator, list(ESTIMATOR_FMUS), "estimator")
    scenarios = choose(args.scenario, list(SCENARIOS), "scenario")
    from fusion_core.presets import load_preset

    from .campaign import load_sensor

    preset = load_preset(args.preset)
    sensor = load_sensor(args.sensor)
    params = parse_params(args.param)
    check_params(params, estimators, preset)
    peers = _peers(args)  # checked before the runs: a missing package fails at once
    jobs = plan(estimators, scenarios, args.seeds, args.jitter, not args.no_contract)
    fmu_dir = kind_dir(args.fmu_dir, args.kind)
    print(f"FMUs: {fmu_dir}", file=sys.stderr)
    with tqdm(total=len(jobs), unit="run", file=sys.stderr) as bar:
        def progress(job: object) -> None:
            bar.set_postfix_str(f"{job.estimator} {job.scenario}")  # type: ignore[attr-defined]
            bar.update()

        result = run_campaign(estimators, scenarios, args.seeds, args.jitter, fmu_dir,
                              progress, not args.no_contract, params,
                              args.duration, not args.no_timing_check, args.jobs,
                              preset=preset, sensor=sensor)
    print(contract_table(result))
    peer_rows = None
    if peers:
        from .peer_runs import peer_table, run_peers

        peer_rows = run_peers(peers, scenarios, args.seeds, sensor, args.duration)
        print("\n" + peer_table(peer_rows))
    summaries = seed_summaries(result, peer_rows)
    if over_several_seeds(summaries):
        print("\n" + seed_summary_table(summaries))
    write_reports(result, args.out, plots=not args.no_plots, peers=peer_rows,
                  summaries=summaries)
    print(f"\nreports: {args.out / 'report.md'}, {args.out / 'report.json'}")
    return 0 if result.passed else 1


def _peers(args: argparse.Namespace) -> dict[str, Any]:
    """The public filters of --peers by name (testbenches.peers), their packages checked."""
    if not args.peers:
        return {}
    from .peers import PEERS, PeerUnavailable, check_peers

    if args.jitter:
        raise ValueError(f"--peers needs one sample rate, so --jitter 0: got --jitter "
                         f"{args.jitter:g}")
    names = choose(args.peers, list(PEERS), "peer")
    try:
        check_peers(names)
    except PeerUnavailable as err:  # the pip command is in the message
        raise ValueError(str(err)) from None
    return {n: PEERS[n] for n in names}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m testbenches", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a testbench campaign and check the contract")
    run.add_argument("--estimator", default="all",
                     help=f"all or a comma list of {', '.join(ESTIMATOR_FMUS)}")
    run.add_argument("--scenario", default="all",
                     help=f"all or a comma list of {', '.join(SCENARIOS)}")
    run.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                     help="estimator FMU parameter for every run (repeatable); an enumeration "
                     "by item name, e.g. --param gyro_sampling=mean")
    add_preset(run)
    add_sensor(run)
    run.add_argument("--seeds", type=positive_int, default=1,
                     help="seeds per estimator x scenario (1)")
    run.add_argument("--jitter", type=jitter_fraction, default=0.0,
                     help="communication-step jitter, fraction of the period (0)")
    run.add_argument("--duration", type=positive_float, default=None,
                     help="seconds per run instead of each scenario's own duration")
    run.add_argument("--out", type=Path, default=Path("reports"), help="report folder (reports)")
    run.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR, help="built FMUs (dist)")
    run.add_argument("--kind", choices=KINDS, default="auto",
                     help="FMUs to run: native (FMI 2.0 from the C twin, FMU_DIR/native/fmi2), "
                     "pythonfmu (FMU_DIR), or auto: native where built (default)")
    run.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    run.add_argument("--jobs", type=positive_int, default=2,
                     help="worker processes (2: the campaign on two cores; 1: all in this one)")
    run.add_argument("--no-timing-check", action="store_true",
                     help="report T3 (the compute budget, in CPU time) but leave it out of the "
                     "verdict, e.g. under a profiler or valgrind")
    run.add_argument("--no-contract", action="store_true",
                     help="only the runs, without the T1, T2, T4 and position extras")
    run.add_argument("--peers", default="", metavar="LIST",
                     help="also run public filters on the same samples and score them against "
                     "the same bounds, for reference (not in the verdict): all or a comma list "
                     "of vqf, madgwick, mahony (the bench extra: pip install -e '.[bench]')")
    ssp = sub.add_parser("export-ssp", help="write a testbench as an SSP file")
    ssp.add_argument("--estimator", required=True, choices=list(ESTIMATOR_FMUS))
    ssp.add_argument("--scenario", required=True, choices=list(SCENARIOS))
    ssp.add_argument("--seed", type=int, default=0, help="sensor noise seed (0)")
    ssp.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                     help="estimator FMU parameter (repeatable)")
    ssp.add_argument("--noise-free", action="store_true", help="a sensor without noise")
    ssp.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR, help="built FMUs (dist)")
    ssp.add_argument("out", type=Path, help="the SSP file to write")
    add_broad_parser(sub)
    add_fit_parsers(sub)
    add_campaign_parser(sub)
    add_budget_parser(sub)
    args = parser.parse_args(argv)
    try:
        if args.command == "run":
            return cmd_run(args)
        if args.command == "export-ssp":
            from .contract import NOISE_FREE
            from .ssp import export_ssp

            path = export_ssp(args.estimator, args.scenario, args.out, args.seed,
                              parse_params(args.param), NOISE_FREE if args.noise_free else None,
                              args.fmu_dir)
            print(f"wrote {path}")
            return 0
        if args.command == "broad":
            from .broad.cli import cmd_broad

            return cmd_broad(args)
        if args.command in ("noise", "tune"):
            from .fit.cli import cmd_noise, cmd_tune

            return (cmd_noise if args.command == "noise" else cmd_tune)(args)
        if args.command == "campaign":
            from .montecarlo.cli import cmd_campaign

            return cmd_campaign(args)
        if args.command == "budget":
            from .budget import cmd_budget

            return cmd_budget(args)
    except (ValueError, FileNotFoundError, ConnectionError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 2


if __name__ == "__main__":
    sys.exit(main())
