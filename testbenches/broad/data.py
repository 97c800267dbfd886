"""BROAD trials: loading either of the dataset's file formats, and the dataset's trial groups.

BROAD (Laidig, Caruso, Cereatti, Seel. "BROAD - A Benchmark for Robust Inertial Orientation
Estimation". Data 6(7):72, 2021, doi:10.3390/data6070072) ships every trial twice, as HDF5 (the
sampling rate is a file attribute) and as a MATLAB v5 .mat file (a variable); both hold the same
fields. A trial has `imu_acc` [N, 3] m/s^2, `imu_gyr` [N, 3] rad/s, `imu_mag` [N, 3] uT (unused
here), `opt_quat` [N, 4] (w first, sensor frame to an ENU-like global frame, NaN where the markers
were not visible), `opt_pos` [N, 3] m, `movement` [N] (the samples that count for the error
metric) and `sampling_rate` [Hz]. The IMU and the optical reference are already synchronised and
the reference frame is aligned to the sensor frame (the file's `info` says so), so no alignment
step is needed before comparing them.

`load_trial` reads any such file by its content (not its extension) and refuses anything else
with a `NotABroadTrial` error that says what is missing.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

REQUIRED_FIELDS = ("imu_acc", "imu_gyr", "opt_quat", "movement", "sampling_rate")
"""The fields a 6D evaluation needs; a file without one of them is not a BROAD trial."""

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
MAT5_MAGIC = b"MATLAB 5.0 MAT-file"

GROUP_ORDER = (
    "undisturbed", "disturbed", "rotation", "translation", "combined", "slow", "fast",
    "no_breaks", "with_breaks", "tapping", "vibration", "stationary_magnet", "attached_magnet",
    "office_environment", "mixed",
)
"""BROAD's groups (trials.json) below `all_trials`, in the dataset's order."""

_NAME_GROUPS: tuple[tuple[str, str], ...] = (
    # (regular expression on the trial name, group), the dataset's naming scheme
    (r"(^|_)undisturbed_", "undisturbed"),
    (r"(^|_)disturbed_", "disturbed"),
    (r"_rotation(_|$)", "rotation"),
    (r"_translation(_|$)", "translation"),
    (r"_combined(_|$)", "combined"),
    (r"_slow_", "slow"),
    (r"_fast_", "fast"),
    (r"_with_breaks(_|$)", "with_breaks"),
    (r"_tapping(_|$)", "tapping"),
    (r"_vibration(_|$)", "vibration"),
    (r"_stationary_magnet(_|$)", "stationary_magnet"),
    (r"_attached_magnet(_|$)", "attached_magnet"),
    (r"_office(_|$)", "office_environment"),
    (r"_mixed(_|$)", "mixed"),
)


class NotABroadTrial(ValueError):
    """The file is not a BROAD trial (wrong format, or fields missing or of the wrong shape)."""


@dataclass(frozen=True)
class BroadTrial:
    """One BROAD trial, arrays as float64 (movement as bool), rows in time order."""

    name: str
    path: Path
    acc: np.ndarray
    """imu_acc [N, 3], specific force in m/s^2 (reads about (0, 0, +g) lying level)."""
    gyro: np.ndarray
    """imu_gyr [N, 3], rad/s."""
    opt_quat: np.ndarray
    """[N, 4] reference orientation, w first, sensor to global (z up); NaN rows: no reference."""
    movement: np.ndarray
    """[N] bool: the samples the error metric counts."""
    rate: float
    """sampling_rate [Hz]."""
    gyro_sampling: str = "mean"
    """What the gyro sample is (the estimators' gyro_sampling): BROAD's myon aktos-t delivers
    the mean rate over the interval ending at each sample (integrating the gyro from the optical
    reference over 0.5 s windows of the fast-rotation trials, the rectangle rule lands closer
    to the reference than the trapezoid rule)."""
    sensor_delay: float = 2.4e-3
    """How long the IMU's samples lag the optical reference [s] (the estimators' sensor_delay):
    shifting the gyro's integration window against the reference's rotation
    (testbenches.broad.gyro.fit_delay, no estimator involved) fits best about 0.7 of a sample
    later on every one of the 13 published trials (docs/results/broad.md, "What the errors came
    from"); the
    sensor's internal filters and the time-stamping of its samples against the cameras', the
    same in every trial. Uncorrected it is an error of rate x delay in every output (0.4 deg at
    180 deg/s)."""

    @property
    def n(self) -> int:
        return int(self.acc.shape[0])

    @property
    def dt(self) -> float:
        """The sample period [s]."""
        return 1.0 / self.rate

    @property
    def duration(self) -> float:
        return self.n / self.rate

    def head(self, seconds: float) -> BroadTrial:
        """The first `seconds` of the trial (for short tests and quick looks)."""
        k = max(1, min(self.n, round(seconds * self.rate)))
        return replace(
            self, acc=self.acc[:k], gyro=self.gyro[:k], opt_quat=self.opt_quat[:k],
            movement=self.movement[:k],
        )


def load_trial(path: str | Path) -> BroadTrial:
    """Read a BROAD trial from an HDF5 or MATLAB v5 file (the format is sniffed from the content).

    Raises NotABroadTrial (a ValueError) naming the file and the problem for anything that is not
    a BROAD trial, FileNotFoundError for a missing file.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    with path.open("rb") as f:
        head = f.read(1024)
    if head.startswith(HDF5_SIGNATURE) or head[512:520] == HDF5_SIGNATURE:
        fields, info = _read_hdf5(path)  # BROAD's .hdf5 (or a MATLAB v7.3 file, which is HDF5)
    elif head.startswith(MAT5_MAGIC):
        fields, info = _read_mat5(path)
    else:
        raise NotABroadTrial(
            f"{path}: not a BROAD trial: the file is neither HDF5 nor a MATLAB v5 .mat file"
        )
    return _trial_from_fields(path, fields, info)


def _read_hdf5(path: Path) -> tuple[dict[str, Any], str]:
    try:
        import h5py
    except ImportError as err:  # pragma: no cover - h5py is a dependency of the broad command
        raise ImportError(
            "reading BROAD's HDF5 files needs h5py: pip install 'h5py>=3.8'"
        ) from err
    fields: dict[str, Any] = {}
    try:
        with h5py.File(path, "r") as f:
            for name in REQUIRED_FIELDS:
                if name in f and isinstance(f[name], h5py.Dataset):
                    fields[name] = f[name][()]
                elif name in f.attrs:
                    fields[name] = f.attrs[name]
            info = f.attrs.get("info", "")
    except (OSError, RuntimeError, KeyError, ValueError) as err:  # h5py's for a damaged or
        # cut file ("truncated file: eof = ...", "addr overflow" as it follows a link)
        raise NotABroadTrial(f"{path}: not a BROAD trial: unreadable HDF5 file ({err})") from None
    return fields, info.decode() if isinstance(info, bytes) else str(info)


def _read_mat5(path: Path) -> tuple[dict[str, Any], str]:
    import scipy.io

    try:
        mat = scipy.io.loadmat(path, variable_names=[*REQUIRED_FIELDS, "info"])
    except Exception as err:  # scipy raises several types for damaged files
        raise NotABroadTrial(f"{path}: not a BROAD trial: unreadable .mat file ({err})") from None
    info = mat.get("info")
    text = str(np.asarray(info).ravel()[0]) if info is not None and np.size(info) else ""
    return {k: mat[k] for k in REQUIRED_FIELDS if k in mat}, text


def _as_rows(a: Any, width: int) -> np.ndarray:
    """A [N, width] float array; a MATLAB v7.3 file stores the transpose."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 2 and a.shape[1] != width and a.shape[0] == width:
        a = a.T
    return a


def _trial_from_fields(path: Path, fields: Mapping[str, Any], info: str) -> BroadTrial:
    missing = [k for k in REQUIRED_FIELDS if k not in fields]
    if missing:
        raise NotABroadTrial(
            f"{path}: not a BROAD trial: missing field(s) {', '.join(missing)} "
            f"(a BROAD trial has {', '.join(REQUIRED_FIELDS)})"
        )
    acc = _as_rows(fields["imu_acc"], 3)
    gyro = _as_rows(fields["imu_gyr"], 3)
    quat = _as_rows(fields["opt_quat"], 4)
    movement = np.asarray(fields["movement"]).ravel()
    rate_arr = np.asarray(fields["sampling_rate"], dtype=float).ravel()
    n = acc.shape[0] if acc.ndim == 2 else -1
    problems = []
    if acc.ndim != 2 or acc.shape[1] != 3:
        problems.append(f"imu_acc has shape {acc.shape}, expected [N, 3]")
    if gyro.shape != acc.shape:
        problems.append(f"imu_gyr has shape {gyro.shape}, expected {acc.shape}")
    if quat.shape != (n, 4):
        problems.append(f"opt_quat has shape {quat.shape}, expected [{n}, 4]")
    if movement.shape != (n,):
        problems.append(f"movement has {movement.size} values, expected {n}")
    if rate_arr.size != 1 or not math.isfinite(rate_arr[0]) or rate_arr[0] <= 0.0:
        problems.append(f"sampling_rate is {rate_arr.tolist()}, expected one positive number")
    if problems:
        raise NotABroadTrial(f"{path}: not a BROAD trial: {'; '.join(problems)}")
    return BroadTrial(
        name=_trial_name(path, info),
        path=path,
        acc=np.ascontiguousarray(acc),
        gyro=np.ascontiguousarray(gyro),
        opt_quat=np.ascontiguousarray(quat),
        movement=movement.astype(bool),
        rate=float(rate_arr[0]),
    )


def _trial_name(path: Path, info: str) -> str:
    """The trial's name from the file's `info` text ('Trial: NAME'), else the file name."""
    m = re.search(r"^Trial:\s*(\S+)", info, re.MULTILINE)
    return m.group(1) if m else path.stem


# ----- groups ------------------------------------------------------------------------------------
def load_trials_json(path: str | Path) -> dict[str, Any]:
    """BROAD's trials.json (groups and the groups of every trial)."""
    with Path(path).open() as f:
        data = json.load(f)
    if not isinstance(data, dict) or "trials" not in data:
        raise ValueError(f"{path}: not BROAD's trials.json (no 'trials')")
    return data


def find_trials_json(paths: Iterable[str | Path]) -> Path | None:
    """trials.json beside the first trial file that has one."""
    for p in paths:
        candidate = Path(p).parent / "trials.json"
        if candidate.is_file():
            return candidate
    return None


def trial_groups(name: str, trials_json: Mapping[str, Any] | None = None) -> list[str]:
    """The BROAD groups of a trial: from trials.json when it lists the trial, otherwise from the
    dataset's naming scheme (NN_undisturbed_slow_rotation_with_breaks_A, NN_disturbed_tapping_B,
    ...). `all_trials` is left out (every trial is in it)."""
    if trials_json is not None and name in trials_json.get("trials", {}):
        groups = trials_json["trials"][name].get("groups", [])
    else:
        groups = [g for pattern, g in _NAME_GROUPS if re.search(pattern, name)]
        if "undisturbed" in groups and "with_breaks" not in groups:
            groups.append("no_breaks")
    return [g for g in GROUP_ORDER if g in groups] + sorted(
        g for g in groups if g not in GROUP_ORDER and g != "all_trials"
    )


__all__ = [
    "GROUP_ORDER",
    "REQUIRED_FIELDS",
    "BroadTrial",
    "NotABroadTrial",
    "find_trials_json",
    "load_trial",
    "load_trials_json",
    "trial_groups",
]
