"""The sensor's calibration at every estimator's input: calibrated = matrix (raw - offset).

A MEMS IMU's largest errors after its bias are the scale factors and the misalignment of its
axes (a few percent and a few tenths of a degree on consumer parts). A 6D filter cannot learn
them in motion (linear acceleration of a few tenths of a g hides the tenths of a degree they
cause), so the engineer calibrates the part before use (testbenches.calibrate: static poses
and the rotations between them, Tedaldi et al. 2014; or Ferraris et al. 1995) and the filter
applies the result to every sample before anything else reads it:

    acc_calibrated  = acc_cal  (acc_raw  - acc_off)
    gyro_calibrated = gyro_cal (gyro_raw - gyro_off)

then the mounting rotation turns both into the filter frame. The matrix takes scale, the
axes' misalignment and cross-coupling; the offset the bias. The sample rules (finite values,
max_rate) and the gyro's rail (gyro_range) judge the sensor's own readings, before calibration:
they are properties of the part's converter.

Every estimator has the 24 parameters (CALIBRATION_PARAMS; fixed after construction, like the
mounting): `acc_cal_xx` ... `acc_cal_zz` (row, then column), `acc_off_x` ... `acc_off_z` [m/s2],
and the same for the gyro [rad/s]. `Calibration` reads and writes the calibration file
(`calibration.json`: `acc_cal` and `gyro_cal`, each {"matrix": 3x3, "offset": 3} in SI units)
and gives the parameters.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

from .linalg import Mat9
from .types import Param, read_json

AXES: Final = ("x", "y", "z")
SENSORS: Final = ("acc", "gyro")
OFFSET_UNIT: Final = {"acc": "m/s2", "gyro": "rad/s"}
OFFSET_LIMIT: Final = {"acc": 100.0, "gyro": 10.0}
"""The largest offset a part may have: 10 g, 570 deg/s (a consumer part's turn-on bias is below
1 m/s2 and 0.5 rad/s)."""
DIAGONAL_RANGE: Final = (0.8, 1.25)
"""The scale a calibration may apply to an axis: a working MEMS part's scale error is a few
percent (the MPU-6050's +-3 %), far inside 20 %; a swapped or lost axis is no calibration (a
turned sensor is the mounting's business)."""
OFF_DIAGONAL_LIMIT: Final = 0.2
"""The largest cross-coupling a calibration may apply (about 11 deg of misalignment: the
MPU-6050's cross-axis sensitivity is +-2 %, but a part soldered askew on its board, or a
session whose poses are the faces of a case the part sits in at an angle, adds the angle to
the case; imucal's example session has 6 deg)."""
FILE_ENTRIES: Final = ("units", "method", "input_units", "gravity", "recording", "acc", "gyro",
                       "poses", "static_intervals", "detector", "turn_degrees", "sections",
                       "held_out", "comparisons", "filled", "level")
"""What a calibration file may hold beside acc_cal and gyro_cal: what `imu-fusion calibrate`
measured and how (units must be the SI ones the matrices and offsets are in)."""
MAX_CONDITION: Final = 3.0
"""The entries' ranges keep a calibration matrix's condition number (largest over smallest
singular value) below this for any combination of them (2.74 at the worst corner; 1 for the
identity): no matrix they allow is singular or amplifies one axis's noise against another's
beyond what a part's own scale errors do."""


def matrix_names(sensor: str) -> tuple[str, ...]:
    """The parameter names of sensor's matrix, row by row: acc_cal_xx, acc_cal_xy, ..."""
    return tuple(f"{sensor}_cal_{r}{c}" for r in AXES for c in AXES)


def offset_names(sensor: str) -> tuple[str, ...]:
    """The parameter names of sensor's offset: acc_off_x, acc_off_y, acc_off_z."""
    return tuple(f"{sensor}_off_{a}" for a in AXES)


def _params(sensor: str) -> tuple[Param, ...]:
    what = {"acc": "accelerometer", "gyro": "gyro"}[sensor]
    matrix = tuple(
        Param(name, 1.0 if name[-1] == name[-2] else 0.0,
              f"Calibration of the {what}: row {name[-2]}, column {name[-1]} of the matrix in "
              f"calibrated = {sensor}_cal ({sensor} - {sensor}_off) (scale on the diagonal, "
              "misalignment and cross-coupling off it; the identity: none)",
              unit="1", low=DIAGONAL_RANGE[0] if name[-1] == name[-2] else -OFF_DIAGONAL_LIMIT,
              high=DIAGONAL_RANGE[1] if name[-1] == name[-2] else OFF_DIAGONAL_LIMIT,
              tunable=False)
        for name in matrix_names(sensor))
    offset = tuple(
        Param(name, 0.0,
              f"Calibration of the {what}: the {name[-1]} offset subtracted from the raw "
              f"reading before the matrix (the part's bias as the calibration measured it)",
              unit=OFFSET_UNIT[sensor], low=-OFFSET_LIMIT[sensor], high=OFFSET_LIMIT[sensor],
              display_unit="deg/s" if sensor == "gyro" else None, tunable=False)
        for name in offset_names(sensor))
    return matrix + offset


CALIBRATION_PARAMS: Final[tuple[Param, ...]] = _params("acc") + _params("gyro")
"""The calibration every estimator applies to its input (identity and zero by default)."""
SPECS: Final[dict[str, Param]] = {p.name: p for p in CALIBRATION_PARAMS}

Vec3 = tuple[float, float, float]
IDENTITY: Final[Mat9] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def condition_number(m: Sequence[float]) -> float:
    """Largest over smallest singular value of the 3x3 matrix m (row by row); inf if singular."""
    import numpy as np

    s = np.linalg.svd(np.asarray(m, dtype=float).reshape(3, 3), compute_uv=False)
    return math.inf if s[-1] == 0.0 else float(s[0] / s[-1])


def check_matrix(sensor: str, m: Sequence[float]) -> None:
    """ValueError naming the entry and its range where a calibration matrix has an entry that
    is not finite or out of range (CALIBRATION_PARAMS); within the ranges no matrix is singular
    or badly conditioned (MAX_CONDITION)."""
    for name, v in zip(matrix_names(sensor), m, strict=True):
        if not math.isfinite(v):
            raise ValueError(f"calibration {sensor}_cal: entry {name}={float(v)!r} is not finite")
        spec = SPECS[name]
        if not spec.low <= v <= spec.high:  # type: ignore[operator]
            raise ValueError(f"calibration {sensor}_cal: entry {name}={float(v)!r} is out of "
                             f"range: allowed {spec.allowed()}")


def matrices(values: Mapping[str, Any]) -> dict[str, tuple[Mat9, Vec3]]:
    """Each sensor's (matrix, offset) from parameter values."""
    return {s: (tuple(float(values[n]) for n in matrix_names(s)),  # type: ignore[misc]
                tuple(float(values[n]) for n in offset_names(s)))
            for s in SENSORS}


def check_calibration(values: Mapping[str, Any]) -> None:
    """Estimator construction's check of the calibration parameters (check_matrix for each)."""
    for sensor, (m, _) in matrices(values).items():
        if m != IDENTITY:
            check_matrix(sensor, m)


@dataclass(frozen=True)
class Calibration:
    """A part's calibration: per sensor a 3x3 matrix (row by row) and an offset, in SI units;
    calibrated = matrix (raw - offset). Read from and written to calibration.json."""

    acc_matrix: Mat9 = IDENTITY
    acc_offset: Vec3 = (0.0, 0.0, 0.0)
    gyro_matrix: Mat9 = IDENTITY
    gyro_offset: Vec3 = (0.0, 0.0, 0.0)
    extra: dict[str, Any] = field(default_factory=dict, compare=False)
    """What the file holds beside the model (units, poses, residuals, uncertainties)."""

    def __post_init__(self) -> None:
        for sensor in SENSORS:
            check_matrix(sensor, getattr(self, f"{sensor}_matrix"))

    def params(self) -> dict[str, float]:
        """The estimators' parameters of this calibration."""
        out: dict[str, float] = {}
        for sensor in SENSORS:
            out.update(zip(matrix_names(sensor), getattr(self, f"{sensor}_matrix"), strict=True))
            out.update(zip(offset_names(sensor), getattr(self, f"{sensor}_offset"), strict=True))
        return out

    @classmethod
    def from_params(cls, values: Mapping[str, Any]) -> Calibration:
        """The calibration of estimator parameters (params' inverse; a name left out keeps
        its default)."""
        full = {p.name: values.get(p.name, p.default) for p in CALIBRATION_PARAMS}
        (am, ao), (gm, go) = matrices(full).values()
        return cls(am, ao, gm, go)

    def apply(self, acc: Any, gyro: Any) -> tuple[Any, Any]:
        """Calibrated arrays [N, 3] of raw ones, as the estimators compute them."""
        import numpy as np

        def one(sensor: str, raw: Any) -> Any:
            m = np.asarray(getattr(self, f"{sensor}_matrix")).reshape(3, 3)
            d = np.asarray(raw, dtype=float) - np.asarray(getattr(self, f"{sensor}_offset"))
            return d @ m.T

        return one("acc", acc), one("gyro", gyro)

    def to_json(self) -> dict[str, Any]:
        """The file's content: acc_cal and gyro_cal as {"matrix": 3x3, "offset": 3}, then extra."""
        doc: dict[str, Any] = {}
        for sensor in SENSORS:
            m = getattr(self, f"{sensor}_matrix")
            doc[f"{sensor}_cal"] = {"matrix": [list(m[i:i + 3]) for i in (0, 3, 6)],
                                    "offset": list(getattr(self, f"{sensor}_offset"))}
        doc.update(self.extra)
        return doc

    def write(self, path: Path) -> None:
        path.write_text(json.dumps(self.to_json(), indent=1) + "\n")

    @classmethod
    def from_json(cls, doc: Mapping[str, Any], where: str = "calibration") -> Calibration:
        """From the file's content; ValueError saying which entry is missing or wrong (a file
        with neither acc_cal nor gyro_cal calibrates nothing, and is refused as not one)."""
        if not any(f"{sensor}_cal" in doc for sensor in SENSORS):
            raise ValueError(f"{where}: no acc_cal or gyro_cal entry, so not a calibration (it "
                             f"holds {', '.join(map(repr, doc)) or 'nothing'}); `imu-fusion "
                             "calibrate` writes one")
        unknown = [k for k in doc if k not in (*(f"{s}_cal" for s in SENSORS), *FILE_ENTRIES)]
        if unknown:
            raise ValueError(f"{where}: unknown entr{'y' if len(unknown) == 1 else 'ies'} "
                             f"{', '.join(map(repr, unknown))}: a calibration file holds acc_cal "
                             f"and gyro_cal, and beside them {', '.join(FILE_ENTRIES)}")
        units = doc.get("units")
        if units is not None:
            wrong = {s: units.get(s) for s in SENSORS if isinstance(units, dict)
                     and units.get(s) not in (None, OFFSET_UNIT[s])}
            if not isinstance(units, dict) or wrong:
                raise ValueError(f"{where}: units {units!r}: the file's offsets are in m/s2 "
                                 "(acc) and rad/s (gyro), and say so or nothing")
        fields: dict[str, Any] = {}
        for sensor in SENSORS:
            key = f"{sensor}_cal"
            part = doc.get(key, {"matrix": [IDENTITY[i:i + 3] for i in (0, 3, 6)],
                                 "offset": [0.0, 0.0, 0.0]})
            if not isinstance(part, dict) or set(part) != {"matrix", "offset"}:
                got = ", ".join(map(repr, part)) if isinstance(part, dict) else repr(part)
                raise ValueError(f"{where}: {key} must be {{\"matrix\": 3x3 numbers, "
                                 f"\"offset\": 3 numbers}} and nothing else; it holds {got}")
            try:
                rows = part["matrix"]
                m = tuple(float(v) for row in rows for v in row)
                o = tuple(float(v) for v in part["offset"])
            except (KeyError, TypeError, ValueError) as err:
                raise ValueError(f"{where}: {key} must be {{\"matrix\": 3x3 numbers, \"offset\": "
                                 f"3 numbers}} ({type(err).__name__}: {err})") from None
            if len(rows) != 3 or len(m) != 9 or len(o) != 3:
                raise ValueError(f"{where}: {key} must hold a 3x3 matrix and 3 offsets")
            limit = OFFSET_LIMIT[sensor]
            for name, v in zip(offset_names(sensor), o, strict=True):
                if not (math.isfinite(v) and abs(v) <= limit):
                    raise ValueError(f"{where}: {name}={v!r} is not finite or beyond +-{limit:g} "
                                     f"{OFFSET_UNIT[sensor]}")
            fields[f"{sensor}_matrix"], fields[f"{sensor}_offset"] = m, o
        extra = {k: v for k, v in doc.items() if k not in ("acc_cal", "gyro_cal")}
        try:
            return cls(**fields, extra=extra)
        except ValueError as err:
            raise ValueError(f"{where}: {err}") from None

    @classmethod
    def read(cls, path: Path | str) -> Calibration:
        """calibration.json; ValueError (or FileNotFoundError) saying what is wrong."""
        doc = read_json(path, "calibration file")
        if not isinstance(doc, dict):
            raise ValueError(f"{path}: expected an object with acc_cal and gyro_cal")
        return cls.from_json(doc, str(path))
