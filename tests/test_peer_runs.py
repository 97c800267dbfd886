"""testbenches.peer_runs: public filters scored by the contract's metric on its own samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusion_core.kinematics import accel_roll_pitch
from fusion_core.sensor import sensor_preset
from testbenches.peer_runs import peer_table, roll_pitch_from_up, run_peers


def accelerometer_only(acc: np.ndarray, gyro: np.ndarray, rate: float) -> np.ndarray:
    """A 'filter' that takes each accelerometer sample for up: its error is known physics."""
    return acc / np.linalg.norm(acc, axis=1, keepdims=True)


def test_roll_pitch_from_up_inverts_the_resting_specific_force_as_accel_roll_pitch() -> None:
    rng = np.random.default_rng(3)
    up = rng.normal(size=(50, 3))
    roll, pitch = roll_pitch_from_up(up)
    for k in range(len(up)):
        assert (roll[k], pitch[k]) == pytest.approx(accel_roll_pitch(*up[k]), abs=1e-15)


def test_the_accelerometer_alone_fails_the_translation_move_and_passes_at_rest() -> None:
    """translation_2m's bound says the raw accelerometer's pitch RMSE over the scored part is
    4.1 deg (contract.TRANSLATION); at rest the one-sample tilt noise is about 0.16 deg."""
    rows = run_peers({"acc": accelerometer_only}, ["translation_2m", "static_level"], 1,
                     sensor_preset("ideal"))
    move, rest = rows
    assert (move.scenario, move.seed, move.allowed) == ("translation_2m", 0, (0.5, 4.1))
    assert 3.8 < move.rmse_pitch_deg < 4.5
    assert move.rmse_roll_deg < 0.5
    assert rest.passed is False  # 0.16 deg of noise against the 0.1 deg bound
    assert 0.1 < max(rest.rmse_roll_deg, rest.rmse_pitch_deg) < 0.3


def test_an_attitude_one_degree_off_scores_one_degree() -> None:
    c, s = math.cos(math.radians(1.0)), math.sin(math.radians(1.0))

    def tilted(acc: np.ndarray, gyro: np.ndarray, rate: float) -> np.ndarray:
        # the truth's up direction at rest is (0, 0, 1); this peer says roll = 1 deg
        return np.tile([0.0, s, c], (len(acc), 1))

    (row,) = run_peers({"tilted": tilted}, ["static_level"], 1, sensor_preset("ideal"))
    assert row.rmse_roll_deg == pytest.approx(1.0, abs=1e-9)
    assert row.rmse_pitch_deg == pytest.approx(0.0, abs=1e-9)
    assert row.passed is False


def test_moderate_dynamics_gets_numbers_but_no_verdict() -> None:
    """Its bound is per estimator class (the papers' rows), which a peer does not have."""
    (row,) = run_peers({"acc": accelerometer_only}, ["moderate_dynamics"], 1,
                       sensor_preset("realistic"), duration=6.0)
    assert row.allowed is None and row.passed is None
    assert math.isfinite(row.rmse_roll_deg)
    line = peer_table([row]).splitlines()[-1]
    assert line.split()[-2:] == ["-", "-"]


def test_every_seed_is_a_row_of_its_own_with_its_own_samples() -> None:
    rows = run_peers({"acc": accelerometer_only}, ["static_tilted"], 3, sensor_preset("ideal"))
    assert [r.seed for r in rows] == [0, 1, 2]
    assert len({r.rmse_roll_deg for r in rows}) == 3
