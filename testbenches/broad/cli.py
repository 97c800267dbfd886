"""`python -m testbenches broad PATH...`: the command line of the BROAD evaluation.

Kept apart from testbenches/__main__.py, which only registers the subcommand and dispatches to
`cmd_broad`; everything it does is callable from Python (`testbenches.broad.evaluate`,
`testbenches.broad.report.write_reports`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from fusion_core.registry import keys_help

from ..fmus import DEFAULT_FMU_DIR
from ..options import (
    add_calibration,
    add_cluster,
    add_no_plots,
    add_preset,
    choose,
    non_negative_int,
    out_folder,
    positive_float,
)

if TYPE_CHECKING:
    from .cv import CvResult, Grid
    from .data import BroadTrial
    from .run import BroadResult

HELP = """\
Evaluate the estimators on BROAD trials (Laidig et al., Data 2021): inclination RMSE over each
trial's movement samples, a trial x estimator table with means per BROAD group, and
DIR/report.json, DIR/report.md and a bar chart. PATH: trial files (.hdf5 or MATLAB v5 .mat) or
folders holding them. Peers (--peers) need the bench extra: pip install -e '.[bench]'."""


def add_broad_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:  # type: ignore[type-arg]
    """Register the `broad` subcommand on the subparsers of `python -m testbenches`."""
    from ..battery import PARTS as BATTERY_PARTS  # the help names the grid, choices, parts
    from .cv import CHOICES, CV_GRID

    p = sub.add_parser("broad", help="accuracy on BROAD's real recordings (inclination RMSE)",
                       description=HELP)
    p.set_defaults(func=cmd_broad)
    p.add_argument("paths", nargs="+", type=Path, metavar="PATH",
                   help="BROAD trial files (.hdf5, .mat) or folders of them")
    p.add_argument("--estimator", default="all",
                   help=f"all or a comma list of {keys_help()} (all)")
    add_preset(p, more=", all (both named ones), or a comma list of them")
    add_calibration(p)
    p.add_argument("--peers", action="store_true",
                   help="also run VQF (6D), Madgwick and Mahony (ahrs) on the same trials, and VQF "
                   "with its output turned ahead over the sensor's delay as ours (vqf-ahead)")
    p.add_argument("--fmu", action="store_true",
                   help="run the estimators as the built FMUs through fmpy instead of fusion_core")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR,
                   help="folder of the built FMUs, for --fmu (dist)")
    p.add_argument("--trials-json", type=Path, default=None,
                   help="BROAD's trials.json for the groups (default: the one beside the files; "
                   "else the groups in the trial names)")
    p.add_argument("--head", type=positive_float, default=None, metavar="SECONDS",
                   help="use only the first SECONDS of every trial (a quick look)")
    p.add_argument("--out", type=out_folder, default=Path("reports/broad"),
                   help="report folder (reports/broad)")
    add_no_plots(p, "the bar chart")
    p.add_argument("--cv", action="store_true",
                   help="cross-validate the defaults: each parameter a scan chooses ("
                   + ", ".join(CV_GRID) + ") chosen again without each motion fold (slow "
                   "rotation, fast rotation, translation, disturbed/combined) and scored on it; "
                   "prints the cross-validated mean beside the in-sample one (and VQF's with "
                   "--peers) and adds cv_mean_inclination_rmse_deg to report.json "
                   "(testbenches.broad.cv)")
    p.add_argument("--cv-grid", action="append", default=[], metavar="NAME=V1,V2,...",
                   help="cross-validate these parameters and values instead (repeat for several; "
                   "implies --cv): e.g. --cv-grid scale_time=0.25,0.5,1 --cv-grid "
                   "max_correction_time=1,3,10 (default: "
                   + ", ".join(f"{k}={','.join(f'{v:g}' for v in vs)}" for k, vs in CV_GRID.items())
                   + "). The trials may be "
                   "recordings of one's own in BROAD's format, their motion groups in their names "
                   "or a trials.json")
    p.add_argument("--cv-unconstrained", action="store_true",
                   help="let each fold choose any grid point, also one that fails the contract's "
                   "accuracy bounds on the realistic sensor (by default a fold chooses the best "
                   "point that keeps them: testbenches.broad.feasible); implies --cv")
    p.add_argument("--cv-choice", choices=CHOICES, default=None,
                   help="how each fold chooses among the grid points: regret (default) takes the "
                   "point whose worst training fold is least above that fold's best, so that it "
                   "holds on every kind of motion; mean takes the lowest mean over the training "
                   "trials (testbenches.broad.cv.CHOICES); implies --cv")
    p.add_argument("--cv-battery-parts", type=non_negative_int, default=None, metavar="N",
                   help="parts per cell of the synthetic battery that says whether a fold's "
                   "choice, or the nested cross-validation's, may leave a filter's longer vector "
                   "out (testbenches.broad.cv.PROCEDURES; default "
                   f"{BATTERY_PARTS}; 0: BROAD's folds alone decide); runs on --scheduler")
    add_cluster(p)
    p.add_argument("--gyro-fit", action="store_true",
                   help="also fit each trial's gyro against the reference (scale-factor, "
                   "cross-axis and bias errors, its lag; testbenches.broad.gyro): a table and "
                   "DIR/gyro_fit.json")
    return p


def cmd_broad(args: argparse.Namespace) -> int:
    """Run the evaluation, print the table, write the reports. Exit status 0, or 2 on bad input
    (the message says what was wrong)."""
    from tqdm import tqdm

    from fusion_core import ESTIMATORS
    from fusion_core.presets import PRESETS

    from ..battery import PARTS as BATTERY_PARTS
    from ..peers import AHEAD_PEERS, PEERS, PeerUnavailable, check_peers
    from .data import load_trial
    from .report import table, write_reports
    from .run import collect_paths, evaluate, plan_columns

    estimators = choose(args.estimator, list(ESTIMATORS), "estimator")
    run_cv = args.cv or bool(args.cv_grid) or args.cv_unconstrained or bool(args.cv_choice)
    grid = None
    if args.cv_grid:  # refused before any run
        from .cv import CV_ESTIMATORS, check_grid, parse_grid

        grid = parse_grid(args.cv_grid)
        check_grid(grid, [k for k in estimators if k in CV_ESTIMATORS] or list(CV_ESTIMATORS))
    presets = list(PRESETS) if args.preset == "all" else [p for p in args.preset.split(",") if p]
    peers = [*PEERS, *AHEAD_PEERS] if args.peers else []
    try:
        check_peers(peers)
    except PeerUnavailable as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    columns = plan_columns(estimators, presets, peers, fmu=args.fmu,
                           calibration=args.calibration)
    files = collect_paths(args.paths)
    if not files:
        raise ValueError(f"no trial files in {', '.join(map(str, args.paths))}")
    trials = [load_trial(f) for f in files]  # refuses a non-trial before any long run
    if args.head is not None:
        trials = [t.head(args.head) for t in trials]
    with tqdm(total=len(files) * len(columns), unit="run", file=sys.stderr) as bar:
        def progress(trial: str, column: str) -> None:
            bar.set_postfix_str(f"{trial[:28]} {column}")
            bar.update()

        result = evaluate(trials, columns, fmu_dir=args.fmu_dir, trials_json=args.trials_json,
                          progress=progress)
    print(table(result))
    parts = BATTERY_PARTS if args.cv_battery_parts is None else args.cv_battery_parts
    cv = (cross_validation(trials, result, estimators, args.out, args.peers, grid,
                           constrained=not args.cv_unconstrained, plot=not args.no_plots,
                           choice=args.cv_choice or "regret", battery_parts=parts,
                           scheduler=args.scheduler, workers=args.workers)
          if run_cv else None)
    extra = ({"cv_mean_inclination_rmse_deg": cv.cv_means(),
              "nested_cv_mean_inclination_rmse_deg": cv.nested_means()}
             if cv is not None else None)
    paths = write_reports(result, args.out, plot=not args.no_plots, extra=extra)
    print("\nmean_inclination_rmse_deg: " + ", ".join(
        f"{k} {v:.3f}" for k, v in result.means().items()))
    print("reports: " + ", ".join(str(p) for p in paths.values()))
    if run_cv:
        from .cv import cv_table

        print("\n" + (cv_table(cv) if cv is not None else
                      "cross-validation: none of the chosen estimators has a scanned parameter"))
    if args.gyro_fit:
        print(f"\n{gyro_fit_table(trials, result, args.out)}")
    return 0


def cross_validation(trials: list[BroadTrial], result: BroadResult, estimators: list[str],
                     out: Path, peers: bool, grid: Grid | None = None,
                     constrained: bool = True, plot: bool = True,
                     choice: str = "regret", battery_parts: int = 0,
                     scheduler: str | None = "local", workers: int = 2) -> CvResult | None:
    """The cross-validation (testbenches.broad.cv) of the estimators that have one over grid
    (None: CV_GRID), each fold choosing by choice (cv.CHOICES) among the points that keep the
    contract where constrained, written to DIR/cv.json (and with plot DIR/cv.png); None where
    none has. The peer the evaluation ran already is taken from it. battery_parts: parts per
    cell of the battery that says whether a choice may leave a filter's longer vector out,
    run on scheduler with workers (testbenches.mechanisms.longer_vector_on_battery; 0, or
    fewer than three folds: not run, BROAD's folds alone decide)."""
    import json

    from tqdm import tqdm

    from ..peers import AHEAD_PEERS
    from .cv import CV_ESTIMATORS, CV_GRID, NESTED_FOLDS, cross_validate, fold_of
    from .feasible import contract_failure

    keys = [k for k in estimators if k in CV_ESTIMATORS]
    if not keys:
        return None
    groups = [t.groups for t in result.trials]
    kept = None
    nested = len({fold_of(g) for g in groups}) >= NESTED_FOLDS
    stretch = "acc_lowpass_stretch" in (grid or CV_GRID)
    if battery_parts > 0 and nested and stretch:
        from ..battery import MOTIONS, SENSOR_CLASSES
        from ..mechanisms import longer_vector_on_battery

        with tqdm(desc="battery, longer vector", unit="cell", file=sys.stderr,
                  total=2 * len(MOTIONS) * len(SENSOR_CLASSES)) as bar:
            kept = longer_vector_on_battery(keys, battery_parts, scheduler, workers, bar.update)
    measured = {c.name: {t.name: t.rmse_deg[c.name] for t in result.trials}
                for c in result.columns if c.kind == "peer"}
    with tqdm(desc="cross-validation", unit="trial", file=sys.stderr,
              total=len(trials) * len(keys) + (len(trials) if peers else 0)) as bar:
        cv = cross_validate(trials, groups, keys,
                            {"vqf-ahead": AHEAD_PEERS["vqf-ahead"]} if peers else None,
                            lambda label: bar.update(), measured, grid,
                            contract_failure if constrained else None, choice,
                            battery_keeps=kept)
    out.mkdir(parents=True, exist_ok=True)
    (out / "cv.json").write_text(json.dumps(cv.as_dict(), indent=1))
    if plot:
        from .cv import plot_cv

        plot_cv(cv, out / "cv.png")
    return cv


def gyro_fit_table(trials: list[BroadTrial], result: BroadResult, out: Path) -> str:
    """Each trial's gyro fitted against its reference (testbenches.broad.gyro) as a table, also
    written to out/gyro_fit.json, and every column's mean inclination RMSE as evaluated beside
    its scale oracle (gyro.scale_oracle). trials: the evaluated trials, in result's order."""
    import json

    import numpy as np

    from .gyro import fit_delay, fit_gyro, scale_oracle

    rows, fits = [], {}
    head = (f"{'trial':44s} {'scale error x/y/z %':>22s} {'max cross %':>11s} "
            f"{'bias x/y/z deg/s':>22s} {'windows':>7s} {'resid deg':>9s} {'lag ms':>6s}")
    for trial, evaluated in zip(trials, result.trials, strict=True):
        try:
            fit = fit_gyro(trial)
        except ValueError as err:
            rows.append(f"{trial.name[:44]:44s} {err}")
            continue
        d = {**fit.as_dict(), **fit_delay(trial).as_dict()}
        d["rmse_deg"] = evaluated.rmse_deg
        d["rmse_scale_removed_deg"] = scale_oracle(trial, fit, result.columns,
                                                   evaluated.groups).rmse_deg
        fits[trial.name] = d
        scale = "/".join(f"{v:+.2f}" for v in d["scale_error_pct"])
        bias = "/".join(f"{v:+.3f}" for v in d["bias_dps"])
        rows.append(f"{trial.name[:44]:44s} {scale:>22s} {d['max_abs_cross_axis_pct']:11.2f} "
                    f"{bias:>22s} {d['windows']:7d} {d['residual_deg']:9.3f} "
                    f"{d['delay_ms']:6.2f}")
    out.mkdir(parents=True, exist_ok=True)
    (out / "gyro_fit.json").write_text(json.dumps(fits, indent=1))
    lines = ["gyro against the reference (integral(gyro) = M dphi + b T; lag: how late the "
             "gyro shows the reference's rotation, gyro.fit_delay):", head,
             "-" * len(head), *rows]
    if fits:
        lines.append(f"\nmean inclination RMSE over the {len(fits)} fitted trials, as evaluated "
                     "-> with each trial's fitted scale errors divided out of its gyro (oracle):")
        for name in result.names:
            a = np.mean([d["rmse_deg"][name] for d in fits.values()])
            b = np.mean([d["rmse_scale_removed_deg"][name] for d in fits.values()])
            lines.append(f"  {name:12s} {a:.3f} -> {b:.3f} deg")
    return "\n".join(lines)


__all__ = ["add_broad_parser", "cmd_broad"]
