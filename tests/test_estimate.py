"""`imu-fusion estimate`: the estimators on a user's recording, its units and columns found, and
one line, never a traceback, for a file that cannot serve."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fusion_core.registry import KEYS, create
from testbenches.cli import main

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"
TRUTH = REPO / "examples" / "tilt_motion_truth.csv"


def _example() -> dict[str, np.ndarray]:
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    return {"time": data[:, 0], "acc": data[:, 1:4], "gyro": data[:, 4:7], "dt": data[:, 7]}


def test_estimate_writes_every_estimators_outputs_as_fusion_core_gives_them(tmp_path, capsys):
    assert main(["estimate", str(EXAMPLE), "--reference", str(TRUTH), "--out", str(tmp_path),
                 "--no-plots"]) == 0
    text = capsys.readouterr().out
    ex = _example()
    dt = np.diff(ex["time"], prepend=ex["time"][0] - 0.01)
    for key in KEYS:
        out = np.loadtxt(tmp_path / f"tilt_motion_{key}.csv", delimiter=",", skiprows=1)
        want = create(key).run(ex["acc"], ex["gyro"], dt)
        assert np.array_equal(out[:, 1], want["roll"]) and np.array_equal(out[:, 2], want["pitch"])
        assert out.shape[1] == (12 if key == "poskf" else 6)
        line = next(row for row in text.splitlines() if row.startswith(f"{key} "))
        assert float(line.split()[2]) < 1.5, line  # inclination RMSE [deg] against the truth


def test_units_and_column_names_are_found(tmp_path):
    """acc in g, gyro in deg/s, other column names and a time column of its own name: the
    same estimates as from the SI file (to rounding of the conversions)."""
    ex = _example()
    other = tmp_path / "mine.csv"
    gyro = np.degrees(ex["gyro"])
    gyro[400, 0] = 45.0  # a fast turn: beyond 35 rad/s only in deg/s, so detected as deg/s
    np.savetxt(other, np.column_stack([ex["time"], ex["acc"] / 9.80665, gyro]), delimiter=",",
               header="stamp,ax,ay,az,gx,gy,gz", comments="")
    assert main(["estimate", str(other), "--time-column", "stamp", "--estimator", "kf",
                 "--out", str(tmp_path), "--no-plots"]) == 0
    got = np.loadtxt(tmp_path / "mine_kf.csv", delimiter=",", skiprows=1)
    si_gyro = np.radians(gyro)
    dt = np.diff(ex["time"], prepend=ex["time"][0] - 0.01)
    want = create("kf").run(ex["acc"], si_gyro, dt)
    assert np.max(np.abs(got[:, 1] - want["roll"])) < 1e-9


def test_an_hdf5_recording_with_a_rate(tmp_path):
    h5py = pytest.importorskip("h5py")
    ex = _example()
    path = tmp_path / "rec.h5"
    with h5py.File(path, "w") as f:
        f["acc"] = ex["acc"]
        f["gyro"] = ex["gyro"]
        f.attrs["rate"] = 100.0
    assert main(["estimate", str(path), "--estimator", "ukf", "--out", str(tmp_path),
                 "--no-plots"]) == 0
    assert (tmp_path / "rec_ukf.csv").is_file()


@pytest.mark.parametrize(("content", "says"), [
    ("time,acc_x,acc_y,acc_z,gyro_x,gyro_y\n0,0,0,9.8,0,0\n0.01,0,0,9.8,0,0\n",
     "no column for gyro_z"),
    ("time,ax,ay,az,gx,gy,gz\n0,0,0,9.8,0,0,0\n0.02,0,0,9.8,0,0,0\n0.01,0,0,9.8,0,0,0\n",
     "the time does not increase at sample 2"),
    ("time,ax,ay,az,gx,gy,gz\n0,0,0,98,0,0,0\n0.01,0,0,98,0,0,0\n",
     "neither about 1 (g) nor about 9.81"),
    ("ax,ay,az,gx,gy,gz\n0,0,9.8,0,0,0\n0,0,9.8,0,0,0\n", "give the sample rate"),
    ("time,ax,ay,az,gx,gy,gz\n0,0,0,9.8,0,0,x\n0.01,0,0,9.8,0,0,0\n", "not a number"),
])
def test_a_bad_file_gets_one_line_that_says_what_is_wrong(tmp_path, content, says):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    proc = subprocess.run([sys.executable, "-m", "testbenches", "estimate", str(path), "--out",
                           str(tmp_path), "--no-plots"], capture_output=True, text=True,
                          timeout=120, cwd=REPO)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and says in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


def test_the_console_script_lists_every_command():
    proc = subprocess.run([sys.executable, "-m", "testbenches", "--help"], capture_output=True,
                          text=True, timeout=120, cwd=REPO)
    for command in ("estimate", "build-fmus", "run", "broad", "noise", "tune", "campaign",
                    "budget", "export-ssp"):
        assert command in proc.stdout


def test_a_calibration_file_is_applied_at_every_estimators_input(tmp_path, capsys):
    from fusion_core.calibration import Calibration

    cal = Calibration(acc_matrix=(1.02, 0.01, 0.0, 0.0, 0.98, 0.0, 0.0, 0.0, 1.01),
                      gyro_offset=(0.01, -0.02, 0.0))
    path = tmp_path / "calibration.json"
    cal.write(path)
    assert main(["estimate", str(EXAMPLE), "--estimator", "ukf", "--calibration", str(path),
                 "--out", str(tmp_path), "--no-plots"]) == 0
    ex = _example()
    dt = np.diff(ex["time"], prepend=ex["time"][0] - 0.01)
    got = np.loadtxt(tmp_path / "tilt_motion_ukf.csv", delimiter=",", skiprows=1)
    want = create("ukf", cal.params()).run(ex["acc"], ex["gyro"], dt)
    assert np.array_equal(got[:, 1], want["roll"])
    path.write_text('{"gyro_cal": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 2]], '
                    '"offset": [0, 0, 0]}}')
    assert main(["estimate", str(EXAMPLE), "--calibration", str(path), "--out",
                 str(tmp_path), "--no-plots"]) == 2
    assert "gyro_cal_zz=2.0 is out of range" in capsys.readouterr().err
