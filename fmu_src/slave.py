"""FmuSlave: the pythonfmu slave base that every FMU of the project is built on.

A concrete FMU declares VARIABLES (a table of `Variable`) and `create_model(params)`, which
returns the Python object that does the work (the `Model` protocol: step, set_parameter,
get_state, set_state). Everything FMI is done here, once:

- registration: one pythonfmu variable per table row (nested=False, so names may hold dots);
  outputs get initial="exact" and their start value (pythonfmu writes no InitialUnknowns);
- modelDescription.xml: units, display units, ranges and enumeration types are added to what
  pythonfmu writes (`to_xml`, see model_description.py), plus the capability flags;
- no exception leaves a callback: pythonfmu turns one into fmi2Fatal, which ends the whole
  simulation. A failing doStep is logged and returns fmi2Discard; anything else is logged and
  the call does nothing;
- fast paths for what a host does every step (set the inputs, get the outputs): fmi2SetReal on
  Real inputs and fmi2GetReal/fmi2GetInteger write and read the value table directly through
  value-reference tables built once, instead of pythonfmu's per-variable setter and getter
  objects. Every other call (parameters, outputs, unknown references, a value that does not
  convert) takes the full guarded path, so the two give the same values, logs and results;
- parameters: every new value is checked against the table's range, then by building the
  model with it (before exitInitializationMode) or by `model.set_parameter` (tunable ones,
  while running), so the model's own checks (several parameters together) apply too. A refused
  value is logged as an error naming the parameter and its allowed range, and the previous value
  stays; a fixed parameter cannot change after initialisation;
- FMU state: the values of every variable plus the model's own `get_state()`, as JSON-ready
  data, so getFMUstate/setFMUstate and serialisation cover the whole filter state (pythonfmu's
  default only stores the registered variables);
- logging: `FmiLog` passes model warnings to the FMI logger (shown when the host switches debug
  logging on, e.g. `fmpy simulate --debug-logging`).
"""

from __future__ import annotations

import json
import math
import sys
import traceback
from collections.abc import Mapping
from functools import partial
from types import MappingProxyType
from typing import Any, ClassVar, Protocol

from pythonfmu import Boolean, DefaultExperiment, Fmi2Slave, Integer, Real
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability

from .variables import Variable

STATE_FORMAT = 2
"""Version of the FMU state layout (stored in every state; a mismatch is refused). 2: the
FMU's time is part of it."""

STEP_TIME_TOLERANCE = 1e-9
"""How far (relative, at least 1 s's worth) a communication point may lie from the FMU's time,
as in the native FMUs: masters sum their steps their own way, so the two differ by rounding; a
skipped or repeated step differs by a whole step."""

_PINNED_GLOBALS: list[dict[str, Any]] = []
"""Extra references to slave-module globals (see FmuSlave.__init_subclass__): 8 bytes per
instantiation, never released."""


class FmiLog:
    """What a model may log: warnings and errors, sent through the FMI logger callback."""

    def __init__(self, slave: Fmi2Slave) -> None:
        self._log = slave.log

    def info(self, message: str) -> None:
        self._log(_printf_safe(message), Fmi2Status.ok)

    def warning(self, message: str) -> None:
        self._log(_printf_safe(message), Fmi2Status.warning)

    def error(self, message: str) -> None:
        self._log(_printf_safe(message), Fmi2Status.error)


def _check_state_value(var: Variable, value: Any) -> None:
    """ValueError naming the variable unless a restored value is of its type and, for a parameter
    or an output, in its range (an output finite too; an input may hold anything a host may set,
    NaN included, since a bad sample is the model's to reject)."""
    types = {"Real": (int, float), "Integer": (int,), "Enumeration": (int,), "Boolean": (bool,)}
    boolean = isinstance(value, bool)
    if not isinstance(value, types[var.type]) or (var.type != "Boolean" and boolean):
        raise ValueError(f"state value of {var.name} is {value!r}, not a {var.type}")
    if var.causality == "input":
        return
    if var.causality == "output" and not math.isfinite(value):
        raise ValueError(f"state value of output {var.name} = {value!r} is not finite")
    try:
        var.check(value)
        if var.type == "Enumeration":
            var.to_model(value)
    except ValueError as err:
        raise ValueError(f"state value of {var.causality} {var.name}: {err}") from None


def _printf_safe(message: str) -> str:
    """The FMI logger callback takes the message as a printf format: escape '%'."""
    return message.replace("%", "%%")


class Model(Protocol):
    """The Python object an FMU wraps (an estimator, later the plant and the sensor model)."""

    def step(
        self, t: float, h: float, values: Mapping[str, Any], log: FmiLog
    ) -> Mapping[str, Any]:
        """Advance over the communication step [t, t+h] with the inputs in `values` (a read-only
        view of every variable by name); return the new output values by name. FmuSlave copies
        them into its table at once, so a model may refill and return the same dict each step."""
        ...

    def set_parameter(self, name: str, value: Any) -> None:
        """Change a tunable parameter of the running model; ValueError if not allowed."""
        ...

    def get_state(self) -> dict[str, Any]:
        """The whole internal state as JSON-ready data."""
        ...

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a get_state() result; ValueError if it does not fit."""
        ...

    # Optional: `initial_outputs(t) -> Mapping[str, Any]`, the output values of a model set up
    # for a start at time t (the plant's truth at t). FmuSlave writes them whenever the start
    # time or a parameter changes before the first step, so a master that reads the outputs
    # after initialisation (Jacobi) reads the model's own values, not the table's start values.


class FmuSlave(Fmi2Slave):
    """Base of every FMU: a variable table and a model object (see the module docstring)."""

    VARIABLES: ClassVar[tuple[Variable, ...]] = ()
    FMI_OPTIONS: ClassVar[dict[str, bool]] = {
        "needsExecutionTool": True,  # a Python interpreter with numpy must be present
        "canHandleVariableCommunicationStepSize": True,
        "canGetAndSetFMUstate": True,
        "canSerializeFMUstate": True,
    }
    author = "imu-fusion-fmu contributors"
    license = "MIT"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.01)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        # pythonfmu 0.7's fmi2Instantiate re-executes the slave module's source to find the
        # class, then Py_DECREFs the module's globals dict, a borrowed reference: every
        # instantiation takes one reference too many, and the second or third instance of an
        # FMU crashes the host when the dict is freed. The re-execution defines the class
        # again, which runs this hook: one extra reference each time balances the books.
        module = sys.modules.get(cls.__module__)
        if module is not None:
            _PINNED_GLOBALS.append(module.__dict__)

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._fmi_log = FmiLog(self)
        self._variables = {v.name: v for v in self.VARIABLES}
        self._values: dict[str, Any] = {v.name: v.start for v in self.VARIABLES}
        self._values.update(self.start_values())
        self._view = MappingProxyType(self._values)
        self._running = False
        self._terminated = False
        for var in self.VARIABLES:
            self.register_variable(self._scalar_variable(var), nested=False)
        self._fast_inputs, self._fast_reals, self._fast_integers = self._fast_tables()
        self._time = 0.0  # the start time, then the end of the last step
        self._model: Model = self.create_model(self.model_parameters())
        self._write_initial_outputs()

    # ----- to be provided by a concrete FMU ---------------------------------------------------
    def start_values(self) -> dict[str, Any]:
        """Start values that differ from the VARIABLES table's for this FMU (by name, in FMI
        form); none by default."""
        return {}

    def create_model(self, params: dict[str, Any]) -> Model:
        """A new model with these parameter values; ValueError naming a refused parameter."""
        raise NotImplementedError

    # ----- variables ----------------------------------------------------------------------------
    def _scalar_variable(self, var: Variable) -> Real | Integer | Boolean:
        kind = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "Enumeration": Integer}
        return kind[var.type](
            var.name,
            causality=Fmi2Causality[var.causality],
            variability=Fmi2Variability[var.variability or "continuous"],
            initial=Fmi2Initial[var.initial] if var.causality == "output" else None,
            description=var.description,
            getter=partial(self._values.__getitem__, var.name),
            setter=partial(self._set_value, var),
        )

    def _fast_tables(self) -> tuple[dict[int, str], dict[int, str], dict[int, str]]:
        """Value reference -> variable name, for the fast paths of set_real, get_real and
        get_integer: the Real inputs (setting one is `_values[name] = float(value)`, all that
        `_set_value` does for an input, as Variable.coerce of a Real is float()), every Real and
        every Integer (an Enumeration is an FMI Integer) variable (getting one is
        `float(_values[name])` / `int(_values[name])`, what pythonfmu's get_real/get_integer do
        with the getters registered in `_scalar_variable`).

        A subclass that overrides `_set_value` gets no fast inputs, so its own setter always
        runs."""
        by_name = {sv.name: vr for vr, sv in self.vars.items()}
        own_setter = type(self)._set_value is not FmuSlave._set_value
        inputs, reals, integers = {}, {}, {}
        for var in self.VARIABLES:
            vr = by_name[var.name]
            if var.type == "Real":
                reals[vr] = var.name
                if var.causality == "input" and not own_setter:
                    inputs[vr] = var.name
            elif var.type in ("Integer", "Enumeration"):
                integers[vr] = var.name
        return inputs, reals, integers

    def model_parameters(self) -> dict[str, Any]:
        """The current parameter values in the form the model takes (enumerations as names)."""
        return {
            name: var.to_model(self._values[name])
            for name, var in self._variables.items()
            if var.causality == "parameter"
        }

    def _set_value(self, var: Variable, value: Any) -> None:
        try:
            value = var.coerce(value)
            if var.causality == "input":
                self._values[var.name] = value
            elif var.causality == "parameter":
                self._set_parameter(var, value)
            else:
                self._fmi_log.error(f"{var.name} is an output: it cannot be set (value {value!r})")
        except Exception:
            self._log_exception(f"setting {var.name} = {value!r}")

    def _set_parameter(self, var: Variable, value: float | int | bool) -> None:
        old = self._values[var.name]
        if value == old:
            return
        try:
            var.check(value)
            model_value = var.to_model(value)
            if not self._running:
                # Nothing has been sampled yet: build the model anew with the new value, which
                # validates it together with the others (and fixed parameters may still change).
                params = self.model_parameters()
                params[var.name] = model_value
                self._model = self.create_model(params)
                self._write_initial_outputs()
            elif not var.tunable:
                raise ValueError(
                    f"parameter {var.name!r} is fixed after initialisation: set it before "
                    f"exitInitializationMode (allowed {var.allowed()})"
                )
            else:
                self._model.set_parameter(var.name, model_value)
        except ValueError as err:
            self._fmi_log.error(f"refused: {err}. {var.name} keeps its value {old!r}")
            return
        self._values[var.name] = value

    def _write_initial_outputs(self) -> None:
        initial = getattr(self._model, "initial_outputs", None)
        if initial is not None:
            self._values.update(initial(self._time))

    # ----- life cycle ---------------------------------------------------------------------------
    def setup_experiment(self, start_time: float, stop_time: float | None,
                         tolerance: float | None) -> None:
        if self._running:
            self._fmi_log.error(f"setupExperiment(startTime={start_time!r}) after "
                                "initialisation: ignored")
            return
        self._time = float(start_time)
        self._write_initial_outputs()

    def exit_initialization_mode(self) -> None:
        self._running = True
        self._terminated = False

    def terminate(self) -> None:
        self._terminated = True

    def do_step(self, current_time: float, step_size: float) -> bool:
        # The call sequence as far as pythonfmu lets a slave see it: a doStep out of sequence
        # or with a step size that is not > 0 is logged and answered with fmi2Discard (pythonfmu
        # has no fmi2Error for a slave to return), and nothing is stepped.
        why = ("before exitInitializationMode" if not self._running else
               "after terminate" if self._terminated else
               f"with a step size h = {step_size!r} that is not > 0"
               if not step_size > 0.0 else
               f"at a communication point other than the FMU's time {self._time!r} (the end "
               "of the last step, or the start time)"
               if not abs(current_time - self._time) <= STEP_TIME_TOLERANCE * max(
                   1.0, abs(self._time)) else "")
        if why:
            self._fmi_log.error(f"doStep(t={current_time!r}, h={step_size!r}) {why}: nothing "
                                "was stepped")
            return False
        try:
            outputs = self._model.step(current_time, step_size, self._view, self._fmi_log)
            self._values.update(outputs)
            self._time = current_time + step_size
        except Exception:
            self._log_exception(f"doStep(t={current_time!r}, h={step_size!r})")
            return False  # fmi2Discard
        return True

    # ----- pythonfmu entry points: fast paths, then the full guarded path -----------------------
    # pythonfmu's C++ wrapper calls these once per fmi2SetReal/fmi2GetReal/... with lists of
    # value references (and values); their Python cost is paid on every step of every host.
    # A fast path handles the calls a host makes every step with one dict operation per value;
    # any exception in it (a reference it does not handle, a value that does not convert) sends
    # the whole call to the full path, which logs exactly as before. The full path repeats the
    # call from the start: the inputs the fast path may already have written are written again
    # with the same values, and the fast getters write nothing.
    def get_real(self, vrs: list[int]) -> list[float]:
        try:
            values, names = self._values, self._fast_reals
            return [float(values[names[vr]]) for vr in vrs]
        except Exception:
            return self._guard_get(super().get_real, "fmi2GetReal", vrs, float("nan"))

    def get_integer(self, vrs: list[int]) -> list[int]:
        try:
            values, names = self._values, self._fast_integers
            return [int(values[names[vr]]) for vr in vrs]
        except Exception:
            return self._guard_get(super().get_integer, "fmi2GetInteger", vrs, 0)

    def get_boolean(self, vrs: list[int]) -> list[bool]:
        return self._guard_get(super().get_boolean, "fmi2GetBoolean", vrs, False)

    def set_real(self, vrs: list[int], values: list[float]) -> None:
        # Fast path: only Real inputs (a host's every step). Inputs are stored, never checked
        # here: a bad sample is the model's to reject at doStep (invalid_samples counts it).
        # zip stops at the shorter list, as in pythonfmu's set_real.
        try:
            table, names = self._values, self._fast_inputs
            for vr, value in zip(vrs, values, strict=False):
                table[names[vr]] = float(value)
        except Exception:
            self._guard(super().set_real, "fmi2SetReal", vrs, values)

    def set_integer(self, vrs: list[int], values: list[int]) -> None:
        self._guard(super().set_integer, "fmi2SetInteger", vrs, values)

    def set_boolean(self, vrs: list[int], values: list[bool]) -> None:
        self._guard(super().set_boolean, "fmi2SetBoolean", vrs, values)

    def _guard(self, setter: Any, what: str, vrs: list[int], values: list[Any]) -> None:
        try:
            setter(vrs, values)
        except Exception:
            self._log_exception(f"{what}{tuple(vrs)}")

    def _guard_get(self, getter: Any, what: str, vrs: list[int], default: Any) -> list[Any]:
        """getter(vrs), or `default` for every reference when it raises (logged)."""
        try:
            return getter(vrs)
        except Exception:
            self._log_exception(f"{what}{tuple(vrs)}")
            return [default] * len(vrs)

    def _log_exception(self, what: str) -> None:
        self._fmi_log.error(f"{what} failed, call ignored:\n{traceback.format_exc()}")

    # ----- FMU state ----------------------------------------------------------------------------
    def _get_fmu_state(self) -> dict[str, Any]:
        try:
            state = {
                "fmu": type(self).__name__,
                "format": STATE_FORMAT,
                "running": self._running,
                "time": self._time,
                "values": dict(self._values),
                "model": self._model.get_state(),
            }
            # A JSON round trip: the in-memory state is exactly what serialisation stores.
            return json.loads(json.dumps(state))
        except Exception:
            self._log_exception("fmi2GetFMUstate")
            return {"error": "fmi2GetFMUstate failed"}

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        try:
            self._restore(state)
        except Exception as err:
            self._fmi_log.error(f"fmi2SetFMUstate refused, the FMU keeps its state: {err!r}")

    def _restore(self, state: dict[str, Any]) -> None:
        if "error" in state:
            raise ValueError(state["error"])
        if state.get("fmu") != type(self).__name__ or state.get("format") != STATE_FORMAT:
            raise ValueError(
                f"state of {state.get('fmu')!r} (format {state.get('format')!r}) does not fit "
                f"{type(self).__name__} (format {STATE_FORMAT})"
            )
        values = state.get("values")
        if not isinstance(values, dict) or set(values) != set(self._values):
            raise ValueError("state variables differ from this FMU's variables")
        for name, var in self._variables.items():
            _check_state_value(var, values[name])
        if not isinstance(state.get("running"), bool):
            raise ValueError(f"state field 'running' = {state.get('running')!r} is not a bool")
        time = state.get("time")
        if not (isinstance(time, float) and math.isfinite(time)):
            raise ValueError(f"state field 'time' = {time!r} is not a finite float")
        params = {
            name: var.to_model(var.coerce(values[name]))
            for name, var in self._variables.items()
            if var.causality == "parameter"
        }
        model = self.create_model(params)
        model.set_state(json.loads(json.dumps(state["model"])))  # never share the state's lists
        self._model = model
        self._values.update({n: var.coerce(values[n]) for n, var in self._variables.items()})
        self._running = bool(state["running"])
        self._time = time

    @staticmethod
    def _fmu_state_to_bytes(state: dict[str, Any]) -> bytes:
        return json.dumps(state, separators=(",", ":")).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(state: bytes) -> dict[str, Any]:
        try:
            restored = json.loads(state.decode("utf-8"))
        except Exception as err:
            return {"error": f"serialized FMU state is not readable: {err!r}"}
        return restored if isinstance(restored, dict) else {"error": "not an FMU state"}

    # ----- modelDescription.xml -----------------------------------------------------------------
    def to_xml(self, model_options: dict[str, Any] | None = None) -> Any:
        """pythonfmu's model description plus units, ranges, types and capability flags."""
        from .model_description import decorate, project_version

        self.version = project_version()
        root = super().to_xml({**self.FMI_OPTIONS, **(model_options or {})})
        decorate(root, self.VARIABLES)
        return root
