"""Madgwick's gradient-descent orientation filter for roll and pitch, its IMU (6D) form.

References:
  S. O. H. Madgwick, A. J. L. Harrison, R. Vaidyanathan (2011), Estimation of IMU and MARG
  orientation using a gradient descent algorithm, IEEE ICORR; its IMU algorithm, derived in
  S. O. H. Madgwick (2010), An efficient orientation filter for inertial and inertial/magnetic
  sensor arrays (report, University of Bristol), whose equation numbers are cited here:
  eq. 12 the quaternion's rate from the gyro, eq. 25-26 the objective function of gravity and
  its Jacobian, eq. 34 the gradient, eq. 33 the rate with the normalised gradient step scaled
  by beta, eq. 13 the integration.
"""

from __future__ import annotations

import math
from typing import ClassVar, Final

from .base import NEVER_ESTIMATED, Estimator
from .kinematics import accel_roll_pitch, quat_from_roll_pitch_yaw, quat_roll_pitch
from .state import UNIT, StateSpec
from .types import Estimate, Param

NO_BIAS: Final = (0.0, 0.0, 0.0)
"""The bias outputs: the IMU form of the filter has no gyro-bias state."""
BETA_PARAM: Final = Param(
    "beta", 0.033,
    "Gain of the gradient step: the rate [rad/s] at which the accelerometer's gravity direction "
    "pulls the attitude, beta = sqrt(3/4) times the gyro's mean zero-mean error (Madgwick 2010, "
    "sec. 3.6; 0.033 for the IMU form in his experiments)",
    unit="rad/s", low=0.0,
)


class MadgwickFilter(Estimator):
    """Madgwick's IMU filter (Madgwick, Harrison, Vaidyanathan 2011; report eq. 12-34).

    The state is the attitude quaternion q = (w, x, y, z), body to world, with a free yaw.
    Per sample:
    - the rate of q from the gyro, q_dot = 0.5 q (x) (0, w) (eq. 12), with w the sample's rate
      (gyro_sampling="mean", the paper's rule) or the mean of the previous and this sample's
      (gyro_sampling="point": the rate linear between them, its mean over the interval);
    - where the accelerometer reads anything (|a| > 0), the objective f, the gravity direction
      q predicts minus the measured one a / |a| (eq. 25), its Jacobian J (eq. 26) and the
      gradient J^T f (eq. 34); the rate becomes q_dot - beta J^T f / |J^T f| (eq. 33): the
      attitude moves towards the accelerometer's tilt at beta rad/s;
    - q + q_dot dt (eq. 13), normalised.

    The paper takes the gradient at the previous sample's attitude against this sample's
    accelerometer (gyro_sampling="mean"), so that in a turn the step pulls towards an attitude
    one sample behind, and the estimate trails by up to the turn of one sample, |w| dt, on
    noise-free data. With gyro_sampling="point" (the recommended sampling, as in
    the mgcf) q is first turned by the gyro to this sample's time (eq. 12-13), and the gradient
    step (eq. 25-34, 13) is taken there.

    The filter starts from the first sample's accelerometer tilt (every estimator's first-sample
    rule) rather than the identity. Its parameter is its paper's: beta = 0.033. It has no
    accelerometer gate, no gyro-bias state (the bias outputs are 0) and no rule for a gyro
    sample at its rail (gyro_range marks such samples, which it integrates as any).
    """

    PARAMS = (BETA_PARAM,)
    TWIN: ClassVar[str | None] = "fc_madgwick"
    GYRO_ONLY: ClassVar[dict[str, float] | None] = {"beta": 0.0}
    ZERO_BIAS: ClassVar[dict[str, str]] = {
        f"bias_{a}": f"{NEVER_ESTIMATED}: the IMU form of the filter has no gyro-bias state"
        for a in "xyz"}
    STATE: ClassVar[StateSpec] = {"q": UNIT}

    def _configure(self) -> None:
        p = self._params
        self._beta = float(p["beta"])

    def _reset(self) -> None:
        self.q = (1.0, 0.0, 0.0, 0.0)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        roll, pitch = accel_roll_pitch(ax, ay, az)
        self.q = quat_from_roll_pitch_yaw(roll, pitch, 0.0)

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        w, x, y, z = self.q
        if self._trapezoid:  # the rate's mean over the interval, linear between the samples
            px, py, pz = self.gyro_prev
            gx, gy, gz = 0.5 * (px + gx), 0.5 * (py + gy), 0.5 * (pz + gz)
        # eq. 12: q_dot = 0.5 q (x) (0, gx, gy, gz)
        dw = 0.5 * (-x * gx - y * gy - z * gz)
        dx = 0.5 * (w * gx + y * gz - z * gy)
        dy = 0.5 * (w * gy - x * gz + z * gx)
        dz = 0.5 * (w * gz + x * gy - y * gx)
        if self._trapezoid:  # the gradient taken at this sample's time: q turned first
            w, x, y, z = w + dw * dt, x + dx * dt, y + dy * dt, z + dz * dt
            n = math.sqrt(w * w + x * x + y * y + z * z)
            w, x, y, z = w / n, x / n, y / n, z / n
            dw = dx = dy = dz = 0.0
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        if norm > 0.0:
            ax, ay, az = ax / norm, ay / norm, az / norm
            # eq. 25: the gravity direction q predicts in the body frame minus the measured one
            f1 = 2.0 * (x * z - w * y) - ax
            f2 = 2.0 * (w * x + y * z) - ay
            f3 = 2.0 * (0.5 - x * x - y * y) - az
            # eq. 26 and 34: J^T f
            sw = -2.0 * y * f1 + 2.0 * x * f2
            sx = 2.0 * z * f1 + 2.0 * w * f2 - 4.0 * x * f3
            sy = -2.0 * w * f1 + 2.0 * z * f2 - 4.0 * y * f3
            sz = 2.0 * x * f1 + 2.0 * y * f2
            step = math.sqrt(sw * sw + sx * sx + sy * sy + sz * sz)
            if step > 0.0:  # eq. 33: the normalised step, scaled by beta
                k = self._beta / step
                dw -= k * sw
                dx -= k * sx
                dy -= k * sy
                dz -= k * sz
        # eq. 13, then back onto the unit sphere
        w, x, y, z = w + dw * dt, x + dx * dt, y + dy * dt, z + dz * dt
        n = math.sqrt(w * w + x * x + y * y + z * z)
        self.q = (w / n, x / n, y / n, z / n)

    def _estimate(self) -> Estimate:
        roll, pitch = quat_roll_pitch(*self.q)
        return Estimate(roll, pitch, NO_BIAS)


__all__ = ["MadgwickFilter"]
