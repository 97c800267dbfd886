"""MEMS IMU error model (the ImuSensor FMU's math): noise, bias, bias random walk, range,
quantisation and timestamp jitter, seeded and reproducible.

Defaults are the MPU-6050 datasheet's: gyro rate-noise density 0.005 deg/s/sqrt(Hz), accelerometer
noise density 400 ug/sqrt(Hz), full-scale ranges +-2000 deg/s and +-16 g, 16-bit converters.

Noise convention: the parameters are power spectral densities S, the squares of the datasheets'
densities n (S = n^2; FMI 2.0 base units have integer exponents, so n's unit rad/(s.sqrt(Hz))
cannot be declared, S's rad2/s can). A continuous white noise of PSD S sampled over an interval h
has standard deviation sqrt(S / h) (n / sqrt(h); one-sided, per Hz, as datasheets state it). A
bias random walk of PSD K moves the bias by sqrt(K h) (one standard deviation) per interval.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .types import (
    DEG,
    MPU6050_ACC_DENSITY,
    MPU6050_GYRO_DENSITY,
    G,
    Param,
    check_param_names,
)

SENSOR_PARAMS: tuple[Param, ...] = (
    Param("seed", 0, "Seed of the noise generator (same seed, same samples)", low=0, high=2**31 - 1,
          tunable=False),
    Param("gyro_psd", MPU6050_GYRO_DENSITY**2,
          "Gyro white-noise power spectral density (the rate-noise density squared; MPU-6050: "
          "(0.005 deg/s/sqrt(Hz))^2)", unit="rad2/s", low=0.0, display_unit="deg2/s"),
    Param("acc_psd", MPU6050_ACC_DENSITY**2,
          "Accelerometer white-noise power spectral density (the noise density squared; "
          "MPU-6050: (400 ug/sqrt(Hz))^2)", unit="m2/s3", low=0.0),
    *(Param(f"gyro_bias_{a}", 0.0, f"Constant gyro bias, {a} axis", unit="rad/s",
            display_unit="deg/s") for a in "xyz"),
    *(Param(f"acc_bias_{a}", 0.0, f"Constant accelerometer bias, {a} axis", unit="m/s2")
      for a in "xyz"),
    Param("gyro_bias_psd", 0.0,
          "Gyro bias random-walk power spectral density (the random-walk density squared)",
          unit="rad2/s3", low=0.0, display_unit="deg2/s3"),
    Param("acc_bias_psd", 0.0,
          "Accelerometer bias random-walk power spectral density (the random-walk density "
          "squared)", unit="m2/s5", low=0.0),
    Param("gyro_range", 2000.0 * DEG, "Gyro full-scale range (outputs saturate at +-range)",
          unit="rad/s", low=0.0, low_open=True, display_unit="deg/s"),
    Param("acc_range", 16.0 * G, "Accelerometer full-scale range (outputs saturate at +-range)",
          unit="m/s2", low=0.0, low_open=True),
    Param("bits", 16, "Converter resolution; 0 turns quantisation off", low=0, high=32),
    Param("jitter", 0.0,
          "Standard deviation of the sample-time error: the reported dt is the interval plus the "
          "difference of two successive timestamp errors", unit="s", low=0.0),
)
_SPECS = {p.name: p for p in SENSOR_PARAMS}
"""SENSOR_PARAMS by name."""


class ImuSensorModel:
    """Turn true body rates and specific force into IMU samples, one interval at a time."""

    PARAMS = SENSOR_PARAMS

    def __init__(self, **params: Any) -> None:
        check_param_names(params, _SPECS, "the IMU sensor model")
        self.params: dict[str, Any] = {name: spec.default for name, spec in _SPECS.items()}
        self.params.update({k: _SPECS[k].validate(v) for k, v in params.items()})
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
        # Written out per axis: this runs once per testbench step (the ImuSensor FMU's doStep).
        gb, ab = self.gyro_bias, self.acc_bias
        gw, aw = math.sqrt(p["gyro_bias_psd"] * h), math.sqrt(p["acc_bias_psd"] * h)
        gb[0] += gw * z[6]
        gb[1] += gw * z[7]
        gb[2] += gw * z[8]
        ab[0] += aw * z[9]
        ab[1] += aw * z[10]
        ab[2] += aw * z[11]
        gn, an = math.sqrt(p["gyro_psd"] / h), math.sqrt(p["acc_psd"] / h)
        gyro = _convert(omega[0] + gb[0] + gn * z[0], omega[1] + gb[1] + gn * z[1],
                        omega[2] + gb[2] + gn * z[2], p["gyro_range"], p["bits"])
        acc = _convert(f[0] + ab[0] + an * z[3], f[1] + ab[1] + an * z[4],
                       f[2] + ab[2] + an * z[5], p["acc_range"], p["bits"])
        dt = h
        if p["jitter"] > 0.0:
            new_error = p["jitter"] * z[12]
            dt = max(h + new_error - self.time_error, 1e-6 * h)
            self.time_error = new_error
        return acc, gyro, dt

    def set_param(self, name: str, value: Any) -> None:
        """Change a tunable parameter between samples (a bias takes its new value now)."""
        check_param_names((name,), _SPECS, "the IMU sensor model")
        spec = _SPECS[name]
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


def _saturate(v: float, full_scale: float) -> float:
    """v clipped to [-full_scale, full_scale] (a NaN stays NaN)."""
    v = v if v > -full_scale else -full_scale
    return v if full_scale > v else full_scale


def _convert(
    x: float, y: float, z: float, full_scale: float, bits: int
) -> tuple[float, float, float]:
    """Saturate at +-full_scale, then round to the converter's step 2 full_scale / 2^bits."""
    x, y, z = _saturate(x, full_scale), _saturate(y, full_scale), _saturate(z, full_scale)
    if bits:
        lsb = 2.0 * full_scale / 2.0**bits
        return round(x / lsb) * lsb, round(y / lsb) * lsb, round(z / lsb) * lsb
    return x, y, z
