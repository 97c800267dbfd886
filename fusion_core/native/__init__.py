"""fusion_core's C twin: the same estimators in C99, and their Python binding.

The C sources beside this file (fc_core.c, fc_cf.c, ...) are the twins of the Python modules:
the same names, the same state fields, the same floating-point operations in the same order, libm
where Python calls math, compiled without fused multiply-add or fast-math, so that a run through
either gives the same numbers (tests/test_native.py: within 1e-12, in practice bit for bit). They
need libc and libm only, so the very same files go into the native FMUs and onto a
microcontroller.

This module builds them into a shared library with the C compiler it finds (CC, else cc; cached
under build/native/ in a source checkout, else ~/.cache/imu-fusion-fmu/native, keyed on the
sources and the flags) and binds it with cffi. `available()` says whether that worked and
`reason()` why not; where it did not, every estimator still runs in Python. `Estimator.run(...,
backend="auto")` uses the native twin where there is one and it is available.

By hand, the library is one command:

    cc -std=c99 -O2 -fPIC -shared -ffp-contract=off -fno-fast-math \\
        -o libfusion_core.so fusion_core/native/*.c -lm
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import struct
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..types import RUN_CHUNK

HERE = Path(__file__).resolve().parent
SOURCES = (
    "fc_core.c", "fc_noise.c", "fc_cf.c", "fc_mgcf.c", "fc_kf.c", "fc_ukf.c", "fc_poskf.c",
    "fc_sensor.c", "fc_plant.c", "fc_state.c", "fc_state_tables.c",
)
"""The C sources, in link order."""
HEADERS = (
    "fc_core.h", "fc_noise.h", "fc_params.h", "fc_state.h", "fc_cf.h", "fc_mgcf.h", "fc_kf.h",
    "fc_ukf.h", "fc_poskf.h", "fc_sensor.h", "fc_plant.h",
)
"""The headers, in the order the binding declares them."""
DATA_HEADERS = ("fc_scenarios.h",)
"""Headers of tables the binding does not declare (the scenarios' signal nodes), compiled in."""
CFLAGS = ("-std=c99", "-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math")
"""No fused multiply-add (-ffp-contract=off) and no fast-math: each operation rounds as
Python's does, which is what makes the twins equal."""
FC_SKIPPED = 1
"""fc_status: FC_OK 0 and FC_SKIPPED 1 took the sample, the larger values rejected it."""
ESTIMATE_FIELDS = 11
"""Doubles per fc_estimate: roll, pitch, bias[3], pos[3], vel[3]."""
_ESTIMATE_DOUBLES = struct.Struct("=11d")
"""An fc_estimate's memory, read as Python floats."""
BASE_STATE = ("initialized", "n_samples", "n_rejected", "gyro_prev")
"""Estimator._BASE_STATE: these live in the twin's `base` member."""
STATE_ATTRIBUTES = {"UnscentedKalmanFilter": {"P": "_P"}}
"""Where a twin's state field is kept under another Python attribute: the UKF's P is its packed
lower triangle `_P` (the `P` property shows it as a 6x6 list)."""
POSKF_PENDING_MAX = 2048
"""fc_poskf.h's FC_POSKF_PENDING_MAX (position.PENDING_MAX)."""

PREBUILT = HERE / "libfusion_core.so"
"""A library built beside the sources, as the pythonfmu FMUs ship it (fmu_src.build): loaded
first where it loads (same platform); elsewhere the library is built or Python runs."""

_lib: Any = None
_ffi: Any = None
_reason: str | None = "not loaded yet"
_tried = False


def cache_dir() -> Path:
    """Where the built library is kept: FUSION_CORE_NATIVE_CACHE, else build/native in a source
    checkout, else the user's cache folder."""
    env = os.environ.get("FUSION_CORE_NATIVE_CACHE")
    if env:
        return Path(env)
    repo = HERE.parents[1]
    if (repo / "pyproject.toml").is_file():
        return repo / "build" / "native"
    return Path.home() / ".cache" / "imu-fusion-fmu" / "native"


def compiler() -> str | None:
    """The C compiler to build with: $CC, else cc, gcc or clang on the PATH."""
    cc = os.environ.get("CC")
    if cc:
        return shutil.which(cc)
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return found
    return None


def _key(cc: str) -> str:
    h = hashlib.sha256()
    for name in (*SOURCES, *HEADERS, *DATA_HEADERS):
        h.update(name.encode() + b"\0" + (HERE / name).read_bytes())
    h.update(" ".join((cc, *CFLAGS)).encode())
    return h.hexdigest()[:16]


def build(force: bool = False) -> Path:
    """Compile the library (unless cached) and return its path; RuntimeError saying why not."""
    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler found (set CC, or install cc, gcc or clang)")
    target = cache_dir() / _key(cc) / "libfusion_core.so"
    if target.is_file() and not force:
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
    os.close(fd)
    cmd = [cc, *CFLAGS, "-o", tmp, *(str(HERE / s) for s in SOURCES), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        os.unlink(tmp)
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-10:])
        raise RuntimeError(f"building the C twin failed ({' '.join(cmd)}):\n{tail}")
    os.replace(tmp, target)  # atomic: a parallel build never sees half a library
    return target


def cdef() -> str:
    """The headers as cffi declarations: comments, include guards, #includes, macros and the
    static inline default functions left out; integer #defines kept, and written into the
    declarations that use them (array sizes)."""
    out: list[str] = []
    defines: dict[str, str] = {}
    for name in HEADERS:
        text = re.sub(r"/\*.*?\*/", "", (HERE / name).read_text(), flags=re.S)
        text = text.replace("\\\n", " ")  # a macro's continued lines into one
        text = re.sub(r"static inline[^{]*\{.*?\n\}\n", "", text, flags=re.S)
        for line in text.splitlines():
            line = line.rstrip()
            define = re.match(r"#define (\w+) (-?\d+)$", line)
            if define:
                defines[define.group(1)] = define.group(2)
            elif line.startswith("#"):
                continue
            elif defines:
                line = re.sub(r"\b(" + "|".join(defines) + r")\b",
                              lambda m: defines[m.group(1)], line)
            out.append(line)
    return "\n".join(out)


def normals(seed: int, stream: int, k0: int, n: int, channels: int) -> np.ndarray:
    """fusion_core.noise.normals computed by the C twin (fc_noise.c)."""
    lib, ffi = lib_and_ffi()
    out = np.empty((n, channels))
    key = lib.fc_stream_key(seed, stream)
    for i in range(n):
        lib.fc_normals(key, k0 + i, channels,
                       ffi.cast("double *", ffi.from_buffer(out[i], require_writable=True)))
    return out


def _load() -> None:
    global _lib, _ffi, _reason, _tried
    _tried = True
    try:
        import cffi  # type: ignore[import-untyped]
    except ImportError as err:
        _reason = f"cffi is not installed ({err})"
        return
    ffi = cffi.FFI()
    try:
        ffi.cdef(cdef())
    except (cffi.CDefError, cffi.FFIError) as err:
        _reason = str(err)
        return
    if PREBUILT.is_file():  # an FMU's copy: the library built with it, if it loads here
        try:
            _lib, _ffi, _reason = ffi.dlopen(str(PREBUILT)), ffi, None
            return
        except OSError:
            pass
    try:
        _lib = ffi.dlopen(str(build()))
        _ffi = ffi
        _reason = None
    except (RuntimeError, OSError) as err:
        _reason = str(err)


def available() -> bool:
    """Whether the C twin is built and loaded (building it on first use)."""
    if not _tried:
        _load()
    return _lib is not None


def reason() -> str | None:
    """Why the C twin is not available (no compiler, build failed, ...); None when it is."""
    available()
    return _reason


def lib_and_ffi() -> tuple[Any, Any]:
    """The loaded library and its cffi FFI; RuntimeError with the reason where unavailable."""
    if not available():
        raise RuntimeError(f"the native backend is unavailable: {reason()}")
    return _lib, _ffi


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
    if name == "PositionKalmanFilter":
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
    if name == "PositionKalmanFilter":
        _take_position(twin, estimator)
    else:
        attrs = STATE_ATTRIBUTES.get(name, {})
        for field in estimator.STATE:
            attr = attrs.get(field, field)
            setattr(estimator, attr, _field_value(twin, field, getattr(estimator, attr)))
    estimator.last = estimator.output()


def _fill_position(lib: Any, twin: Any, est: Any) -> None:
    """The position filter's state: its own fields, its queue and its two nested Kalman filters
    (whose parameters fc_poskf_configure already set from the position filter's)."""
    _, ffi = lib_and_ffi()
    _fill(lib, ffi.addressof(twin[0], "tilt"), est.tilt)
    _fill(lib, ffi.addressof(twin[0], "att"), est.att)
    twin.yaw = est.yaw
    _set_field(twin, "x", est._x)
    _set_field(twin, "P", est._P)
    twin.quiet_time = est.quiet_time
    twin.stationary = est.stationary
    if len(est.pending) > POSKF_PENDING_MAX:
        raise ValueError(f"the stationary queue holds {len(est.pending)} samples, more than "
                         f"the C twin's {POSKF_PENDING_MAX}")
    twin.pending_head = 0
    twin.pending_count = len(est.pending)
    for i, entry in enumerate(est.pending):
        for j, v in enumerate(entry):
            twin.pending[i][j] = v
    _set_field(twin, "turned", est.turned)
    _set_field(twin, "f_mean", est.f_mean)


def _take_position(twin: Any, est: Any) -> None:
    _, ffi = lib_and_ffi()
    take_state(est.tilt, ffi.addressof(twin[0], "tilt"))
    take_state(est.att, ffi.addressof(twin[0], "att"))
    est.yaw = float(twin.yaw)
    est._x = tuple(float(v) for v in twin.x)
    est._P = tuple(float(v) for v in twin.P)
    est.quiet_time = float(twin.quiet_time)
    est.stationary = bool(twin.stationary)
    head, count = twin.pending_head, twin.pending_count
    est.pending = [tuple(float(v) for v in twin.pending[(head + i) % POSKF_PENDING_MAX])
                   for i in range(count)]
    est.turned = tuple(float(v) for v in twin.turned)
    est.f_mean = tuple(float(v) for v in twin.f_mean)


def new_twin(estimator: Any) -> Any:
    """A C twin holding the estimator's parameters and its whole state."""
    lib, ffi = lib_and_ffi()
    prefix = type(estimator).TWIN
    twin = ffi.new(f"{prefix} *")
    params = ffi.new(f"{prefix}_params *")
    specs = estimator.param_specs()
    for name, value in estimator.params.items():
        choices = specs[name].choices
        setattr(params, name, choices.index(value) if choices is not None else value)
    getattr(lib, f"{prefix}_init")(twin, params)
    _fill(lib, twin, estimator)
    return twin


def run(estimator: Any, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray
        ) -> dict[str, np.ndarray]:
    """Estimator.run through the C twin: the same outputs, and the estimator's state afterwards
    is the one the Python run would leave. The samples go through in chunks of RUN_CHUNK, so
    that, as in the Python run, memory beyond the outputs does not grow with N."""
    lib, ffi = lib_and_ffi()
    twin = new_twin(estimator)
    run_twin = getattr(lib, f"{type(estimator).TWIN}_run")
    n = acc.shape[0]
    out = {"roll": np.empty(n), "pitch": np.empty(n), "bias": np.empty((n, 3)),
           "rejected": np.zeros(n, dtype=bool)}
    if estimator.HAS_POSITION:
        out["pos"] = np.empty((n, 3))
        out["vel"] = np.empty((n, 3))
    est = np.zeros((RUN_CHUNK, ESTIMATE_FIELDS))
    rejected = np.zeros(RUN_CHUNK, dtype=np.uint8)
    est_p = ffi.cast("fc_estimate *", ffi.from_buffer(est, require_writable=True))
    rejected_p = ffi.cast("unsigned char *", ffi.from_buffer(rejected, require_writable=True))
    for lo in range(0, n, RUN_CHUNK):
        hi = min(lo + RUN_CHUNK, n)
        a = np.ascontiguousarray(acc[lo:hi], dtype=np.float64)
        g = np.ascontiguousarray(gyro[lo:hi], dtype=np.float64)
        h = np.ascontiguousarray(dt[lo:hi], dtype=np.float64)
        run_twin(twin, hi - lo, ffi.cast("double *", ffi.from_buffer(a)),
                 ffi.cast("double *", ffi.from_buffer(g)),
                 ffi.cast("double *", ffi.from_buffer(h)), est_p, rejected_p)
        k = hi - lo
        out["roll"][lo:hi] = est[:k, 0]
        out["pitch"][lo:hi] = est[:k, 1]
        out["bias"][lo:hi] = est[:k, 2:5]
        out["rejected"][lo:hi] = rejected[:k] != 0
        if estimator.HAS_POSITION:
            out["pos"][lo:hi] = est[:k, 5:8]
            out["vel"][lo:hi] = est[:k, 8:11]
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


# ----- the plant -------------------------------------------------------------------------------
def plant_truth(scenario_id: int, t: np.ndarray) -> np.ndarray:
    """The truth of a scenario at times t [N] by the C twin (fc_plant.c): [N, 15] in
    synthetic.TRUTH_NAMES' order, as Trajectory.truth_at gives it sample by sample."""
    lib, ffi = lib_and_ffi()
    t = np.ascontiguousarray(t, dtype=np.float64)
    out = np.empty((t.shape[0], 15))
    if lib.fc_plant_run(scenario_id, t.shape[0], ffi.cast("double *", ffi.from_buffer(t)),
                        ffi.cast("double *", ffi.from_buffer(out, require_writable=True))) != 0:
        raise ValueError(f"unknown scenario id {scenario_id}")
    return out


# ----- the sensor model ------------------------------------------------------------------------
SENSOR_LISTS = ("gyro_turn_on", "acc_turn_on", "gyro_walk", "acc_walk", "gyro_gm", "acc_gm")
"""The sensor's per-axis state vectors (fields of the same names in fc_sensor)."""


def _sensor_twin(model: Any) -> Any:
    lib, ffi = lib_and_ffi()
    twin = ffi.new("fc_sensor *")
    params = ffi.new("fc_sensor_params *")
    for spec in type(model).PARAMS:  # sensor.SENSOR_PARAMS
        value = model.params[spec.name]
        setattr(params, spec.name, spec.choices.index(value) if spec.choices else value)
    lib.fc_sensor_init(twin, params)
    twin.k = model.k
    for name in SENSOR_LISTS:
        _set_field(twin, name, getattr(model, name))
    for name in ("gyro_matrix", "acc_matrix"):
        for i, row in enumerate(getattr(model, name)):
            for j, v in enumerate(row):
                getattr(twin, name)[i][j] = v
    twin.has_omega_prev = model.omega_prev is not None
    if model.omega_prev is not None:
        _set_field(twin, "omega_prev", model.omega_prev)
    twin.time_error = model.time_error
    for name in ("gyro_filter", "acc_filter"):
        filt = getattr(model, name)
        if filt is not None and filt.state is not None:
            c = getattr(twin, name)
            c.started = 1
            for i, row in enumerate(filt.state):
                for j, v in enumerate(row):
                    c.state[i][j] = v
    return twin


def _sensor_take(twin: Any, model: Any) -> None:
    model.k = int(twin.k)
    for name in SENSOR_LISTS:
        setattr(model, name, [float(v) for v in getattr(twin, name)])
    for name in ("gyro_matrix", "acc_matrix"):
        setattr(model, name, [[float(v) for v in row] for row in getattr(twin, name)])
    model.omega_prev = [float(v) for v in twin.omega_prev] if twin.has_omega_prev else None
    model.time_error = float(twin.time_error)
    for name in ("gyro_filter", "acc_filter"):
        filt = getattr(model, name)
        c = getattr(twin, name)
        if filt is not None and c.started:
            filt.state = [[float(v) for v in row] for row in c.state]


def sensor_run(model: Any, omega: np.ndarray, f: np.ndarray, h: np.ndarray
               ) -> dict[str, np.ndarray]:
    """ImuSensorModel.run through the C twin (fc_sensor.c); the model's state follows."""
    lib, ffi = lib_and_ffi()
    if np.any(~(h > 0.0)):
        raise ValueError(f"interval h={float(h[~(h > 0.0)][0])!r} s must be > 0")
    twin = _sensor_twin(model)
    n = omega.shape[0]
    out = {"acc": np.empty((n, 3)), "gyro": np.empty((n, 3)), "dt": np.empty(n),
           "gyro_bias": np.empty((n, 3))}
    ins = [np.ascontiguousarray(a, dtype=np.float64) for a in (omega, f, h)]

    def ptr(a: np.ndarray) -> Any:
        return ffi.cast("double *", ffi.from_buffer(a, require_writable=a.flags.writeable))

    lib.fc_sensor_run(twin, n, *(ptr(a) for a in ins),
                      *(ptr(out[k]) for k in ("acc", "gyro", "dt", "gyro_bias")))
    _sensor_take(twin, model)
    return out


__all__ = ["available", "build", "cache_dir", "compiler", "has_twin", "normals", "plant_truth",
           "reason", "run", "sensor_run"]
