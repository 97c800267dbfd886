"""Presets (recommended = the defaults, paper = the papers' filters), preset files, the MGCF
schedules and the gyro sampling property that chooses the integration rule."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from helpers import KEYS, make

from fusion_core import DEG, ESTIMATORS, G
from fusion_core.papers.mgcf import SCHEDULES, scheduled_w0
from fusion_core.presets import PAPER_RULES, PRESETS, load_preset, preset_params
from fusion_core.registry import ENTRY, FILTER, create


@pytest.mark.parametrize("key", KEYS)
def test_the_defaults_are_the_recommended_preset(key: str) -> None:
    assert preset_params("recommended", key) == {}
    assert make(key).params == make(key, **load_preset("recommended")[key]).params


@pytest.mark.parametrize("key", KEYS)
def test_the_paper_preset_runs_the_papers_filter_at_its_values(key: str) -> None:
    paper = make(key, **preset_params("paper", key))
    assert type(paper) is ENTRY[key].paper_class  # the reference, else the class itself
    # the paper's values are its defaults, with the papers' rules
    assert paper.params == {**type(paper)().params, **PAPER_RULES}
    assert paper.params["gyro_sampling"] == "mean"  # the papers' rectangle rule
    assert paper.params["sensor_delay"] == 0.0


def test_old_preset_names_say_what_they_became() -> None:
    with pytest.raises(ValueError, match="'broad' is now 'recommended'"):
        preset_params("broad", "kf")
    with pytest.raises(ValueError, match="'default' is now 'paper'"):
        load_preset("default")


def test_a_preset_file_is_loaded_and_checked(tmp_path: Path) -> None:
    good = tmp_path / "mine.json"
    good.write_text(json.dumps({"kf": {"R_measure": 1e-4}}))
    preset = load_preset(good)
    assert preset["kf"] == {"R_measure": 1e-4} and preset["cf"] == {}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"kf": {"R_measure": -1.0}}))
    with pytest.raises(ValueError, match="R_measure"):
        load_preset(bad)
    bad.write_text(json.dumps({"ekf": {}}))
    with pytest.raises(ValueError, match="unknown estimator"):
        load_preset(bad)


def test_every_named_preset_builds_every_estimator() -> None:
    for name in PRESETS:
        for key in ESTIMATORS:
            create(key, preset_params(name, key))


@pytest.mark.parametrize(
    ("rho", "w0"),
    [(0.0, 0.1), (0.0249, 0.1), (0.025, 0.07), (0.0349, 0.07), (0.035, 0.05), (0.0499, 0.05),
     (0.05, 0.0), (0.3, 0.0)],
)
def test_the_experimental_schedule_is_duong_quocs_section_4_2(rho: float, w0: float) -> None:
    assert scheduled_w0(rho, SCHEDULES["experimental"]) == w0


@pytest.mark.parametrize(
    ("rho", "w0"),
    [(0.0, 0.1), (0.0099, 0.1), (0.01, 0.07), (0.2499, 0.07), (0.25, 0.035), (0.3499, 0.035),
     (0.35, 0.0)],
)
def test_the_simulation_schedule_is_duong_quocs_section_4_1(rho: float, w0: float) -> None:
    assert scheduled_w0(rho, SCHEDULES["simulation"]) == w0


def only_gyro(key: str) -> dict[str, object]:
    """The options with which only the gyro moves roll (Estimator.GYRO_ONLY: the recommended
    class's, else its paper's filter's)."""
    options = ENTRY[key].cls.GYRO_ONLY
    if options is not None:
        return dict(options)
    paper = ENTRY[key].paper_class.GYRO_ONLY
    assert paper is not None, f"{key}: neither class declares GYRO_ONLY"
    return {FILTER: "paper", **paper}


@pytest.mark.parametrize("key", KEYS)
def test_the_sampling_property_chooses_the_integration_rule(key: str) -> None:
    """A rate ramp about x with the accelerometer gated out: a point-sample filter integrates
    the trapezoid (the exact angle for point samples), a mean-sample filter rate times dt (the
    exact angle for interval means)."""
    h, n = 0.01, 50
    t = np.arange(n) * h
    rate = 0.5 + 2.0 * t  # rad/s
    level = np.tile([0.0, 0.0, G], (n, 1))
    acc = level * 3.0  # |a| = 3 g: every correction skips it
    acc[0] = level[0]  # the first sample initialises roll = 0
    for sampling in ("point", "mean"):
        gyro = np.zeros((n, 3))
        if sampling == "point":
            gyro[:, 0] = rate
            expected = 0.5 * (t[-1]) + t[-1] ** 2
        else:  # the mean of the ramp over each interval (t_{k-1}, t_k]
            gyro[1:, 0] = 0.5 * (rate[1:] + rate[:-1])
            expected = 0.5 * (t[-1]) + t[-1] ** 2
        est = make(key, gyro_sampling=sampling, **only_gyro(key))
        out = est.run(acc, gyro, h)
        assert out["roll"][-1] == pytest.approx(expected, abs=2e-4), (key, sampling)
        wrong = make(key, gyro_sampling="mean" if sampling == "point" else "point",
                     **only_gyro(key))
        assert abs(wrong.run(acc, gyro, h)["roll"][-1] - expected) > 1e-3, (key, sampling)


def test_poskf_outputs_the_recommended_kf_attitude() -> None:
    rng = np.random.default_rng(0)
    n = 2000
    t = np.arange(n) * 0.01
    roll = 0.4 * np.sin(1.3 * t)
    acc = np.column_stack([np.zeros(n), G * np.sin(roll), G * np.cos(roll)])
    acc += 0.5 * rng.standard_normal((n, 3))
    gyro = np.column_stack([0.4 * 1.3 * np.cos(1.3 * t), np.zeros(n), np.zeros(n)])
    pos = make("poskf").run(acc, gyro, 0.01)
    kf = make("kf").run(acc, gyro, 0.01)
    assert np.array_equal(pos["roll"], kf["roll"]) and np.array_equal(pos["pitch"], kf["pitch"])
    tilt = make("poskf", filter="paper").run(acc, gyro, 0.01)  # the paper's: its tilt stage's
    assert not np.array_equal(tilt["roll"], kf["roll"])
    assert math.isfinite(float(np.abs(pos["roll"] - roll).max() / DEG))


def test_the_recommended_defaults_are_the_noise_derivation_at_the_reference_sensor():
    """presets.noise_preset (what `testbenches noise` writes for a user's sensor) and the
    classes' defaults cannot drift apart: at the reference sensor it gives the defaults (ukf's
    acc_noise, and cf's and mgcf's, rounded to 0.005)."""
    from fusion_core.building_blocks import REAL_GYRO_DENSITY
    from fusion_core.position import REAL_ACC_DENSITY
    from fusion_core.presets import REFERENCE_ACC_SAMPLE_STD, noise_preset

    derived = noise_preset(REAL_GYRO_DENSITY, REAL_ACC_DENSITY, REFERENCE_ACC_SAMPLE_STD)
    assert set(derived) == set(ESTIMATORS)
    for key, params in derived.items():
        specs = ESTIMATORS[key].param_specs()
        for name, value in params.items():
            rel = 0.02 if name == "acc_noise" else 1e-12
            assert value == pytest.approx(specs[name].default, rel=rel), (key, name)
