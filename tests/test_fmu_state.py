"""getFMUstate/setFMUstate and serialise/deserialise cover the whole filter state."""

from __future__ import annotations

import numpy as np

from fmu_src.host import FmuInstance

SPLITS = (60, 420)
"""Where the state is saved: at rest (the position filter's stationary queue is filling) and
in the middle of the motion."""


def outputs_equal(a: dict, b: dict) -> bool:
    """Bit-identical outputs (NaN never appears: every output is finite)."""
    return all(np.array_equal(a[k], b[k]) for k in a)


def samples(rec: dict, start: int, stop: int | None = None) -> tuple:
    return rec["acc_meas"][start:stop], rec["gyro_meas"][start:stop], rec["dt"][start:stop]


def test_get_and_set_state_continue_identically(fmu_path, fmu_recording):
    with FmuInstance(fmu_path) as fmu:
        for split in SPLITS:
            fmu.run_samples(*samples(fmu_recording, 0 if split == SPLITS[0] else SPLITS[0], split))
            state = fmu.get_state()
            time = fmu.time
            first = fmu.run_samples(*samples(fmu_recording, split, split + 200))
            fmu.set_state(state)
            fmu.time = time
            again = fmu.run_samples(*samples(fmu_recording, split, split + 200))
            fmu.set_state(state)  # a state may be set more than once
            fmu.time = time
            fmu.free_state(state)
            assert outputs_equal(first, again), f"continuation after sample {split} differs"
        assert not [m for m in fmu.messages if m.status != "OK"]


def test_serialized_state_continues_identically_in_a_fresh_instance(
    fmu_path, fmu_key, fmu_recording, fusion_core_run
):
    split = SPLITS[0]
    ref = fusion_core_run(fmu_key, *samples(fmu_recording, 0))
    with FmuInstance(fmu_path, instance_name="first") as first:
        first.run_samples(*samples(fmu_recording, 0, split))
        data = first.serialize()
        continued = first.run_samples(*samples(fmu_recording, split))
    with FmuInstance(fmu_path, instance_name="second") as second:
        second.deserialize(data)
        restored = second.run_samples(*samples(fmu_recording, split))
        errors = [m for m in second.messages if m.status != "OK"]
    assert not errors, errors
    assert outputs_equal(continued, restored)
    assert np.array_equal(restored["roll"], ref["roll"][split:])


def test_state_holds_parameters_and_invalid_samples(built_fmus, fmu_recording):
    acc, gyro, dt = samples(fmu_recording, 0, 100)
    with FmuInstance(built_fmus.path("AngleBiasKalmanFilter")) as fmu:
        fmu.run_samples(acc[:50], gyro[:50], dt[:50])
        fmu.set({"R_measure": 2e-5})
        fmu.sample(acc[50], gyro[50], 0.0)  # rejected: dt = 0
        data = fmu.serialize()
        fmu.set({"R_measure": 5e-5})
        fmu.sample(acc[51], gyro[51], float("nan"))  # rejected
        assert fmu.get("invalid_samples") == 2
        fmu.deserialize(data)
        assert fmu.get("invalid_samples") == 1
        assert fmu.get("R_measure") == 2e-5
        restored = fmu.run_samples(acc[51:], gyro[51:], dt[51:])
    with FmuInstance(built_fmus.path("AngleBiasKalmanFilter")) as fmu:
        fmu.run_samples(acc[:50], gyro[:50], dt[:50])
        fmu.set({"R_measure": 2e-5})
        fmu.sample(acc[50], gyro[50], 0.0)
        straight = fmu.run_samples(acc[51:], gyro[51:], dt[51:])
    assert outputs_equal(restored, straight)


def test_state_of_another_fmu_is_refused_and_the_state_kept(built_fmus, fmu_recording):
    acc, gyro, dt = samples(fmu_recording, 0, 60)
    with FmuInstance(built_fmus.path("ComplementaryFilter")) as cf:
        cf.run_samples(acc, gyro, dt)
        foreign = cf.serialize()
    with FmuInstance(built_fmus.path("AngleBiasKalmanFilter")) as kf:
        kf.run_samples(acc[:30], gyro[:30], dt[:30])
        before = kf.get("roll"), kf.get("bias_x")
        kf.deserialize(foreign)  # status OK; the refusal is logged
        assert (kf.get("roll"), kf.get("bias_x")) == before
        errors = [m.message for m in kf.messages if m.status == "ERROR"]
        assert len(errors) == 1 and "ComplementaryFilter" in errors[0]
        kf.run_samples(acc[30:], gyro[30:], dt[30:])  # and it keeps running
