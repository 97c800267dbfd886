"""The step API that every estimator shares: parameters, input checks, run, state.

The input stage every estimator shares is declared here once: its parameters (COMMON_PARAMS:
the gyro sampling rule, the sample limits, mounting, calibration, gyro range, sensor delay) and
its work on each sample (Estimator._prepare; the C twin's fc_base_configure and
fc_base_prepare). A subclass declares PARAMS (its own filter's parameters only) and STATE (the
attributes that make up its internal state, each with the check a restored value must pass:
fusion_core.state), and
implements `_reset()`, `_init(...)`, `_estimate()` and `_update(ax, ay, az, gx, gy, gz, dt)`, or
instead of `_update` the hot-path form `_advance(ax, ay, az, gx, gy, gz, dt)`, which also
returns the estimate (one call less per sample). Everything else (validation, the first-sample
rule, batch runs, json state) is written once here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar, Final, NamedTuple

import numpy as np

from .building_blocks.sampling import GYRO_SAMPLING_PARAM
from .calibration import CALIBRATION_PARAMS, check_calibration, matrices
from .kinematics import roll_pitch_ahead
from .linalg import Mat9, Vec3, mat_vec, vec_sub
from .state import BASE_STATE, NESTED, StateSpec, check_field
from .types import (
    ABSENT,
    GYRO_RANGE_DEFAULT,
    RUN_CHUNK,
    Estimate,
    G,
    InvalidSample,
    Param,
    check_param_names,
)

MAX_RATE_DEFAULT: Final = 1000.0
"""Default max_rate [rad/s] (57,300 deg/s): about three times the widest full-scale range of any
MEMS gyro we know of (Analog Devices ADXRS649, +-20,000 deg/s; consumer parts such as the
MPU-6050 end at +-2000 deg/s). A larger reading is no measurement."""
RAIL_MARGIN: Final = 1e-3
"""A gyro reading within this fraction of gyro_range is at the rail: a 16-bit converter's last
code is 0.003 % below its range, and no rate the sensor measured sits that close to it unless it
clipped."""
MOUNTING_PARAMS: tuple[Param, ...] = tuple(
    Param(
        f"mount_{axis}", 0.0,
        f"Mounting: {axis} angle of the rotation from the sensor frame to the filter frame "
        "(Z-Y-X: yaw, then pitch, then roll), applied to every sample at the input, as flight "
        "stacks' board-rotation setting; all three 0: the sensor's axes are the filter's",
        unit="rad", low=-math.pi, high=math.pi, display_unit="deg", tunable=False,
    )
    for axis in ("roll", "pitch", "yaw")
)
"""The mounting rotation (interface v2): a sensor resting in any orientation (x up, upside
down, turned on its side) is given as the rotation that takes its axes to the filter's, so that
every estimator sees the body frame of docs/interface.md."""
COMMON_PARAMS: tuple[Param, ...] = (
    GYRO_SAMPLING_PARAM,
    Param(
        "max_dt", 1.0, "Longest accepted time between samples; a longer dt is rejected",
        unit="s", low=0.0, low_open=True, tunable=True,
    ),
    Param(
        "max_rate", MAX_RATE_DEFAULT,
        "Largest accepted gyro reading (norm of the rate vector); a larger one is rejected: no "
        "sensor delivers it (default about 3x the widest MEMS gyro range, +-20,000 deg/s)",
        unit="rad/s", low=0.0, low_open=True, display_unit="deg/s",
    ),
    *MOUNTING_PARAMS,
    *CALIBRATION_PARAMS,
    Param(
        "gyro_range", GYRO_RANGE_DEFAULT,
        "The gyro's full-scale range: a sample with an axis at it (within 0.1 %) is at the rail, "
        "no measurement of the rate, which may be anything beyond it; the filters learn no bias "
        "from it, their attitude's uncertainty grows, and their accelerometer pre-filter starts "
        "again after it (a sensor property, default the MPU-6050's +-2000 deg/s)",
        unit="rad/s", low=1e-3, display_unit="deg/s", tunable=False,
    ),
    Param(
        "sensor_delay", 0.0,
        "How long the sensor's samples lag the instants they are read at (its internal "
        "filters' group delay, e.g. the MPU-6050 DLPF's 0.98-19 ms): the roll and pitch outputs "
        "are turned ahead over it with the last bias-corrected rate, so they are the attitude at "
        "the sample's time stamp; the filter's state is not changed (0: outputs as estimated)",
        unit="s", low=0.0, high=0.1,
    ),
)
MIN_INIT_NORM: Final = 0.1 * G
"""Accelerometer norm [m/s^2] a sample needs to initialise roll and pitch: below it (free fall,
a thrown body) there is no gravity direction to start from, and the filter waits for the next
sample (skipped, not rejected: nothing has been estimated yet)."""
MAX_ACC_NORM: Final = 1000.0 * G
"""Accelerometer norm [m/s^2] beyond which a reading is taken as no reading at all, (0, 0, 0),
like a sample in free fall: far beyond any MEMS accelerometer's range (+-16 g for the MPU-6050,
+-200 g for high-g parts such as the ADXL375), and too large to filter without overflow. The
gyro of such a sample is still integrated."""
NEVER_ESTIMATED: Final = "always 0"
"""How the reason of a bias output the filter never estimates begins (Estimator.ZERO_BIAS)."""
BACKENDS: Final = ("auto", "python", "native")
"""Estimator.run's backends."""
_MIN_INIT_NORM2: Final = MIN_INIT_NORM * MIN_INIT_NORM
_MAX_ACC_NORM2: Final = MAX_ACC_NORM * MAX_ACC_NORM


IDENTITY: Final[Mat9] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
ZERO3: Final = (0.0, 0.0, 0.0)


def mounting_matrix(roll: float, pitch: float, yaw: float) -> Mat9:
    """The rotation matrix Rz(yaw) Ry(pitch) Rx(roll), row by row, that takes a vector from
    the sensor frame to the filter frame; exactly the identity for zero angles, and with
    exact zeros and ones for right angles (cosines and sines of multiples of pi/2 rounded), so
    that a right-angle mounting permutes the axes without rounding."""
    def cs(a: float) -> tuple[float, float]:
        c, s = math.cos(a), math.sin(a)
        quarter = a / (0.5 * math.pi)
        if abs(quarter - round(quarter)) < 1e-12:
            c, s = float(round(c)), float(round(s))
        return c, s

    cr, sr = cs(roll)
    cp, sp = cs(pitch)
    cy, sy = cs(yaw)
    return (
        cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
        sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
        -sp, cp * sr, cp * cr,
    )


def check_backend(backend: str) -> None:
    """ValueError unless backend is one of BACKENDS (Estimator.run, ImuSensorModel.run)."""
    if backend not in BACKENDS:
        raise ValueError(f"backend={backend!r} is not allowed: expected one of "
                         f"{', '.join(repr(b) for b in BACKENDS)}")


def _plain(value: Any) -> Any:
    """A json-serialisable copy of a state value (tuples become lists)."""
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _restore(template: Any, value: Any) -> Any:
    """value in the shape of template (lists back to tuples where the state holds tuples, named
    tuples to their own type)."""
    if isinstance(template, tuple):
        items = tuple(_restore(t, v) for t, v in zip(template, value, strict=True))
        return type(template)(*items) if hasattr(template, "_fields") else items
    if isinstance(template, list):  # a list may change length (queues): match what is there
        n = len(template)
        return [_restore(template[i] if i < n else None, v) for i, v in enumerate(value)]
    if isinstance(template, bool):  # (before int: a bool is an int)
        return bool(value)
    if isinstance(template, int):
        return int(value)
    if isinstance(template, float):
        return float(value)
    return value


class SensorNoise(NamedTuple):
    """A sensor's noise as `imu-fusion noise` measures it at rest: what the parameters of
    Estimator.noise_params follow from (presets.noise_preset)."""

    gyro_density: float
    """Gyro white-noise density [rad/s/sqrt(Hz)]: the Allan deviation at tau = 1 s."""
    acc_density: float
    """Accelerometer white-noise density [m/s^2/sqrt(Hz)]."""
    acc_sample_std: float
    """Standard deviation of one accelerometer sample at rest [m/s^2], at the rate the filter
    runs."""
    gyro_bias_std: float = 0.0
    """Spread (1 sigma, per axis) of the gyro bias a part starts a run with [rad/s]: what a
    start-up calibration leaves, or a datasheet's turn-on tolerance for a part run without
    one."""


class Estimator:
    """Base class of the estimators. See the module docstring."""

    PARAMS: ClassVar[tuple[Param, ...]] = ()
    STATE: ClassVar[StateSpec] = {}
    TWIN: ClassVar[str | None] = None
    """The C twin's prefix (fusion_core/native: fc_cf for fc_cf_step, fc_cf_run, ...) where this
    exact class has one; a subclass, which may change the Python methods, has none of its own."""
    HAS_POSITION: ClassVar[bool] = False
    ZERO_BIAS: ClassVar[dict[str, str]] = {}
    """The bias outputs this filter may leave at 0, each with the reason (its FMU's variable
    descriptions say it): one it never estimates begins with NEVER_ESTIMATED, one that stays 0
    until something observes it says what; the others are estimated."""
    BIAS_IN_MOTION: ClassVar[tuple[int, ...]] = ()
    """The gyro axes (0 x, 1 y, 2 z) whose bias the filter learns while it moves, not only at
    rest: those the contract scores the bias error of."""
    SCANNED: ClassVar[tuple[str, ...]] = ()
    """The parameters sensor physics fixes nothing for, whose recommended values came from a
    coarse scan: what `imu-fusion tune` fits by default (the class docstring says why each).
    The noise-derived ones come from `imu-fusion noise`, the rest detector's thresholds and the
    pre-filter's time constant are VQF's published values: fitting those too on a handful of
    recordings fits the recordings' motions, not the sensor."""
    GYRO_ONLY: ClassVar[dict[str, float] | None] = None
    """Parameter values with which only the gyro moves roll and pitch, on samples whose
    accelerometer reads 3 g (the accelerometer's corrections off or gated out): what the tests
    of the integration rule run; None where the class has no such setting (the tests run its
    paper's filter instead)."""
    COMMON: ClassVar[tuple[Param, ...]] = COMMON_PARAMS
    """The parameters every estimator shares (a paper's reference filter, which knows no gyro
    range, leaves gyro_range out: fusion_core.papers)."""

    @classmethod
    def noise_params(cls, noise: SensorNoise) -> dict[str, float]:
        """The parameters of this filter that follow from a sensor's noise, by the derivation
        its recommended defaults come from (presets.noise_preset adds the gyro range for every
        estimator); none by default."""
        return {}

    def __init__(self, **params: Any) -> None:
        specs = self.param_specs()
        check_param_names(params, specs, type(self).__name__)
        values = {name: spec.default for name, spec in specs.items()}
        values.update({name: specs[name].validate(v) for name, v in params.items()})
        check_calibration(values)
        self._check_params(values)
        self._set_params(values)
        self.reset()

    # ----- parameters -------------------------------------------------------------------------
    @classmethod
    def param_specs(cls) -> dict[str, Param]:
        """Every parameter of this estimator by name, in declaration order."""
        return {p.name: p for p in (*cls.PARAMS, *cls.COMMON)}

    @property
    def params(self) -> dict[str, Any]:
        """A copy of the current parameter values."""
        return dict(self._params)

    def set_param(self, name: str, value: Any) -> None:
        """Change one tunable parameter of a running filter (the state is kept)."""
        specs = self.param_specs()
        check_param_names((name,), specs, type(self).__name__)
        if not specs[name].tunable:
            raise ValueError(f"parameter {name!r} is fixed after construction: use a new instance")
        values = dict(self._params)
        values[name] = specs[name].validate(value)
        self._check_params(values)
        self._set_params(values)

    def _set_params(self, values: dict[str, Any]) -> None:
        """Take checked parameter values and derive the hot path's constants from them."""
        self._params = values
        self._max_dt = float(values["max_dt"])
        self._max_rate2 = float(values["max_rate"]) ** 2
        self._mounting = mounting_matrix(float(values["mount_roll"]), float(values["mount_pitch"]),
                                         float(values["mount_yaw"]))
        self._mounted: bool = self._mounting != IDENTITY
        (self._acc_cal, self._acc_off), (self._gyro_cal, self._gyro_off) = (
            matrices(values).values())
        self._calibrated: bool = (self._acc_cal != IDENTITY or self._gyro_cal != IDENTITY
                                  or self._acc_off != ZERO3 or self._gyro_off != ZERO3)
        self._delay = float(values["sensor_delay"])
        self._trapezoid: bool = values["gyro_sampling"] == "point"
        self._rail = float(values.get("gyro_range", ABSENT["gyro_range"])) * (1.0 - RAIL_MARGIN)
        self._configure()

    def _check_params(self, values: dict[str, Any]) -> None:
        """Checks that involve several parameters; raise ValueError naming them."""

    def _configure(self) -> None:
        """Derive the constants the hot path uses from self._params (called after every change)."""

    # ----- life cycle -------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget every sample: the next valid sample initialises the filter again."""
        self.initialized = False
        self.n_samples = 0
        self.n_rejected = 0
        self.gyro_prev = (0.0, 0.0, 0.0)
        self.clipped = False  # whether this sample's gyro is at its rail (gyro_range)
        self._reset()
        self.last = self.output()

    def _reset(self) -> None:
        raise NotImplementedError

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        """Initialise from the first valid sample (attitude from the accelerometer)."""
        raise NotImplementedError

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        """Process one valid sample after the first."""
        raise NotImplementedError

    def _estimate(self) -> Estimate:
        raise NotImplementedError

    # ----- samples ----------------------------------------------------------------------------
    def check_sample(self, acc: Sequence[float], gyro: Sequence[float], dt: float) -> None:
        """Raise InvalidSample saying what is wrong with a sample; return None for a good one.

        Rejected: a NaN or infinite value, dt outside (0, max_dt], a gyro reading above
        max_rate. Not rejected: any finite accelerometer reading (one near zero or far from g
        is not trusted by the filters' corrections, but the gyro is still integrated).
        """
        ax, ay, az = acc
        gx, gy, gz = gyro
        for name, values in (("acc", (ax, ay, az)), ("gyro", (gx, gy, gz)), ("dt", (dt,))):
            for v in values:
                if not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise InvalidSample(f"{name}={_fmt(values)} is not finite")
        if not 0.0 < dt <= self._params["max_dt"]:
            raise InvalidSample(
                f"dt={dt!r} s is outside the allowed range (0, max_dt={self._params['max_dt']!r}] s"
            )
        rate = math.hypot(gx, gy, gz)
        if not rate <= self._params["max_rate"]:
            raise InvalidSample(
                f"gyro rate {rate:.4g} rad/s is above max_rate={self._params['max_rate']!r} rad/s: "
                "no sensor delivers it"
            )

    def step(self, acc: Sequence[float], gyro: Sequence[float], dt: float) -> Estimate:
        """Process one IMU sample: specific force acc [m/s^2], body rate gyro [rad/s], dt [s].

        dt is the time since the previous sample (ignored for the first valid sample, which
        initialises roll and pitch from the accelerometer). A bad sample raises InvalidSample and
        leaves the state exactly as it was.
        """
        try:
            ax, ay, az = float(acc[0]), float(acc[1]), float(acc[2])
            gx, gy, gz = float(gyro[0]), float(gyro[1]), float(gyro[2])
            dt = float(dt)
        except (TypeError, ValueError, IndexError) as err:
            raise InvalidSample(
                f"sample is not three accelerations, three rates and dt: {err}"
            ) from None
        ax, ay, az, gx, gy, gz = self._prepare(ax, ay, az, gx, gy, gz, dt)
        return self._take(ax, ay, az, gx, gy, gz, dt)

    def step_prepared(self, acc: Vec3, gyro: Vec3, dt: float, clipped: bool) -> Estimate:
        """One sample that a filter holding this one has already checked and conditioned with
        the same limits (its _prepare: the position filter's attitude kf), with its rail flag:
        judged on the sensor's own axes against the sensor's gyro_range, which the conditioned
        sample no longer shows (a mounting mixes the axes) and which this filter's own
        parameters need not hold. The rest of step."""
        self.clipped = clipped
        return self._take(acc[0], acc[1], acc[2], gyro[0], gyro[1], gyro[2], dt)

    def _take(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        """step after the input stage: the first valid sample initialises, the others advance;
        the estimate (turned ahead over sensor_delay) kept as last and returned."""
        if self.initialized:
            last = self._advance(ax, ay, az, gx, gy, gz, dt)
        elif ax * ax + ay * ay + az * az >= _MIN_INIT_NORM2:
            self._init(ax, ay, az, gx, gy, gz)
            self.initialized = True
            last = self._estimate()
        else:  # no gravity direction to start from yet (MIN_INIT_NORM)
            return self.last
        self.gyro_prev = (gx, gy, gz)
        if self._delay > 0.0:
            last = self._ahead(last)
        self.last = last
        self.n_samples += 1
        return last

    def _prepare(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> tuple[float, float, float, float, float, float]:
        """The input stage every estimator shares (its parameters are COMMON_PARAMS; its C twin
        is fc_base_prepare), on one sample as the sensor gave it: the sample rules (InvalidSample
        where it is rejected, the state untouched), whether the gyro is at its rail
        (self.clipped, on the sensor's own axes), the part's calibration (calibrated = cal
        (raw - off), fusion_core.calibration), the mounting into the filter frame, and an
        accelerometer reading beyond MAX_ACC_NORM taken as none. Returns the sample as the
        filter sees it."""
        # One test covers every value: check_sample says what is wrong only when it fails (a
        # finite sample whose sum merely overflowed, e.g. acc = 1e308, passes there).
        w2 = gx * gx + gy * gy + gz * gz
        if not (math.isfinite(ax + ay + az + w2 + dt) and w2 <= self._max_rate2
                and 0.0 < dt <= self._max_dt):
            self.check_sample((ax, ay, az), (gx, gy, gz), dt)
        rail = self._rail
        self.clipped = not (-rail < gx < rail and -rail < gy < rail and -rail < gz < rail)
        acc, gyro = (ax, ay, az), (gx, gy, gz)
        if self._calibrated:
            acc = mat_vec(self._acc_cal, vec_sub(acc, self._acc_off))
            gyro = mat_vec(self._gyro_cal, vec_sub(gyro, self._gyro_off))
        if self._mounted:
            acc = mat_vec(self._mounting, acc)
            gyro = mat_vec(self._mounting, gyro)
        ax, ay, az = acc
        if not ax * ax + ay * ay + az * az <= _MAX_ACC_NORM2:  # (or an overflow to inf)
            ax = ay = az = 0.0
        return ax, ay, az, gyro[0], gyro[1], gyro[2]

    def stream(self) -> Any:
        """This estimator stepped through its C twin: a fusion_core.native.Stream whose
        step(acc, gyro, dt) gives step()'s results to the bit at the twin's speed (get_state,
        set_state and set_param through it stay exact). ValueError saying why where the twin
        is not available or the class has none."""
        from .native.stream import Stream

        return Stream(self)

    def output(self) -> Estimate:
        """The estimate of the current state as the outputs give it (sensor_delay)."""
        est = self._estimate()
        return self._ahead(est) if self._delay > 0.0 and self.initialized else est

    def _ahead(self, est: Estimate) -> Estimate:
        """est with roll and pitch turned ahead over sensor_delay by the last sample's rate minus
        est's bias (kinematics.roll_pitch_ahead)."""
        gx, gy, gz = self.gyro_prev
        bx, by, bz = est.bias
        roll, pitch = roll_pitch_ahead(est.roll, est.pitch, gx - bx, gy - by, gz - bz,
                                       self._delay)
        return est._replace(roll=roll, pitch=pitch)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        """Process one valid sample after the first and return the new estimate: _update, then
        _estimate. An estimator may override it with one method doing both (the hot path);
        self.gyro_prev is still the previous sample's rate here."""
        self._update(ax, ay, az, gx, gy, gz, dt)
        return self._estimate()

    def run(
        self,
        acc: np.ndarray,
        gyro: np.ndarray,
        dt: np.ndarray | float,
        backend: str = "auto",
    ) -> dict[str, np.ndarray]:
        """Run over N samples: acc, gyro [N, 3], dt [N] or a scalar.

        Returns numpy arrays roll, pitch [N], bias [N, 3], rejected [N] (bool) and, for the
        position filter, pos and vel [N, 3]. A rejected sample repeats the last estimate.

        backend: "python" (this class), "native" (its C twin, fusion_core.native; ValueError
        where there is none or it is not available, saying why) or "auto" (the C twin where
        there is one and it is available, else Python). Either way the outputs and the state
        the filter is left in are the same (to 1e-12), so a run may continue with step().
        """
        check_backend(backend)
        acc = np.asarray(acc, dtype=float)
        gyro = np.asarray(gyro, dtype=float)
        if acc.ndim != 2 or acc.shape[1] != 3 or gyro.shape != acc.shape:
            raise ValueError(
                f"acc and gyro must both have shape [N, 3]: got {acc.shape} and {gyro.shape}"
            )
        n = acc.shape[0]
        dts = np.broadcast_to(np.asarray(dt, dtype=float), (n,))
        if backend != "python":
            from . import native

            if native.has_twin(self) and native.available():
                return native.run(self, acc, gyro, dts)
            if backend == "native":
                why = (f"{type(self).__name__} has no C twin of its own (the estimators of "
                       "fusion_core.ESTIMATORS have one)" if not native.has_twin(self)
                       else f"the C twin is unavailable: {native.reason()}")
                raise ValueError(f"backend='native': {why}")
        out = {
            "roll": np.empty(n),
            "pitch": np.empty(n),
            "bias": np.empty((n, 3)),
            "rejected": np.zeros(n, dtype=bool),
        }
        if self.HAS_POSITION:
            out["pos"] = np.empty((n, 3))
            out["vel"] = np.empty((n, 3))
        step = self.step
        # Chunks of RUN_CHUNK samples: the Python lists of inputs and estimates never hold more
        # than one chunk, so memory does not grow with N beyond the output arrays.
        for lo in range(0, n, RUN_CHUNK):
            hi = min(lo + RUN_CHUNK, n)
            rows: list[Estimate] = []
            append = rows.append
            chunk = zip(acc[lo:hi].tolist(), gyro[lo:hi].tolist(), dts[lo:hi].tolist(), strict=True)
            for i, (a, w, h) in enumerate(chunk, lo):
                try:
                    est = step(a, w, h)
                except InvalidSample:
                    out["rejected"][i] = True
                    self.n_rejected += 1
                    est = self.last
                append(est)
            out["roll"][lo:hi] = [e.roll for e in rows]
            out["pitch"][lo:hi] = [e.pitch for e in rows]
            out["bias"][lo:hi] = [e.bias for e in rows]
            if self.HAS_POSITION:
                out["pos"][lo:hi] = [e.pos for e in rows]
                out["vel"][lo:hi] = [e.vel for e in rows]
        return out

    # ----- state ------------------------------------------------------------------------------
    _BASE_STATE: ClassVar[StateSpec] = BASE_STATE

    def get_state(self) -> dict[str, Any]:
        """The whole filter state and parameters as plain floats, ints, bools, strings and lists."""
        state = {name: _plain(getattr(self, name)) for name in (*self._BASE_STATE, *self.STATE)}
        return {"estimator": type(self).__name__, "params": dict(self._params), "state": state}

    def set_state(self, snapshot: dict[str, Any]) -> None:
        """Restore a get_state() snapshot: continuing from it is bit-identical.

        Everything is checked before anything is taken (check_state): a snapshot that fails
        raises ValueError naming the parameter or the state field, and the filter is unchanged.
        """
        params = self.check_state(snapshot)
        self._set_params(params)
        state = snapshot["state"]
        for name in (*self._BASE_STATE, *self.STATE):
            setattr(self, name, _restore(getattr(self, name), state[name]))
        self._restored()
        self.last = self.output()

    def check_state(self, snapshot: Any) -> dict[str, Any]:
        """The parameters of a get_state() snapshot, checked, after checking the whole snapshot:
        this estimator's, every parameter named and in its range, every state field present, of
        its shape and passing its check (fusion_core.state). ValueError naming what is wrong."""
        name = type(self).__name__
        if not isinstance(snapshot, dict) or snapshot.get("estimator") != name:
            owner = snapshot.get("estimator") if isinstance(snapshot, dict) else snapshot
            raise ValueError(f"state of {owner!r} cannot be restored into {name}")
        params, state = snapshot.get("params"), snapshot.get("state")
        if not isinstance(params, dict) or not isinstance(state, dict):
            raise ValueError(f"a state of {name} holds 'params' and 'state' dicts")
        specs = self.param_specs()
        check_param_names(params, specs, name)
        missing = sorted(set(specs) - set(params))
        if missing:
            raise ValueError(f"state snapshot lacks the parameter(s) {', '.join(missing)}")
        checked = {k: specs[k].validate(params[k]) for k in specs}
        self._check_params(checked)
        fields = {**self._BASE_STATE, **self.STATE}
        unknown = sorted(set(state) - set(fields))
        missing = sorted(set(fields) - set(state))
        if missing or unknown:
            raise ValueError(f"state snapshot of {name}: "
                             + "; ".join(([f"lacks {', '.join(missing)}"] if missing else [])
                                         + ([f"has unknown {', '.join(unknown)}"] if unknown
                                            else [])))
        for field, check in fields.items():
            check_field(field, check, state[field], getattr(self, field))
            if check is NESTED:
                self._check_nested(field, state[field], checked)
        return checked

    def _check_nested(self, field: str, snapshot: dict[str, Any], params: dict[str, Any]
                      ) -> None:
        """Check the snapshot of a nested estimator's state (a NESTED field), given the checked
        parameters of this one."""
        raise NotImplementedError(f"{type(self).__name__} has no nested state {field!r}")

    def _restored(self) -> None:
        """Hook for subclasses whose state holds nested estimators."""


def _fmt(values: tuple[float, ...]) -> str:
    return "(" + ", ".join(repr(v) for v in values) + ")"
