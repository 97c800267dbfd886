"""BROAD evaluation (issue 5): the trial loader (both formats), the inclination metric, the
`broad` command line and the FMU path. Runs on BROAD trials in the folder BROAD_DIR names
(default ../shared/data/broad beside the project, where CI keeps the shared trials), cut to a
45 s slice where a whole trial would be slow; skipped with the reason where they are absent."""

from __future__ import annotations

import argparse
import json
import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fusion_core import DEG, ESTIMATORS
from fusion_core.kinematics import quat_from_roll_pitch_yaw
from fusion_core.presets import PRESETS, preset_params
from fusion_core.registry import ATTITUDE_FILTERS, create
from testbenches.__main__ import main
from testbenches.broad.data import BroadTrial, NotABroadTrial, load_trial, trial_groups
from testbenches.broad.metric import (
    gravity_from_quat,
    gravity_from_roll_pitch,
    inclination_error,
    inclination_rmse_deg,
)
from testbenches.broad.run import Column, evaluate, plan_columns, run_fmu, run_fusion_core

h5py = pytest.importorskip("h5py")

DATA = Path(os.environ.get("BROAD_DIR",
                       Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"))
HDF5_TRIAL = DATA / "10_undisturbed_slow_translation_A.hdf5"
MAT_TRIAL = DATA / "01_undisturbed_slow_rotation_A.mat"
RATE = 285.7142857142857

pytestmark = [
    pytest.mark.heavy,  # BROAD's trials: `make test-fast` leaves them out
    pytest.mark.skipif(not HDF5_TRIAL.is_file() or not MAT_TRIAL.is_file(),
                       reason=f"no BROAD trials in {DATA} (set BROAD_DIR to a folder "
                       "with 10_undisturbed_slow_translation_A.hdf5 and "
                       "01_undisturbed_slow_rotation_A.mat)"),
]


def write_slice(path: Path, seconds: float = 45.0, source: Path = HDF5_TRIAL) -> Path:
    """The first `seconds` of a shared trial as a BROAD HDF5 file (rest, then movement from
    36.8 s on for trial 10)."""
    trial = load_trial(source)
    k = round(seconds * trial.rate)
    with h5py.File(path, "w") as f:
        f["imu_acc"] = trial.acc[:k]
        f["imu_gyr"] = trial.gyro[:k]
        f["opt_quat"] = trial.opt_quat[:k]
        f["movement"] = trial.movement[:k]
        f.attrs["sampling_rate"] = trial.rate
    return path


# ----- loader --------------------------------------------------------------------------------
@pytest.mark.parametrize("path", [HDF5_TRIAL, MAT_TRIAL], ids=["hdf5", "mat"])
def test_loader_reads_both_formats_into_the_same_fields(path: Path) -> None:
    trial = load_trial(path)
    assert trial.name == path.stem
    assert trial.rate == pytest.approx(RATE, rel=1e-12)
    assert trial.acc.shape == trial.gyro.shape == (trial.n, 3)
    assert trial.opt_quat.shape == (trial.n, 4)
    assert trial.movement.shape == (trial.n,) and trial.movement.dtype == bool
    assert 0.3 < trial.movement.mean() < 0.8
    # at rest the accelerometer reads +g along up: about (0, 0, 9.8) for a level sensor
    assert np.linalg.norm(trial.acc[:100], axis=1).mean() == pytest.approx(9.81, abs=0.2)


def test_loader_finds_the_format_from_the_content_not_the_file_name(tmp_path: Path) -> None:
    renamed = write_slice(tmp_path / "trial_without_suffix", seconds=5.0)
    trial = load_trial(renamed)
    assert trial.n == round(5.0 * RATE)
    assert trial.duration == pytest.approx(5.0, abs=1.0 / RATE)


def test_loader_refuses_a_file_that_is_neither_hdf5_nor_mat(tmp_path: Path) -> None:
    path = tmp_path / "notes.mat"
    path.write_text("imu_acc, imu_gyr\n1, 2\n")
    with pytest.raises(NotABroadTrial, match="neither HDF5 nor a MATLAB v5"):
        load_trial(path)


def test_loader_refuses_an_hdf5_file_without_the_trial_fields_naming_them(tmp_path: Path) -> None:
    path = tmp_path / "other.hdf5"
    with h5py.File(path, "w") as f:
        f["imu_acc"] = np.zeros((10, 3))
        f["imu_gyr"] = np.zeros((10, 3))
    with pytest.raises(NotABroadTrial, match=r"missing field.*opt_quat, movement, sampling_rate"):
        load_trial(path)


def test_loader_refuses_fields_of_the_wrong_shape(tmp_path: Path) -> None:
    path = tmp_path / "bad.hdf5"
    with h5py.File(path, "w") as f:
        f["imu_acc"] = np.zeros((10, 3))
        f["imu_gyr"] = np.zeros((10, 3))
        f["opt_quat"] = np.zeros((9, 4))
        f["movement"] = np.zeros(10, dtype=bool)
        f.attrs["sampling_rate"] = 100.0
    with pytest.raises(NotABroadTrial, match=r"opt_quat has shape \(9, 4\)"):
        load_trial(path)


def test_groups_come_from_the_trial_name_when_trials_json_does_not_list_it() -> None:
    assert trial_groups("99_undisturbed_fast_rotation_with_breaks_C") == [
        "undisturbed", "rotation", "fast", "with_breaks"]
    assert trial_groups("98_disturbed_phone_vibration_C") == ["disturbed", "vibration"]


# ----- metric --------------------------------------------------------------------------------
def test_a_constant_one_degree_tilt_error_gives_one_degree() -> None:
    n = 2000
    t = np.linspace(0.0, 20.0, n)
    roll, pitch, yaw = 0.6 * np.sin(0.7 * t), 0.4 * np.cos(0.3 * t), 2.0 * t
    ref = np.array([quat_from_roll_pitch_yaw(r, p, y) for r, p, y in zip(roll, pitch, yaw,
                                                                            strict=True)])
    # 1 deg more pitch turns the up direction by exactly 1 deg, whatever the roll
    est = gravity_from_roll_pitch(roll, pitch + 1.0 * DEG)
    movement = np.ones(n, dtype=bool)
    assert inclination_rmse_deg(est, gravity_from_quat(ref), movement) == pytest.approx(
        1.0, abs=1e-9)


def test_the_metric_ignores_heading_nan_references_and_samples_outside_movement() -> None:
    q = np.array([quat_from_roll_pitch_yaw(0.2, -0.1, y) for y in (0.0, 1.0, 2.0, 3.0)])
    g_ref = gravity_from_quat(q)
    g_est = gravity_from_roll_pitch(np.full(4, 0.2), np.full(4, -0.1 + 2.0 * DEG))
    g_ref[1] = np.nan  # markers not visible
    g_est[3] = (1.0, 0.0, 0.0)  # way off, but not a movement sample
    movement = np.array([True, True, True, False])
    assert inclination_rmse_deg(g_est, g_ref, movement) == pytest.approx(2.0, abs=1e-9)


def test_reference_and_accelerometer_agree_at_rest_so_the_frames_match() -> None:
    """BROAD's opt_quat and our frame convention: at rest the normalised accelerometer and
    R(q)^T e_z agree to a few tenths of a degree (sensor misalignment), not 180 or 90 deg."""
    trial = load_trial(HDF5_TRIAL)
    rest = ~trial.movement & np.all(np.isfinite(trial.opt_quat), axis=1)
    err = inclination_error(trial.acc[rest], gravity_from_quat(trial.opt_quat[rest]))
    assert np.median(err) < 1.0 * DEG


@pytest.mark.parametrize("key", ["kf", "poskf"])
@pytest.mark.parametrize("path", [HDF5_TRIAL, MAT_TRIAL], ids=["translation", "rotation"])
def test_a_sensor_resting_x_up_without_a_mounting_is_as_accurate_as_z_up(key: str, path: Path
                                                                          ) -> None:
    """A real recording turned so that the sensor rests x-up (pitch -90 deg), no mounting set:
    the Kalman filters' inclination error stays the z-up one's, within 10 % (on the sensor's own
    axes, tilt_axes='body', it would not: the papers' filters are made for a near-level
    sensor)."""
    trial = load_trial(path)
    x_up = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # sensor x = up
    turned = replace(trial, acc=trial.acc @ x_up, gyro=trial.gyro @ x_up)
    up = gravity_from_quat(trial.opt_quat)
    assert np.median(turned.acc[~trial.movement][:, 0]) > 9.0  # x reads +g at rest

    def error(t: BroadTrial, ref: np.ndarray) -> float:
        out = run_fusion_core(key, {}, t)
        return inclination_rmse_deg(gravity_from_roll_pitch(out["roll"], out["pitch"]), ref,
                                    t.movement)

    z_up, x_up_err = error(trial, up), error(turned, up @ x_up)
    assert x_up_err <= 1.1 * z_up, (z_up, x_up_err)


# ----- evaluation and command line ------------------------------------------------------------
def test_presets_name_every_estimator_with_valid_parameters() -> None:
    for preset in PRESETS:
        for key in ESTIMATORS:
            create(key, preset_params(preset, key))  # raises on an unknown or out-of-range value


def test_the_recommended_preset_beats_the_papers_on_a_slice_with_motion(tmp_path: Path) -> None:
    path = write_slice(tmp_path / "slice.hdf5")
    result = evaluate([path], plan_columns(["cf", "mgcf", "kf"], ["paper", "recommended"]))
    means = result.means()
    for key in ("cf", "mgcf", "kf"):
        assert means[key] < means[f"{key}-paper"], means
    assert means["mgcf"] < 1.0, means


def test_the_loader_says_the_gyro_samples_are_interval_means_and_the_run_follows_it() -> None:
    trial = load_trial(HDF5_TRIAL).head(8.0)
    assert trial.gyro_sampling == "mean"
    followed = run_fusion_core("kf", {}, trial)["roll"]
    assert np.array_equal(followed, run_fusion_core("kf", {"gyro_sampling": "mean"}, trial)["roll"])
    assert not np.array_equal(followed,
                              run_fusion_core("kf", {"gyro_sampling": "point"}, trial)["roll"])


def test_the_loader_states_the_sensors_delay_and_the_run_turns_the_outputs_over_it() -> None:
    trial = load_trial(HDF5_TRIAL).head(8.0)
    assert 2e-3 < trial.sensor_delay < 3e-3  # testbenches.broad.gyro.fit_delay: 2.36-2.51 ms
    followed = run_fusion_core("kf", {}, trial)["roll"]
    stated = run_fusion_core("kf", {"sensor_delay": trial.sensor_delay}, trial)["roll"]
    assert np.array_equal(followed, stated)
    papers = run_fusion_core("kf", preset_params("paper", "kf"), trial)["roll"]
    assert np.array_equal(papers, run_fusion_core(
        "kf", {**preset_params("paper", "kf"), "sensor_delay": 0.0}, trial)["roll"])


ALL_TRIALS = sorted(p for p in DATA.glob("*") if p.suffix in (".hdf5", ".mat"))


@pytest.mark.skipif(len(ALL_TRIALS) != 13, reason=f"the 13 shared BROAD trials are not all in "
                    f"{DATA} (found {len(ALL_TRIALS)})")
@pytest.mark.heavy
def test_the_defaults_meet_the_broad_targets_on_the_13_shared_trials() -> None:
    """The interface's accuracy targets with the defaults: the best estimator <= 0.65 deg mean
    inclination RMSE (VQF as published: 0.689), cf, mgcf, kf and ukf <= 0.9, poskf <= 1.5 and
    within 0.05 deg of kf (its attitude is its tilt stage's)."""
    result = evaluate(ALL_TRIALS, plan_columns(list(ESTIMATORS), ["recommended"]))
    means = result.means()
    assert min(means.values()) <= 0.65, means
    for key in ATTITUDE_FILTERS:
        assert means[key] <= 0.9, means
    assert means["poskf"] <= 1.5, means
    assert abs(means["poskf"] - means["kf"]) <= 0.05, means


@pytest.fixture(scope="module")
def shared_cv() -> Any:
    """The cross-validation of the attitude filters' defaults over the 13 shared trials, VQF
    with the output prediction beside them (about 3 minutes)."""
    from testbenches.broad.cv import CV_ESTIMATORS, cross_validate
    from testbenches.peers import AHEAD_PEERS

    if len(ALL_TRIALS) != 13:
        pytest.skip(f"the 13 shared BROAD trials are not all in {DATA} (found {len(ALL_TRIALS)})")
    pytest.importorskip("vqf")
    trials = [load_trial(p) for p in ALL_TRIALS]
    groups = [t.groups for t in evaluate(trials, plan_columns(["kf"], ["recommended"])).trials]
    return cross_validate(trials, groups, CV_ESTIMATORS, {"vqf-ahead": AHEAD_PEERS["vqf-ahead"]})


@pytest.mark.slow
def test_cross_validated_the_defaults_meet_issue_32s_targets(shared_cv: Any) -> None:
    """Issue 32's targets on the 13 shared trials, every scanned parameter chosen again without
    each motion fold (by regret, among the points the contract allows): the best at most
    0.53 deg and at most VQF's with the same output prediction (0.545, nothing to fit), each
    attitude filter at most 0.60, and cross-validated minus in-sample at most 0.02 deg for
    each (docs/results/broad.md gives the figures)."""
    cv = shared_cv.cv_means()
    vqf = float(np.mean(list(shared_cv.peers["vqf-ahead"].values())))
    assert all(v <= 0.60 for v in cv.values()), cv
    assert min(cv.values()) <= min(0.53, vqf), (cv, vqf)
    for key in ("cf", "mgcf", "kf", "ukf"):
        e = shared_cv.estimators[key]
        assert e.cv_mean() - e.in_sample_mean() <= 0.02, (key, e.cv_mean(), e.in_sample_mean())


def test_cli_on_one_trial_slice_prints_the_table_and_writes_the_reports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")
    out = tmp_path / "report"
    status = main(["broad", str(path), "--estimator", "cf,kf", "--preset", "all",
                   "--out", str(out)])
    assert status == 0
    text = capsys.readouterr().out
    assert "10_undisturbed_slow_translation_A" in text and "kf-paper" in text
    report = json.loads((out / "report.json").read_text())
    means = report["mean_inclination_rmse_deg"]
    assert set(means) == {"cf", "cf-paper", "kf", "kf-paper"}
    assert all(math.isfinite(v) and 0.0 < v < 30.0 for v in means.values()), means
    (trial,) = report["trials"]
    assert trial["inclination_rmse_deg"] == means
    assert trial["groups"] == ["undisturbed", "translation", "slow", "no_breaks"]
    assert "undisturbed" in report["groups"]
    assert (out / "report.md").is_file() and (out / "broad_inclination_rmse.png").is_file()


def test_cli_refuses_a_file_that_is_not_a_broad_trial(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "not_a_trial.hdf5"
    with h5py.File(path, "w") as f:
        f["something"] = np.zeros(3)
    assert main(["broad", str(path), "--out", str(tmp_path / "r")]) == 2
    assert "not a BROAD trial" in capsys.readouterr().err


@pytest.mark.heavy
def test_cli_runs_the_peers_on_the_same_trial(tmp_path: Path) -> None:
    pytest.importorskip("vqf")
    pytest.importorskip("ahrs")
    path = write_slice(tmp_path / "slice.hdf5")
    out = tmp_path / "report"
    assert main(["broad", str(path), "--estimator", "mgcf", "--peers", "--no-plots",
                 "--out", str(out)]) == 0
    means = json.loads((out / "report.json").read_text())["mean_inclination_rmse_deg"]
    assert set(means) == {"mgcf", "vqf", "ahrs-madgwick", "ahrs-mahony", "vqf-ahead"}
    assert means["vqf"] < 2.0, means  # VQF on an undisturbed slow trial
    assert means["vqf-ahead"] != means["vqf"], means  # turned ahead over the trial's 2.4 ms


def test_up_ahead_turns_the_up_direction_as_the_estimators_sensor_delay_does() -> None:
    """A roll rate turns the up direction as a roll of rate x delay: the peers' prediction is
    the estimators' (fusion_core.kinematics.roll_pitch_ahead)."""
    from fusion_core.kinematics import roll_pitch_ahead
    from testbenches.broad.metric import gravity_from_roll_pitch
    from testbenches.peers import up_ahead

    roll, pitch, w, delay = 0.4, -0.3, np.array([0.7, -1.1, 2.0]), 0.01
    up = gravity_from_roll_pitch(np.array([roll]), np.array([pitch]))
    expect = gravity_from_roll_pitch(*map(np.atleast_1d, roll_pitch_ahead(roll, pitch, *w, delay)))
    np.testing.assert_allclose(up_ahead(up, w[None, :], delay), expect, atol=1e-12)


@pytest.mark.parametrize("key", ["cf", "kf", "mgcf"])
def test_fmu_gives_the_fusion_core_numbers_with_the_recommended_preset(built_fmus, key: str
                                                                       ) -> None:
    assert built_fmus.returncode == 0, built_fmus.output
    trial = load_trial(HDF5_TRIAL).head(8.0)
    params = preset_params("recommended", key)
    core = run_fusion_core(key, params, trial)
    fmu = run_fmu(key, params, trial, built_fmus.directory)
    np.testing.assert_array_equal(fmu["roll"], core["roll"])
    np.testing.assert_array_equal(fmu["pitch"], core["pitch"])
    assert Column(key, "fmu", key).kind == "fmu"


def test_cli_gyro_fit_writes_each_trials_gyro_errors_and_the_oracle_rmse(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 90.0, MAT_TRIAL)
    out = tmp_path / "report"
    assert main(["broad", str(path), "--estimator", "kf", "--gyro-fit", "--no-plot",  # old name
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "gyro against the reference" in text and "kf " in text
    (fit,) = json.loads((out / "gyro_fit.json").read_text()).values()
    assert len(fit["scale_error_pct"]) == 3 and len(fit["cross_axis_pct"]) == 6
    assert all(abs(v) < 2.0 for v in fit["scale_error_pct"])  # a calibrated gyro: percents
    assert fit["windows"] >= 100
    assert 0.0 < fit["rmse_deg"]["kf"] < 5.0 and 0.0 < fit["rmse_scale_removed_deg"]["kf"] < 5.0


def test_the_motion_folds_of_the_cross_validation() -> None:
    from testbenches.broad.cv import fold_of

    assert fold_of(["undisturbed", "rotation", "slow"]) == "slow_rotation"
    assert fold_of(["undisturbed", "rotation", "fast", "with_breaks"]) == "fast_rotation"
    assert fold_of(["undisturbed", "translation", "fast"]) == "translation"
    assert fold_of(["disturbed", "tapping"]) == "disturbed_combined"
    assert fold_of(["undisturbed", "combined", "slow"]) == "disturbed_combined"


def test_cv_on_two_folds_chooses_without_the_held_out_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`broad --cv` on a rotation and a translation slice: each held-out trial's error is the
    grid point chosen on the other one's, and report.json gains the cross-validated means."""
    a = write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")
    b = write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 45.0, MAT_TRIAL)
    out = tmp_path / "report"
    assert main(["broad", str(a), str(b), "--estimator", "kf", "--cv", "--no-plots",
                 "--out", str(out)]) == 0
    assert "leave one motion fold out" in capsys.readouterr().out
    report = json.loads((out / "report.json").read_text())
    cv = json.loads((out / "cv.json").read_text())["estimators"]["kf"]
    assert report["cv_mean_inclination_rmse_deg"]["kf"] == pytest.approx(cv["cv_mean_deg"])
    assert set(cv["chosen_per_fold"]) == {"slow_rotation", "translation"}
    assert cv["in_sample_mean_deg"] == pytest.approx(report["mean_inclination_rmse_deg"]["kf"],
                                                     abs=1e-6)  # report.json's 6 decimals


def test_cv_grid_cross_validates_the_parameters_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`broad --cv-grid NAME=V1,V2` (implying --cv) chooses those parameters again per fold and
    nothing else: cv.json holds that grid, each fold's choice is one of its values, and the
    held-out error is the chosen point's."""
    from testbenches.broad.cv import _rmse
    from testbenches.broad.data import load_trial
    from testbenches.broad.run import run_fusion_core

    a = write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")
    b = write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 45.0, MAT_TRIAL)
    out = tmp_path / "report"
    assert main(["broad", str(a), str(b), "--estimator", "kf", "--no-plots", "--out", str(out),
                 "--cv-grid", "scale_time=0.25,0.5"]) == 0
    assert "(scale_time where the estimator has it; among the points that keep" in \
        capsys.readouterr().out
    doc = json.loads((out / "cv.json").read_text())
    assert doc["grid"] == {"scale_time": [0.25, 0.5]}
    cv = doc["estimators"]["kf"]
    assert cv["grid_points"] == [{"scale_time": 0.25}, {"scale_time": 0.5}]
    assert len(cv["grid_errors_deg"]) == 2 and len(doc["trials"]) == 2
    for point, row in zip(cv["grid_points"], cv["grid_errors_deg"], strict=True):
        for trial, err in zip(doc["trials"], row, strict=True):
            if cv["chosen_per_fold"][doc["folds"][trial]] == point:
                assert err == pytest.approx(cv["cv_held_out_deg"][trial])
    assert cv["defaults"] == {"scale_time": 0.5}
    for fold, point in cv["chosen_per_fold"].items():
        assert set(point) == {"scale_time"} and point["scale_time"] in (0.25, 0.5)
        (trial,) = [t for t, f in doc["folds"].items() if f == fold]
        t = load_trial(a if trial.startswith("10") else b)
        r = run_fusion_core("kf", point, t)
        assert cv["cv_held_out_deg"][trial] == pytest.approx(_rmse(t, r["roll"], r["pitch"]))


@pytest.mark.parametrize(("entries", "says"), [
    (["scale_time"], "expected NAME=V1,V2,... with numbers"),
    (["scale_time=fast"], "expected NAME=V1,V2,... with numbers"),
    (["no_such=1"], "no_such is no parameter of kf; allowed: "),
    (["scale_time=-1"], "kf: parameter 'scale_time'=-1.0 is out of range"),
    (["scale_time="], "scale_time needs at least one value"),
    (["scale_time=0.5", "scale_time=1"], "scale_time is given twice"),
])
def test_cv_grid_refuses_a_bad_entry_before_any_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], entries: list[str], says: str
) -> None:
    a = write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")
    out = tmp_path / "report"
    grid = [arg for entry in entries for arg in ("--cv-grid", entry)]
    assert main(["broad", str(a), "--estimator", "kf", "--no-plots", "--out", str(out),
                 *grid]) == 2
    assert says in capsys.readouterr().err
    assert not out.exists()


def test_the_contract_constraint_names_the_first_check_a_point_fails() -> None:
    """The defaults keep the contract's per-run accuracy bounds (make run); the kf with a 2 s
    measured vector still fills when high_dynamics' first move starts and leaves its pitch
    bound, and the reason says so."""
    from testbenches.broad.feasible import contract_failure

    assert contract_failure("kf", {}) is None
    why = contract_failure("kf", {"acc_lowpass": 2.0})
    assert why is not None and why.startswith("high_dynamics: FAIL accuracy pitch RMSE")


def test_the_constraint_keeps_the_share_of_the_papers_row_the_defaults_owe() -> None:
    """The mgcf's defaults meet half the paper's moderate_dynamics row on the realistic sensor
    (tests/test_paper_rows.py); without its bias learning in motion, a 1.5 s measured vector
    leaves it in pitch, which the contract's own bound (the whole row) allows, and the
    constraint says so."""
    from testbenches.broad.feasible import contract_failure

    assert contract_failure("mgcf", {}) is None
    why = contract_failure("mgcf", {"acc_lowpass": 1.5, "motion_bias_gain": 0.0})
    assert why is not None and why.startswith("moderate_dynamics: FAIL defaults' pitch RMSE")
    assert "0.5 of the paper's row" in why


def test_a_fold_chooses_the_best_point_the_constraint_allows(tmp_path: Path) -> None:
    """With the best point of every fold refused, each fold takes the next best by its own
    training mean, the refusal is recorded with its reason, and without a constraint the
    refused point is chosen again."""
    from testbenches.broad.cv import cross_validate
    from testbenches.broad.data import load_trial

    trials = [load_trial(write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")),
              load_trial(write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 45.0,
                                     MAT_TRIAL))]
    groups = [["undisturbed", "translation", "slow"], ["undisturbed", "rotation", "slow"]]
    grid = {"scale_time": [0.1, 0.5, 2.0]}
    free = cross_validate(trials, groups, ["kf"], grid=grid, constraint=None)
    e = free.estimators["kf"]
    refused = {fold: point["scale_time"] for fold, point in e.chosen.items()}

    def refuse(key: str, point: dict[str, float]) -> str | None:
        return "refused here" if point["scale_time"] in refused.values() else None

    held = cross_validate(trials, groups, ["kf"], grid=grid, constraint=refuse).estimators["kf"]
    assert not free.estimators["kf"].refused and held.refused
    assert set(held.refused.values()) == {"refused here"}
    for fold, point in held.chosen.items():
        assert point["scale_time"] not in refused.values()
        train = [j for j, t in enumerate(trials) if free.folds[t.name] != fold]
        allowed = [i for i, p in enumerate(e.grid) if p["scale_time"] not in refused.values()]
        best = min(allowed, key=lambda i: e.errors[i, train].mean())
        assert point == e.grid[best]


def test_the_regret_choice_takes_the_point_that_holds_on_every_training_fold() -> None:
    """Point 3 has the lowest mean over the training trials, carried by the fold with most
    trials, and is twice the best on another fold; point 1 is at most 22 % above the best on
    every fold: regret takes point 1, mean point 3. With 1 and 3 refused, the regret counts
    against the allowed points' best: point 2 is at most 25 % above it on each fold, point 0 33 %
    on one, so regret takes 2 where mean takes 0."""
    from testbenches.broad.cv import EstimatorCv, _Allowed, _choose

    folds = [[0, 1, 2, 3], [4], [5]]  # the columns of three training folds
    errors = np.array([[1.0, 1.0, 1.0, 1.0, 1.4, 0.5],
                       [1.1, 1.1, 1.1, 1.1, 1.0, 0.5],
                       [1.25, 1.25, 1.25, 1.25, 1.05, 0.55],
                       [0.9, 0.9, 0.9, 0.9, 1.0, 1.0]])
    points = [{"p": float(i)} for i in range(len(errors))]
    cv = EstimatorCv("kf", {"p": 0.0}, grid=points, errors=errors)

    def free(key: str, point: dict[str, float]) -> str | None:
        return None

    def no_1_or_3(key: str, point: dict[str, float]) -> str | None:
        return "refused here" if point["p"] in (1.0, 3.0) else None

    assert _choose(cv, folds, _Allowed("kf", points, free), "mean") == 3
    assert _choose(cv, folds, _Allowed("kf", points, free), "regret") == 1
    assert _choose(cv, folds, _Allowed("kf", points, no_1_or_3), "mean") == 0
    assert _choose(cv, folds, _Allowed("kf", points, no_1_or_3), "regret") == 2
    assert set(cv.refused) == {"p=1", "p=3"}
    exact = EstimatorCv("kf", {"p": 0.0}, grid=points[:2], errors=np.array(
        [[0.0, 1.0], [0.1, 0.5]]))  # a fold where point 0 is exact: no 0/0, point 0 wins
    assert _choose(exact, [[0], [1]], _Allowed("kf", points[:2], free), "regret") == 0


def test_broad_offers_the_choices_cross_validate_makes() -> None:
    """--cv-choice's values are cv.CHOICES."""
    from testbenches.broad.cli import add_broad_parser
    from testbenches.broad.cv import CHOICES

    parser = add_broad_parser(argparse.ArgumentParser().add_subparsers())
    (action,) = [a for a in parser._actions if a.dest == "cv_choice"]
    assert tuple(action.choices) == CHOICES


def test_cv_unconstrained_and_the_choice_are_said_in_cv_json(tmp_path: Path) -> None:
    a = write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")
    b = write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 45.0, MAT_TRIAL)
    out = tmp_path / "report"
    assert main(["broad", str(a), str(b), "--estimator", "kf", "--no-plots", "--out", str(out),
                 "--cv-unconstrained", "--cv-choice", "mean", "--cv-grid",
                 "scale_time=0.25,0.5"]) == 0
    doc = json.loads((out / "cv.json").read_text())
    assert doc["constrained_by_contract"] is False and doc["choice"] == "mean"
    assert "by the lowest training mean" in doc["method"]
    assert doc["estimators"]["kf"]["refused_by_contract"] == {}


def test_cv_draws_in_sample_against_cross_validated_per_fold(tmp_path: Path) -> None:
    a = write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5")
    b = write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 45.0, MAT_TRIAL)
    out = tmp_path / "report"
    assert main(["broad", str(a), str(b), "--estimator", "kf", "--out", str(out),
                 "--cv-grid", "scale_time=0.25,0.5"]) == 0
    assert (out / "cv.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["broad", str(a), str(b), "--estimator", "kf", "--out", str(tmp_path / "np"),
                 "--no-plots", "--cv-grid", "scale_time=0.25,0.5"]) == 0
    assert not (tmp_path / "np" / "cv.png").exists()


def test_the_nested_cv_chooses_each_folds_procedure_and_point_without_it() -> None:
    """Nested leave-one-fold-out on a made-up error matrix: what a fold's own trials say changes
    its score, never its choice."""
    import numpy as np

    from testbenches.broad.cv import EstimatorCv, _Allowed, nested_cv

    grid = [{"acc_lowpass_stretch": s, "acc_lowpass": a} for s in (1.0, 2.0) for a in (1.0, 2.0)]
    trials = [f"t{i}" for i in range(8)]
    columns = {f: [2 * k, 2 * k + 1] for k, f in enumerate(("a", "b", "c", "d"))}
    rng = np.random.default_rng(3)
    errors = 0.5 + rng.uniform(0.0, 0.2, (len(grid), len(trials)))

    def run(errors: np.ndarray) -> EstimatorCv:
        cv = EstimatorCv("kf", {"acc_lowpass_stretch": 2.0, "acc_lowpass": 1.0}, grid=grid,
                         errors=errors.copy())
        cv.in_sample = {t: 0.0 for t in trials}
        nested_cv(cv, columns, _Allowed("kf", grid, None))
        return cv

    base = run(errors)
    assert set(base.nested) == set(trials) and set(base.nested_procedure) == set(columns)
    changed = errors.copy()
    changed[:, columns["a"]] = [[9.0, 9.0], [0.1, 0.1], [5.0, 5.0], [7.0, 7.0]]
    other = run(changed)
    assert other.nested_procedure["a"] == base.nested_procedure["a"]
    point = [i for i in range(len(grid)) if base.nested["t0"] == errors[i, 0]]
    assert point and other.nested["t0"] == changed[point[0], 0]  # the same point, rescored


def test_cv_on_three_folds_asks_the_battery_about_the_longer_vector(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`broad --cv` with three folds runs the battery with and without the longer vector
    (stubbed here: its ratio set, as battery_worth sets it) with the parts and scheduler given,
    and no fold then chooses a point without the vector; with 0 parts it is not asked."""
    from testbenches import mechanisms

    asked: list[tuple[int, str | None]] = []

    def battery_worth(worth: dict, parts: int, scheduler: str | None, workers: int,
                      progress: Any = None) -> None:
        asked.append((parts, scheduler))
        for w in worth.values():
            w.battery_ratio = 1.064

    monkeypatch.setattr(mechanisms, "battery_worth", battery_worth)
    files = [write_slice(tmp_path / "10_undisturbed_slow_translation_A.hdf5"),
             write_slice(tmp_path / "01_undisturbed_slow_rotation_A.hdf5", 45.0, MAT_TRIAL),
             write_slice(tmp_path / "24_disturbed_tapping_A.hdf5")]
    grid = ["--cv-grid", "acc_lowpass_stretch=1,2"]
    out = tmp_path / "kept"
    assert main(["broad", *map(str, files), "--estimator", "kf", "--no-plots", "--out", str(out),
                 *grid, "--cv-battery-parts", "3", "--scheduler", "here:1"]) == 0
    assert asked == [(3, "here:1")]
    assert "where the battery keeps it" in capsys.readouterr().out
    cv = json.loads((out / "cv.json").read_text())["estimators"]["kf"]
    assert cv["longer_vector_kept_by_battery"] == "its mean error 1.064 times as large without it"
    assert all(p["acc_lowpass_stretch"] == 2.0 for p in cv["chosen_per_fold"].values())
    assert main(["broad", *map(str, files), "--estimator", "kf", "--no-plots", "--out",
                 str(tmp_path / "alone"), *grid, "--cv-battery-parts", "0"]) == 0
    assert asked == [(3, "here:1")]
    alone = json.loads((tmp_path / "alone" / "cv.json").read_text())["estimators"]["kf"]
    assert alone["longer_vector_kept_by_battery"] is None  # BROAD alone: these slices drop it
    assert any(p["acc_lowpass_stretch"] == 1.0 for p in alone["chosen_per_fold"].values())


def test_the_nested_cv_leaves_out_no_mechanism_the_battery_keeps() -> None:
    """Where the training folds score best without the longer vector, the nested procedure
    leaves it out, unless the battery keeps it (EstimatorCv.battery_keeps): then only the
    whole grid is offered, and the outer fold gets the point chosen from it."""
    import numpy as np

    from testbenches.broad.cv import EstimatorCv, _Allowed, nested_cv

    grid = [{"acc_lowpass_stretch": s, "acc_lowpass": a} for s in (1.0, 2.0) for a in (1.0, 2.0)]
    trials = [f"t{i}" for i in range(8)]
    columns = {f: [2 * k, 2 * k + 1] for k, f in enumerate(("a", "b", "c", "d"))}
    errors = np.array([[0.40] * 6 + [0.90] * 2,  # without the vector: best but on fold d
                       [0.45] * 6 + [0.95] * 2,
                       [0.50] * 6 + [0.50] * 2,  # with it: level everywhere
                       [0.55] * 6 + [0.60] * 2])

    def run(kept: str | None) -> EstimatorCv:
        cv = EstimatorCv("mgcf", {"acc_lowpass_stretch": 2.0, "acc_lowpass": 1.0}, grid=grid,
                         errors=errors.copy(), battery_keeps=kept)
        cv.in_sample = {t: 0.0 for t in trials}
        nested_cv(cv, columns, _Allowed("mgcf", grid, None, kept))
        return cv

    alone = run(None)
    assert alone.nested["t6"] == 0.90  # fold d: left out on the other folds' say
    kept = run("its mean error 1.064 times as large without it")
    assert all(p.endswith(", grid") for p in kept.nested_procedure.values())
    assert kept.nested["t6"] == 0.50 and kept.nested["t0"] == 0.50
    assert _Allowed("mgcf", grid, None, "its mean error 1.064")(0).startswith(
        "leaves out the longer vector, which the battery keeps (its mean error 1.064")
