"""Recordings for `noise` and `tune`: a CSV file or a BROAD trial, as arrays in SI units.

CSV: a header row naming the columns; acc_x, acc_y, acc_z [m/s^2] and gyro_x, gyro_y, gyro_z
[rad/s] are required; `time` [s] or `dt` [s] give the sampling (else --rate); a reference for
`tune` is either quaternion columns q_w, q_x, q_y, q_z (sensor to a z-up frame, as BROAD's) or
roll and pitch [rad]. BROAD trials (HDF5 or .mat, testbenches.broad.data) bring their own rate and
reference, and `rest()` finds their rest segment (the start, before `movement` begins).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..broad.data import NotABroadTrial, load_trial
from ..broad.metric import gravity_from_quat, gravity_from_roll_pitch

IMU_COLUMNS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")
QUAT_COLUMNS = ("q_w", "q_x", "q_y", "q_z")


class RecordingError(ValueError):
    """A file that cannot serve: what is wrong and what is allowed."""


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
    """Which columns, units and rate were taken, and why (testbenches.estimate.load_recording)."""

    @property
    def sensor(self) -> dict[str, Any]:
        """The estimators' parameters that describe the recording's sensor."""
        return {"gyro_sampling": self.gyro_sampling, "sensor_delay": self.sensor_delay}

    @property
    def counted(self) -> np.ndarray:
        """The samples a score counts (all of them where the recording does not say)."""
        return self.counts if self.counts is not None else np.ones(len(self.dt), dtype=bool)

    @property
    def duration(self) -> float:
        return float(np.sum(self.dt))

    def slice(self, start: int, stop: int) -> Recording:
        return Recording(
            self.name, self.acc[start:stop], self.gyro[start:stop], self.dt[start:stop],
            self.rate, self.gyro_sampling,
            None if self.up_ref is None else self.up_ref[start:stop],
            None if self.counts is None else self.counts[start:stop], self.sensor_delay,
        )


def load(path: str | Path, rate: float | None = None) -> Recording:
    """A BROAD trial (by content) or a CSV file; RecordingError saying what is missing."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        trial = load_trial(path)
    except NotABroadTrial:
        return _load_csv(path, rate)
    up = gravity_from_quat(trial.opt_quat)
    return Recording(trial.name, trial.acc, trial.gyro, np.full(trial.n, trial.dt), trial.rate,
                     trial.gyro_sampling, up, trial.movement & np.all(np.isfinite(up), axis=1),
                     trial.sensor_delay)


def csv_header_rows(path: Path) -> tuple[list[str], list[list[str]]]:
    """A CSV file's header (names stripped) and its non-empty rows; RecordingError for an empty
    file."""
    with path.open(newline="") as fh:
        reader = csv.reader(fh)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise RecordingError(f"{path}: empty file") from None
        return header, [r for r in reader if r]


def _load_csv(path: Path, rate: float | None) -> Recording:
    header, rows = csv_header_rows(path)
    missing = [c for c in IMU_COLUMNS if c not in header]
    if missing:
        raise RecordingError(
            f"{path}: missing column(s) {', '.join(missing)}; a recording needs acc_x, acc_y, "
            "acc_z [m/s^2], gyro_x, gyro_y, gyro_z [rad/s], optionally time or dt [s] and, for "
            "tune, q_w, q_x, q_y, q_z or roll, pitch [rad] (or a BROAD trial file)")
    try:
        data = np.array(rows, dtype=float)
    except ValueError as err:
        raise RecordingError(f"{path}: a value is not a number ({err})") from None
    col = {name: data[:, i] for i, name in enumerate(header)}
    n = len(data)
    if n < 2:
        raise RecordingError(f"{path}: {n} sample(s); a recording needs many")
    if "dt" in col:
        dt = col["dt"].copy()
    elif "time" in col:
        dt = np.diff(col["time"], prepend=col["time"][0] - np.median(np.diff(col["time"])))
    elif rate:
        dt = np.full(n, 1.0 / rate)
    else:
        raise RecordingError(f"{path}: no time or dt column: give the sampling rate (--rate HZ)")
    nominal = 1.0 / rate if rate else float(np.median(dt[1:]))
    dt[0] = nominal
    up = None
    if all(c in col for c in QUAT_COLUMNS):
        up = gravity_from_quat(np.column_stack([col[c] for c in QUAT_COLUMNS]))
    elif "roll" in col and "pitch" in col:
        up = gravity_from_roll_pitch(col["roll"], col["pitch"])
    acc = np.column_stack([col[c] for c in IMU_COLUMNS[:3]])
    gyro = np.column_stack([col[c] for c in IMU_COLUMNS[3:]])
    counts = None if up is None else np.all(np.isfinite(up), axis=1)
    return Recording(path.stem, acc, gyro, dt, 1.0 / nominal, "point", up, counts)


def rest(rec: Recording) -> Recording:
    """A BROAD trial's rest segment: the samples before its first movement sample (the whole
    recording when it has no movement flags)."""
    if rec.counts is None or not np.any(rec.counts):
        return rec
    first = int(np.argmax(rec.counts))
    return rec.slice(0, first)
