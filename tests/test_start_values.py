"""What the FMUs' outputs read before the first step (docs/interface.md, Timing): a Jacobi
master (libcosim, Ecos, a parallel container) or a tool that reads outputs after initialisation
passes them on as if they were a step's, so none may plant a false sample.

- ImuPlant: its truth at the start time for the scenario chosen, from the moment the start time
  or the scenario is set (not the start values of the default scenario);
- ImuSensor: dt = 0, which every estimator refuses and counts (no sample);
so an estimator that reads them first rejects one sample and starts from the truth's first one.
"""

from __future__ import annotations

import numpy as np
import pytest
from native_fmu import NativeFmu

from fusion_core.scenarios import get_scenario
from fusion_core.synthetic import TRUTH_NAMES

KINDS = ("fmi2", "fmi3", "pythonfmu")


def _fmu(built_fmus, kind: str, name: str) -> NativeFmu:
    path = built_fmus.path(name) if kind == "pythonfmu" else built_fmus.native(kind, name)
    fmu = NativeFmu(path, instance=f"{name}-{kind}")
    fmu.instantiate()
    return fmu


def _enter_initialisation(fmu: NativeFmu, start: float) -> None:
    if fmu.version == "fmi3":
        fmu.fmu.enterInitializationMode(startTime=start)
    else:
        fmu.fmu.setupExperiment(startTime=start)
        fmu.fmu.enterInitializationMode()


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("start", [0.0, 2.5])
def test_the_plants_outputs_before_the_first_step_are_the_chosen_scenarios_truth(
        built_fmus, kind, start):
    scenario = get_scenario("moderate_dynamics")
    truth = dict(zip(TRUTH_NAMES, scenario.trajectory().truth_at(start), strict=True))
    assert abs(truth["pitch"]) > 0.1  # not the level start of the default scenario
    plant = _fmu(built_fmus, kind, "ImuPlant")
    try:
        _enter_initialisation(plant, start)
        plant.set("scenario", scenario.id)
        in_initialisation = {n: plant.get(n) for n in TRUTH_NAMES}
        plant.fmu.exitInitializationMode()
        after = {n: plant.get(n) for n in TRUTH_NAMES}
    finally:
        plant.free()
    assert in_initialisation == truth
    assert after == truth


@pytest.mark.parametrize("kind", KINDS)
def test_the_sensors_outputs_before_the_first_step_are_no_sample(built_fmus, kind):
    sensor = _fmu(built_fmus, kind, "ImuSensor")
    kf = _fmu(built_fmus, kind, "AngleBiasKalmanFilter")
    try:
        sensor.start()
        kf.start()
        start = {n: sensor.get(n) for n in ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y",
                                             "gyro_z", "dt")}
        assert start["dt"] == 0.0
        kf.step(0.0, 0.01, **start)  # what a Jacobi master's first step hands on
        assert kf.get("invalid_samples") == 1
        assert (kf.get("roll"), kf.get("pitch")) == (0.0, 0.0)  # no estimate taken from it
        tilted = {"acc_x": 0.0, "acc_y": 9.80665 * np.sin(0.3), "acc_z": 9.80665 * np.cos(0.3),
                  "gyro_x": 0.0, "gyro_y": 0.0, "gyro_z": 0.0, "dt": 0.01}
        kf.step(0.01, 0.01, **tilted)  # the first real sample initialises the filter
        assert kf.get("roll") == pytest.approx(0.3, abs=1e-12)
    finally:
        sensor.free()
        kf.free()


@pytest.mark.parametrize("kind", KINDS)
def test_the_plants_outputs_are_calculated_in_initialisation_from_the_scenario(built_fmus, kind):
    """No start value a tool could take for the truth: each output is initial="calculated",
    listed among the initial unknowns with the scenario as what it depends on."""
    from fmpy import read_model_description

    path = (built_fmus.path("ImuPlant") if kind == "pythonfmu"
            else built_fmus.native(kind, "ImuPlant"))
    md = read_model_description(str(path))
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    assert {v.initial for v in outputs} == {"calculated"}
    assert all(v.start is None for v in outputs)
    scenario = next(v for v in md.modelVariables if v.name == "scenario")
    unknowns = {u.variable.name: [d.name for d in u.dependencies] for u in md.initialUnknowns}
    assert unknowns == {v.name: [scenario.name] for v in outputs}
