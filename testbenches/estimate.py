"""`imu-fusion estimate RECORDING`: the estimators on a user's own recording.

A recording is a CSV file with a header row, or an HDF5 file (a BROAD trial, or datasets `acc`
and `gyro` [N, 3] with `time` [N] or a `rate` attribute). Columns are found by name: the
accelerometer as acc_x/acc_y/acc_z (or ax/ay/az, accX/accY/accZ, acc_x_g, ...), the gyro as
gyro_x/... (or gx/gy/gz, gyrX/..., wx/wy/wz), the time as time/t/timestamp (or --time-column), the
sampling as dt or --rate; --column QUANTITY=NAME maps any other name. The delimiter, the
encoding and a unit stated in a column's name ("Gyroscope X (deg/s)") are read off the file
(testbenches.reader). Units are given (--acc-unit g|m/s2, --gyro-unit rad/s|deg/s), stated by
the header, or found from the data: the accelerometer's from its norm (1 in g, 9.81 in m/s^2),
the gyro's as the unit in which its turn explains the accelerometer's turn of gravity
(testbenches.gyro_unit). A given or stated gyro unit the data contradict is refused with the
evidence, and so is a recording whose data cannot tell the unit where none is given. A sample
without a number in every column is rejected and counted by the estimators, not the file.

A reference, roll and pitch [rad] or a quaternion q_w, q_x, q_y, q_z (sensor to a z-up frame),
in the recording or in a file of its own (--reference, matched by time), gives the inclination
RMSE, beside VQF's on the same samples where the `vqf` package is installed.

It writes, per estimator, OUT/<recording>_<estimator>.csv (time, roll, pitch [rad], bias_x..z
[rad/s], and for the position filter pos_x..z [m], vel_x..z [m/s]) and OUT/<recording>.png.
A file that cannot serve gets one line saying what was wrong.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .fit.recording import read_csv, recording_from_args, reference_up  # the one reader
from .options import (
    add_calibration,
    add_preset,
    add_recording_options,
    parse_params,
    with_calibration,
)
from .reader import TIME_SCALE

G_STANDARD = 9.80665
DEG = np.pi / 180.0


def add_estimate_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("estimate", help="run estimators on your own recording (CSV or HDF5)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.set_defaults(func=cmd_estimate)
    p.add_argument("recording", type=Path, help="CSV or HDF5 recording")
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
                   help="an estimator parameter for every chosen estimator (repeatable)")
    p.add_argument("--reference", type=Path, default=None,
                   help="a CSV of time with roll, pitch [rad] or q_w, q_x, q_y, q_z: the "
                   "reference, matched by time")
    p.add_argument("--out", type=Path, default=Path("reports/estimate"),
                   help="output folder (reports/estimate)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plot")


def reference_by_time(path: Path, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The up direction [N, 3] of a reference file (time with roll, pitch or q_w..q_z) at the
    recording's times (linear between the reference's samples; NaN outside them and where the
    reference has no valid row); RecordingError where it cannot serve."""
    from .fit.recording import RecordingError

    found = read_csv(path, None)
    cols, header = found.values, found.header
    if "time" not in cols:
        raise RecordingError(f"{path}: a reference needs a time column [s]; it has "
                             f"{', '.join(header)}")
    up, quat = reference_up(cols, path)
    if up is None:
        raise RecordingError(f"{path}: a reference holds roll and pitch [rad] or q_w, q_x, q_y, "
                             f"q_z; it has {', '.join(header)}")
    ref_t = cols["time"] * TIME_SCALE.get(found.units.get("time") or "s", 1.0)
    keep = np.isfinite(ref_t) & np.all(np.isfinite(up), axis=1)
    if not keep.any():
        raise RecordingError(f"{path}: no row of the reference holds a time and a valid "
                             "attitude")
    lo, hi = float(ref_t[keep].min()), float(ref_t[keep].max())
    if hi < t[0] or lo > t[-1]:
        raise RecordingError(f"{path}: the reference's time ({lo:.6g} to {hi:.6g} s) does not "
                             f"overlap the recording's ({t[0]:.6g} to {t[-1]:.6g} s): both "
                             "must count from the same instant")
    out = np.column_stack([np.interp(t, ref_t[keep], up[keep, i], left=np.nan, right=np.nan)
                           for i in range(3)])
    q_at = None
    if quat is not None:  # componentwise between neighbours of one sign, renormalised
        q = quat[keep].copy()
        flips = np.cumsum(np.concatenate([[0], np.sum(q[1:] * q[:-1], axis=1) < 0.0])) % 2
        q[flips == 1] *= -1.0
        q_at = np.column_stack([np.interp(t, ref_t[keep], q[:, i], left=np.nan,
                                          right=np.nan) for i in range(4)])
        q_at /= np.linalg.norm(q_at, axis=1, keepdims=True)
    return out / np.linalg.norm(out, axis=1, keepdims=True), q_at


WORLD_UP_SPREAD_DEG = 10.0
"""The most the accelerometer at rest may scatter around the reference's vertical (median
angle) for that vertical to be taken."""
WORLD_UP_TILT_DEG = 5.0
"""A reference vertical further than this from the world frame's z axis is taken as the
reference's up (a y-up motion-capture frame), and said so."""


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each v [N, 3] rotated by the unit quaternion q [N, 4] (w first): R(q) v."""
    w, u = q[:, :1], q[:, 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def align_reference_world(rec: Any, path: Path) -> str:
    """For a quaternion reference (rec.ref_quat, sensor to world): the world's vertical as the
    accelerometer at rest sees it, heading-free (the mean over quiet samples of the measured
    direction turned into the world frame), and the reference's up in the sensor frame
    recomputed about it where the world frame is not z-up. Returns what was found, for the
    printout; RecordingError where no vertical explains the accelerometer."""
    from .fit.recording import RecordingError

    q = getattr(rec, "ref_quat", None)
    if q is None:
        return ""
    norm = np.linalg.norm(rec.acc, axis=1)
    quiet = np.isfinite(norm) & np.all(np.isfinite(q), axis=1)
    quiet &= np.abs(norm / np.nanmedian(norm) - 1.0) < 0.05
    if quiet.sum() < 10:
        return ""
    seen = _rotate(q[quiet], rec.acc[quiet] / norm[quiet, None])
    up = seen.mean(axis=0)
    up /= np.linalg.norm(up)
    spread = float(np.degrees(np.median(np.arccos(np.clip(seen @ up, -1.0, 1.0)))))
    if spread > WORLD_UP_SPREAD_DEG:
        raise RecordingError(
            f"{path}: no vertical of the reference's world frame explains the accelerometer at "
            f"rest (it scatters {spread:.3g} deg around the best one): is the quaternion the "
            "sensor-to-world rotation, w first (q_w, q_x, q_y, q_z), and of the same sensor?")
    tilt = float(np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0))))
    if tilt <= WORLD_UP_TILT_DEG:
        return f"reference: its world frame is z-up (within {tilt:.2g} deg)"
    axis = int(np.argmax(np.abs(up)))
    off = float(np.degrees(np.arccos(min(1.0, abs(float(up[axis]))))))
    if off <= WORLD_UP_TILT_DEG:  # frames are laid along their axes: that axis, exactly
        up = np.eye(3)[axis] * np.sign(up[axis])
        found = f"{'+' if up[axis] > 0 else '-'}{'xyz'[axis]} (within {off:.2g} deg)"
    else:
        found = f"({up[0]:+.3f}, {up[1]:+.3f}, {up[2]:+.3f}), {tilt:.3g} deg from z"
    conj = q * np.array([1.0, -1.0, -1.0, -1.0])
    rec.up_ref = _rotate(conj, np.broadcast_to(up, (len(q), 3)).copy())
    return f"reference: its world frame's up is {found}: scored about that vertical"


# ----- running ---------------------------------------------------------------------------------

def estimator_params(args: argparse.Namespace, entry: dict[str, Any]) -> dict[str, Any]:
    """A preset entry with the command's sensor options and --param on top."""
    from .fit.recording import RecordingError

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
    params.update(parse_params(args.param))
    return params


def cmd_estimate(args: argparse.Namespace) -> int:
    from fusion_core.presets import load_preset
    from fusion_core.registry import KEYS, create

    from .broad.metric import gravity_from_roll_pitch, inclination_rmse_deg
    from .fit.recording import RecordingError
    from .options import choose

    keys = choose(args.estimator, list(KEYS), "estimator")
    rec, t = recording_from_args(args.recording, args)
    if args.reference is not None:
        rec.up_ref, rec.ref_quat = reference_by_time(args.reference, t)
        rec.counts = np.all(np.isfinite(rec.up_ref), axis=1)
    found = align_reference_world(rec, args.reference or args.recording)
    if found:
        print(found)
    if rec.up_ref is not None:  # scored where every estimator and VQF took the sample
        rec.counts = rec.counted & rec.valid
        scored = int(rec.counts.sum())
        if scored == 0:
            raise RecordingError(f"{args.recording}: no sample has both a valid reference and "
                                 "numbers in every column: nothing to score")
        print(f"reference: {scored} of {len(rec.counts)} samples scored (the others lack a "
              "valid reference or a number)")
    preset = with_calibration(load_preset(args.preset), args.calibration)
    estimators = {k: create(k, estimator_params(args, preset[k])) for k in keys}
    args.out.mkdir(parents=True, exist_ok=True)
    rows, traces = [], {}
    for key, est in estimators.items():
        out = est.run(rec.acc, rec.gyro, rec.dt)
        traces[key] = out
        path = args.out / f"{rec.name}_{key}.csv"
        _write_csv(path, t, out)
        rmse = None
        if rec.up_ref is not None:
            rmse = inclination_rmse_deg(gravity_from_roll_pitch(out["roll"], out["pitch"]),
                                        rec.up_ref, rec.counted)
        rows.append((key, int(out["rejected"].sum()), rmse, path))
    vqf_rmse, vqf_note = None, ""
    if rec.up_ref is not None:
        vqf_rmse, vqf_note = _vqf(rec, estimator_params(args, preset[keys[0]]))
    print(f"{'estimator':<10} {'rejected':>8} {'incl. RMSE [deg]':>17}  output")
    for key, rejected, rmse, path in rows:
        shown = f"{rmse:17.4f}" if rmse is not None else f"{'-':>17}"
        print(f"{key:<10} {rejected:>8} {shown}  {path}")
    if rec.up_ref is not None:
        shown = f"{vqf_rmse:17.4f}" if vqf_rmse is not None else f"{'-':>17}"
        print(f"{'vqf':<10} {'-':>8} {shown}  {vqf_note}")
    if not args.no_plots:
        print(_plot(args.out / f"{rec.name}.png", t, traces, rec))
    return 0


def _write_csv(path: Path, t: np.ndarray, out: dict[str, np.ndarray]) -> None:
    names = ["time", "roll", "pitch", "bias_x", "bias_y", "bias_z"]
    cols = [t, out["roll"], out["pitch"], *out["bias"].T]
    if "pos" in out:
        names += [f"{q}_{a}" for q in ("pos", "vel") for a in "xyz"]
        cols += [*out["pos"].T, *out["vel"].T]
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=",".join(names), comments="",
               fmt="%.17g")


def conditioned(acc: np.ndarray, gyro: np.ndarray, params: dict[str, Any]
                ) -> tuple[np.ndarray, np.ndarray]:
    """The samples as every estimator's input stage makes them of the parameters: calibrated
    (M (raw - b)), then turned by the mounting into the filter's frame."""
    from fusion_core.base import mounting_matrix
    from fusion_core.calibration import Calibration

    acc, gyro = Calibration.from_params(params).apply(acc, gyro)
    r = np.asarray(mounting_matrix(float(params.get("mount_roll", 0.0)),
                                   float(params.get("mount_pitch", 0.0)),
                                   float(params.get("mount_yaw", 0.0)))).reshape(3, 3)
    return acc @ r.T, gyro @ r.T


def _vqf(rec: Any, params: dict[str, Any]) -> tuple[float | None, str]:
    """VQF's inclination RMSE on the samples the estimators took (their calibration and
    mounting applied, the samples they reject left out), or why there is none."""
    from .broad.metric import inclination_rmse_deg
    from .peers import PeerUnavailable, run_vqf

    valid = rec.valid
    acc, gyro = conditioned(rec.acc[valid], rec.gyro[valid], params)
    try:
        up_valid = run_vqf(acc, gyro, rec.rate)
    except PeerUnavailable as err:
        return None, f"(VQF not run: {str(err).split('; ')[-1]})"
    up = np.full((len(valid), 3), np.nan)
    up[valid] = up_valid  # VQF takes no sample the estimators rejected
    return inclination_rmse_deg(up, rec.up_ref, rec.counted), "VQF on the same samples"


def _plot(path: Path, t: np.ndarray, traces: dict[str, dict[str, np.ndarray]], rec: Any) -> str:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return "(no plot: matplotlib is not installed)"
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(9, 5.5))
    for key, out in traces.items():
        axes[0].plot(t, np.degrees(out["roll"]), lw=0.9, label=key)
        axes[1].plot(t, np.degrees(out["pitch"]), lw=0.9, label=key)
    if rec.up_ref is not None:
        up = rec.up_ref
        ref_roll = np.degrees(np.arctan2(up[:, 1], up[:, 2]))
        ref_pitch = np.degrees(np.arctan2(-up[:, 0], np.hypot(up[:, 1], up[:, 2])))
        axes[0].plot(t, ref_roll, "k--", lw=0.8, label="reference")
        axes[1].plot(t, ref_pitch, "k--", lw=0.8, label="reference")
    axes[0].set_ylabel("roll [deg]")
    axes[1].set_ylabel("pitch [deg]")
    axes[1].set_xlabel("time [s]")
    axes[0].legend(fontsize=8, ncol=3)
    axes[0].set_title(rec.name)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return f"plot: {path}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: imu-fusion estimate RECORDING (or python -m testbenches estimate)")
