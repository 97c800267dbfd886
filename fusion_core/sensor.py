"""MEMS IMU error model (the ImuSensor FMU's math): noise, bias, bias random walk, range,
quantisation and timestamp jitter, seeded and reproducible.

Defaults are the MPU-6050 datasheet's: gyro rate-noise density 0.005 deg/s/sqrt(Hz), accelerometer
noise density 400 ug/sqrt(Hz), full-scale ranges +-2000 deg/s and +-16 g, 16-bit converters.

Noise convention: a continuous white noise of density n sampled over an interval h has standard
deviation n / sqrt(h) (the density is one-sided per sqrt(Hz), as datasheets state it). A bias
random walk of density k moves the bias by k sqrt(h) (one standard deviation) per interval.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .types import DEG, G, Param

SENSOR_PARAMS: tuple[Param, ...] = (
    Param("seed", 0, "Seed of the noise generator (same seed, same samples)", low=0, high=2**31 - 1,
          tunable=False),
    Param("gyro_noise", 0.005 * DEG, "Gyro white-noise density", unit="rad/(s.sqrt(Hz))",
          low=0.0, display_unit="deg/(s.sqrt(Hz))"),
    Param("acc_noise", 400e-6 * G, "Accelerometer white-noise density", unit="m/(s2.sqrt(Hz))",
          low=0.0),
    *(Param(f"gyro_bias_{a}", 0.0, f"Constant gyro bias, {a} axis", unit="rad/s",
            display_unit="deg/s") for a in "xyz"),
    *(Param(f"acc_bias_{a}", 0.0, f"Constant accelerometer bias, {a} axis", unit="m/s2")
      for a in "xyz"),
    Param("gyro_bias_walk", 0.0, "Gyro bias random-walk density", unit="rad/(s.sqrt(s))", low=0.0),
    Param("acc_bias_walk", 0.0, "Accelerometer bias random-walk density", unit="m/(s2.sqrt(s))",
          low=0.0),
    Param("gyro_range", 2000.0 * DEG, "Gyro full-scale range (outputs saturate at +-range)",
          unit="rad/s", low=0.0, low_open=True, display_unit="deg/s"),
    Param("acc_range", 16.0 * G, "Accelerometer full-scale range (outputs saturate at +-range)",
          unit="m/s2", low=0.0, low_open=True),
    Param("bits", 16, "Converter resolution; 0 turns quantisation off", low=0, high=32),
    Param("jitter", 0.0,
          "Standard deviation of the sample-time error: the reported dt is the interval plus the "
          "difference of two successive timestamp errors", unit="s", low=0.0),
)


class ImuSensorModel:
    """Turn true body rates and specific force into IMU samples, one interval at a time."""

    PARAMS = SENSOR_PARAMS

    def __init__(self, **params: Any) -> None:
        specs = {p.name: p for p in SENSOR_PARAMS}
        unknown = sorted(set(params) - set(specs))
        if unknown:
            raise ValueError(f"unknown sensor parameter(s) {', '.join(unknown)}: allowed "
                             f"{', '.join(specs)}")
        self.params = {name: spec.default for name, spec in specs.items()}
        self.params.update({k: specs[k].validate(v) for k, v in params.items()})
        self.reset()

    def reset(self) -> None:
        p = self.params
        self.rng = np.random.Generator(np.random.PCG64(p["seed"]))
        self.gyro_bias = [p[f"gyro_bias_{a}"] for a in "xyz"]
        self.acc_bias = [p[f"acc_bias_{a}"] for a in "xyz"]
        self.time_error = 0.0

    def sample(
        self, omega: tuple[float, float, float], f: tuple[float, float, float], h: float
    ) -> tuple[tuple[float, float, float], tuple[float, float, float], float]:
        """The IMU sample taken at the end of an interval h: (acc, gyro, dt)."""
        p = self.params
        if not h > 0.0:
            raise ValueError(f"interval h={h!r} s must be > 0")
        z = self.rng.standard_normal(13).tolist()
        sq = math.sqrt(h)
        for i in range(3):
            self.gyro_bias[i] += p["gyro_bias_walk"] * sq * z[6 + i]
            self.acc_bias[i] += p["acc_bias_walk"] * sq * z[9 + i]
        gn, an = p["gyro_noise"] / sq, p["acc_noise"] / sq
        gyro = [omega[i] + self.gyro_bias[i] + gn * z[i] for i in range(3)]
        acc = [f[i] + self.acc_bias[i] + an * z[3 + i] for i in range(3)]
        gyro = _convert(gyro, p["gyro_range"], p["bits"])
        acc = _convert(acc, p["acc_range"], p["bits"])
        dt = h
        if p["jitter"] > 0.0:
            new_error = p["jitter"] * z[12]
            dt = max(h + new_error - self.time_error, 1e-6 * h)
            self.time_error = new_error
        return acc, gyro, dt

    def set_param(self, name: str, value: Any) -> None:
        """Change a tunable parameter between samples (a bias takes its new value now)."""
        spec = next((p for p in SENSOR_PARAMS if p.name == name), None)
        if spec is None:
            raise ValueError(f"unknown sensor parameter {name!r}")
        if not spec.tunable:
            raise ValueError(f"sensor parameter {name!r} is fixed after the start")
        self.params[name] = spec.validate(value)
        for prefix, bias in (("gyro_bias_", self.gyro_bias), ("acc_bias_", self.acc_bias)):
            if name.startswith(prefix):
                bias["xyz".index(name[-1])] = self.params[name]

    def get_state(self) -> dict[str, Any]:
        return {
            "params": dict(self.params),
            "rng": self.rng.bit_generator.state,
            "gyro_bias": list(self.gyro_bias),
            "acc_bias": list(self.acc_bias),
            "time_error": self.time_error,
        }

    def set_state(self, state: dict[str, Any]) -> None:
        self.params = dict(state["params"])
        self.rng = np.random.Generator(np.random.PCG64())
        self.rng.bit_generator.state = state["rng"]
        self.gyro_bias = [float(v) for v in state["gyro_bias"]]
        self.acc_bias = [float(v) for v in state["acc_bias"]]
        self.time_error = float(state["time_error"])


def _convert(values: list[float], full_scale: float, bits: int) -> tuple[float, float, float]:
    """Saturate at +-full_scale, then round to the converter's step 2 full_scale / 2^bits."""
    out = [min(full_scale, max(-full_scale, v)) for v in values]
    if bits:
        lsb = 2.0 * full_scale / 2.0**bits
        out = [round(v / lsb) * lsb for v in out]
    return out[0], out[1], out[2]
