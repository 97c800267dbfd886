"""Bad samples and bad parameters (INTERFACE.md, Bad input): refused, counted, logged, survived."""

from __future__ import annotations

import numpy as np

import fusion_core
from fmu_src.host import FmuInstance
from fusion_core.kalman import RECOMMENDED_INIT_BIAS_STD

BAD_SAMPLES = {
    # sample index: (what is wrong, acc, gyro, dt); the others are the fmu_recording's
    40: ("NaN accelerometer", (float("nan"), 0.0, 9.8), None, None),
    80: ("infinite gyro", None, (0.0, float("inf"), 0.0), None),
    120: ("dt = 0", None, None, 0.0),
    160: ("dt above max_dt", None, None, 1.5),
    200: ("gyro above max_rate", None, (2000.0, 0.0, 0.0), None),
    240: ("negative dt", None, None, -0.01),
    241: ("NaN dt", None, None, float("nan")),
}

IMU = ("acc_meas", "gyro_meas", "dt")
"""The keys of a synthetic.record() recording that make up the IMU samples."""


def corrupted(fmu_recording: dict, n: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    acc = fmu_recording["acc_meas"][:n].copy()
    gyro = fmu_recording["gyro_meas"][:n].copy()
    dt = fmu_recording["dt"][:n].copy()
    for i, (_, a, w, h) in BAD_SAMPLES.items():
        if a is not None:
            acc[i] = a
        if w is not None:
            gyro[i] = w
        if h is not None:
            dt[i] = h
    return acc, gyro, dt


def test_bad_samples_are_rejected_counted_logged_and_the_run_continues(
    fmu_path, fmu_key, fmu_recording, fusion_core_run
):
    acc, gyro, dt = corrupted(fmu_recording)
    with FmuInstance(fmu_path) as fmu:
        out = fmu.run_samples(acc, gyro, dt)  # fmpy raises if a doStep is not fmi2OK
        warnings = [m.message for m in fmu.messages if m.status == "WARNING"]
        others = [m for m in fmu.messages if m.status not in ("OK", "WARNING")]
    bad = sorted(BAD_SAMPLES)
    expected_count = np.searchsorted(bad, np.arange(len(acc)), side="right")
    assert np.array_equal(out["invalid_samples"], expected_count)
    assert out["invalid_samples"][-1] == len(BAD_SAMPLES)
    for k in ("roll", "pitch", "bias"):
        assert np.all(np.isfinite(out[k]))
    for i in bad:  # the estimate is kept over a rejected sample
        assert out["roll"][i] == out["roll"][i - 1] and out["pitch"][i] == out["pitch"][i - 1]
    assert len(warnings) == len(BAD_SAMPLES) and not others
    assert "is not finite" in warnings[0] and "rejected" in warnings[0]
    assert "outside the allowed range" in warnings[2]
    assert "max_rate" in warnings[4]
    # The run continues from the kept state exactly like fusion_core's.
    ref = fusion_core_run(fmu_key, acc, gyro, dt)
    assert np.array_equal(ref["rejected"].nonzero()[0], np.array(bad))
    assert np.max(np.abs(out["roll"] - ref["roll"])) <= 1e-12
    assert np.max(np.abs(out["bias"] - ref["bias"])) <= 1e-12


def test_out_of_range_parameter_is_refused_with_its_name_and_range(
    fmu_path, fmu_key, fmu_recording, fusion_core_run
):
    with FmuInstance(fmu_path, parameters={"max_dt": -1.0}) as fmu:
        errors = [m.message for m in fmu.messages if m.status == "ERROR"]
        assert len(errors) == 1
        spec = fusion_core.ESTIMATORS[fmu_key].param_specs()["max_dt"]
        assert "max_dt" in errors[0] and spec.allowed() in errors[0]
        assert fmu.get("max_dt") == 1.0  # the default stays
        acc, gyro, dt = (fmu_recording[k][:100] for k in ("acc_meas", "gyro_meas", "dt"))
        out = fmu.run_samples(acc, gyro, dt)  # and the host (this process) carries on
    assert np.array_equal(out["roll"], fusion_core_run(fmu_key, acc, gyro, dt)["roll"])


def test_out_of_range_tunable_parameter_while_running_is_refused(
    built_fmus, fmu_recording, fusion_core_run
):
    acc, gyro, dt = (fmu_recording[k][:200] for k in IMU)
    with FmuInstance(built_fmus.path("ComplementaryFilter")) as fmu:
        first = fmu.run_samples(acc[:100], gyro[:100], dt[:100])
        fmu.set({"tau": -0.5})
        errors = [m.message for m in fmu.messages if m.status == "ERROR"]
        allowed = fusion_core.ESTIMATORS["cf"].param_specs()["tau"].allowed()
        assert len(errors) == 1 and "'tau'" in errors[0] and allowed in errors[0]
        assert fmu.get("tau") == 1.0
        rest = fmu.run_samples(acc[100:], gyro[100:], dt[100:])
    ref = fusion_core_run("cf", acc, gyro, dt)
    assert np.array_equal(np.concatenate([first["roll"], rest["roll"]]), ref["roll"])


def test_tunable_parameter_change_while_running_takes_effect_at_that_sample(
    built_fmus, fmu_recording
):
    acc, gyro, dt = (fmu_recording[k][:200] for k in IMU)
    with FmuInstance(built_fmus.path("AngleBiasKalmanFilter")) as fmu:
        fmu.run_samples(acc[:100], gyro[:100], dt[:100])
        fmu.set({"R_measure": 4e-5})
        rest = fmu.run_samples(acc[100:], gyro[100:], dt[100:])
        assert not [m for m in fmu.messages if m.status != "OK"]
    est = fusion_core.AngleBiasKalmanFilter()
    est.run(acc[:100], gyro[:100], dt[:100])
    est.set_param("R_measure", 4e-5)
    assert np.array_equal(rest["roll"], est.run(acc[100:], gyro[100:], dt[100:])["roll"])


def test_fixed_parameter_is_refused_after_initialisation(built_fmus):
    with FmuInstance(built_fmus.path("UnscentedKalmanFilter")) as fmu:
        fmu.set({"gyro_sampling": "mean", "init_bias_std": 0.1})
        errors = [m.message for m in fmu.messages if m.status == "ERROR"]
        assert fmu.get("gyro_sampling") == 1
        assert fmu.get("init_bias_std") == RECOMMENDED_INIT_BIAS_STD
    assert len(errors) == 2
    assert "'gyro_sampling' is fixed after initialisation" in errors[0]
    assert "'init_bias_std' is fixed after initialisation" in errors[1]


def test_fixed_parameter_is_accepted_before_initialisation(
    built_fmus, fmu_recording, fusion_core_run
):
    acc, gyro, dt = (fmu_recording[k][:100] for k in IMU)
    params = {"gyro_sampling": "mean", "init_bias_std": 0.1}
    with FmuInstance(built_fmus.path("UnscentedKalmanFilter"), parameters=params) as fmu:
        out = fmu.run_samples(acc, gyro, dt)
        assert fmu.get("gyro_sampling") == 2
    assert np.array_equal(out["bias"], fusion_core_run("ukf", acc, gyro, dt, **params)["bias"])


def test_unknown_enumeration_value_is_refused_with_the_items(built_fmus):
    with FmuInstance(built_fmus.path("GainScheduledComplementaryFilter"),
                     parameters={"gyro_sampling": 7}) as fmu:
        errors = [m.message for m in fmu.messages if m.status == "ERROR"]
        assert fmu.get("gyro_sampling") == 1
    assert len(errors) == 1
    assert "'gyro_sampling'=7" in errors[0]
    assert "1 = point, 2 = mean" in errors[0]


def test_writing_an_output_is_refused_and_the_fmu_continues(built_fmus, fmu_recording):
    with FmuInstance(built_fmus.path("ComplementaryFilter")) as fmu:
        fmu.run_samples(*(fmu_recording[k][:5] for k in IMU))
        roll = fmu.get("roll")
        fmu.set({"roll": 1.0, "invalid_samples": 3})
        assert fmu.get("roll") == roll and fmu.get("invalid_samples") == 0
        errors = [m.message for m in fmu.messages if m.status == "ERROR"]
        fmu.run_samples(fmu_recording["acc_meas"][5:9], fmu_recording["gyro_meas"][5:9],
                        fmu_recording["dt"][5:9])
    assert len(errors) == 2 and "roll is an output" in errors[0]
