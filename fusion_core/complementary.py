"""Complementary filter for roll and pitch.

References:
  W. Gui, Y. Tang, S. Mukhopadhyay (2015), complementary filter vs Kalman filter for tilt,
  eq. 1-2: angle = a (angle + gyro dt) + (1 - a) acc_angle, a = tau / (tau + dt),
  tau = 0.75 s (a = 0.96 at their loop time dt = 0.03 s).
  Das & Mary, low-cost IMU filtering, eq. 1 (the same filter).
"""

from __future__ import annotations

from .base import INTEGRATION_PARAM, Estimator
from .kinematics import accel_roll_pitch, clamp_pitch, euler_step, heun_euler_step, wrap_angle
from .types import Estimate, G, Param

ACC_GATE_PARAMS: tuple[Param, ...] = (
    Param(
        "gate_low", 0.9,
        "Accelerometer gate, lower bound of |acc|/g: below it the accelerometer correction is "
        "skipped (free fall, strong deceleration)",
        low=0.0, high=1.0,
    ),
    Param(
        "gate_high", 1.1,
        "Accelerometer gate, upper bound of |acc|/g: above it the accelerometer correction is "
        "skipped (strong linear acceleration)",
        low=1.0,
    ),
)
"""Gui et al.'s accelerometer-magnitude gate. The papers give no bounds; ours, 0.9 g to 1.1 g, skip
the accelerometer where at least 0.1 g of linear acceleration acts along gravity, yet stay open at
rest for an uncalibrated MEMS accelerometer (scale-factor error up to about 3 %). Measured on the
moderate_dynamics scenario: CF RMSE 0.40/0.46 deg with these bounds, 1.33/1.58 deg with the wide
0.5 g to 2 g of common MPU-6050 sketches. Both bounds are parameters."""


class ComplementaryFilter(Estimator):
    """Complementary filter (Gui et al. 2015 eq. 1-2; Das & Mary eq. 1) for roll and pitch.

    Per sample: the gyro propagates roll and pitch through the Z-Y-X Euler-rate kinematics
    (Heun's method on the average of the previous and current rate, or the papers' rectangle rule
    with integration="rectangle"); then, when gate_low <= |acc|/g <= gate_high, the angles are
    blended with the accelerometer's roll and pitch:  angle = a*angle_pred + (1-a)*acc_angle with
    a = tau/(tau + dt) computed from each sample's own dt (written as
    angle_pred + (1-a)*wrap(acc_angle - angle_pred), the same number, so roll does not jump at
    +-180 deg).

    A constant gyro bias b leaves a steady-state error b*tau: this filter has no bias state, and
    its bias outputs are always 0.

    Parameters: tau [s] time constant (0.75); gate_low, gate_high accelerometer gate (|acc|/g);
    integration; max_dt [s].
    """

    PARAMS = (
        Param(
            "tau", 0.75, "Complementary-filter time constant, a = tau/(tau+dt) (Gui et al. eq. 2)",
            unit="s", low=0.0, low_open=True,
        ),
        *ACC_GATE_PARAMS,
        INTEGRATION_PARAM,
    )
    STATE = ("roll", "pitch")

    def _configure(self) -> None:
        p = self._params
        self._tau = p["tau"]
        self._gate_low2 = (p["gate_low"] * G) ** 2
        self._gate_high2 = (p["gate_high"] * G) ** 2
        self._trapezoid = p["integration"] == "trapezoid"

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        self.roll, self.pitch = accel_roll_pitch(ax, ay, az)

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        if self._trapezoid:
            roll, pitch = heun_euler_step(self.roll, self.pitch, self.gyro_prev, (gx, gy, gz), dt)
        else:
            roll, pitch = euler_step(self.roll, self.pitch, (gx, gy, gz), dt)
        norm2 = ax * ax + ay * ay + az * az
        if self._gate_low2 <= norm2 <= self._gate_high2:
            acc_roll, acc_pitch = accel_roll_pitch(ax, ay, az)
            k = dt / (self._tau + dt)  # 1 - a, Gui et al. eq. 2
            roll += k * wrap_angle(acc_roll - roll)
            pitch += k * (acc_pitch - pitch)
        self.roll = wrap_angle(roll)
        self.pitch = clamp_pitch(pitch)

    def _estimate(self) -> Estimate:
        return Estimate(self.roll, self.pitch, (0.0, 0.0, 0.0))


__all__ = ["ACC_GATE_PARAMS", "ComplementaryFilter"]
