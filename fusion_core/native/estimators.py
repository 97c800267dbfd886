"""The estimators through their C twins: an estimator's parameters and state into its twin and
back (exactly), a run over arrays, and a per-sample stepper (fusion_core.native)."""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

from ..state import BASE_STATE as STATE_BASE
from ..types import ABSENT, RUN_CHUNK, Estimate
from .library import available, lib_and_ffi

FC_SKIPPED = 1
"""fc_status: FC_OK 0 and FC_SKIPPED 1 took the sample, the larger values rejected it."""
ESTIMATE_FIELDS = 2 + 3 * (len(Estimate._fields) - 2)
"""Doubles per fc_estimate: roll, pitch, then bias[3], pos[3], vel[3] (types.Estimate)."""
_ESTIMATE_DOUBLES = struct.Struct("=11d")
"""An fc_estimate's memory, read as Python floats."""
BASE_STATE = tuple(STATE_BASE)
"""Estimator._BASE_STATE's fields (fusion_core.state.BASE_STATE): they live in the twin's `base`
member."""
STATE_ATTRIBUTES = {"UnscentedKalmanFilter": {"P": "_P"}, "PaperUnscentedKalmanFilter": {"P": "_P"}}
"""Where a twin's state field is kept under another Python attribute: the UKFs' P is their packed
lower triangle `_P` (the `P` property shows it as a 6x6 list)."""
def poskf_pending_max() -> int:
    """The C twin's FC_POSKF_PENDING_MAX, which fusion_core.native.generate writes into
    fc_params.h from position.PENDING_MAX (tests/test_native.py holds them equal)."""
    lib, _ = lib_and_ffi()
    return int(lib.FC_POSKF_PENDING_MAX)


def has_twin(estimator: object) -> bool:
    """Whether this estimator's exact class has a C twin (a subclass may change its Python
    methods, so it never runs natively)."""
    cls = type(estimator)
    return cls.__dict__.get("TWIN") is not None and cls.__module__.startswith("fusion_core.")


# ----- an estimator's state and parameters, both ways ------------------------------------------
def _leaves(value: Any) -> list[float]:
    """A state value's numbers in order (a Measure's vectors one after the other)."""
    if isinstance(value, (tuple, list)):
        return [x for v in value for x in _leaves(v)]
    return [value]


def _shaped(template: Any, values: Any) -> Any:
    """The numbers of the iterator values in the shape of template (named tuples by type)."""
    if isinstance(template, tuple):
        items = tuple(_shaped(t, values) for t in template)
        return type(template)(*items) if hasattr(template, "_fields") else items
    return float(next(values))


def _field_value(cdata: Any, name: str, template: Any) -> Any:
    value = getattr(cdata, name)
    if isinstance(template, tuple):
        n = len(_leaves(template))
        return _shaped(template, iter([value[i] for i in range(n)]))
    if isinstance(template, list):
        return [float(value[i]) for i in range(len(template))]
    if isinstance(template, bool):
        return bool(value)
    if isinstance(template, int):
        return int(value)
    return float(value)


def _set_field(cdata: Any, name: str, value: Any) -> None:
    if isinstance(value, (tuple, list)):
        arr = getattr(cdata, name)
        for i, v in enumerate(_leaves(value)):
            arr[i] = v
    else:
        setattr(cdata, name, value)


def _fill(lib: Any, twin: Any, estimator: Any) -> None:
    """Copy the Python estimator's whole state into its twin (a pointer to the C struct)."""
    name = type(estimator).__name__
    for field in BASE_STATE:
        _set_field(twin.base, field, getattr(estimator, field))
    if estimator.HAS_POSITION:
        _fill_position(lib, twin, estimator)
    else:
        attrs = STATE_ATTRIBUTES.get(name, {})
        for field in estimator.STATE:
            _set_field(twin, field, getattr(estimator, attrs.get(field, field)))
    getattr(lib, f"{type(estimator).TWIN}_restored")(twin)


def take_state(estimator: Any, twin: Any) -> None:
    """Copy the twin's whole state into the Python estimator (which continues from it
    exactly)."""
    name = type(estimator).__name__
    for field in BASE_STATE:
        setattr(estimator, field, _field_value(twin.base, field, getattr(estimator, field)))
    if estimator.HAS_POSITION:
        _take_position(twin, estimator)
    else:
        attrs = STATE_ATTRIBUTES.get(name, {})
        for field in estimator.STATE:
            attr = attrs.get(field, field)
            setattr(estimator, attr, _field_value(twin, field, getattr(estimator, attr)))
    estimator.last = estimator.output()


def _fill_position(lib: Any, twin: Any, est: Any) -> None:
    """A position filter's state: its own fields, its nested Kalman filters (whose parameters
    its configure already set from the position filter's) and the recommended one's queue."""
    _, ffi = lib_and_ffi()
    _fill(lib, ffi.addressof(twin[0], "tilt"), est.tilt)
    twin.yaw = est.yaw
    _set_field(twin, "x", est._x)
    _set_field(twin, "P", est._P)
    if not hasattr(est, "att"):  # the paper's: the tilt stage is all
        return
    _fill(lib, ffi.addressof(twin[0], "att"), est.att)
    twin.quiet_time = est.quiet_time
    twin.stationary = est.stationary
    if len(est.pending) > poskf_pending_max():
        raise ValueError(f"the stationary queue holds {len(est.pending)} samples, more than "
                         f"the C twin's {poskf_pending_max()}")
    twin.pending_head = 0
    twin.pending_count = len(est.pending)
    for i, entry in enumerate(est.pending):
        for j, v in enumerate(entry):
            twin.pending[i][j] = v
    _set_field(twin, "turned", est.turned)
    _set_field(twin, "f_mean", est.f_mean)
    twin.aligned = est.aligned


def _take_position(twin: Any, est: Any) -> None:
    _, ffi = lib_and_ffi()
    take_state(est.tilt, ffi.addressof(twin[0], "tilt"))
    est.yaw = float(twin.yaw)
    est._x = tuple(float(v) for v in twin.x)
    est._P = tuple(float(v) for v in twin.P)
    if not hasattr(est, "att"):  # the paper's: the tilt stage is all
        return
    take_state(est.att, ffi.addressof(twin[0], "att"))
    est.quiet_time = float(twin.quiet_time)
    est.stationary = bool(twin.stationary)
    head, count = twin.pending_head, twin.pending_count
    size = poskf_pending_max()
    est.pending = [tuple(float(v) for v in twin.pending[(head + i) % size])
                   for i in range(count)]
    est.turned = tuple(float(v) for v in twin.turned)
    est.f_mean = tuple(float(v) for v in twin.f_mean)
    est.aligned = bool(twin.aligned)


def twin_params(ffi: Any, estimator: Any) -> Any:
    """The estimator's parameter values as its twin's params struct (fc_params.h), made by ffi
    (the double build's or a float one's): its own parameters by name, the input stage's in
    params.input (fc_input_params), a choice as its index; a COMMON parameter the class leaves
    out at base.ABSENT's value, as the generated T_params_default sets it."""
    cls = type(estimator)
    params = ffi.new(f"{cls.TWIN}_params *")
    for name, value in ABSENT.items():
        setattr(params.input, name, value)
    for name, spec in estimator.param_specs().items():
        value = estimator.params[name]
        value = spec.choices.index(value) if spec.choices is not None else value
        *path, field = param_field(cls, name).split(".")
        setattr(param_struct(params, path), field, value)
    return params


def param_field(cls: Any, name: str) -> str:
    """The field of parameter `name` of estimator class cls in its twin's params struct
    (fc_params.h): `name` for one of its own (cls.PARAMS), `input.name` for one of the input
    stage every estimator shares (fc_input_params). The native FMUs' config.h and the binding
    both fill the struct by it."""
    return name if any(p.name == name for p in cls.PARAMS) else f"input.{name}"


def param_struct(params: Any, path: list[str]) -> Any:
    """The struct within params that path (param_field's dotted prefix) names."""
    for part in path:
        params = getattr(params, part)
    return params


def new_twin(estimator: Any) -> Any:
    """A C twin holding the estimator's parameters and its whole state."""
    lib, ffi = lib_and_ffi()
    prefix = type(estimator).TWIN
    twin = ffi.new(f"{prefix} *")
    params = twin_params(ffi, estimator)
    getattr(lib, f"{prefix}_init")(twin, params)
    _fill(lib, twin, estimator)
    return twin


def run(estimator: Any, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray
        ) -> dict[str, np.ndarray]:
    """Estimator.run through the C twin: the same outputs, and the estimator's state afterwards
    is the one the Python run would leave. The twin writes each output into its array
    (T_run_columns) and reads contiguous float64 inputs where they are, in one call; other
    inputs are copied in chunks of RUN_CHUNK, so that, as in the Python run, memory beyond the
    outputs does not grow with N."""
    lib, ffi = lib_and_ffi()
    twin = new_twin(estimator)
    run_twin = getattr(lib, f"{type(estimator).TWIN}_run_columns")
    n = acc.shape[0]
    out = {"roll": np.empty(n), "pitch": np.empty(n), "bias": np.empty((n, 3)),
           "rejected": np.zeros(n, dtype=bool)}
    if estimator.HAS_POSITION:
        out["pos"] = np.empty((n, 3))
        out["vel"] = np.empty((n, 3))

    def column(name: str, lo: int, kind: str = "double *") -> Any:
        a = out.get(name)  # the output array from sample lo, as the twin's pointer
        if a is None:
            return ffi.NULL
        return ffi.cast(kind, ffi.from_buffer(a[lo:], require_writable=True))

    # contiguous float64 inputs go to the twin whole; others are copied chunk by chunk
    whole = all(x.dtype == np.float64 and x.flags.c_contiguous for x in (acc, gyro, dt))
    chunk = max(n, 1) if whole else RUN_CHUNK
    for lo in range(0, n, chunk):
        hi = min(lo + chunk, n)
        a = np.ascontiguousarray(acc[lo:hi], dtype=np.float64)
        g = np.ascontiguousarray(gyro[lo:hi], dtype=np.float64)
        h = np.ascontiguousarray(dt[lo:hi], dtype=np.float64)
        run_twin(twin, hi - lo, ffi.cast("double *", ffi.from_buffer(a)),
                 ffi.cast("double *", ffi.from_buffer(g)),
                 ffi.cast("double *", ffi.from_buffer(h)), column("roll", lo),
                 column("pitch", lo), column("bias", lo), column("pos", lo), column("vel", lo),
                 column("rejected", lo, "unsigned char *"))
    take_state(estimator, twin)
    return out


class Stepper:
    """An estimator stepped sample by sample through its C twin: Estimator.step's outputs (to
    the bit) at the twin's speed, for the pythonfmu FMUs' doStep.

    While it steps, the twin holds the state: `sync()` copies it into the Python estimator
    (before anything reads that object: get_state, set_param), `load()` takes the estimator's
    parameters and state into a new twin (after set_state or set_param)."""

    def __init__(self, estimator: Any) -> None:
        lib, ffi = lib_and_ffi()
        self.estimator = estimator
        self._step = getattr(lib, f"{type(estimator).TWIN}_step")
        self._acc = ffi.new("double[3]")
        self._gyro = ffi.new("double[3]")
        self._null = ffi.NULL  # no estimate copied out: last() reads the twin's own
        self._n = ESTIMATE_FIELDS if estimator.HAS_POSITION else 5
        self.load()

    def load(self) -> None:
        _, ffi = lib_and_ffi()
        self.twin = new_twin(self.estimator)
        # the twin's last estimate as doubles, read without a cffi attribute access per field
        self._last = ffi.buffer(ffi.addressof(self.twin[0], "last"))

    def sync(self) -> None:
        take_state(self.estimator, self.twin)

    def step(self, acc: Any, gyro: Any, dt: float) -> bool:
        """One sample; False when the twin rejected it (its state unchanged: the estimator's
        check_sample says why)."""
        a, g = self._acc, self._gyro
        a[0], a[1], a[2] = acc
        g[0], g[1], g[2] = gyro
        return self._step(self.twin, a, g, dt, self._null) <= FC_SKIPPED

    def last(self) -> tuple[float, ...]:
        """The last estimate: roll, pitch, bias (3) and, for the position filter, pos, vel."""
        return _ESTIMATE_DOUBLES.unpack_from(self._last)[:self._n]


def stepper(estimator: Any) -> Stepper | None:
    """A Stepper for the estimator where its twin is available, else None (Python steps)."""
    return Stepper(estimator) if has_twin(estimator) and available() else None
