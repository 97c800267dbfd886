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


@pytest.mark.parametrize("options, shared", [
    ([], True), (["--sensor-delay", "0.004", "--mounting", "0,0,30"], True),
    (["--param", "Q_angle=0.01"], False)])
def test_the_kf_takes_its_outputs_from_the_position_filters_run_where_they_are_its(
        tmp_path, monkeypatch, options, shared):
    """The position filter runs the recommended kf inside (PositionKalmanFilter
    attitude_params): with both estimators and the same kf, the kf is not run a second time
    and its outputs are still its own; a kf of other parameters runs."""
    from fusion_core.kalman import AngleBiasKalmanFilter

    calls = []
    kf_run = AngleBiasKalmanFilter.run
    monkeypatch.setattr(AngleBiasKalmanFilter, "run",
                        lambda self, *a, **k: calls.append(1) or kf_run(self, *a, **k))
    assert main(["estimate", str(EXAMPLE), "--estimator", "kf,poskf", "--out", str(tmp_path),
                 "--no-plots", *options]) == 0
    assert (not calls) == shared
    ex = _example()
    dt = np.diff(ex["time"], prepend=ex["time"][0] - 0.01)
    params = {"sensor_delay": 0.004, "mount_yaw": np.radians(30.0)} if len(options) == 4 else (
        {"Q_angle": 0.01} if options else {})
    want = create("kf", params).run(ex["acc"], ex["gyro"], dt)
    got = np.loadtxt(tmp_path / "tilt_motion_kf.csv", delimiter=",", skiprows=1)
    assert np.array_equal(got[:, 1], want["roll"]) and np.array_equal(got[:, 3:6], want["bias"])


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
     "line 4: the time 0.01 s does not increase from 0.02 s on line 3"),
    ("time,ax,ay,az,gx,gy,gz\n0,0,0,98,0,0,0\n0.01,0,0,98,0,0,0\n",
     "neither about 1 (g), 9.81 (m/s2) nor 1000 (mg)"),
    ("ax,ay,az,gx,gy,gz\n0,0,9.8,0,0,0\n0,0,9.8,0,0,0\n", "give the sample rate"),
    ("time,ax,ay,az,gx,gy,gz\n0,0,0,9.8,0,0,x\n0.01,0,0,9.8,0,0,0\n",
     "line 2, column 'gz': 'x' is not a number"),
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


# ----- a file as a logger or a spreadsheet writes it, and units that cannot be silently wrong -----
def _logger_file(path: Path, delimiter: str = ",", bom: bool = False, deg: bool = True,
                 g: bool = True, header_units: bool = True, comma: bool = False) -> None:
    """tilt_motion.csv as a logger writes it: its own column names with units in them (comma:
    a decimal comma, each cell quoted where the delimiter is a comma too)."""
    ex = _example()
    acc = ex["acc"] / 9.80665 if g else ex["acc"]
    gyro = np.degrees(ex["gyro"]) if deg else ex["gyro"]
    au, gu = ("(g)" if g else "(m/s^2)"), ("(deg/s)" if deg else "(rad/s)")
    names = ["Time (s)"] + [f"Accelerometer {a} {au if header_units else ''}".strip()
                            for a in "XYZ"] + [
        f"Gyroscope {a} {gu if header_units else ''}".strip() for a in "XYZ"]
    def cell(v: float) -> str:
        text = f"{v:.9g}"
        if not comma:
            return text
        text = text.replace(".", ",")
        return f'"{text}"' if delimiter == "," else text

    rows = [delimiter.join(names)] + [delimiter.join(cell(v) for v in row) for row in
                                      np.column_stack([ex["time"], acc, gyro])]
    path.write_text(("\ufeff" if bom else "") + "\n".join(rows) + "\n", encoding="utf-8")


def _kf_roll(tmp_path: Path, name: str) -> np.ndarray:
    return np.loadtxt(tmp_path / f"{name}_kf.csv", delimiter=",", skiprows=1)[:, 1]


@pytest.mark.parametrize(("delimiter", "bom", "comma"), [
    (",", False, False), (";", True, False), ("\t", False, False), (";", False, True),
    ("\t", False, True), (",", False, True)])
def test_a_loggers_header_delimiter_and_byte_order_mark_are_read(tmp_path, capsys, delimiter,
                                                                 bom, comma):
    """Names like 'Gyroscope X (deg/s)', units in them, semicolons or tabs, a UTF-8 BOM as
    spreadsheets write, a decimal comma (German Excel: between semicolons, between tabs as its
    Unicode Text, or quoted between commas): the same estimate as from the SI file, and the
    choices printed."""
    path = tmp_path / "logger.csv"
    _logger_file(path, delimiter, bom, comma=comma)
    assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path),
                 "--no-plots"]) == 0
    said = capsys.readouterr().out
    assert "acc in g (from the header)" in said and "gyro in deg/s (from the header" in said
    ex = _example()
    want = create("kf").run(ex["acc"], ex["gyro"], np.full(len(ex["time"]), 0.01))
    assert np.max(np.abs(_kf_roll(tmp_path, "logger") - want["roll"])) < 1e-6


@pytest.mark.parametrize(("option", "said"), [
    (["--gyro-unit", "rad/s"], "--gyro-unit rad/s contradicts the header, which states deg/s"),
    (["--acc-unit", "m/s2"], "--acc-unit m/s2 contradicts the header, which states g")])
def test_a_given_unit_the_header_contradicts_is_refused(tmp_path, capsys, option, said):
    """A unit given on the command line that is not the header's: refused whether or not the
    data could tell (a quiet recording cannot), and nothing is written."""
    path = tmp_path / "logger.csv"
    _logger_file(path)
    out = tmp_path / "out"
    assert main(["estimate", str(path), "--estimator", "kf", *option, "--out", str(out),
                 "--no-plots"]) == 2
    assert said in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


def test_a_column_map_names_what_the_reader_does_not_know(tmp_path):
    ex = _example()
    path = tmp_path / "odd.csv"
    np.savetxt(path, np.column_stack([ex["time"], ex["acc"], ex["gyro"]]), delimiter=",",
               header="when,f1,f2,f3,w1,w2,w3", comments="")
    mapping = [f"--column={q}={n}" for q, n in (("time", "when"), ("acc_x", "f1"),
               ("acc_y", "f2"), ("acc_z", "f3"), ("gyro_x", "w1"), ("gyro_y", "w2"),
               ("gyro_z", "w3"))]
    assert main(["estimate", str(path), "--estimator", "kf", *mapping, "--out", str(tmp_path),
                 "--no-plots"]) == 0


def test_rows_without_numbers_are_rejected_one_by_one_not_the_file(tmp_path, capsys):
    ex = _example()
    gyro = ex["gyro"].copy()
    gyro[100:105] = np.nan
    path = tmp_path / "gaps.csv"
    np.savetxt(path, np.column_stack([ex["time"], ex["acc"], gyro]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path),
                 "--no-plots"]) == 0
    out = capsys.readouterr().out
    assert "5 sample(s) without a number" in out
    assert next(r for r in out.splitlines() if r.startswith("kf ")).split()[1] == "5"


def test_the_gyro_unit_is_found_from_the_data_in_motion_in_both_units(tmp_path, capsys):
    for deg in (True, False):
        path = tmp_path / f"moving_{deg}.csv"
        _logger_file(path, deg=deg, header_units=False)
        assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path),
                     "--no-plots"]) == 0
        unit = "deg/s" if deg else "rad/s"
        assert f"gyro in {unit} (from the data" in capsys.readouterr().out


def _still(path: Path, bias_deg_s: float, deg: bool) -> None:
    """A sensor at rest tilted 10 deg for 60 s at 100 Hz with a gyro bias."""
    rng = np.random.default_rng(1)
    n = 6000
    acc = np.array([0.0, np.sin(0.17), np.cos(0.17)]) * 9.80665 + 0.02 * rng.standard_normal(
        (n, 3))
    gyro = np.radians(bias_deg_s + 0.05 * rng.standard_normal((n, 3)))
    gyro = np.degrees(gyro) if deg else gyro
    np.savetxt(path, np.column_stack([np.arange(n) / 100.0, acc, gyro]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")


def test_a_still_recording_in_deg_s_with_a_bias_is_not_read_as_rad_s(tmp_path, capsys):
    """Read as rad/s, 0.3 deg/s of bias would turn the filters by 17 deg/s. At rest the data
    cannot tell a unit (a bias turns nothing, in either unit), so the command asks for it
    rather than guess; told deg/s, the roll stays at the tilt."""
    path = tmp_path / "still.csv"
    _still(path, 0.3, deg=True)
    assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path),
                 "--no-plots"]) == 2
    assert "give --gyro-unit rad/s, deg/s or mdps" in capsys.readouterr().err
    assert main(["estimate", str(path), "--gyro-unit", "deg/s", "--estimator", "kf",
                 "--out", str(tmp_path), "--no-plots"]) == 0
    assert np.max(np.abs(np.degrees(_kf_roll(tmp_path, "still")) - 9.74)) < 1.0


@pytest.mark.parametrize("bias_deg_s", [0.0, 5.0])
@pytest.mark.parametrize("deg", [True, False], ids=["deg/s", "rad/s"])
def test_the_gyro_unit_from_the_data_holds_with_an_uncalibrated_bias(tmp_path, capsys,
                                                                      bias_deg_s, deg):
    """A gyro bias of 5 deg/s (a MEMS part before calibration) turns nothing the accelerometer
    sees: only the turns decide, and they decide right in either unit."""
    ex = _example()
    gyro = ex["gyro"] + np.radians(bias_deg_s)
    path = tmp_path / "biased.csv"
    np.savetxt(path, np.column_stack([ex["time"], ex["acc"], np.degrees(gyro) if deg else gyro]),
               delimiter=",", header="time,ax,ay,az,gx,gy,gz", comments="")
    assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path),
                 "--no-plots"]) == 0
    assert f"gyro in {'deg/s' if deg else 'rad/s'} (from the data" in capsys.readouterr().out


def test_a_given_gyro_unit_the_data_contradict_is_refused_with_the_evidence(tmp_path):
    path = tmp_path / "moving.csv"
    _logger_file(path, deg=True, header_units=False)
    proc = subprocess.run([sys.executable, "-m", "testbenches", "estimate", str(path),
                           "--gyro-unit", "rad/s", "--out", str(tmp_path), "--no-plots"],
                          capture_output=True, text=True, timeout=120, cwd=REPO)
    assert proc.returncode == 2
    assert "the gyro's unit rad/s (given) contradicts the data" in proc.stderr
    assert "missed by rad/s:" in proc.stderr and "give --gyro-unit deg/s" in proc.stderr


def test_a_recording_that_cannot_tell_its_gyro_unit_is_refused_unless_told(tmp_path, capsys):
    """At rest with a calibrated gyro neither unit turns gravity measurably: refused with the
    option to give; given, it runs."""
    path = tmp_path / "quiet.csv"
    _still(path, 0.0, deg=False)
    assert main(["estimate", str(path), "--out", str(tmp_path), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "too little motion" in err and "give --gyro-unit rad/s, deg/s or mdps" in err
    assert main(["estimate", str(path), "--gyro-unit", "rad/s", "--estimator", "kf",
                 "--out", str(tmp_path), "--no-plots"]) == 0


def test_a_gyro_at_its_rail_is_refused_with_the_misses_not_as_too_little_motion(tmp_path,
                                                                               capsys):
    """The example's gyro clipped at a fifth of its largest rate: the sensor turns in hundreds
    of windows, but the clipped gyro explains gravity's turn in neither unit. The refusal says
    so, with both misses; "too little motion" would send the user looking for the wrong fault."""
    ex = _example()
    rail = 0.2 * np.max(np.abs(ex["gyro"]))
    path = tmp_path / "clipped.csv"
    np.savetxt(path, np.column_stack([ex["time"], ex["acc"], np.clip(ex["gyro"], -rail, rail)]),
               delimiter=",", header="time,ax,ay,az,gx,gy,gz", comments="")
    assert main(["estimate", str(path), "--out", str(tmp_path), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "too little motion" not in err
    assert "missed by rad/s:" in err and "no unit explains the turn" in err
    assert "give --gyro-unit rad/s, deg/s or mdps" in err


def _reference(path: Path, time: np.ndarray, roll: np.ndarray, pitch: np.ndarray) -> None:
    np.savetxt(path, np.column_stack([time, roll, pitch]), delimiter=",",
               header="time,roll,pitch", comments="")


@pytest.mark.parametrize(("make", "says"), [
    ("no overlap", "does not overlap the recording's"),
    ("two takes", "line 502: the reference's time 0.01 s does not increase from 5 s on line 501"),
    ("rows twice", "line 3: the reference's time 0.01 s repeats 0.01 s on line 2 (500 such"),
    ("zero quaternions", "none of the reference's 1000 quaternions is a rotation"),
])
def test_a_reference_that_cannot_serve_is_refused_not_scored_as_nan(tmp_path, capsys, make,
                                                                     says):
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    ref = tmp_path / "ref.csv"
    t, roll, pitch = truth[:, 0], truth[:, 1], truth[:, 2]
    if make == "no overlap":
        _reference(ref, t + 1000.0, roll, pitch)
    elif make == "two takes":  # a clock started again halfway: read between the wrong rows
        _reference(ref, np.where(np.arange(len(t)) >= 500, t - 5.0, t), roll, pitch)
    elif make == "rows twice":
        _reference(ref, np.repeat(t[::2], 2)[:len(t)], roll, pitch)
    else:
        np.savetxt(ref, np.column_stack([t, np.zeros((len(t), 4))]), delimiter=",",
                   header="time,q_w,q_x,q_y,q_z", comments="")
    assert main(["estimate", str(EXAMPLE), "--reference", str(ref), "--out", str(tmp_path),
                 "--no-plots"]) == 2
    assert says in capsys.readouterr().err


def _small_tilts(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sensor tilted 2 deg in roll and 1 deg in pitch, swaying by half a degree, for 30 s at
    100 Hz (a vehicle's or a building's tilts), and its time, roll and pitch [rad]."""
    rng = np.random.default_rng(3)
    t = np.arange(3000) / 100.0
    roll = np.radians(2.0 + 0.5 * np.sin(2 * np.pi * 0.3 * t))
    pitch = np.radians(1.0 + 0.3 * np.sin(2 * np.pi * 0.2 * t))
    g = 9.80665
    acc = np.column_stack([-g * np.sin(pitch), g * np.cos(pitch) * np.sin(roll),
                           g * np.cos(pitch) * np.cos(roll)]) + rng.normal(0, 0.02, (3000, 3))
    gyro = np.column_stack([np.gradient(roll, t), np.gradient(pitch, t), np.zeros(3000)])
    np.savetxt(path, np.column_stack([t, acc, gyro + rng.normal(0, 0.002, (3000, 3))]),
               delimiter=",", header="time,ax,ay,az,gx (rad/s),gy (rad/s),gz (rad/s)",
               comments="")
    return t, roll, pitch


def _kf_rmse(out: str) -> float:
    return float(next(r for r in out.splitlines() if r.startswith("kf ")).split()[2])


def test_a_reference_in_degrees_is_read_in_degrees_whatever_its_range(tmp_path, capsys):
    """A reference's roll and pitch in degrees, the header silent: beyond radians' range (the
    example's 29 deg) they can only be degrees; within it (a vehicle's tilts of 1-2 deg, which
    read as radians are tens of degrees off) the accelerometer at rest tells: each scores as
    the reference in radians does, and the command says why it read degrees."""
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    rec = tmp_path / "tilts.csv"
    cases = [(EXAMPLE, truth[:, 0], truth[:, 1], truth[:, 2], "beyond radians' range"),
             (rec, *_small_tilts(rec), "from the data: the accelerometer at rest misses")]
    for recording, t, roll, pitch, why in cases:
        scores = []
        for name, scale in (("rad.csv", 1.0), ("deg.csv", 180.0 / np.pi)):
            _reference(tmp_path / name, t, roll * scale, pitch * scale)
            assert main(["estimate", str(recording), "--estimator", "kf", "--reference",
                         str(tmp_path / name), "--out", str(tmp_path / "out"),
                         "--no-plots"]) == 0
            out = capsys.readouterr().out
            scores.append(_kf_rmse(out))
        assert f"roll and pitch in deg ({why}" in out
        assert scores[1] == pytest.approx(scores[0], abs=1e-6)


def _battery_files(tmp_path: Path, motion: str) -> tuple[Path, Path, Path]:
    """A battery part's recording of a motion (the realistic MPU-6050, seed 0; its units in
    the header) and its truth as roll and pitch [rad] and as quaternions (sensor to world)."""
    from scipy.spatial.transform import Rotation

    from testbenches.battery import part_samples

    t, truth, sample = part_samples(motion, "mpu6050", 0)
    rec = tmp_path / f"{motion}.csv"
    np.savetxt(rec, np.column_stack([t, sample["acc"], sample["gyro"]]), delimiter=",",
               header="time,acc_x (m/s^2),acc_y (m/s^2),acc_z (m/s^2),gyro_x (rad/s),"
               "gyro_y (rad/s),gyro_z (rad/s)", comments="", fmt="%.10g")
    angles = tmp_path / f"{motion}_rp.csv"
    _reference(angles, t, truth["roll"], truth["pitch"])
    quat = Rotation.from_euler("ZYX", np.column_stack([truth["yaw"], truth["pitch"],
                                                      truth["roll"]])).as_quat()
    quats = tmp_path / f"{motion}_q.csv"
    np.savetxt(quats, np.column_stack([t, quat[:, [3, 0, 1, 2]]]), delimiter=",",
               header="time,q_w,q_x,q_y,q_z", comments="")
    return rec, angles, quats


@pytest.mark.parametrize("motion", ["pendulum", "shaking"])
def test_a_true_reference_of_a_motion_never_at_rest_is_scored(tmp_path, capsys, motion):
    """A pendulum's accelerometer never rests and a shaker's is no gravity's where its norm is
    near g: that direction missed a true reference by tens of degrees, so a pendulum's roll in
    radians read as degrees (27.6 deg scored) and a quaternion reference was refused ("no
    vertical ... explains the accelerometer at rest"). The laws that hold in any motion
    (testbenches.reference_axes) take both as they are."""
    rec, angles, quats = _battery_files(tmp_path, motion)
    scores = []
    for reference in (angles, quats):
        assert main(["estimate", str(rec), "--estimator", "kf", "--reference", str(reference),
                     "--no-plots", "--out", str(tmp_path / "out")]) == 0
        said = capsys.readouterr().out
        assert "in deg" not in said
        scores.append(_kf_rmse(said))
    assert max(scores) < 1.0
    assert scores[0] == pytest.approx(scores[1], abs=1e-3)


@pytest.mark.parametrize("kind,serves", [
    ("pitch", "they agree with the pitch's sign turned"),
    ("swapped", "they agree with roll and pitch swapped"),
    ("mounted", "they agree with --mounting 90,0,0"),
    ("own columns", "they agree with the pitch's sign turned"),
])
def test_a_reference_in_other_axes_is_refused_naming_what_serves(tmp_path, capsys, kind,
                                                                  serves):
    """A reference of another convention (its pitch's sign, roll and pitch swapped; in a file
    of its own or in the recording's own columns) or of a body the sensor sits on turned by
    90 deg scored 22-88 deg for VQF and the kf alike, with nothing said: along its up direction
    the accelerometer does not average 1 g, and the gyro does not turn it as it turns.
    Refused, with the convention or the mounting that meets both; the mounting given, the
    example's own score."""
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    roll, pitch = truth[:, 1], truth[:, 2]
    ex = _example()
    acc, gyro, columns = ex["acc"], ex["gyro"], [ex["time"]]
    if kind == "mounted":  # the sensor turned by 90 deg about x on the body the truth is of
        turn = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
        acc, gyro = acc @ turn.T, gyro @ turn.T
    angles = {"pitch": (roll, -pitch), "swapped": (pitch, roll)}.get(kind, (roll, pitch))
    own = []  # the recording's own roll and pitch, the pitch's sign turned
    if kind == "own columns":
        own = [np.interp(ex["time"], truth[:, 0], roll),
               -np.interp(ex["time"], truth[:, 0], pitch)]
    recording = tmp_path / "recording.csv"
    np.savetxt(recording, np.column_stack([*columns, acc, gyro, *own]), delimiter=",",
               comments="", fmt="%.17g", header="time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z"
               + (",roll,pitch" if own else ""))
    args = ["estimate", str(recording), "--estimator", "kf", "--no-plots", "--out",
            str(tmp_path / "out")]
    if kind != "own columns":
        _reference(tmp_path / "ref.csv", truth[:, 0], *angles)
        args += ["--reference", str(tmp_path / "ref.csv")]
    assert main(args) == 2
    said = capsys.readouterr().err
    assert "the reference does not describe this sensor in its axes" in said and serves in said
    assert "in degrees" not in said
    if kind == "mounted":
        assert main([*args, "--mounting", "90,0,0"]) == 0
        assert _kf_rmse(capsys.readouterr().out) == pytest.approx(0.5996, abs=1e-3)


def test_the_recordings_own_angles_in_degrees_are_refused_unless_stated(tmp_path, capsys):
    """The recording's own roll and pitch in degrees, the header silent, within radians'
    range (a device logging its own tilts of 1-2 deg): taken as radians, refused by the laws
    of motion with no hint of why; the refusal now names degrees and how to state them.
    Stated, they are scored, and the read names the file's columns it took as the reference
    and their unit (a device's own estimate logged beside its samples is no truth, and the
    score should not look like one)."""
    _, roll, pitch = _small_tilts(tmp_path / "tilts.csv")
    samples = np.loadtxt(tmp_path / "tilts.csv", delimiter=",", skiprows=1)
    for header, code in (("roll,pitch", 2), ("roll (deg),pitch (deg)", 0)):
        own = tmp_path / "own.csv"
        np.savetxt(own, np.column_stack([samples, np.degrees(roll), np.degrees(pitch)]),
                   delimiter=",", header="time,ax,ay,az,gx (rad/s),gy (rad/s),gz (rad/s),"
                   + header, comments="")
        assert main(["estimate", str(own), "--estimator", "kf", "--no-plots", "--out",
                     str(tmp_path / "out")]) == code
        said = capsys.readouterr()
        if code:
            assert "they agree with roll and pitch in degrees: state the unit in the header " \
                   "(roll (deg), pitch (deg))" in said.err
        else:
            assert ("reference from this file's columns roll='roll (deg)', pitch='pitch (deg)' "
                    "in deg (from the header)") in said.out
            assert _kf_rmse(said.out) < 0.1


def test_a_reference_unit_the_data_contradict_is_refused(tmp_path, capsys):
    """A header that says deg over radians (read as degrees they are level, 2 deg off the
    accelerometer at rest) is refused with the evidence, not scored."""
    t, roll, pitch = _small_tilts(tmp_path / "tilts.csv")
    ref = tmp_path / "ref.csv"
    np.savetxt(ref, np.column_stack([t, roll, pitch]), delimiter=",",
               header="time,roll (deg),pitch (deg)", comments="")
    assert main(["estimate", str(tmp_path / "tilts.csv"), "--reference", str(ref), "--out",
                 str(tmp_path / "out"), "--no-plots"]) == 2
    assert ("the header states roll and pitch in deg, but the accelerometer at rest misses "
            "their up direction by 2.") in capsys.readouterr().err


def test_a_reference_files_columns_are_mapped_by_their_own_option(tmp_path, capsys):
    """A reference whose quaternion is q0..q3 (w first here; an index names no order) scores
    with --reference-column as with the names the reader knows; without it the refusal says
    how; the option without a reference, or for a quantity no reference has, is refused."""
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    t, roll, pitch, yaw = truth[:, 0], truth[:, 1], truth[:, 2], truth[:, 3]
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    q = np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                         cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])
    scores = []
    for name, header in (("named.csv", "stamp,q_w,q_x,q_y,q_z"),
                         ("indexed.csv", "stamp,q0,q1,q2,q3")):
        path = tmp_path / name
        np.savetxt(path, np.column_stack([t, q]), delimiter=",", header=header, comments="")
        mapped = ["--reference-column", "time=stamp"] + (
            [f"--reference-column=q_{c}=q{k}" for k, c in enumerate("wxyz")]
            if name == "indexed.csv" else [])
        assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference", str(path),
                     *mapped, "--out", str(tmp_path / "out"), "--no-plots"]) == 0
        scores.append(_kf_rmse(capsys.readouterr().out))
    assert scores[1] == scores[0] == pytest.approx(0.5996, abs=1e-4)
    bare = ["estimate", str(EXAMPLE), "--out", str(tmp_path / "out"), "--no-plots"]
    assert main([*bare, "--reference", str(tmp_path / "indexed.csv"), "--reference-column",
                 "time=stamp"]) == 2
    assert "it has stamp, q0, q1, q2, q3: map them with --reference-column" in \
        capsys.readouterr().err
    assert main([*bare, "--reference-column", "q_w=q0"]) == 2
    assert "--reference-column is given, but no --reference" in capsys.readouterr().err
    assert main([*bare, "--reference-offset", "0.3"]) == 2
    assert "--reference-offset is given, but no --reference" in capsys.readouterr().err
    assert main([*bare, "--reference", str(tmp_path / "indexed.csv"), "--reference-column",
                 "acc_x=q0"]) == 2
    assert "QUANTITY one of time, roll, pitch, q_w, q_x, q_y, q_z" in capsys.readouterr().err


def test_a_reference_clock_apart_from_the_recordings_is_said_and_an_offset_aligns_it(
        tmp_path, capsys):
    """A reference whose clock runs 0.3 s (or -0.5 s, or 3 s) from the recording's would score
    tens of degrees: its up direction turns apart from the gyro's turn (reference_axes), and
    the refusal says the offset the turn rates show and the option that aligns them, which
    then scores as the aligned reference does; an aligned reference gets no such word."""
    import re

    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    for shift in (0.3, -0.5, 3.0):
        ref = tmp_path / "late.csv"
        _reference(ref, truth[:, 0] + shift, truth[:, 1], truth[:, 2])
        bare = ["estimate", str(EXAMPLE), "--estimator", "kf", "--reference", str(ref),
                "--out", str(tmp_path / "out"), "--no-plots"]
        assert main(bare) == 2
        said = capsys.readouterr().err
        assert "the reference does not describe this sensor in its axes" in said
        offset = float(re.search(r"give --reference-offset (\S+) to align them", said)[1])
        assert offset == pytest.approx(-shift, abs=0.03)  # to three samples
        assert main([*bare, "--reference-offset", str(-shift)]) == 0
        said = capsys.readouterr().out
        assert "clock runs" not in said and _kf_rmse(said) == pytest.approx(0.5996, abs=1e-3)
    assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference", str(TRUTH),
                 "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    assert "clock runs" not in capsys.readouterr().out


def test_a_recording_timed_since_1970_is_plotted_from_its_first_sample(tmp_path, monkeypatch):
    """A bag's or a logger's epoch times (1.7e9 s) plotted as they are read "+1.7e9" under an
    axis of seconds: the plot starts at the first sample and its axis names when that was."""
    pytest.importorskip("matplotlib")
    import matplotlib.axes

    from testbenches import estimate

    assert estimate.plot.when(1.7e9) == "2023-11-14 22:13:20 UTC"
    assert estimate.plot.when(2.0e5) == "200000 s"
    ex = _example()
    path = tmp_path / "epoch.csv"
    np.savetxt(path, np.column_stack([1.7e9 + ex["time"], ex["acc"], ex["gyro"]]),
               delimiter=",", header="time,ax,ay,az,gx (rad/s),gy (rad/s),gz (rad/s)",
               comments="", fmt="%.17g")
    labels = []
    real = matplotlib.axes.Axes.set_xlabel
    monkeypatch.setattr(matplotlib.axes.Axes, "set_xlabel",
                        lambda self, text, *a, **k: labels.append(text) or real(self, text))
    assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path)]) == 0
    assert [x for x in labels if x] == ["time [s] since 2023-11-14 22:13:20 UTC"]
    assert (tmp_path / "epoch.png").is_file()


def test_a_file_without_a_calibration_in_it_is_refused_as_calibration(tmp_path, capsys):
    path = tmp_path / "calibration.json"
    path.write_text('{"foo": 1}')
    assert main(["estimate", str(EXAMPLE), "--calibration", str(path), "--out",
                 str(tmp_path), "--no-plots"]) == 2
    assert "no acc_cal or gyro_cal entry, so not a calibration" in capsys.readouterr().err


def test_vqf_runs_on_the_samples_the_estimators_take_mounted(tmp_path, capsys):
    """A sensor mounted x-up (--mounting 0,90,0): the raw file holds the example's samples
    turned back by the mounting, so the estimators' input is the example's, and VQF's row
    equals VQF's on the example itself."""
    pytest.importorskip("vqf", reason="the bench extra: pip install -e '.[bench]'")
    from fusion_core.base import mounting_matrix

    ex = _example()
    r = np.asarray(mounting_matrix(0.0, np.pi / 2, 0.0)).reshape(3, 3)
    raw = tmp_path / "mounted.csv"
    np.savetxt(raw, np.column_stack([ex["time"], ex["acc"] @ r, ex["gyro"] @ r]),
               delimiter=",", header="time,ax,ay,az,gx,gy,gz", comments="", fmt="%.17g")

    def vqf_row(path: Path, *extra: str) -> float:
        assert main(["estimate", str(path), "--estimator", "kf", "--reference", str(TRUTH),
                     "--gyro-unit", "rad/s", "--out", str(tmp_path), "--no-plots",
                     *extra]) == 0
        out = capsys.readouterr().out
        return float(next(r for r in out.splitlines() if r.startswith("vqf ")).split()[2])

    assert vqf_row(raw, "--mounting", "0,90,0") == pytest.approx(vqf_row(EXAMPLE), abs=1e-3)


def _quat_zyx(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Sensor-to-world unit quaternions (w first) of Z-Y-X Euler angles."""
    cr, sr, cp, sp = np.cos(roll / 2), np.sin(roll / 2), np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    return np.column_stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


@pytest.mark.parametrize("block_rows", [None, 302])
def test_vqf_integrates_over_the_samples_missing_as_the_estimators_do(tmp_path, capsys,
                                                                      monkeypatch,
                                                                      block_rows):
    """Samples without numbers (or lines no row of the table) are rejected; the estimators
    integrate the next sample over its dt, which spans them. VQF has a fixed sampling period:
    given the next sample once, it turned through the gap by nothing and its row was worse
    (1.11 deg against 0.97 for one sample missed at 5 s). It takes it once per period missed,
    across a block's edge too; a row written twice takes no time and changes nothing."""
    pytest.importorskip("vqf", reason="the bench extra: pip install -e '.[bench]'")
    import testbenches.table as table

    if block_rows:
        monkeypatch.setattr(table, "BLOCK_ROWS", block_rows)
    lines = EXAMPLE.read_text().splitlines(keepends=True)

    def vqf_row(name: str, text: list[str]) -> float:
        path = tmp_path / name
        path.write_text("".join(text))
        assert main(["estimate", str(path), "--estimator", "kf", "--reference", str(TRUTH),
                     "--gyro-unit", "rad/s", "--out", str(tmp_path), "--no-plots"]) == 0
        out = capsys.readouterr().out
        return float(next(r for r in out.splitlines() if r.startswith("vqf ")).split()[2])

    whole = vqf_row("whole.csv", lines)
    gap = [x if not 300 <= k < 304 else x.split(",")[0] + ",,,,,,,\n"
           for k, x in enumerate(lines)]
    twice = [*lines[:500], lines[499], *lines[500:]]
    assert vqf_row("gap.csv", gap) == pytest.approx(whole, abs=0.01)
    assert vqf_row("twice.csv", twice) == pytest.approx(whole, abs=1e-4)


def test_a_reference_whose_world_frame_is_y_up_is_aligned_heading_free(tmp_path, capsys):
    """Motion capture often has y up: the same attitudes in a y-up world frame score as in
    the z-up one, and the command says which vertical it found."""
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    q = _quat_zyx(truth[:, 1], truth[:, 2], truth[:, 3])
    to_y_up = np.tile([np.cos(-np.pi / 4), np.sin(-np.pi / 4), 0.0, 0.0], (len(q), 1))
    header = "time,q_w,q_x,q_y,q_z"
    z_up, y_up = tmp_path / "z.csv", tmp_path / "y.csv"
    np.savetxt(z_up, np.column_stack([truth[:, 0], q]), delimiter=",", header=header,
               comments="")
    np.savetxt(y_up, np.column_stack([truth[:, 0], _quat_mul(to_y_up, q)]), delimiter=",",
               header=header, comments="")
    rmse = {}
    for path in (z_up, y_up):
        assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference", str(path),
                     "--out", str(tmp_path), "--no-plots"]) == 0
        out = capsys.readouterr().out
        rmse[path.stem] = _kf_rmse(out)
    assert "world frame's up is +y" in out
    assert rmse["y"] == pytest.approx(rmse["z"], abs=1e-4)


def test_a_quaternion_reference_of_another_sensor_is_refused(tmp_path, capsys):
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    rng = np.random.default_rng(2)
    q = rng.standard_normal((len(truth), 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    path = tmp_path / "random.csv"
    np.savetxt(path, np.column_stack([truth[:, 0], q]), delimiter=",",
               header="time,q_w,q_x,q_y,q_z", comments="")
    assert main(["estimate", str(EXAMPLE), "--reference", str(path), "--out", str(tmp_path),
                 "--no-plots"]) == 2
    assert "no vertical of the reference's world frame explains" in capsys.readouterr().err


def test_each_estimator_takes_the_blocks_in_order_at_its_own_pace():
    """estimate's _Lanes: every task sees every block in order, a fast task does not wait for
    a slow one at the end of a block, no more than IN_FLIGHT blocks are held, done() follows
    the slowest, and a task's exception is raised in the caller."""
    import time

    from testbenches import estimate

    class Task:
        def __init__(self, pause):
            self.pause, self.seen, self.times = pause, [], []

        def block(self, k):
            time.sleep(self.pause)
            self.seen.append(k)
            self.times.append(time.perf_counter())

    fast, slow, done = Task(0.0), Task(0.02), []
    lanes = estimate.lanes.Lanes([fast, slow], done.append)
    held = []
    for k in range(10):
        lanes.submit(k + 1, k)
        held.append(k + 1 - len(done))
    lanes.close()
    assert fast.seen == slow.seen == list(range(10))
    assert fast.times[-1] < slow.times[-2]  # the fast one ran ahead
    assert max(held) <= estimate.lanes.IN_FLIGHT
    assert done == [k + 1 for k in range(10)]

    class Failing(Task):
        def block(self, k):
            if k == 2:
                raise ValueError("disk full")
            super().block(k)

    failing = Failing(0.0)
    lanes = estimate.lanes.Lanes([Task(0.0), failing], lambda n: None)
    with pytest.raises(ValueError, match="disk full"):
        for k in range(10):
            lanes.submit(1, k)
        lanes.close()
    lanes.close(quiet=True)
    assert failing.seen == [0, 1]


def test_the_reader_thread_has_ended_when_the_blocks_loop_does():
    """estimate's _read_ahead: where the caller stops on an error (a reference that does not
    overlap, found on the first block), the thread reading the next block has ended before the
    error leaves: a reader still in pyarrow's C++ at the interpreter's exit aborted the process
    (exit status 134, "terminate called without an active exception") instead of the one-line
    refusal."""
    import threading
    import time

    from testbenches import estimate

    read = []

    def blocks():
        yield 0
        time.sleep(0.3)  # the next block, still being read when the caller stops
        read.append(1)
        yield 1
        read.append(2)

    before = threading.active_count()
    with pytest.raises(RuntimeError, match="stop"):
        for _ in estimate.lanes.read_ahead(blocks()):
            raise RuntimeError("stop")
    assert read == [1]  # the block in hand was finished, no further one read
    assert threading.active_count() == before


def test_a_sensor_that_starts_z_down_is_said_and_a_mounting_turns_it(tmp_path, capsys):
    """A drone autopilot logs its IMU in a z-down frame (FRD: level reads -g on z). Read in this
    project's z-up frame its roll is near 180 deg: without a reference the command says why;
    a z-up reference, 160 deg off, is refused naming the mounting that serves (a score of
    160 deg would be no estimator's); --mounting 180,0,0 reads it as the level example it
    is."""
    ex = _example()
    frd = tmp_path / "frd.csv"
    flip = np.array([1.0, -1.0, -1.0])
    np.savetxt(frd, np.column_stack([ex["time"], ex["acc"] * flip, ex["gyro"] * flip]),
               delimiter=",", header="time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z",
               comments="", fmt="%.17g")
    alone = ["estimate", str(frd), "--estimator", "kf", "--no-plots"]
    assert main([*alone, "--out", str(tmp_path / "a")]) == 0
    said = capsys.readouterr().out
    assert "starts with its z axis down" in said and "--mounting 180,0,0" in said
    args = [*alone, "--reference", str(TRUTH)]
    assert main([*args, "--out", str(tmp_path / "a")]) == 2
    assert "they agree with --mounting 180,0,0" in capsys.readouterr().err
    assert main([*args, "--mounting", "180,0,0", "--out", str(tmp_path / "b")]) == 0
    turned = capsys.readouterr().out
    assert "z axis down" not in turned
    rmse = float(next(r for r in turned.splitlines() if r.startswith("kf ")).split()[2])
    assert rmse < 1.5


@pytest.mark.parametrize("extra,says", [
    (["--time-column", "acc_x"], "the column 'acc_x' is taken for both acc_x and time"),
    (["--column", "gyro_x=acc_x"], "the column 'acc_x' is taken for both acc_x and gyro_x"),
    (["--out", "FILE"], "is a file: the outputs go to a folder"),  # argparse's, after usage
    (["--calibration", "MISSING"], "calibration file"),
    (["--preset", "MISSING"], "preset file"),
    (["--param", "foo=1"], "--param foo: no estimator run here has it; they have Q_angle"),
    (["--estimator", "cf", "--param", "Q_angle=1e-5"], "--param Q_angle: no estimator run here"),
])
def test_an_option_that_cannot_serve_gets_one_line(tmp_path, extra, says):
    """A column given for a quantity another already takes (pyarrow's KeyError on the
    doubled field, as a traceback), --out naming a file (FileExistsError: now refused by the
    option's type, as argparse refuses, after the usage), a calibration or preset file that is
    not there (an errno's text), a parameter no estimator run has: one line each."""
    out = tmp_path / "FILE"
    out.write_text("keep")
    missing = "MISSING" in extra
    extra = [str(out) if e == "FILE" else str(tmp_path / "none.json") if e == "MISSING" else e
             for e in extra]
    args = ["--out", str(tmp_path / "out"), *extra] if "--out" not in extra else extra
    proc = subprocess.run([sys.executable, "-m", "testbenches", "estimate", str(EXAMPLE),
                           "--no-plots", *args], capture_output=True, text=True, timeout=120,
                          cwd=REPO)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert says in lines[-1] and "Traceback" not in proc.stderr, proc.stderr
    assert "Errno" not in proc.stderr and (not missing or "no such file" in lines[-1])
    assert len(lines) == 1 or lines[0].startswith("usage:"), proc.stderr
    assert out.read_text() == "keep"


def test_a_parameter_goes_to_the_estimators_that_have_it(tmp_path):
    """--param Q_angle (the Kalman filters') with every estimator: the Kalman filters take it,
    the others run as they would without it."""
    assert main(["estimate", str(EXAMPLE), "--estimator", "cf,kf", "--param", "Q_angle=1e-3",
                 "--out", str(tmp_path), "--no-plots"]) == 0
    ex = _example()
    dt = np.diff(ex["time"], prepend=ex["time"][0] - 0.01)
    for key, params in (("cf", {}), ("kf", {"Q_angle": 1e-3})):
        out = np.loadtxt(tmp_path / f"tilt_motion_{key}.csv", delimiter=",", skiprows=1)
        np.testing.assert_array_equal(out[:, 1], create(key, params).run(
            ex["acc"], ex["gyro"], dt)["roll"])


def test_a_reference_whose_header_states_degrees_is_read_in_degrees(tmp_path, capsys):
    """roll and pitch under "Roll (deg)", "Pitch (deg)": the same RMSE as the truth in rad (they
    were refused as degrees though the header said so); a unit that is no angle is refused."""
    truth = np.genfromtxt(TRUTH, delimiter=",", names=True)

    def rmse(ref: Path) -> float:
        assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference", str(ref),
                     "--out", str(tmp_path / "out"), "--no-plots", "--no-vqf"]) == 0
        line = next(r for r in capsys.readouterr().out.splitlines() if r.startswith("kf "))
        return float(line.split()[2])

    deg = tmp_path / "deg.csv"
    np.savetxt(deg, np.column_stack([truth["time"], np.degrees(truth["roll"]),
                                     np.degrees(truth["pitch"])]),
               delimiter=",", header="time,Roll (deg),Pitch (deg)", comments="", fmt="%.17g")
    assert rmse(deg) == pytest.approx(rmse(TRUTH), abs=1e-4)
    bad = tmp_path / "bad.csv"
    bad.write_text(deg.read_text().replace("Pitch (deg)", "Pitch (g)", 1))
    assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference", str(bad),
                 "--out", str(tmp_path / "out"), "--no-plots"]) == 2
    assert "states the unit(s) deg, g for roll and pitch" in capsys.readouterr().err


def test_the_plot_keeps_every_kth_sample_and_computes_no_more() -> None:
    """Thinned keeps the rows that are multiples of one k (at most 2 * PLOT_POINTS of them,
    the same whichever blocks they came in), and asks a block's `make` for those rows alone:
    a long first block is not computed whole to be thinned afterwards."""
    from testbenches.estimate import PLOT_POINTS, Thinned

    asked: list[int] = []

    def make(at: np.ndarray, row0: int) -> dict[str, np.ndarray]:
        asked.append(len(at))
        return {"t": (row0 + at) * 0.01}

    rows = 10 * 262144 + 12345
    blocks = [(0, 262144), (262144, 5), (262149, rows - 262149)]
    trace = Thinned()
    for row0, n in blocks:
        trace.add_at(row0, n, lambda at, row0=row0: make(at, row0))
    assert len(trace.rows) <= 2 * PLOT_POINTS
    assert np.array_equal(trace.rows, np.arange(0, rows, trace.k))
    assert np.array_equal(trace.values["t"], trace.rows * 0.01)
    assert max(asked) <= 2 * PLOT_POINTS  # the first block's 262144 rows were never asked for
    whole = Thinned()
    whole.add(0, {"t": np.arange(rows) * 0.01})
    assert whole.k == trace.k and np.array_equal(whole.rows, trace.rows)
