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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .options import (
    add_calibration,
    add_preset,
    add_recording_options,
    parse_params,
    with_calibration,
)
from .reader import TIME_SCALE

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


# ----- reading ---------------------------------------------------------------------------------

def _norm_name(name: str) -> str:
    return name.strip().lower().replace(" ", "_").replace("-", "_")


def _find(names: list[str], quantity: str, given: str | None = None) -> int | None:
    """The column of a quantity: the one given (by its name as written, with or without its
    unit), else the first of its aliases."""
    normed = [_norm_name(n) for n in names]
    wanted = (_norm_name(given),) if given else ALIASES[quantity]
    for alias in wanted:
        if alias in normed:
            return normed.index(alias)
    return None


def parse_columns(specs: list[str]) -> dict[str, str]:
    """--column QUANTITY=NAME options as {quantity: column name}; RecordingError for a quantity
    that is not one of ALIASES' or a spec without '='."""
    from .fit.recording import RecordingError

    out = {}
    for spec in specs:
        quantity, sep, name = spec.partition("=")
        quantity = quantity.strip()
        if not sep or quantity not in (*ALIASES, *EXTRA_COLUMNS):
            raise RecordingError(f"--column {spec!r}: expected QUANTITY=NAME with QUANTITY one "
                                 f"of {', '.join((*ALIASES, *EXTRA_COLUMNS))}")
        out[quantity] = name.strip()
    return out


EXTRA_COLUMNS = ("dt", "roll", "pitch", "q_w", "q_x", "q_y", "q_z")
"""Columns found by their own name only: the sampling and a reference."""


@dataclass
class Columns:
    """What read_csv found: each quantity's values, the header names it came from and the unit
    the header states for it (None: none stated)."""

    values: dict[str, np.ndarray]
    source: dict[str, str]
    units: dict[str, str | None]
    header: list[str]
    lines: np.ndarray


def read_csv(path: Path, time_column: str | None,
             columns: dict[str, str] | None = None) -> Columns:
    """The quantities of a delimited text file (testbenches.reader), found by the header's
    names or the columns given ({quantity: name}); RecordingError otherwise."""
    from .fit.recording import RecordingError
    from .reader import TableError, read_table

    try:
        table = read_table(path)
    except TableError as err:
        raise RecordingError(str(err)) from None
    given = dict(columns or {})
    if time_column:
        given.setdefault("time", time_column)
    found = Columns({}, {}, {}, table.header, table.lines)
    for quantity in (*ALIASES, *EXTRA_COLUMNS):
        name = given.get(quantity)
        i = None
        if name is not None:
            i = _find(table.header, quantity, name)
            if i is None:
                i = _find(table.names, quantity, name)
            if i is None:
                raise RecordingError(f"{path}: no column {name!r} for {quantity}: the header "
                                     f"has {', '.join(table.header)}")
        elif quantity in ALIASES:
            i = _find(table.names, quantity)
        else:
            i = _find(table.names, "time", quantity)
        if i is not None:
            found.values[quantity] = table.column(i)
            found.source[quantity] = table.header[i]
            found.units[quantity] = table.units[i]
    return found


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


def _stated(units: dict[str, str | None], axes: tuple[str, ...], path: Path) -> str | None:
    """The one unit the header states for these columns (None: none); RecordingError where
    they state different ones."""
    from .fit.recording import RecordingError

    stated = {units.get(a) for a in axes} - {None}
    if len(stated) > 1:
        raise RecordingError(f"{path}: the header states the units {', '.join(sorted(stated))} "
                             f"for {', '.join(axes)}: one unit for the three axes serves")
    return stated.pop() if stated else None


def load_recording(path: Path, *, rate: float | None = None, time_column: str | None = None,
                   acc_unit: str = "auto", gyro_unit: str = "auto",
                   columns: dict[str, str] | None = None) -> Any:
    """The recording in SI units (testbenches.fit.recording.Recording; its `described` says
    which columns, units and rate were taken and why) and the time of each sample [s];
    RecordingError saying what is wrong."""
    from .broad.data import NotABroadTrial, load_trial
    from .fit.recording import Recording, RecordingError, load

    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    lines = None
    units: dict[str, str | None] = {}
    source: dict[str, str] = {}
    if path.suffix.lower() in (".hdf5", ".h5", ".mat"):
        try:
            load_trial(path)
        except NotABroadTrial:
            if path.suffix.lower() == ".mat":
                raise RecordingError(f"{path}: a .mat file must be a BROAD trial") from None
            cols = read_hdf5(path)
        else:  # a BROAD trial: its own rate, sampling, delay and reference
            rec = load(path)
            rec.described = (f"a BROAD trial: {len(rec.dt)} samples at {rec.rate:.4g} Hz, "
                             "m/s2 and rad/s")
            return rec, np.cumsum(rec.dt) - rec.dt[0]
    else:
        found = read_csv(path, time_column, columns)
        cols, units, source, lines = found.values, found.units, found.source, found.lines
        missing = [q for q in IMU_AXES if q not in cols]
        if missing:
            raise RecordingError(
                f"{path}: no column for {', '.join(missing)}: the header has "
                f"{', '.join(found.header)}; name them acc_x, acc_y, acc_z, gyro_x, gyro_y, "
                "gyro_z (or ax, ay, az, gx, gy, gz), or map them with --column QUANTITY=NAME")
    acc = np.column_stack([cols[f"acc_{a}"] for a in "xyz"])
    gyro = np.column_stack([cols[f"gyro_{a}"] for a in "xyz"])
    n = len(acc)
    if n < 2:
        raise RecordingError(f"{path}: {n} sample(s); a recording needs many")
    line_of = (lambda k: f"line {int(lines[k])}") if lines is not None else (
        lambda k: f"sample {k}")
    if "time" in cols:
        t = cols["time"] * TIME_SCALE.get(units.get("time") or "s", 1.0)
        dt, t = _steps_from_time(t, path, line_of)
    elif "dt" in cols:
        dt = cols["dt"] * TIME_SCALE.get(units.get("dt") or "s", 1.0)
        dt = dt.copy()
        dt[0] = float(np.nanmedian(dt[1:]))
        t = np.cumsum(np.where(np.isfinite(dt), dt, 0.0)) - dt[0]
    elif rate:
        dt = np.full(n, 1.0 / rate)
        t = np.arange(n) / rate
    else:
        raise RecordingError(f"{path}: no time or dt column: give the sample rate (--rate HZ), "
                             "the time column's name (--time-column NAME) or map it with "
                             "--column time=NAME")
    finite = np.all(np.isfinite(acc), 1) & np.all(np.isfinite(gyro), 1) & np.isfinite(dt)
    if not finite.any():
        raise RecordingError(f"{path}: no sample holds numbers in every column")
    acc_scale, acc_how = _acc_scale(path, acc[finite], acc_unit,
                                    _stated(units, tuple(f"acc_{a}" for a in "xyz"), path))
    gyro_scale, gyro_how = _gyro_scale(path, acc, gyro, dt, gyro_unit,
                                       _stated(units, tuple(f"gyro_{a}" for a in "xyz"), path))
    acc = acc * acc_scale
    gyro = gyro * gyro_scale
    up, ref_quat = reference_up(cols, path)
    counts = None if up is None else np.all(np.isfinite(up), axis=1)
    period = float(np.nanmedian(dt))
    rec = Recording(path.stem, acc, gyro, dt, 1.0 / period, "point", up, counts)
    rec.ref_quat = ref_quat
    where = ", ".join(f"{q}={source[q]!r}" for q in (*IMU_AXES, "time", "dt") if q in source)
    missing_rows = int((~finite).sum())
    rec.described = (
        f"{n} samples, {float(np.nansum(dt[1:])):.4g} s at {1.0 / period:.4g} Hz; acc in "
        f"{acc_how}; gyro in {gyro_how}"
        + (f"; columns {where}" if where else "")
        + (f"; {missing_rows} sample(s) without a number in every column, which the "
           "estimators reject and count" if missing_rows else ""))
    return rec, t


IMU_AXES = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")


def recording_from_args(path: Path, args: argparse.Namespace) -> Any:
    """load_recording with the options add_recording_options defines, the choices printed."""
    rec, t = load_recording(path, rate=args.rate, time_column=args.time_column,
                            acc_unit=args.acc_unit, gyro_unit=args.gyro_unit,
                            columns=parse_columns(args.column))
    print(f"{path}: {rec.described}")
    return rec, t


def _steps_from_time(t: np.ndarray, path: Path, line_of: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each sample's dt from a time column: the time since the last sample with a time (a
    sample without one gets dt NaN, which the estimators reject); RecordingError where the
    time does not increase."""
    from .fit.recording import RecordingError

    valid = np.flatnonzero(np.isfinite(t))
    if len(valid) < 2:
        raise RecordingError(f"{path}: fewer than two samples with a time")
    steps = np.diff(t[valid])
    if not np.all(steps > 0.0):
        i = int(np.argmax(~(steps > 0.0)))
        a, b = valid[i], valid[i + 1]
        raise RecordingError(f"{path}, {line_of(b)}: the time {float(t[b]):.6g} s does not "
                             f"increase from {float(t[a]):.6g} s on {line_of(a)}")
    dt = np.full(len(t), np.nan)
    dt[valid[1:]] = steps
    dt[valid[0]] = float(np.median(steps))
    filled = np.interp(np.arange(len(t)), valid, t[valid])  # the time of a sample without one
    return dt, np.where(np.isfinite(t), t, filled)


def _acc_scale(path: Path, acc: np.ndarray, unit: str, stated: str | None
               ) -> tuple[float, str]:
    """The factor to m/s^2 and how it was chosen: given, stated by the header, or from the
    median norm (1 g or 9.81 m/s^2 at rest, and near it on average in motion); refused where
    the norm in that unit cannot be gravity's."""
    from .fit.recording import RecordingError

    norm = float(np.median(np.linalg.norm(acc, axis=1)))
    chosen = unit if unit != "auto" else stated
    how = "given" if unit != "auto" else "from the header"
    if chosen is None:
        if 0.5 < norm < 2.0:
            chosen = "g"
        elif 5.0 < norm < 20.0:
            chosen = "m/s2"
        else:
            raise RecordingError(
                f"{path}: the accelerometer's median norm is {norm:.4g}, neither about 1 (g) "
                "nor about 9.81 (m/s2): give --acc-unit, or check the columns")
        how = f"from its median norm {norm:.4g}"
    scale = {"m/s2": 1.0, "g": G_STANDARD}.get(chosen)
    if scale is None:
        raise RecordingError(f"{path}: the accelerometer's unit {chosen!r} is not one of g, "
                             "m/s2")
    si = norm * scale
    if not 4.0 < si < 40.0:
        raise RecordingError(f"{path}: the accelerometer's median norm is {si:.4g} m/s2 in the "
                             f"unit {chosen} ({how}), which cannot be right (gravity is 9.81)")
    return scale, f"{chosen} ({how})"


def _gyro_scale(path: Path, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray, unit: str,
                stated: str | None) -> tuple[float, str]:
    """The factor to rad/s and how it was chosen: the unit in which the gyro's turn explains
    the accelerometer's turn of gravity (testbenches.gyro_unit). A unit given or stated by the
    header that the data contradict is refused with the evidence; where the data cannot tell
    and no unit is given or stated, the recording is refused."""
    from .fit.recording import RecordingError
    from .gyro_unit import UNITS, gyro_unit_evidence

    evidence = gyro_unit_evidence(acc, gyro, dt)
    chosen = unit if unit != "auto" else stated
    if chosen is not None:
        how = "given" if unit != "auto" else "from the header"
        if chosen not in UNITS:
            raise RecordingError(f"{path}: the gyro's unit {chosen!r} is not one of rad/s, "
                                 "deg/s")
        if evidence.unit is not None and evidence.unit != chosen:
            raise RecordingError(
                f"{path}: the gyro's unit {chosen} ({how}) contradicts the data: "
                f"{evidence.describe()}, so it reads in {evidence.unit}; give --gyro-unit "
                f"{evidence.unit}, or check the columns")
        return UNITS[chosen], f"{chosen} ({how}" + (
            ", and the data agree)" if evidence.unit else ")")
    if evidence.unit is None:
        raise RecordingError(
            f"{path}: the gyro's unit cannot be told from the data (the gyro turns gravity "
            "measurably in neither rad/s nor deg/s: too little motion): give --gyro-unit rad/s "
            "or deg/s")
    return UNITS[evidence.unit], f"{evidence.unit} (from the data: {evidence.describe()})"


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


QUAT_NORM_TOLERANCE = 0.1
"""A reference quaternion whose norm is further than this from 1 is no rotation: its row is
left out (and counted)."""


def reference_up(cols: dict[str, np.ndarray], path: Path
                 ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The up direction [N, 3] of the reference columns in the sensor frame, taking the
    reference's world frame as z-up, and for a quaternion reference the unit quaternions
    [N, 4] (rows of invalid ones NaN in both; None, None: no reference columns); RecordingError
    where nothing in them can be an attitude or roll and pitch are not in rad."""
    from .broad.metric import gravity_from_quat, gravity_from_roll_pitch
    from .fit.recording import RecordingError

    if all(c in cols for c in ("q_w", "q_x", "q_y", "q_z")):
        q = np.column_stack([cols[c] for c in ("q_w", "q_x", "q_y", "q_z")])
        norm = np.linalg.norm(q, axis=1)
        valid = np.isfinite(norm) & (np.abs(norm - 1.0) <= QUAT_NORM_TOLERANCE)
        if not valid.any():
            raise RecordingError(f"{path}: none of the reference's {len(q)} quaternions is a "
                                 f"rotation (norm within {QUAT_NORM_TOLERANCE} of 1; median "
                                 f"norm {float(np.nanmedian(norm)):.4g})")
        unit = np.full((len(q), 4), np.nan)
        unit[valid] = q[valid] / norm[valid, None]
        return gravity_from_quat(unit), unit
    if "roll" in cols and "pitch" in cols:
        roll, pitch = cols["roll"], cols["pitch"]
        if np.nanmax(np.abs(roll)) > np.pi + 1e-6 or np.nanmax(np.abs(pitch)) > np.pi / 2 + 1e-6:
            raise RecordingError(
                f"{path}: the reference's roll reaches {float(np.nanmax(np.abs(roll))):.4g} and "
                f"its pitch {float(np.nanmax(np.abs(pitch))):.4g}, beyond pi and pi/2: they "
                "are in degrees? a reference gives roll and pitch in rad")
        return gravity_from_roll_pitch(roll, pitch), None
    return None, None


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
        rec.counts = rec.counted & _valid(rec)
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

    valid = _valid(rec)
    acc, gyro = conditioned(rec.acc[valid], rec.gyro[valid], params)
    try:
        up_valid = run_vqf(acc, gyro, rec.rate)
    except PeerUnavailable as err:
        return None, f"(VQF not run: {str(err).split('; ')[-1]})"
    up = np.full((len(valid), 3), np.nan)
    up[valid] = up_valid  # VQF takes no sample the estimators rejected
    return inclination_rmse_deg(up, rec.up_ref, rec.counted), "VQF on the same samples"


def _valid(rec: Any) -> np.ndarray:
    """The samples with a number in every column and a dt (the others the estimators reject)."""
    return (np.all(np.isfinite(rec.acc), 1) & np.all(np.isfinite(rec.gyro), 1)
            & np.isfinite(rec.dt))


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
