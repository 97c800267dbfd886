"""Recordings as arrays in SI units: the Recording every command works on, and the one way a
recording file becomes one: `load_recording` (every command, with the options it is given:
`recording_from_args`), over the table reader (testbenches.reader), the units found or checked
(testbenches.gyro_unit); `load` for a CSV file in SI units or a BROAD trial.

CSV: a header row naming the columns (ALIASES, or --column maps); the accelerometer and the
gyro are required; `time` or `dt` give the sampling (else --rate); a reference for `tune` is
either quaternion columns q_w, q_x, q_y, q_z (sensor to world) or roll and pitch [rad]. BROAD
trials (HDF5 or .mat, testbenches.broad.data) bring their own rate and reference, and `rest()`
finds their rest segment (the start, before `movement` begins).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.base import COMMON_PARAMS

from ..broad.data import NotABroadTrial, load_trial
from ..broad.metric import gravity_from_quat
from ..gyro_unit import UNITS, median_period
from ..table import TIME_OF_DAY, TIME_SCALE
from ..time_unit import DAY_S, median_step
from .columns import ALIASES, find_names, name_forms, norm_name, unit_in_name

IMU_COLUMNS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")
QUAT_COLUMNS = ("q_w", "q_x", "q_y", "q_z")
AS_READ_AXES = "x,y,z"
"""The gyro's axes as its columns give them (--gyro-axes)."""


class RecordingError(ValueError):
    """A file that cannot serve: what is wrong and what is allowed."""


def valid_samples(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """Rows with a finite accelerometer, gyro and dt. Column by column: numpy's all() along a
    row of three takes several times as long as the six passes (a long recording's every
    block is checked)."""
    ok = np.isfinite(dt)
    for column in (*acc.T, *gyro.T):
        ok &= np.isfinite(column)
    return ok


@dataclass
class Recording:
    """acc, gyro [N, 3]; dt [N] (dt[0] = the nominal period); up_ref [N, 3] the reference up
    direction in the sensor frame (None without a reference); counts [N] the samples a score
    counts (BROAD's movement; all samples for a CSV)."""

    name: str
    acc: np.ndarray
    gyro: np.ndarray
    dt: np.ndarray
    rate: float
    gyro_sampling: str = "point"
    up_ref: np.ndarray | None = None
    counts: np.ndarray | None = None
    sensor_delay: float = 0.0
    """How long the samples lag the reference [s] (the estimators' sensor_delay; 0 for a CSV)."""
    ref_quat: np.ndarray | None = None
    """A quaternion reference's unit quaternions [N, 4], sensor to world (None: none)."""
    described: str = ""
    """Which columns, units and rate were taken, and why (load_recording)."""
    gyro_unit: str = "rad/s"
    """The unit the file's gyro was read in (testbenches.gyro_unit.UNITS)."""
    gyro_unit_checked: bool = True
    """False where gyro_unit was given or stated by the header and the data could not confirm
    it (no turns to compare, as in a still recording): a wrong one then shows only in what the
    numbers mean (a noise density no gyro has, rotation a still sensor cannot have)."""

    @property
    def sensor(self) -> dict[str, Any]:
        """The estimators' parameters that describe the recording's sensor."""
        return {"gyro_sampling": self.gyro_sampling, "sensor_delay": self.sensor_delay}

    @property
    def valid(self) -> np.ndarray:
        """The samples with a number in every column and a dt (the others the estimators
        reject and count)."""
        return valid_samples(self.acc, self.gyro, self.dt)

    @property
    def counted(self) -> np.ndarray:
        """The samples a score counts (all of them where the recording does not say)."""
        return self.counts if self.counts is not None else np.ones(len(self.dt), dtype=bool)

    @property
    def duration(self) -> float:
        return float(np.sum(self.dt))

    def slice(self, start: int, stop: int) -> Recording:
        """Samples start to stop, with what is said of the whole recording."""
        return replace(self, **{name: None if (v := getattr(self, name)) is None
                                else v[start:stop] for name in PER_SAMPLE})


def load(path: str | Path, rate: float | None = None) -> Recording:
    """A BROAD trial (by content) or a CSV file in SI units (m/s^2, rad/s), read by
    load_recording (which checks the units against the data); RecordingError saying what is
    wrong."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        trial = load_trial(path)
    except NotABroadTrial:
        return load_recording(path, rate=rate, acc_unit="m/s2", gyro_unit="rad/s")[0]
    return trial_recording(trial)


def trial_recording(trial: Any) -> Recording:
    """A BROAD trial (testbenches.broad.data.BroadTrial) as a Recording: its rate, sampling,
    delay and reference, scored over its movement samples."""
    up = gravity_from_quat(trial.opt_quat)
    return Recording(trial.name, trial.acc, trial.gyro, np.full(trial.n, trial.dt), trial.rate,
                     trial.gyro_sampling, up, trial.movement & np.all(np.isfinite(up), axis=1),
                     trial.sensor_delay)


PER_SAMPLE = ("acc", "gyro", "dt", "up_ref", "counts", "ref_quat")
"""Recording's fields that hold a row per sample (the others describe the whole recording)."""


def rest(rec: Recording) -> Recording:
    """A BROAD trial's rest segment: the samples before its first movement sample (the whole
    recording when it has no movement flags)."""
    if rec.counts is None or not np.any(rec.counts):
        return rec
    first = int(np.argmax(rec.counts))
    return rec.slice(0, first)


G_STANDARD = 9.80665


# ----- reading ---------------------------------------------------------------------------------

REFERENCE_COLUMNS = ("time", "roll", "pitch", *QUAT_COLUMNS)
"""The quantities a reference file's columns may be (estimate's --reference-column)."""


SENSORS = ("acc", "gyro")
"""The quantities --column takes for a sensor's three axes at once: acc=NAME for acc_x=NAME_x,
acc_y=NAME_y, acc_z=NAME_z (NAME_x found as the header spells it: NAME.x, NAME[0], NAMEX,
NAME_1 of a variable of three columns), or acc=X,Y,Z naming the three."""


def parse_columns(specs: list[str], option: str = "--column",
                  allowed: tuple[str, ...] | None = None) -> dict[str, str]:
    """QUANTITY=NAME options as {quantity: column name}, a sensor's (SENSORS, where allowed is
    None) as its three axes'; RecordingError for a quantity that is not one of `allowed`
    (ALIASES' and EXTRA_COLUMNS where None), a spec without '=' or a sensor given other than
    one name or three."""
    sensors = SENSORS if allowed is None else ()
    allowed = allowed or (*ALIASES, *EXTRA_COLUMNS)
    out = {}
    for spec in specs:
        quantity, sep, name = spec.partition("=")
        quantity = quantity.strip()
        if sep and quantity in sensors:
            names = [n.strip() for n in name.split(",")]
            if len(names) not in (1, 3) or not all(names):
                raise RecordingError(f"{option} {spec!r}: a sensor's columns are one name "
                                     f"({quantity}=NAME, for NAME_x, NAME_y, NAME_z) or three "
                                     f"({quantity}=X,Y,Z)")
            axes = names if len(names) == 3 else [f"{names[0]}_{a}" for a in "xyz"]
            out.update({f"{quantity}_{a}": n for a, n in zip("xyz", axes, strict=True)})
            continue
        if not sep or quantity not in allowed:
            more = f" (or {' or '.join(sensors)} for the three axes)" if sensors else ""
            raise RecordingError(f"{option} {spec!r}: expected QUANTITY=NAME with QUANTITY one "
                                 f"of {', '.join(allowed)}{more}")
        out[quantity] = name.strip()
    return out


COUNTER_NAMES = ("n_samples", "sample", "samples", "sample_index", "index", "idx", "counter",
                 "count", "frame", "n", "packet_counter")
"""Column names of a sample counter: no time, and said so where the time is missing."""
CLOCK_NAMES = {"sample_time_fine": "Xsens's clock, in ticks of 100 us in an MT Manager export "
                                   "and of 1 us in a Movella DOT one (--time-unit us)"}
"""Column names of a sensor's clock in a unit its file does not state and no step tells
(time_unit: both are rates an IMU is sampled at): said where the time is missing, not taken."""
INSTANCE_NAMES = ("i", "instance", "imu_instance", "imu_id", "imu_index", "sensor_id",
                  "sensor_index", "sensor_instance")
"""Column names that number the sensor a row is from (ArduPilot's IMU messages: "I"), where a
logger interleaves several sensors' rows."""
INTERLEAVED_SHARE = 0.1
"""A sensor's number on at least this share of the rows, and another's too: the rows are
several sensors'."""
EXTRA_COLUMNS = ("dt", "roll", "pitch")
"""Columns found by their own name only: the sampling and a reference."""


@dataclass
class Columns:
    """Where each quantity is in a table: its column index, the header name it came from and
    the unit the header states for it (None: none stated)."""

    index: dict[str, int]
    source: dict[str, str]
    units: dict[str, str | None]
    header: list[str]
    other_times: list[int] = field(default_factory=list)
    """Further columns a time's name fits, where the time was not given (a logger's epoch
    seconds beside its milliseconds): what serves where the one taken does not rise."""
    instances: list[int] = field(default_factory=list)
    """Columns that number a sensor (INSTANCE_NAMES: ArduPilot's "I"), checked to hold one."""
    where: Any = None
    """Where a row (counting from 0) is in the file, as its reader counts ("line 201"; the
    table's `where`)."""

    def take(self, table: Any, quantity: str, i: int) -> None:
        """Column i of the table (testbenches.reader.TableSource) as the quantity's."""
        self.index[quantity], self.source[quantity] = i, table.header[i]
        self.units[quantity] = table.units[i] or _unit_in_name(quantity, table.names[i])


def find_columns(table: Any, time_column: str | None = None,
                 columns: dict[str, str] | None = None) -> Columns:
    """The quantities of a table (testbenches.reader.TableSource), found by the header's names
    or the columns given ({quantity: name}); RecordingError for a given name it lacks."""
    given = dict(columns or {})
    if time_column:
        given.setdefault("time", time_column)
    found = Columns({}, {}, {}, table.header, where=table.where)
    alike: dict[str, list[int]] = {}  # quantity -> every column whose name fits as its does
    for quantity in (*ALIASES, *EXTRA_COLUMNS):
        name = given.get(quantity)
        hits: list[int] = []
        if name is not None:
            hits = (find_names(table.header, quantity, name)
                    or find_names(table.names, quantity, name))
            if not hits:
                raise RecordingError(f"{table.path}: no column {name!r} for {quantity}: the "
                                     f"header has {', '.join(table.header)}")
        elif quantity in ALIASES:
            hits = find_names(table.names, quantity)
        else:
            hits = find_names(table.names, "time", quantity)
        if hits:
            found.take(table, quantity, hits[0])
            alike[quantity] = hits
    if "time" in found.index and "time" not in given:
        taken = set(found.index.values())
        found.other_times = [j for j, forms in enumerate(zip(*name_forms(table.names), strict=True))
                             if j not in taken and set(forms) & set(ALIASES["time"])]
    found.instances = [j for j, name in enumerate(table.names)
                       if norm_name(name) in INSTANCE_NAMES and j not in found.index.values()]
    users: dict[int, list[str]] = {}
    for quantity, i in found.index.items():
        users.setdefault(i, []).append(quantity)
    for i, quantities in users.items():
        if len(quantities) > 1:  # a column given for one quantity that another's name fits
            raise RecordingError(
                f"{table.path}: the column {table.header[i]!r} is taken for both "
                f"{' and '.join(quantities)}: each needs a column of its own (--column "
                "QUANTITY=NAME, --time-column NAME)")
    for quantity, same in alike.items():
        if len(same) > 1:  # which one is meant, no name can say
            shown = ", ".join(f"{j + 1} {table.header[j]!r}" for j in same)
            twins = len({table.header[j].strip().lower() for j in same}) == 1
            raise RecordingError(
                f"{table.path}: {len(same)} columns' names fit {quantity} alike (columns "
                f"{shown}), so it could be any of them: " + (
                    "they are one name, which no --column can tell apart: rename them apart in "
                    "the file's header" if twins else
                    f"rename them apart or give the one meant (--column {quantity}=NAME)"))
    return found


def _repeated_names(header: list[str]) -> str:
    """Where the header names several columns alike (x, y, z for the accelerometer's and the
    gyro's, with no row above naming the groups: testbenches.reader._grouped), saying so and
    what serves: no name given with --column can tell such columns apart."""
    seen: dict[str, list[str]] = {}  # as compared -> as written
    for name in header:
        seen.setdefault(name.strip().lower(), []).append(name.strip())
    repeated = [names[0] for key, names in seen.items() if key and len(names) > 1]
    if not repeated:
        return ""
    return (f" ({', '.join(map(repr, repeated))} "
            f"{'names' if len(repeated) == 1 else 'each name'} more than one column, which no "
            "--column can tell apart: rename them apart in the file's header, acc_x or "
            "\"Accelerometer X\", or write the groups' names in a row above them, "
            "\"Accelerometer\" over the accelerometer's first column)")


def _unit_in_name(quantity: str, name: str) -> str | None:
    """The unit a column's name states: a time or dt column's (time_ms, timestamp_ns, micros),
    an accelerometer's or gyro's as a word of its own (columns.unit_in_name: gyro_rad[0],
    gyro_x_dps); else None."""
    if quantity not in ("time", "dt"):
        return unit_in_name(quantity, name)
    normed = norm_name(name)
    named = {"millis": "ms", "micros": "us",  # a sketch's millis() and micros()
             "seconds_elapsed": "s"}  # Sensor Logger's
    if normed in named:
        return named[normed]
    *_, suffix = normed.rpartition("_")
    return suffix if suffix in TIME_SCALE and normed != suffix else None


def open_table(path: Path, want: str = "imu", topic: str | None = None) -> Any:
    """testbenches.reader.open_table, or for a ROS bag testbenches.bags.open_bag (`want` "imu"
    for a recording, "pose" for a reference; the topic named, else the only one of its kind),
    its TableError as a RecordingError."""
    from ..bags import is_bag, open_bag
    from ..reader import TableError
    from ..reader import open_table as open_any

    try:
        if is_bag(path):
            return open_bag(path, want, topic)
        if topic is not None:
            raise RecordingError(f"{path}: a topic is given ({topic}), but this is no ROS bag "
                                 "(a .bag, a ROS 2 bag's folder or its .db3 or .mcap file)")
        return open_any(path, want)
    except TableError as err:
        raise RecordingError(str(err)) from None


def read_columns(path: Path, time_column: str | None = None,
                 columns: dict[str, str] | None = None, want: str = "imu",
                 topic: str | None = None) -> tuple[dict[str, np.ndarray], Columns]:
    """Every row of the quantities a file holds ({quantity: values}) and where they were
    found (a ROS bag's topic of `want`: open_table); RecordingError where the file cannot be
    read."""
    from ..reader import TableError

    table = open_table(path, want, topic)
    found = find_columns(table, time_column, columns)
    names = list(found.index)
    try:
        data = table.read([found.index[q] for q in names])
    except TableError as err:
        raise RecordingError(str(err)) from None
    return {q: data[:, k] for k, q in enumerate(names)}, found


def _stated(units: dict[str, str | None], axes: tuple[str, ...], path: Path) -> str | None:
    """The one unit the header states for these columns (None: none); RecordingError where
    they state different ones."""

    stated = {units.get(a) for a in axes} - {None}
    if len(stated) > 1:
        raise RecordingError(f"{path}: the header states the units {', '.join(sorted(stated))} "
                             f"for {', '.join(axes)}: one unit for the three axes serves")
    return stated.pop() if stated else None


PREFIX_ROWS = 1 << 18
"""The units, the first sample's dt and the reference's checks are decided on the first this
many samples (at 100 Hz, 44 minutes), so that a recording of any length is read once, in
blocks; the rest is converted as they decided."""


@dataclass
class _Clock:
    """Each sample's dt and time from a time column, a dt column or a rate, block after block
    (the last time stamp carried across blocks). A sample's dt is the time since the last row
    that holds a sample (`holds`: a number in every accelerometer and gyro column), so that a
    row the estimators reject, or one that is no sample at all (a merged export's row of
    another topic), takes no time from the next: its gyro's turn is what it is over the whole
    span since the last."""

    kind: str  # "time", "dt" or "rate"
    scale: float
    first_dt: float
    path: Path
    where: Any
    last_t: float | None = None
    last_row: int = -1
    last_sample_t: float | None = None
    last_sample_row: int | None = None
    pending: float = 0.0
    """The dt of rows since the last sample (a dt column's)."""
    total: float = 0.0
    moduli: tuple[float, ...] = ()
    """Where the time is a microcontroller's counter (ms or us), the moduli [s] of the widths it
    may have (COUNTER_BITS; a time of day's day): a fall by about one of them from below it is
    the counter starting again, not time going back (none: no counter)."""
    offset: float = 0.0
    wraps: int = 0
    wrapped_at: float = 0.0
    """The modulus [s] of the last wrap (which width the counter has: COUNTER_BITS)."""
    twice: int = 0
    """Rows that repeat the row before them, time and numbers (_without_twice)."""
    gaps: int = 0
    """Samples whose dt spans GAP_PERIODS sample periods or more (samples a logger dropped, a
    pause), the longest such dt [s] and where its sample is."""
    longest_gap: float = 0.0
    gap_at: str = ""
    last_values: Any = None
    """The last row's numbers (for the next block's first row)."""
    repeats: str = ""
    """What to say where a time repeats: how often it does over the first rows, and the rate
    that would space the samples (a time coarser than the sampling)."""

    def __call__(self, raw: np.ndarray | None, row0: int, n: int,
                 holds: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Each row's dt [s] (NaN for a row that holds no sample or no time) and time [s]."""
        if holds is None:
            holds = np.ones(n, dtype=bool)
        if self.kind == "rate":
            dt = np.full(n, np.nan)
            rows = np.flatnonzero(holds)
            dt[rows] = self.first_dt * self._rows_since(rows + row0)
            return dt, (row0 + np.arange(n)) * self.first_dt
        assert raw is not None
        if self.kind == "dt":
            dt = raw * self.scale
            if row0 == 0:
                dt = dt.copy()
                dt[0] = self.first_dt
            t = self.total + np.cumsum(np.where(np.isfinite(dt), dt, 0.0)) - self.first_dt
            self.total = float(t[-1] + self.first_dt)
            self._count_gaps(dt, row0 + np.arange(n), np.ones(n))
            return self._carried(dt, holds), t
        return self._from_time(raw * self.scale, row0, holds)

    def _count_gaps(self, steps: np.ndarray, rows: np.ndarray, spans: np.ndarray) -> None:
        """Counts the steps of the time (a time column's from row to row, a dt column's own)
        over `spans` rows each, before the row in `rows`, that are GAP_PERIODS periods or more
        beyond a period a row: a gap in the time, not rows without numbers (their samples
        are said on their own) or without a time."""
        over = np.flatnonzero(steps >= (spans - 1.0 + GAP_PERIODS) * self.first_dt)
        if len(over):
            self.gaps += len(over)
            k = int(over[np.argmax(steps[over])])
            if steps[k] > self.longest_gap:
                self.longest_gap, self.gap_at = float(steps[k]), self.where(int(rows[k]))

    def _rows_since(self, rows: np.ndarray) -> np.ndarray:
        """Of each sample's row, the rows since the last sample's (1 for the very first)."""
        last = rows[0] - 1 if self.last_sample_row is None and len(rows) else self.last_sample_row
        if len(rows):
            self.last_sample_row = int(rows[-1])
        return np.diff(np.concatenate([[last], rows])) if len(rows) else rows

    def _carried(self, dt: np.ndarray, holds: np.ndarray) -> np.ndarray:
        """A dt column's samples, each with the dt of the rows since the last sample added."""
        extra = np.where(~holds & np.isfinite(dt), dt, 0.0)
        before = np.concatenate([[0.0], np.cumsum(extra)])  # extra over the rows before each
        rows = np.flatnonzero(holds)
        out = np.full(len(dt), np.nan)
        if not len(rows):
            self.pending += float(before[-1])
            return out
        since = before[rows] - before[np.concatenate([[0], rows[:-1] + 1])]
        since[0] += self.pending
        out[rows] = dt[rows] + since
        self.pending = float(before[-1] - before[rows[-1] + 1])
        return out

    def _from_time(self, t: np.ndarray, row0: int, holds: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
        """A sample's dt is the time since the last sample with a time (a row without one gets
        dt NaN, which the estimators reject, and as its time that last time plus the nominal
        period per row since; every row's time must rise from the last row's that has one)."""
        if self.moduli:
            t = self._unwrapped(t)
        valid = np.flatnonzero(np.isfinite(t))
        dt = np.full(len(t), np.nan)
        times = t[valid]
        rows = row0 + valid
        if self.last_t is not None:
            times_all = np.concatenate([[self.last_t], times])
            rows_all = np.concatenate([[self.last_row], rows])
        else:
            times_all, rows_all = times, rows
        steps = np.diff(times_all)
        self._count_gaps(steps, rows_all[1:], np.diff(rows_all))
        if not np.all(steps > 0.0):
            i = int(np.argmax(~(steps > 0.0)))
            same = steps[i] == 0.0
            raise RecordingError(
                f"{self.path}, {self.where(int(rows_all[i + 1]))}: the time "
                f"{float(times_all[i + 1]):.6g} s " + ("repeats" if same else "does not "
                                                       "increase from")
                + f" {'the time ' if same else ''}{float(times_all[i]):.6g} s on "
                f"{self.where(int(rows_all[i]))}" + (
                    self.repeats if same else "" if steps[i] > -RESTART_S else
                    "; a time that starts again is a recording written on after another (a "
                    "logger that restarted and appended to the same file): split the file "
                    "there"))
        samples = np.flatnonzero(np.isfinite(t) & holds)
        sample_t = t[samples]
        if self.last_sample_t is not None:
            dt[samples] = np.diff(np.concatenate([[self.last_sample_t], sample_t]))
        elif len(samples):
            dt[samples[1:]] = np.diff(sample_t)
            dt[samples[0]] = self.first_dt
        if len(samples):
            self.last_sample_t = float(sample_t[-1])
        if len(rows_all) == 0:  # no time yet: the period per sample from the first
            return dt, (row0 + np.arange(len(t))) * self.first_dt
        if len(valid) == len(t) > 0:  # every row has its time
            self.last_t, self.last_row = float(times[-1]), int(rows[-1])
            return dt, t
        here = row0 + np.arange(len(t))
        k = np.searchsorted(rows_all, here, side="right") - 1  # the last sample with a time
        k = np.maximum(k, 0)
        at = times_all[k] + (here - rows_all[k]) * self.first_dt
        if len(valid):
            self.last_t, self.last_row = float(times[-1]), int(rows[-1])
        return dt, np.where(np.isfinite(t), t, at)

    def _unwrapped(self, t: np.ndarray) -> np.ndarray:
        """The times [s] with the counter's wraps taken out (self.moduli, wrap_amounts)."""
        valid = np.isfinite(t)
        raw = t[valid]
        if not len(raw):
            return t + self.offset
        last = self.last_t - self.offset if self.last_t is not None else raw[0]
        before = np.concatenate([[last], raw[:-1]])
        amounts = wrap_amounts(before, raw - before, self.moduli, self.first_dt)
        t = t + self.offset
        if amounts.any():
            t[valid] += np.cumsum(amounts)
            self.offset += float(np.sum(amounts))
            self.wraps += int(np.count_nonzero(amounts))
            self.wrapped_at = float(amounts[np.flatnonzero(amounts)[-1]])
        return t


MAX_DT = next(p.default for p in COMMON_PARAMS if p.name == "max_dt")
"""The estimators' default max_dt [s]: a longer gap is a sample they reject."""
GAP_PERIODS = 2.5
"""A sample whose dt is this many sample periods or more follows a gap: a sample or more
dropped (a phone's scheduling stretches a step by half a period at times, never so far)."""
COUNTER_BITS = (16, 32)
"""The widths of a microcontroller's time counter: 32 bits (Arduino's millis() and micros():
micros() starts again every 71.6 minutes) or 16 (a timer's ms count, again every 65.5 s). A
counter's value is below 2^bits, so a fall by 2^16 from below it is no 32-bit counter's."""
COUNTER_WRAP = 2.0 ** max(COUNTER_BITS)
"""The largest counter's modulus: a time of integers below it may be a counter."""
COUNTER_SCALES = (TIME_SCALE["ms"], TIME_SCALE["us"])
"""The units such a counter counts in (a factor to seconds each)."""
WRAP_STEPS = 10.0
"""A fall of the time by the counter's modulus less at most this many periods is a wrap."""


def wrap_amounts(before: np.ndarray, steps: np.ndarray, moduli: tuple[float, ...],
                 period: float) -> np.ndarray:
    """Of each step of a time (from the values `before`), the modulus by which its counter
    started again there (0: none): a fall from below the modulus that the modulus turns into
    a step of at most WRAP_STEPS periods, the smallest such modulus."""
    out = np.zeros(len(steps))
    for modulus in sorted(moduli):
        up = steps + modulus
        out[(out == 0.0) & (steps < 0.0) & (before < modulus) & (up > 0.0)
            & (up <= WRAP_STEPS * period)] = modulus
    return out


def counter_moduli(scale: float) -> tuple[float, ...]:
    """The moduli [s] of a counter of each of COUNTER_BITS counting in units of `scale` s."""
    return tuple(2.0 ** bits * scale for bits in COUNTER_BITS)


@dataclass
class RecordingSource:
    """A recording opened for reading in blocks, in SI units: each block a Recording of those
    samples and their times [s]; the units, columns and rate decided on its first samples
    (`choices` says which and why); `rows` the number of samples where the format says it
    (None for text until read)."""

    path: Path
    name: str
    rate: float
    choices: str
    rows: int | None
    _blocks: Any
    time_unit: str = "s"
    """The unit of the file's time column (s where the times come from a rate or the format)."""
    read_notes: dict[str, Any] = field(default_factory=dict)
    """What the last read found ("wraps": how often the time's counter started again)."""
    found: list[str] = field(default_factory=list)
    """What reading found left out (the table's: TableSource.found)."""

    def blocks(self, rows: int | None = None) -> Iterator[tuple[Recording, np.ndarray]]:
        """(Recording, time [s]) of each block of samples, from the first; RecordingError where
        a row cannot serve."""
        from ..table import BLOCK_ROWS, TableError

        try:
            yield from self._blocks(rows or BLOCK_ROWS)
        except TableError as err:
            raise RecordingError(str(err)) from None

    def load(self) -> tuple[Recording, np.ndarray]:
        """The whole recording and its times; its `described` says what was read."""
        parts = list(self.blocks())
        rec = concatenate([p for p, _ in parts])
        t = np.concatenate([t for _, t in parts])
        rec.described = self.summary(len(rec.dt), float(np.nansum(rec.dt[1:])),
                                     int((~rec.valid).sum()))
        return rec, t

    def summary(self, n: int, duration: float, missing: int, choices: bool = True) -> str:
        """What was read: the count and length, the choices (unless told not to), the samples
        without numbers."""
        wrapped = self.read_notes.get("wraps", 0)
        twice = self.read_notes.get("twice", 0)
        missing -= twice  # said on their own
        what = ("the time of day passed midnight" if self.time_unit == TIME_OF_DAY
                else f"the time's {self.read_notes.get('bits', 32)}-bit counter started again")
        return (f"{n} samples, {duration:.4g} s at {self.rate:.4g} Hz"
                + (f"; {self.choices}" if choices else "")
                + (f"; {missing} sample(s) without a number in every column, which the "
                   "estimators reject and count (the next sample's dt spans them)"
                   if missing else "")
                + (f"; {what} {wrapped} time(s), taken as going on" if wrapped else "")
                + (f"; {twice} row(s) repeat the row before them, time and numbers (a logger "
                   "wrote them twice): rejected and counted, as samples without a time"
                   if twice else "")
                + self._gaps_said()
                + "".join(f"; {said}" for said in dict.fromkeys(self.found)))


    def _gaps_said(self) -> str:
        """The gaps in the time the last read found (_Clock.gaps), for the summary."""
        gaps = self.read_notes.get("gaps", 0)
        if not gaps:
            return ""
        longest, at = self.read_notes["longest_gap"], self.read_notes["gap_at"]
        return (f"; {gaps} gap(s) in the time of {GAP_PERIODS:g} sample periods or more (samples "
                f"dropped, a pause; the longest {longest:.4g} s, before the sample on {at}): the "
                "estimators integrate the sample after a gap over it" + (
                    f", or reject it where the gap exceeds their max_dt ({MAX_DT:g} s)"
                    if longest > MAX_DT else ""))


def concatenate(parts: list[Recording]) -> Recording:
    """The blocks of one recording as one."""

    def joined(name: str) -> np.ndarray | None:
        values = [getattr(p, name) for p in parts]
        return None if values[0] is None else np.concatenate(values)

    return replace(parts[0], **{name: joined(name) for name in PER_SAMPLE})


def _broad_source(path: Path, trial: Any) -> RecordingSource:
    rec = trial_recording(trial)
    t = np.cumsum(rec.dt) - rec.dt[0]

    def blocks(rows: int) -> Iterator[tuple[Recording, np.ndarray]]:
        for lo in range(0, len(rec.dt), rows):
            yield rec.slice(lo, lo + rows), t[lo:lo + rows]

    return RecordingSource(path, rec.name, rec.rate, "a BROAD trial: m/s2 and rad/s, its own "
                           "rate, sampling, delay and reference", len(rec.dt), blocks)


def open_recording(path: Path, *, rate: float | None = None, time_column: str | None = None,
                   acc_unit: str = "auto", gyro_unit: str = "auto",
                   columns: dict[str, str] | None = None,
                   time_unit: str = "auto", acc_sign: str = "auto",
                   gyro_axes: str = AS_READ_AXES, topic: str | None = None,
                   counts: tuple[float, float] | None = None) -> RecordingSource:
    """The recording opened for reading in blocks (RecordingSource), its units, columns and
    rate decided from its first PREFIX_ROWS samples: given, stated by the file, or from the
    data (which must not contradict what is given or stated); the gyro's axes in the
    accelerometer's as `gyro_axes` orders them (parse_axes); `counts`, a converter's raw
    counts per g and per deg/s, in place of the units (the gyro's scale still checked against
    the data); RecordingError saying what is wrong."""
    from ..bags import is_bag
    from ..reader import TableError
    from .sensor_files import is_sensor_files, open_sensor_files

    axes = parse_axes(gyro_axes)
    if is_bag(path) or topic is not None:  # a ROS bag's IMU topic
        table = open_table(path, "imu", topic)
    elif is_sensor_files(path):  # a phone app's export: one file per sensor
        others = sorted(set(columns or {}) - {"time"})
        if others:
            raise RecordingError(f"{path}: --column {others[0]}=... maps a file's column; the "
                                 "files of a folder or archive are found by their names (the "
                                 "time's column may be given)")
        try:
            table = open_sensor_files(path, time_column or (columns or {}).get("time"))
        except TableError as err:
            raise RecordingError(str(err)) from None
        time_column, columns = None, None
    elif not path.is_file():
        raise RecordingError(f"{path}: no such file")
    else:
        if path.suffix.lower() in (".hdf5", ".h5", ".mat"):
            try:
                return _broad_source(path, load_trial(path))
            except NotABroadTrial:
                pass
        table = open_table(path)
    found = find_columns(table, time_column, columns)
    missing = [q for q in IMU_AXES if q not in found.index]
    if missing:
        raise RecordingError(
            f"{path}: no column for {', '.join(missing)}: the header has "
            f"{', '.join(found.header)}; name them acc_x, acc_y, acc_z, gyro_x, gyro_y, "
            "gyro_z (or ax, ay, az, gx, gy, gz), or map them with --column QUANTITY=NAME"
            + _unknown_units(found.header, missing) + _repeated_names(found.header)
            + (f" ({table.note})" if table.note else ""))
    names = list(found.index)
    wanted = [found.index[q] for q in names]
    try:
        prefix_block = table.first_block(wanted + found.other_times + found.instances,
                                         PREFIX_ROWS)
    except TableError as err:
        raise RecordingError(str(err)) from None
    if prefix_block is None:
        prefix_block = np.empty((0, len(wanted) + len(found.other_times)
                                 + len(found.instances)))
    prefix = {q: prefix_block[:, k] for k, q in enumerate(names)}
    other_times = {j: prefix_block[:, len(names) + k] for k, j in enumerate(found.other_times)}
    for k, j in enumerate(found.instances):
        _one_sensor(path, table.header[j],
                    prefix_block[:, len(names) + len(found.other_times) + k])
    units = found.units
    n = len(prefix_block)
    if n < 2:
        raise RecordingError(f"{path}: {n} sample(s); a recording needs many")
    given_rate = rate
    rate = rate or table.attrs.get("rate")
    split = _split_rows(*_vectors(prefix))
    if "time" in prefix and not split:  # rows written twice take no time, as in _samples
        prefix["time"] = _without_twice(prefix, None)[0]
    joiner = None
    keep: Any = slice(None)  # the rows that are samples (all, unless split)
    if split:
        if "time" not in prefix:
            raise RecordingError(f"{path}: {split}; a time column joins them, and this file "
                                 "has none")
        joiner = _JoinedRows
        prefix, keep = joiner()(prefix)
    time_taken = ""
    if not split and "time" in prefix and not _rises(prefix["time"]):
        rising = next((j for j, t in other_times.items() if _rises(t)), None)
        if rising is not None:  # a time that repeats or goes back, where another rises
            time_taken = (f"; {found.source['time']!r} does not rise from row to row, "
                          f"{table.header[rising]!r} does")
            found.take(table, "time", rising)
            prefix["time"] = other_times[rising]
            wanted = [found.index[q] for q in names]
    if counts is not None:
        acc_unit, gyro_unit = _counted_units(path, counts, acc_unit, gyro_unit, units)
    # the samples as read (counts in g and deg/s): the time unit's evidence needs their
    # directions only
    def vectors(cols: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        acc, gyro = _vectors(cols)
        if counts is not None:
            acc, gyro = acc / counts[0], gyro / counts[1]
        return acc, gyro if axes is None else gyro @ axes.T

    acc, gyro = vectors({q: v[keep] for q, v in prefix.items()})
    holds = _holds(prefix)  # the rows that are samples, whose times the steps are
    t_unit, time_how = "s", ""
    if time_unit != "auto" and not ("time" in prefix or "dt" in prefix):
        raise RecordingError(f"{path}: --time-unit {time_unit} is given, but the recording has "
                             "no time or dt column for it (leave it out)")
    timed = "time" in prefix or "dt" in prefix
    if timed and given_rate:  # the user's rate over the file's time (a time that cannot serve)
        kind = "time" if "time" in prefix else "dt"
        if split or time_unit != "auto":
            raise RecordingError(
                f"{path}: --rate is given, but " + ("the accelerometer and the gyro are on rows "
                                                    "of their own, which their time joins"
                                                    if split else "so is --time-unit")
                + ": leave one of them out")
        column_rate = _column_rate(path, kind, prefix[kind], units.get(kind), acc, gyro,
                                   table.where, keep, holds)
        if column_rate is not None and abs(column_rate / given_rate - 1.0) > RATE_AGREES:
            raise RecordingError(
                f"{path}: --rate {given_rate:g} contradicts its {kind} column "
                f"{found.source[kind]!r}, whose steps give {column_rate:.4g} Hz: leave --rate out "
                "to take the column's (--rate spaces the samples of a file whose time cannot: "
                "none, or one that repeats)")
        clock = _Clock("rate", 1.0, 1.0 / given_rate, path, table.where)
        time_how = f"time from the rate given ({given_rate:g} Hz), the file's {kind} column left"
    elif timed:
        kind = "time" if "time" in prefix else "dt"
        clock, t_unit, time_how = _time_clock(path, kind, prefix[kind], time_unit,
                                              units.get(kind), acc, gyro, table.where, keep,
                                              holds)
        time_how += time_taken
    elif rate:
        clock = _Clock("rate", 1.0, 1.0 / rate, path, table.where)
        time_how = "" if given_rate else f"time from the rate the file states ({rate:g} Hz)"
    else:
        counters = [h for h, nm in zip(table.header, table.names, strict=True)
                    if norm_name(nm) in COUNTER_NAMES]
        hints = ([f"{', '.join(map(repr, counters))} counts samples, which is no time"]
                 if counters else [])
        hints += [f"{h!r} is {CLOCK_NAMES[norm_name(nm)]}"
                  for h, nm in zip(table.header, table.names, strict=True)
                  if norm_name(nm) in CLOCK_NAMES]
        hint = f" ({'; '.join(hints)})" if hints else ""
        raise RecordingError(f"{path}: no time or dt column{hint}: give the sample rate (--rate "
                             "HZ), the time column's name (--time-column NAME) or map it with "
                             "--column time=NAME")
    dt = replace(clock)(prefix.get(clock.kind), 0, n, holds)[0][keep]
    finite = valid_samples(acc, gyro, dt)
    if not finite.any():
        raise RecordingError(f"{path}: no sample holds numbers in every column")
    acc_scale, acc_how = _acc_scale(path, acc[finite], acc_unit,
                                    _stated(units, tuple(f"acc_{a}" for a in "xyz"), path),
                                    counts[0] if counts is not None else None)
    sign, sign_how = _acc_sign(path, acc_sign, [table.names[found.index[f"acc_{a}"]]
                                                for a in "xyz"], table.platform)
    acc_scale, acc_how = sign * acc_scale, acc_how + sign_how

    def more() -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The blocks after the first, as read (for the gyro unit's evidence)."""
        evidence_clock = replace(clock)
        row0 = 0
        join = joiner() if joiner else None
        for block in table.blocks(wanted, PREFIX_ROWS):
            cols, d, _ = _samples(block, names, join, evidence_clock, row0)
            if row0 > 0:
                yield (*vectors(cols), d)
            row0 += len(block)

    found_unit = _gyro_unit(
        path, acc, gyro, dt, gyro_unit, _stated(units, tuple(f"gyro_{a}" for a in "xyz"), path),
        more if n == PREFIX_ROWS else None, counts[1] if counts is not None else None)
    gyro_scale, gyro_how, used = UNITS[found_unit.unit], found_unit.how, found_unit.samples
    if axes is not None:
        gyro_how += ("; its axes as the accelerometer's "
                     f"{', '.join(c.strip() for c in gyro_axes.split(','))} (given)")
    _holds_gravity(path, acc[finite] * acc_scale, gyro[finite] * gyro_scale, dt[finite],
                   f"acc in {acc_how}; gyro in {gyro_how}", (acc[finite], gyro[finite]))
    period = median_period(dt)
    if n == PREFIX_ROWS:  # the file may go on
        acc_how += f" over the first {n} samples"
        gyro_how += f" over the first {used} samples"
    where = ", ".join(f"{q}={found.source[q]!r}" for q in (*IMU_AXES, "time", "dt")
                      if q in found.source)
    reference = [q for q in ("roll", "pitch", *QUAT_COLUMNS) if q in found.source]
    if reference:  # the file's own: said, as a device's own estimate may be what they hold
        stated = units.get("roll") if "roll" in reference else None
        where += ("; reference from this file's columns "
                  + ", ".join(f"{q}={found.source[q]!r}" for q in reference)
                  + (f" in {stated} (from the header)" if stated
                     else " in rad" if "roll" in reference else ""))
    if split:
        time_how += ("; the accelerometer and the gyro on rows of their own: each gyro row a "
                     "sample, with the accelerometer's latest row before it")
    choices = (f"acc in {acc_how}; gyro in {gyro_how}" + (f"; {time_how}" if time_how else "")
               + (f"; columns {where}" if where else "")
               + (f"; {table.note}" if table.note else "")
               + ("" if table.kind == "text" else f"; read as {table.kind}"))
    name = path.stem

    read_notes: dict[str, Any] = {}

    def blocks(rows: int) -> Iterator[tuple[Recording, np.ndarray]]:
        run_clock = replace(clock)
        row0 = 0
        join = joiner() if joiner else None
        for block in table.blocks(wanted, rows):
            cols, dt, t = _samples(block, names, join, run_clock, row0)
            row0 += len(block)
            acc, gyro = vectors(cols)
            acc, gyro = acc * acc_scale, gyro * gyro_scale
            up, ref_quat = reference_up(cols, path, units)
            counts = None if up is None else np.all(np.isfinite(up), axis=1)
            rec = Recording(name, acc, gyro, dt, 1.0 / period, "point", up, counts,
                            gyro_unit=found_unit.unit, gyro_unit_checked=found_unit.checked)
            rec.ref_quat = ref_quat
            read_notes["wraps"], read_notes["twice"] = run_clock.wraps, run_clock.twice
            read_notes["gaps"] = run_clock.gaps
            read_notes["longest_gap"], read_notes["gap_at"] = (run_clock.longest_gap,
                                                               run_clock.gap_at)
            if run_clock.wrapped_at:
                read_notes["bits"] = round(np.log2(run_clock.wrapped_at / run_clock.scale))
            yield rec, t

    return RecordingSource(path, name, 1.0 / period, choices, table.rows, blocks, t_unit,
                           read_notes, table.found)


def _samples(block: np.ndarray, names: list[str], join: Any, clock: _Clock, row0: int
             ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """A block's samples by quantity, their dt and times: joined first where the sensors are
    on rows of their own (join: a _JoinedRows, or None), the clock run over every row so that
    it names a row by the file's line."""
    cols = {q: block[:, k] for k, q in enumerate(names)}
    if join is None and clock.kind == "time":  # a row written twice: no time of its own
        cols["time"], clock.last_values, twice = _without_twice(cols, clock.last_values)
        clock.twice += twice
    cols, rows = join(cols) if join else (cols, slice(None))
    dt, t = clock(cols.get(clock.kind), row0, len(block), _holds(cols))
    return {q: v[rows] for q, v in cols.items()}, dt[rows], t[rows]


def _without_twice(cols: dict[str, np.ndarray], before: np.ndarray | None
                   ) -> tuple[np.ndarray, np.ndarray | None, int]:
    """The time column with NaN for the rows that repeat the row before them in every column,
    time included (`before`: the previous block's last row), this block's last row, and how
    many: a logger that wrote a row twice. A sensor's noise makes two samples' six numbers and
    times alike only there; whole samples alike at rest differ in their time."""
    if not len(cols["time"]):
        return cols["time"], before, 0
    columns = [cols[q] for q in sorted(cols)]  # column by column: no copy of the block
    twice = np.empty(len(columns[0]), dtype=bool)
    twice[0] = before is not None and all(c[0] == b for c, b in zip(columns, before, strict=True))
    twice[1:] = True
    for c in columns:
        twice[1:] &= c[1:] == c[:-1]
    last = np.array([c[-1] for c in columns], dtype=float)
    return np.where(twice, np.nan, cols["time"]), last, int(twice.sum())


RATE_AGREES = 0.02
"""A rate given and a file's time agree within this fraction (a crystal's and a logger's clock,
a nominal rate against the measured one)."""


def _column_rate(path: Path, kind: str, raw: np.ndarray, stated: str | None, acc: np.ndarray,
                 gyro: np.ndarray, where: Any, keep: Any, holds: np.ndarray | None
                 ) -> float | None:
    """The rate [Hz] a time or dt column's steps give (_time_clock's reading of it), None where
    it cannot serve (it repeats, does not rise, or its unit cannot be told)."""
    try:
        clock = _time_clock(path, kind, raw, "auto", stated, acc, gyro, where, keep, holds)[0]
        period = median_period(replace(clock)(raw, 0, len(raw), holds)[0])
    except RecordingError:
        return None
    return 1.0 / period if np.isfinite(period) and period > 0.0 else None


def _time_clock(path: Path, kind: str, raw: np.ndarray, unit: str, stated: str | None,
                acc: np.ndarray, gyro: np.ndarray, where: Any, keep: Any = slice(None),
                holds: np.ndarray | None = None) -> tuple[_Clock, str, str]:
    """The clock of a time or dt column from its first rows `raw` (numbers as read), its
    unit and how that was chosen (_time_scale; acc, gyro as read, of the rows `keep` selects,
    are the evidence where the steps leave two units). A time of integers below 2^32 in ms or
    us is a microcontroller's counter, and a time of day passes midnight: their wraps (wraps)
    count as going on."""
    day = stated == TIME_OF_DAY
    zeros, span = 0, (0, 0.0)
    if kind == "time":
        timed = np.isfinite(raw)
        if holds is not None and np.count_nonzero(timed & holds) >= 2:
            timed &= holds  # the samples' steps, not a merged export's other rows'
        valid = np.flatnonzero(timed)
        if len(valid) < 2:
            raise RecordingError(f"{path}: fewer than two samples with a time")
        values = raw[valid]
        steps = np.diff(values)
        step = median_step(values)
        counter = bool(np.all((values == np.round(values)) & (values >= 0.0)
                              & (values < COUNTER_WRAP)))
        moduli = (DAY_S,) if day else counter_moduli(1.0) if counter else ()
        increasing = bool(np.all((steps > 0.0)
                                 | (wrap_amounts(values[:-1], steps, moduli, step) > 0.0)))
        zeros, span = int(np.sum(steps == 0.0)), (len(values) - 1, float(values[-1] - values[0]))
    else:
        step, increasing, counter = median_period(raw[1:]), True, False

    def clock_in(scale: float) -> _Clock:
        first = step * scale if increasing else float("nan")
        moduli = ((DAY_S,) if day else counter_moduli(scale)
                  if counter and scale in COUNTER_SCALES else ())
        repeats = ""
        if zeros and span[1] == 0.0:
            repeats = (f" (the time holds one number over the first {span[0] + 1} rows: written "
                       "with too few digits for the samples' spacing, as 6 significant digits of "
                       "seconds since 1970 (C's %g) or a 32-bit float (steps of 128 s there) "
                       "are; write it with more, or give --rate HZ to space the samples by a "
                       "rate, the time left)")
        elif zeros and span[1] > 0.0:
            mean_rate = span[0] / (span[1] * scale)
            repeats = (f" ({zeros} of the first {span[0]} steps are 0 between rows of other "
                       "numbers (a row written twice whole is rejected and counted): a time "
                       "coarser than the samples' spacing, which is "
                       f"{mean_rate:.4g} Hz on average; give --rate {mean_rate:.4g} to space "
                       "the samples by a rate, the time left)")
        return _Clock(kind, scale, first, path, where, moduli=moduli, repeats=repeats)

    # the unit from the mean step where the time repeats: a clock coarser than the samples
    # rises by its tick, not by their spacing (whole epoch seconds at 100 Hz)
    unit_step = span[1] / span[0] if zeros and span[1] > 0.0 else step
    def dt_of(scale: float) -> np.ndarray:
        return clock_in(scale)(raw, 0, len(raw), holds)[0][keep]

    t_unit, scale, how = _time_scale(path, kind, unit_step, unit, stated, dt_of, acc, gyro)
    return clock_in(scale), t_unit, how


def _unknown_units(header: list[str], missing: list[str]) -> str:
    """Where a missing quantity's column is there but for a unit in brackets this reader does
    not know ("Gyro X (1/s)"), which kept it from its name: saying so, and what serves."""
    from ..table import bracketed, unit_named

    by_unit: dict[str, list[str]] = {}
    for name in header:
        found = bracketed(name)
        if found and unit_named(found[1]) is None and any(
                find_names([found[0]], q) for q in missing):
            by_unit.setdefault(found[1], []).append(repr(name))
    if not by_unit:
        return ""
    said = "; ".join(f"{', '.join(names)} state{'s' if len(names) == 1 else ''} the unit "
                     f"{unit!r}" for unit, names in by_unit.items())
    return (f" ({said}, which this reader does not know: map each column with --column "
            "QUANTITY=NAME and give its unit with --acc-unit or --gyro-unit)")


def _one_sensor(path: Path, name: str, numbers: np.ndarray) -> None:
    """RecordingError where a column that numbers the sensor (INSTANCE_NAMES) gives two or more
    numbers on INTERLEAVED_SHARE of the rows each: the rows are several sensors', which read as
    one would be one sensor at several times the rate, its samples alternating."""
    values, counts = np.unique(numbers[np.isfinite(numbers)], return_counts=True)
    many = counts >= INTERLEAVED_SHARE * len(numbers)
    if many.sum() < 2 or not np.all(values == np.round(values)):
        return
    shown = ", ".join(f"{v:g} on {c} rows" for v, c in zip(values, counts, strict=True))
    raise RecordingError(
        f"{path}: the rows are {int(many.sum())} sensors', as {name!r} numbers them ({shown}; "
        "read as one they would alternate): keep one sensor's rows (an ArduPilot log: "
        "mavlogdump.py --types IMU --condition 'IMU.I==0' --format csv FILE.bin)")


def _rises(t: np.ndarray) -> bool:
    """Whether a time column's numbers rise from each row to the next (NaN rows left out)."""
    values = t[np.isfinite(t)]
    return len(values) > 1 and bool(np.all(np.diff(values) > 0.0))


def _holds(cols: dict[str, np.ndarray]) -> np.ndarray:
    """The rows of a block's columns that hold a sample: a number in every accelerometer and
    gyro column."""
    ok = np.isfinite(cols[IMU_COLUMNS[0]])
    for name in IMU_COLUMNS[1:]:
        ok &= np.isfinite(cols[name])
    return ok


def _vectors(cols: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The accelerometer and gyro [n, 3] of a block's columns."""
    return (np.column_stack([cols[f"acc_{a}"] for a in "xyz"]),
            np.column_stack([cols[f"gyro_{a}"] for a in "xyz"]))


def load_recording(path: Path, *, rate: float | None = None, time_column: str | None = None,
                   acc_unit: str = "auto", gyro_unit: str = "auto",
                   columns: dict[str, str] | None = None) -> Any:
    """The recording in SI units (Recording; its `described` says which columns, units and
    rate were taken and why) and the time of each sample [s] (open_recording, read whole);
    RecordingError saying what is wrong."""
    return open_recording(path, rate=rate, time_column=time_column, acc_unit=acc_unit,
                          gyro_unit=gyro_unit, columns=columns).load()


IMU_AXES = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")


def source_from_args(path: Path, args: argparse.Namespace) -> RecordingSource:
    """open_recording with the options add_recording_options defines."""
    return open_recording(path, rate=args.rate, time_column=args.time_column,
                          acc_unit=args.acc_unit, gyro_unit=args.gyro_unit,
                          columns=parse_columns(args.column), time_unit=args.time_unit,
                          acc_sign=args.acc_sign, gyro_axes=args.gyro_axes,
                          topic=args.topic, counts=getattr(args, "counts", None))


def recording_from_args(path: Path, args: argparse.Namespace) -> Any:
    """load_recording with the options add_recording_options defines, the choices printed."""
    rec, t = source_from_args(path, args).load()
    print(f"{path}: {rec.described}")
    return rec, t


def _given_against_header(path: Path, sensor: str, option: str, unit: str,
                          stated: str | None) -> None:
    """RecordingError where a unit given on the command line is not the one the header states
    for the same columns: one of the two is wrong, and the data may be too quiet to tell."""
    if unit != "auto" and stated is not None and unit != stated:
        raise RecordingError(
            f"{path}: --{option} {unit} contradicts the header, which states {stated} for the "
            f"{sensor}: leave --{option} out to take the header's, or rename the columns where "
            "the header is wrong")


def _split_rows(acc: np.ndarray, gyro: np.ndarray) -> str:
    """Where no row holds both the accelerometer and the gyro but rows hold each (a logger
    that writes each sensor's readings as they come, or at its own rate): saying so; else
    ""."""
    if np.any(np.all(np.isfinite(acc), 1) & np.all(np.isfinite(gyro), 1)):
        return ""
    only_acc = int(np.sum(_only(acc, gyro)))
    only_gyro = int(np.sum(_only(gyro, acc)))
    if only_acc and only_gyro:
        return (f"the accelerometer and the gyro are on rows of their own ({only_acc} rows "
                f"hold only the accelerometer, {only_gyro} only the gyro)")
    return ""


def _only(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rows that hold a's three axes and none of b's."""
    return np.all(np.isfinite(a), 1) & ~np.any(np.isfinite(b), 1)


class _JoinedRows:
    """The rows of a recording whose accelerometer and gyro are on rows of their own, as
    samples: each gyro row is one (the gyro's readings are what is integrated, each over its
    own dt), with the accelerometer's latest row at or before it (the estimators low-pass the
    accelerometer over a second or more, so a reading a fraction of a period old is its
    value). The accelerometer's rows are no samples: their time is NaN to the clock, which so
    steps from gyro row to gyro row and still names a row by its line. One per read: the
    latest accelerometer row carries across its blocks; gyro rows before any have none (NaN:
    rejected and counted)."""

    def __init__(self) -> None:
        self.last = np.full(3, np.nan)

    def __call__(self, cols: dict[str, np.ndarray]) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """The block's columns with each row's accelerometer filled and the accelerometer
        rows' time NaN, and which rows are samples."""
        acc, gyro = _vectors(cols)
        own = np.all(np.isfinite(acc), 1)
        acc_row = _only(acc, gyro)
        latest = np.maximum.accumulate(np.where(acc_row, np.arange(len(acc)), -1))
        filled = np.where((latest >= 0)[:, None], acc[np.maximum(latest, 0)], self.last)
        filled = np.where((own & ~acc_row)[:, None], acc, filled)  # a row with both: its own
        if acc_row.any():
            self.last = acc[np.flatnonzero(acc_row)[-1]].copy()
        out = dict(cols)
        out.update({f"acc_{a}": filled[:, i] for i, a in enumerate("xyz")})
        out["time"] = np.where(acc_row, np.nan, cols["time"])
        return out, ~acc_row


def _time_scale(path: Path, kind: str, step: float, unit: str, stated: str | None,
                dt_of: Any, acc: np.ndarray, gyro: np.ndarray) -> tuple[str, float, str]:
    """The unit of the time or dt column (kind), its factor to seconds and how it was chosen:
    given, stated by the header, or from its median step (numbers as read) and where two units
    give IMU rates from the data (testbenches.time_unit; dt_of(scale): each sample's dt [s] in a
    unit of that factor). A step that is no IMU rate in the unit given or stated is refused
    with the rate it would be, and so is a given unit that is not the header's."""
    from ..table import DATETIME, DURATION
    from ..time_unit import RATE_RANGE, TimeUnit, candidates, listed, rate_in, time_unit

    if stated in (DATETIME, TIME_OF_DAY, DURATION):
        holds = {DATETIME: "dates and times", TIME_OF_DAY: "times of day",
                 DURATION: "durations with their unit"}[stated]
        if unit != "auto":
            raise RecordingError(f"{path}: --time-unit {unit} is given, but the {kind} column "
                                 f"holds {holds}, which are read as such (leave it out)")
        if stated == TIME_OF_DAY:
            return TIME_OF_DAY, 1.0, (f"{kind} from its times of day (seconds since midnight; "
                                      "a midnight passed taken as going on)")
        if stated == DURATION:
            return "s", 1.0, f"{kind} from its durations (each with its unit, as seconds)"
        return "s", 1.0, f"{kind} from its dates and times (seconds since 1970, UTC)"
    _given_against_header(path, kind, "time-unit", unit, stated)
    chosen = unit if unit != "auto" else stated
    if chosen is not None:
        how = "given" if unit != "auto" else "from the header"
        if chosen not in TIME_SCALE:
            raise RecordingError(f"{path}: the {kind} column's unit {chosen!r} is not one of "
                                 f"{', '.join(TIME_SCALE)}")
        if np.isfinite(step) and step > 0.0 and chosen not in candidates(step):
            fits = candidates(step)
            serve = "check the column"
            if fits:
                serve = (f"in {listed(fits)} it is "
                         + ", ".join(f"{rate_in(step, u):.4g} Hz" for u in fits) + ": "
                         + ("give --time-unit " + listed(fits) if unit != "auto"
                            else "correct the unit in the header"))
            raise RecordingError(
                f"{path}: the {kind} column's median step {step:.6g} is "
                f"{rate_in(step, chosen):.4g} Hz in {chosen} ({how}), a rate no IMU is "
                f"sampled at ({RATE_RANGE[0]:g} to {RATE_RANGE[1]:g} Hz); {serve}")
        return chosen, TIME_SCALE[chosen], f"{kind} in {chosen} ({how})"
    if not (np.isfinite(step) and step > 0.0):  # a time that does not increase: the clock
        return "s", 1.0, f"{kind} in s"           # names where, in the file's own numbers
    found = time_unit(kind, step, dt_of, acc, gyro)
    if not isinstance(found, TimeUnit):
        raise RecordingError(f"{path}: {found}")
    return found.unit, found.scale, f"{kind} in {found.unit} ({found.how})"


RESTART_S = 1.0
"""A time that goes back by more than this [s] started again (a logger restarted), where a
smaller step back is rows out of order."""
ACC_UNITS = {"m/s2": 1.0, "g": G_STANDARD, "mg": G_STANDARD / 1000.0}
"""The accelerometer's units and their factor to m/s^2."""
ACC_NORMS = {"g": (0.5, 2.0), "m/s2": (5.0, 20.0), "mg": (500.0, 2000.0)}
"""The median norm of the accelerometer (gravity, at rest and on average in motion) that each
unit gives, as numbers read; they do not overlap."""
COUNTS_PER_G = (256, 2048, 4096, 8192, 16384)
"""Raw accelerometer counts per g of common MEMS parts at their ranges (an ADXL345's 256; an
MPU-6050's or ICM's 16384 to 2048 at +-2 to 16 g); a norm of 1000 or so is mg."""


def _counts_hint(norm: float) -> str:
    """Where a median norm is about a common part's counts per g: what the numbers are."""
    near = [c for c in COUNTS_PER_G if abs(norm / c - 1.0) < 0.15]
    if not near:
        return ""
    return (f"that is about {near[0]}, a MEMS part's raw counts per g (an MPU-6050 gives "
            "16384 at +-2 g, 2048 at +-16 g): give --counts PER_G,PER_DPS, its counts per g "
            "and per deg/s from its datasheet (an MPU-6050's 16384,131 at +-2 g and +-250 "
            "deg/s), or ")


def _counted_units(path: Path, counts: tuple[float, float], acc_unit: str, gyro_unit: str,
                   units: dict[str, str | None]) -> tuple[str, str]:
    """The units --counts gives the numbers (g and deg/s once divided by its counts);
    RecordingError where a unit is also given or stated by the header."""
    if acc_unit != "auto" or gyro_unit != "auto":
        raise RecordingError(f"{path}: --counts gives the accelerometer's and the gyro's units "
                             "(its counts per g and per deg/s): leave --acc-unit and "
                             "--gyro-unit out")
    stated = sorted({u for q, u in units.items() if q in IMU_AXES and u})
    if stated:
        raise RecordingError(f"{path}: --counts is given, but the header states the unit(s) "
                             f"{', '.join(stated)} for the accelerometer or the gyro: numbers "
                             "in a unit are no counts; leave --counts out")
    return "g", "deg/s"


def _acc_scale(path: Path, acc: np.ndarray, unit: str, stated: str | None,
               per_g: float | None = None) -> tuple[float, str]:
    """The factor to m/s^2 and how it was chosen: given, stated by the header, or from the
    median norm (1 g or 9.81 m/s^2 at rest, and near it on average in motion); refused where
    the norm in that unit cannot be gravity's, and where a given unit is not the header's.
    `per_g`: the numbers are counts divided by this many per g (--counts), unit g."""
    _given_against_header(path, "accelerometer", "acc-unit", unit, stated)
    norm = float(np.median(np.linalg.norm(acc, axis=1)))
    chosen = unit if unit != "auto" else stated
    how = ("given" if per_g is None else f"from its counts, {per_g:g} per g, --counts"
           ) if unit != "auto" else "from the header"
    if chosen is None:
        chosen = next((u for u, (lo, hi) in ACC_NORMS.items() if lo < norm < hi), None)
        if chosen is None:
            low = (" (a phone's linear or user acceleration, from which gravity was taken out, "
                   "reads so: give its total acceleration)" if norm < ACC_NORMS["g"][0] else "")
            raise RecordingError(
                f"{path}: the accelerometer's median norm is {norm:.4g}, neither about 1 (g), "
                f"9.81 (m/s2) nor 1000 (mg){low}: {_counts_hint(norm)}give --acc-unit, or check "
                "the columns")
        how = f"from its median norm {norm:.4g}"
    scale = ACC_UNITS.get(chosen)
    if scale is None:
        raise RecordingError(f"{path}: the accelerometer's unit {chosen!r} is not one of "
                             f"{', '.join(ACC_UNITS)}")
    si = norm * scale
    if not 4.0 < si < 40.0:
        held = ""
        if per_g is not None:  # the counts per g the numbers hold
            near = [c for c in COUNTS_PER_G if abs(norm * per_g / c - 1.0) < 0.15]
            held = (f": it holds about {norm * per_g:.4g} counts per g"
                    + (f" ({near[0]}: give --counts {near[0]},...)" if near else ""))
        raise RecordingError(f"{path}: the accelerometer's median norm is {si:.4g} m/s2 in the "
                             f"unit {chosen} ({how}), which cannot be right (gravity is "
                             f"9.81){held}")
    return scale, f"{chosen} ({how})"


IOS_ACC_NAMES = ("accelerometer_acceleration",)
"""Accelerometer column stems that only iOS apps write (SensorLog's accelerometerAccelerationX),
whose values are Core Motion's: the negative of specific force, in g."""


def _acc_sign(path: Path, given: str, names: list[str], platform: str) -> tuple[float, str]:
    """The accelerometer's sign (+1: specific force; -1: its negative, iOS's Core Motion) and
    how it was chosen, said where it is not +1 or was given; names: the accelerometer's columns'
    names (without their units). A negated accelerometer reads as the sensor turned upside
    down, and its gyro still explains every turn (a point reflection commutes with rotations),
    so the data cannot tell: given, else the columns' names, else +1; a phone app's export that
    says it was recorded on iOS, where the app's setting decides, is refused until given."""
    if given != "auto":
        return float(given), "" if given == "+1" else ", sign -1 (given)"
    if all(norm_name(name).startswith(IOS_ACC_NAMES) for name in names):
        return -1.0, (", sign -1 (iOS's Core Motion: the columns are SensorLog's, which read "
                      "-1 g up at rest)")
    if platform == "iOS":
        raise RecordingError(
            f"{path}: recorded on iOS (its metadata says so), whose accelerometer reads the "
            "negative of specific force (a phone flat on a table: z = -1 g) unless the app "
            "turned it (Sensor Logger's 'Standardise Units & Frames'), and the export does not "
            "say which: give --acc-sign -1 (the setting off, the app's default) or +1 (on). "
            "Taken with the wrong sign the phone reads as upside down")
    return 1.0, ""


def parse_axes(text: str) -> np.ndarray | None:
    """The matrix that takes the gyro's readings, as read, into the accelerometer's axes, of a
    signed order of its axes ("x,-y,z": its y negated; "y,x,z": x and y swapped); None for the
    axes as read; RecordingError for anything else."""
    cells = [c.strip().lower() for c in text.split(",")]
    names = [c.lstrip("+-") for c in cells]
    if len(cells) != 3 or sorted(names) != ["x", "y", "z"]:
        raise RecordingError(f"--gyro-axes {text!r}: the gyro's x, y and z, each once, in the "
                             "accelerometer's order, each with its sign: x,-y,z or y,x,-z")
    m = np.zeros((3, 3))
    for row, (cell, name) in enumerate(zip(cells, names, strict=True)):
        m[row, "xyz".index(name)] = -1.0 if cell.startswith("-") else 1.0
    return None if np.array_equal(m, np.eye(3)) else m


@dataclass(frozen=True)
class _GyroUnit:
    unit: str
    how: str
    """How it was chosen, for the choices printed."""
    samples: int
    """Over how many samples."""
    checked: bool
    """Whether the data confirmed it (Recording.gyro_unit_checked)."""


def _gyro_unit(path: Path, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray, unit: str,
               stated: str | None, more: Any = None, per_dps: float | None = None
               ) -> _GyroUnit:
    """The gyro's unit, how it was chosen and over how many samples: the unit in which the
    gyro's turn explains the accelerometer's turn of gravity (testbenches.gyro_unit), the
    windows of further blocks (`more`: (acc, gyro, dt) each) pooled while the first cannot
    tell and no unit is given. A unit given or stated by the header that the data contradict
    is refused with the evidence; where the data cannot tell and no unit is given or stated,
    the recording is refused, and so is a given unit that is not the header's. `per_dps`:
    the gyro's numbers are its counts divided by this many per deg/s (--counts), unit deg/s."""
    from ..gyro_unit import MIN_WINDOWS, verdict, window_misses
    from ..time_unit import listed

    _given_against_header(path, "gyro", "gyro-unit", unit, stated)
    misses = window_misses(acc, gyro, dt)
    evidence, used = verdict(misses), len(dt)
    chosen = unit if unit != "auto" else stated
    if chosen is None and evidence.unit is None and more is not None:
        for a, g, d in more():
            extra = window_misses(a, g, d)
            misses = {u: np.concatenate([misses[u], extra[u]]) for u in misses}
            evidence, used = verdict(misses), used + len(d)
            if evidence.unit is not None:
                break
    if evidence.unit is None and evidence.windows >= MIN_WINDOWS:  # turns no unit explains
        _axes_as_read(path, acc, gyro, dt, {u: UNITS[u] for u in ((chosen,) if chosen in UNITS
                                                                  else UNITS)})
    if chosen is not None:
        how = ("given" if per_dps is None else f"from its counts, {per_dps:g} per deg/s, --counts"
               ) if unit != "auto" else "from the header"
        if chosen not in UNITS:
            raise RecordingError(f"{path}: the gyro's unit {chosen!r} is not one of "
                                 f"{', '.join(UNITS)}")
        if evidence.unit is None and chosen == "rad/s":
            _no_gyro_noise(path, acc, gyro, dt, how)
        if evidence.unit is not None and evidence.unit != chosen and per_dps is not None:
            raise RecordingError(
                f"{path}: the gyro's counts per deg/s ({per_dps:g}, --counts) contradict the "
                f"data: {evidence.describe()}: give the counts per deg/s of the range the part "
                "was set to (an MPU-6050's 131, 65.5, 32.8 or 16.4 at +-250 to +-2000 deg/s)")
        if evidence.unit is not None and evidence.unit != chosen:
            raise RecordingError(
                f"{path}: the gyro's unit {chosen} ({how}) contradicts the data: "
                f"{evidence.describe()}, so it reads in {evidence.unit}; give --gyro-unit "
                f"{evidence.unit}, or check the columns{_swapped(acc, gyro)}")
        return _GyroUnit(chosen, f"{chosen} ({how}" + (
            ", and the data agree)" if evidence.unit else ")"), used, evidence.unit is not None)
    if evidence.unit is None:
        raise RecordingError(
            f"{path}: the gyro's unit cannot be told from the data ({evidence.undecided()}): "
            f"give --gyro-unit {listed(list(UNITS))}{_swapped(acc, gyro)}")
    return _GyroUnit(evidence.unit, f"{evidence.unit} (from the data: {evidence.describe()})",
                     used, True)


GYRO_DENSITY_MAX = math.radians(0.3)
"""The most white noise a MEMS gyro's rate has [rad/s/sqrt(Hz)]: ten times the noisiest
datasheets' 0.03 deg/s/sqrt(Hz) (an MPU-6050's is 0.005)."""
STILL_DEG = 3.0
"""A sensor is still where nine in ten of its accelerometer's samples point within this of
their mean direction [deg] (a MEMS accelerometer's noise turns one by a few tenths at most):
no motion and no vibration moves its gyro, whose sample-to-sample steps are then its noise."""


def _density(x: np.ndarray, dt: np.ndarray) -> float:
    """The white noise density of the columns of x (the median over them) from their
    sample-to-sample steps, which leave out a bias and a slow motion: the steps' standard
    deviation (from their median absolute deviation, which a few absurd samples do not move)
    over sqrt(2), times sqrt(the median period)."""
    steps = np.diff(x, axis=0)
    steps = steps[np.all(np.isfinite(steps), axis=1)]
    period = float(np.nanmedian(dt)) if len(dt) else float("nan")
    if len(steps) < 10 or not period > 0.0:
        return float("nan")
    spread = 1.4826 * np.median(np.abs(steps - np.median(steps, axis=0)), axis=0)
    return float(np.median(spread)) / math.sqrt(2.0) * math.sqrt(period)


def _still(acc: np.ndarray) -> bool:
    """Whether the accelerometer (any unit) shows the sensor still (STILL_DEG)."""
    acc = acc[np.all(np.isfinite(acc), axis=1)]
    norm = np.linalg.norm(acc, axis=1)
    mean = acc.mean(axis=0) if len(acc) else np.zeros(3)
    if len(acc) < 10 or not np.linalg.norm(mean) > 0.0 or not np.all(norm > 0.0):
        return False
    cos = acc @ (mean / np.linalg.norm(mean)) / norm
    return bool(np.degrees(np.arccos(np.clip(np.quantile(cos, 0.1), -1.0, 1.0))) <= STILL_DEG)


def _no_gyro_noise(path: Path, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                   how: str) -> None:
    """RecordingError where a gyro said to be in rad/s (`how`: given or from the header) and
    not confirmed by the data (no turn of gravity to compare) has a white noise no gyro has
    (GYRO_DENSITY_MAX) while the sensor is still (_still), and one a gyro has in deg/s: deg/s
    read as rad/s, which turns the attitude of a still sensor by tens of degrees."""
    gyro_density = _density(gyro, dt)
    if not (gyro_density > GYRO_DENSITY_MAX and gyro_density * UNITS["deg/s"] <= GYRO_DENSITY_MAX
            and _still(acc)):
        return
    raise RecordingError(
        f"{path}: the gyro in rad/s ({how}) has a white noise of "
        f"{math.degrees(gyro_density):.3g} deg/s/sqrt(Hz), more than ten times any MEMS gyro's "
        f"(an MPU-6050's is 0.005), while the accelerometer shows the sensor still; in deg/s it "
        f"would be {math.degrees(gyro_density * UNITS['deg/s']):.3g}: "
        + ("correct the header's unit to deg/s" if how == "from the header"
           else "give --gyro-unit deg/s") + ", or check the columns")


def _axes_as_read(path: Path, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                  scales: dict[str, float]) -> None:
    """RecordingError where the gyro's turn explains the accelerometer's only with its axes in
    another signed order (testbenches.gyro_unit.gyro_axes), saying which."""
    from ..gyro_unit import gyro_axes

    found = gyro_axes(acc, gyro, dt, scales)
    if found is None:
        return
    order, unit, best, as_read = found
    raise RecordingError(
        f"{path}: the gyro's axes are not the accelerometer's: its turn explains how the "
        f"accelerometer sees gravity turn with its axes as ({order}) in {unit} (a median miss of "
        f"{best:.3g} deg, against {as_read:.3g} deg as read): a sign or an order that differs "
        "between the two (a left-handed frame, axes remapped in one sensor only); give "
        f"--gyro-axes {order.replace(' ', '')}")


SWAP_KEPT = 1.0 / 3.0
"""The share of its mean norm that an accelerometer's mean vector keeps (gravity keeps its
direction but where the sensor tumbles: 0.35 shaking to 1.0 in the battery's motions), and a
gyro's never approaches (its turns go back and forth: at most 0.07 there)."""


def _kept(v: np.ndarray) -> float:
    """The norm of a vector's mean over its mean norm (0 for no finite sample)."""
    v = v[np.all(np.isfinite(v), axis=1)]
    norm = float(np.mean(np.linalg.norm(v, axis=1))) if len(v) else 0.0
    return float(np.linalg.norm(v.mean(axis=0))) / norm if norm > 0.0 else 0.0


def _swapped(acc: np.ndarray, gyro: np.ndarray) -> str:
    """Where the gyro's columns, as read, hold what an accelerometer's would and the
    accelerometer's what a gyro's would (a norm of gravity's in one of ACC_NORMS' units and a
    mean vector of at least SWAP_KEPT of it; the accelerometer's columns' mean vector less:
    a gyro's large turn-on bias keeps a direction too, but then the accelerometer's columns
    keep gravity's), the question whether the two sensors' columns are swapped, for a
    refusal; else ""."""
    norm = float(np.nanmedian(np.linalg.norm(gyro, axis=1))) if len(gyro) else 0.0
    kept = _kept(gyro)
    unit = next((u for u, (lo, hi) in ACC_NORMS.items() if lo < norm < hi), None)
    if unit is None or kept < SWAP_KEPT or _kept(acc) >= SWAP_KEPT:
        return ""
    return (f". The gyro's columns read as an accelerometer's would (a median norm of "
            f"{norm:.4g}, gravity's in {unit}, whose mean vector keeps {kept:.0%} of it): are "
            "the accelerometer's and the gyro's columns swapped? Map them with --column "
            "acc=NAME --column gyro=NAME")


def _holds_gravity(path: Path, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                   units: str, read: tuple[np.ndarray, np.ndarray]) -> None:
    """RecordingError where the accelerometer, in SI units with the gyro's, holds no gravity
    (testbenches.gravity): a phone's linear acceleration, or units or axes taken wrongly, or the
    two sensors' columns swapped (read: acc and gyro as read, _swapped)."""
    from ..gravity import WINDOW_S, held_gravity

    found = held_gravity(acc, gyro, dt)
    if found is None or found.held:
        return
    raise RecordingError(
        f"{path}: the accelerometer holds no gravity as read: its samples, turned with the gyro "
        f"and averaged over {WINDOW_S:g} s, keep {found.g:.3g} g (median of {found.windows} "
        "windows) where gravity keeps 1 g. Its columns may hold a phone's linear or user "
        "acceleration, from which gravity was taken out: give the accelerometer's own (total) "
        "acceleration (Android's TYPE_ACCELEROMETER, Sensor Logger's TotalAcceleration, "
        f"phyphox's acceleration with g); or the units ({units}) or the axes are not what they "
        "are taken for" + _swapped(*read))


QUAT_NORM_TOLERANCE = 0.1
"""A reference quaternion whose norm is further than this from 1 is no rotation: its row is
left out (and counted)."""


def in_radians(roll: np.ndarray, pitch: np.ndarray) -> bool:
    """Whether roll and pitch can be radians: within pi and pi/2 (NaN left out)."""
    return bool(np.nanmax(np.abs(roll), initial=0.0) <= np.pi + 1e-6
                and np.nanmax(np.abs(pitch), initial=0.0) <= np.pi / 2 + 1e-6)


def reference_up(cols: dict[str, np.ndarray], path: Path,
                 units: dict[str, str | None] | None = None
                 ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The up direction [N, 3] of the reference columns in the sensor frame, taking the
    reference's world frame as z-up, and for a quaternion reference the unit quaternions
    [N, 4] (rows of invalid ones NaN in both; None, None: no reference columns); RecordingError
    where nothing in them can be an attitude, or roll and pitch are in neither rad nor the deg
    their header states (`units`, find_columns')."""
    from ..broad.metric import gravity_from_quat, gravity_from_roll_pitch

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
        stated = {(units or {}).get(c) for c in ("roll", "pitch")} - {None}
        if len(stated) > 1 or not stated <= {"rad", "deg"}:
            raise RecordingError(f"{path}: the reference's header states the unit(s) "
                                 f"{', '.join(sorted(stated))} for roll and pitch: one of rad "
                                 "or deg serves")
        scale = np.pi / 180.0 if stated == {"deg"} else 1.0
        roll, pitch = cols["roll"] * scale, cols["pitch"] * scale
        if not in_radians(roll, pitch):
            raise RecordingError(
                f"{path}: the reference's roll reaches {float(np.nanmax(np.abs(roll))):.4g} and "
                f"its pitch {float(np.nanmax(np.abs(pitch))):.4g}, beyond pi and pi/2: they "
                "are in degrees? a reference gives roll and pitch in rad, or in deg where its "
                "header says so (roll (deg))")
        return gravity_from_roll_pitch(roll, pitch), None
    return None, None
