"""Shared types and constants of fusion_core: the estimate, the bad-sample error, parameter specs,
and the reading of a JSON file of parameters.

Conventions (docs/interface.md): SI units; body frame x forward,
y left, z up; the accelerometer measures specific force, so a sensor lying still and level reads
(0, 0, +G); attitude is Z-Y-X Euler (yaw, pitch, roll), roll in (-pi, pi], pitch in [-pi/2, pi/2].
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, NamedTuple

G: Final = 9.80665
"""Standard gravity [m/s^2]; the accelerometer norm of a sensor at rest."""

DEG: Final = math.pi / 180.0
"""One degree in radians."""

MPU6050_GYRO_DENSITY: Final = 0.005 * DEG
"""MPU-6050 datasheet gyro rate-noise density [rad/s/sqrt(Hz)]; its square is the PSD [rad2/s]."""
MPU6050_ACC_DENSITY: Final = 400e-6 * G
"""MPU-6050 datasheet accelerometer noise density, 400 ug/sqrt(Hz) [m/s^2/sqrt(Hz)]."""
RUN_CHUNK: Final = 1024
"""Samples that run() converts to Python floats and collects at a time."""
GYRO_RANGE_DEFAULT: Final = 2000.0 * DEG
"""Default gyro_range [rad/s]: +-2000 deg/s, the widest setting of the MPU-6050 class of consumer
MEMS gyros (the realistic sensor model's range)."""
ABSENT: Final[dict[str, float]] = {"gyro_range": math.inf}
"""What a shared parameter (base.COMMON_PARAMS) a class leaves out amounts to: without gyro_range
(the papers' filters know no gyro range) no sample is at a rail."""


class Estimate(NamedTuple):
    """One estimator output: the estimate at the time of the sample just processed.

    roll, pitch [rad]; bias = (bias_x, bias_y, bias_z) gyro bias estimate [rad/s] (zeros for an
    estimator without a bias state). pos, vel [m, m/s] only from the position filter.
    """

    roll: float
    pitch: float
    bias: tuple[float, float, float]
    pos: tuple[float, float, float] | None = None
    vel: tuple[float, float, float] | None = None


class InvalidSample(ValueError):
    """A sample that the estimator refused; the estimator state is exactly as before the call."""


UNIT_LIMITS: Final[dict[str, float]] = {
    "s": 1e6,        # a time constant, window or interval of 11.6 days acts as "never"
    "rad/s": 1e4,    # 573,000 deg/s: ten times the largest accepted gyro reading by default
    "m/s2": 1e4,     # about 1,000 g, beyond which a reading is no reading (base.MAX_ACC_NORM)
    "m/s": 1e3,      # a speed threshold or noise of 1 km/s
    "rad2": 1e2,     # an angle's variance: a standard deviation of 10 rad knows no angle
    "rad2/s": 1.0,   # a rate noise density of 57 deg/s/sqrt(Hz), 10^4 times a MEMS gyro's
    "rad2/s3": 1.0,  # a rate random walk of 57 deg/s/sqrt(s)
    "m2/s3": 1e4,    # an acceleration noise density of 100 m/s^2/sqrt(Hz)
    "m2/s5": 1e4,    # a jerk (or acceleration random walk) density of 100 m/s^3/sqrt(Hz)
}
"""The range of a numeric parameter of each unit that states none of its own: far beyond any
physical value, and small enough that the filters' arithmetic (squares, products of a few such
values) cannot overflow. Every numeric parameter's range is finite, so that any value a host may
set keeps every estimate finite (tests/test_params.py sweeps each range's ends)."""


@dataclass(frozen=True)
class Param:
    """Declarative description of one tuning parameter, shared by fusion_core and fmu_src.

    A numeric parameter is valid when low <(=) value <(=) high (open or closed bounds); a string
    parameter when it is one of `choices`. `unit` is an SI unit string ("1" when dimensionless),
    `display_unit` a friendlier unit for tools (for example "deg2/s"), `tunable` whether it may be
    changed between samples of a running filter. A bound left out is the unit's limit
    (UNIT_LIMITS): -limit below, +limit above.
    """

    name: str
    default: float | int | bool | str
    description: str
    unit: str = "1"
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple[str, ...] | None = None
    display_unit: str | None = None
    tunable: bool = True

    def __post_init__(self) -> None:
        limit = UNIT_LIMITS.get(self.unit)
        if limit is not None and self.choices is None and not isinstance(self.default, bool):
            if self.high is None:
                object.__setattr__(self, "high", limit)
            if self.low is None:
                object.__setattr__(self, "low", -limit)

    @property
    def kind(self) -> type:
        return type(self.default)

    def allowed(self) -> str:
        """The allowed range in words, for error messages."""
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind is bool:
            return "True or False"
        lo = "-inf" if self.low is None else repr(self.low)
        hi = "inf" if self.high is None else repr(self.high)
        return f"{'(' if self.low_open or self.low is None else '['}{lo}, {hi}" + (
            ")" if self.high_open or self.high is None else "]"
        )

    def validate(self, value: object) -> float | int | bool | str:
        """Return the value converted to the parameter's type, or raise ValueError naming it."""
        where = f"parameter {self.name!r}={value!r}"
        if self.choices is not None:
            if value not in self.choices:
                raise ValueError(f"{where} is not allowed: expected {self.allowed()}")
            return value  # type: ignore[return-value]
        if self.kind is bool:
            if not isinstance(value, (bool, int)) or value not in (0, 1):
                raise ValueError(f"{where} is not allowed: expected True or False")
            return bool(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where} is not a number: allowed range {self.allowed()}")
        if self.kind is int and float(value) != int(value):
            raise ValueError(f"{where} is not a whole number: allowed range {self.allowed()}")
        v = float(value)
        ok = math.isfinite(v) or (v == math.inf and self.high is None)
        if self.low is not None:
            ok = ok and (v > self.low if self.low_open else v >= self.low)
        if self.high is not None:
            ok = ok and (v < self.high if self.high_open else v <= self.high)
        if not ok:
            raise ValueError(f"{where} is out of range: allowed {self.allowed()} {self.unit}")
        return int(v) if self.kind is int else v


RENAMED_PARAMS: dict[str, str] = {
    "gyro_noise": "gyro_psd",
    "bias_noise": "bias_psd",
    "zaru_noise": "zaru_psd",
    "acc_noise": "acc_psd",
    "gyro_bias_walk": "gyro_bias_psd",
    "acc_bias_walk": "acc_bias_psd",
}
"""Noise parameters renamed in 0.2.0, when the noise densities n [rad/(s.sqrt(Hz)), ...] became
power spectral densities n^2 [rad2/s, ...]: FMI 2.0 base units have integer exponents only."""


REPLACED_PARAMS: dict[str, str] = {
    "integration": "integration is now gyro_sampling, a property of the sensor: 'trapezoid' -> "
    "'point', 'rectangle' -> 'mean'",
}
"""Parameters replaced by one of another meaning, with what to write instead."""


def check_param_names(given: Iterable[str], specs: dict[str, Param], owner: str) -> None:
    """ValueError listing the names in `given` that `owner` does not have, what it allows, and
    the new name of a renamed noise parameter (whose value must now be squared)."""
    unknown = sorted(set(given) - set(specs))
    if not unknown:
        return
    hints = [
        f"{name} is now {RENAMED_PARAMS[name]}, the density squared (a power spectral density)"
        for name in unknown if RENAMED_PARAMS.get(name) in specs
    ] + [REPLACED_PARAMS[name] for name in unknown if name in REPLACED_PARAMS]
    raise ValueError(
        f"unknown parameter(s) {', '.join(unknown)} for {owner}: allowed {', '.join(specs)}"
        + "".join(f"; {h}" for h in hints)
    )


class MissingFile(FileNotFoundError, ValueError):
    """A file of parameters that is not there: a FileNotFoundError, and a ValueError as every
    other fault of such a file is, so that a caller catching either kind catches it."""


def read_json(path: Path | str, what: str) -> Any:
    """The JSON document of a file of parameters (a calibration, a preset, a sensor):
    MissingFile where there is none, ValueError where it is no JSON, each naming `what`
    ("calibration file") and the path."""
    path = Path(path)
    if not path.is_file():
        raise MissingFile(f"{what} {path}: no such file")
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ValueError(f"{what} {path}: not JSON ({err})") from None
