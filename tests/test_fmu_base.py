"""FmuSlave is general: a non-estimator FMU from a variable table and a model object (the way
the plant and sensor FMUs will be built) gets the same validation, ranges, state and logging."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from fmu_src.host import FmuInstance

REPO = Path(__file__).resolve().parents[1]

TOY_MODULE = '''
"""A toy FMU for the FmuSlave tests: y = integral of gain * u, optionally clamped to [-1, 1]."""
from fmu_src.slave import FmuSlave
from fmu_src.variables import Variable, integer_output, real_input, real_output


class Accumulator:
    def __init__(self, gain, clamp):
        self.gain, self.clamp, self.y, self.steps = gain, clamp, 0.0, 0

    def step(self, t, h, values, log):
        self.y += self.gain * values["u"] * h
        self.steps += 1
        if self.clamp and abs(self.y) > 1.0:
            log.warning(f"y = {self.y} clamped to [-1, 1] at t = {t + h}")
            self.y = max(-1.0, min(1.0, self.y))
        return {"y": self.y, "steps": self.steps}

    def set_parameter(self, name, value):
        setattr(self, name, value)

    def get_state(self):
        return {"y": self.y, "steps": self.steps}

    def set_state(self, state):
        self.y, self.steps = state["y"], state["steps"]


class ToyIntegrator(FmuSlave):
    description = "Toy integrator for the FmuSlave tests"
    VARIABLES = (
        real_input("u", "m/s", "Rate to integrate"),
        real_output("y", "m", "Integral of gain * u"),
        integer_output("steps", "doStep calls so far"),
        Variable("gain", "parameter", "Real", "Gain on u", 1.0, unit="1", low=0.0, high=10.0),
        Variable("clamp", "parameter", "Boolean", "Clamp y to [-1, 1]", False,
                 variability="fixed"),
    )

    def create_model(self, params):
        return Accumulator(**params)
'''


@pytest.fixture(scope="module")
def toy_fmu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("toy_src") / "toy_integrator_fmu.py"
    src.write_text(TOY_MODULE)
    out = tmp_path_factory.mktemp("toy_fmu")
    subprocess.run(
        [sys.executable, "-c", "import sys; from pathlib import Path; from fmu_src.build import "
         "build_script; build_script(Path(sys.argv[1]), Path(sys.argv[2]))", str(src), str(out)],
        cwd=REPO, check=True, capture_output=True, timeout=300,
    )
    return out / "ToyIntegrator.fmu"


def test_toy_fmu_validates_with_units_and_types(toy_fmu):
    assert validate_fmu(str(toy_fmu)) == []
    md = read_model_description(str(toy_fmu))
    v = {x.name: x for x in md.modelVariables}
    assert (v["u"].unit, v["y"].unit, v["gain"].unit) == ("m/s", "m", "1")
    assert (v["gain"].min, v["gain"].max) == ("0.0", "10.0")
    assert v["steps"].type == "Integer" and v["steps"].variability == "discrete"
    assert v["clamp"].type == "Boolean" and v["clamp"].variability == "fixed"
    assert md.coSimulation.canSerializeFMUstate


def test_toy_fmu_steps_logs_and_refuses_out_of_range_parameters(toy_fmu):
    with FmuInstance(toy_fmu, parameters={"clamp": True, "gain": 11.0}) as fmu:
        for _ in range(30):
            fmu.set({"u": 5.0})
            fmu.fmu.doStep(currentCommunicationPoint=fmu.time, communicationStepSize=0.01)
            fmu.time += 0.01
        assert fmu.get("y") == 1.0 and fmu.get("steps") == 30  # 30 * 0.01 * 5 > 1: clamped
        fmu.set({"gain": float("nan")})
        fmu.set({"clamp": False})  # fixed: refused after initialisation
        errors = [m.message for m in fmu.messages if m.status == "ERROR"]
        warnings = [m.message for m in fmu.messages if m.status == "WARNING"]
        assert fmu.get("gain") == 1.0 and fmu.get("clamp") is True
    assert len(errors) == 3
    assert "'gain'=11.0 is out of range: allowed [0.0, 10.0]" in errors[0]
    assert "'gain'=nan is out of range" in errors[1]
    assert "'clamp' is fixed after initialisation" in errors[2]
    assert len(warnings) == 11 and "clamped" in warnings[0]  # steps 20 to 30


def test_toy_fmu_state_continues_in_a_fresh_instance(toy_fmu):
    with FmuInstance(toy_fmu, parameters={"gain": 2.0}) as first:
        first.set({"u": 0.3})
        first.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.5)
        data = first.serialize()
    with FmuInstance(toy_fmu) as second:
        second.deserialize(data)
        assert (second.get("y"), second.get("steps"), second.get("gain")) == (0.3, 1, 2.0)
        assert second.get("u") == 0.3  # inputs are part of the FMU state
        second.fmu.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.5)
        assert second.get("y") == pytest.approx(0.6, abs=1e-15) and second.get("steps") == 2
