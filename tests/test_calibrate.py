"""`imu-fusion calibrate`: a known part recovered from a simulated session, the refusals, and
on the real imucal session Ferraris's calibration beside imucal's."""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest

from fusion_core.calibration import Calibration
from fusion_core.scenarios import get_scenario
from fusion_core.sensor import ImuSensorModel, sensor_preset
from testbenches.calibrate import ferraris as fer
from testbenches.calibrate.detect import Static
from testbenches.calibrate.tedaldi import CalibrationRefused, calibrate_session, check_spread
from testbenches.cli import main

pytestmark = pytest.mark.heavy  # calibration sessions simulated and fitted

REPO = Path(__file__).resolve().parents[1]
IMUCAL = Path(os.environ.get("IMUCAL_DIR", REPO.parent / "shared" / "data" / "imucal"))
SESSION = IMUCAL / "example_ferraris_session.csv"
SECTIONS = IMUCAL / "example_ferraris_session_list.json"
needs_imucal_data = pytest.mark.skipif(
    not SESSION.is_file(), reason=f"no imucal session in {IMUCAL} (set IMUCAL_DIR)")


def simulated(seed: int = 0, scenario: str = "calibration_session"):
    """The session recorded through an uncalibrated realistic part (MPU-6050 initial
    tolerances: gyro bias 6.7 deg/s, scale 1 %, cross-axis 0.67 %); the part's model too."""
    sc = get_scenario(scenario)
    t = np.arange(0.0, sc.duration, 0.01)
    truth = sc.truth(t)
    part = ImuSensorModel(**{**sensor_preset("realistic"), "seed": seed, "calibration": "none"})
    out = part.run(truth[:, 3:6], truth[:, 6:9], 0.01)
    return t, out["acc"], out["gyro"], np.full(len(t), 0.01), part


def frame_error(cal_matrix: np.ndarray, true_matrix: np.ndarray, rotation: np.ndarray) -> float:
    """How far the calibration is from undoing the part's matrix, in the accelerometer's own
    frame (a calibration cannot see a rotation of the whole sensor: that is the mounting)."""
    return float(np.max(np.abs(cal_matrix @ true_matrix - rotation)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_known_part_is_recovered_from_a_simulated_session(seed: int) -> None:
    _, acc, gyro, dt, part = simulated(seed)
    session = calibrate_session(acc, gyro, dt)
    assert len(session.statics) == 14
    p = session.acc.matrix @ np.array(part.acc_matrix)
    u, _, vt = np.linalg.svd(p)
    rotation = u @ vt  # the frame the accelerometer defines
    assert frame_error(session.acc.matrix, np.array(part.acc_matrix), rotation) < 1e-3
    assert frame_error(session.gyro.matrix, np.array(part.gyro_matrix), rotation) < 1e-3
    assert np.max(np.abs(session.gyro.offset - np.array(part.gyro_bias))) < 2e-4  # rad/s
    assert np.max(np.abs(session.acc.offset - np.array(part.acc_bias))) < 5e-3  # m/s^2
    # the fit's own uncertainty is of the size of the errors it leaves
    assert 1e-5 < np.max(session.gyro.matrix_std) < 2e-3
    assert np.sqrt(np.mean(session.gyro.after ** 2)) < 0.1 * np.sqrt(
        np.mean(session.gyro.before ** 2))


def test_too_few_poses_are_refused_with_what_to_record() -> None:
    t, acc, gyro, dt, _ = simulated()
    head = t < 25.0  # six poses, the last cut short
    with pytest.raises(CalibrationRefused, match=r"in 6 distinct directions .* record 12 or "
                                                 "more poses spread over the sphere"):
        calibrate_session(acc[head], gyro[head], dt[head])


def test_a_rotation_at_the_gyros_range_is_refused() -> None:
    _, acc, gyro, dt, _ = simulated()
    with pytest.raises(CalibrationRefused, match=r"reached its range \(\+-150 deg/s\): .* turn "
                                                 "the sensor more slowly"):
        calibrate_session(acc, gyro, dt, gyro_range=math.radians(150.0))


def test_a_session_without_its_turns_is_refused() -> None:
    """The moves cut out (a recording with gaps): the gyro saw no rotation between poses."""
    t, acc, gyro, dt, _ = simulated()
    phase = (t - 3.0) % 4.6
    still = (t < 3.0) | (phase > 1.6)
    with pytest.raises(CalibrationRefused, match=r"the gyro saw .* the recording must hold the "
                                                 "turns"):
        calibrate_session(acc[still], gyro[still], dt[still])


def test_poses_not_spread_over_the_sphere_are_refused() -> None:
    """Ten poses turned about one horizontal axis only: their gravity directions lie in a
    plane, which cannot give the third axis's scale."""
    angles = np.radians(np.arange(0.0, 360.0, 36.0))
    statics = [Static(0, 1, 9.81 * np.array([0.0, math.sin(a), math.cos(a)]), np.zeros(3))
               for a in angles]
    with pytest.raises(CalibrationRefused, match=r"not spread over the sphere .* hold the "
                                                 "sensor with each axis pointing up and down"):
        check_spread(statics)


@pytest.mark.heavy  # a session calibrated (and refitted per pose): seconds
def test_the_command_writes_the_calibration_and_its_plot(tmp_path, capsys) -> None:
    t, acc, gyro, _, part = simulated(1)
    csv = tmp_path / "session.csv"
    np.savetxt(csv, np.column_stack([t, acc / 9.80665, np.degrees(gyro)]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    out = tmp_path / "cal"
    assert main(["calibrate", str(csv), "--acc-unit", "g", "--gyro-unit", "deg/s",
                 "--out", str(out)]) == 0
    cal = Calibration.read(out / "calibration.json")
    doc = json.loads((out / "calibration.json").read_text())
    assert doc["method"] == "tedaldi" and doc["poses"] == 14
    assert len(doc["acc"]["residual_after"]) == 14
    assert np.array(doc["gyro"]["matrix_std"]).shape == (3, 3)
    assert (out / "calibration.png").stat().st_size > 10_000
    assert np.max(np.abs(np.array(cal.gyro_offset) - np.array(part.gyro_bias))) < 2e-4
    assert "14 static poses" in capsys.readouterr().out
    # a recording that cannot serve: one line, exit status 2
    short = tmp_path / "short.csv"
    np.savetxt(short, np.column_stack([t, acc, gyro])[:1500], delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    assert main(["calibrate", str(short), "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "distinct directions" in err


@needs_imucal_data
def test_ferraris_on_the_imucal_session_gives_imucals_scale_errors() -> None:
    from testbenches.fit.recording import load_recording

    rec, _ = load_recording(SESSION, rate=102.4, acc_unit="m/s2", gyro_unit="deg/s")
    acc_fit, gyro_fit = fer.ferraris(rec.acc, rec.gyro, rec.dt, fer.read_sections(SECTIONS))
    scales = fer.summary(acc_fit, gyro_fit)
    # imucal's own result on this session: gyro x +2.8 %, y -1.8 %; accelerometer z +2.3 %
    assert scales["gyro"]["scale"][0] == pytest.approx(1.028, abs=1e-3)
    assert scales["gyro"]["scale"][1] == pytest.approx(0.982, abs=1e-3)
    assert scales["acc"]["scale"][2] == pytest.approx(1.023, abs=1e-3)


@needs_imucal_data
def test_ours_beside_imucals_with_the_given_and_with_our_own_sections(tmp_path) -> None:
    pytest.importorskip("imucal", reason="imucal is not installed (the bench extra has it)")
    assert main(["calibrate", str(SESSION), "--rate", "102.4", "--gyro-unit", "deg/s",
                 "--acc-unit", "m/s2", "--sections", str(SECTIONS), "--gravity", "9.81",
                 "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "calibration.json").read_text())
    comp = doc["comparisons"]
    assert doc["method"] == "ferraris"  # six poses do not determine Tedaldi's model
    Calibration.read(tmp_path / "calibration.json")  # the file the command wrote is one it reads
    for ours in ("ferraris", "ferraris_own_sections"):
        for sensor in ("acc", "gyro"):
            diff = np.abs(np.array(comp[ours][f"{sensor}_matrix"])
                          - np.array(comp["imucal"][f"{sensor}_matrix"]))
            assert np.max(diff) <= 0.003, (ours, sensor, diff)
    assert np.max(np.abs(np.array(comp["ferraris"]["gyro_matrix"])
                         - np.array(comp["imucal"]["gyro_matrix"]))) < 1e-9  # the same method


def _level_tilt_deg(acc_matrix: np.ndarray, part_matrix: np.ndarray) -> float:
    """How far from z up a level housing reads once calibrated [deg]: the part's matrix and
    the calibration's, the offsets left out (they are the session's)."""
    f = acc_matrix @ part_matrix @ np.array([0.0, 0.0, 9.80665])
    return float(np.degrees(np.arccos(f[2] / np.linalg.norm(f))))


def test_level_turns_the_calibrated_axes_onto_the_level_pose(tmp_path, capsys) -> None:
    """A part's triad tilted in its housing (cross-axis errors of 0.67 %) is left tilted by a
    calibration from poses and turns alone; the session's first pose, held level, shows it
    (calibrate --level), and both sensors' axes are turned alike."""
    from testbenches.calibrate.level import levelled

    t, acc, gyro, _, part = simulated(2)
    csv = tmp_path / "session.csv"
    np.savetxt(csv, np.column_stack([t, acc, gyro]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    tilt = {}
    for option in ([], ["--level"]):
        out = tmp_path / f"cal{len(option)}"
        assert main(["calibrate", str(csv), "--out", str(out), "--no-plots", *option]) == 0
        doc = json.loads((out / "calibration.json").read_text())
        tilt[bool(option)] = _level_tilt_deg(np.array(doc["acc_cal"]["matrix"]),
                                             np.array(part.acc_matrix))
    assert tilt[False] > 0.1 and tilt[True] < 0.01, tilt
    assert "levelled (--level): the still pose nearest z up read roll" in capsys.readouterr().out
    assert set(doc["level"]) == {"pose", "roll_deg", "pitch_deg"}
    Calibration.from_json(doc)  # the file the command wrote is one it reads
    gyro_cal = np.array(doc["gyro_cal"]["matrix"])
    u, _, vt = np.linalg.svd(np.array(doc["acc_cal"]["matrix"]) @ np.array(part.acc_matrix))
    assert frame_error(gyro_cal, np.array(part.gyro_matrix), u @ vt) < 1e-3
    session = calibrate_session(acc, gyro, np.full(len(t), 0.01))
    with pytest.raises(ValueError, match=r"reads 90\.0 deg from z up"):
        levelled(session.acc, session.gyro, session.acc.offset + np.array([9.8, 0.0, 0.0]))


@pytest.mark.parametrize("seed", [8, 16])
def test_a_part_calibrated_first_is_levelled_by_its_sessions_first_pose(seed: int) -> None:
    """The contract's calibrated-first parts: their session's first pose is level
    (scenarios.CALIBRATION_POSES_DEG), so the matrices leave a level part reading level but
    for the session's noise; the session's fit alone leaves these parts 0.1 deg off."""
    from testbenches.calibrate.part import SESSION, part_calibration
    from testbenches.samples import scenario_samples

    sensor = sensor_preset("realistic")
    values = part_calibration(sensor, seed)
    acc_m = np.array([values[f"acc_cal_{r}{c}"] for r in "xyz" for c in "xyz"]).reshape(3, 3)
    part = np.array(ImuSensorModel(**{**sensor, "seed": seed}).acc_matrix)
    assert _level_tilt_deg(acc_m, part) < 0.05
    _, _, out = scenario_samples(SESSION, seed, {**sensor, "seed": seed})
    fit = calibrate_session(out["acc"], out["gyro"], out["dt"]).acc.matrix
    assert _level_tilt_deg(fit, part) > 0.08


def test_a_part_calibrated_first_gets_its_own_matrices_undone() -> None:
    from testbenches.calibrate.part import part_calibration

    sensor = sensor_preset("realistic")
    values = part_calibration(sensor, 3)
    part = ImuSensorModel(**{**sensor, "seed": 3})
    acc_m = np.array([values[f"acc_cal_{r}{c}"] for r in "xyz" for c in "xyz"]).reshape(3, 3)
    gyro_m = np.array([values[f"gyro_cal_{r}{c}"] for r in "xyz" for c in "xyz"]).reshape(3, 3)
    u, _, vt = np.linalg.svd(acc_m @ np.array(part.acc_matrix))
    assert frame_error(gyro_m, np.array(part.gyro_matrix), u @ vt) < 1e-3
    assert not any(name.endswith(("_off_x", "_off_y", "_off_z")) for name in values)


def test_a_campaign_that_calibrates_first_applies_each_parts_matrices() -> None:
    from fusion_core.registry import create
    from testbenches.calibrate.part import part_calibration
    from testbenches.montecarlo.plan import plan
    from testbenches.montecarlo.simulate import scenario_samples, simulate

    sensor = sensor_preset("realistic")
    (plain,) = plan(["kf"], ["roll_pitch"], 1, sensor=sensor)
    (run,) = plan(["kf"], ["roll_pitch"], 1, sensor=sensor, calibrate_first=True)
    assert run.key != plain.key  # a resumed campaign never mixes the two
    result = simulate(run)
    params = {"gyro_sampling": "point", **part_calibration(sensor, 0)}
    _, _, sample = scenario_samples("roll_pitch", 0, sensor)
    want = create("kf", params).run(sample["acc"], sample["gyro"], sample["dt"])
    assert np.array_equal(result.estimate["roll"], want["roll"])
    assert not np.array_equal(simulate(plain).estimate["roll"], want["roll"])


@pytest.mark.fmu
@pytest.mark.heavy
def test_run_calibrate_first_through_the_fmus_gives_the_campaigns_figures(built_fmus) -> None:
    from testbenches.contract_runs import run_contract
    from testbenches.fmus import kind_dir
    from testbenches.montecarlo.plan import plan
    from testbenches.montecarlo.simulate import run_row

    sensor = sensor_preset("realistic")
    result = run_contract(estimators=["ukf"], scenarios=["roll_pitch"], seeds=1,
                          fmu_dir=kind_dir(built_fmus.directory), contract_checks=False,
                          timing=False, sensor=sensor, calibrate_first=True)
    (run,) = plan(["ukf"], ["roll_pitch"], 1, sensor=sensor, calibrate_first=True)
    row = run_row(run)
    (fmu_run,) = result.runs
    assert fmu_run.metrics["rmse_roll_deg"] == pytest.approx(row["rmse_roll_deg"], abs=1e-9)


@needs_imucal_data
def test_a_six_face_session_is_calibrated_by_ferraris_on_the_sections_it_finds(tmp_path,
                                                                               capsys) -> None:
    """The shipped imucal session as a user first tries it: the counter column is named as no
    time; with the rate, Ferraris's method on the session's own sections (no --sections), and
    each held-out pose and move meets the calibration far better than the raw data."""
    assert main(["calibrate", str(SESSION), "--gyro-unit", "deg/s", "--out",
                 str(tmp_path)]) == 2
    assert "'n_samples' counts samples, which is no time" in capsys.readouterr().err
    assert main(["calibrate", str(SESSION), "--rate", "102.4", "--gyro-unit", "deg/s",
                 "--gravity", "9.81", "--out", str(tmp_path)]) == 0
    said = capsys.readouterr().out
    assert "Ferraris's on the six poses and three full turns found in the session" in said
    doc = json.loads((tmp_path / "calibration.json").read_text())
    assert doc["method"] == "ferraris" and set(doc["sections"]) == set(fer.SECTIONS)
    held_acc = np.array(doc["acc"]["residual_held_out"])
    held_gyro = np.degrees(doc["gyro"]["residual_held_out"])
    assert len(held_acc) >= 4 and len(held_gyro) >= 4
    assert np.sqrt(np.mean(held_acc ** 2)) < 0.02  # raw: 0.55 m/s2 at the same poses
    assert np.sqrt(np.mean(held_gyro ** 2)) < 1.5  # deg, moves of about 90 deg by hand
    assert (tmp_path / "calibration.png").stat().st_size > 10_000


@pytest.mark.heavy  # a session calibrated (and refitted per pose): seconds
def test_tedaldis_held_out_residuals_are_each_pose_left_out() -> None:
    _, acc, gyro, dt, _ = simulated(1)
    session = calibrate_session(acc, gyro, dt)
    from testbenches.calibrate.heldout import tedaldi_held_out

    held = tedaldi_held_out(session, 9.80665)
    assert len(held.acc) == len(session.statics) and len(held.gyro) == len(session.turns)
    # left out, a pose is met less well than in the fit, but still to a few mm/s2
    assert np.sqrt(np.mean(held.acc ** 2)) > np.sqrt(np.mean(session.acc.after ** 2))
    assert np.sqrt(np.mean(held.acc ** 2)) < 0.01
    assert np.degrees(np.sqrt(np.mean(held.gyro ** 2))) < 0.2


@needs_imucal_data
def test_a_session_with_empty_cells_is_filled_and_a_long_gap_refused(tmp_path, capsys) -> None:
    """A logger's empty cells in a session ('cannot convert float NaN to integer'): filled from
    their neighbours, said, and the calibration is the whole session's to 1e-4; a run of them
    longer than MAX_FILLED_S would make up part of a turn, and is refused naming the samples
    (numbered as --sections numbers them)."""
    from testbenches.calibrate.cli import MAX_FILLED_S

    lines = SESSION.read_text().splitlines()
    args = ["--rate", "102.4", "--gyro-unit", "deg/s", "--no-plots"]
    assert main(["calibrate", str(SESSION), *args, "--out", str(tmp_path / "whole")]) == 0
    capsys.readouterr()
    holes = list(lines)
    for row in (1000, 5000, 9000):  # a cell each, in poses and turns
        cells = holes[row].split(",")
        cells[2 + row % 3] = ""
        holes[row] = ",".join(cells)
    path = tmp_path / "holes.csv"
    path.write_text("\n".join(holes) + "\n")
    assert main(["calibrate", str(path), *args, "--out", str(tmp_path / "holes")]) == 0
    assert "3 sample(s) without a number in every column filled" in capsys.readouterr().out
    whole, filled = (json.loads((tmp_path / n / "calibration.json").read_text())
                     for n in ("whole", "holes"))
    for sensor in ("acc_cal", "gyro_cal"):
        np.testing.assert_allclose(filled[sensor]["matrix"], whole[sensor]["matrix"], atol=1e-4)
    assert "filled" in filled
    Calibration.from_json(filled)  # the file the command wrote is one it reads
    gap = list(lines)
    rows = int(0.3 * 102.4)
    assert rows / 102.4 > MAX_FILLED_S
    for row in range(3001, 3001 + rows):
        cells = gap[row].split(",")
        cells[2] = ""
        gap[row] = ",".join(cells)
    path.write_text("\n".join(gap) + "\n")
    assert main(["calibrate", str(path), *args, "--out", str(tmp_path / "gap")]) == 2
    assert re.search(r"samples 3000 to 3029 \(from 0, as --sections numbers them\) lack a "
                     r"number .*record the session again", capsys.readouterr().err)
