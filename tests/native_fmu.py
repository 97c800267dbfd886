"""A thin driver of one native FMU instance, FMI 2.0 or FMI 3.0, through fmpy's low-level calls,
with the log lines the FMU sends kept for the tests (tests/test_native_fmu.py)."""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2CoSimulation,
)
from fmpy.fmi3 import FMU3Slave

_libc = ctypes.CDLL(None)
_calloc = _libc.calloc
_calloc.restype = ctypes.c_void_p
_free = _libc.free


class NativeFmu:
    """One instance: values by name, every status checked by fmpy (FMICallException)."""

    def __init__(self, path: Path, unzipdir: str | None = None, instance: str = "test",
                 token: str | None = None) -> None:
        self.md = read_model_description(str(path))
        self.version = "fmi3" if self.md.fmiVersion.startswith("3") else "fmi2"
        self.unzipdir = unzipdir or extract(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.log: list[tuple[int, str]] = []
        cls = FMU3Slave if self.version == "fmi3" else FMU2Slave
        guid = self.md.instantiationToken if self.version == "fmi3" else self.md.guid
        self.fmu = cls(guid=token or guid, unzipDirectory=self.unzipdir,
                       modelIdentifier=self.md.coSimulation.modelIdentifier,
                       instanceName=instance)
        self._keep: list[Any] = []

    def _record(self, status: int, message: bytes | str | None) -> None:
        text = message.decode() if isinstance(message, bytes) else str(message)
        self.log.append((int(status), text))

    def instantiate(self) -> None:
        """Instantiate with logging on and a logger that records every line."""
        if self.version == "fmi3":
            def log3(env, status, category, message):
                self._record(status, message)
            self.fmu.instantiate(loggingOn=True, logMessage=log3)
            return
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, message: self._record(status, message))
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_free)
        # No fmpy logger proxy: it keeps one logger for the whole process, so every instance's
        # lines would reach the last instance's logger. The messages hold no printf arguments.
        self._keep.append(callbacks)
        self.fmu.instantiate(callbacks=callbacks, loggingOn=True)

    def raw_instantiate(self) -> Any:
        """The instantiate call itself (the instance pointer, None when refused)."""
        try:
            self.instantiate()
        except Exception:
            return None
        return self.fmu.component

    def start(self, **params: float) -> None:
        if self.version == "fmi3":
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        for name, value in params.items():
            self.set(name, value)
        self.fmu.exitInitializationMode()

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def set(self, name: str, value: float) -> None:
        v = self.vars[name]
        if v.type in ("Real", "Float64"):
            (self.fmu.setFloat64 if self.version == "fmi3" else self.fmu.setReal)(
                [v.valueReference], [float(value)])
        elif v.type == "Boolean":
            self.fmu.setBoolean([v.valueReference], [bool(value)])
        elif v.type == "Enumeration" and self.version == "fmi3":
            self.fmu.setInt64([v.valueReference], [int(value)])
        elif self.version == "fmi3":
            self.fmu.setInt32([v.valueReference], [int(value)])
        else:
            self.fmu.setInteger([v.valueReference], [int(value)])

    def get(self, name: str) -> float:
        v = self.vars[name]
        if v.type in ("Real", "Float64"):
            return (self.fmu.getFloat64 if self.version == "fmi3" else self.fmu.getReal)(
                [v.valueReference])[0]
        if v.type == "Boolean":
            return self.fmu.getBoolean([v.valueReference])[0]
        if v.type == "Enumeration" and self.version == "fmi3":
            return self.fmu.getInt64([v.valueReference])[0]
        if self.version == "fmi3":
            return self.fmu.getInt32([v.valueReference])[0]
        return self.fmu.getInteger([v.valueReference])[0]

    def get_reals(self, names: list[str]) -> list[float]:
        """The Real (Float64) variables names, in one call."""
        vrs = [self.vars[n].valueReference for n in names]
        return list((self.fmu.getFloat64 if self.version == "fmi3" else self.fmu.getReal)(vrs))

    def set_reals(self, values: dict[str, float]) -> None:
        """The Real (Float64) variables of values, in one call."""
        vrs = [self.vars[n].valueReference for n in values]
        (self.fmu.setFloat64 if self.version == "fmi3" else self.fmu.setReal)(
            vrs, [float(v) for v in values.values()])

    def step(self, t: float, h: float, **inputs: float) -> None:
        """Set the inputs (the Real ones in one call) and step from t by h."""
        real = {n: v for n, v in inputs.items() if self.vars[n].type in ("Real", "Float64")}
        if real:
            self.set_reals(real)
        for name, value in inputs.items():
            if name not in real:
                self.set(name, value)
        self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)

    def save(self) -> Any:
        return self.fmu.getFMUState() if self.version == "fmi3" else self.fmu.getFMUstate()

    def restore(self, state: Any) -> None:
        (self.fmu.setFMUState if self.version == "fmi3" else self.fmu.setFMUstate)(state)

    def serialize(self, state: Any) -> bytes:
        return (self.fmu.serializeFMUState if self.version == "fmi3"
                else self.fmu.serializeFMUstate)(state)

    def deserialize(self, data: bytes) -> Any:
        return (self.fmu.deserializeFMUState if self.version == "fmi3"
                else self.fmu.deSerializeFMUstate)(data)

    def terminate(self) -> None:
        self.fmu.terminate()

    def free(self) -> None:
        self.fmu.freeInstance()


def refused(call: Any, *args: Any, **kwargs: Any) -> bool:
    """Whether an fmpy call raised FMICallException with status fmi2Error / fmi3Error (3)."""
    try:
        call(*args, **kwargs)
    except FMICallException as err:
        return err.status == 3
    return False


FMI2_COSIMULATION = fmi2CoSimulation
