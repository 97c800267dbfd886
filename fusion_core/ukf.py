"""Unscented Kalman filter on the gravity direction, augmented with the gyro bias.

Reference:
  Duong Quoc et al., eq. 14-17: the state is the gravity direction in the body frame,
  X = [-sin(theta), sin(phi) cos(theta), cos(phi) cos(theta)] (the accelerometer reading of a
  sensor at rest divided by g, INTERFACE.md), propagated by the gyro and observed through the
  measurement [acc/g; |X|^2 = 1]; roll and pitch follow from X as from a resting accelerometer.
  Scaled sigma points: Wan & van der Merwe (2000), "The unscented Kalman filter for nonlinear
  estimation" (alpha, beta, kappa).

Process model, in this project's frame. X is the world up axis e_z expressed in body axes,
X = R^T e_z with R body-to-world. Since R_dot = R [omega]x, d(R^T)/dt = -[omega]x R^T, so
  X_dot = -omega x X = X x omega,   omega = gyro - b  (b: gyro bias, a random walk).
(The paper writes the same equation for a z-down frame; the sign is the one above for the
specific-force direction with z up.) Over one interval the body turns by the rotation vector
phi (trapezoid rate plus coning correction), so X_{k+1} = exp(-[phi]x) X_k exactly (Rodrigues).
"""

from __future__ import annotations

import math

import numpy as np

from .base import INTEGRATION_PARAM, Estimator
from .types import DEG, Estimate, G, Param

N_STATE = 6  # X (3), gyro bias b (3)


class UnscentedKalmanFilter(Estimator):
    """Duong Quoc et al. UKF (gravity direction) with three gyro-bias states.

    State x = [X (3), b (3)]; covariance P (6x6).
    Predict: each sigma point is rotated by its own bias-corrected rotation increment
      (exp(-[phi_i]x) X_i), b_i unchanged; Q = gyro_noise^2 dt (I - X X^T) for X (the gyro noise
      turns X only perpendicular to itself) and bias_noise^2 dt I for b.
    Update: z = [acc/g; 1], h(x) = [X; |X|^2], R = diag(acc_noise^2 I3, norm_noise^2); the
      accelerometer update is skipped while rho = ||acc|/g - 1| >= acc_gate (the accelerometer
      then measures more than gravity). After the update X is renormalised to unit length.
    Defaults (ours; the paper's values are not in our sources): gyro_noise 10x the MPU-6050
    density (it also absorbs integration and model error), acc_noise 0.06 (white noise plus an
    allowance for unmodelled linear acceleration), acc_gate 0.1 (10 % of g along gravity is
    certainly not gravity; 3 % scale-factor error of an uncalibrated sensor still passes).
    Measured on moderate_dynamics: RMSE 0.21/0.37 deg (0.43/0.63 with acc_noise 0.03 and the
    gate at Duong Quoc's 0.35).
    Output: roll = atan2(X2, X3), pitch = atan2(-X1, sqrt(X2^2 + X3^2)); bias = b.

    Parameters: gyro_noise [rad/s/sqrt(Hz)], bias_noise [rad/s/sqrt(s)], acc_noise [1]
    (standard deviation of acc/g, white noise and unmodelled acceleration), norm_noise [1],
    acc_gate [1], init_bias_std [rad/s], alpha, beta, kappa, integration, max_dt [s].
    """

    PARAMS = (
        Param(
            "gyro_noise", 0.05 * DEG,
            "Gyro white-noise density driving the gravity direction (process noise)",
            unit="rad/(s.sqrt(Hz))", low=0.0, low_open=True,
        ),
        Param(
            "bias_noise", 0.002 * DEG,
            "Gyro bias random-walk density (process noise of the bias states)",
            unit="rad/(s.sqrt(s))", low=0.0,
        ),
        Param(
            "acc_noise", 0.06,
            "Standard deviation of one accelerometer sample divided by g (noise and unmodelled "
            "linear acceleration)",
            low=0.0, low_open=True,
        ),
        Param(
            "norm_noise", 0.01, "Standard deviation of the unit-norm pseudo-measurement |X|^2 = 1",
            low=0.0, low_open=True,
        ),
        Param(
            "acc_gate", 0.1,
            "Skip the accelerometer update while ||acc|/g - 1| is at or above this value",
            low=0.0, low_open=True,
        ),
        Param(
            "init_bias_std", 1.0 * DEG, "Initial standard deviation of each gyro-bias state",
            unit="rad/s", low=0.0, low_open=True, tunable=False,
        ),
        Param("alpha", 1.0, "Sigma-point spread (scaled unscented transform)", low=0.0,
              low_open=True, high=1.0),
        Param("beta", 2.0, "Prior-distribution parameter (2 is optimal for Gaussians)", low=0.0),
        Param("kappa", 0.0, "Secondary scaling parameter (> -5 keeps n + lambda > 0 for n = 6)",
              low=-5.0, low_open=True),
        INTEGRATION_PARAM,
    )
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
        self._q_gyro = p["gyro_noise"] ** 2
        self._q_bias = p["bias_noise"] ** 2
        self._R = np.diag([p["acc_noise"] ** 2] * 3 + [p["norm_noise"] ** 2])
        self._gate = p["acc_gate"]
        self._trapezoid = p["integration"] == "trapezoid"

    def _reset(self) -> None:
        self.x = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        self.P = np.zeros((N_STATE, N_STATE)).tolist()

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        n = math.sqrt(ax * ax + ay * ay + az * az)
        self.x = [ax / n, ay / n, az / n, 0.0, 0.0, 0.0]
        # X from one accelerometer sample: its noise, per axis; b: the prior on the bias.
        p_x = self._params["acc_noise"] ** 2
        p_b = self._params["init_bias_std"] ** 2
        self.P = np.diag([p_x] * 3 + [p_b] * 3).tolist()

    def _sigma_points(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        """2n+1 sigma points x, x +- gamma * columns of sqrt(P) (rows of the result)."""
        S = _sqrt_psd(P) * self._gamma
        return np.vstack([x, x + S.T, x - S.T])

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        x = np.asarray(self.x)
        P = np.asarray(self.P)
        # ---- predict (eq. 14-15): sigma points through X_{k+1} = exp(-[phi]x) X_k
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
        # ---- update (eq. 16-17): z = [acc/g; 1], h = [X; |X|^2]
        rho = abs(math.sqrt(ax * ax + ay * ay + az * az) / G - 1.0)
        if rho < self._gate:
            Z = np.column_stack([chi[:, :3], np.einsum("ij,ij->i", chi[:, :3], chi[:, :3])])
            z_pred = self._wm @ Z
            dz = Z - z_pred
            S = (dz.T * self._wc) @ dz + self._R
            Pxz = (d.T * self._wc) @ dz
            K = np.linalg.solve(S, Pxz.T).T
            z = np.array([ax / G, ay / G, az / G, 1.0])
            x_pred = x_pred + K @ (z - z_pred)
            P_pred = P_pred - K @ S @ K.T
        x_pred[:3] /= np.linalg.norm(x_pred[:3])
        self.x = x_pred.tolist()
        self.P = (0.5 * (P_pred + P_pred.T)).tolist()

    def _estimate(self) -> Estimate:
        X1, X2, X3, bx, by, bz = self.x
        return Estimate(math.atan2(X2, X3), math.atan2(-X1, math.hypot(X2, X3)), (bx, by, bz))


def _rotate_back(X: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Rows X_i rotated by exp(-[phi_i]x) (Rodrigues): a world-fixed vector seen from a body that
    turned by phi_i."""
    angle = np.linalg.norm(phi, axis=1)
    small = angle < 1e-8
    safe = np.where(small, 1.0, angle)
    sin_a = np.where(small, 1.0 - angle**2 / 6.0, np.sin(angle) / safe)  # sin(a)/a
    cos_a = np.where(small, 0.5 - angle**2 / 24.0, (1.0 - np.cos(angle)) / safe**2)  # (1-cos)/a^2
    cross = np.cross(phi, X)
    return X - sin_a[:, None] * cross + cos_a[:, None] * np.cross(phi, cross)


def _sqrt_psd(P: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of P; for a P that rounding made indefinite, the symmetric square
    root with negative eigenvalues clipped to zero (never raises for a finite P)."""
    try:
        return np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(0.5 * (P + P.T))
        return V * np.sqrt(np.clip(w, 0.0, None))
