"""`python -m testbenches run ...`: the contract run's command line (testbenches.contract_runs):
estimator x scenario x seed runs through the FMUs with the contract checks; prints the contract
table, writes DIR/report.json, DIR/report.md and plots; exit status 1 on any FAIL."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from fusion_core.scenarios import ESTIMATION_SCENARIOS

from .contract import accuracy_limits
from .fmus import DEFAULT_FMU_DIR, ESTIMATOR_FMUS, KINDS, kind_dir
from .master import MASTERS
from .options import (
    add_calibration,
    add_no_plots,
    add_preset,
    add_sensor,
    choose,
    jitter_fraction,
    load_sensor,
    non_negative_int,
    out_folder,
    parse_params,
    positive_float,
    positive_int,
    with_calibration,
)
from .parts import CALIBRATED_SHARE, PARTS
from .peers import PEERS

CALIBRATED_PCT = f"{100 * CALIBRATED_SHARE:g}"


def add_run_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    run = sub.add_parser("run", help="run the testbench through the FMUs and check the contract")
    run.add_argument("--estimator", default="all",
                     help=f"all or a comma list of {', '.join(ESTIMATOR_FMUS)}")
    run.add_argument("--scenario", default="all",
                     help=f"all or a comma list of {', '.join(ESTIMATION_SCENARIOS)}")
    run.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                     help="estimator FMU parameter for every run (repeatable); an enumeration "
                     "by item name, e.g. --param gyro_sampling=mean")
    add_preset(run)
    add_calibration(run)
    run.add_argument("--calibrate-first", action="store_true",
                     help="calibrate each seed's sensor part on its own calibration session "
                     "first (the calibrate command's code) and apply its matrices in the runs")
    add_sensor(run)
    run.add_argument("--seeds", type=positive_int, default=1,
                     help="seeds per estimator x scenario (1)")
    run.add_argument("--parts", type=non_negative_int, default=PARTS, metavar="N",
                     help=f"state each accuracy check over N sensor parts too, as delivered (the "
                     f"typical part within the bound) and calibrated first ({CALIBRATED_PCT} "
                     f"%% of parts within it), through the C twins; 0: no ({PARTS})")
    run.add_argument("--jitter", type=jitter_fraction, default=0.0,
                     help="communication-step jitter, fraction of the period (0)")
    run.add_argument("--duration", type=positive_float, default=None,
                     help="seconds per run instead of each scenario's own duration")
    run.add_argument("--out", type=out_folder, default=Path("reports"),
                     help="report folder (reports)")
    run.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR, help="built FMUs (dist)")
    run.add_argument("--kind", choices=KINDS, default="auto",
                     help="FMUs to run: native (FMI 2.0 from the C twin, FMU_DIR/native/fmi2), "
                     "pythonfmu (FMU_DIR), or auto: native where built (default)")
    run.add_argument("--master", choices=MASTERS, default="gauss-seidel",
                     help="how the FMUs step: gauss-seidel (each on the newest outputs of the "
                     "one before it, the default) or jacobi (each on the others' outputs of "
                     "the previous step, as libcosim, Ecos and parallel containers do: the "
                     "chain adds 2 steps of delay, by which the truth is aligned)")
    add_no_plots(run, "the PNG plots")
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
                     f"of {', '.join(PEERS)} (the bench extra: pip install -e '.[bench]')")
    run.set_defaults(func=cmd_run)


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


def cmd_run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from .contract_runs import contract_jobs, run_contract
    from .report import (
        contract_table,
        over_several_seeds,
        seed_summaries,
        seed_summary_table,
        write_reports,
    )

    estimators = choose(args.estimator, list(ESTIMATOR_FMUS), "estimator")
    scenarios = choose(args.scenario, list(ESTIMATION_SCENARIOS), "scenario")
    from fusion_core.presets import load_preset

    preset = with_calibration(load_preset(args.preset), args.calibration)
    sensor = load_sensor(args.sensor)
    params = parse_params(args.param)
    check_params(params, estimators, preset)
    peers = _peers(args)  # checked before the runs: a missing package fails at once
    jobs = contract_jobs(estimators, scenarios, seeds=args.seeds, jitter=args.jitter,
                         contract_checks=not args.no_contract)
    fmu_dir = kind_dir(args.fmu_dir, args.kind)
    print(f"FMUs: {fmu_dir}", file=sys.stderr)
    parts = 0 if args.no_contract else args.parts
    bounded = sum(accuracy_limits(e, s) is not None for e in estimators for s in scenarios)
    n_parts = 2 * parts * bounded  # the pairs with a bound are run over parts
    with tqdm(total=len(jobs) + n_parts, unit="run", file=sys.stderr) as bar:
        def progress(job: object) -> None:
            bar.set_postfix_str(f"{job.estimator} {job.scenario}")  # type: ignore[attr-defined]
            bar.update()

        def part_done() -> None:
            bar.set_postfix_str(f"over {parts} parts")
            bar.update()

        result = run_contract(estimators=estimators, scenarios=scenarios, seeds=args.seeds,
                              jitter=args.jitter, fmu_dir=fmu_dir, progress=progress,
                              contract_checks=not args.no_contract, params=params,
                              duration=args.duration, timing=not args.no_timing_check,
                              jobs=args.jobs, preset=preset, sensor=sensor,
                              calibrate_first=args.calibrate_first, master=args.master,
                              parts=parts, parts_progress=part_done)
    print(contract_table(result))
    peer_rows = None
    if peers:
        from .peer_runs import peer_table, run_peers

        peer_rows = run_peers(peers, scenarios, args.seeds, sensor, args.duration,
                              calibrate_first=args.calibrate_first)
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
