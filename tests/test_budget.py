"""The sensor error budget (testbenches.budget): one source off at a time, on the same seeds."""

from __future__ import annotations

import json

import pytest

from fusion_core.building_blocks import CONSTANT_NOISE
from fusion_core.sensor import SENSOR_PARAMS, sensor_preset
from testbenches.__main__ import main
from testbenches.budget import MOTION_ONLY, SOURCES, BudgetRow, budget_table, error_budget

EMPTY = {"cf": {}, "kf": {}}


def test_every_source_switches_off_real_sensor_parameters():
    names = {p.name for p in SENSOR_PARAMS}
    for _, off in SOURCES.values():
        assert off and set(off) <= names
    assert set(MOTION_ONLY) == {k for _, off in SOURCES.values() for k in off}


def test_a_source_the_sensor_does_not_have_changes_nothing():
    # the ideal sensor has no scale, cross-axis, calibration, drift or filter errors: switching
    # them off must give the same samples, so exactly the same RMSE (same seeds)
    (row,) = error_budget(["kf"], ["roll_pitch"], 1, sensor_preset("ideal"), EMPTY)
    for name in ("gyro_scale", "gyro_cross", "calibration", "bias_drift", "dlpf"):
        assert row.without[name] == row.full, name
    assert row.without["noise"] != row.full  # white noise is the ideal sensor's one error
    assert row.motion_only[0] < row.full[0]


def test_the_gyro_scale_error_is_what_limits_the_roll_sweep():
    # roll 45 deg at 0.32 Hz: a 1 % scale-factor error turns 0.45 deg of roll the wrong way at
    # each swing, more than the accelerometer corrects at that frequency with constant noise
    # (the recommended filters' adaptive noise is what removes it); perfect samples of the same
    # motion leave almost nothing
    (row,) = error_budget(["ukf"], ["roll_sweep"], 1, sensor_preset("realistic"),
                          {"ukf": CONSTANT_NOISE})
    assert row.without["gyro_scale"][0] < 0.5 * row.full[0]
    assert row.without["dlpf"][0] > 0.8 * row.full[0]
    assert max(row.motion_only) < 0.02
    assert row.limit == (0.25, 0.25)


def test_dominant_is_the_source_whose_removal_helps_the_worse_axis_most():
    without = {name: (0.3, 0.2) for name in SOURCES}
    without.update(gyro_scale=(0.1, 0.2), dlpf=(0.3, 0.05))
    row = BudgetRow("kf", "roll_sweep", (0.25, 0.25), (0.3, 0.2), without, (0.0, 0.0))
    assert row.dominant() == "gyro_scale"  # roll is the worse axis; dlpf leaves it at 0.3
    assert "gyro_scale" in budget_table([row]).splitlines()[2]


def test_the_command_writes_json_markdown_and_plot(tmp_path, capsys):
    out = tmp_path / "b"
    assert main(["budget", "--estimator", "cf", "--scenario", "static_tilted", "--seeds", "1",
                 "--out", str(out)]) == 0
    doc = json.loads((out / "budget.json").read_text())
    assert [r["estimator"] for r in doc["rows"]] == ["cf"]
    assert set(doc["rows"][0]["without"]) == set(SOURCES)
    assert "| cf | static_tilted |" in (out / "budget.md").read_text()
    assert (out / "budget.png").stat().st_size > 0
    assert "motion only" in capsys.readouterr().out


def test_bad_options_say_what_is_allowed(capsys):
    with pytest.raises(SystemExit) as stop:  # argparse's refusal, before any run
        main(["budget", "--seeds", "0"])
    assert stop.value.code == 2
    assert "an integer of at least 1" in capsys.readouterr().err
    assert main(["budget", "--scenario", "nope"]) == 2
    assert "allowed" in capsys.readouterr().err
