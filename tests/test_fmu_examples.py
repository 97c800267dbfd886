"""The example CSVs are what examples/make_inputs.py writes and give sensible traces."""

from __future__ import annotations

import importlib.util
import math
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.util import read_csv

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DEG = math.pi / 180.0


def load(name: str):
    spec = importlib.util.spec_from_file_location(f"examples_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_example_csvs_are_reproducible():
    make_inputs = load("make_inputs")
    for stem, rec in make_inputs.recordings().items():
        written = np.loadtxt(EXAMPLES / f"{stem}.csv", delimiter=",", skiprows=1)
        expected = make_inputs.input_table(rec)
        np.testing.assert_allclose(written, expected, rtol=1e-9, atol=1e-12)
        _, truth = make_inputs.truth_table(rec)
        written_truth = np.loadtxt(EXAMPLES / f"{stem}_truth.csv", delimiter=",", skiprows=1)
        np.testing.assert_allclose(written_truth, truth, rtol=1e-9, atol=1e-12)
        assert written[0, 0] == 0.0 and written[-1, 0] == 9.99  # rows for doStep(0..9.99, 0.01)


@pytest.mark.parametrize("kind", ["fmi3", "pythonfmu"])
def test_readme_command_gives_a_sensible_attitude_trace(built_fmus, tmp_path, kind):
    """The documented fmpy command (docs/guide/fmus.md) on the native FMI 3.0 FMU, and on the
    pythonfmu FMU, whose process may abort at exit after writing its results (pythonfmu's
    defect, docs/guide/modelica-simulink.md)."""
    out_csv = tmp_path / "AngleBiasKalmanFilter_out.csv"
    fmu = (built_fmus.path("AngleBiasKalmanFilter") if kind == "pythonfmu"
           else built_fmus.native(kind, "AngleBiasKalmanFilter"))
    proc = subprocess.run(
        [sys.executable, "-m", "fmpy.cli", "simulate", str(fmu), "--input-file",
         str(EXAMPLES / "tilt_motion.csv"), "--output-interval", "0.01", "--output-file",
         str(out_csv)],
        capture_output=True, cwd=tmp_path, timeout=300, check=False,
    )
    allowed = (0,) if kind != "pythonfmu" else (0, -signal.SIGABRT)
    assert proc.returncode in allowed, proc.stderr
    out = np.genfromtxt(out_csv, delimiter=",", names=True)
    truth = np.genfromtxt(EXAMPLES / "tilt_motion_truth.csv", delimiter=",", names=True)
    assert len(out) == 1001 and np.allclose(out["time"][1:], truth["time"])
    after = truth["time"] >= 1.0
    for name in ("roll", "pitch"):
        rmse = np.sqrt(np.mean((out[name][1:][after] - truth[name][after]) ** 2))
        # 0.25 deg: the recommended kf corrects with a time constant of about 3.7 s at 100 Hz
        # (the papers' values, 0.5 s), so the gyro noise and the bias left after its 1.5 s of
        # rest detection show as about 0.2 deg on this fast two-axis motion
        assert rmse < 0.25 * DEG, f"{name} RMSE {rmse / DEG:.3f} deg"
    last_second = truth["time"] >= 9.0
    for axis in "xy":  # the estimated biases have converged to the true ones
        err = np.abs(out[f"bias_{axis}"][1:][last_second] - truth[f"bias_{axis}"][last_second])
        assert err.max() < 0.1 * DEG, f"bias_{axis}"


def test_position_example_ends_near_two_metres(built_fmus):
    inputs = read_csv(str(EXAMPLES / "move_2m.csv"))
    result = simulate_fmu(str(built_fmus.path("PositionKalmanFilter")), input=inputs,
                          output_interval=0.01, output=["pos_x", "pos_y", "vel_x"])
    assert abs(result["pos_x"][-1] - 2.0) < 0.02
    assert abs(result["pos_y"][-1]) < 0.05 and abs(result["vel_x"][-1]) < 0.01
