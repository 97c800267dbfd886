"""The plain-float paper UKF is the same filter as a numpy implementation.

tests/reference_ukf.py is that implementation (13 sigma points as rows of a numpy array, 6x6
covariance, np.linalg.solve); fusion_core.papers.ukf computes the same unscented transform with
closed-form sigma-point algebra in Python floats. On a noisy 60 s recording both must agree at
every sample to 1e-9 rad in roll and pitch and 1e-9 rad/s in the gyro bias.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from reference_ukf import ReferenceUnscentedKalmanFilter

from fusion_core import synthetic
from fusion_core.papers import PaperUnscentedKalmanFilter
from fusion_core.scenarios import get_scenario

pytestmark = pytest.mark.heavy  # the UKF against a numpy reference over minutes of samples

PAPER_POINT = {"gyro_sampling": "point"}
"""The paper's filter with the rule of the synthetic recordings' point samples."""
ANGLE_TOL = 1e-9  # rad
BIAS_TOL = 1e-9  # rad/s


@functools.cache
def moderate_dynamics_recording() -> dict[str, np.ndarray]:
    """moderate_dynamics, 60 s at 100 Hz, MPU-6050 noise, seed 0."""
    trajectory = get_scenario("moderate_dynamics").trajectory()
    return synthetic.record(trajectory, 60.0, 100.0, noise=synthetic.MPU6050, seed=0)


@functools.cache
def default_runs() -> tuple[PaperUnscentedKalmanFilter, ReferenceUnscentedKalmanFilter, dict, dict]:
    """Both filters with default parameters after the whole recording, and their outputs."""
    rec = moderate_dynamics_recording()
    args = (rec["acc_meas"], rec["gyro_meas"], rec["dt"])
    new = PaperUnscentedKalmanFilter(**PAPER_POINT)
    ref = ReferenceUnscentedKalmanFilter(**PAPER_POINT)
    return new, ref, new.run(*args), ref.run(*args)


def differences(new: dict[str, np.ndarray], ref: dict[str, np.ndarray]) -> dict[str, float]:
    diff = {k: float(np.max(np.abs(new[k] - ref[k]))) for k in ("roll", "pitch", "bias")}
    print(f"\nmax |new - reference|: {diff}")
    return diff


def test_reference_is_a_busy_recording() -> None:
    # A test that cannot fail is a defect: the accelerometer update must both run and be
    # skipped (gate), and the bias must move, for the comparison to cover every branch.
    rec = moderate_dynamics_recording()
    rho = np.abs(np.linalg.norm(rec["acc_meas"], axis=1) / 9.80665 - 1.0)
    gate = PaperUnscentedKalmanFilter().params["acc_gate"]
    assert 0.1 < np.mean(rho < gate) < 0.95
    assert np.max(np.abs(default_runs()[3]["bias"])) > 1e-4


def test_defaults_match_the_numpy_reference_at_every_sample() -> None:
    diff = differences(*default_runs()[2:])
    assert diff["roll"] < ANGLE_TOL
    assert diff["pitch"] < ANGLE_TOL
    assert diff["bias"] < BIAS_TOL


@pytest.mark.parametrize(
    "params",
    [
        {"gyro_sampling": "mean"},
        {"alpha": 0.5, "beta": 0.0, "kappa": 1.0},
        {"acc_gate": 10.0, "acc_noise": 0.01},
        {"norm_noise": 0.0},
    ],
    ids=["rectangle", "other-sigma-weights", "always-update", "no-norm-row"],
)
def test_other_parameters_match_the_numpy_reference(params: dict[str, object]) -> None:
    rec = moderate_dynamics_recording()
    args = (rec["acc_meas"][:2001], rec["gyro_meas"][:2001], rec["dt"][:2001])  # first 20 s
    diff = differences(
        PaperUnscentedKalmanFilter(**{**PAPER_POINT, **params}).run(*args),
        ReferenceUnscentedKalmanFilter(**{**PAPER_POINT, **params}).run(*args),
    )
    assert diff["roll"] < ANGLE_TOL
    assert diff["pitch"] < ANGLE_TOL
    assert diff["bias"] < BIAS_TOL


def test_covariance_matches_the_numpy_reference_after_60_s() -> None:
    new, ref = default_runs()[:2]
    P_new, P_ref = np.array(new.P), np.array(ref.P)
    assert np.array_equal(P_new, P_new.T)
    assert np.max(np.abs(P_new - P_ref)) <= 1e-9 * np.max(np.abs(P_ref))


def test_a_covariance_made_indefinite_by_rounding_takes_the_references_square_root() -> None:
    rec = moderate_dynamics_recording()
    acc, gyro, dt = rec["acc_meas"][:200], rec["gyro_meas"][:200], rec["dt"][:200]
    new = PaperUnscentedKalmanFilter(**PAPER_POINT)
    ref = ReferenceUnscentedKalmanFilter(**PAPER_POINT)
    new.run(acc, gyro, dt)
    ref.run(acc, gyro, dt)
    # Push the smallest eigenvalue just below zero: Cholesky fails, both fall back to the
    # clipped symmetric square root.
    P = np.array(ref.P)
    w, V = np.linalg.eigh(P)
    P = P - (w[0] + 1e-12 * w[-1]) * np.outer(V[:, 0], V[:, 0])
    P = 0.5 * (P + P.T)
    assert np.min(np.linalg.eigvalsh(P)) < 0.0
    new.P = P.tolist()
    ref.P = P.tolist()
    a = new.step(acc[200 - 1], gyro[200 - 1], float(dt[0]))
    b = ref.step(acc[200 - 1], gyro[200 - 1], float(dt[0]))
    assert abs(a.roll - b.roll) < ANGLE_TOL
    assert abs(a.pitch - b.pitch) < ANGLE_TOL
    assert np.max(np.abs(np.subtract(a.bias, b.bias))) < BIAS_TOL
    assert np.max(np.abs(np.array(new.P) - np.array(ref.P))) <= 1e-9 * np.max(np.abs(P))


def test_general_update_agrees_with_the_cholesky_update() -> None:
    from fusion_core.papers import ukf

    rng = np.random.default_rng(1)
    A = rng.standard_normal((10, 10))
    joint = A @ A.T + 10 * np.eye(10)  # covariance of [x (6); z (4)]
    P = tuple(joint[i, j] for i in range(6) for j in range(i + 1))
    S = tuple(joint[6 + i, 6 + j] for i in range(4) for j in range(i + 1))
    rows = tuple(tuple(joint[i, 6:]) for i in range(6))
    x = tuple(rng.standard_normal(6))
    y = tuple(rng.standard_normal(4))
    fast = ukf.kalman_update(x, P, S, rows, y)
    general = ukf.general_update(x, P, S, rows, y)
    np.testing.assert_allclose(fast[:6], general[:6], rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast[6], general[6], rtol=0, atol=1e-12)
