"""`imu-fusion crosscheck`: the native FMUs in the FMI Cross-Check layout, fusion_core's
reference against fmpy's simulation, and fmpy's own tree validation with 0 problems."""

from __future__ import annotations

import numpy as np
import pytest

from fusion_core import registry
from testbenches.crosscheck import (
    DURATION,
    STEP,
    _description,
    check_model,
    estimator_reference,
    read_csv,
    run_crosscheck,
)

pytestmark = [pytest.mark.fmu, pytest.mark.heavy]


@pytest.fixture(scope="module")
def crosscheck(built_fmus, tmp_path_factory: pytest.TempPathFactory):
    built_fmus.native("fmi2", "ImuPlant")  # skipped with the reason where none were built
    out = tmp_path_factory.mktemp("crosscheck")
    checked, problems, fmu_count = run_crosscheck(built_fmus.directory, out, log=lambda _: None)
    return out, checked, problems, fmu_count


def test_every_model_passes_in_both_standards(crosscheck) -> None:
    _, checked, problems, fmu_count = crosscheck
    models = {"ImuPlant", "ImuSensor", *registry.FMU_NAMES.values()}
    assert {(c.version, c.model) for c in checked} == {(v, m) for v in ("2.0", "3.0")
                                                       for m in models}
    assert [c.model for c in checked if c.problem is not None] == []
    assert problems == [] and fmu_count == len(models)


def test_the_tree_has_the_cross_check_files(crosscheck) -> None:
    _, checked, _, _ = crosscheck
    for c in checked:
        assert (c.fmu_dir / f"{c.model}.fmu").is_file()
        for suffix in ("_ref.csv", "_ref.opt"):
            assert (c.fmu_dir / f"{c.model}{suffix}").is_file()
        assert (c.fmu_dir / f"{c.model}_in.csv").is_file() == (c.model != "ImuPlant")
        for name in (f"{c.model}_out.csv", f"{c.model}_cc.sh", f"{c.model}_cc.log", "passed"):
            assert (c.result_dir / name).is_file(), name
        assert "/fmus/" in c.fmu_dir.as_posix() and "/results/" in c.result_dir.as_posix()


def test_the_native_fmus_give_fusion_cores_outputs_to_the_bit(crosscheck) -> None:
    """Beyond the cross-check's bands: every output equals the Python reference (the twins
    are equal bit for bit, and 17 digits carry a double through the CSV files)."""
    _, checked, _, _ = crosscheck
    for c in checked:
        ref = read_csv(c.fmu_dir / f"{c.model}_ref.csv")
        out = read_csv(c.result_dir / f"{c.model}_out.csv")
        assert len(out) == round(DURATION / STEP) + 1
        for name in c.outputs:
            assert np.array_equal(out[name], ref[name]), (c.version, c.model, name)


def test_a_result_off_its_reference_is_not_passed(built_fmus, tmp_path) -> None:
    fmu = built_fmus.native("fmi2", "AngleBiasKalmanFilter")
    n = round(DURATION / STEP)
    t = np.arange(n + 1) * STEP
    inputs = {"acc_x": 0.0 * t, "acc_y": 0.0 * t, "acc_z": 9.80665 + 0.0 * t,
              "gyro_x": 0.0 * t, "gyro_y": 0.0 * t, "gyro_z": 0.0 * t, "dt": STEP + 0.0 * t}
    ref = estimator_reference("kf", _description(fmu), inputs, n)
    ref["roll"] = ref["roll"] + 0.2  # a reference the FMU does not give
    c = check_model("AngleBiasKalmanFilter", "fmi2", fmu, tmp_path, inputs, ref)
    assert c.problem is not None
    assert not (c.result_dir / "passed").exists()
