"""The papers' complementary filter for roll and pitch.

References:
  W. Gui, Y. Tang, S. Mukhopadhyay (2015), complementary filter vs Kalman filter for tilt,
  eq. 1-2: angle = a (angle + gyro dt) + (1 - a) acc_angle, a = tau / (tau + dt),
  tau = 0.75 s (a = 0.96 at their loop time dt = 0.03 s).
  Das & Mary, low-cost IMU filtering, eq. 1 (the same filter).
"""

from __future__ import annotations

from typing import ClassVar, Final

from ..base import NEVER_ESTIMATED, Estimator
from ..kinematics import (
    HALF_PI,
    PI,
    accel_roll_pitch,
    clamp_pitch,
    euler_step,
    heun_euler_step,
    wrap_angle,
)
from ..state import ANGLE, HALF_ANGLE, StateSpec
from ..types import Estimate, G, Param
from .common import PAPER_COMMON, PAPER_GATE

NO_BIAS: Final = (0.0, 0.0, 0.0)
"""The bias outputs: the papers' complementary filter has no bias state."""
TAU_PARAM: Final = Param(
    "tau", 0.75, "Complementary-filter time constant, a = tau/(tau+dt) (Gui et al. eq. 2: 0.75 s, "
    "a = 0.96 at their 30 ms loop)",
    unit="s", low=0.0, low_open=True,
)


class PaperComplementaryFilter(Estimator):
    """Gui et al. eq. 1-2 (Das & Mary eq. 1): the complementary filter for roll and pitch.

    Per sample: the gyro propagates roll and pitch through the Z-Y-X Euler-rate kinematics (the
    papers' rectangle rule, or Heun's method with gyro_sampling="point"); then, while
    gate_low <= |acc|/g <= gate_high, angle = a angle_pred + (1 - a) acc_angle with
    a = tau / (tau + dt) from each sample's own dt, written as
    angle_pred + (1 - a) wrap(acc_angle - angle_pred), the same number, so that roll does not
    jump at +-180 deg. A constant gyro bias b leaves a steady error b tau: the filter has no
    bias state, and its bias outputs are 0.
    """

    PARAMS = (TAU_PARAM, *PAPER_GATE)
    COMMON = PAPER_COMMON
    TWIN: ClassVar[str | None] = "fc_paper_cf"
    ZERO_BIAS: ClassVar[dict[str, str]] = {
        f"bias_{a}": f"{NEVER_ESTIMATED}: this filter has no gyro-bias state" for a in "xyz"}
    STATE: ClassVar[StateSpec] = {"roll": ANGLE, "pitch": HALF_ANGLE}

    def _configure(self) -> None:
        p = self._params
        self._tau = float(p["tau"])
        self._gate_low2 = (p["gate_low"] * G) ** 2
        self._gate_high2 = (p["gate_high"] * G) ** 2

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        self.roll, self.pitch = accel_roll_pitch(ax, ay, az)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        if self._trapezoid:
            p0, q0, r0 = self.gyro_prev
            roll, pitch = heun_euler_step(self.roll, self.pitch, p0, q0, r0, gx, gy, gz, dt)
        else:
            roll, pitch = euler_step(self.roll, self.pitch, gx, gy, gz, dt)
        if self._gate_low2 <= ax * ax + ay * ay + az * az <= self._gate_high2:
            acc_roll, acc_pitch = accel_roll_pitch(ax, ay, az)
            k = dt / (self._tau + dt)  # 1 - a, Gui et al. eq. 2
            y = acc_roll - roll
            roll += k * (y if -PI <= y <= PI else wrap_angle(y))
            pitch += k * (acc_pitch - pitch)
        self.roll = roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)
        return Estimate(roll, pitch, NO_BIAS)

    def _estimate(self) -> Estimate:
        return Estimate(self.roll, self.pitch, NO_BIAS)


__all__ = ["PaperComplementaryFilter"]
