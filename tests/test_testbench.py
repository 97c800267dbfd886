"""The testbench (issue 4): master, plant and sensor models, contract checks, command line.

The FMUs come from the session's build (conftest.built_fmus). Runs are short (5-15 s of motion)
to keep the suite fast; the full campaign is `make run`.
"""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from hypothesis import given, settings
from hypothesis import strategies as st

from fusion_core import DEG, ESTIMATORS, G
from fusion_core.building_blocks import CONSTANT_NOISE
from fusion_core.kinematics import euler_rates
from fusion_core.scenarios import SCENARIOS
from fusion_core.sensor import SENSOR_PRESETS, ImuSensorModel
from testbenches import contract, master, run_testbench
from testbenches.master import CHAIN_DELAY, MASTERS

REPO = Path(__file__).resolve().parent.parent
KEYS = tuple(ESTIMATORS)


@pytest.fixture(scope="module")
def fmu_dir(built_fmus) -> Path:
    assert built_fmus.returncode == 0, built_fmus.output
    return built_fmus.directory


# ----- master ------------------------------------------------------------------------------------
@pytest.mark.parametrize("key", KEYS)
def test_master_equals_a_direct_fusion_core_run_on_the_same_samples(
    key: str, fmu_dir: Path
) -> None:
    """The estimator FMU inside the three-FMU loop gives exactly fusion_core's estimates for the
    samples the sensor FMU produced (bit-identical: no extra delay, no lost sample)."""
    r = run_testbench(key, "moderate_dynamics", duration=5.0, jitter=0.2, fmu_dir=fmu_dir)
    s = r.sample
    acc = np.column_stack([s["acc_x"], s["acc_y"], s["acc_z"]])
    gyro = np.column_stack([s["gyro_x"], s["gyro_y"], s["gyro_z"]])
    direct = ESTIMATORS[key]().run(acc, gyro, s["dt"])
    assert np.array_equal(direct["roll"], r.estimate["roll"])
    assert np.array_equal(direct["pitch"], r.estimate["pitch"])
    assert np.array_equal(direct["bias"][:, 0], r.estimate["bias_x"])
    if key == "poskf":
        assert np.array_equal(direct["pos"][:, 0], r.estimate["pos_x"])


def test_plant_outputs_are_the_truth_at_the_end_of_each_step(fmu_dir: Path) -> None:
    """Step k of the master records the truth at t_k = (k + 1) h (Gauss-Seidel ordering)."""
    r = run_testbench("cf", "roll_sweep", duration=2.0, fmu_dir=fmu_dir, evaluate=False)
    truth = SCENARIOS["roll_sweep"].trajectory().truth(r.t)
    assert r.t[0] == pytest.approx(0.01)
    assert np.max(np.abs(truth["roll"] - r.truth["roll"])) < 1e-12


def test_every_plant_output_is_the_truth_and_the_sensor_samples_that_step(fmu_dir: Path) -> None:
    """At 1 kHz with jittered steps, on rotation plus linear acceleration (high_dynamics: its
    first move starts at 2 s), all 15 plant outputs are Trajectory.truth at t_k; a noise-free
    sensor without quantisation passes that step's omega and f on unchanged, with dt = h_k to the
    picosecond (the master wires each step's plant outputs to the sensor and the sample to the
    estimator)."""
    r = run_testbench("kf", "high_dynamics", duration=3.0, rate=1000.0, jitter=0.2, seed=5,
                      fmu_dir=fmu_dir, sensor_params=contract.NOISE_FREE, evaluate=False)
    truth = SCENARIOS["high_dynamics"].trajectory().truth(r.t)
    for name in ("roll", "pitch", "yaw"):
        np.testing.assert_allclose(r.truth[name], truth[name], rtol=0.0, atol=1e-12)
    for key in ("omega", "f", "pos", "vel"):
        for i, a in enumerate("xyz"):
            np.testing.assert_allclose(r.truth[f"{key}_{a}"], truth[key][:, i], rtol=0.0,
                                       atol=1e-12)
    for a in "xyz":
        assert np.array_equal(r.sample[f"gyro_{a}"], r.truth[f"omega_{a}"])
        assert np.array_equal(r.sample[f"acc_{a}"], r.truth[f"f_{a}"])
    steps = master.communication_steps(3.0, 1000.0, 0.2, 5)
    assert np.array_equal(r.sample["dt"], np.floor(steps * 1e12 + 0.5) / 1e12)
    assert np.max(np.abs(r.sample["dt"] - steps)) <= 5e-13
    assert np.ptp(r.truth["vel_x"]) > 1.0  # the move really happened


def test_a_failed_fmi_call_stops_the_master(fmu_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every FMI status is checked: a communication step h = 0 makes the sensor's doStep fail
    (fmi2Discard), and the run raises instead of recording the step."""
    monkeypatch.setattr(master, "communication_steps", lambda *args: np.array([0.01, 0.0, 0.01]))
    with pytest.raises(FMICallException, match="fmi2DoStep"):
        run_testbench("cf", "roll_sweep", duration=0.03, fmu_dir=fmu_dir, evaluate=False)


# ----- contract checks T1-T4 on short scenarios ---------------------------------------------------
def test_t1_alignment_passes_for_every_attitude_estimator(fmu_dir: Path) -> None:
    """Noise-free roll sweep (peak rate 1.58 rad/s) at 100 Hz: error < 0.05 deg after 5 s."""
    runs = [run_testbench(k, "roll_sweep", duration=8.0, fmu_dir=fmu_dir,
                          sensor_params=contract.NOISE_FREE) for k in KEYS]
    check = contract.check_t1(runs)
    print("\n" + check.line())
    assert check.passed


def test_t2_variable_step_passes(fmu_dir: Path) -> None:
    """+-20 % jittered steps: RMSE within 10 % of the fixed-step run (cf, 15 s, noise-free)."""
    kw = {"duration": 15.0, "fmu_dir": fmu_dir, "sensor_params": contract.NOISE_FREE}
    fixed = run_testbench("mgcf", contract.T2_SCENARIO, **kw)
    jittered = run_testbench("mgcf", contract.T2_SCENARIO, jitter=contract.T2_JITTER, **kw)
    check = contract.check_t2(fixed, jittered)
    print("\n" + check.line())
    assert np.ptp(np.diff(jittered.t)) > 0.3 / 100.0  # the steps really varied
    assert check.passed


def test_t3_budget_is_measured_per_step_and_reported(fmu_dir: Path) -> None:
    """T3 is a measurement (no wall-clock assertion here): p50 <= p99, one time per step."""
    r = run_testbench("kf", "static_level", duration=2.0, fmu_dir=fmu_dir)
    check = next(c for c in r.checks if c.name.startswith("T3"))
    assert len(r.step_us) == len(r.t)
    assert 0.0 < r.metrics["step_p50_us"] <= r.metrics["step_p99_us"] == check.measured
    assert check.allowed == pytest.approx(1000.0)


def test_t4_same_seed_gives_a_bit_identical_trace(fmu_dir: Path) -> None:
    first = run_testbench("ukf", "roll_pitch", duration=3.0, seed=4, fmu_dir=fmu_dir)
    again = run_testbench("ukf", "roll_pitch", duration=3.0, seed=4, fmu_dir=fmu_dir)
    assert contract.check_t4(first, again).passed


# ----- every check can fail ----------------------------------------------------------------------
def test_a_one_sample_lag_fails_t1_by_about_omega_h(fmu_dir: Path) -> None:
    """The estimate shifted by one sample (a hidden delay) fails T1 with ~|omega| h of error."""
    r = run_testbench("cf", "roll_sweep", duration=8.0, fmu_dir=fmu_dir,
                      sensor_params=contract.NOISE_FREE)
    delayed = {k: np.r_[v[:1], v[:-1]] for k, v in r.estimate.items()}
    lagged = dataclasses.replace(r, estimate=delayed)
    contract.evaluate(lagged)
    check = contract.check_t1([lagged])
    peak_rate = np.max(np.abs(r.truth["omega_x"]))
    print("\n" + check.line())
    assert not check.passed
    assert check.measured == pytest.approx(peak_rate * 0.01 / DEG, rel=0.1)


def test_the_papers_rectangle_rule_fails_t1_and_accuracy(fmu_dir: Path) -> None:
    """gyro_sampling="mean" (the papers' rule) lags by half a step: 0.5 deg on the sweep (with
    constant noise: the adaptive noise's fast correction in pure rotation hides most of it)."""
    params = {"gyro_sampling": "mean", **CONSTANT_NOISE}
    r = run_testbench("cf", "roll_sweep", duration=8.0, fmu_dir=fmu_dir, params=params)
    t1 = contract.check_t1([run_testbench("cf", "roll_sweep", duration=8.0, fmu_dir=fmu_dir,
                                          params=params, sensor_params=contract.NOISE_FREE)])
    assert not t1.passed
    assert not next(c for c in r.checks if c.name == "accuracy roll RMSE").passed


def test_a_mistuned_estimator_fails_accuracy(fmu_dir: Path) -> None:
    """tau = 1000 s: the CF integrates a 1 deg/s gyro bias almost freely on the static tilt."""
    r = run_testbench("cf", "static_tilted", duration=6.0, fmu_dir=fmu_dir,
                      params={"tau": 1000.0}, sensor_params={"gyro_bias_x": 1.0 * DEG})
    failed = [c.name for c in r.checks if not c.passed]
    print(f"\nRMSE roll {r.metrics['rmse_roll_deg']:.2f} deg: failed {failed}")
    assert "accuracy roll RMSE" in failed


def test_t2_fails_when_the_jittered_rmse_differs(fmu_dir: Path) -> None:
    fixed = run_testbench("cf", "roll_pitch", duration=3.0, fmu_dir=fmu_dir)
    rmse = 1.2 * fixed.metrics["rmse_roll_deg"]
    worse = dataclasses.replace(fixed, metrics={**fixed.metrics, "rmse_roll_deg": rmse})
    assert not contract.check_t2(fixed, worse).passed


def test_t4_fails_when_the_traces_differ(fmu_dir: Path) -> None:
    a = run_testbench("cf", "roll_pitch", duration=2.0, seed=1, fmu_dir=fmu_dir)
    b = run_testbench("cf", "roll_pitch", duration=2.0, seed=2, fmu_dir=fmu_dir)
    assert not contract.check_t4(a, b).passed


def test_position_check_fails_without_the_zero_velocity_update(paper_fmus) -> None:
    """The paper's filter (no zero-velocity update, the tilt from every accelerometer sample) on
    the 2 m move (3 seeds): the final x error exceeds Safitri's 0.0385 m."""
    runs = [run_testbench("poskf", "translation_2m", seed=s, fmu_dir=paper_fmus.directory,
                          params={"filter": "paper"}) for s in range(3)]
    checks = contract.check_position(runs)
    print("\n" + "\n".join(c.line() for c in checks))
    assert not checks[0].passed


# ----- plant and sensor models -------------------------------------------------------------------
@pytest.mark.parametrize("name", list(SCENARIOS))
def test_plant_truth_is_consistent_with_finite_differences(name: str) -> None:
    """Body rates reproduce the finite-difference Euler rates through the Euler kinematics, and
    the specific force equals R^T (a + g e_z) with a from finite differences of the position."""
    traj = SCENARIOS[name].trajectory()
    h = 1e-5  # the vibration tones reach 184 Hz
    t = np.linspace(1.0, 3.0, 41)
    d = traj.truth(t)
    up, down = traj.truth(t + h), traj.truth(t - h)
    droll = (up["roll"] - down["roll"]) / (2 * h)
    dpitch = (up["pitch"] - down["pitch"]) / (2 * h)
    rates = np.array([euler_rates(p, q, *w) for p, q, w in zip(d["roll"], d["pitch"], d["omega"],
                                                                strict=True)])
    assert np.max(np.abs(rates[:, 0] - droll)) < 1e-5
    assert np.max(np.abs(rates[:, 1] - dpitch)) < 1e-5
    acc = (up["pos"] - 2 * d["pos"] + down["pos"]) / h**2
    for i in range(len(t)):
        cr, sr = math.cos(d["roll"][i]), math.sin(d["roll"][i])
        cp, sp = math.cos(d["pitch"][i]), math.sin(d["pitch"][i])
        cy, sy = math.cos(d["yaw"][i]), math.sin(d["yaw"][i])
        rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
        ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
        rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
        f = (rz @ ry @ rx).T @ (acc[i] + [0.0, 0.0, G])
        assert np.max(np.abs(f - d["f"][i])) < 2e-3 * max(1.0, np.abs(acc[i]).max())


@pytest.mark.heavy  # statistics over long recordings
def test_sensor_noise_matches_the_configured_densities_within_5_percent() -> None:
    """40 000 samples at 100 Hz, no quantisation: sample std * sqrt(h) / density in [0.95, 1.05]
    for every axis, the density being sqrt of the configured PSD; the bias random walk's
    increments likewise."""
    m = ImuSensorModel(**{**SENSOR_PRESETS["ideal"], "bits": 0}, gyro_bias_psd=1e-3**2,
                       acc_bias_psd=1e-2**2, seed=3)
    h = 0.01
    rows, gb, ab = [], [], []
    for _ in range(40_000):
        acc, gyro, _ = m.sample((0.0, 0.0, 0.0), (0.0, 0.0, G), h)
        rows.append((*gyro, *acc))
        gb.append(list(m.gyro_bias))
        ab.append(list(m.acc_bias))
    x = np.asarray(rows)
    white = np.diff(x, axis=0).std(axis=0) / math.sqrt(2) * math.sqrt(h)
    gyro_ratio = white[:3] / math.sqrt(m.params["gyro_psd"])
    acc_ratio = white[3:] / math.sqrt(m.params["acc_psd"])
    walk_g = np.diff(np.asarray(gb), axis=0).std(axis=0) / math.sqrt(h) / 1e-3
    walk_a = np.diff(np.asarray(ab), axis=0).std(axis=0) / math.sqrt(h) / 1e-2
    print(f"\ngyro {gyro_ratio}, acc {acc_ratio}, walks {walk_g} {walk_a}")
    for ratio in (walk_g, walk_a):
        assert np.all(np.abs(ratio - 1.0) < 0.05)
    # The white noise rides on the slowly walking bias: difference it out (std of x_k - x_{k-1}
    # is sqrt(2) sigma plus a walk increment 100x smaller than sigma here).
    for ratio in (gyro_ratio, acc_ratio):
        assert np.all(np.abs(ratio - 1.0) < 0.05)


def test_sensor_saturates_and_quantises_like_a_16_bit_mpu6050() -> None:
    m = ImuSensorModel(**SENSOR_PRESETS["ideal"], gyro_psd=0.0, acc_psd=0.0)
    acc, gyro, _ = m.sample((50.0, 0.001, 0.0), (0.0, 0.0, 20 * G), 0.01)
    lsb = 2 * 2000 * DEG / 2**16
    assert gyro[0] == pytest.approx(round(2000 * DEG / lsb) * lsb)
    assert gyro[1] == pytest.approx(round(0.001 / lsb) * lsb)
    assert acc[2] == pytest.approx(16 * G)


# ----- command line ------------------------------------------------------------------------------
def _cli(*args: str, fmu_dir: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "testbenches", "run", "--no-contract", "--no-plots",
         "--no-timing-check",
         "--fmu-dir", str(fmu_dir), "--out", str(out), *args],
        cwd=REPO, capture_output=True, text=True, timeout=300,
    )


def test_cli_exits_0_when_every_check_passes(fmu_dir: Path, tmp_path: Path) -> None:
    # kf and ukf: 0.055 deg on this 3 s run, well inside the 0.1 deg bound (the complementary
    # filters' slow correction keeps the first sample's noise for longer: 0.10-0.12 deg)
    proc = _cli("--estimator", "kf,ukf", "--scenario", "static_level", "--duration", "3",
                "--sensor", "ideal", fmu_dir=fmu_dir, out=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "PASS" in proc.stdout
    import json

    report = json.loads((tmp_path / "report.json").read_text())
    assert {r["estimator"] for r in report["runs"]} == {"kf", "ukf"}
    assert "rmse_roll_deg" in report["runs"][0]["metrics"]
    assert (tmp_path / "report.md").is_file()


def test_cli_runs_the_paper_preset_through_the_papers_fmus(fmu_dir: Path, paper_fmus,
                                                          tmp_path: Path) -> None:
    """The paper preset through FMUs built with --preset paper: no parameter may be refused; on
    the recommended FMUs the testbench refuses with the command that builds the right ones."""
    args = ("--estimator", "kf,poskf", "--scenario", "static_level", "--duration", "1",
            "--preset", "paper")
    proc = _cli(*args, fmu_dir=paper_fmus.directory, out=tmp_path)
    assert proc.returncode in (0, 1), proc.stdout + proc.stderr  # 1: a check FAILs
    assert "error" not in proc.stderr.lower(), proc.stderr
    assert "refused" not in proc.stdout + proc.stderr
    wrong = _cli(*args, fmu_dir=fmu_dir, out=tmp_path)
    assert wrong.returncode == 2
    assert "python build_fmu.py --preset paper" in wrong.stderr


def test_cli_exits_1_on_a_failed_check(fmu_dir: Path, tmp_path: Path) -> None:
    proc = _cli("--estimator", "cf", "--scenario", "roll_sweep", "--duration", "5",
                "--param", "gyro_sampling=mean",
                *[a for k, v in CONSTANT_NOISE.items() for a in ("--param", f"{k}={v:g}")],
                fmu_dir=fmu_dir, out=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "FAIL: accuracy roll RMSE" in proc.stdout


def test_cli_exits_2_with_a_message_for_an_unknown_parameter(fmu_dir: Path, tmp_path: Path) -> None:
    proc = _cli("--estimator", "cf", "--scenario", "static_level", "--duration", "1",
                "--param", "nope=1", fmu_dir=fmu_dir, out=tmp_path)
    assert proc.returncode == 2
    assert "--param, cf: unknown parameter(s) nope for ComplementaryFilter: allowed tau" \
        in proc.stderr
    assert "0/1" not in proc.stderr  # refused before the first run, not during it
    proc = _cli("--estimator", "cf", "--scenario", "static_level", "--duration", "1",
                "--param", "tau=abc", fmu_dir=fmu_dir, out=tmp_path)
    assert proc.returncode == 2
    assert "--param, cf: parameter 'tau'='abc' is not a number" in proc.stderr


def test_reports_hold_a_plot_per_run_and_the_checks(fmu_dir: Path, tmp_path: Path) -> None:
    import json

    from testbenches.contract_runs import ContractResult
    from testbenches.report import write_reports

    r = run_testbench("kf", "roll_pitch", duration=2.0, fmu_dir=fmu_dir)
    write_reports(ContractResult(runs=[r]), tmp_path, plots=True)
    report = json.loads((tmp_path / "report.json").read_text())
    png = tmp_path / report["runs"][0]["plot"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    names = {c["name"] for c in report["runs"][0]["checks"]}
    assert names >= {"accuracy roll RMSE", "T3 compute budget p99"}
    assert "![kf roll_pitch]" in (tmp_path / "report.md").read_text()


def test_exported_ssp_runs_in_fmpy_and_matches_the_master_two_steps_later(
    fmu_dir: Path, tmp_path: Path
) -> None:
    """fmpy's SSP master is Jacobi: the sensor sees the plant and the estimator the sensor one
    step late, and the connectors start at 0: two all-zero samples, the first rejected (dt = 0),
    the second skipped (no gravity to start from). With a noise-free sensor the SSP's estimate in
    row k is bit-identical to the master's estimate of step k - 2."""
    from testbenches.ssp import export_ssp, simulate

    path = export_ssp("mgcf", "roll_pitch", tmp_path / "tb.ssp",
                      sensor_params=contract.NOISE_FREE, fmu_dir=fmu_dir)
    rows = simulate(path, stop_time=2.0, step_size=0.01)
    master = run_testbench("mgcf", "roll_pitch", duration=2.0, fmu_dir=fmu_dir,
                           sensor_params=contract.NOISE_FREE, evaluate=False)
    n = len(rows) - 2
    for name in ("roll", "pitch"):
        assert np.array_equal(rows[f"estimator.{name}"][2:], master.estimate[name][:n])
    assert rows["estimator.invalid_samples"][-1] == 1


def test_cli_exits_2_with_a_message_for_an_unknown_estimator(fmu_dir: Path, tmp_path: Path) -> None:
    proc = _cli("--estimator", "cf,nope", "--scenario", "static_level", fmu_dir=fmu_dir,
                out=tmp_path)
    assert proc.returncode == 2
    assert "unknown estimator 'nope': allowed all, cf" in proc.stderr


def test_cli_peers_refuses_an_unknown_name_and_a_jittered_run(tmp_path: Path) -> None:
    from testbenches.__main__ import main

    assert main(["run", "--peers", "vqf,nope", "--out", str(tmp_path)]) == 2
    assert main(["run", "--peers", "vqf", "--jitter", "0.2", "--out", str(tmp_path)]) == 2


def test_cli_peers_says_how_to_install_a_missing_peer(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from testbenches.__main__ import main

    monkeypatch.setitem(sys.modules, "vqf", None)  # import vqf now raises ImportError
    assert main(["run", "--peers", "vqf", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "needs the Python package 'vqf'" in err and "pip install" in err


def test_cli_peers_scores_vqf_on_the_same_samples_beside_the_contract(
    fmu_dir: Path, tmp_path: Path
) -> None:
    pytest.importorskip("vqf", reason="the VQF peer needs the bench extra (pip install -e "
                        "'.[bench]')")
    import json

    from fusion_core.sensor import sensor_preset
    from testbenches.peer_runs import run_peers
    from testbenches.peers import PEERS

    proc = _cli("--estimator", "kf", "--scenario", "roll_sweep", "--duration", "8",
                "--peers", "vqf", fmu_dir=fmu_dir, out=tmp_path)
    assert proc.returncode in (0, 1), proc.stderr
    assert "Public filters on the same samples" in proc.stdout
    report = json.loads((tmp_path / "report.json").read_text())
    (row,) = report["peers"]
    (direct,) = run_peers({"vqf": PEERS["vqf"]}, ["roll_sweep"], 1, sensor_preset("realistic"),
                          duration=8.0)
    assert (row["peer"], row["scenario"], row["seed"]) == ("vqf", "roll_sweep", 0)
    assert row["rmse_roll_deg"] == direct.rmse_roll_deg
    assert "vqf       roll_sweep" in (tmp_path / "report.md").read_text()



@settings(max_examples=300, deadline=None)
@given(st.lists(st.one_of(st.floats(-3.2, 3.2), st.floats(width=64)), min_size=1, max_size=40))
def test_the_roll_error_wrap_is_numpys_remainder_to_the_bit(values: list[float]) -> None:
    # the metrics' fast path (every x + pi already in [0, 2 pi): roll errors within about
    # +-180 deg) against the remainder it stands for, and the fallback on any double
    x = np.array(values)
    with np.errstate(invalid="ignore", over="ignore"):
        want = np.remainder(x + math.pi, 2 * math.pi) - math.pi
        got = contract.wrap_angles(x)
    nan = np.isnan(want)
    assert np.array_equal(np.isnan(got), nan)
    assert np.array_equal(got[~nan].view(np.uint64), want[~nan].view(np.uint64))


# ----- the Jacobi master (docs/interface.md, Timing) ----------------------------------------------
def test_the_chain_delay_is_measured_0_steps_gauss_seidel_and_2_jacobi(fmu_dir: Path) -> None:
    """The same noise-free sweep under both masters: the measured delay is the declared one,
    each estimate aligned by it passes T1, and the Jacobi run's only rejected sample is the
    sensor's start (dt = 0)."""
    kw = {"duration": 8.0, "fmu_dir": fmu_dir, "sensor_params": contract.NOISE_FREE}
    runs = {m: run_testbench("kf", "roll_sweep", master=m, **kw) for m in MASTERS}
    assert {m: r.measured_delay for m, r in runs.items()} == CHAIN_DELAY
    for r in runs.values():
        assert contract.check_delay([r]).passed
        assert contract.check_t1([r]).passed
        assert all(c.passed for c in r.checks), [c.line() for c in r.checks]
    assert (runs["gauss-seidel"].invalid_samples, runs["jacobi"].invalid_samples) == (0, 1)
    assert len(runs["jacobi"].t) == len(runs["gauss-seidel"].t) - 1


def test_a_hidden_extra_step_fails_the_chain_delay_check(fmu_dir: Path) -> None:
    """A Jacobi run whose estimates lag one step more than the master declares: the delay
    check measures 3 steps against 2 and fails."""
    r = run_testbench("cf", "roll_sweep", duration=8.0, fmu_dir=fmu_dir, master="jacobi",
                      sensor_params=contract.NOISE_FREE)
    lagged = dataclasses.replace(r, measured_delay=r.measured_delay + 1)
    check = contract.check_delay([lagged])
    assert not check.passed and (check.measured, check.allowed) == (3, 2)


def test_the_contract_holds_under_the_jacobi_master(fmu_dir: Path) -> None:
    """moderate_dynamics under Jacobi: the accuracy checks pass on the aligned traces, and the
    RMSE is the Gauss-Seidel run's within a hundredth of a degree."""
    gs = run_testbench("ukf", "moderate_dynamics", fmu_dir=fmu_dir)
    jac = run_testbench("ukf", "moderate_dynamics", fmu_dir=fmu_dir, master="jacobi")
    assert all(c.passed for c in jac.checks), [c.line() for c in jac.checks]
    for axis in ("rmse_roll_deg", "rmse_pitch_deg"):
        assert jac.metrics[axis] == pytest.approx(gs.metrics[axis], abs=0.01)


def test_t2_holds_under_jacobi_where_the_sensor_knows_its_inputs_hold_at_a_steps_start(
        fmu_dir: Path) -> None:
    """Jittered steps under Jacobi: the sensor's inputs are the plant's outputs of the step
    before, so its sample covers that step (inputs_at = start, which the Jacobi master sets).
    Left at end, the sample's dt is the next step's and T2 fails by far."""
    kw = {"duration": 15.0, "fmu_dir": fmu_dir, "master": "jacobi"}
    fixed = run_testbench("mgcf", contract.T2_SCENARIO, sensor_params=contract.NOISE_FREE, **kw)
    jittered = run_testbench("mgcf", contract.T2_SCENARIO, jitter=contract.T2_JITTER,
                             sensor_params=contract.NOISE_FREE, **kw)
    assert jittered.sensor_params["inputs_at"] == "start"
    assert contract.check_t2(fixed, jittered).passed
    wrong = run_testbench("mgcf", contract.T2_SCENARIO, jitter=contract.T2_JITTER,
                          sensor_params={**contract.NOISE_FREE, "inputs_at": "end"}, **kw)
    assert wrong.sensor_params["inputs_at"] == "end"
    assert not contract.check_t2(fixed, wrong).passed


def test_a_run_too_short_to_show_its_delay_says_so_without_a_warning():
    """A run of a step or two (a benchmark's setup timing) has no step after the largest delay
    to score: -1, where a mean of nothing warned and argmin of NaNs gave 0, a delay."""
    import warnings

    from testbenches.master import measured_delay

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert measured_delay(np.zeros((3, 2)), np.zeros((2, 2))) == -1
        truth = np.column_stack([np.sin(np.arange(41) * 0.3), np.cos(np.arange(41) * 0.2)])
        assert measured_delay(truth, truth[1:]) == 0  # estimate[k] of the truth at t_{k+1}
        assert measured_delay(truth, truth[:-1]) == 1
