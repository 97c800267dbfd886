"""The per-sample hot path (issue 6): Estimator.step's inline checks and each estimator's fused
_advance give what the general code gives: the same estimate as _estimate(), the same refusals
and messages, the cached constants follow set_param and set_state, and the Kalman filter's
shared covariance still follows two different ones axis by axis."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import KEYS, make, noisy_two_axis_recording

from fusion_core import G, InvalidSample
from fusion_core.base import Estimator
from fusion_core.building_blocks import CONSTANT_NOISE
from fusion_core.types import Estimate

DT = 0.01
LEVEL = (0.0, 0.0, G)
STILL = (0.0, 0.0, 0.0)

PAPER = {"filter": "paper"}
OPTION_SETS: dict[str, list[dict]] = {
    "cf": [{}, {"gyro_sampling": "mean"}, {"acc_lowpass": 0.0}, PAPER,
           {**PAPER, "gyro_sampling": "point"}],
    "kf": [{}, {"gyro_sampling": "mean"}, {"acc_lowpass": 0.5}, {"rest_time": 0.0}, PAPER,
           {**PAPER, "gyro_sampling": "point"}],
    "mgcf": [{}, {"gyro_sampling": "mean"}, {"w0": 0.0}, {"acc_lowpass": 0.0},
             {"rest_time": 0.0}, PAPER, {**PAPER, "schedule": "fixed", "w0": 0.0}],
}
"""Each filter's defaults, the options that take another path through its hot step, and its
paper's filter."""


@pytest.mark.parametrize(
    ("key", "params"), [(k, p) for k, sets in OPTION_SETS.items() for p in sets]
)
def test_each_step_returns_the_estimate_that_estimate_builds(key: str, params: dict) -> None:
    """The hot paths build their Estimate inline: it must be _estimate()'s, field by field."""
    est = make(key, **params)
    rec = noisy_two_axis_recording(2.0)
    for a, w, h in zip(rec["acc_meas"].tolist(), rec["gyro_meas"].tolist(), rec["dt"].tolist(),
                       strict=True):
        got = est.step(a, w, h)
        assert type(got) is Estimate
        assert got == est._estimate() == est.last
        assert all(type(v) is float for v in (got.roll, got.pitch, *got.bias))


@pytest.mark.parametrize("key", KEYS)
def test_messages_say_what_was_wrong(key: str) -> None:
    est = make(key)
    est.step(LEVEL, STILL, DT)
    cases = {
        "acc=": ((math.nan, 0.0, G), STILL, DT),
        "gyro=": (LEVEL, (0.0, math.inf, 0.0), DT),
        "dt=": (LEVEL, STILL, -DT),
        "max_dt": (LEVEL, STILL, 2.0),
        "max_rate": (LEVEL, (0.0, 0.0, 2000.0), DT),
        "three accelerations": ((0.0, G), STILL, DT),
    }
    for expected, (acc, gyro, dt) in cases.items():
        with pytest.raises(InvalidSample, match=expected):
            est.step(acc, gyro, dt)


@pytest.mark.parametrize("key", KEYS)
def test_max_dt_follows_set_param_and_set_state(key: str) -> None:
    """step keeps max_dt in an attribute: a new value must reach it both ways."""
    est = make(key)
    est.step(LEVEL, STILL, DT)
    est.step(LEVEL, STILL, 0.5)
    est.set_param("max_dt", 0.05)
    with pytest.raises(InvalidSample, match=r"max_dt=0\.05"):
        est.step(LEVEL, STILL, 0.5)
    other = make(key)  # max_dt 1 s, then the snapshot's 0.05 s
    other.set_state(est.get_state())
    with pytest.raises(InvalidSample, match=r"max_dt=0\.05"):
        other.step(LEVEL, STILL, 0.5)
    other.step(LEVEL, STILL, 0.05)


@pytest.mark.parametrize("params", [{**CONSTANT_NOISE, "acc_lowpass": 0.0},
                                    {**CONSTANT_NOISE, "acc_lowpass": 0.0, "rest_time": 0.0},
                                    PAPER, {**PAPER, "gyro_sampling": "point"}])
def test_kalman_snapshot_with_two_covariances_follows_each_axis(params: dict) -> None:
    """The roll and pitch filters share one covariance; a snapshot holding two different ones
    (no filter makes one, but set_state takes it) is followed axis by axis: each covariance and
    gain as a filter whose two axes both started from it (the recording stays near level, on
    the sensor's own face; with constant Q and R and no measured vector: the adaptive noise and
    the vector's noise follow the bias-corrected rate, which both axes' biases move)."""
    rec = noisy_two_axis_recording(3.0)
    acc, gyro, dt = rec["acc_meas"], rec["gyro_meas"], rec["dt"]
    base = make("kf", **params)
    base.run(acc[:100], gyro[:100], dt[:100])
    snapshot = base.get_state()
    p_roll = [2e-5, 1e-7, 1e-7, 3e-6]
    p_pitch = [7e-5, -4e-7, -4e-7, 9e-6]

    def resumed(first: list[float], second: list[float]) -> Estimator:
        est = make("kf", **params)
        state = {**snapshot, "state": {**snapshot["state"], "P_roll": first, "P_pitch": second}}
        est.set_state(state)
        return est

    mixed, rolls, pitches = resumed(p_roll, p_pitch), resumed(p_roll, p_roll), resumed(
        p_pitch, p_pitch)
    for i in range(100, 300):
        for est in (mixed, rolls, pitches):
            est.step(acc[i], gyro[i], dt[i])
        assert mixed.P_roll == rolls.P_roll and mixed.gain_roll == rolls.gain_roll
        assert mixed.P_pitch == pitches.P_pitch and mixed.gain_pitch == pitches.gain_pitch
    assert mixed.P_roll != mixed.P_pitch
    assert np.isfinite([mixed.roll, mixed.pitch, mixed.bias_x, mixed.bias_y]).all()
