"""The estimator helper: everything the five estimator FMUs share, on top of FmuSlave.

Variables (docs/interface.md): inputs acc_x..z [m/s2], gyro_x..z [rad/s], dt [s];
outputs roll, pitch [rad], bias_x..z [rad/s], invalid_samples [1] and, for the position filter,
pos_x..z [m], vel_x..z [m/s]; one parameter per fusion_core `Param` of the estimator class.

Sample semantics: the inputs set before doStep(t, h) are one new IMU sample (taken at t+h; dt is
the time since the previous sample, and the estimator integrates over dt, not over h); the
first doStep's sample initialises the estimator from the accelerometer; values set during
initialisation are not a sample; the outputs after doStep(t, h) are the estimate for that
sample. A rejected sample (NaN/inf, dt <= 0, dt > max_dt, a rate above max_rate) leaves the
filter state exactly as it was, counts in invalid_samples, logs a warning and the step returns OK.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from functools import partial
from operator import itemgetter
from pathlib import Path
from typing import Any, ClassVar

from fusion_core import G, InvalidSample
from fusion_core.base import Estimator
from fusion_core.types import Estimate

from .names import PRESET_FILE
from .slave import FmiLog, FmuSlave
from .variables import (
    Variable,
    integer_output,
    parameter_variable,
    real_input,
    real_output,
    variable_table,
)

AXES = ("x", "y", "z")
PAPER_NOTE = (" Built with the preset 'paper': the paper's own filter at its values "
              "(fusion_core.papers.{name}).")
"""What a paper's filter adds to its FMU's description."""


def preset_starts(key: str, resources: str | None = None) -> dict[str, Any]:
    """The preset entry an FMU of estimator key was built with, from PRESET_FILE in its
    resources folder (the build writes it there, fmu_src.build; checked when it was written):
    {} for the recommended values, the defaults; "filter": "paper" chooses the paper's filter
    (fusion_core.registry)."""
    path = Path(resources) / PRESET_FILE if resources else None
    if path is None or not path.is_file():
        return {}
    return dict(json.loads(path.read_text()).get(key, {}))


def estimator_table(key: str, entry: Mapping[str, Any]
                    ) -> tuple[type[Estimator], tuple[Variable, ...]]:
    """The estimator class a preset entry chooses for key and its FMU's variable table, the
    entry's values as start values; built once per process for each class and entry."""
    from fusion_core.registry import FILTER, estimator_class

    cls = estimator_class(key, dict(entry))
    starts = {k: v for k, v in entry.items() if k != FILTER}
    table = variable_table(
        f"{cls.__name__} {json.dumps(starts, sort_keys=True)}",
        partial(estimator_variables, cls, cls.ZERO_BIAS or None, starts))
    return cls, table


def model_description(text: str, cls: type[Estimator]) -> str:
    """An estimator FMU's description: its model's text, and for a paper's filter a note."""
    from fusion_core.registry import REFERENCES

    paper = cls in REFERENCES.values()
    return text + (PAPER_NOTE.format(name=cls.__name__) if paper else "")


def estimator_variables(
    cls: type[Estimator], zero_bias: Mapping[str, str] | None = None,
    starts: Mapping[str, Any] | None = None,
) -> tuple[Variable, ...]:
    """The variable table of an estimator FMU: INTERFACE.md's inputs and outputs, then one
    parameter per `cls.param_specs()` entry, starting at starts' value where it names one.
    zero_bias maps bias outputs that are always 0 to the reason, which goes into their
    description."""
    zero_bias = dict(zero_bias or {})
    starts = dict(starts or {})
    first = cls().last
    axis_word = {"x": "x (forward)", "y": "y (left)", "z": "z (up)"}
    inputs = (
        *(
            real_input(
                f"acc_{a}", "m/s2",
                f"Accelerometer sample: specific force along body {axis_word[a]}; a sensor "
                "lying still and level reads (0, 0, +9.80665)",
                G if a == "z" else 0.0,
            )
            for a in AXES
        ),
        *(
            real_input(
                f"gyro_{a}", "rad/s",
                f"Gyro sample: body angular rate about {axis_word[a]}", display_unit="deg/s",
            )
            for a in AXES
        ),
        real_input(
            "dt", "s",
            "Time since the previous IMU sample; the estimator integrates over dt, not over the "
            "communication step. Ignored for the first sample (which initialises the attitude "
            "from the accelerometer); dt <= 0 or dt > max_dt rejects the sample",
            0.01,
        ),
    )
    outputs: list[Variable] = [
        real_output(
            "roll", "rad",
            "Roll estimate phi (Z-Y-X Euler angle about body x), in (-pi, pi], at the time of "
            "the last sample processed", first.roll, "deg",
        ),
        real_output(
            "pitch", "rad",
            "Pitch estimate theta (Z-Y-X Euler angle about body y), in [-pi/2, pi/2], at the "
            "time of the last sample processed", first.pitch, "deg",
        ),
    ]
    for a, b in zip(AXES, first.bias, strict=True):
        name = f"bias_{a}"
        note = f"; {zero_bias.pop(name)}" if name in zero_bias else ""
        outputs.append(
            real_output(name, "rad/s", f"Gyro bias estimate about body {a}{note}", b, "deg/s")
        )
    if zero_bias:
        raise ValueError(f"zero_bias names unknown outputs: {sorted(zero_bias)}")
    outputs.append(
        integer_output(
            "invalid_samples",
            "Samples rejected so far (a NaN or infinite value, dt <= 0, dt > max_dt, a gyro "
            "rate above max_rate); a rejected sample leaves the filter state unchanged",
        )
    )
    if cls.HAS_POSITION:
        pos = first.pos or (0.0, 0.0, 0.0)
        vel = first.vel or (0.0, 0.0, 0.0)
        outputs += [
            real_output(f"pos_{a}", "m", f"Position estimate along level-frame {a} (start "
                        "heading frame, origin at the first sample)", p)
            for a, p in zip(AXES, pos, strict=True)
        ]
        outputs += [
            real_output(f"vel_{a}", "m/s", f"Velocity estimate along level-frame {a}", v)
            for a, v in zip(AXES, vel, strict=True)
        ]
    params = tuple(
        parameter_variable(dataclasses.replace(p, default=starts.get(p.name, p.default)))
        for p in cls.param_specs().values()
    )
    table = (*inputs, *outputs, *params)
    names = [v.name for v in table]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise ValueError(f"{cls.__name__}: parameter names clash with FMU variables: {clash}")
    return table


ACC_INPUTS = tuple(f"acc_{a}" for a in AXES)
GYRO_INPUTS = tuple(f"gyro_{a}" for a in AXES)
_ZERO3 = (0.0, 0.0, 0.0)


class EstimatorModel:
    """A fusion_core estimator as an FmuSlave model: one sample per doStep.

    This runs on every doStep, so what can be prepared is prepared once: the readers of the
    acc and gyro triples (`operator.itemgetter`, one C call for three values) and the output
    dict, which each step refills in place (cheaper than building a new dict: FmuSlave copies
    the returned values into its table at once and keeps no reference to the dict).
    """

    def __init__(self, cls: type[Estimator], params: dict[str, Any]) -> None:
        from fusion_core.native import stepper

        self.estimator = cls(**params)
        self.invalid_samples = 0
        self._position = cls.HAS_POSITION
        self._acc = itemgetter(*ACC_INPUTS)
        self._gyro = itemgetter(*GYRO_INPUTS)
        self._out: dict[str, Any] = {}
        self.outputs(self.estimator.last)  # every output key, in a fixed order
        # The samples go through the C twin where it loads (fusion_core.native.Stepper: the
        # same outputs, to the bit, at the twin's speed), else through the Python estimator.
        self._stepper = stepper(self.estimator)
        self._names = ("roll", "pitch", "bias_x", "bias_y", "bias_z") + (
            tuple(f"{q}_{a}" for q in ("pos", "vel") for a in AXES) if self._position else ())

    def step(
        self, t: float, h: float, values: Mapping[str, Any], log: FmiLog
    ) -> dict[str, Any]:
        est = self.estimator
        acc, gyro, dt = self._acc(values), self._gyro(values), values["dt"]
        st = self._stepper
        if st is not None:
            taken = st.step(acc, gyro, dt)
            if not taken:
                self._rejected(t + h, est, acc, gyro, dt, log)
            out = self._out
            out.update(zip(self._names, st.last(), strict=True))
            out["invalid_samples"] = self.invalid_samples
            return out
        try:
            # Every sample goes to the estimator, which checks it (fusion_core's step): a bad
            # one raises InvalidSample and leaves the filter state as it was.
            estimate = est.step(acc, gyro, dt)
        except InvalidSample as err:
            self._count(t + h, str(err), log)
            estimate = est.last
        return self.outputs(estimate)

    def _rejected(self, t: float, est: Estimator, acc: Any, gyro: Any, dt: float,
                  log: FmiLog) -> None:
        """A sample the twin rejected: counted and logged with the sample rules' reason."""
        try:
            est.check_sample(acc, gyro, dt)
            reason = "rejected by the sample rules"
        except InvalidSample as err:
            reason = str(err)
        self._count(t, reason, log)

    def _count(self, t: float, reason: str, log: FmiLog) -> None:
        self.invalid_samples += 1
        log.warning(f"sample at t = {t:.9g} s rejected, the filter state is kept: {reason} "
                    f"({self.invalid_samples} rejected so far)")

    def outputs(self, e: Estimate) -> dict[str, Any]:
        """The output values for an estimate, in the model's output dict (refilled on every
        call: copy it to keep the values)."""
        out = self._out
        out["roll"] = e.roll
        out["pitch"] = e.pitch
        out["bias_x"], out["bias_y"], out["bias_z"] = e.bias
        out["invalid_samples"] = self.invalid_samples
        if self._position:
            out["pos_x"], out["pos_y"], out["pos_z"] = e.pos or _ZERO3
            out["vel_x"], out["vel_y"], out["vel_z"] = e.vel or _ZERO3
        return out

    def set_parameter(self, name: str, value: Any) -> None:
        if self._stepper is not None:
            self._stepper.sync()
        self.estimator.set_param(name, value)
        if self._stepper is not None:
            self._stepper.load()

    def get_state(self) -> dict[str, Any]:
        if self._stepper is not None:
            self._stepper.sync()
        return {"estimator": self.estimator.get_state(), "invalid_samples": self.invalid_samples}

    def set_state(self, state: dict[str, Any]) -> None:
        count = state.get("invalid_samples")
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise ValueError(f"state field invalid_samples = {count!r} is not a count")
        self.estimator.set_state(state.get("estimator"))
        self.invalid_samples = count
        if self._stepper is not None:
            self._stepper.load()


class EstimatorSlave(FmuSlave):
    """Base of the estimator FMUs: a subclass names its estimator and its paper.

    Class attributes of a subclass: `key` (the estimator's key, fusion_core.registry) and
    `description` (the modelDescription text naming the paper). Which class it runs (the
    recommended one or the paper's, fusion_core.papers) and its start values are the preset it
    was built with (preset_starts), read per instance from the FMU's own resources, so that
    they hold even where another FMU's fmu_src was imported first in the same process.
    """

    key: ClassVar[str]

    def __init__(self, **kwargs: Any) -> None:
        entry = preset_starts(self.key, kwargs.get("resources"))
        self.estimator, self.VARIABLES = estimator_table(self.key, entry)
        super().__init__(**kwargs)
        self.description = model_description(type(self).description, self.estimator)

    def create_model(self, params: dict[str, Any]) -> EstimatorModel:
        return EstimatorModel(self.estimator, params)

    def to_xml(self, model_options: dict[str, Any] | None = None) -> Any:
        """FmuSlave's, with this instance's description (pythonfmu takes the class's)."""
        root = super().to_xml(model_options)
        root.set("description", self.description)
        return root
