"""MEMS IMU error model (the ImuSensor FMU's math), seeded and reproducible.

The default is a realistic MPU-6050-class IMU: every error a user of such a part meets, each
value from the InvenSense MPU-6000/6050 product specification (PS-MPU-6000A-00, rev. 3.4; "DS"
below) or stated as our reading where the datasheet gives a bound, not a distribution:

- white noise density: gyro 0.005 deg/s/sqrt(Hz), accelerometer 400 ug/sqrt(Hz) (DS: rate
  noise spectral density; power spectral density);
- bias left after the usual calibration (calibration="startup"): gyro 0.16 deg/s, accelerometer
  0.5 mg (1 sigma): the DS temperature coefficients (ZRO +-20 deg/s over 125 K, zero-g +-35 mg
  over 70 K) times 1 K of warm-up after the calibration;
- scale and cross-axis errors: gyro 1 % and 0.67 % (DS +-3 % and +-2 % taken as 3 sigma; users
  calibrate a gyro's bias at start-up, not its scale, which needs a turntable); accelerometer
  0.1 % and 0.1 % (our reading of what a six-position calibration, PX4's and ArduPilot's set-up
  step, leaves);
- uncalibrated (calibration="none"): gyro bias 6.7 deg/s, accelerometer 17 mg (x, y), 27 mg (z),
  1 %, 0.67 % (DS initial tolerances +-20 deg/s, +-50/+-80 mg, +-3 %, +-2 % as 3 sigma);
- bias instability, a Gauss-Markov process of 100 s: gyro 0.003 deg/s (about 10 deg/h),
  accelerometer 0.1 mg (the order that Allan-variance studies of the MPU-6050 report; the DS
  gives none);
- digital low-pass filter: DLPF_CFG 0, gyro 256 Hz and 0.98 ms, accelerometer 260 Hz and 0 ms
  (DS register 26; 0 is the register's reset value);
- full-scale range +-2000 deg/s and +-16 g at 16 bits (DS FS_SEL = 3, AFS_SEL = 3);
- gyro sample: a point value (the DLPF's output read at the output rate).

The per-run errors (bias left after calibration, scale factor, cross-axis) are drawn once
from the seed, so every seed is another sensor off the same production line; the noise and the
bias instability are drawn per sample. SENSOR_PRESETS["ideal"] switches everything off but the
white noise (the papers' comparisons, and the contract's noise-free runs with the noise off too).

Noise convention: the parameters are power spectral densities S, the squares of the datasheets'
densities n (S = n^2; FMI 2.0 base units have integer exponents, so n's unit rad/(s.sqrt(Hz))
cannot be declared, S's rad2/s can). A continuous white noise of PSD S sampled over an interval h
has standard deviation sqrt(S / h) (n / sqrt(h); one-sided, per Hz, as datasheets state it). A
bias random walk of PSD K moves the bias by sqrt(K h) (one standard deviation) per interval.

Order of the errors within one sample, as in the part: true rate (its interval mean with
gyro_sampling="mean") -> scale factor and cross-axis -> bias -> white noise -> digital low-pass
filter -> saturation -> quantisation.
"""

from __future__ import annotations

import math
from typing import Any, Final

from .noise import NormalBlocks, normals
from .state import COUNT, REAL, StateSpec, check_field
from .types import (
    DEG,
    MPU6050_ACC_DENSITY,
    MPU6050_GYRO_DENSITY,
    G,
    Param,
    check_param_names,
)

MG = 1e-3 * G
"""One milli-g [m/s^2]."""

DLPF_TABLE: dict[int, tuple[float, float, float, float]] = {
    0: (260.0, 0.0, 256.0, 0.98e-3),
    1: (184.0, 2.0e-3, 188.0, 1.9e-3),
    2: (94.0, 3.0e-3, 98.0, 2.8e-3),
    3: (44.0, 4.9e-3, 42.0, 4.8e-3),
    4: (21.0, 8.5e-3, 20.0, 8.3e-3),
    5: (10.0, 13.8e-3, 10.0, 13.4e-3),
    6: (5.0, 19.0e-3, 5.0, 18.6e-3),
}
"""MPU-6050 DLPF_CFG -> (accelerometer bandwidth [Hz], delay [s], gyro bandwidth [Hz], delay [s])
(DS register 26, CONFIG). 7 (reserved in the DS) is not offered; -1 turns the filter off."""


def dlpf_delay(cfg: int) -> float:
    """The gyro's delay [s] at DLPF_CFG cfg as the datasheet gives it (DLPF_TABLE; 0 with the
    filter off): what a user of the part gives the estimators as sensor_delay, their outputs
    turned ahead over it (docs/guide/own-sensor.md)."""
    return 0.0 if cfg < 0 else DLPF_TABLE[cfg][3]

Calibrated = tuple[tuple[float, float, float], tuple[float, float, float], float, float]
CALIBRATION: dict[str, Calibrated] = {
    "startup": ((0.16 * DEG,) * 3, (0.5 * MG,) * 3, 0.001, 0.001),
    "none": ((20.0 / 3.0 * DEG,) * 3, (50.0 / 3.0 * MG, 50.0 / 3.0 * MG, 80.0 / 3.0 * MG),
             0.01, 0.02 / 3.0),
    "perfect": ((0.0,) * 3, (0.0,) * 3, 0.0, 0.0),
}
"""calibration -> per-axis standard deviations of the per-run errors it leaves: gyro bias
[rad/s], accelerometer bias [m/s^2], accelerometer scale-factor error, accelerometer cross-axis
sensitivity (see the module docstring for the sources). The gyro's scale and cross-axis errors
are parameters of their own: users do not calibrate them."""

SENSOR_PARAMS: tuple[Param, ...] = (
    Param("seed", 0, "Seed of the noise generator and of the per-run errors (same seed, same "
          "sensor and samples)", low=0, high=2**31 - 1, tunable=False),
    Param("gyro_sampling", "point",
          "What the gyro sample is: 'point' (the rate at the sample instant) or 'mean' (the mean "
          "rate over the interval ending at the sample, as integrating IMUs deliver); an "
          "estimator's gyro_sampling must match it", choices=("point", "mean"), tunable=False),
    Param("gyro_psd", MPU6050_GYRO_DENSITY**2,
          "Gyro white-noise power spectral density (the rate-noise density squared; MPU-6050: "
          "(0.005 deg/s/sqrt(Hz))^2)", unit="rad2/s", low=0.0, display_unit="deg2/s"),
    Param("acc_psd", MPU6050_ACC_DENSITY**2,
          "Accelerometer white-noise power spectral density (the noise density squared; "
          "MPU-6050: (400 ug/sqrt(Hz))^2)", unit="m2/s3", low=0.0),
    Param("calibration", "startup",
          "Per-run errors drawn from the seed: 'startup' (what the usual calibration leaves: "
          "gyro bias 0.16 deg/s after averaging at rest at start-up, accelerometer bias 0.5 mg, "
          "scale and cross-axis 0.1 % after a six-position calibration), 'none' (the MPU-6050 "
          "datasheet's tolerances as 3 sigma: 6.7 deg/s, 17-27 mg, 1 %, 0.67 %) or 'perfect'",
          choices=tuple(CALIBRATION), tunable=False),
    *(Param(f"gyro_bias_{a}", 0.0, f"Constant gyro bias added to the per-run one, {a} axis",
            unit="rad/s", display_unit="deg/s") for a in "xyz"),
    *(Param(f"acc_bias_{a}", 0.0, f"Constant accelerometer bias added to the per-run one, {a} axis",
            unit="m/s2") for a in "xyz"),
    Param("gyro_bias_instability", 0.003 * DEG,
          "Gyro bias instability: standard deviation of a first-order Gauss-Markov bias "
          "(time constant bias_time_constant); 0.003 deg/s, about 10 deg/h",
          unit="rad/s", low=0.0, display_unit="deg/s"),
    Param("acc_bias_instability", 0.1 * MG,
          "Accelerometer bias instability: standard deviation of a first-order Gauss-Markov bias "
          "(time constant bias_time_constant); 0.1 mg", unit="m/s2", low=0.0),
    Param("bias_time_constant", 100.0, "Correlation time of the Gauss-Markov bias instability",
          unit="s", low=0.0, low_open=True),
    Param("gyro_bias_psd", 0.0,
          "Gyro bias random-walk power spectral density (the random-walk density squared)",
          unit="rad2/s3", low=0.0, display_unit="deg2/s3"),
    Param("acc_bias_psd", 0.0,
          "Accelerometer bias random-walk power spectral density (the random-walk density "
          "squared)", unit="m2/s5", low=0.0),
    Param("gyro_scale_std", 0.01,
          "Per-run scale-factor error of each gyro axis, standard deviation (MPU-6050 "
          "datasheet +-3 % as 3 sigma)", low=0.0, high=0.5, tunable=False),
    Param("gyro_cross_axis_std", 0.02 / 3.0,
          "Per-run cross-axis sensitivity of every gyro axis pair, standard deviation (MPU-6050 "
          "datasheet +-2 % as 3 sigma)", low=0.0, high=0.5, tunable=False),
    Param("dlpf_cfg", 0,
          "MPU-6050 digital low-pass filter setting DLPF_CFG 0..6 (bandwidth 260/184/94/44/21/10/"
          "5 Hz, delay 0-19 ms; 0 is the register's reset value), or -1 for no filter",
          low=-1, high=6, tunable=False),
    Param("gyro_range", 2000.0 * DEG, "Gyro full-scale range (outputs saturate at +-range)",
          unit="rad/s", low=1e-3, display_unit="deg/s"),  # a converter step stays a double
    Param("acc_range", 16.0 * G, "Accelerometer full-scale range (outputs saturate at +-range)",
          unit="m/s2", low=1e-2),
    Param("bits", 16, "Converter resolution; 0 turns quantisation off", low=0, high=32),
    Param("jitter", 0.0,
          "Standard deviation of the sample-time error: the reported dt is the interval plus the "
          "difference of two successive timestamp errors", unit="s", low=0.0),
)
_SPECS = {p.name: p for p in SENSOR_PARAMS}
"""SENSOR_PARAMS by name."""

SENSOR_PRESETS: dict[str, dict[str, Any]] = {
    "realistic": {},
    "ideal": {"calibration": "perfect", "gyro_bias_instability": 0.0,
              "acc_bias_instability": 0.0, "gyro_scale_std": 0.0, "gyro_cross_axis_std": 0.0,
              "dlpf_cfg": -1},
}
"""Sensor parameter sets: 'realistic' (the defaults: an MPU-6050-class IMU as a user meets it)
and 'ideal' (white noise, range and quantisation only: the sensor of the papers' simulations)."""

N_NORMALS = 19
"""Standard normals drawn per sample: white noise (6), bias random walk (6), Gauss-Markov bias
instability (6), timestamp jitter (1)."""
N_RUN_NORMALS = 30
"""Standard normals of the per-run errors: turn-on biases (6), the gyro's and the
accelerometer's scale and cross-axis errors (9 each), the bias instability's start (6)."""
NOISE_STREAM, RUN_STREAM = 0, 1
"""The streams of fusion_core.noise the sensor draws from: per sample, and once per run."""


def sensor_preset(name: str) -> dict[str, Any]:
    """A copy of a named sensor parameter set (ValueError naming the allowed ones)."""
    if name not in SENSOR_PRESETS:
        raise ValueError(f"unknown sensor {name!r}: allowed {', '.join(SENSOR_PRESETS)}")
    return dict(SENSOR_PRESETS[name])


class LowPass2:
    """A 2nd-order Butterworth low-pass (bilinear transform, pre-warped) on three channels, or a
    pure delay where the corner is beyond what the sample rate can show.

    Stands for the MPU-6050's DLPF at the output rate 1/h: below 0.45/h the datasheet bandwidth
    is the -3 dB corner (whose group delay is then close to the datasheet's delay); above it the
    samples cannot show the magnitude response, and only the datasheet delay is kept, as a
    linear interpolation back by delay/h samples.
    """

    def __init__(self, bandwidth: float, delay: float) -> None:
        self.bandwidth = bandwidth
        self.delay = delay
        self.h = 0.0
        self.coef: tuple[float, ...] = ()
        self.state: list[list[float]] | None = None  # per channel: x1, x2, y1, y2

    def _design(self, h: float) -> None:
        self.h = h
        if self.bandwidth >= 0.45 / h:
            self.coef = (min(self.delay / h, 1.0),)
            return
        k = math.tan(math.pi * self.bandwidth * h)
        norm = 1.0 / (1.0 + math.sqrt(2.0) * k + k * k)
        b0 = k * k * norm
        a1 = 2.0 * (k * k - 1.0) * norm
        a2 = (1.0 - math.sqrt(2.0) * k + k * k) * norm
        self.coef = (b0, 2.0 * b0, b0, a1, a2)

    def __call__(self, x: list[float], h: float) -> list[float]:
        if h != self.h:
            self._design(h)
        if self.state is None:  # start at rest at the first value (no transient)
            self.state = [[v, v, v, v] for v in x]
        out = []
        for v, s in zip(x, self.state, strict=True):
            if len(self.coef) == 1:
                y = v - self.coef[0] * (v - s[0])
            else:
                b0, b1, b2, a1, a2 = self.coef
                y = b0 * v + b1 * s[0] + b2 * s[1] - a1 * s[2] - a2 * s[3]
            s[1], s[0], s[3], s[2] = s[0], v, s[2], y
            out.append(y)
        return out


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
        # Counter-based noise (fusion_core.noise): sample k's normals depend on (seed, k) only,
        # the same in the C twin and whatever the partition of the run into steps.
        self.k = 0  # samples drawn so far
        self._noise = NormalBlocks(p["seed"], NOISE_STREAM, N_NORMALS)
        # The per-run errors from a stream of their own, so that they do not shift the noise.
        r = normals(p["seed"], RUN_STREAM, 0, 1, N_RUN_NORMALS)[0].tolist()
        gyro_std, acc_std, acc_scale, acc_cross = CALIBRATION[p["calibration"]]
        self.gyro_turn_on = [r[i] * gyro_std[i] for i in range(3)]
        self.acc_turn_on = [r[3 + i] * acc_std[i] for i in range(3)]
        self.gyro_matrix = _error_matrix(r[6:15], p["gyro_scale_std"], p["gyro_cross_axis_std"])
        self.acc_matrix = _error_matrix(r[15:24], acc_scale, acc_cross)
        self.gyro_walk = [0.0, 0.0, 0.0]  # random walk (gyro_bias_psd)
        self.acc_walk = [0.0, 0.0, 0.0]
        # Gauss-Markov bias instability, started from its stationary distribution
        self.gyro_gm = [v * p["gyro_bias_instability"] for v in r[24:27]]
        self.acc_gm = [v * p["acc_bias_instability"] for v in r[27:30]]
        self.omega_prev: list[float] | None = None
        self.time_error = 0.0
        cfg = int(p["dlpf_cfg"])
        if cfg < 0:
            self.acc_filter: LowPass2 | None = None
            self.gyro_filter: LowPass2 | None = None
        else:
            acc_bw, acc_delay, gyro_bw, gyro_delay = DLPF_TABLE[cfg]
            self.acc_filter = LowPass2(acc_bw, acc_delay)
            self.gyro_filter = LowPass2(gyro_bw, gyro_delay)

    @property
    def gyro_bias(self) -> list[float]:
        """The gyro bias now [rad/s]: constant + per-run + random walk + bias instability."""
        p = self.params
        return [p[f"gyro_bias_{a}"] + self.gyro_turn_on[i] + self.gyro_walk[i] + self.gyro_gm[i]
                for i, a in enumerate("xyz")]

    @property
    def acc_bias(self) -> list[float]:
        """The accelerometer bias now [m/s^2]."""
        p = self.params
        return [p[f"acc_bias_{a}"] + self.acc_turn_on[i] + self.acc_walk[i] + self.acc_gm[i]
                for i, a in enumerate("xyz")]

    def sample(
        self, omega: tuple[float, float, float], f: tuple[float, float, float], h: float
    ) -> tuple[tuple[float, float, float], tuple[float, float, float], float]:
        """The IMU sample taken at the end of an interval h: (acc, gyro, dt)."""
        p = self.params
        if not h > 0.0:
            raise ValueError(f"interval h={h!r} s must be > 0")
        z = self._noise.at(self.k)
        self.k += 1
        rate = list(omega)
        if p["gyro_sampling"] == "mean":
            # the rate's mean over the interval, the rate taken linear between its ends
            prev = self.omega_prev if self.omega_prev is not None else rate
            self.omega_prev = rate
            rate = [0.5 * (a + b) for a, b in zip(prev, rate, strict=True)]
        gw, aw = math.sqrt(p["gyro_bias_psd"] * h), math.sqrt(p["acc_bias_psd"] * h)
        decay = math.exp(-h / p["bias_time_constant"])
        drive = math.sqrt(1.0 - decay * decay)
        g_gm, a_gm = drive * p["gyro_bias_instability"], drive * p["acc_bias_instability"]
        for i in range(3):
            self.gyro_walk[i] += gw * z[6 + i]
            self.acc_walk[i] += aw * z[9 + i]
            self.gyro_gm[i] = decay * self.gyro_gm[i] + g_gm * z[12 + i]
            self.acc_gm[i] = decay * self.acc_gm[i] + a_gm * z[15 + i]
        gn, an = math.sqrt(p["gyro_psd"] / h), math.sqrt(p["acc_psd"] / h)
        gb, ab = self.gyro_bias, self.acc_bias
        gyro = [v + gb[i] + gn * z[i] for i, v in enumerate(_apply(self.gyro_matrix, rate))]
        acc = [v + ab[i] + an * z[3 + i] for i, v in enumerate(_apply(self.acc_matrix, f))]
        if self.gyro_filter is not None and self.acc_filter is not None:
            gyro = self.gyro_filter(gyro, h)
            acc = self.acc_filter(acc, h)
        # a host's step h carries the rounding of its time grid (t_k+1 - t_k: 0.01 as
        # 0.009999999999999787): without jitter the sample's dt is h to the picosecond
        dt = math.floor(h * 1e12 + 0.5) / 1e12
        if p["jitter"] > 0.0:
            new_error = p["jitter"] * z[18]
            dt = max(h + new_error - self.time_error, 1e-6 * h)
            self.time_error = new_error
        return (_convert(acc, p["acc_range"], p["bits"]),
                _convert(gyro, p["gyro_range"], p["bits"]), dt)

    def run(self, omega: Any, f: Any, h: Any, backend: str = "auto") -> dict[str, Any]:
        """N samples at once: true rates omega and specific forces f [N, 3], intervals h [N] or
        a scalar. Returns numpy arrays acc, gyro [N, 3], dt [N] and gyro_bias [N, 3] (the true
        bias at each sample). backend as in Estimator.run: "native" (fusion_core.native's
        twin, fc_sensor.c), "python" or "auto" (native where available); the same samples to
        1e-12 either way, and the model's state afterwards is the same."""
        import numpy as np

        from .base import check_backend

        check_backend(backend)
        omega = np.asarray(omega, dtype=float)
        f = np.asarray(f, dtype=float)
        if omega.ndim != 2 or omega.shape[1] != 3 or f.shape != omega.shape:
            raise ValueError(f"omega and f must both have shape [N, 3]: got {omega.shape} and "
                             f"{f.shape}")
        n = omega.shape[0]
        hs = np.broadcast_to(np.asarray(h, dtype=float), (n,))
        if backend != "python":
            from . import native

            if native.available():
                return native.sensor_run(self, omega, f, hs)
            if backend == "native":
                raise ValueError(f"backend='native': the C twin is unavailable: "
                                 f"{native.reason()}")
        out = {"acc": np.empty((n, 3)), "gyro": np.empty((n, 3)), "dt": np.empty(n),
               "gyro_bias": np.empty((n, 3))}
        for i, (w, a, step) in enumerate(zip(omega.tolist(), f.tolist(), hs.tolist(),
                                             strict=True)):
            out["acc"][i], out["gyro"][i], out["dt"][i] = self.sample(tuple(w), tuple(a), step)
            out["gyro_bias"][i] = self.gyro_bias
        return out

    def set_param(self, name: str, value: Any) -> None:
        """Change a tunable parameter between samples (a constant bias takes its value now)."""
        check_param_names((name,), _SPECS, "the IMU sensor model")
        spec = _SPECS[name]
        if not spec.tunable:
            raise ValueError(f"sensor parameter {name!r} is fixed after the start")
        self.params[name] = spec.validate(value)

    STATE: Final[StateSpec] = {
        "k": COUNT, "gyro_turn_on": REAL, "acc_turn_on": REAL, "gyro_matrix": REAL,
        "acc_matrix": REAL, "gyro_walk": REAL, "acc_walk": REAL, "gyro_gm": REAL, "acc_gm": REAL,
        "omega_prev": REAL, "time_error": REAL,
    }
    """The model's state, each field with the check a restored value must pass
    (fusion_core.state; omega_prev may also be None, before the first sample); besides it, the
    DLPF's state: None before the first sample, else 3 channels of 4 values."""

    def get_state(self) -> dict[str, Any]:
        state = {name: _copy(getattr(self, name)) for name in self.STATE}
        for name in ("gyro_filter", "acc_filter"):
            filt = getattr(self, name)
            state[name] = None if filt is None or filt.state is None else _copy(filt.state)
        return {"params": dict(self.params), **state}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a get_state() result. Everything is checked first (parameters by their
        ranges, every state field by its check): ValueError naming what is wrong, and the model
        is unchanged."""
        if not isinstance(state, dict) or not isinstance(state.get("params"), dict):
            raise ValueError("a sensor state is a dict with the 'params' dict")
        params = state["params"]
        check_param_names(params, _SPECS, "the IMU sensor model")
        missing = sorted(set(_SPECS) - set(params))
        if missing:
            raise ValueError(f"sensor state lacks the parameter(s) {', '.join(missing)}")
        checked = {k: _SPECS[k].validate(v) for k, v in params.items()}
        fresh = ImuSensorModel(**checked)
        for name, check in self.STATE.items():
            if name not in state:
                raise ValueError(f"sensor state lacks {name}")
            if name == "omega_prev" and state[name] is None:
                continue
            template = [0.0, 0.0, 0.0] if name == "omega_prev" else getattr(fresh, name)
            check_field(name, check, state[name], template)
        for name in ("gyro_filter", "acc_filter"):
            value = state.get(name)
            if value is not None:
                if getattr(fresh, name) is None:
                    raise ValueError(f"sensor state holds {name} but dlpf_cfg is off")
                check_field(name, REAL, value, [[0.0] * 4] * 3)
        self.params = checked
        self.reset()
        for name in self.STATE:
            setattr(self, name, _copy(state[name]))
        for name in ("gyro_filter", "acc_filter"):
            filt = getattr(self, name)
            if filt is not None:
                filt.state = _copy(state.get(name))


def _copy(value: Any) -> Any:
    """A plain copy of a list of floats, a list of lists, a float or None."""
    if isinstance(value, (list, tuple)):
        return [_copy(v) for v in value]
    return value


def _error_matrix(z: list[float], scale_std: float, cross_std: float) -> list[list[float]]:
    """I + diag(scale errors) + cross-axis terms off the diagonal: measured = M true; z holds 9
    standard normals, the 3 scale errors' and the 6 cross-axis terms' in row order."""
    cross = iter(z[3:9])
    return [[1.0 + z[i] * scale_std if i == j else next(cross) * cross_std for j in range(3)]
            for i in range(3)]


def _apply(m: list[list[float]], v: Any) -> list[float]:
    return [m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2] for i in range(3)]


def _saturate(v: float, full_scale: float) -> float:
    """v clipped to [-full_scale, full_scale] (a NaN stays NaN)."""
    v = v if v > -full_scale else -full_scale
    return v if full_scale > v else full_scale


def _convert(v: list[float], full_scale: float, bits: int) -> tuple[float, float, float]:
    """Saturate at +-full_scale, then round to the converter's step 2 full_scale / 2^bits."""
    x, y, z = (_saturate(c, full_scale) for c in v)
    if bits:
        lsb = 2.0 * full_scale / 2.0**bits
        return round(x / lsb) * lsb, round(y / lsb) * lsb, round(z / lsb) * lsb
    return x, y, z
