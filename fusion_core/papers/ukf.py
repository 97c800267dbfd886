"""The paper's unscented Kalman filter on the gravity direction, augmented with the gyro bias.

Reference:
  Duong Quoc et al., eq. 14-17: the state is the gravity direction in the body frame,
  X = [-sin(theta), sin(phi) cos(theta), cos(phi) cos(theta)] (the accelerometer reading of a
  sensor at rest divided by g, docs/interface.md), propagated by the gyro and observed through the
  measurement [acc/g; |X|^2 = 1]; roll and pitch follow from X as from a resting accelerometer.
  Scaled sigma points: Wan & van der Merwe (2000), "The unscented Kalman filter for nonlinear
  estimation" (alpha, beta, kappa).

Process model, in this project's frame. X is the world up axis e_z expressed in body axes,
X = R^T e_z with R body-to-world. Since R_dot = R [omega]x, d(R^T)/dt = -[omega]x R^T, so
  X_dot = -omega x X = X x omega,   omega = gyro - b  (b: gyro bias, a random walk).
(The paper writes the same equation for a z-down frame; the sign is the one above for the
specific-force direction with z up.) Over one interval the body turns by the rotation vector
phi (trapezoid rate plus coning correction), so X_{k+1} = exp(-[phi]x) X_k exactly (Rodrigues).

Implementation: plain floats, no matrices. It computes the same unscented transform as a
textbook implementation (13 sigma points, every one through the exact process model; the
tests compare it with the numpy version to 1e-9), using identities that hold exactly:
  - sigma points x +- gamma s_j, s_j the columns of the Cholesky factor of P (n = 6);
  - phi is affine in the bias: with w0 = g0 - b, w1 = g1 - b,
      phi(b) = (w0 + w1) dt/2 + (w0 dt x w1 dt)/12 = c - M b,
      c = (g0 + g1) dt/2 + (dt^2/12) g0 x g1,  M v = dt v - (dt^2/12) (g1 - g0) x v,
    so the pair x +- gamma s_j turns by phi(b) -+ M s_j^b (one M product per pair);
  - the bias part of each sigma point is not transformed: its mean is b and its covariance
    P_bb (2 wc gamma^2 = 1 and wm0 + 2n wm = 1), and the X-b cross covariance is
    wc sum_j (Y_j+ - Y_j-) (s_j^b)^T (Y: rotated X parts; the mean cancels);
  - with e_i = Y_i - Y_0 (deviations from the rotated central point, small numbers) and
    mu = wm sum e_i, the mean is Y_0 + mu and
      P_XX = wc sum e_i e_i^T + (beta - alpha^2) mu mu^T
    (the weights wm_i = wc_i for i >= 1 and sum wc_i = 2 - alpha^2 + beta);
  - a rotation keeps the norm, so the pseudo-measurement |Y_i|^2 = |X_i|^2 is known before the
    rotation: |X +- s|^2 - |X|^2 = +-2 X.s + |s|^2;
  - the measurement prediction of the X part is the state's X part, so S[:3, :3] and
    P_xz[:, :3] are the predicted covariance (before Q) plus R, and K S K^T = P_xz S^-1 P_xz^T
    = Y^T Y with Y = L_S^-1 P_xz^T (L_S the Cholesky factor of S).
P is kept as its lower triangle (21 floats, row by row); the `P` attribute shows it as a full
6x6 list of lists.

One sample is the paper's equations in turn, each a function the recommended filter
(fusion_core.ukf) is built on too: rotation_terms (the interval's rotation, eq. 14),
sigma_predict (the unscented transform of the process model, eq. 14-15), predicted_covariance
(its covariance plus Q, eq. 15), measurement_update (eq. 16-17).
"""

from __future__ import annotations

import math
from typing import ClassVar, Final, NamedTuple

from ..base import Estimator
from ..kinematics import accel_roll_pitch, rotate_back
from ..linalg import (
    cholesky4,
    packed,
    packed_diagonal,
    packed_index,
    sigma_offsets,
    unpacked,
)
from ..state import COV, REAL, UNIT, Segments, StateSpec
from ..types import DEG, MPU6050_GYRO_DENSITY, Estimate, G, Param
from .common import PAPER_COMMON, Vec3

N_STATE: Final = 6  # X (3), gyro bias b (3)
UpdateResult = tuple[float, float, float, float, float, float, tuple[float, ...]]
"""The updated state x (6 floats) and the packed covariance P (21 floats)."""
RotationTerms = tuple[float, float, float, float, float, float]
"""c (3) and the coefficients d (3) of phi(b) = c - M b, M v = dt v - d x v (module docstring)."""


def rotation_terms(prev: Vec3, g: Vec3, dt: float, trapezoid: bool) -> RotationTerms:
    """The interval's rotation vector as an affine function of the bias (eq. 14): c and d of
    phi(b) = c - M b with M v = dt v - d x v. The trapezoid rate with the coning term between
    the previous sample prev and this one g, or the papers' rule phi = (g - b) dt (d = 0)."""
    gx, gy, gz = g
    if trapezoid:
        h0, h1, h2 = prev
        k = dt * dt / 12.0
        hdt = 0.5 * dt
        return (hdt * (h0 + gx) + k * (h1 * gz - h2 * gy),
                hdt * (h1 + gy) + k * (h2 * gx - h0 * gz),
                hdt * (h2 + gz) + k * (h0 * gy - h1 * gx),
                k * (gx - h0), k * (gy - h1), k * (gz - h2))
    return gx * dt, gy * dt, gz * dt, 0.0, 0.0, 0.0


class Prediction(NamedTuple):
    """The unscented transform of one sample's process model (sigma_predict): the predicted
    mean of X, its covariance before Q (A, packed 3x3), the weighted X-b cross terms (C, row by
    row), the mean deviation mu and, for the unit-norm pseudo-measurement, |X_0|^2 and the
    sums of nu = |X_i|^2 - |X_0|^2 over the sigma points."""

    X: tuple[float, float, float]
    A: tuple[float, float, float, float, float, float]
    C: tuple[float, float, float, float, float, float, float, float, float]
    mu: tuple[float, float, float]
    v_prior: float
    v_sum: float
    vv: float
    ev: tuple[float, float, float]
    bv: tuple[float, float, float]


def sigma_predict(x: list[float], P: tuple[float, ...], terms: RotationTerms, dt: float,
                  gamma: float, w: float, w_mu: float, norm_row: bool) -> Prediction:
    """Eq. 14-15: every sigma point x +- gamma s_j through X_{k+1} = exp(-[phi]x) X_k, with
    phi(b) = c - M b (rotation_terms); b is unchanged. norm_row: also the sums of the unit-norm
    pseudo-measurement |X|^2 = 1 (eq. 16's second row)."""
    X0, X1, X2, b0, b1, b2 = x
    offsets = sigma_offsets(P, gamma)  # gamma s_j, j = 1..6
    c0, c1, c2, d0, d1, d2 = terms
    f0 = c0 - (dt * b0 - (d1 * b2 - d2 * b1))
    f1 = c1 - (dt * b1 - (d2 * b0 - d0 * b2))
    f2 = c2 - (dt * b2 - (d0 * b1 - d1 * b0))
    Y0, Y1, Y2 = rotate_back((X0, X1, X2), (f0, f1, f2))  # the central point
    # Sums over the outer points, e = Y_i - Y_0: sum e (m), sum e e^T (e..),
    # sum_j (e_j+ - e_j-) (s_j^b)^T (x..), and for the pseudo-measurement
    # nu = |X_i|^2 - |X_0|^2 = +-2 X_0.s + |s|^2: sum nu, sum nu^2, sum e nu,
    # sum_j (nu_j+ - nu_j-) s_j^b (nu = 0 for the Cholesky columns 4-6, whose X part is 0).
    m0 = m1 = m2 = 0.0
    e00 = e10 = e11 = e20 = e21 = e22 = 0.0
    x00 = x01 = x02 = x10 = x11 = x12 = x20 = x21 = x22 = 0.0
    v_sum = vv = ev0 = ev1 = ev2 = bv0 = bv1 = bv2 = 0.0
    for s0, s1, s2, s3, s4, s5 in offsets:
        t0 = dt * s3 - (d1 * s5 - d2 * s4)  # M s^b
        t1 = dt * s4 - (d2 * s3 - d0 * s5)
        t2 = dt * s5 - (d0 * s4 - d1 * s3)
        # x + s and x - s through the process model, as deviations from the central point
        r0, r1, r2 = rotate_back((X0 + s0, X1 + s1, X2 + s2), (f0 - t0, f1 - t1, f2 - t2))
        ep0, ep1, ep2 = r0 - Y0, r1 - Y1, r2 - Y2
        r0, r1, r2 = rotate_back((X0 - s0, X1 - s1, X2 - s2), (f0 + t0, f1 + t1, f2 + t2))
        em0, em1, em2 = r0 - Y0, r1 - Y1, r2 - Y2
        m0 += ep0 + em0
        m1 += ep1 + em1
        m2 += ep2 + em2
        e00 += ep0 * ep0 + em0 * em0
        e10 += ep1 * ep0 + em1 * em0
        e11 += ep1 * ep1 + em1 * em1
        e20 += ep2 * ep0 + em2 * em0
        e21 += ep2 * ep1 + em2 * em1
        e22 += ep2 * ep2 + em2 * em2
        u0, u1, u2 = ep0 - em0, ep1 - em1, ep2 - em2
        x00 += u0 * s3
        x01 += u0 * s4
        x02 += u0 * s5
        x10 += u1 * s3
        x11 += u1 * s4
        x12 += u1 * s5
        x20 += u2 * s3
        x21 += u2 * s4
        x22 += u2 * s5
        if norm_row and (s0 or s1 or s2):
            a = 2.0 * (X0 * s0 + X1 * s1 + X2 * s2)
            q = s0 * s0 + s1 * s1 + s2 * s2
            vp, vm = q + a, q - a
            v_sum += vp + vm
            vv += vp * vp + vm * vm
            ev0 += ep0 * vp + em0 * vm
            ev1 += ep1 * vp + em1 * vm
            ev2 += ep2 * vp + em2 * vm
            a = vp - vm
            bv0 += a * s3
            bv1 += a * s4
            bv2 += a * s5
    mu0, mu1, mu2 = w * m0, w * m1, w * m2
    return Prediction(
        (Y0 + mu0, Y1 + mu1, Y2 + mu2),  # the predicted mean of X; b is unchanged
        # the unscented covariance of X (A) and of b with X (C), before the process noise
        (w * e00 + w_mu * mu0 * mu0, w * e10 + w_mu * mu1 * mu0, w * e11 + w_mu * mu1 * mu1,
         w * e20 + w_mu * mu2 * mu0, w * e21 + w_mu * mu2 * mu1, w * e22 + w_mu * mu2 * mu2),
        (w * x00, w * x01, w * x02, w * x10, w * x11, w * x12, w * x20, w * x21, w * x22),
        (mu0, mu1, mu2),
        X0 * X0 + X1 * X1 + X2 * X2,  # |X_0|^2 (1 but for rounding)
        v_sum, vv, (ev0, ev1, ev2), (bv0, bv1, bv2),
    )


def predicted_covariance(pred: Prediction, P: tuple[float, ...], h: Vec3, qg: float,
                         qb: float) -> tuple[float, ...]:
    """Eq. 15: the predicted covariance (packed) with Q = qg (I - h h^T) for X (the gyro noise
    turns X only perpendicular to itself; h the predicted X normalised) and qb I for b."""
    a00, a10, a11, a20, a21, a22 = pred.A
    x00, x01, x02, x10, x11, x12, x20, x21, x22 = pred.C
    h0, h1, h2 = h
    return (
        a00 + qg * (1.0 - h0 * h0),
        a10 - qg * (h1 * h0), a11 + qg * (1.0 - h1 * h1),
        a20 - qg * (h2 * h0), a21 - qg * (h2 * h1), a22 + qg * (1.0 - h2 * h2),
        x00, x10, x20, P[9] + qb,
        x01, x11, x21, P[13], P[14] + qb,
        x02, x12, x22, P[18], P[19], P[20] + qb,
    )


def measurement_update(pred: Prediction, b: Vec3, P: tuple[float, ...], acc: Vec3, r: float,
                       w: float, w_mu: float, r_norm: float | None, learn_bias: bool
                       ) -> UpdateResult:
    """Eq. 16-17: z = [acc/g; 1], h = [X; |X|^2], R = diag(r I3, r_norm) (r_norm None: no
    pseudo-measurement, z = acc/g and h = X alone). S = [[A + r I, s_v], [s_v^T, s_vv + r_norm]],
    P_xz = [[A, s_v], [C, c_v]]; kalman_update (the bias states as consider states, unchanged,
    unless learn_bias)."""
    ax, ay, az = acc
    X0, X1, X2 = pred.X
    mu0, mu1, mu2 = pred.mu
    a00, a10, a11, a20, a21, a22 = pred.A
    x00, x01, x02, x10, x11, x12, x20, x21, x22 = pred.C
    ev0, ev1, ev2 = pred.ev
    bv0, bv1, bv2 = pred.bv
    mu_v = w * pred.v_sum
    sv0 = w * ev0 + w_mu * mu0 * mu_v
    sv1 = w * ev1 + w_mu * mu1 * mu_v
    sv2 = w * ev2 + w_mu * mu2 * mu_v
    if r_norm is not None:
        s33 = w * pred.vv + w_mu * mu_v * mu_v + r_norm
        y3 = 1.0 - (pred.v_prior + mu_v)
    else:  # no pseudo-measurement: with its sums 0, s33 = 1 and a zero innovation the last
        # row is independent of the others and changes nothing (exactly)
        s33, y3 = 1.0, 0.0
    S = (a00 + r, a10, a11 + r, a20, a21, a22 + r, sv0, sv1, sv2, s33)
    rows = (
        (a00, a10, a20, sv0), (a10, a11, a21, sv1), (a20, a21, a22, sv2),
        (x00, x10, x20, w * bv0), (x01, x11, x21, w * bv1), (x02, x12, x22, w * bv2),
    )
    innovation = (ax / G - X0, ay / G - X1, az / G - X2, y3)
    return kalman_update((X0, X1, X2, b[0], b[1], b[2]), P, S, rows, innovation, learn_bias)


def unscented_constants(alpha: float, beta: float, kappa: float) -> tuple[float, float, float]:
    """gamma, w and w_mu of the scaled sigma points (Wan & van der Merwe): lambda =
    alpha^2 (n + kappa) - n, gamma = sqrt(n + lambda); wm_0 = lambda/(n + lambda),
    wc_0 = wm_0 + 1 - alpha^2 + beta, wm_i = wc_i = w = 1/(2(n + lambda)) for i = 1..2n.
    Deviations are taken from the central point, so only w and (sum of wc) - 2 =
    w_mu = beta - alpha^2 appear (module docstring)."""
    n = N_STATE
    alpha2 = alpha ** 2
    lam = alpha2 * (n + kappa) - n
    return math.sqrt(n + lam), 0.5 / (n + lam), beta - alpha2


SIGMA_PARAMS: Final[tuple[Param, ...]] = (
    Param("alpha", 1.0, "Sigma-point spread (scaled unscented transform; Wan and van der "
          "Merwe's range 1e-4 to 1)", low=1e-4, high=1.0),
    Param("beta", 2.0, "Prior-distribution parameter (2 is optimal for Gaussians)", low=0.0,
          high=1000.0),
    Param("kappa", 0.0, "Secondary scaling parameter (> -5 keeps n + lambda > 0 for n = 6)",
          low=-5.0, low_open=True, high=1000.0),
)
"""The scaled unscented transform's parameters (Wan & van der Merwe 2000)."""
PAPER_UKF_PARAMS: Final[tuple[Param, ...]] = (
    Param("gyro_psd", MPU6050_GYRO_DENSITY**2,
          "Gyro white-noise power spectral density driving the gravity direction (process "
          "noise; the MPU-6050 datasheet's 0.005 deg/s/sqrt(Hz), squared)",
          unit="rad2/s", low=0.0, low_open=True, display_unit="deg2/s"),
    Param("bias_psd", (0.002 * DEG) ** 2,
          "Gyro bias random-walk power spectral density (process noise of the bias states)",
          unit="rad2/s3", low=0.0, display_unit="deg2/s3"),
    Param("acc_noise", 0.06,
          "Standard deviation of one accelerometer sample divided by g (white noise and an "
          "allowance for linear acceleration)", low=1e-6, high=10.0),
    Param("norm_noise", 0.01,
          "Standard deviation of the unit-norm pseudo-measurement |X|^2 = 1 (0: no such row; X "
          "is renormalised after every update either way)", low=0.0, high=10.0),
    Param("acc_gate", 0.1,
          "Skip the accelerometer update while rho = ||acc|/g - 1| is at or above this value",
          low=0.0, low_open=True, high=1000.0),
    Param("init_bias_std", 1.0 * DEG, "Initial standard deviation of each gyro-bias state",
          unit="rad/s", low=0.0, low_open=True, tunable=False, display_unit="deg/s"),
    *SIGMA_PARAMS,
)
"""The parameters of PaperUnscentedKalmanFilter. The paper gives no noise values: these are
ours for its simulated MPU-6050 at 100 Hz (the datasheet's gyro density, acc_noise 0.06 with an
allowance for linear acceleration, the gate at rho 0.1, norm_noise 0.01)."""


class GravityDirectionState:
    """The state both UKFs hold: x = [X (3), b (3)] and the packed covariance _P, with the 6x6
    view of P and the estimate that follows from x."""

    x: list[float]
    _P: tuple[float, ...]

    @property
    def P(self) -> list[list[float]]:
        """The 6x6 state covariance as a list of lists (a copy; x = [X (3), b (3)])."""
        return unpacked(self._P)

    @P.setter
    def P(self, value: list[list[float]]) -> None:
        self._P = packed(value)

    def _estimate(self) -> Estimate:
        X1, X2, X3, bx, by, bz = self.x
        roll, pitch = accel_roll_pitch(X1, X2, X3)  # X is a resting accelerometer's direction
        return Estimate(roll, pitch, (bx, by, bz))


class PaperUnscentedKalmanFilter(GravityDirectionState, Estimator):
    """Duong Quoc et al. eq. 14-17: the UKF on the gravity direction X with three gyro-bias
    states, as the paper writes it.

    State x = [X (3), b (3)]; covariance P (6x6, packed).
    Predict: each sigma point is rotated by its own bias-corrected rotation (exp(-[phi_i]x) X_i,
      the papers' rule phi = (g - b) dt, or with gyro_sampling="point" the trapezoid rate with
      the coning term), b_i unchanged; Q = gyro_psd dt (I - X X^T) for X and bias_psd dt I
      for b.
    Update: z = [acc/g; 1], h(x) = [X; |X|^2], R = diag(acc_noise^2 I3, norm_noise^2) (with
      norm_noise 0, z = acc/g and h(x) = X alone), skipped while rho = ||acc|/g - 1| >=
      acc_gate (the accelerometer then measures more than gravity). X is renormalised after.
    Start: X the first accelerometer sample's direction, P = diag(acc_noise^2 I3,
    init_bias_std^2 I3).
    Output: roll = atan2(X2, X3), pitch = atan2(-X1, sqrt(X2^2 + X3^2)); bias = b.
    """

    PARAMS = PAPER_UKF_PARAMS
    COMMON = PAPER_COMMON
    TWIN: ClassVar[str | None] = "fc_paper_ukf"
    STATE: ClassVar[StateSpec] = {"x": Segments(((UNIT, 3), (REAL, 3))), "P": COV}

    def _configure(self) -> None:
        p = self._params
        self._gamma, self._w, self._w_mu = unscented_constants(
            float(p["alpha"]), float(p["beta"]), float(p["kappa"]))
        self._q_gyro = float(p["gyro_psd"])
        self._q_bias = float(p["bias_psd"])
        self._r_acc = float(p["acc_noise"]) ** 2
        self._r_norm = float(p["norm_noise"]) ** 2
        self._gate = float(p["acc_gate"])

    def _reset(self) -> None:
        self.x = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        self._P: tuple[float, ...] = (0.0,) * 21  # packed lower triangle of the 6x6 P

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        n = math.sqrt(ax * ax + ay * ay + az * az)
        self.x = [ax / n, ay / n, az / n, 0.0, 0.0, 0.0]
        p_x = self._params["acc_noise"] ** 2
        p_b = self._params["init_bias_std"] ** 2
        self._P = packed_diagonal((p_x, p_x, p_x, p_b, p_b, p_b))

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        b = (self.x[3], self.x[4], self.x[5])
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        update = abs(norm / G - 1.0) < self._gate and norm > 0.0  # rho < acc_gate
        norm_row = update and self._r_norm > 0.0  # the pseudo-measurement |X|^2 = 1
        terms = rotation_terms(self.gyro_prev, (gx, gy, gz), dt, self._trapezoid)
        pred = sigma_predict(self.x, self._P, terms, dt, self._gamma, self._w, self._w_mu,
                             norm_row)
        X0, X1, X2 = pred.X
        n = math.sqrt(X0 * X0 + X1 * X1 + X2 * X2)
        inv = 1.0 / n
        P = predicted_covariance(pred, self._P, (X0 * inv, X1 * inv, X2 * inv),
                                 self._q_gyro * dt, self._q_bias * dt)
        b0, b1, b2 = b
        if update:
            X0, X1, X2, b0, b1, b2, P = measurement_update(
                pred, b, P, (ax, ay, az), self._r_acc, self._w, self._w_mu,
                self._r_norm if norm_row else None, True)
            n = math.sqrt(X0 * X0 + X1 * X1 + X2 * X2)
        self.x = [X0 / n, X1 / n, X2 / n, b0, b1, b2]
        self._P = P
        return self._estimate()


def kalman_update(
    x: tuple[float, ...],
    P: tuple[float, ...],
    S: tuple[float, ...],
    rows: tuple[tuple[float, float, float, float], ...],
    y: tuple[float, float, float, float],
    learn_bias: bool = True,
) -> UpdateResult:
    """(*(x + K y), P - K S K^T) with K = P_xz S^-1 (eq. 17): x (6), P packed (21), S the packed
    4x4 innovation covariance, rows the rows of the 6x4 P_xz, y the innovation. With
    S = L L^T and Y = L^-1 P_xz^T: K y = Y^T (L^-1 y) and K S K^T = Y^T Y. With learn_bias
    False the bias rows of K are 0 (the biases are consider states, Schmidt 1966): b and its
    own covariance block stay, the rest is the same update."""
    s00, s10, s11, s20, s21, s22, s30, s31, s32, s33 = S
    L = cholesky4(s00, s10, s11, s20, s21, s22, s30, s31, s32, s33)
    if L is None:
        return consider_bias(general_update(x, P, S, rows, y), x, P, learn_bias)
    l00, l10, l11, l20, l21, l22, l30, l31, l32, l33 = L
    i0, i1, i2, i3 = 1.0 / l00, 1.0 / l11, 1.0 / l22, 1.0 / l33
    Y = []
    for r0, r1, r2, r3 in (*rows, y):  # forward substitution, L^-1 r
        y0 = r0 * i0
        y1 = (r1 - l10 * y0) * i1
        y2 = (r2 - l20 * y0 - l21 * y1) * i2
        Y.append((y0, y1, y2, (r3 - l30 * y0 - l31 * y1 - l32 * y2) * i3))
    (a0, a1, a2, a3), (b0, b1, b2, b3), (c0, c1, c2, c3), (d0, d1, d2, d3), \
        (e0, e1, e2, e3), (f0, f1, f2, f3), (z0, z1, z2, z3) = Y
    x0, x1, x2, x3, x4, x5 = x
    return consider_bias((
        x0 + (a0 * z0 + a1 * z1 + a2 * z2 + a3 * z3),
        x1 + (b0 * z0 + b1 * z1 + b2 * z2 + b3 * z3),
        x2 + (c0 * z0 + c1 * z1 + c2 * z2 + c3 * z3),
        x3 + (d0 * z0 + d1 * z1 + d2 * z2 + d3 * z3),
        x4 + (e0 * z0 + e1 * z1 + e2 * z2 + e3 * z3),
        x5 + (f0 * z0 + f1 * z1 + f2 * z2 + f3 * z3),
        (
            P[0] - (a0 * a0 + a1 * a1 + a2 * a2 + a3 * a3),
            P[1] - (b0 * a0 + b1 * a1 + b2 * a2 + b3 * a3),
            P[2] - (b0 * b0 + b1 * b1 + b2 * b2 + b3 * b3),
            P[3] - (c0 * a0 + c1 * a1 + c2 * a2 + c3 * a3),
            P[4] - (c0 * b0 + c1 * b1 + c2 * b2 + c3 * b3),
            P[5] - (c0 * c0 + c1 * c1 + c2 * c2 + c3 * c3),
            P[6] - (d0 * a0 + d1 * a1 + d2 * a2 + d3 * a3),
            P[7] - (d0 * b0 + d1 * b1 + d2 * b2 + d3 * b3),
            P[8] - (d0 * c0 + d1 * c1 + d2 * c2 + d3 * c3),
            P[9] - (d0 * d0 + d1 * d1 + d2 * d2 + d3 * d3),
            P[10] - (e0 * a0 + e1 * a1 + e2 * a2 + e3 * a3),
            P[11] - (e0 * b0 + e1 * b1 + e2 * b2 + e3 * b3),
            P[12] - (e0 * c0 + e1 * c1 + e2 * c2 + e3 * c3),
            P[13] - (e0 * d0 + e1 * d1 + e2 * d2 + e3 * d3),
            P[14] - (e0 * e0 + e1 * e1 + e2 * e2 + e3 * e3),
            P[15] - (f0 * a0 + f1 * a1 + f2 * a2 + f3 * a3),
            P[16] - (f0 * b0 + f1 * b1 + f2 * b2 + f3 * b3),
            P[17] - (f0 * c0 + f1 * c1 + f2 * c2 + f3 * c3),
            P[18] - (f0 * d0 + f1 * d1 + f2 * d2 + f3 * d3),
            P[19] - (f0 * e0 + f1 * e1 + f2 * e2 + f3 * e3),
            P[20] - (f0 * f0 + f1 * f1 + f2 * f2 + f3 * f3),
        ),
    ), x, P, learn_bias)


def consider_bias(result: UpdateResult, x: tuple[float, ...], P: tuple[float, ...],
                   learn_bias: bool) -> UpdateResult:
    """result as it is, or with the bias states x[3:] and their covariance block P_bb as before
    the update (learn_bias False: kalman_update)."""
    if learn_bias:
        return result
    x0, x1, x2, _, _, _, Pn = result
    bb = (9, 13, 14, 18, 19, 20)  # the packed indices of P_bb
    return (x0, x1, x2, x[3], x[4], x[5],
            tuple(P[i] if i in bb else v for i, v in enumerate(Pn)))


def general_update(
    x: tuple[float, ...],
    P: tuple[float, ...],
    S: tuple[float, ...],
    rows: tuple[tuple[float, float, float, float], ...],
    y: tuple[float, float, float, float],
) -> UpdateResult:
    """kalman_update for an S that is not positive definite (possible only with beta < alpha^2,
    which gives the central point a negative covariance weight): K^T = S^-1 P_xz^T by Gauss-Jordan
    elimination with partial pivoting in plain floats (the C twin does the same operations); x +
    K y and P - K S K^T, symmetrised. A singular S leaves x and P as they were."""
    m = 4
    Sf = [[S[packed_index(i, j)] for j in range(m)] for i in range(m)]
    # the augmented system [S | P_xz^T | y]: 6 right-hand sides for K^T, one for S^-1 y
    aug = [Sf[i] + [rows[k][i] for k in range(N_STATE)] + [y[i]] for i in range(m)]
    width = m + N_STATE + 1
    for col in range(m):
        pivot = col
        for i in range(col + 1, m):
            if abs(aug[i][col]) > abs(aug[pivot][col]):
                pivot = i
        if aug[pivot][col] == 0.0:
            return x[0], x[1], x[2], x[3], x[4], x[5], P
        aug[col], aug[pivot] = aug[pivot], aug[col]
        inv = 1.0 / aug[col][col]
        aug[col] = [v * inv for v in aug[col]]
        for i in range(m):
            if i != col and aug[i][col] != 0.0:
                f = aug[i][col]
                aug[i] = [aug[i][k] - f * aug[col][k] for k in range(width)]
    # K[i][k] = (S^-1 P_xz^T)[k][i]; S^-1 y in the last column
    K = [[aug[k][m + i] for k in range(m)] for i in range(N_STATE)]
    Siy = [aug[k][width - 1] for k in range(m)]
    x0, x1, x2, x3, x4, x5 = (x[i] + sum(rows[i][k] * Siy[k] for k in range(m))
                              for i in range(N_STATE))
    # K S K^T = K P_xz^T (K S = P_xz); symmetrised
    KSK = [[sum(K[i][k] * rows[j][k] for k in range(m)) for j in range(N_STATE)]
           for i in range(N_STATE)]
    return (
        x0, x1, x2, x3, x4, x5,
        tuple(P[packed_index(i, j)] - 0.5 * (KSK[i][j] + KSK[j][i])
              for i in range(N_STATE) for j in range(i + 1)),
    )
