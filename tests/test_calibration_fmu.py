"""The calibration in the FMUs: every estimator FMU takes acc_cal and gyro_cal as parameters and
gives fusion_core's outputs with them, whether set by the host or built in as start values
(`build-fmus --calibration`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_src.build import build_all
from fusion_core import registry
from fusion_core.calibration import Calibration

pytestmark = pytest.mark.fmu
REPO = Path(__file__).resolve().parents[1]

PART = Calibration(
    acc_matrix=(1.023, 0.004, -0.002, 0.003, 0.981, 0.006, -0.005, 0.002, 1.012),
    acc_offset=(0.12, -0.07, 0.21),
    gyro_matrix=(1.028, 0.003, 0.001, -0.004, 0.982, 0.002, 0.002, -0.003, 1.004),
    gyro_offset=(0.011, -0.018, 0.006),
)
N = 600


def inputs() -> np.ndarray:
    rng = np.random.default_rng(5)
    t = np.arange(N + 1) * 0.01
    rows = np.zeros(N + 1, dtype=[("time", float)] + [(n, float) for n in (
        "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt")])
    rows["time"] = t
    acc = np.array([0.5, -0.4, 9.7]) + 0.2 * rng.standard_normal((N + 1, 3))
    gyro = 0.3 * np.sin(t)[:, None] * np.array([1.0, -0.5, 0.2]) + 0.01
    for i, a in enumerate("xyz"):
        rows[f"acc_{a}"], rows[f"gyro_{a}"] = acc[:, i], gyro[:, i]
    rows["dt"] = 0.01
    return rows


def reference(key: str, rows: np.ndarray) -> dict[str, np.ndarray]:
    acc = np.column_stack([rows[f"acc_{a}"][:N] for a in "xyz"])
    gyro = np.column_stack([rows[f"gyro_{a}"][:N] for a in "xyz"])
    return registry.create(key, PART.params()).run(acc, gyro, rows["dt"][:N], backend="python")


def assert_equal_outputs(result: np.ndarray, ref: dict[str, np.ndarray], what: str) -> None:
    for name in ("roll", "pitch"):  # the output at t_(k+1) is the estimate after sample k
        assert np.array_equal(result[name][1:], ref[name]), (what, name)
    for i, a in enumerate("xyz"):
        assert np.array_equal(result[f"bias_{a}"][1:], ref["bias"][:, i]), (what, a)


@pytest.mark.parametrize("key", registry.KEYS)
def test_calibration_parameters_set_by_the_host_give_fusion_cores_outputs(built_fmus, key):
    rows = inputs()
    ref = reference(key, rows)
    name = registry.FMU_NAMES[key]
    for version in ("fmi2", "fmi3"):
        result = simulate_fmu(str(built_fmus.native(version, name)), input=rows,
                              stop_time=N * 0.01, output_interval=0.01,
                              start_values=PART.params())
        assert_equal_outputs(result, ref, f"native {version}")
    result = simulate_fmu(str(built_fmus.path(name)), input=rows, stop_time=N * 0.01,
                          output_interval=0.01, start_values=PART.params())
    assert_equal_outputs(result, ref, "pythonfmu")


@pytest.mark.heavy
def test_build_fmus_writes_the_calibration_as_start_values(built_fmus, tmp_path) -> None:
    """`build_fmu.py --calibration FILE` in a process of its own (a process that has run a
    pythonfmu FMU in itself may not build one: pythonfmu's builder then finds no binaries)."""
    built_fmus.native("fmi2", "ImuPlant")  # skipped with the reason where no compiler exists
    path = tmp_path / "calibration.json"
    PART.write(path)
    out = tmp_path / "dist"
    proc = subprocess.run([sys.executable, str(REPO / "build_fmu.py"), "--only",
                           "AngleBiasKalmanFilter", "--kind", "all", "--calibration", str(path),
                           "--out", str(out)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = inputs()
    ref = reference("kf", rows)
    for kind, fmu in (("pythonfmu", out / "AngleBiasKalmanFilter.fmu"),
                      ("fmi2", out / "native" / "fmi2" / "AngleBiasKalmanFilter.fmu"),
                      ("fmi3", out / "native" / "fmi3" / "AngleBiasKalmanFilter.fmu")):
        result = simulate_fmu(str(fmu), input=rows, stop_time=N * 0.01, output_interval=0.01)
        assert_equal_outputs(result, ref, kind)


def test_a_bad_calibration_file_is_refused_by_the_build(tmp_path) -> None:
    path = tmp_path / "calibration.json"
    path.write_text('{"gyro_cal": {"matrix": [[1, 0, 0], [0, 0, 0], [0, 0, 1]], '
                    '"offset": [0, 0, 0]}}')
    with pytest.raises(ValueError, match=r"gyro_cal: entry gyro_cal_yy=0.0 is out of range"):
        build_all(["AngleBiasKalmanFilter"], tmp_path / "dist", kind="native",
                  calibration=path)
