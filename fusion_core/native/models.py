"""The plant, the sensor model and the noise generator through their C twins
(fusion_core.native)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .estimators import _set_field
from .library import lib_and_ffi


def normals(seed: int, stream: int, k0: int, n: int, channels: int) -> np.ndarray:
    """fusion_core.noise.normals computed by the C twin (fc_noise.c)."""
    lib, ffi = lib_and_ffi()
    out = np.empty((n, channels))
    key = lib.fc_stream_key(seed, stream)
    for i in range(n):
        lib.fc_normals(key, k0 + i, channels,
                       ffi.cast("double *", ffi.from_buffer(out[i], require_writable=True)))
    return out



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


__all__ = ["normals", "plant_truth", "sensor_run"]
