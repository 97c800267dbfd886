"""`imu-fusion estimate RECORDING`: the estimators on a user's own recording.

A recording is a CSV file with a header row, or an HDF5 file (a BROAD trial, or datasets `acc`
and `gyro` [N, 3] with `time` [N] or a `rate` attribute). Columns are found by name: the
accelerometer as acc_x/acc_y/acc_z (or ax/ay/az, accX/accY/accZ, acc_x_g, ...), the gyro as
gyro_x/... (or gx/gy/gz, gyrX/..., wx/wy/wz), the time as time/t/timestamp (or --time-column), the
sampling as dt or --rate. Units are given (--acc-unit g|m/s2, --gyro-unit rad/s|deg/s) or
detected: a resting accelerometer reads 1 in g and 9.81 in m/s^2, and a gyro that turns faster
than 35 rad/s (2000 deg/s, the MPU-6050's widest range) is in deg/s. A reference, roll and pitch
[rad] or a quaternion q_w, q_x, q_y, q_z (sensor to a z-up frame), in the recording or in a
file of its own (--reference, matched by time), gives the inclination RMSE, beside VQF's on the
same samples where the `vqf` package is installed.

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

from .options import add_calibration, add_preset, parse_params, with_calibration

ALIASES: dict[str, tuple[str, ...]] = {
    "acc_x": ("acc_x", "ax", "accx", "acc_x_g", "acc_x_ms2", "accelerometer_x", "a_x"),
    "acc_y": ("acc_y", "ay", "accy", "acc_y_g", "acc_y_ms2", "accelerometer_y", "a_y"),
    "acc_z": ("acc_z", "az", "accz", "acc_z_g", "acc_z_ms2", "accelerometer_z", "a_z"),
    "gyro_x": ("gyro_x", "gx", "gyrx", "gyr_x", "gyro_x_dps", "gyroscope_x", "wx", "g_x"),
    "gyro_y": ("gyro_y", "gy", "gyry", "gyr_y", "gyro_y_dps", "gyroscope_y", "wy", "g_y"),
    "gyro_z": ("gyro_z", "gz", "gyrz", "gyr_z", "gyro_z_dps", "gyroscope_z", "wz", "g_z"),
    "time": ("time", "t", "timestamp", "time_s"),
}
"""Column names a recording may use (case and spaces ignored), per quantity."""
G_STANDARD = 9.80665
DEG = np.pi / 180.0
MAX_RAD_S = 35.0
"""A gyro reading above this [rad/s] (2000 deg/s) is taken as deg/s where the unit is detected."""
ACC_UNITS = ("auto", "m/s2", "g")
GYRO_UNITS = ("auto", "rad/s", "deg/s")


def add_estimate_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("estimate", help="run estimators on your own recording (CSV or HDF5)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.set_defaults(func=cmd_estimate)
    p.add_argument("recording", type=Path, help="CSV or HDF5 recording")
    p.add_argument("--estimator", default="all", help="all or a comma list of the estimators")
    add_preset(p)
    add_calibration(p)
    p.add_argument("--rate", type=float, default=None,
                   help="sample rate [Hz] where the file has no time or dt")
    p.add_argument("--time-column", default=None, help="the time column's name [s]")
    p.add_argument("--acc-unit", choices=ACC_UNITS, default="auto",
                   help="the accelerometer's unit (auto: from its norm at rest)")
    p.add_argument("--gyro-unit", choices=GYRO_UNITS, default="auto",
                   help="the gyro's unit (auto: deg/s where it exceeds 35 rad/s)")
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


# ----- reading ---------------------------------------------------------------------------------

def _norm_name(name: str) -> str:
    return name.strip().lower().replace(" ", "_").replace("-", "_")


def _find(header: list[str], quantity: str, given: str | None = None) -> int | None:
    names = [_norm_name(h) for h in header]
    wanted = (_norm_name(given),) if given else ALIASES[quantity]
    for alias in wanted:
        if alias in names:
            return names.index(alias)
    return None


def read_csv(path: Path, time_column: str | None) -> tuple[dict[str, np.ndarray], list[str]]:
    """The columns of a CSV file by the header's names (numbers; RecordingError otherwise)."""
    from .fit.recording import RecordingError, csv_header_rows

    header, rows = csv_header_rows(path)
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise RecordingError(f"{path}: a header and no samples")
    if any(len(r) != len(header) for r in rows):
        bad = next(i for i, r in enumerate(rows, 2) if len(r) != len(header))
        raise RecordingError(f"{path}: line {bad} has another number of values than the header "
                             f"({len(header)})")
    try:
        data = np.array(rows, dtype=float)
    except ValueError as err:
        raise RecordingError(f"{path}: a value is not a number ({err})") from None
    cols: dict[str, np.ndarray] = {}
    for quantity in ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"):
        i = _find(header, quantity)
        if i is not None:
            cols[quantity] = data[:, i]
    i = _find(header, "time", time_column)
    if time_column and i is None:
        raise RecordingError(f"{path}: no column {time_column!r}: the header has "
                             f"{', '.join(header)}")
    if i is not None:
        cols["time"] = data[:, i]
    for name in ("dt", "roll", "pitch", "q_w", "q_x", "q_y", "q_z"):
        j = _find(header, "time", name)
        if j is not None:
            cols[name] = data[:, j]
    return cols, header


def read_hdf5(path: Path) -> dict[str, np.ndarray]:
    """acc, gyro [N, 3] and time [N] (or rate) from an HDF5 file that is not a BROAD trial."""
    import h5py

    from .fit.recording import RecordingError

    with h5py.File(path, "r") as f:
        if "acc" not in f or "gyro" not in f:
            raise RecordingError(f"{path}: an HDF5 recording holds datasets acc and gyro [N, 3] "
                                 f"(and time [N] or a rate attribute); it has "
                                 f"{', '.join(f.keys()) or 'none'}")
        acc, gyro = np.asarray(f["acc"], float), np.asarray(f["gyro"], float)
        cols = {f"acc_{a}": acc[:, i] for i, a in enumerate("xyz")}
        cols.update({f"gyro_{a}": gyro[:, i] for i, a in enumerate("xyz")})
        if "time" in f:
            cols["time"] = np.asarray(f["time"], float)
        elif "rate" in f.attrs:
            cols["time"] = np.arange(len(acc)) / float(f.attrs["rate"])
    return cols


def load_recording(path: Path, *, rate: float | None = None, time_column: str | None = None,
                   acc_unit: str = "auto", gyro_unit: str = "auto") -> Any:
    """The recording in SI units (testbenches.fit.recording.Recording) and the time of each
    sample [s]; RecordingError saying what is wrong."""
    from .broad.data import NotABroadTrial, load_trial
    from .fit.recording import Recording, RecordingError, load

    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    if path.suffix.lower() in (".hdf5", ".h5", ".mat"):
        try:
            load_trial(path)
        except NotABroadTrial:
            if path.suffix.lower() == ".mat":
                raise RecordingError(f"{path}: a .mat file must be a BROAD trial") from None
            cols = read_hdf5(path)
        else:  # a BROAD trial: its own rate, sampling, delay and reference
            rec = load(path)
            return rec, np.cumsum(rec.dt) - rec.dt[0]
    else:
        cols, header = read_csv(path, time_column)
        missing = [q for q in ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")
                   if q not in cols]
        if missing:
            raise RecordingError(
                f"{path}: no column for {', '.join(missing)}: the header has "
                f"{', '.join(header)}; name them acc_x, acc_y, acc_z, gyro_x, gyro_y, gyro_z "
                "(or ax, ay, az, gx, gy, gz)")
    acc = np.column_stack([cols[f"acc_{a}"] for a in "xyz"])
    gyro = np.column_stack([cols[f"gyro_{a}"] for a in "xyz"])
    n = len(acc)
    if n < 2:
        raise RecordingError(f"{path}: {n} sample(s); a recording needs many")
    if not (np.all(np.isfinite(acc)) and np.all(np.isfinite(gyro))):
        bad = int(np.argmax(~(np.all(np.isfinite(acc), 1) & np.all(np.isfinite(gyro), 1))))
        raise RecordingError(f"{path}: sample {bad} is not a number (NaN or infinite)")
    if "time" in cols:
        t = cols["time"]
        steps = np.diff(t)
        if not np.all(steps > 0.0):
            bad = int(np.argmax(~(steps > 0.0))) + 1
            raise RecordingError(f"{path}: the time does not increase at sample {bad} "
                                 f"({t[bad - 1]!r} then {t[bad]!r} s)")
        dt = np.concatenate([[np.median(steps)], steps])
    elif "dt" in cols:
        dt = cols["dt"].copy()
        dt[0] = float(np.median(dt[1:]))
        t = np.cumsum(dt) - dt[0]
    elif rate:
        dt = np.full(n, 1.0 / rate)
        t = np.arange(n) / rate
    else:
        raise RecordingError(f"{path}: no time or dt column: give the sample rate (--rate HZ) "
                             "or the time column's name (--time-column NAME)")
    acc = acc * _acc_scale(path, acc, acc_unit)
    gyro = gyro * _gyro_scale(path, gyro, gyro_unit)
    up = None
    if all(c in cols for c in ("q_w", "q_x", "q_y", "q_z")):
        from .broad.metric import gravity_from_quat

        up = gravity_from_quat(np.column_stack([cols[c] for c in ("q_w", "q_x", "q_y", "q_z")]))
    elif "roll" in cols and "pitch" in cols:
        from .broad.metric import gravity_from_roll_pitch

        up = gravity_from_roll_pitch(cols["roll"], cols["pitch"])
    counts = None if up is None else np.all(np.isfinite(up), axis=1)
    rec = Recording(path.stem, acc, gyro, dt, 1.0 / float(np.median(dt)), "point", up, counts)
    return rec, t


def _acc_scale(path: Path, acc: np.ndarray, unit: str) -> float:
    """The factor to m/s^2: given, or from the median norm (1 g or 9.81 m/s^2 at rest, and
    near it on average in motion)."""
    from .fit.recording import RecordingError

    norm = float(np.median(np.linalg.norm(acc, axis=1)))
    scale = {"m/s2": 1.0, "g": G_STANDARD}.get(unit)
    if scale is None:
        if 0.5 < norm < 2.0:
            scale = G_STANDARD
        elif 5.0 < norm < 20.0:
            scale = 1.0
        else:
            raise RecordingError(
                f"{path}: the accelerometer's median norm is {norm:.4g}, neither about 1 (g) "
                "nor about 9.81 (m/s2): give --acc-unit, or check the columns")
    si = norm * scale
    if not 4.0 < si < 40.0:
        raise RecordingError(f"{path}: the accelerometer's median norm is {si:.4g} m/s2 in the "
                             f"unit {unit}, which cannot be right (gravity is 9.81)")
    return scale


def _gyro_scale(path: Path, gyro: np.ndarray, unit: str) -> float:
    """The factor to rad/s: given, or deg/s where any reading exceeds MAX_RAD_S."""
    if unit == "deg/s":
        return DEG
    if unit == "rad/s":
        return 1.0
    return DEG if float(np.max(np.abs(gyro))) > MAX_RAD_S else 1.0


def reference_by_time(path: Path, t: np.ndarray) -> np.ndarray:
    """The up direction [N, 3] of a reference file (time with roll, pitch or q_w..q_z) at the
    recording's times (linear between the reference's samples; NaN outside them)."""
    from .broad.metric import gravity_from_quat, gravity_from_roll_pitch
    from .fit.recording import RecordingError

    cols, header = read_csv(path, None)
    if "time" not in cols:
        raise RecordingError(f"{path}: a reference needs a time column [s]; it has "
                             f"{', '.join(header)}")
    if all(c in cols for c in ("q_w", "q_x", "q_y", "q_z")):
        up = gravity_from_quat(np.column_stack([cols[c] for c in ("q_w", "q_x", "q_y", "q_z")]))
    elif "roll" in cols and "pitch" in cols:
        up = gravity_from_roll_pitch(cols["roll"], cols["pitch"])
    else:
        raise RecordingError(f"{path}: a reference holds roll and pitch [rad] or q_w, q_x, q_y, "
                             f"q_z; it has {', '.join(header)}")
    out = np.column_stack([np.interp(t, cols["time"], up[:, i], left=np.nan, right=np.nan)
                           for i in range(3)])
    return out / np.linalg.norm(out, axis=1, keepdims=True)


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
    from .options import choose

    keys = choose(args.estimator, list(KEYS), "estimator")
    rec, t = load_recording(args.recording, rate=args.rate, time_column=args.time_column,
                            acc_unit=args.acc_unit, gyro_unit=args.gyro_unit)
    if args.reference is not None:
        rec.up_ref = reference_by_time(args.reference, t)
        rec.counts = np.all(np.isfinite(rec.up_ref), axis=1)
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
        vqf_rmse, vqf_note = _vqf(rec)
    print(f"{rec.name}: {len(rec.dt)} samples, {rec.duration:.1f} s at {rec.rate:.4g} Hz")
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


def _vqf(rec: Any) -> tuple[float | None, str]:
    """VQF's inclination RMSE on the same samples, or why there is none."""
    from .broad.metric import inclination_rmse_deg
    from .peers import PeerUnavailable, run_vqf

    try:
        up = run_vqf(rec.acc, rec.gyro, rec.rate)
    except PeerUnavailable as err:
        return None, f"(VQF not run: {str(err).split('; ')[-1]})"
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
