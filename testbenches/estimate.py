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
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .fit.recording import (  # the one reader
    QUAT_COLUMNS,
    in_radians,
    read_columns,
    reference_up,
)
from .options import (
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
from .table import DATETIME, DURATION, TIME_OF_DAY, TIME_SCALE
from .table_out import FORMATS, TableWriter

OUTPUTS = {"roll": ("roll",), "pitch": ("pitch",), "bias": ("bias_x", "bias_y", "bias_z"),
           "pos": ("pos_x", "pos_y", "pos_z"), "vel": ("vel_x", "vel_y", "vel_z"),
           "rejected": ("rejected",)}
"""The output groups --outputs chooses from, and their columns."""
PLOT_POINTS = 1000
"""The plot keeps at most about twice this many samples per line (every kth, k doubling): about
two per pixel column of the figure (9 in at 110 dpi); more only cost drawing time."""
IN_FLIGHT = 2
"""Blocks read ahead of the slowest estimator at most: what bounds memory while each estimator
works through the blocks at its own pace (_Lanes)."""

G_STANDARD = 9.80665
DEG = np.pi / 180.0


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


class Reference:
    """A reference file (time with roll, pitch or q_w..q_z), read whole (a reference is a
    recording's companion, not its bulk), matched to a recording's times by `at`."""

    def __init__(self, path: Path, recording_time_unit: str = "s",
                 columns: dict[str, str] | None = None, topic: str | None = None,
                 offset: float = 0.0) -> None:
        from .fit.recording import RecordingError

        cols, found = read_columns(path, columns=columns, want="pose", topic=topic)
        if "time" not in cols:
            raise RecordingError(f"{path}: a reference needs a time column; it has "
                                 f"{', '.join(found.header)}")
        units = dict(found.units)
        self.angles: tuple[np.ndarray, np.ndarray] | None = None  # roll, pitch as read
        self.angle_unit, self.angle_how = "", ""
        if "roll" in cols and "pitch" in cols and not all(c in cols for c in QUAT_COLUMNS):
            stated = {units.get(c) for c in ("roll", "pitch")} - {None}
            if not stated:  # rad where the numbers can be radians, else deg: the data decide
                rad = in_radians(cols["roll"], cols["pitch"])
                self.angle_unit = "rad" if rad else "deg"
                self.angle_how = "" if rad else "beyond radians' range"
                units.update(roll=self.angle_unit, pitch=self.angle_unit)
            elif len(stated) == 1:
                self.angle_unit, self.angle_how = stated.pop(), "from the header"
        up, quat = reference_up(cols, path, units)
        if up is None:
            raise RecordingError(f"{path}: a reference holds roll and pitch or q_w, q_x, "
                                 f"q_y, q_z; it has {', '.join(found.header)}: map them with "
                                 "--reference-column QUANTITY=NAME")
        self.time_unit = reference_time_unit(path, cols["time"], found.units.get("time"),
                                             recording_time_unit)
        t = cols["time"] * TIME_SCALE[self.time_unit]
        keep = np.isfinite(t) & np.all(np.isfinite(up), axis=1)
        if not keep.any():
            raise RecordingError(f"{path}: no row of the reference holds a time and a valid "
                                 "attitude")
        _rising(path, t, keep, found.where)
        self.path, self.t, self.up = path, t[keep] + offset, up[keep]
        self.offset = offset
        if self.angle_unit:
            self.angles = (cols["roll"][keep], cols["pitch"][keep])
        self.quat = None
        if quat is not None:  # componentwise between neighbours of one sign, renormalised
            q = quat[keep].copy()
            flips = np.cumsum(np.concatenate([[0], np.sum(q[1:] * q[:-1], axis=1) < 0.0])) % 2
            q[flips == 1] *= -1.0
            self.quat = q

    def angle_unit_from(self, acc: np.ndarray, t: np.ndarray) -> str:
        """For a roll and pitch reference: its unit as the accelerometer at rest sees it on a
        recording's first block (acc as the estimators take it, its samples' times t): the
        other unit where the one taken misses the measured up direction by more than
        ANGLE_UNIT_MISS_DEG (median over the quiet samples) and the other by at most
        WORLD_UP_SPREAD_DEG and a third of that, and the other meets the law that holds in
        any motion (reference_axes: the specific force along it averages g): a pendulum's
        accelerometer, never at rest, points near the sensor's z axis where its norm is near
        g, as a swing in radians read as degrees does. A unit the header does not
        state is taken so (self.up follows), and said; one it states that the data contradict
        is refused with the evidence. "" where there is nothing to say."""
        from .broad.metric import gravity_from_roll_pitch, inclination_error
        from .fit.recording import RecordingError
        from .reference_axes import VERTICAL_TOLERANCE, vertical_share

        if self.angles is None:
            return ""
        within = (t >= self.t[0]) & (t <= self.t[-1])
        quiet = _quiet(acc) & within
        if quiet.sum() < 10:
            return ""
        roll, pitch = (np.interp(t[within], self.t, a) for a in self.angles)
        miss, share = {}, {}
        for unit, scale in (("rad", 1.0), ("deg", np.pi / 180.0)):
            up = gravity_from_roll_pitch(roll * scale, pitch * scale)
            miss[unit] = float(np.degrees(np.median(inclination_error(up[quiet[within]],
                                                                      acc[quiet]))))
            share[unit] = vertical_share(acc[within], up)
        other = "deg" if self.angle_unit == "rad" else "rad"
        if not (miss[self.angle_unit] > ANGLE_UNIT_MISS_DEG
                and miss[other] <= WORLD_UP_SPREAD_DEG
                and miss[other] <= miss[self.angle_unit] / 3.0
                and abs(share[other] - 1.0) <= VERTICAL_TOLERANCE):
            return (f"reference: roll and pitch in {self.angle_unit} ({self.angle_how})"
                    if self.angle_how else "")
        evidence = (f"the accelerometer at rest misses their up direction by "
                    f"{miss[self.angle_unit]:.3g} deg in {self.angle_unit} and by "
                    f"{miss[other]:.3g} deg in {other} (median)")
        if self.angle_how == "from the header":
            raise RecordingError(f"{self.path}: the header states roll and pitch in "
                                 f"{self.angle_unit}, but {evidence}: correct the header")
        scale = np.pi / 180.0 if other == "deg" else 1.0
        self.angle_unit = other
        self.up = gravity_from_roll_pitch(self.angles[0] * scale, self.angles[1] * scale)
        return f"reference: roll and pitch in {other} (from the data: {evidence})"

    def lag_note(self, rec: Any, t: np.ndarray) -> str:
        """Where the reference's clock runs apart from the recording's (a first block's samples
        rec at times t): the offset at which the reference's turn rate agrees best with the
        gyro's (a quaternion's whole turn with the gyro's norm; roll and pitch's tilt with the
        gyro's rate across the measured up direction), by their correlation within
        LAG_SEARCH_S (a third of the block), said where it is two samples or more and agrees
        clearly better than the clocks as read (LAG_CORRELATION, LAG_GAIN); "" otherwise (or
        for a block shorter than LAG_SHORTEST_S)."""
        from .broad.metric import inclination_error
        from .gyro_unit import moving_average

        period = float(np.nanmedian(np.diff(t))) if len(t) > 1 else 0.0
        span = len(t) * period
        if not period > 0.0 or span < LAG_SHORTEST_S:
            return ""
        up, quat = self.at(t)
        ref_rate = np.full(len(t), np.nan)  # central: the turn over the sample's two neighbours
        if quat is not None:  # the whole turn, the gyro's norm
            cos = np.abs(np.sum(quat[2:] * quat[:-2], axis=1))
            ref_rate[1:-1] = 2.0 * np.arccos(np.clip(cos, -1.0, 1.0))
            gyro_rate = np.linalg.norm(rec.gyro, axis=1)
        else:  # the tilt's turn, the gyro across the measured up direction
            ref_rate[1:-1] = inclination_error(up[2:], up[:-2])
            norm = np.linalg.norm(rec.acc, axis=1, keepdims=True)
            gyro_rate = np.linalg.norm(np.cross(rec.gyro, rec.acc / norm), axis=1)
        ref_rate[1:-1] /= t[2:] - t[:-2]
        k = max(1, round(0.1 / period))  # both averaged over 0.1 s, their non-numbers as 0
        a, b = (moving_average(np.where(np.isfinite(x), x, 0.0)[:, None], k)[:, 0]
                for x in (gyro_rate, ref_rate))
        lags, corr = _correlation(a, b, round(min(LAG_SEARCH_S, span / 3.0) / period))
        if corr is None:
            return ""
        best = int(np.argmax(corr))
        at_zero = float(corr[lags == 0][0])
        if (abs(lags[best]) < 2 or corr[best] < LAG_CORRELATION
                or (1.0 - at_zero) < LAG_GAIN * (1.0 - corr[best])):
            return ""
        lag = float(lags[best]) * period
        if 0 < best < len(corr) - 1:  # the peak between samples (a parabola through three)
            c0, c1, c2 = corr[best - 1], corr[best], corr[best + 1]
            if c0 - 2.0 * c1 + c2 < 0.0:
                lag += 0.5 * (c0 - c2) / (c0 - 2.0 * c1 + c2) * period
        return (f"reference: its clock runs {lag:+.3g} s from the recording's (their turn rates "
                f"agree best so: correlation {corr[best]:.2f}, {at_zero:.2f} as read): give "
                f"--reference-offset {self.offset - lag:.4g} to align them")

    @property
    def span(self) -> tuple[float, float]:
        return float(self.t.min()), float(self.t.max())

    def overlap_error(self, first: float, last: float) -> str:
        """Why the reference does not overlap a recording from `first` to `last` [s] (last NaN:
        the recording's start only is known, and the reference ends before it)."""
        lo, hi = self.span
        seen = f"{first:.6g} to {last:.6g} s" if np.isfinite(last) else f"from {first:.6g} s"
        return (f"{self.path}: the reference's time ({lo:.6g} to {hi:.6g} s) does not overlap "
                f"the recording's ({seen}): both must count from the same instant")

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """The up direction [n, 3] at the times t (linear between the reference's samples; NaN
        outside them) and, for a quaternion reference, the unit quaternions [n, 4]."""
        out = np.column_stack([np.interp(t, self.t, self.up[:, i], left=np.nan, right=np.nan)
                               for i in range(3)])
        q_at = None
        if self.quat is not None:
            q_at = np.column_stack([np.interp(t, self.t, self.quat[:, i], left=np.nan,
                                              right=np.nan) for i in range(4)])
            q_at /= np.linalg.norm(q_at, axis=1, keepdims=True)
        return out / np.linalg.norm(out, axis=1, keepdims=True), q_at


LAG_SEARCH_S = 30.0
"""How far apart the clocks of a recording and its reference are looked for [s], at most a
third of the first block's span (two thirds of it then overlap at the farthest)."""
LAG_SHORTEST_S = 4.0
"""The shortest first block [s] whose clock offset is looked for."""
LAG_CORRELATION = 0.5
"""The least correlation of the turn rates at an offset for it to be said."""
LAG_GAIN = 1.5
"""How many times more of the turn rates the clocks as read leave unexplained (one minus the
correlation) than the offset does, at least, for the offset to be said."""


def _correlation(a: np.ndarray, b: np.ndarray, most: int
                 ) -> tuple[np.ndarray, np.ndarray | None]:
    """The correlation coefficient of a[i] with b[i + lag] for lag in -most..most (by FFT),
    and the lags; None where either does not vary."""
    a, b = a - a.mean(), b - b.mean()
    scale = np.sqrt(np.sum(a * a) * np.sum(b * b))
    lags = np.arange(-most, most + 1)
    if not scale > 0.0:
        return lags, None
    size = 1 << int(np.ceil(np.log2(2 * len(a))))
    full = np.fft.irfft(np.conj(np.fft.rfft(a, size)) * np.fft.rfft(b, size), size)
    return lags, full[lags % size] / scale


def _rising(path: Path, t: np.ndarray, keep: np.ndarray, where: Any) -> None:
    """RecordingError where a reference's time (of its rows `keep`) repeats or goes back,
    naming the rows: matched by time, such a reference would be read between the wrong rows
    (two takes appended, rows written twice) and score a number that is none."""
    from .fit.recording import RecordingError

    rows = np.flatnonzero(keep)
    steps = np.diff(t[rows])
    bad = np.flatnonzero(~(steps > 0.0))
    if not len(bad):
        return
    a, b = int(rows[bad[0]]), int(rows[bad[0] + 1])
    how = "repeats" if t[b] == t[a] else "does not increase from"
    raise RecordingError(f"{path}, {where(b)}: the reference's time {t[b]:.6g} s {how} "
                         f"{t[a]:.6g} s on {where(a)} ({len(bad)} such step(s)): a reference's "
                         "time rises from row to row (two takes appended, or rows written "
                         "twice?)")


def reference_time_unit(path: Path, t: np.ndarray, stated: str | None, recording: str) -> str:
    """The unit of a reference's time column: the one its header states, else the one in which
    its steps are a rate a reference is sampled at (testbenches.time_unit.RATE_RANGE), and
    where two are, the recording's (both count from one instant in one unit as a rule, and the
    overlap is checked after); RecordingError where neither serves."""
    from .fit.recording import RecordingError
    from .time_unit import candidates, median_step, rates

    if stated in (DATETIME, TIME_OF_DAY, DURATION):  # read as seconds (since 1970, midnight)
        return "s"
    if stated is not None:
        if stated not in TIME_SCALE:
            raise RecordingError(f"{path}: the reference's time column states the unit "
                                 f"{stated!r}, not one of {', '.join(TIME_SCALE)}")
        return stated
    step = median_step(t)
    found = candidates(step)
    if len(found) == 1:
        return found[0]
    if recording in found or not (np.isfinite(step) and step > 0.0):
        return recording
    seen = rates(step, found) if found else "no rate a reference has in s, ms, us or ns"
    raise RecordingError(f"{path}: the reference's time column states no unit, and its median "
                         f"step {step:.6g} is {seen}, none of them the recording's unit "
                         f"({recording}): state it in the header, as time (ms)")


WORLD_UP_SPREAD_DEG = 10.0
"""The most the accelerometer at rest may miss a roll and pitch reference's up by in the other
unit (median angle) for that unit to be taken (Reference.angle_unit_from)."""
ANGLE_UNIT_MISS_DEG = 1.0
"""A reference's roll and pitch miss the accelerometer at rest by more than this in the unit
taken, and by a third of it in the other, for the other to be theirs: a degree read as a
radian misses by tens of degrees, a radian read as a degree by the tilt itself."""
WORLD_UP_TILT_DEG = 5.0
"""A reference vertical further than this from the world frame's z axis is taken as the
reference's up (a y-up motion-capture frame), and said so."""


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each v [N, 3] rotated by the unit quaternion q [N, 4] (w first): R(q) v."""
    w, u = q[:, :1], q[:, 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


QUIET_NORM = 0.05
"""A sample whose accelerometer's norm is within this share of the median norm is taken as at
rest, its direction the up direction (the reference's world vertical and its angles' unit)."""


def _quiet(acc: np.ndarray) -> np.ndarray:
    """The samples whose accelerometer's norm is within QUIET_NORM of the median norm."""
    norm = np.linalg.norm(acc, axis=1)
    return np.isfinite(norm) & (np.abs(norm / np.nanmedian(norm) - 1.0) < QUIET_NORM)


def find_world_up(acc: np.ndarray, q: np.ndarray | None, path: Path
                  ) -> tuple[np.ndarray | None, str]:
    """For a quaternion reference (q [N, 4], sensor to world, at the samples acc [N, 3] as the
    estimators take them [m/s^2]): the world's vertical, heading-free, where it is not the
    world frame's z axis (None where it is, or where there is nothing to tell), and what was
    found, for the printout. The specific force turned into the world frame averages gravity
    over any motion (reference_axes, law 1): its mean is the vertical, and its length g, to
    within VERTICAL_TOLERANCE, for any reference of this sensor; RecordingError where it is
    not (no vertical of the world frame explains the accelerometer)."""
    from fusion_core.types import G

    from .fit.recording import RecordingError
    from .reference_axes import VERTICAL_TOLERANCE

    if q is None:
        return None, ""
    finite = np.all(np.isfinite(acc), axis=1) & np.all(np.isfinite(q), axis=1)
    if finite.sum() < 10:
        return None, ""
    mean = _rotate(q[finite], acc[finite]).mean(axis=0)
    share = float(np.linalg.norm(mean)) / G
    if abs(share - 1.0) > VERTICAL_TOLERANCE:
        raise RecordingError(
            f"{path}: no vertical of the reference's world frame explains the accelerometer: "
            f"turned into that frame, its specific force averages {share:.2f} g, where a "
            "body's motion averages 1 g along the vertical: is the quaternion the "
            "sensor-to-world rotation, w first (q_w, q_x, q_y, q_z), and of the same sensor?")
    up = mean / np.linalg.norm(mean)
    tilt = float(np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0))))
    if tilt <= WORLD_UP_TILT_DEG:
        return None, f"reference: its world frame is z-up (within {tilt:.2g} deg)"
    axis = int(np.argmax(np.abs(up)))
    off = float(np.degrees(np.arccos(min(1.0, abs(float(up[axis]))))))
    if off <= WORLD_UP_TILT_DEG:  # frames are laid along their axes: that axis, exactly
        up = np.eye(3)[axis] * np.sign(up[axis])
        found = f"{'+' if up[axis] > 0 else '-'}{'xyz'[axis]} (within {off:.2g} deg)"
    else:
        found = f"({up[0]:+.3f}, {up[1]:+.3f}, {up[2]:+.3f}), {tilt:.3g} deg from z"
    return up, f"reference: its world frame's up is {found}: scored about that vertical"


def about_world_up(q: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The world's up `up` [3] in the sensor frame for sensor-to-world quaternions q [n, 4]."""
    conj = q * np.array([1.0, -1.0, -1.0, -1.0])
    return _rotate(conj, np.broadcast_to(up, (len(q), 3)).copy())


# ----- running ---------------------------------------------------------------------------------

def estimator_params(args: argparse.Namespace, entry: dict[str, Any],
                     has: set[str] | None = None) -> dict[str, Any]:
    """A preset entry with the command's sensor options and --param on top: of --param, the
    names in `has` (the estimator's parameters; None: every name)."""
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
    params.update({name: value for name, value in parse_params(args.param).items()
                   if has is None or name in has})
    return params


def param_names(args: argparse.Namespace, keys: list[str]) -> dict[str, set[str]]:
    """Each estimator's parameter names; a --param name none of them has is refused, naming
    those they have (a name only some have, such as the Kalman filter's Q_angle, goes to
    those)."""
    from fusion_core.registry import estimator_class

    from .fit.recording import RecordingError

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
    from .options import choose

    groups = choose(spec, list(OUTPUTS), "output")
    if not position:
        groups = [g for g in groups if g not in ("pos", "vel")]
    return ["time", *(c for g in groups for c in OUTPUTS[g])]


def _columns(out: dict[str, np.ndarray], t: np.ndarray, names: list[str], keep: slice
             ) -> list[np.ndarray]:
    pick = {"time": t, "roll": out["roll"], "pitch": out["pitch"], "rejected": out["rejected"]}
    for group in ("bias", "pos", "vel"):
        if group in out:
            pick.update({f"{group}_{a}": out[group][:, i] for i, a in enumerate("xyz")})
    return [np.asarray(pick[n][keep], dtype=float) for n in names]


class Score:
    """An inclination RMSE [deg] summed block by block (BROAD's rule: the counted samples with
    a reference and an estimate)."""

    def __init__(self) -> None:
        self.sum_sq, self.n = 0.0, 0

    def add(self, up: np.ndarray, rec: Any) -> None:
        from .broad.metric import inclination_error

        if rec.up_ref is None:
            return
        e = inclination_error(up, rec.up_ref)[rec.counted]
        e = e[np.isfinite(e)]
        self.sum_sq += float(np.sum(e * e))
        self.n += len(e)

    @property
    def rmse(self) -> float:
        return float(np.degrees(np.sqrt(self.sum_sq / self.n))) if self.n else float("nan")


class Thinned:
    """Every kth sample of a long series, k doubling whenever more than 2 * PLOT_POINTS are
    kept: what a plot of any length shows."""

    def __init__(self) -> None:
        self.k, self.rows = 1, np.empty(0, dtype=np.int64)
        self.values: dict[str, np.ndarray] = {}

    def add(self, row0: int, values: dict[str, np.ndarray]) -> None:
        """A block's series (each [n] or [n, m]) from the recording's row row0."""
        n = len(next(iter(values.values())))
        self.add_at(row0, n, lambda i: {name: v[i] for name, v in values.items()})

    def add_at(self, row0: int, n: int,
               make: Callable[[np.ndarray], dict[str, np.ndarray]]) -> None:
        """A block of n rows from row row0 whose series `make` gives at the block's indices
        it is passed: only the rows kept are computed (k is doubled first as far as the block
        would double it: a long first block is not computed whole to be thinned)."""

        def kept(k: int) -> int:
            return int(np.count_nonzero(self.rows % k == 0)) + len(range(-row0 % k, n, k))

        k = self.k
        while kept(k) > 2 * PLOT_POINTS:
            k *= 2
        self._thin(k)
        at = np.arange(-row0 % self.k, n, self.k)  # the block's rows r with r % k == 0
        self.rows = np.concatenate([self.rows, row0 + at])
        for name, v in make(at).items():
            old = self.values.get(name)
            self.values[name] = v if old is None else np.concatenate([old, v])

    def _thin(self, k: int) -> None:
        """Every kth sample of those kept (k a power-of-two multiple of self.k)."""
        if k != self.k:
            self.k = k
            keep = self.rows % k == 0
            self.rows = self.rows[keep]
            self.values = {name: v[keep] for name, v in self.values.items()}


class _Run:
    """One estimator over a recording's blocks: its outputs written, its score and plot trace
    kept."""

    def __init__(self, key: str, est: Any, path: Path, fmt: str, names: list[str]) -> None:
        self.key, self.est = key, est
        self.writer = TableWriter(path, fmt, names)
        self.score, self.trace, self.rejected = Score(), Thinned(), 0
        self.also: list[_Run] = []  # runs whose outputs this one's give (_running)

    def block(self, rec: Any, t: np.ndarray, row0: int, every: int) -> None:
        out = self.est.run(rec.acc, rec.gyro, rec.dt)
        for run in (self, *self.also):
            run.take(out, rec, t, row0, every)

    def take(self, out: dict[str, np.ndarray], rec: Any, t: np.ndarray, row0: int,
             every: int) -> None:
        """A block's outputs written, scored and kept for the plot."""
        from .broad.metric import gravity_from_roll_pitch

        keep = slice(-row0 % every, None, every)  # the recording's rows 0, every, 2 every, ...
        self.writer.write(_columns(out, t, self.writer.names, keep))
        if rec.up_ref is None:  # the up direction for the plot's rows only
            self.trace.add_at(row0, len(t), lambda i: {
                "t": t[i], "up": gravity_from_roll_pitch(out["roll"][i], out["pitch"][i])})
        else:
            up = gravity_from_roll_pitch(out["roll"], out["pitch"])
            self.score.add(up, rec)
            self.trace.add(row0, {"t": t, "up": up})
        self.rejected += int(out["rejected"].sum())


def shared_runs(estimators: dict[str, Any]) -> dict[str, str]:
    """Of estimators by key, those whose outputs another's run gives to the bit, each with
    that one's key: a kf whose roll, pitch, bias and rejected samples the position filter's
    gives (PositionKalmanFilter.attitude_params: that filter runs the same kf on the same
    samples) need not run a second time on every sample."""
    from fusion_core.kalman import AngleBiasKalmanFilter
    from fusion_core.position import PositionKalmanFilter

    given: dict[str, str] = {}
    for pos_key, pos in estimators.items():
        if type(pos) is not PositionKalmanFilter:
            continue
        same = pos.attitude_params()
        key = next((key for key, est in estimators.items() if key not in given
                    and type(est) is AngleBiasKalmanFilter and est.params == same), None)
        if key is not None:
            given[key] = pos_key
    return given


def _running(runs: list[_Run]) -> list[_Run]:
    """The runs that run their estimator, each also giving the outputs of those it gives
    (shared_runs)."""
    by_key = {run.key: run for run in runs}
    given = shared_runs({run.key: run.est for run in runs})
    for key, source in given.items():
        by_key[source].also.append(by_key[key])
    return [run for run in runs if run.key not in given]


class _VqfRun:
    """VQF on the samples the estimators took (their calibration and mounting applied, the
    samples they reject left out), block by block; `note` says why there is none."""

    def __init__(self, rate: float, params: dict[str, Any]) -> None:
        from fusion_core.base import COMMON_PARAMS

        from .peers import PeerUnavailable, VqfStream

        self.params, self.score, self.trace = params, Score(), Thinned()
        max_dt = next(float(p.default) for p in COMMON_PARAMS if p.name == "max_dt")
        self.rate, self.most = rate, max(1, round(max_dt * rate))
        self.missed = 0  # samples rejected since the last one taken
        try:
            self.stream: Any = VqfStream(rate)
            self.note = "VQF on the same samples"
        except PeerUnavailable as err:
            self.stream, self.note = None, f"(VQF not run: {str(err).split('; ')[-1]})"

    def block(self, rec: Any, t: np.ndarray, row0: int, every: int) -> None:
        if self.stream is None:
            return
        valid = rec.valid
        acc, gyro = conditioned(rec.acc[valid], rec.gyro[valid], self.params)
        # VQF takes no sample the estimators rejected; as they integrate the sample after
        # such samples over its dt, which spans them, VQF takes it once per sampling period
        # its dt spans, up to once more per sample missed (not for a row written twice,
        # which takes no time) and to max_dt's
        where = np.flatnonzero(valid)
        missed = np.diff(where, prepend=-1 - self.missed) - 1
        self.missed = len(valid) - 1 - int(where[-1]) if len(where) else self.missed + len(valid)
        steps = np.nan_to_num(np.rint(rec.dt[valid] * self.rate), nan=1.0)
        repeats = np.clip(steps, 1, np.minimum(1 + missed, self.most)).astype(int)
        up = np.full((len(valid), 3), np.nan)
        up[valid] = self.stream(np.repeat(acc, repeats, axis=0),
                                np.repeat(gyro, repeats, axis=0))[np.cumsum(repeats) - 1]
        self.score.add(up, rec)
        self.trace.add(row0, {"t": t, "up": up})


class _Lanes:
    """Every task (an estimator's or VQF's run) takes the blocks in order, each at its own pace:
    no task waits for the others at the end of a block. As many worker threads as the machine
    has cores take whichever task has a block waiting and is not running (the C twins run
    without the GIL, so the cores stay busy; one thread per task would hold a malloc arena and
    a block's outputs each). Blocks are handed out as read, at most IN_FLIGHT held at once
    (submit waits); `done(n)` is called once every task has finished a block of n rows. The
    first exception of a task is raised by submit or close."""

    def __init__(self, tasks: list[Any], done: Callable[[int], None]) -> None:
        import collections
        import os
        import queue
        import threading

        self._done, self._lock = done, threading.Lock()
        self._idle = threading.Condition(self._lock)  # notified when no block is left
        self._slots = threading.Semaphore(IN_FLIGHT)
        self._left: dict[int, list[int]] = {}  # block id -> [tasks still on it, rows]
        self._error: BaseException | None = None
        self._pending: list[collections.deque[Any]] = [collections.deque() for _ in tasks]
        self._busy = [False] * len(tasks)  # running, or waiting in the ready queue
        self._tasks = tasks
        self._ready: queue.Queue[int | None] = queue.Queue()
        self._next = 0
        self._workers = [threading.Thread(target=self._work, daemon=True)
                         for _ in range(max(1, min(len(tasks), os.cpu_count() or 1)))]
        for worker in self._workers:
            worker.start()

    def _work(self) -> None:
        while (i := self._ready.get()) is not None:
            with self._lock:
                block_id, args = self._pending[i].popleft()
            if self._error is None:
                try:
                    self._tasks[i].block(*args)
                except BaseException as err:  # raised in the caller
                    with self._lock:
                        self._error = self._error or err
            del args  # a worker holds no block between tasks
            with self._lock:
                if self._pending[i]:
                    self._ready.put(i)  # its next block
                else:
                    self._busy[i] = False
            self._finished(block_id)

    def _finished(self, block_id: int) -> None:
        with self._lock:
            left = self._left[block_id]
            left[0] -= 1
            if left[0] > 0:
                return
            del self._left[block_id]
            if not self._left:
                self._idle.notify_all()
        self._slots.release()
        if self._error is None:
            self._done(left[1])

    def submit(self, rows: int, *args: Any) -> None:
        """One block (rows long) to every task: task.block(*args)."""
        self._slots.acquire()
        self._raise()
        with self._lock:
            self._left[self._next] = [len(self._tasks), rows]
            for i, pending in enumerate(self._pending):
                pending.append((self._next, args))
                if not self._busy[i]:
                    self._busy[i] = True
                    self._ready.put(i)
        self._next += 1

    def close(self, quiet: bool = False) -> None:
        """Wait for every task to finish its blocks; raise the first exception of any (quiet:
        none, the caller is raising its own)."""
        if quiet:
            with self._lock:
                self._error = self._error or RuntimeError("stopped")  # the rest is skipped
        with self._idle:  # every block done (the workers put tasks' next blocks in the queue)
            while self._left:
                self._idle.wait()
        for _ in self._workers:
            self._ready.put(None)
        for worker in self._workers:
            worker.join()
        if not quiet:
            self._raise()

    def _raise(self) -> None:
        if self._error is not None:
            raise self._error


def _read_ahead(blocks: Any) -> Any:
    """The blocks of an iterator, the next one read by a thread of its own while the caller
    works on the last (the reader's exceptions raised in the caller, in order); the thread has
    ended when the caller's loop does, however it ends."""
    import queue
    import threading

    ready: queue.Queue[Any] = queue.Queue(maxsize=1)
    stop = threading.Event()

    def read() -> None:
        try:
            for block in blocks:
                while not stop.is_set():
                    try:
                        ready.put((block, None), timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            ready.put((None, None))
        except BaseException as err:  # handed to the caller
            ready.put((None, err))

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    try:
        while True:
            block, err = ready.get()
            if err is not None:
                raise err
            if block is None:
                return
            yield block
    finally:  # the reader stops after its block in hand: no read is left running at exit,
        stop.set()  # where a C++ reader's threads torn down mid-read abort the process
        thread.join()


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

    from .fit.recording import REFERENCE_COLUMNS, RecordingError, parse_columns, source_from_args
    from .options import choose

    keys = choose(args.estimator, list(KEYS), "estimator")
    preset = with_calibration(load_preset(args.preset), args.calibration)
    has = param_names(args, keys)
    estimators = {key: create(key, estimator_params(args, preset[key], has[key]))
                  for key in keys}
    names = {key: output_columns(args.outputs, est.HAS_POSITION)
             for key, est in estimators.items()}
    if not args.no_plots:  # the plotting library loads while the recording opens, which
        import threading  # leaves the second core idle (reading, units and rate are serial)

        threading.Thread(target=_import_pyplot, daemon=True).start()
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
            runs.append(_Run(key, est, path, args.format, names[key]))
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
        print(_plot(args.out / f"{source.name}.png", runs, vqf if scored else None,
                    found["trace"], source.name))
    return 0


def _run_blocks(args: argparse.Namespace, source: Any, reference: Reference | None,
                runs: list[Any], vqf_params: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """Every block through every estimator (in parallel, each at its own pace: _Lanes) and VQF
    where there is a reference (on the samples as `vqf_params` condition them); what was read,
    found and scored."""
    from .fit.recording import RecordingError

    world_up, notes, vqf = None, [], None
    n = missing = scored = 0
    first_t = last_t = float("nan")
    truth = Thinned()
    duration = 0.0
    lanes = None
    try:
        with _progress(source) as bar:
            for rec, t in _read_ahead(source.blocks()):
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
                        vqf = _VqfRun(source.rate, vqf_params)
                if world_up is not None and rec.ref_quat is not None:
                    rec.up_ref = about_world_up(rec.ref_quat, world_up)
                if rec.up_ref is not None:  # scored where every estimator and VQF took it
                    rec.counts = rec.counted & rec.valid
                    scored += int(rec.counts.sum())
                    truth.add(n, {"t": t, "up": rec.up_ref})
                if lanes is None:  # VQF's lane is known after the first block's reference
                    lanes = _Lanes([*_running(runs), *([vqf] if vqf is not None else [])],
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
    from .reference_axes import check_axes

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


def _import_pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend, or None where matplotlib is not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    return plt


ORIGIN_SHOWN_S = 1e5
"""A recording whose time starts this far from 0 [s] (a clock since 1970, as bags and loggers'
epochs count) is plotted from its first sample, the axis naming when that was."""


def _when(t: float) -> str:
    """The instant a time [s] names: a date where it counts since 1970, else the number."""
    import datetime as dt

    if 1e8 <= t <= 4.1e9:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    return f"{t:.9g} s"


def _plot(path: Path, runs: list[Any], vqf: Any, truth: Thinned, name: str) -> str:
    """The up direction each estimator finds (its three components: readable at any attitude,
    where roll is not near 90 deg of pitch), the reference's, and with a reference each one's
    inclination error; every series thinned alike (Thinned)."""
    plt = _import_pyplot()
    if plt is None:
        return "(no plot: matplotlib is not installed)"
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    from .broad.metric import inclination_error

    scored = len(truth.rows) > 0
    fig, axes = plt.subplots(4 if scored else 3, 1, sharex=True,
                             figsize=(9, 8.5 if scored else 6.5))
    series = [(run.key, run.trace) for run in runs]
    if vqf is not None and vqf.stream is not None:
        series.append(("vqf", vqf.trace))
    firsts = [float(trace.values["t"][0]) for _, trace in series if trace.values]
    origin = min(firsts) if firsts and abs(min(firsts)) >= ORIGIN_SHOWN_S else 0.0
    decades = [np.inf, -np.inf]  # the error's span, log10 [deg]
    for key, trace in series:
        if not trace.values:
            continue
        t, up = trace.values["t"] - origin, trace.values["up"]
        for i, ax in enumerate(axes[:3]):
            ax.plot(t, up[:, i], lw=0.9, label=key)
        if scored:  # the same rows: every series is thinned alike
            _, a, b = np.intersect1d(trace.rows, truth.rows, return_indices=True)
            err = np.maximum(np.degrees(inclination_error(up[a], truth.values["up"][b])), 1e-3)
            axes[3].plot(t[a], err, lw=0.8, label=key)
            if np.isfinite(err).any():
                decades = [min(decades[0], np.log10(np.nanmin(err))),
                           max(decades[1], np.log10(np.nanmax(err)))]
    if scored:
        for i, ax in enumerate(axes[:3]):
            ax.plot(truth.values["t"] - origin, truth.values["up"][:, i], "k--", lw=0.8,
                    label="reference")
        axes[3].set_ylabel("inclination\nerror [deg]")
        axes[3].set_yscale("log")
        # plain numbers (0.1, 1, 10; and 0.2, 0.5 where the error spans few decades, so that
        # any span has labels): the default labels are typeset by mathtext, whose parser is
        # built on its first use, at a cost a short recording's plot feels
        few = decades[1] - decades[0] <= 3.0
        axes[3].yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0) if few else (1.0,)))
        axes[3].yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axes[3].yaxis.set_minor_formatter(NullFormatter())
    for i, ax in enumerate(axes[:3]):
        ax.set_ylabel(f"up, {'xyz'[i]}")
        ax.set_ylim(-1.05, 1.05)
    axes[-1].set_xlabel(f"time [s] since {_when(origin)}" if origin else "time [s]")
    axes[0].legend(fontsize=8, ncol=4, loc="lower right")
    axes[0].set_title(f"{name}: the up direction in the sensor frame (gravity's, unit length)")
    # fixed margins that fit these labels: tight_layout would measure every tick label
    # first, a third of the plot's time on a long recording
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.07 if scored else 0.09,
                        top=0.95 if scored else 0.93, hspace=0.1)
    try:
        fig.savefig(path, dpi=110)
    except OSError as err:  # a full disk: no half-written picture left
        path.unlink(missing_ok=True)
        raise OSError(f"{path}: cannot be written ({err})") from None
    finally:
        plt.close(fig)
    return f"plot: {path}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: imu-fusion estimate RECORDING (or python -m testbenches estimate)")
