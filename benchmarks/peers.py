"""Peer filters from the `bench` extra, timed like ours: one update call per sample.

Each peer gets its inputs in the form its documentation asks for (numpy arrays, its units),
prepared before the timed loop, so only its update call is timed:
  filterpy_ukf   filterpy's UnscentedKalmanFilter on the 3-state gravity direction (predict with
                 the gyro rotation, update with acc/g), Merwe sigma points alpha 1, beta 2,
                 kappa 0: the same model as our UKF without the bias states;
  ahrs_mahony, ahrs_madgwick, ahrs_ekf   ahrs.filters.Mahony/Madgwick.updateIMU and EKF.update
                 (no magnetometer), pure Python on numpy;
  imufusion      imufusion.Ahrs.update_no_magnetometer (C; deg/s and g);
  vqf            vqf.VQF.update (C++ through Cython), one sample per call.
A peer that cannot be imported or run is reported unavailable with the reason.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from fusion_core import G

from .common import RATE_HZ, time_interleaved

PEERS = ("filterpy_ukf", "ahrs_mahony", "ahrs_madgwick", "ahrs_ekf", "imufusion", "vqf")


def _rotate_gravity(x: np.ndarray, dt: float, omega: tuple[float, float, float]) -> np.ndarray:
    """exp(-[omega dt]x) x (Rodrigues), the 3-state process model (plain floats inside, so that
    the peer's time is filterpy's own)."""
    x0, x1, x2 = x.tolist()
    p0, p1, p2 = omega[0] * dt, omega[1] * dt, omega[2] * dt
    a2 = p0 * p0 + p1 * p1 + p2 * p2
    a = math.sqrt(a2)
    sa, ca = (math.sin(a) / a, (1.0 - math.cos(a)) / a2) if a > 1e-8 else (1.0, 0.5)
    u0, u1, u2 = p1 * x2 - p2 * x1, p2 * x0 - p0 * x2, p0 * x1 - p1 * x0
    return np.array((
        x0 - sa * u0 + ca * (p1 * u2 - p2 * u1),
        x1 - sa * u1 + ca * (p2 * u0 - p0 * u2),
        x2 - sa * u2 + ca * (p0 * u1 - p1 * u0),
    ))


def _filterpy_ukf(rec: dict[str, np.ndarray]) -> Callable[[], Callable[[], int]]:
    from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

    dt = float(rec["dt"][0])
    z = [row for row in rec["acc_meas"] / G]
    omega = [tuple(row) for row in rec["gyro_meas"].tolist()]

    def make() -> Callable[[], int]:
        points = MerweScaledSigmaPoints(3, alpha=1.0, beta=2.0, kappa=0.0)
        ukf = UnscentedKalmanFilter(3, 3, dt, hx=lambda x: x, fx=_rotate_gravity, points=points)
        ukf.x = z[0] / np.linalg.norm(z[0])
        ukf.P *= 0.06**2
        ukf.Q = np.eye(3) * (0.05 * math.pi / 180) ** 2 * dt
        ukf.R = np.eye(3) * 0.06**2
        predict, update = ukf.predict, ukf.update

        def run() -> int:
            for zi, wi in zip(z, omega, strict=True):
                predict(omega=wi)
                update(zi)
            return len(z)

        return run

    return make


def _ahrs(name: str, rec: dict[str, np.ndarray]) -> Callable[[], Callable[[], int]]:
    from ahrs.filters import EKF, Madgwick, Mahony

    acc = [row for row in rec["acc_meas"]]
    gyro = [row for row in rec["gyro_meas"]]
    q0 = np.array([1.0, 0.0, 0.0, 0.0])

    def make() -> Callable[[], int]:
        if name == "ahrs_ekf":
            f = EKF(frequency=RATE_HZ, frame="ENU")

            def update(q: np.ndarray, g: np.ndarray, a: np.ndarray) -> np.ndarray:
                return f.update(q, g, a)
        else:
            f = (Mahony if name == "ahrs_mahony" else Madgwick)(frequency=RATE_HZ)
            update = f.updateIMU

        def run() -> int:
            q = q0
            for a, g in zip(acc, gyro, strict=True):
                q = update(q, g, a)
            return len(acc)

        return run

    return make


def _imufusion(rec: dict[str, np.ndarray]) -> Callable[[], Callable[[], int]]:
    import imufusion

    acc = [np.ascontiguousarray(row) for row in rec["acc_meas"] / G]
    gyro = [np.ascontiguousarray(row) for row in np.degrees(rec["gyro_meas"])]
    dt = float(rec["dt"][0])

    def make() -> Callable[[], int]:
        ahrs = imufusion.Ahrs()
        ahrs.set_sample_period(dt)
        return _sample_loop(ahrs.update_no_magnetometer, gyro, acc)

    return make



def _sample_loop(
    update: Callable[[np.ndarray, np.ndarray], object], gyro: list, acc: list
) -> Callable[[], int]:
    """One timed pass: update(gyro, acc) per sample, in a loop of its own (no extra call per
    sample); returns the number of samples."""

    def run() -> int:
        for g, a in zip(gyro, acc, strict=True):
            update(g, a)
        return len(acc)

    return run


def _vqf(rec: dict[str, np.ndarray]) -> Callable[[], Callable[[], int]]:
    from vqf import VQF

    acc = [np.ascontiguousarray(row) for row in rec["acc_meas"]]
    gyro = [np.ascontiguousarray(row) for row in rec["gyro_meas"]]
    dt = float(rec["dt"][0])

    def make() -> Callable[[], int]:
        return _sample_loop(VQF(dt).update, gyro, acc)

    return make


def peer_pass_factory(name: str, rec: dict[str, np.ndarray]) -> Callable[[], Callable[[], int]]:
    """The pass factory of one peer (ImportError or any other error if it cannot run)."""
    if name == "filterpy_ukf":
        return _filterpy_ukf(rec)
    if name.startswith("ahrs_"):
        return _ahrs(name, rec)
    if name == "imufusion":
        return _imufusion(rec)
    if name == "vqf":
        return _vqf(rec)
    raise ValueError(f"unknown peer {name!r}: allowed {', '.join(PEERS)}")


def available_peers(
    rec: dict[str, np.ndarray], names: tuple[str, ...] = PEERS
) -> tuple[dict[str, Callable[[], Callable[[], int]]], dict[str, str]]:
    """Pass factories of the peers that run on this recording (each has made one untimed
    pass), and {peer: reason} for those that are unavailable."""
    factories: dict[str, Callable[[], Callable[[], int]]] = {}
    unavailable: dict[str, str] = {}
    for name in names:
        try:
            factory = peer_pass_factory(name, rec)
            factory()()
            factories[name] = factory
        except Exception as err:  # a missing or broken peer must not end the benchmark
            unavailable[name] = f"{type(err).__name__}: {err}"
    return factories, unavailable


def per_sample_peers(
    rec: dict[str, np.ndarray], repeats: int, names: tuple[str, ...] = PEERS
) -> tuple[dict[str, dict[str, Any]], dict[str, str]]:
    """us per update call of each available peer, and {peer: reason} for the others."""
    factories, unavailable = available_peers(rec, names)
    return time_interleaved(factories, repeats), unavailable
