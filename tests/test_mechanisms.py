"""What each mechanism is worth (testbenches.mechanisms): the switches are real parameter
values of the filters, the keep-or-drop decision follows the training folds only, and the
command runs end to end on two BROAD slices."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from fusion_core.registry import ATTITUDE_FILTERS, ESTIMATORS, create
from testbenches.mechanisms import MECHANISMS, Worth, decide

DATA = Path(os.environ.get("BROAD_DIR",
                           Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"))
TRIALS = (DATA / "10_undisturbed_slow_translation_A.hdf5",
          DATA / "01_undisturbed_slow_rotation_A.mat")


@pytest.mark.parametrize("mechanism", MECHANISMS, ids=lambda m: m.name)
def test_each_switch_is_a_change_the_filters_that_have_it_accept(mechanism) -> None:
    owners = [k for k in ATTITUDE_FILTERS if mechanism.applies(k) or mechanism.dropped(k)]
    assert owners, f"{mechanism.name} belongs to no attitude filter"
    for key in owners:
        specs = ESTIMATORS[key].param_specs()
        on = [p for p, v in mechanism.off.items() if specs[p].default != v]
        assert len(on) == (len(mechanism.off) if mechanism.applies(key) else 0)
        create(key, dict(mechanism.off))  # a valid parameter set
        if mechanism.dropped(key):  # switched on again: every value changes, and is valid
            switch = mechanism.switch(key)
            assert switch and all(specs[p].default != v for p, v in switch.items())
            create(key, dict(switch))


FOLDS = {"a1": "slow", "a2": "slow", "b1": "fast", "c1": "trans", "d1": "dist"}


def test_the_training_folds_decide_and_the_held_out_one_does_not() -> None:
    on = {"a1": 1.0, "a2": 1.0, "b1": 1.0, "c1": 1.0, "d1": 5.0}
    off = {"a1": 2.0, "a2": 2.0, "b1": 2.0, "c1": 2.0, "d1": 1.0}
    # with the disturbed fold held out, every training fold is better with it
    assert decide(on, off, FOLDS, ["slow", "fast", "trans"])
    # with it in training, its regret (5x) outweighs the others' (2x)
    assert not decide(on, off, FOLDS, ["slow", "fast", "dist"])


def test_a_level_outcome_drops_the_mechanism() -> None:
    same = {t: 1.0 for t in FOLDS}
    assert not decide(same, dict(same), FOLDS, ["slow", "fast", "trans", "dist"])


def test_the_verdict_needs_both_ways_of_scoring() -> None:
    on, off = {"a1": 1.0, "b1": 1.0}, {"a1": 2.0, "b1": 2.0}
    w = Worth("kf", "rest", on, off, ["slow", "fast"], dict(on), battery_ratio=1.2)
    assert w.broad_gain() == pytest.approx(1.0) and w.verdict() == "keeps its place"
    w.battery_ratio = 0.9
    assert w.verdict().startswith("mixed: BROAD keep, battery drop")
    level = Worth("kf", "acc_gate", on, dict(on), [], dict(on), battery_ratio=1.001,
                  battery_best=("shaking/worse", 1.05))
    assert level.verdict().startswith("drop")
    level.contract_best = ("high_dynamics", 1.25)  # a contract scenario is a cell too
    assert level.verdict().startswith("keeps its place for the contract's high_dynamics")
    level.battery_best = ("slow_combined/mpu6050", 1.3)  # made for one kind of motion
    assert level.verdict() == "keeps its place for slow_combined/mpu6050"
    level.contract_lost = ["high_dynamics"]
    assert level.verdict().startswith("keeps its place: the contract needs it")


def test_what_the_battery_keeps_is_never_dropped() -> None:
    """Worth.battery_keeps (what `broad --cv`'s nested procedures go by) says why exactly where
    the verdict cannot drop the mechanism on BROAD's folds alone."""
    on, off = {"a1": 1.0, "b1": 1.0}, {"a1": 0.5, "b1": 0.5}  # BROAD: better without it
    w = Worth("kf", "longer_vector", on, off, ["slow"], dict(on))
    assert w.battery_keeps() is None  # the battery not run
    w.battery_ratio, w.battery_best = 1.064, ("pendulum/better", 2.06)
    assert w.battery_keeps() == "its mean error 1.064 times as large without it"
    assert w.verdict().startswith("mixed")
    w.battery_ratio = 1.004  # level, but one cell needs it
    assert w.battery_keeps() == "its pendulum/better error 2.06 times as large without it"
    assert w.verdict() == "keeps its place for pendulum/better"
    w.battery_best = ("pendulum/better", 1.09)
    assert w.battery_keeps() is None and w.verdict().startswith("drop")


def test_a_drop_waits_for_the_grid_chosen_again_without_it() -> None:
    """Level at the recommended point, the fast leak would go; with the grid chosen again per
    fold it stays where the folds choose worse points without it, and goes where they do not."""
    on = {"a1": 1.0, "b1": 1.0}
    w = Worth("kf", "band_leak", on, dict(on), [], dict(on), battery_ratio=1.001)
    assert w.would_change() and w.verdict().startswith("drop")
    w.grid_cv, w.grid_nested = (0.515, 0.497), (0.4975, 0.497)
    assert not w.would_change()
    assert w.verdict().startswith("keeps its place: with the grid chosen again")
    w.grid_cv, w.grid_nested = (0.4975, 0.497), (0.521, 0.507)  # the nested one needs it
    assert w.verdict().startswith("keeps its place: with the grid chosen again")
    w.grid_nested = (0.4975, 0.497)  # both within the tie: the simpler filter
    assert w.verdict().startswith("drop")


def test_a_dropped_mechanism_comes_back_only_where_both_cross_validations_agree() -> None:
    """Scored with it switched on again: level, it stays dropped; where it would keep a place
    at the recommended point, the grid is chosen again with it, and it comes back only if the
    cross-validated and the nested means both gain (the mgcf's fast leak: 0.508 against 0.536
    cross-validated, 0.548 against 0.537 nested)."""
    as_is = {"a1": 1.0, "b1": 1.0}
    w = Worth("mgcf", "band_leak", dict(as_is), dict(as_is), [], dict(as_is),
              battery_ratio=1.001, dropped=True)
    assert not w.would_change() and w.verdict() == "stays dropped: no gain out of sample"
    w.battery_best = ("disturbed/better", 1.2)  # made for one kind of motion
    assert w.would_change() and w.verdict().startswith("would come back")
    w.grid_cv, w.grid_nested = (0.536, 0.508), (0.537, 0.548)
    assert not w.would_change() and w.verdict().startswith("stays dropped: at the recommended")
    w.grid_nested = (0.548, 0.537)
    assert w.verdict().startswith(
        "comes back: at the recommended point it would keep a place for disturbed/better")


def _slices(tmp_path: Path) -> list[str]:
    import h5py

    from testbenches.broad.data import load_trial

    files = []
    for source in TRIALS:
        trial = load_trial(source).head(45.0)
        path = tmp_path / f"{trial.name}.hdf5"
        with h5py.File(path, "w") as f:
            f["imu_acc"], f["imu_gyr"] = trial.acc, trial.gyro
            f["opt_quat"], f["movement"] = trial.opt_quat, trial.movement
            f.attrs["sampling_rate"] = trial.rate
        files.append(str(path))
    return files


@pytest.mark.skipif(not all(p.is_file() for p in TRIALS),
                    reason=f"no BROAD trials in {DATA} (set BROAD_DIR)")
def test_the_grid_is_chosen_again_with_the_mechanism_off(tmp_path: Path) -> None:
    """cross_validate's base reaches every run, over the grid point's own values: with the
    pre-filter off, each point of a grid of acc_lowpass runs the filter without it."""
    pytest.importorskip("h5py")
    from testbenches.broad.cv import _rmse, cross_validate
    from testbenches.broad.run import run_fusion_core
    from testbenches.mechanisms import BY_NAME, load_trials

    trials, groups = load_trials([Path(f) for f in _slices(tmp_path)])
    off = BY_NAME["prefilter"].off
    grid = {"acc_lowpass": [1.0, 2.0]}
    cv = cross_validate(trials, groups, ["kf"], grid=grid, constraint=None, base=off)
    e = cv.estimators["kf"]
    for j, trial in enumerate(trials):
        r = run_fusion_core("kf", off, trial)
        assert e.errors[0, j] == e.errors[1, j] == _rmse(trial, r["roll"], r["pitch"])
        assert e.in_sample[trial.name] == e.errors[0, j]


@pytest.mark.skipif(not all(p.is_file() for p in TRIALS),
                    reason=f"no BROAD trials in {DATA} (set BROAD_DIR)")
def test_the_command_on_two_slices(tmp_path: Path, capsys) -> None:
    pytest.importorskip("h5py")
    from testbenches.cli import main

    files = _slices(tmp_path)
    out = tmp_path / "m"
    assert main(["mechanisms", *files, "--estimator", "kf", "--mechanism", "prefilter,rest",
                 "--parts", "0", "--out", str(out)]) == 0
    report = json.loads((out / "mechanisms.json").read_text())
    prefilter = next(w for w in report["worth"] if w["mechanism"] == "prefilter")
    assert set(prefilter["folds_keeping"]) == {"slow_rotation", "translation"}
    assert prefilter["cv_gain_deg"] > 0.0
    assert "| kf | prefilter |" in capsys.readouterr().out
