"""Public 6D orientation filters run beside ours (the `bench` extra): VQF, Madgwick, Mahony, on
BROAD (`testbenches broad --peers`) and on the contract's own samples (`testbenches run --peers`,
peer_runs). Each returns the estimated up direction in the sensor frame, [N, 3].

- VQF: D. Laidig, T. Seel. "VQF: Highly Accurate IMU Orientation Estimation with Bias Estimation
  and Magnetic Disturbance Rejection". Information Fusion 91:187-204, 2023. The `vqf` package's
  causal filter (`VQF.updateBatch`, its defaults), 6D quaternion `quat6D`. Not `offlineVQF`,
  which also looks at future samples.
- ahrs-madgwick: S. Madgwick, A. Harrison, R. Vaidyanathan. "Estimation of IMU and MARG
  orientation using a gradient descent algorithm". ICORR 2011. `ahrs.filters.Madgwick`, IMU
  form, its default gain 0.033.
- ahrs-mahony: R. Mahony, T. Hamel, J.-M. Pflimlin. "Nonlinear complementary filters on the special
  orthogonal group". IEEE TAC 53(5), 2008. `ahrs.filters.Mahony`, IMU form, its defaults
  k_P = 1, k_I = 0.3.

Conventions, checked against the packages' code: all three take gyro in rad/s and the
accelerometer in m/s^2 (only its direction is used) and expect a resting accelerometer to read
+g along the sensor's up axis, as BROAD and we do; their quaternion (w first) rotates sensor
coordinates into a z-up earth frame, so the up direction in the sensor frame is R(q)^T e_z, the
same formula as for BROAD's reference (ahrs's NED option concerns only its magnetometer forms).
The filters' heading is arbitrary, which the inclination metric ignores. Madgwick and Mahony
start from the first accelerometer sample (ahrs's `acc2q`), VQF from its own first sample.

On recordings whose sensor lags the reference (BROAD: sensor_delay 2.4 ms) `vqf-ahead` is VQF
with its output turned ahead over that delay by its own bias-corrected rate, the prediction our
estimators' sensor_delay makes: the comparison with the same help, beside VQF as published.

The packages are imported only when a peer runs; a missing one raises PeerUnavailable with the
pip command.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np

from .broad.metric import gravity_from_quat

PEER_INSTALL = "pip install 'vqf>=2.0' 'ahrs>=0.3.1'  (or: pip install -e '.[bench]')"


class PeerUnavailable(RuntimeError):
    """A peer's package is not installed."""


def _import(module: str, what: str) -> ModuleType:
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise PeerUnavailable(
            f"{what} needs the Python package {module.split('.')[0]!r}, which is not installed "
            f"({err}); install the peers with: {PEER_INSTALL}"
        ) from None


def _vqf_batch(acc: np.ndarray, gyro: np.ndarray, rate: float, what: str) -> dict[str, Any]:
    """VQF's updateBatch with the package's defaults on the recording (quat6D, bias, ...)."""
    vqf = _import("vqf", what)
    f = vqf.VQF(1.0 / rate)
    return dict(f.updateBatch(np.ascontiguousarray(gyro, dtype=float),
                              np.ascontiguousarray(acc, dtype=float)))


def run_vqf(acc: np.ndarray, gyro: np.ndarray, rate: float) -> np.ndarray:
    """VQF 6D with the package's defaults: up direction [N, 3]."""
    return gravity_from_quat(_vqf_batch(acc, gyro, rate, "the VQF peer")["quat6D"])


class VqfStream:
    """VQF 6D with the package's defaults run block after block, its state carried from one
    block to the next (so the blocks of a recording give what run_vqf gives on the whole):
    calling it with acc, gyro [n, 3] gives the block's up direction [n, 3]."""

    def __init__(self, rate: float) -> None:
        self._filter = _import("vqf", "the VQF peer").VQF(1.0 / rate)

    def __call__(self, acc: np.ndarray, gyro: np.ndarray) -> np.ndarray:
        if len(acc) == 0:
            return np.empty((0, 3))
        out = self._filter.updateBatch(np.ascontiguousarray(gyro, dtype=float),
                                       np.ascontiguousarray(acc, dtype=float))
        return gravity_from_quat(out["quat6D"])


def up_ahead(up: np.ndarray, rate: np.ndarray, delay: float) -> np.ndarray:
    """The up direction [N, 3] in the sensor frame delay [s] later, the sensor turning at rate
    [N, 3] rad/s (its frame): a direction fixed in the world turns by -rate * delay in it."""
    from scipy.spatial.transform import Rotation

    return np.asarray(Rotation.from_rotvec(-np.asarray(rate) * delay).apply(up))


def run_vqf_ahead(acc: np.ndarray, gyro: np.ndarray, rate: float, delay: float) -> np.ndarray:
    """VQF 6D as run_vqf, its up direction turned ahead over the sensor's delay [s] by the gyro
    minus VQF's bias estimate (up_ahead): up direction [N, 3]."""
    out = _vqf_batch(acc, gyro, rate, "the vqf-ahead peer")
    return up_ahead(gravity_from_quat(out["quat6D"]), gyro - out["bias"], delay)


def run_madgwick(acc: np.ndarray, gyro: np.ndarray, rate: float) -> np.ndarray:
    """ahrs Madgwick (IMU) with its default gain: up direction [N, 3]."""
    filters = _import("ahrs.filters", "the Madgwick peer")
    f = filters.Madgwick(gyr=np.asarray(gyro, float), acc=np.asarray(acc, float), frequency=rate)
    return gravity_from_quat(f.Q)


def run_mahony(acc: np.ndarray, gyro: np.ndarray, rate: float) -> np.ndarray:
    """ahrs Mahony (IMU) with its default gains: up direction [N, 3]."""
    filters = _import("ahrs.filters", "the Mahony peer")
    f = filters.Mahony(gyr=np.asarray(gyro, float), acc=np.asarray(acc, float), frequency=rate)
    return gravity_from_quat(f.Q)


PEERS: dict[str, Callable[[np.ndarray, np.ndarray, float], np.ndarray]] = {
    "vqf": run_vqf,
    "ahrs-madgwick": run_madgwick,
    "ahrs-mahony": run_mahony,
}
"""Peer name -> run(acc [N, 3], gyro [N, 3], rate [Hz]) -> up direction [N, 3]. A peer is named
after the package it runs where the filter's name could be an estimator's key (fusion_core's
registry has a madgwick of its own); tests/test_peers.py holds the names apart."""

AHEAD_PEERS: dict[str, Callable[[np.ndarray, np.ndarray, float, float], np.ndarray]] = {
    "vqf-ahead": run_vqf_ahead,
}
"""Peers for recordings that state their sensor's delay: run(acc, gyro, rate, delay [s])."""


def check_peers(names: list[str]) -> None:
    """Raise PeerUnavailable (with the pip command) unless every named peer can be imported."""
    modules = {"vqf": "vqf", "vqf-ahead": "vqf", "ahrs-madgwick": "ahrs.filters",
               "ahrs-mahony": "ahrs.filters"}
    for name in names:
        _import(modules[name], f"the {name} peer")


__all__ = ["AHEAD_PEERS", "PEERS", "PEER_INSTALL", "PeerUnavailable", "check_peers"]
