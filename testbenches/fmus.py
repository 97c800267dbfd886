"""Loading the project's FMUs into fmpy: one extraction per FMU file, instances by name.

`FmuHandle` wraps fmpy's FMU2Slave with what the master needs: variables by name (value
references looked up once), parameters set by name (enumeration items by their names), and every
FMI call's status checked (fmpy raises FMICallException on fmi2Error, fmi2Discard, fmi2Fatal).
"""

from __future__ import annotations

import atexit
import contextlib
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from fmu_src.variables import item_value
from fusion_core.registry import FILTER, FMU_NAMES, REFERENCES, estimator_class

ESTIMATOR_FMUS = FMU_NAMES
"""fusion_core.ESTIMATORS key -> FMU model name."""
PLANT_FMU = "ImuPlant"
SENSOR_FMU = "ImuSensor"
DEFAULT_FMU_DIR = Path("dist")
KINDS = ("auto", "native", "pythonfmu")
"""Which FMUs a testbench runs: the native FMI 2.0 FMUs (fmu_dir/native/fmi2), the pythonfmu
ones (fmu_dir), or auto: the native ones where they are built."""


def kind_dir(fmu_dir: Path | str, kind: str = "auto") -> Path:
    """The folder of the FMUs of one kind under a build folder (build_fmu.py --out)."""
    if kind not in KINDS:
        raise ValueError(f"FMU kind {kind!r}: allowed {', '.join(KINDS)}")
    native = Path(fmu_dir) / "native" / "fmi2"
    if kind == "native" or (kind == "auto" and (native / f"{PLANT_FMU}.fmu").is_file()):
        return native
    return Path(fmu_dir)


@dataclass
class _Unpacked:
    path: Path
    md: Any
    unzipdir: str


_CACHE: dict[Path, _Unpacked] = {}
_TMP = Path(tempfile.mkdtemp(prefix="testbench_fmus_"))
atexit.register(shutil.rmtree, _TMP, ignore_errors=True)


def extract_under(root: str) -> None:
    """Extract FMUs under root (a folder its creator removes): for worker processes, which end
    without running atexit handlers."""
    global _TMP
    _TMP = Path(tempfile.mkdtemp(prefix="worker_", dir=root))


def fmu_path(name: str, fmu_dir: Path | str = DEFAULT_FMU_DIR) -> Path:
    path = Path(fmu_dir) / f"{name}.fmu"
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} does not exist: build the FMUs first (python build_fmu.py --out {fmu_dir})"
        )
    return path


def unpack(path: Path) -> _Unpacked:
    """The model description and the extracted folder of an FMU file (cached per process)."""
    path = path.resolve()
    if path not in _CACHE:
        md = read_model_description(str(path))
        unzipdir = extract(str(path), unzipdir=str(_TMP / f"{path.stem}_{len(_CACHE)}"))
        _CACHE[path] = _Unpacked(path, md, unzipdir)
    return _CACHE[path]


def direct_calls(fmu: Any, *names: str) -> tuple[Any, ...]:
    """An FMU instance's FMI functions, by name, as the ctypes functions fmpy loaded (with their
    argument and result types): the hot loops call them without fmpy's wrapper, which costs
    three Python calls per FMI call to check the status. The caller checks the statuses."""
    return tuple(getattr(fmu.dll, name) for name in names)


def failed(handle: FmuHandle, calls: tuple[str, ...], statuses: tuple[int, ...], t: float,
           h: float) -> None:
    """Raise FMICallException for the first of an FMU's calls in the step [t, t+h] whose
    status was a failure (fmi2Discard or worse; the FMU's log says why)."""
    call, status = next((c, s) for c, s in zip(calls, statuses, strict=True) if s > 1)
    raise FMICallException(function=f"{handle.name} {call} (step at t = {t!r} s, h = {h!r} s)",
                           status=int(status))


class FmuHandle:
    """One instance of an FMU, driven by name."""

    def __init__(self, path: Path, instance_name: str) -> None:
        u = unpack(path)
        self.name = u.md.modelName
        self.md = u.md
        self.vars = {v.name: v for v in u.md.modelVariables}
        self.fmu = FMU2Slave(
            guid=u.md.guid,
            unzipDirectory=u.unzipdir,
            modelIdentifier=u.md.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self.fmu.instantiate()
        self.running = False

    def vrs(self, names: Iterable[str]) -> list[int]:
        """Value references of the named variables (ValueError naming an unknown one)."""
        out = []
        for n in names:
            if n not in self.vars:
                raise ValueError(f"{self.name} has no variable {n!r}")
            out.append(self.vars[n].valueReference)
        return out

    def set_parameters(self, params: Mapping[str, Any]) -> None:
        """Set parameters by name; a choice accepts its item name or its value."""
        for name, value in params.items():
            var = self.vars.get(name)
            if var is None or var.causality != "parameter":
                allowed = sorted(v.name for v in self.vars.values() if v.causality == "parameter")
                raise ValueError(f"{self.name} has no parameter {name!r}: it has {allowed}")
            vr = [var.valueReference]
            if var.type == "Real":
                setter, getter, value = self.fmu.setReal, self.fmu.getReal, float(value)
            elif var.type == "Boolean":
                setter, getter, value = self.fmu.setBoolean, self.fmu.getBoolean, bool(value)
            else:
                if isinstance(value, str):
                    try:
                        value = item_value(var, value)
                    except ValueError as err:
                        raise ValueError(f"{self.name}: {err}") from None
                setter, getter, value = self.fmu.setInteger, self.fmu.getInteger, int(value)
            # a native FMU refuses with fmi2Error, a pythonfmu FMU logs and keeps its value
            with contextlib.suppress(FMICallException):
                setter(vr, [value])
            back = getter(vr)[0]
            if back != value:  # the FMU logs why it refused; the master must not go on
                raise ValueError(
                    f"{self.name} refused {name} = {value!r} (it kept {back!r}); allowed: "
                    f"{var.description}"
                )

    def start(self, params: Mapping[str, Any], stop_time: float) -> None:
        """setupExperiment, parameters, initialisation mode in and out."""
        self.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)
        self.fmu.enterInitializationMode()
        self.set_parameters(params)
        self.fmu.exitInitializationMode()
        self.running = True

    def free(self) -> None:
        """Terminate (an instance that got as far as running; the FMI state machine allows
        terminate only then) and free the instance."""
        try:
            if self.running:
                self.fmu.terminate()
        finally:
            self.fmu.freeInstance()


def estimator_parameters(fmu: FmuHandle, key: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """params for estimator key's FMU: without the choice of the filter ("filter": "paper"),
    which the FMU's build made. ValueError, saying how to build the right one, where the FMU
    runs another class than params choose (its parameters are not that class's)."""
    cls = estimator_class(key, dict(params))
    have = {v.name for v in fmu.md.modelVariables if v.causality == "parameter"}
    if have != set(cls.param_specs()):
        paper = cls in REFERENCES.values()
        raise ValueError(
            f"the {fmu.name} FMU in this folder does not run the "
            f"{'paper' if paper else 'recommended'} filter ({cls.__name__}) these parameters "
            f"choose: build its FMUs with python build_fmu.py --preset "
            f"{'paper' if paper else 'recommended'} --out DIR and pass --fmu-dir DIR")
    return {k: v for k, v in params.items() if k != FILTER}
