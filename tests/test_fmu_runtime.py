"""Estimator FMUs compute exactly what fusion_core computes, one IMU sample per doStep."""

from __future__ import annotations

import numpy as np

import fusion_core
from fmu_src.host import FmuInstance

TOLERANCE = 1e-12
"""|FMU - fusion_core| allowed on every output [rad, rad/s, m, m/s] (the issue's figure)."""

OUTPUTS = ("roll", "pitch", "bias")

IMU = ("acc_meas", "gyro_meas", "dt")
"""The keys of a synthetic.record() recording that make up the IMU samples."""


def max_difference(out: dict, ref: dict, keys: tuple[str, ...]) -> float:
    return max(float(np.max(np.abs(np.asarray(out[k]) - np.asarray(ref[k])))) for k in keys)


def output_keys(key: str) -> tuple[str, ...]:
    return OUTPUTS + (("pos", "vel") if fusion_core.ESTIMATORS[key].HAS_POSITION else ())


def test_outputs_equal_fusion_core_run(fmu_path, fmu_key, fmu_recording, fusion_core_run):
    acc, gyro, dt = fmu_recording["acc_meas"], fmu_recording["gyro_meas"], fmu_recording["dt"]
    ref = fusion_core_run(fmu_key, acc, gyro, dt)
    with FmuInstance(fmu_path) as fmu:
        out = fmu.run_samples(acc, gyro, dt)
    assert len(out["roll"]) == len(acc) == 1200
    assert max_difference(out, ref, output_keys(fmu_key)) <= TOLERANCE
    assert np.all(out["invalid_samples"] == 0)


def test_estimator_integrates_over_dt_not_the_communication_step(
    fmu_path, fmu_key, fmu_recording, fusion_core_run
):
    # Samples at 100 Hz (dt = 0.01 s) fed with a communication step of 0.025 s.
    acc, gyro, dt = (fmu_recording[k][:300] for k in IMU)
    ref = fusion_core_run(fmu_key, acc, gyro, dt)
    with FmuInstance(fmu_path) as fmu:
        out = fmu.run_samples(acc, gyro, dt, h=0.025)
    assert max_difference(out, ref, output_keys(fmu_key)) <= TOLERANCE


def test_inputs_set_during_initialisation_are_not_a_sample(fmu_path, fmu_key, fusion_core_run):
    tilted = (0.0, fusion_core.G * np.sin(0.5), fusion_core.G * np.cos(0.5))  # roll 0.5 rad
    level = (0.0, 0.0, fusion_core.G)
    with FmuInstance(fmu_path, parameters={"acc_x": tilted[0], "acc_y": tilted[1],
                                           "acc_z": tilted[2], "dt": 0.01}) as fmu:
        assert fmu.get("roll") == 0.0  # the start value: nothing has been sampled yet
        out = fmu.run_samples([level, level], [(0.0, 0.0, 0.0)] * 2, 0.01)
    ref = fusion_core_run(fmu_key, [level, level], [(0.0, 0.0, 0.0)] * 2, 0.01)
    # The first doStep's sample (level) initialised the filter; the tilted values never counted.
    assert max_difference(out, ref, output_keys(fmu_key)) <= TOLERANCE
    assert abs(out["roll"][0]) < 1e-15


def test_first_sample_initialises_from_the_accelerometer(fmu_path, fmu_key, fusion_core_run):
    roll, pitch = 0.3, -0.2
    g = fusion_core.G
    acc = (-g * np.sin(pitch), g * np.sin(roll) * np.cos(pitch), g * np.cos(roll) * np.cos(pitch))
    with FmuInstance(fmu_path) as fmu:
        fmu.sample(acc, (0.4, -0.1, 0.2), 0.01)
        got = fmu.get("roll"), fmu.get("pitch")
    assert got[0] == fusion_core_run(fmu_key, [acc], [(0.4, -0.1, 0.2)], 0.01)["roll"][0]
    assert abs(got[0] - roll) < 1e-12
    assert abs(got[1] - pitch) < 1e-12


def test_bias_outputs_described_as_always_zero_are_zero(fmu_path, fmu_recording):
    with FmuInstance(fmu_path) as fmu:
        described_zero = {
            axis: "always 0" in fmu.variables[f"bias_{axis}"].description for axis in "xyz"
        }
        out = fmu.run_samples(*(fmu_recording[k] for k in IMU))
    for i, axis in enumerate("xyz"):
        all_zero = bool(np.all(out["bias"][:, i] == 0.0))
        # A biased gyro (0.01, -0.006, 0.004) rad/s: an estimated bias moves; a missing one is 0
        # and its description must say so.
        assert all_zero == described_zero[axis], f"bias_{axis}"
