"""`imu-fusion estimate RECORDING`: the estimators on a user's own recording.

A recording is a delimited text file (CSV) with a header row, a Parquet file, an HDF5 file or a
MATLAB .mat file (a BROAD trial, or columns as 1-D datasets or variables, acc and gyro also as
[N, 3] ones, with a time column or a `rate`; testbenches.reader), a PX4 log, or a ROS bag's IMU
topic (testbenches.bags). Columns are found by name: the accelerometer as acc_x/acc_y/acc_z (or
ax/ay/az, accX/accY/accZ, acc_x_g, ...), the gyro as gyro_x/... (or gx/gy/gz, gyrX/...,
wx/wy/wz), the time as time/t/timestamp (or --time-column), the sampling as dt or --rate;
--column QUANTITY=NAME maps any other name. The delimiter, the encoding and a unit stated in a
column's name ("Gyroscope X (deg/s)") are read off the file (testbenches.reader). Units are
given (--acc-unit g|m/s2, --gyro-unit rad/s|deg/s; raw counts with --counts PER_G,PER_DPS),
stated by the header, or found from the data: the accelerometer's from its norm (1 in g, 9.81 in
m/s^2), the gyro's as the unit in which its turn explains the accelerometer's turn of gravity
(testbenches.gyro_unit), the time's (--time-unit s|ms|us|ns) as the unit in which its steps are
an IMU's rate, the data deciding where two are (testbenches.time_unit). A given or stated unit
the data contradict is refused with the evidence, and so is a recording whose data cannot tell
the unit where none is given. A sample without a number in every column is rejected and counted
by the estimators, not the file.

A reference, roll and pitch [rad or deg: as its header says, else as the accelerometer at rest
tells] or a quaternion q_w, q_x, q_y, q_z (sensor to a z-up frame), in the recording or in a
file of its own (--reference, matched by time), gives the inclination RMSE, beside VQF's on the
same samples where the `vqf` package is installed.

It writes, per estimator, OUT/<recording>_<estimator>.csv (or .parquet, .h5 with --format):
time, roll, pitch [rad], bias_x..z [rad/s], and for the position filter pos_x..z [m],
vel_x..z [m/s] (--outputs chooses, --every N keeps every Nth sample), and OUT/<recording>.png.
The recording is read, run and written in blocks, the estimators in parallel through their C
twin, so memory does not grow with its length; a progress bar shows on a terminal. A file that
cannot serve gets one line saying what was wrong, and no output file.
"""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.types import DEG

from ..options import (
    RECORDING_HELP,
    add_calibration,
    add_no_plots,
    add_preset,
    add_recording_options,
    out_folder,
    parse_params,
    positive_int,
    with_calibration,
)
from ..table_out import FORMATS
from .lanes import Lanes, read_ahead
from .plot import draw, import_pyplot
from .reference import Reference, about_world_up, find_world_up
from .runs import PLOT_POINTS, Run, Thinned, VqfRun, conditioned, running, shared_runs

__all__ = ["PLOT_POINTS", "Reference", "Thinned", "add_estimate_parser", "cmd_estimate",
           "conditioned", "estimator_params", "output_columns", "param_names", "shared_runs"]

OUTPUTS = {"roll": ("roll",), "pitch": ("pitch",), "bias": ("bias_x", "bias_y", "bias_z"),
           "pos": ("pos_x", "pos_y", "pos_z"), "vel": ("vel_x", "vel_y", "vel_z"),
           "rejected": ("rejected",)}
"""The output groups --outputs chooses from, and their columns."""


def add_estimate_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("estimate", help="run estimators on your own recording (CSV, Parquet, "
                       "HDF5, MAT)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.set_defaults(func=cmd_estimate)
    p.add_argument("recording", type=Path, help=f"the recording: {RECORDING_HELP}")
    p.add_argument("--estimator", default="all", help="all or a comma list of the estimators")
    add_preset(p)
    add_calibration(p)
    add_recording_options(p)
    p.add_argument("--mounting", default=None, metavar="ROLL,PITCH,YAW",
                   help="the rotation [deg] from the sensor's axes to the body's (Z-Y-X), as "
                   "the estimators' mount_roll, mount_pitch, mount_yaw")
    p.add_argument("--gyro-sampling", choices=("point", "mean"), default=None,
                   help="what the gyro sample is: the rate at its instant (point, the default) "
                   "or the mean over the interval (integrating IMUs)")
    p.add_argument("--sensor-delay", type=float, default=None,
                   help="how long the samples lag their time stamps [s] (outputs turned ahead)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="an estimator parameter, for every chosen estimator that has it "
                   "(repeatable; a name none has is refused)")
    p.add_argument("--reference", type=Path, default=None,
                   help="a file of time with roll, pitch [rad or deg] or q_w, q_x, q_y, q_z "
                   "(any the reader takes; a ROS bag's pose topic): the reference, matched by "
                   "time")
    p.add_argument("--reference-offset", type=float, default=0.0, metavar="SECONDS",
                   help="added to the reference's time: its clock against the recording's "
                   "(estimate says the offset the turn rates show)")
    p.add_argument("--reference-topic", default=None, metavar="NAME",
                   help="a ROS bag reference's pose topic, where it has several")
    p.add_argument("--reference-column", action="append", default=[], metavar="QUANTITY=NAME",
                   help="the reference file's column of a quantity (time, roll, pitch, "
                   "q_w..q_z) where its name is none the reader knows (repeatable)")
    p.add_argument("--out", type=out_folder, default=Path("reports/estimate"),
                   help="output folder (reports/estimate)")
    p.add_argument("--format", choices=tuple(FORMATS), default="csv",
                   help="the outputs' format (csv)")
    p.add_argument("--outputs", default="roll,pitch,bias,pos,vel", metavar="LIST",
                   help=f"which outputs to write beside time: a comma list of {', '.join(OUTPUTS)} "
                   "(default roll,pitch,bias,pos,vel; pos and vel for the position filter)")
    p.add_argument("--every", type=positive_int, default=1, metavar="N",
                   help="write every Nth sample (the estimators still take every one)")
    add_no_plots(p, "the PNG plot")
    p.add_argument("--no-vqf", action="store_true",
                   help="with a reference, leave out VQF's row (and its line in the plot)")


def estimator_params(args: argparse.Namespace, entry: dict[str, Any],
                     has: set[str] | None = None) -> dict[str, Any]:
    """A preset entry with the command's sensor options and --param on top: of --param, the
    names in `has` (the estimator's parameters; None: every name)."""
    from ..fit.recording import RecordingError

    params = dict(entry)
    if args.gyro_sampling:
        params["gyro_sampling"] = args.gyro_sampling
    if args.sensor_delay is not None:
        params["sensor_delay"] = args.sensor_delay
    if args.mounting:
        try:
            roll, pitch, yaw = (float(v) * DEG for v in args.mounting.split(","))
        except ValueError:
            raise RecordingError(f"--mounting {args.mounting!r}: expected ROLL,PITCH,YAW in "
                                 "deg, e.g. 0,90,0") from None
        params.update(mount_roll=roll, mount_pitch=pitch, mount_yaw=yaw)
    params.update({name: value for name, value in parse_params(args.param).items()
                   if has is None or name in has})
    return params


def param_names(args: argparse.Namespace, keys: list[str]) -> dict[str, set[str]]:
    """Each estimator's parameter names; a --param name none of them has is refused, naming
    those they have (a name only some have, such as the Kalman filter's Q_angle, goes to
    those)."""
    from fusion_core.registry import estimator_class

    from ..fit.recording import RecordingError

    names = {key: set(estimator_class(key).param_specs()) for key in keys}
    known = set().union(*names.values())
    unknown = sorted(set(parse_params(args.param)) - known)
    if unknown:
        raise RecordingError(f"--param {', '.join(unknown)}: no estimator run here has it; "
                             f"they have {', '.join(sorted(known))}")
    return names


def output_columns(spec: str, position: bool) -> list[str]:
    """The output columns --outputs names (time first), for an estimator with or without a
    position; ValueError naming an unknown group."""
    from ..options import choose

    groups = choose(spec, list(OUTPUTS), "output")
    if not position:
        groups = [g for g in groups if g not in ("pos", "vel")]
    return ["time", *(c for g in groups for c in OUTPUTS[g])]


class _NoBar(contextlib.nullcontext):  # type: ignore[type-arg]
    def update(self, n: int) -> None:
        pass


def _progress(source: Any) -> Any:
    """A progress bar on a terminal (tqdm, where installed)."""
    try:
        from tqdm import tqdm
    except ImportError:
        return _NoBar()
    return tqdm(total=source.rows, unit="sample", unit_scale=True, disable=None,
                desc=source.name, leave=False)


def cmd_estimate(args: argparse.Namespace) -> int:
    from fusion_core.presets import load_preset
    from fusion_core.registry import KEYS, create

    from ..fit.recording import REFERENCE_COLUMNS, RecordingError, parse_columns, source_from_args
    from ..options import choose

    keys = choose(args.estimator, list(KEYS), "estimator")
    preset = with_calibration(load_preset(args.preset), args.calibration)
    has = param_names(args, keys)
    estimators = {key: create(key, estimator_params(args, preset[key], has[key]))
                  for key in keys}
    names = {key: output_columns(args.outputs, est.HAS_POSITION)
             for key, est in estimators.items()}
    if not args.no_plots:  # the plotting library loads while the recording opens, which
        import threading  # leaves the second core idle (reading, units and rate are serial)

        threading.Thread(target=import_pyplot, daemon=True).start()
    mapped = parse_columns(args.reference_column, "--reference-column", REFERENCE_COLUMNS)
    given = [name for name, value in (("--reference-column", mapped),
                                      ("--reference-topic", args.reference_topic),
                                      ("--reference-offset", args.reference_offset)) if value]
    if given and args.reference is None:
        raise RecordingError(f"{given[0]} is given, but no --reference: it names a reference "
                             "file's columns, topic or clock offset (a reference in the "
                             "recording's own file is mapped with --column)")
    source = source_from_args(args.recording, args)
    print(f"{args.recording}: {source.choices}")
    reference = (Reference(args.reference, source.time_unit, mapped, args.reference_topic,
                           args.reference_offset) if args.reference is not None else None)
    args.out.mkdir(parents=True, exist_ok=True)
    runs: list[Any] = []
    try:
        for key, est in estimators.items():
            path = args.out / f"{source.name}_{key}{FORMATS[args.format]}"
            runs.append(Run(key, est, path, args.format, names[key]))
        vqf_params = estimator_params(args, preset[keys[0]], has[keys[0]])  # calibration, mounting
        vqf, found = _run_blocks(args, source, reference, runs, vqf_params)
        written = [run.writer.commit() for run in runs]  # one that fails: the rest discarded
    except BaseException:
        for run in runs:
            run.writer.discard()
        raise
    print(found["read"])
    for line in found["notes"]:
        print(line)
    print(f"{'estimator':<10} {'rejected':>8} {'incl. RMSE [deg]':>17}  output")
    scored = found["scored"]
    for run, path in zip(runs, written, strict=True):
        shown = f"{run.score.rmse:17.4f}" if scored else f"{'-':>17}"
        print(f"{run.key:<10} {run.rejected:>8} {shown}  {path}")
    if scored and vqf is not None:
        shown = f"{vqf.score.rmse:17.4f}" if vqf.stream is not None else f"{'-':>17}"
        print(f"{'vqf':<10} {'-':>8} {shown}  {vqf.note}")
    if not args.no_plots:
        print(draw(args.out / f"{source.name}.png", runs, vqf if scored else None,
                    found["trace"], source.name))
    return 0


def _run_blocks(args: argparse.Namespace, source: Any, reference: Reference | None,
                runs: list[Any], vqf_params: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """Every block through every estimator (in parallel, each at its own pace: lanes.Lanes) and VQF
    where there is a reference (on the samples as `vqf_params` condition them); what was read,
    found and scored."""
    from ..fit.recording import RecordingError

    world_up, notes, vqf = None, [], None
    n = missing = scored = 0
    first_t = last_t = float("nan")
    truth = Thinned()
    duration = 0.0
    lanes = None
    try:
        with _progress(source) as bar:
            for rec, t in read_ahead(source.blocks()):
                if n == 0:  # the samples as the estimators take them, for the checks
                    seen = conditioned(rec.acc, rec.gyro, vqf_params)
                    if reference is not None and reference.span[1] < t[0]:
                        raise RecordingError(reference.overlap_error(float(t[0]),
                                                                     float("nan")))
                    if reference is not None and (said := reference.angle_unit_from(seen[0],
                                                                                     t)):
                        notes.append(said)
                if reference is not None:
                    rec.up_ref, rec.ref_quat = reference.at(t)
                    rec.counts = np.all(np.isfinite(rec.up_ref), axis=1)
                if n == 0:
                    world_up, said_first = _first_block(rec, t, seen, args, reference,
                                                        vqf_params)
                    notes += said_first
                    if rec.up_ref is not None and not args.no_vqf:
                        vqf = VqfRun(source.rate, vqf_params)
                if world_up is not None and rec.ref_quat is not None:
                    rec.up_ref = about_world_up(rec.ref_quat, world_up)
                if rec.up_ref is not None:  # scored where every estimator and VQF took it
                    rec.counts = rec.counted & rec.valid
                    scored += int(rec.counts.sum())
                    truth.add(n, {"t": t, "up": rec.up_ref})
                if lanes is None:  # VQF's lane is known after the first block's reference
                    lanes = Lanes([*running(runs), *([vqf] if vqf is not None else [])],
                                   bar.update)
                lanes.submit(len(t), rec, t, n, args.every)  # rec is not changed after this
                if n == 0:
                    first_t = float(t[0])
                last_t = float(t[-1])
                duration += float(np.nansum(rec.dt[1:] if n == 0 else rec.dt))
                missing += int((~rec.valid).sum())
                n += len(t)
            if lanes is not None:
                lanes.close()
    except BaseException:
        if lanes is not None:  # the estimators stop before their outputs are discarded
            lanes.close(quiet=True)
        raise
    if reference is not None and scored == 0:
        lo, hi = reference.span
        if hi < first_t or lo > last_t:
            raise RecordingError(reference.overlap_error(first_t, last_t))
    if vqf is not None or reference is not None or scored:
        if scored == 0:
            raise RecordingError(f"{args.recording}: no sample has both a valid reference and "
                                 "numbers in every column: nothing to score")
        notes.append(f"reference: {scored} of {n} samples scored (the others lack a valid "
                     "reference or a number)")
    found = {"read": f"read {source.summary(n, duration, missing, choices=False)}", "notes": notes,
             "scored": scored, "trace": truth}
    return vqf, found


def _first_block(rec: Any, t: np.ndarray, seen: tuple[np.ndarray, np.ndarray],
                 args: argparse.Namespace, reference: Reference | None,
                 params: dict[str, Any]) -> tuple[np.ndarray | None, list[str]]:
    """A first block's (rec at times t; `seen`, its acc and gyro as `params` condition them)
    world vertical of a quaternion reference (find_world_up) and what to say of it, of a z axis
    down and of a reference's clock; RecordingError where its reference (a file's or its own
    columns') breaks a law of motion (reference_axes.check_axes)."""
    from ..reference_axes import check_axes

    path = args.reference or args.recording
    world_up, note = find_world_up(seen[0], rec.ref_quat, path)
    lag = reference.lag_note(rec, t) if reference is not None else ""
    if rec.up_ref is not None:
        up = (rec.up_ref if world_up is None or rec.ref_quat is None
              else about_world_up(rec.ref_quat, world_up))
        unmounted = {**params, "mount_roll": 0.0, "mount_pitch": 0.0, "mount_yaw": 0.0}
        check_axes(path, *seen, rec.dt, up, rec.ref_quat is None, lag,
                   conditioned(rec.acc, rec.gyro, unmounted))
    return world_up, [said for said in (note, _z_down_note(rec, args), lag) if said]


Z_DOWN_COS = -0.9
"""The accelerometer's mean direction over the first second with a z component below this (25
deg from straight down) starts the sensor with its z axis down."""


def _z_down_note(rec: Any, args: argparse.Namespace) -> str:
    """Where the sensor starts with its z axis down and no mounting is given, what that means:
    roll near +-180 deg is right in this project's z-up frame, and a recording in a z-down
    frame (NED or FRD, as drone autopilots log it) reads as a level one turned over."""
    if args.mounting:
        return ""
    first = rec.acc[:max(2, round(rec.rate))]
    first = first[np.all(np.isfinite(first), axis=1)]
    if not len(first):
        return ""
    mean = first.mean(axis=0)
    norm = float(np.linalg.norm(mean))
    if not (norm > 0.0 and mean[2] / norm < Z_DOWN_COS):
        return ""
    return ("the sensor starts with its z axis down (the accelerometer reads gravity along -z), "
            "so roll is near +-180 deg; a recording in a z-down frame (NED or FRD, as PX4 and "
            "ArduPilot log it) reads as level with --mounting 180,0,0")
