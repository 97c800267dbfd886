"""The models behind the testbench's plant and sensor FMUs (fmu_src.slave's Model protocol).

They live here, not in the slave modules, because pythonfmu executes a slave module's source
again for every instance and keeps what it defines (fmu_src.slave.FmuSlave.__init_subclass__):
a slave module that only declares its FMU keeps that per-instance cost small.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

from fusion_core.scenarios import get_scenario
from fusion_core.sensor import ImuSensorModel
from fusion_core.synthetic import TRUTH_NAMES, Trajectory

from .slave import FmiLog
from .variables import Variable


def truth(trajectory: Trajectory, t: float) -> dict[str, float]:
    """The output values: the trajectory's truth at time t, by variable name (plain-float
    evaluation: the same values as Trajectory.truth, without numpy's per-call cost)."""
    return dict(zip(TRUTH_NAMES, trajectory.truth_at(t), strict=True))


@functools.lru_cache(maxsize=1)
def plant_start() -> dict[str, float]:
    """The plant's outputs before its first step (scenario 0 at t = 0): its start values."""
    return truth(get_scenario(0).trajectory(), 0.0)


class PlantModel:
    """A scenario's truth, sampled at the end of each communication step."""

    def __init__(self, params: dict[str, Any]) -> None:
        self.scenario = get_scenario(int(params["scenario"]))
        self.trajectory = self.scenario.trajectory()

    def initial_outputs(self, t: float) -> dict[str, float]:
        """The truth at the start time: what a master reads before the first step."""
        return truth(self.trajectory, t)

    def step(self, t: float, h: float, values: Mapping[str, Any], log: FmiLog) -> dict[str, Any]:
        return truth(self.trajectory, t + h)

    def set_parameter(self, name: str, value: Any) -> None:
        raise ValueError(f"parameter {name!r} is fixed after initialisation")

    def get_state(self) -> dict[str, Any]:
        return {"scenario": self.scenario.id}  # the truth is a function of time only

    def set_state(self, state: dict[str, Any]) -> None:
        if state.get("scenario") != self.scenario.id:
            raise ValueError(f"a state of scenario {state.get('scenario')!r} does not fit "
                             f"parameter scenario = {self.scenario.id}")


INPUTS_AT = Variable(
    "inputs_at", "parameter", "Integer",
    "When the inputs set before doStep(t, h) hold: 1 = end (at t+h: the plant stepped first, "
    "as a Gauss-Seidel master has it; the sample covers [t, t+h]) or 2 = start (at t: the "
    "plant's outputs of the step before, as libcosim, Ecos and parallel containers pass them; "
    "the sample covers the step before). Matters where the steps vary: dt is then the right "
    "step's. Allowed: 1 = end, 2 = start; default 'end'; fixed after initialisation",
    1, variability="fixed", low=1, high=2, items=("end", "start"))
"""The sensor FMU's master timing parameter (its own, not the sensor model's)."""


def sample_interval(h: float, values: Mapping[str, Any]) -> float:
    """The interval a sensor sample covers: the step h where the inputs hold at its end, the
    step before (last_step) where they hold at its start (the first sample: h)."""
    last = values["last_step"]
    return h if values["inputs_at"] == 1 or not last > 0.0 else last


class SensorModel:
    """ImuSensorModel behind the FmuSlave model protocol."""

    def __init__(self, params: dict[str, Any]) -> None:
        self.model = ImuSensorModel(**{k: v for k, v in params.items() if k != INPUTS_AT.name})

    def step(self, t: float, h: float, values: Mapping[str, Any], log: FmiLog) -> dict[str, Any]:
        acc, gyro, dt = self.model.sample(
            (values["omega_x"], values["omega_y"], values["omega_z"]),
            (values["f_x"], values["f_y"], values["f_z"]),
            sample_interval(h, values),
        )
        bias = self.model.gyro_bias
        return {"acc_x": acc[0], "acc_y": acc[1], "acc_z": acc[2],
                "gyro_x": gyro[0], "gyro_y": gyro[1], "gyro_z": gyro[2], "dt": dt,
                "true_bias_x": bias[0], "true_bias_y": bias[1], "true_bias_z": bias[2],
                "last_step": h}

    def set_parameter(self, name: str, value: Any) -> None:
        self.model.set_param(name, value)

    def get_state(self) -> dict[str, Any]:
        return self.model.get_state()

    def set_state(self, state: dict[str, Any]) -> None:
        self.model.set_state(state)
