"""Endurance of the Kalman-type estimators (kf, ukf, poskf): 1,000,000 steps on a realistic
recording (`make test-slow`): the covariance stays symmetric positive definite along the way and
the error does not drift."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import make

from fusion_core import DEG
from fusion_core.scenarios import SCENARIOS
from fusion_core.sensor import ImuSensorModel

STEPS = 1_000_000
CHUNK = 50_000
RATE = 100.0


def realistic_recording(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """n samples of moderate_dynamics (its sines run on past the scenario's 60 s) through the
    realistic sensor."""
    sc = SCENARIOS["moderate_dynamics"]
    t = np.arange(1, n + 1) / RATE
    truth = sc.trajectory().truth(t)
    sensor = ImuSensorModel(seed=seed)
    h = 1.0 / RATE
    acc, gyro = np.empty((n, 3)), np.empty((n, 3))
    for i, (w, f) in enumerate(zip(truth["omega"].tolist(), truth["f"].tolist(), strict=True)):
        a, g, _ = sensor.sample(tuple(w), tuple(f), h)
        acc[i], gyro[i] = a, g
    return {"acc": acc, "gyro": gyro, "roll": truth["roll"], "pitch": truth["pitch"]}


def covariances(key: str, state: dict) -> list[np.ndarray]:
    s = state["state"]
    if key == "kf":
        return [np.array(s[name]).reshape(2, 2) for name in ("P_roll", "P_pitch")]
    if key == "ukf":
        return [np.array(s["P"])]
    return [np.array(s["P"]), *covariances("kf", s["tilt_state"]),
            *covariances("kf", s["attitude_state"])]


@pytest.mark.slow
@pytest.mark.parametrize("key", ["kf", "ukf", "poskf"])
def test_a_million_steps_keep_the_covariance_positive_definite_and_the_error_flat(key: str
                                                                                 ) -> None:
    rec = realistic_recording(STEPS)
    est = make(key)
    worst = math.inf
    rmse = []
    for lo in range(0, STEPS, CHUNK):
        hi = lo + CHUNK
        out = est.run(rec["acc"][lo:hi], rec["gyro"][lo:hi], 1.0 / RATE)
        err_roll = np.remainder(out["roll"] - rec["roll"][lo:hi] + math.pi, 2 * math.pi) - math.pi
        err = np.hypot(err_roll, out["pitch"] - rec["pitch"][lo:hi])
        rmse.append(float(np.sqrt(np.mean(err**2)) / DEG))
        for P in covariances(key, est.get_state()):
            assert np.allclose(P, P.T, rtol=1e-9, atol=1e-18)
            eig = np.linalg.eigvalsh(0.5 * (P + P.T))
            worst = min(worst, float(eig.min() / max(eig.max(), 1e-300)))
            assert eig.min() > 0.0, (lo, eig)
    print(f"\n{key}: {STEPS} steps, RMSE per {CHUNK} steps {min(rmse):.3f}-{max(rmse):.3f} deg, "
          f"worst eigenvalue ratio {worst:.3g}")
    assert max(rmse[len(rmse) // 2:]) < 1.5 * max(rmse[1:len(rmse) // 2])  # no drift
