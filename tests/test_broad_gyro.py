"""The gyro fit against a reference orientation (testbenches.broad.gyro): it recovers a known
sensitivity matrix and bias from a synthetic recording, refuses a recording that does not turn,
and on BROAD's fast-rotation trial finds the sub-percent errors of a calibrated gyro (that test
skips with the reason where the shared trials are absent)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from testbenches.broad.data import BroadTrial, load_trial
from testbenches.broad.gyro import fit_delay, fit_gyro

pytestmark = pytest.mark.heavy  # gyro fits on synthetic recordings: seconds each

RATE = 285.7142857142857
SUB = 8  # integration steps per sample interval
M_TRUE = np.array([[1.008, 0.004, -0.003],
                   [-0.006, 0.995, 0.005],
                   [0.002, -0.004, 1.003]])
B_TRUE = np.radians([0.3, -0.2, 0.5])


def body_rate(t: np.ndarray) -> np.ndarray:
    """A tumbling motion about every axis, rates to about 5 rad/s [N, 3]."""
    return np.column_stack([3.0 * np.sin(2.1 * t), 2.5 * np.sin(1.3 * t + 1.0),
                            2.0 * np.sin(0.9 * t + 2.0)])


def synthetic_trial(gyro_sampling: str, seconds: float = 30.0, lag: float = 0.0) -> BroadTrial:
    """A recording of body_rate: the reference orientation integrated finely, and a gyro whose
    sample is M omega + b at the sample instant ('point') or over the interval ('mean'), lag
    [s] late (it shows the rate of lag seconds before)."""
    n = round(seconds * RATE)
    h = 1.0 / RATE / SUB
    t = np.arange(n * SUB + 1) * h
    w = body_rate(t)
    steps = Rotation.from_rotvec(0.5 * (w[:-1] + w[1:]) * h)
    rot = Rotation.identity()
    quats = [rot.as_quat()]
    for k in range(n * SUB):
        rot = rot * steps[k]
        if (k + 1) % SUB == 0:
            quats.append(rot.as_quat())
    q = np.array(quats)[1:, [3, 0, 1, 2]]  # samples 1..n, w first
    w = body_rate(t - lag)
    if gyro_sampling == "mean":
        mid = 0.5 * (w[:-1] + w[1:])
        omega = mid.reshape(n, SUB, 3).mean(axis=1)
    else:
        omega = w[SUB::SUB]
    gyro = omega @ M_TRUE.T + B_TRUE
    acc = np.tile([0.0, 0.0, 9.80665], (n, 1))
    return BroadTrial(name="synthetic", path=Path("synthetic"), acc=acc, gyro=gyro, opt_quat=q,
                      movement=np.ones(n, dtype=bool), rate=RATE, gyro_sampling=gyro_sampling,
                      sensor_delay=lag)


@pytest.mark.heavy
@pytest.mark.parametrize("sampling", ["mean", "point"])
def test_the_fit_recovers_a_known_sensitivity_matrix_and_bias(sampling: str) -> None:
    fit = fit_gyro(synthetic_trial(sampling))
    assert np.max(np.abs(fit.matrix - M_TRUE)) < 2e-4  # 0.02 % of scale or cross-axis
    assert np.max(np.abs(np.degrees(fit.bias - B_TRUE))) < 0.01  # deg/s
    assert np.allclose(fit.scale_error, np.diag(M_TRUE) - 1.0, atol=2e-4)
    assert fit.windows > 1000, fit.as_dict()


def test_the_fit_at_the_sensors_delay_does_not_read_the_lag_as_scale_errors() -> None:
    """The same motion with a gyro 0.7 samples late: fitted at its delay, the matrix is the one of
    the gyro without lag; fitted as if it had none, the lag reads as scale and cross-axis terms."""
    on_time = fit_gyro(synthetic_trial("mean", seconds=8.0)).matrix
    lagged = synthetic_trial("mean", seconds=8.0, lag=0.7 / RATE)
    assert np.max(np.abs(fit_gyro(lagged).matrix - on_time)) < 2e-5
    assert np.max(np.abs(fit_gyro(lagged, delay=0.0).matrix - on_time)) > 1e-3


def test_a_recording_that_does_not_turn_is_refused_with_the_reason() -> None:
    trial = synthetic_trial("mean", seconds=5.0)
    still = BroadTrial(name="still", path=trial.path, acc=trial.acc, gyro=trial.gyro * 0.0,
                       opt_quat=np.tile([1.0, 0.0, 0.0, 0.0], (trial.n, 1)),
                       movement=trial.movement, rate=RATE, sensor_delay=0.0)
    with pytest.raises(ValueError, match="at least 100 are needed"):
        fit_gyro(still)


@pytest.mark.parametrize("sampling", ["mean", "point"])
@pytest.mark.parametrize("lag_samples", [0.0, 0.7, -0.4])
def test_the_delay_fit_finds_a_known_lag(sampling: str, lag_samples: float) -> None:
    trial = synthetic_trial(sampling, seconds=8.0, lag=lag_samples / RATE)
    delay = fit_delay(trial)
    assert delay.samples == pytest.approx(lag_samples, abs=0.03)
    assert delay.seconds == pytest.approx(lag_samples / RATE, abs=0.03 / RATE)


DATA = Path(os.environ.get("BROAD_DIR",
                       Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"))
FAST = DATA / "06_undisturbed_fast_rotation_A.mat"


@pytest.mark.skipif(not FAST.is_file(), reason=f"no BROAD trial {FAST.name} in {DATA} "
                    "(set BROAD_DIR to the folder of BROAD's trials)")
def test_broads_gyro_has_sub_percent_scale_errors_that_a_6d_filter_integrates() -> None:
    fit = fit_gyro(load_trial(FAST))
    assert np.all(np.abs(fit.scale_error) < 0.01)
    assert np.max(np.abs(fit.scale_error)) > 0.002  # measurable: 0.71 % on x
    assert abs(fit.residual) < np.radians(0.5)


@pytest.mark.skipif(not FAST.is_file(), reason=f"no BROAD trial {FAST.name} in {DATA} "
                    "(set BROAD_DIR to the folder of BROAD's trials)")
def test_broads_gyro_lags_the_reference_by_the_loaders_sensor_delay() -> None:
    """The loader's sensor_delay (2.4 ms) is what the gyro's timing against the reference says,
    and taking it out of the fit halves the residual of the fast rotations."""
    trial = load_trial(FAST)
    delay = fit_delay(trial)
    assert delay.seconds == pytest.approx(trial.sensor_delay, abs=0.2e-3)
    fit = delay.as_dict()
    assert fit["residual_deg_at_delay"] < 0.6 * fit["residual_deg_at_zero"]
