"""The `noise` and `tune` commands' argument parsing (python -m testbenches noise|tune ...)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from fusion_core import ESTIMATORS
from fusion_core.registry import estimator_class

from ..options import (
    RECORDING_HELP,
    add_calibration,
    add_no_plots,
    add_preset,
    add_recording_options,
    non_negative_float,
    out_folder,
    positive_float,
    positive_int,
    with_calibration,
)


def add_fit_parsers(sub: argparse._SubParsersAction) -> None:
    noise = sub.add_parser(
        "noise", help="noise densities of a static recording (Allan deviation), a preset for "
        "every estimator and the sensor FMU's parameters for that sensor")
    noise.set_defaults(func=cmd_noise)
    noise.add_argument("file", type=Path, help=f"a static recording: {RECORDING_HELP}; or a "
                       "BROAD trial (its rest segment is used)")
    add_recording_options(noise)
    noise.add_argument("--out", type=out_folder, default=Path("reports/noise"),
                       help="folder for noise.json, preset.json, sensor.json, allan.png")
    noise.add_argument("--gyro-range", type=positive_float, default=2000.0, metavar="DEG_S",
                       help="the gyro's full-scale range setting [deg/s] from its datasheet or "
                       "its configuration (a static recording cannot show it): every estimator "
                       "treats a sample at it as clipped (2000, the MPU-6050 class's widest)")
    noise.add_argument("--gyro-bias-std", type=non_negative_float, default=0.0,
                       metavar="DEG_S", help="the spread (1 sigma) of the gyro bias the part "
                       "starts a run with where it runs without a start-up calibration: its "
                       "datasheet's zero-rate offset tolerance (a static recording shows one "
                       "start's bias, not the spread); the Kalman filters' bias prior is at "
                       "least this (0: a part calibrated at start-up)")
    add_no_plots(noise, "allan.png")

    tune = sub.add_parser(
        "tune", help="fit an estimator's tunable parameters to recordings with a reference, "
        "validated on others")
    tune.set_defaults(func=cmd_tune)
    tune.add_argument("--estimator", required=True, choices=list(ESTIMATORS))
    tune.add_argument("files", type=Path, nargs="+",
                      help="recordings to fit: BROAD trials, or CSV with reference columns "
                      "(q_w, q_x, q_y, q_z or roll, pitch [rad])")
    tune.add_argument("--validate", type=Path, nargs="*", default=[],
                      help="recordings that check the fit (not fitted)")
    add_preset(tune, "--start", more=": where the fit starts")
    add_calibration(tune)
    tune.add_argument("--params", default=None,
                      help="comma list of the parameters to fit, or all (every tunable one); "
                      "default: those the recommended preset took from a scan (cf tau, mgcf "
                      "w0 and zeta, kf Q_bias, ukf bias_psd, poskf q)")
    tune.add_argument("--max-evaluations", type=positive_int, default=300,
                      help="runs of the estimator over the fit set at most (300)")
    tune.add_argument("--max-worse", type=non_negative_float, default=0.03,
                      help="how much worse than at the start any one fit recording may end, a "
                      "fraction (0.03)")
    add_recording_options(tune)
    tune.add_argument("--fmu", action="store_true",
                      help="confirm the fitted preset through the estimator's FMU")
    tune.add_argument("--fmu-dir", type=Path, default=Path("dist"), help="built FMUs (dist)")
    tune.add_argument("--out", type=out_folder, default=Path("reports/tune"),
                      help="folder for preset.json, tune.json, tune.png")
    add_no_plots(tune, "tune.png")


def cmd_noise(args: argparse.Namespace) -> int:
    from .noise import run_noise
    from .recording import recording_from_args, rest

    rec = rest(recording_from_args(args.file, args)[0])
    noise = run_noise(rec, args.out, plots=not args.no_plots,
                      gyro_range=math.radians(args.gyro_range),
                      gyro_bias_std=math.radians(args.gyro_bias_std))
    g, a = noise["gyro_density"]["mean"], noise["acc_density"]["mean"]
    print(f"{rec.name}: {noise['recording']['duration_s']:.0f} s at {rec.rate:g} Hz")
    print(f"  gyro white noise {noise['gyro_density_deg_s_sqrt_hz']:.4g} deg/s/sqrt(Hz) "
          f"(gyro_psd {g * g:.4g} rad2/s)")
    print(f"  acc white noise {noise['acc_density_ug_sqrt_hz']:.4g} ug/sqrt(Hz) "
          f"(acc_psd {a * a:.4g} m2/s3)")
    print(f"  gyro range +-{args.gyro_range:g} deg/s (gyro_range {noise['gyro_range']:.6g} rad/s; "
          "--gyro-range: a static recording cannot show it)")
    if args.gyro_bias_std > 0.0:
        print(f"  gyro turn-on bias +-{args.gyro_bias_std:g} deg/s (1 sigma): the Kalman "
              "filters' init_bias_std at least that")
    if "note" in noise:
        print(f"  note: {noise['note']}")
    print(f"wrote {args.out}/noise.json, preset.json, sensor.json"
          + ("" if args.no_plots else ", allan.png"))
    return 0


def cmd_tune(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from fusion_core.presets import load_preset

    from .recording import recording_from_args
    from .tune import fmu_score, require_reference, tune, write

    fit_recs = [recording_from_args(p, args)[0] for p in args.files]
    val_recs = [recording_from_args(p, args)[0] for p in args.validate]
    start = with_calibration(load_preset(args.start), args.calibration)[args.estimator]
    for rec in (*fit_recs, *val_recs):  # before the progress bar starts
        require_reference(rec, start)
    names = [n.strip() for n in args.params.split(",")] if args.params else None
    with tqdm(total=args.max_evaluations, unit="run", file=sys.stderr) as bar:
        def progress(best: float) -> None:
            bar.set_postfix_str(f"best {best:.4f} deg")
            bar.update()

        result = tune(args.estimator, fit_recs, val_recs, start, names, args.max_evaluations,
                      progress, args.max_worse)
    if args.fmu:
        from ..fmus import kind_dir

        result.fmu_fit_rmse_deg = fmu_score(args.estimator, result.fitted, fit_recs,
                                            kind_dir(args.fmu_dir))
    write(result, args.out, plots=not args.no_plots)
    print(f"{args.estimator}: fit {result.start_fit_rmse_deg:.4f} -> {result.fit_rmse_deg:.4f} "
          f"deg over {len(fit_recs)} recording(s), {result.evaluations} runs, "
          f"{result.seconds:.0f} s")
    if result.validation_rmse_deg is not None:
        print(f"  validation {result.start_validation_rmse_deg:.4f} -> "
              f"{result.validation_rmse_deg:.4f} deg over {len(val_recs)} recording(s)")
    if result.fmu_fit_rmse_deg is not None:
        print(f"  through the FMU: fit {result.fmu_fit_rmse_deg:.4f} deg")
    specs = estimator_class(args.estimator, start).param_specs()
    for d in result.dimensions:
        before = result.start.get(d.name, specs[d.name].default)
        print(f"  {d.name}: {before:.6g} -> {result.fitted.get(d.name, before):.6g}")
    print(f"wrote {args.out}/preset.json, tune.json" + ("" if args.no_plots else ", tune.png"))
    return 0
