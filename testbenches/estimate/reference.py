"""The reference `imu-fusion estimate` scores against: a file of its own (or the recording's
own columns) of time with roll and pitch or a quaternion, matched to the recording's samples by
time; the unit of its angles, its clock's offset and its world frame's vertical found from the
data where the file does not state them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..fit.recording import QUAT_COLUMNS, in_radians, read_columns, reference_up
from ..table import DATETIME, DURATION, TIME_OF_DAY, TIME_SCALE


class Reference:
    """A reference file (time with roll, pitch or q_w..q_z), read whole (a reference is a
    recording's companion, not its bulk), matched to a recording's times by `at`."""

    def __init__(self, path: Path, recording_time_unit: str = "s",
                 columns: dict[str, str] | None = None, topic: str | None = None,
                 offset: float = 0.0) -> None:
        from ..fit.recording import RecordingError

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
        from ..broad.metric import gravity_from_roll_pitch, inclination_error
        from ..fit.recording import RecordingError
        from ..reference_axes import VERTICAL_TOLERANCE, vertical_share

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
        from ..broad.metric import inclination_error
        from ..gyro_unit import moving_average

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
    from ..fit.recording import RecordingError

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
    from ..fit.recording import RecordingError
    from ..time_unit import candidates, median_step, rates

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

    from ..fit.recording import RecordingError
    from ..reference_axes import VERTICAL_TOLERANCE

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
