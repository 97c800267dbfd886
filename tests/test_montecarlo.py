"""Monte Carlo campaigns on Dask (testbenches.montecarlo): rows, resume, retries, statistics."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from testbenches.montecarlo.plan import parse_variation, plan
from testbenches.montecarlo.runner import MAX_BATCH, MIN_BATCH, batches, connect, execute
from testbenches.montecarlo.simulate import run_row, simulate
from testbenches.montecarlo.store import read_rows
from testbenches.montecarlo.summary import summarise
from testbenches.options import load_sensor

pytestmark = pytest.mark.heavy  # Dask campaigns

pytest.importorskip("distributed")


def small_plan(seeds: int = 4, design: str = "lhs") -> list:
    return plan(["cf", "kf"], ["static_tilted"], seeds,
                [parse_variation("gyro_scale_std=0:0.02")], duration=8.0,
                sensor=load_sensor("realistic"), kind=design)


@pytest.mark.heavy
def test_a_small_campaign_on_two_local_workers_writes_one_row_per_run(tmp_path):
    runs = small_plan()
    stats = execute(runs, tmp_path, "local", workers=2, batch_size=3, log=lambda s: None)
    rows = read_rows(tmp_path)
    assert stats["ran"] == len(runs) == 8 and stats["failed"] == 0
    assert sorted(r["key"] for r in rows) == sorted(r.key for r in runs)
    assert len(list((tmp_path / "runs").glob("*.parquet"))) == 3  # batches of 3, 3 and 2
    row = rows[0]
    for column in ("estimator", "scenario", "seed", "vary_gyro_scale_std", "rmse_roll_deg",
                   "rmse_pitch_deg", "max_err_deg", "bias_err_dps", "invalid_samples",
                   "seconds", "status"):
        assert column in row
    assert all(r["status"] == "ok" and math.isfinite(r["rmse_roll_deg"]) for r in rows)


def test_the_same_campaign_again_runs_nothing_and_keeps_each_run_once(tmp_path):
    runs = small_plan(3)
    execute(runs, tmp_path, "local", workers=2, log=lambda s: None)
    again = execute(runs, tmp_path, "local", workers=2, log=lambda s: None)
    assert again["ran"] == 0 and again["already_done"] == len(runs)
    keys = [r["key"] for r in read_rows(tmp_path)]
    assert sorted(keys) == sorted(r.key for r in runs) and len(keys) == len(set(keys))



@pytest.mark.heavy
def test_a_sobol_campaign_grows_by_running_only_the_new_seeds(tmp_path):
    """A Sobol sequence's first N points are those of any longer one, so more seeds add runs
    (a Latin hypercube of another size is another design: it runs anew)."""
    runs = small_plan(2, "sobol")
    execute(runs, tmp_path, "local", workers=2, log=lambda s: None)
    more = small_plan(4, "sobol")
    assert {r.key for r in runs} <= {r.key for r in more}
    grown = execute(more, tmp_path, "local", workers=2, log=lambda s: None)
    assert grown["ran"] == len(more) - len(runs) == 4


def test_a_run_that_raises_is_retried_then_recorded_as_failed(tmp_path):
    good = small_plan(1)[0]
    bad = dataclasses.replace(good, key="0123456789abcdef", params={"tau": -1.0})
    stats = execute([good, bad], tmp_path, "local", workers=2, retries=2, log=lambda s: None)
    rows = {r["key"]: r for r in read_rows(tmp_path)}
    assert stats["failed"] == 1
    assert rows[bad.key]["status"] == "failed" and rows[bad.key]["attempts"] == 3
    assert "tau" in rows[bad.key]["error"] and math.isnan(rows[bad.key]["rmse_roll_deg"])
    assert rows[good.key]["status"] == "ok"
    assert summarise(list(rows.values()))["groups"][0]["failed"] == 1


def test_the_summary_statistics_are_numpys_on_the_same_rows():
    rng = np.random.default_rng(3)
    rows = [{"key": str(i), "estimator": "kf", "scenario": "vibration", "seed": i,
             "status": "ok", "rmse_roll_deg": float(x), "rmse_pitch_deg": float(y),
             "max_err_deg": float(x + y), "bias_err_dps": 0.01}
            for i, (x, y) in enumerate(rng.gamma(2.0, 0.3, size=(400, 2)))]
    s = summarise(rows)["groups"][0]
    roll = np.array([r["rmse_roll_deg"] for r in rows])
    assert s["rmse_roll_deg"]["mean"]["value"] == pytest.approx(roll.mean())
    assert s["rmse_roll_deg"]["median"]["value"] == pytest.approx(np.median(roll))
    assert s["rmse_roll_deg"]["p95"]["value"] == pytest.approx(np.percentile(roll, 95))
    assert s["rmse_roll_deg"]["p99"]["value"] == pytest.approx(np.percentile(roll, 99))
    ci = s["rmse_roll_deg"]["p95"]
    assert ci["low"] < ci["value"] < ci["high"]
    assert s["contract"]["share_within"] == pytest.approx(
        np.mean((roll <= 3.0) & (np.array([r["rmse_pitch_deg"] for r in rows]) <= 3.0)))


def test_a_variation_must_name_a_numeric_parameter_and_a_range():
    with pytest.raises(ValueError, match="NAME=LOW:HIGH"):
        parse_variation("gyro_psd=1e-8")
    with pytest.raises(ValueError, match="neither a sensor parameter"):
        parse_variation("nope=0:1")
    with pytest.raises(ValueError, match="LOW must be below HIGH"):
        parse_variation("tau=2:1")
    assert parse_variation("R_measure=1e-6:1e-4:log").target == "estimator"


@pytest.mark.parametrize(("runs", "workers"), [(3000, 2), (10500, 2), (3000, 1), (20, 2), (3, 4)])
def test_batches_hold_every_run_once_in_order_and_shrink_to_the_end(runs, workers):
    parts = batches(list(range(runs)), workers)
    assert [r for part in parts for r in part] == list(range(runs))
    sizes = [len(p) for p in parts]
    assert sizes[:-1] == sorted(sizes[:-1], reverse=True)  # the last takes what is left
    assert max(sizes) <= MAX_BATCH
    assert len(parts) >= min(runs, workers)  # a small campaign still gives every worker work
    if runs >= 8 * MIN_BATCH * workers:  # the last batches are the smallest, not as large as
        assert sizes[-2] == MIN_BATCH < sizes[0]  # the first: the workers finish together
    assert len(batches(list(range(runs)), workers, size=7)[0]) == min(7, runs)


def test_an_address_where_no_scheduler_answers_is_an_error_that_says_what_to_do():
    import socket

    with socket.socket() as s:  # a port that was free a moment ago: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(ConnectionError, match=r"no Dask scheduler answers.*dask scheduler"):
        connect(f"127.0.0.1:{port}", timeout=1)


def test_a_campaign_run_is_the_fmu_testbench_run(built_fmus):
    """The native core's run gives the three FMUs' trace (the UKF: bit for bit)."""
    from testbenches.master import run_testbench

    path = built_fmus.native("fmi2", "ImuPlant")
    run = plan(["ukf"], ["moderate_dynamics"], 2, duration=10.0,
               sensor=load_sensor("realistic"))[1]
    mine = simulate(run)
    ref = run_testbench("ukf", "moderate_dynamics", seed=run.seed, duration=10.0,
                        params=run.params, sensor_params=run.sensor, fmu_dir=path.parent,
                        evaluate=False)
    for part in ("truth", "sample", "estimate"):
        a, b = getattr(mine, part), getattr(ref, part)
        assert all(np.array_equal(a[k], b[k]) for k in b), part
    assert run_row(run)["rmse_roll_deg"] == pytest.approx(
        __import__("testbenches.contract", fromlist=["x"]).compute_metrics(ref)["rmse_roll_deg"],
        abs=0.0)


def test_an_fmu_in_the_loop_run_scores_as_the_native_core_run(built_fmus):
    """--fmu: the run through the FMUs (fmpy) gives the native core's row."""
    built_fmus.native("fmi2", "ImuPlant")
    run = plan(["ukf"], ["vibration"], 1, duration=6.0, sensor=load_sensor("realistic"))[0]
    fmu_run = dataclasses.replace(run, fmu=True)
    a, b = run_row(run), run_row(fmu_run, str(built_fmus.directory))
    for metric in ("rmse_roll_deg", "rmse_pitch_deg", "max_err_deg", "bias_err_dps"):
        assert a[metric] == b[metric]


@pytest.mark.heavy
def test_the_campaign_command_writes_its_summary_and_plots(tmp_path):
    import json
    import subprocess
    import sys

    from conftest import REPO

    cmd = [sys.executable, "-m", "testbenches", "campaign", "--estimator", "cf,kf", "--scenario",
           "static_tilted", "--seeds", "6", "--duration", "6", "--vary",
           "gyro_scale_std=0:0.02", "--workers", "2", "--out", str(tmp_path)]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=300,
                          check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "| cf | static_tilted | 6 | 0 |" in proc.stdout
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["runs"] == 12 and len(summary["groups"]) == 2
    for name in ("summary.md", "errors.png", "vary_gyro_scale_std.png", "campaign.json"):
        assert (tmp_path / name).is_file(), name
    again = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=300,
                           check=False)
    assert "0 run(s) now" in again.stdout and "12 already in" in again.stdout
