"""A small fmpy host for the project's FMUs: one FMU instance per object, one sample per doStep.

Used by the tests, the examples and the C-host comparison. It drives fmpy's low-level FMI 2.0
API (instantiate, setupExperiment, enter/exitInitializationMode, set/get by value reference,
doStep, FMU state, terminate, freeInstance) and collects the FMU's log messages.

    with FmuInstance("dist/AngleBiasKalmanFilter.fmu", parameters={"R_measure": 1e-5}) as fmu:
        out = fmu.run_samples(acc, gyro, dt)   # out["roll"], out["bias"], ...
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Iterable, Mapping, Sequence
from ctypes import byref
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)

from .variables import item_value

INPUTS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt")
"""The estimator FMUs' inputs, in the order run_samples sets them."""
STATUS = ("OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING")


@dataclass(frozen=True)
class LogMessage:
    """One message an FMU sent to the FMI logger."""

    instance: str
    status: str
    category: str
    message: str


class SerializedState(bytes):
    """A serialised FMU state and the time it was taken at (where the next doStep starts)."""

    time: float

    def __new__(cls, data: bytes, time: float) -> SerializedState:
        out = super().__new__(cls, data)
        out.time = time
        return out


class FmuInstance:
    """An instantiated, initialised co-simulation FMU (see the module docstring).

    parameters: start values to set before initialisation, by name (an enumeration may be
    given by item name). unzip_dir: an extracted FMU to share between instances (otherwise
    the FMU is extracted into a temporary folder that close() removes).
    """

    def __init__(
        self,
        fmu: str | Path,
        instance_name: str = "instance",
        parameters: Mapping[str, Any] | None = None,
        unzip_dir: str | Path | None = None,
        logging_on: bool = True,
        start_time: float = 0.0,
    ) -> None:
        self.path = Path(fmu)
        self.model_description = md = read_model_description(str(fmu))
        self.variables = {v.name: v for v in md.modelVariables}
        self._own_dir = unzip_dir is None
        self.unzip_dir = Path(extract(str(fmu)) if unzip_dir is None else unzip_dir)
        self.messages: list[LogMessage] = []
        self.time = start_time
        self._state_times: dict[int, float] = {}
        self._last_step = 0.01  # the communication step sample() falls back to
        self._callbacks = _callbacks(self._on_log)
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=str(self.unzip_dir),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=logging_on)
        self._open = True
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        self.set(parameters or {})
        self.fmu.exitInitializationMode()

    # ----- values -------------------------------------------------------------------------------
    def vr(self, names: Iterable[str]) -> list[int]:
        """Value references of the named variables."""
        return [self.variables[n].valueReference for n in names]

    def set(self, values: Mapping[str, Any]) -> None:
        """Set variables by name (Real, Integer, a choice by value or item name, Boolean)."""
        for name, value in values.items():
            var = self.variables[name]
            vr = [var.valueReference]
            if var.type == "Real":
                self.fmu.setReal(vr, [float(value)])
            elif var.type == "Boolean":
                self.fmu.setBoolean(vr, [bool(value)])
            else:
                if isinstance(value, str):
                    value = item_value(var, value)
                self.fmu.setInteger(vr, [int(value)])

    def get(self, name: str) -> Any:
        """One variable's value by name."""
        var = self.variables[name]
        vr = [var.valueReference]
        if var.type == "Real":
            return self.fmu.getReal(vr)[0]
        if var.type == "Boolean":
            return bool(self.fmu.getBoolean(vr)[0])
        return self.fmu.getInteger(vr)[0]

    # ----- stepping -----------------------------------------------------------------------------
    def _step_for(self, dt: float) -> float:
        """The communication step for a sample: its dt, or the last step where dt is not finite
        and > 0 (a bad sample's dt is the sample's to carry; a step size that is not > 0 is a
        host error the FMUs refuse, docs/interface.md)."""
        if math.isfinite(dt) and dt > 0.0:
            self._last_step = dt
        return self._last_step

    def sample(self, acc: Sequence[float], gyro: Sequence[float], dt: float,
               h: float | None = None) -> None:
        """Set one IMU sample and doStep over h (default: _step_for(dt)) from the current
        time."""
        h = self._step_for(dt) if h is None else h
        self.fmu.setReal(self.vr(INPUTS), [*map(float, acc), *map(float, gyro), float(dt)])
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def run_samples(
        self, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray | float, h: float | None = None
    ) -> dict[str, np.ndarray]:
        """One sample per doStep; returns arrays like fusion_core's run(): roll, pitch [N],
        bias [N, 3], invalid_samples [N] and, for the position filter, pos, vel [N, 3].
        h is the communication step (default: each sample's dt)."""
        acc = np.asarray(acc, dtype=float)
        gyro = np.asarray(gyro, dtype=float)
        n = len(acc)
        dts = np.broadcast_to(np.asarray(dt, dtype=float), (n,))
        position = "pos_x" in self.variables
        real_names = ["roll", "pitch", "bias_x", "bias_y", "bias_z"]
        if position:
            real_names += ["pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z"]
        in_vr = self.vr(INPUTS)
        out_vr = self.vr(real_names)
        count_vr = self.vr(["invalid_samples"])
        reals = np.empty((n, len(real_names)))
        counts = np.empty(n, dtype=int)
        set_real, do_step = self.fmu.setReal, self.fmu.doStep
        get_real, get_integer = self.fmu.getReal, self.fmu.getInteger
        for i in range(n):
            step = self._step_for(float(dts[i])) if h is None else h
            set_real(in_vr, [*acc[i].tolist(), *gyro[i].tolist(), float(dts[i])])
            do_step(currentCommunicationPoint=self.time, communicationStepSize=step)
            self.time += step
            reals[i] = get_real(out_vr)
            counts[i] = get_integer(count_vr)[0]
        out = {
            "roll": reals[:, 0], "pitch": reals[:, 1], "bias": reals[:, 2:5],
            "invalid_samples": counts,
        }
        if position:
            out["pos"] = reals[:, 5:8]
            out["vel"] = reals[:, 8:11]
        return out

    # ----- state and life cycle -----------------------------------------------------------------
    # A state holds the FMU's time, and the next doStep must start there (the FMUs refuse any
    # other communication point), so the host keeps the time of every state it took.
    def get_state(self) -> Any:
        """fmi2GetFMUstate (free it with free_state)."""
        state = self.fmu.getFMUstate()
        self._state_times[state.value] = self.time
        return state

    def set_state(self, state: Any) -> None:
        self.fmu.setFMUstate(state)
        self.time = self._state_times.get(state.value, self.time)

    def free_state(self, state: Any) -> None:
        self._state_times.pop(state.value, None)
        self.fmu.freeFMUstate(state)

    def serialize(self) -> SerializedState:
        """The current FMU state, serialised (bytes that also carry the host's time)."""
        state = self.fmu.getFMUstate()
        try:
            return SerializedState(self.fmu.serializeFMUstate(state), self.time)
        finally:
            self.fmu.freeFMUstate(state)

    def deserialize(self, data: bytes, time: float | None = None) -> None:
        """Restore a serialised FMU state into this instance; the next sample steps from `time`
        (default: the time a SerializedState carries; plain bytes keep this host's time)."""
        errors = sum(m.status == "ERROR" for m in self.messages)
        state = self.fmu.deSerializeFMUstate(data)
        try:
            self.fmu.setFMUstate(state)
        finally:
            self.fmu.freeFMUstate(state)
        if time is None:
            time = getattr(data, "time", None)
        # a pythonfmu FMU answers a refused state with OK and an error in its log
        if time is not None and sum(m.status == "ERROR" for m in self.messages) == errors:
            self.time = time

    def close(self) -> None:
        """fmi2Terminate and fmi2FreeInstance; remove the extracted FMU if this object made it."""
        if self._open:
            self._open = False
            try:
                self.fmu.terminate()
            finally:
                self.fmu.freeInstance()
                if self._own_dir:
                    shutil.rmtree(self.unzip_dir, ignore_errors=True)

    def __enter__(self) -> FmuInstance:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _on_log(self, env: Any, instance: bytes, status: int, category: bytes | None,
                message: bytes) -> None:
        self.messages.append(
            LogMessage(
                instance.decode() if instance else "",
                STATUS[status] if 0 <= status < len(STATUS) else str(status),
                category.decode() if category else "",
                message.decode("utf-8", "replace") if message else "",
            )
        )


def _callbacks(logger: Any) -> fmi2CallbackFunctions:
    """FMI callbacks whose logger calls `logger` with the printf-formatted message."""
    from fmpy import calloc, free
    from fmpy.logging import addLoggerProxy

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    addLoggerProxy(byref(callbacks))
    return callbacks
