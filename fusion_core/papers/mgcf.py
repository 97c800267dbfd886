"""The paper's modified-gain complementary filter: a Mahony-style quaternion PI filter whose gain
is switched by the accelerometer's norm.

Reference:
  Duong Quoc et al., complementary filter gain, eq. 7-13: the attitude quaternion is driven by
  the gyro plus a PI correction from the accelerometer error e = a_n x v (measured x estimated
  gravity direction in the body frame); Kp = 2 zeta w0, Ki = w0^2 (the PI loop as a second-order
  system with natural frequency w0 and damping zeta = 2); w0 is switched by
  rho = | |a|/g - 1 | so that the accelerometer is trusted less the further its norm is from g.
  Their simulation table (section 4.1): rho < 0.01 -> w0 = 0.1 rad/s, < 0.25 -> 0.07,
  < 0.35 -> 0.035, else 0 (gyro only); their experimental table for the MPU-6050 (section 4.2):
  rho < 0.025 -> 0.1, < 0.035 -> 0.07, < 0.05 -> 0.05, else 0. With a fixed w0 the filter is
  their conventional CF (CCF): w0 = 0.05 rad/s in their experiment.
  Mahony, Hamel, Pflimlin (2008), "Nonlinear complementary filters on the special orthogonal
  group", give the PI law this filter uses: omega = gyro - b + Kp e, b_dot = -Ki e.
"""

from __future__ import annotations

import math
from typing import ClassVar, Final

from ..base import Estimator
from ..kinematics import (
    accel_roll_pitch,
    quat_from_roll_pitch_yaw,
    quat_gravity_body,
    quat_mul_rotvec,
    quat_roll_pitch,
    rotation_increment,
)
from ..state import NONNEG, REAL, UNIT, StateSpec
from ..types import Estimate, G, Param
from .common import PAPER_COMMON, Vec3

Quat = tuple[float, float, float, float]

SCHEDULES: Final[dict[str, tuple[tuple[float, float], ...]]] = {
    # (rho upper bound, w0 [rad/s]); rho at or above the last bound gives w0 = 0.
    # Duong Quoc et al. section 4.1 (simulated data, zeta = 2).
    "simulation": ((0.01, 0.1), (0.25, 0.07), (0.35, 0.035)),
    # Duong Quoc et al. section 4.2 (their MPU-6050, low and medium dynamics, zeta = 2); their
    # conventional CF (CCF) in that experiment is schedule="fixed" with w0 = 0.05 rad/s.
    "experimental": ((0.025, 0.1), (0.035, 0.07), (0.05, 0.05)),
}


def scheduled_w0(rho: float, table: tuple[tuple[float, float], ...]) -> float:
    """w0 for accelerometer-norm deviation rho from a (bound, w0) table (Duong Quoc et al.)."""
    for bound, w0 in table:
        if rho < bound:
            return w0
    return 0.0


def quat_first_order(q: Quat, w: tuple[float, float, float], dt: float) -> Quat:
    """q + dt/2 q (x) (0, w), renormalised: the first-order rule of Mahony's reference code."""
    qw, qx, qy, qz = q
    wx, wy, wz = 0.5 * dt * w[0], 0.5 * dt * w[1], 0.5 * dt * w[2]
    rw = qw - qx * wx - qy * wy - qz * wz
    rx = qx + qw * wx + qy * wz - qz * wy
    ry = qy + qw * wy - qx * wz + qz * wx
    rz = qz + qw * wz + qx * wy - qy * wx
    n = 1.0 / math.sqrt(rw * rw + rx * rx + ry * ry + rz * rz)
    return rw * n, rx * n, ry * n, rz * n


def pi_step(q: Quat, bias: Vec3, prev: Vec3, g: Vec3, a: Vec3, norm: float, w0: float,
            kp: float, dt: float, trapezoid: bool, learn_bias: bool) -> tuple[Quat, Vec3]:
    """One step of the PI law (eq. 7-13, Mahony et al. 2008) from the attitude q and the bias
    b, the previous and this gyro sample, the specific force a of norm |a| and the gains
    w0 and Kp: with point samples (trapezoid) the gyro first turns q over the interval (the
    rate linear between the samples, with the coning term), and the error is taken against
    the attitude at this sample's time; else it is taken against the previous attitude
    (Mahony's reference order) and q then follows the PI-corrected rate by the first-order
    rule. e = a/|a| x v, v = R(q)^T e_z; while learn_bias, b <- b - Ki e dt (Ki = w0^2).
    Returns the new q and b."""
    bx, by, bz = bias
    gx, gy, gz = g
    if trapezoid:
        p0, q0, r0 = prev
        q = quat_mul_rotvec(q, *rotation_increment(
            p0 - bx, q0 - by, r0 - bz, gx - bx, gy - by, gz - bz, dt
        ))
    ex = ey = ez = 0.0  # Mahony's error, zero while the correction is off
    if w0 > 0.0:
        vx, vy, vz = quat_gravity_body(*q)  # the estimated gravity direction in the body frame
        inv = 1.0 / norm
        nx, ny, nz = a[0] * inv, a[1] * inv, a[2] * inv
        ex, ey, ez = ny * vz - nz * vy, nz * vx - nx * vz, nx * vy - ny * vx
        if learn_bias:  # the integral term, whose negative is the gyro bias
            ki_dt = w0 * w0 * dt
            bx, by, bz = bias = (bx - ki_dt * ex, by - ki_dt * ey, bz - ki_dt * ez)
    if not trapezoid:  # one Euler step with the PI-corrected rate
        q = quat_first_order(q, (gx + kp * ex - bx, gy + kp * ey - by, gz + kp * ez - bz), dt)
    elif w0 > 0.0:
        kp_dt = kp * dt
        q = quat_mul_rotvec(q, kp_dt * ex, kp_dt * ey, kp_dt * ez)
    return q, bias


PAPER_MGCF_PARAMS: Final[tuple[Param, ...]] = (
    Param(
        "schedule", "simulation",
        "w0 schedule over rho = ||a|/g - 1|: 'simulation' (Duong Quoc et al. section 4.1), "
        "'experimental' (section 4.2), or 'fixed' (constant w0: their conventional CF)",
        choices=("simulation", "experimental", "fixed"),
    ),
    Param("w0", 0.1, "Natural frequency of the PI correction when schedule='fixed' (their CCF: "
          "0.05 rad/s)", unit="rad/s", low=0.0),
    Param("zeta", 2.0, "Damping ratio of the PI correction, Kp = 2 zeta w0 (Duong Quoc et al.: 2)",
          low=0.0, high=1000.0),
)


class PaperGainScheduledFilter(Estimator):
    """Duong Quoc et al. eq. 7-13: the modified-gain complementary filter (quaternion PI,
    scheduled w0), as the paper writes it.

    Per sample:
      v   = R(q)^T e_z, the estimated gravity direction in the body frame;
      e   = a/|a| x v (Mahony's correction term), v from the previous attitude (Mahony's
            reference order) or, with gyro_sampling="point", after the gyro prediction to this
            sample's time;
      rho = | |a|/g - 1 |; w0 = schedule(rho) (or the parameter w0 with schedule="fixed");
      Kp  = 2 zeta w0, Ki = w0^2;
      b  <- b - Ki e dt (the integral term; b is the gyro-bias estimate, output as bias_*);
      the body rate gyro - b + Kp e rotates q over dt by the first-order quaternion rule
      (quat_first_order), or, with gyro_sampling="point", the rate linear between the previous
      and this gyro sample with the two-sample coning correction (kinematics.rotation_increment)
      and then the correction Kp e dt.
    Roll and pitch come from the quaternion; yaw is carried along but unobservable.
    """

    PARAMS = PAPER_MGCF_PARAMS
    COMMON = PAPER_COMMON
    TWIN: ClassVar[str | None] = "fc_paper_mgcf"
    GYRO_ONLY: ClassVar[dict[str, float] | None] = {}  # its schedule takes 3 g out
    STATE: ClassVar[StateSpec] = {"q": UNIT, "bias": REAL, "w0_now": NONNEG}

    def _configure(self) -> None:
        p = self._params
        self._table = SCHEDULES.get(p["schedule"])
        self._w0_fixed = float(p["w0"])
        self._two_zeta = 2.0 * float(p["zeta"])

    def _reset(self) -> None:
        self.q: Quat = (1.0, 0.0, 0.0, 0.0)
        self.bias = (0.0, 0.0, 0.0)
        self.w0_now = 0.0

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        roll, pitch = accel_roll_pitch(ax, ay, az)
        self.q = quat_from_roll_pitch_yaw(roll, pitch, 0.0)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        table = self._table
        w0 = self._w0_fixed if table is None else scheduled_w0(abs(norm / G - 1.0), table)
        if not norm > 0.0:  # no gravity direction in this sample: gyro only
            w0 = 0.0
        self.w0_now = w0
        q, self.bias = pi_step(
            self.q, self.bias, self.gyro_prev, (gx, gy, gz), (ax, ay, az), norm, w0,
            self._two_zeta * w0, dt, self._trapezoid, True)
        self.q = q
        roll, pitch = quat_roll_pitch(*q)
        return Estimate(roll, pitch, self.bias)

    def _estimate(self) -> Estimate:
        roll, pitch = quat_roll_pitch(*self.q)
        return Estimate(roll, pitch, self.bias)


__all__ = ["SCHEDULES", "PaperGainScheduledFilter", "pi_step", "quat_first_order",
           "scheduled_w0"]
