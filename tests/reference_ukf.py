"""The paper's UKF written with numpy: the reference for test_ukf_equivalence.

Numpy on 6x6 matrices, 13 sigma points as rows, and the textbook update without the
pseudo-measurement row |X|^2 = 1 where norm_noise is 0. Parameters (names, defaults, ranges) are
taken from fusion_core's PaperUnscentedKalmanFilter, so the two always run with the same values.
"""

from __future__ import annotations

import math

import numpy as np

from fusion_core.base import Estimator
from fusion_core.papers import PaperUnscentedKalmanFilter
from fusion_core.types import Estimate, G

N_STATE = 6  # X (3), gyro bias b (3)


class ReferenceUnscentedKalmanFilter(Estimator):
    """fusion_core.papers.PaperUnscentedKalmanFilter written with numpy (see the module
    docstring)."""

    PARAMS = PaperUnscentedKalmanFilter.PARAMS
    COMMON = PaperUnscentedKalmanFilter.COMMON
    STATE = ("x", "P")

    def _configure(self) -> None:
        p = self._params
        n = N_STATE
        lam = p["alpha"] ** 2 * (n + p["kappa"]) - n
        self._gamma = math.sqrt(n + lam)
        wm = np.full(2 * n + 1, 0.5 / (n + lam))
        wc = wm.copy()
        wm[0] = lam / (n + lam)
        wc[0] = wm[0] + 1.0 - p["alpha"] ** 2 + p["beta"]
        self._wm, self._wc = wm, wc
        self._q_gyro = p["gyro_psd"]
        self._q_bias = p["bias_psd"]
        self._norm_row = p["norm_noise"] > 0.0
        self._R = np.diag([p["acc_noise"] ** 2] * 3 + [p["norm_noise"] ** 2] * self._norm_row)
        self._gate = p["acc_gate"]
        self._trapezoid = p["gyro_sampling"] == "point"

    def _reset(self) -> None:
        self.x = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        self.P = np.zeros((N_STATE, N_STATE)).tolist()

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        n = math.sqrt(ax * ax + ay * ay + az * az)
        self.x = [ax / n, ay / n, az / n, 0.0, 0.0, 0.0]
        p_x = self._params["acc_noise"] ** 2
        p_b = self._params["init_bias_std"] ** 2
        self.P = np.diag([p_x] * 3 + [p_b] * 3).tolist()

    def _sigma_points(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        S = _sqrt_psd(P) * self._gamma
        return np.vstack([x, x + S.T, x - S.T])

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        x = np.asarray(self.x)
        P = np.asarray(self.P)
        chi = self._sigma_points(x, P)
        b = chi[:, 3:]
        w1 = np.array([gx, gy, gz]) - b
        if self._trapezoid:
            w0 = np.asarray(self.gyro_prev) - b
            phi = 0.5 * (w0 + w1) * dt + np.cross(w0 * dt, w1 * dt) / 12.0
        else:
            phi = w1 * dt
        chi[:, :3] = _rotate_back(chi[:, :3], phi)
        x_pred = self._wm @ chi
        d = chi - x_pred
        P_pred = (d.T * self._wc) @ d
        X = x_pred[:3] / np.linalg.norm(x_pred[:3])
        P_pred[:3, :3] += self._q_gyro * dt * (np.eye(3) - np.outer(X, X))
        P_pred[3:, 3:] += self._q_bias * dt * np.eye(3)
        rho = abs(math.sqrt(ax * ax + ay * ay + az * az) / G - 1.0)
        if rho < self._gate:
            Z = chi[:, :3]
            if self._norm_row:
                Z = np.column_stack([Z, np.einsum("ij,ij->i", chi[:, :3], chi[:, :3])])
            z_pred = self._wm @ Z
            dz = Z - z_pred
            S = (dz.T * self._wc) @ dz + self._R
            Pxz = (d.T * self._wc) @ dz
            K = np.linalg.solve(S, Pxz.T).T
            z = np.array([ax / G, ay / G, az / G, 1.0][:Z.shape[1]])
            x_pred = x_pred + K @ (z - z_pred)
            P_pred = P_pred - K @ S @ K.T
        x_pred[:3] /= np.linalg.norm(x_pred[:3])
        self.x = x_pred.tolist()
        self.P = (0.5 * (P_pred + P_pred.T)).tolist()

    def _estimate(self) -> Estimate:
        X1, X2, X3, bx, by, bz = self.x
        return Estimate(math.atan2(X2, X3), math.atan2(-X1, math.hypot(X2, X3)), (bx, by, bz))


def _rotate_back(X: np.ndarray, phi: np.ndarray) -> np.ndarray:
    angle = np.linalg.norm(phi, axis=1)
    small = angle < 1e-8
    safe = np.where(small, 1.0, angle)
    sin_a = np.where(small, 1.0 - angle**2 / 6.0, np.sin(angle) / safe)
    cos_a = np.where(small, 0.5 - angle**2 / 24.0, (1.0 - np.cos(angle)) / safe**2)
    cross = np.cross(phi, X)
    return X - sin_a[:, None] * cross + cos_a[:, None] * np.cross(phi, cross)


def _sqrt_psd(P: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(0.5 * (P + P.T))
        return V * np.sqrt(np.clip(w, 0.0, None))
