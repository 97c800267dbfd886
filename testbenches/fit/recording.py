"""Recordings as arrays in SI units: the Recording every command works on, and `load` for a
CSV file in SI units or a BROAD trial (the commands read theirs with the options they are given,
testbenches.estimate.recording_from_args; both through the one reader, testbenches.reader).

CSV: a header row naming the columns (testbenches.estimate.ALIASES); the accelerometer and the
gyro are required; `time` or `dt` give the sampling (else --rate); a reference for `tune` is
either quaternion columns q_w, q_x, q_y, q_z (sensor to world) or roll and pitch [rad]. BROAD
trials (HDF5 or .mat, testbenches.broad.data) bring their own rate and reference, and `rest()`
finds their rest segment (the start, before `movement` begins).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..broad.data import NotABroadTrial, load_trial
from ..broad.metric import gravity_from_quat

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
    """A BROAD trial (by content) or a CSV file in SI units (m/s^2, rad/s), read by the one
    reader (testbenches.estimate.load_recording, which checks the units against the data);
    RecordingError saying what is wrong."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        trial = load_trial(path)
    except NotABroadTrial:
        from ..estimate import load_recording

        return load_recording(path, rate=rate, acc_unit="m/s2", gyro_unit="rad/s")[0]
    up = gravity_from_quat(trial.opt_quat)
    return Recording(trial.name, trial.acc, trial.gyro, np.full(trial.n, trial.dt), trial.rate,
                     trial.gyro_sampling, up, trial.movement & np.all(np.isfinite(up), axis=1),
                     trial.sensor_delay)


def rest(rec: Recording) -> Recording:
    """A BROAD trial's rest segment: the samples before its first movement sample (the whole
    recording when it has no movement flags)."""
    if rec.counts is None or not np.any(rec.counts):
        return rec
    first = int(np.argmax(rec.counts))
    return rec.slice(0, first)
