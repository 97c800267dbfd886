"""Bias learning in motion for the complementary filters, until a rest has measured the bias.

A start-up calibration leaves a gyro bias of tenths of a degree per second (the realistic
MPU-6050: 0.16 deg/s, 1 sigma), and a recording that starts in motion (a shaken, carried or
rolling sensor) gives the rest detector nothing to measure it on. A complementary filter then
carries the bias times its correction time as tilt error. The Kalman filters learn the bias from
the accelerometer in motion; the complementary filters' correction can too, as the integral term
of a PI loop (Mahony et al. 2008, the passive complementary filter: b <- b - Ki e dt, with e the
tilt innovation as a body rate).

Ki follows from the loop, not from a scan: with the proportional gain Kp = 1 / tau (tau the
correction time) the loop s^2 + Kp s + Ki has the damping zeta = Kp / (2 sqrt(Ki)), so
Ki = motion_bias_gain / tau^2 with motion_bias_gain = 1 / (4 zeta^2); by default 0.5, zeta =
1 / sqrt(2) (the loop's fastest response without overshoot of more than 5 %). The tau is the
correction time the measured disturbance sets, without the shortening for the gyro's scale errors
while the sensor turns: that term trusts the accelerometer sooner for an error proportional to the
rate, which is no bias, and a gain from it learns the turns of a fast swing as bias.

That loop leaves out the measured vector's lag (fusion_core.measured_vector: two low-pass stages
of acc_lowpass / 2), so tau is taken no shorter than one stage, nor than one sample: a loop faster
than its measurement oscillates, and a short correction time set by the user (or a shortening by
the adaptive noise) would otherwise make Ki as large as 1 / dt^2. With that floor the loop keeps
its gain margin for every tau at damping ratios down to 0.5, hence the gain's upper bound 1.

It learns only where the Kalman filters' bias does (the same gates: bias_gate on what reaches the
measured vector, bias_innovation, no sample at the rail, a settled vector), and only until the
first rest: a rest measures the bias directly, better than any motion, and after it the integral
would learn from sustained linear acceleration (BROAD's translation trials) what the rest already
told.
"""

from __future__ import annotations

from typing import Final

from ..types import Param

MOTION_BIAS_GAIN: Final = 0.5
"""Recommended motion_bias_gain: 1 / (4 zeta^2) at the PI loop's damping ratio zeta = 1/sqrt(2)."""

MOTION_BIAS_PARAM = Param(
    "motion_bias_gain", MOTION_BIAS_GAIN,
    "Integral gain of the bias learning in motion before the first rest, Ki tau^2 of a PI loop "
    "on the correction time tau (= 1 / (4 zeta^2) at the loop's damping ratio zeta; tau no "
    "shorter than a stage of the measured vector's low-pass); 0 = off, the bias is learned at "
    "rest only; at most 1 (zeta = 0.5), beyond which the loop oscillates against that lag",
    low=0.0, high=1.0,
)


def motion_bias_ki(tau: float, gain: float, dt: float, stage: float) -> float:
    """Ki [1/s^2] of the PI loop whose proportional gain is 1 / tau: gain / tau^2, with tau no
    shorter than one sample dt nor than one stage of the measured vector's low-pass (stage)."""
    if tau < dt:
        tau = dt
    if tau < stage:
        tau = stage
    return gain / (tau * tau)


__all__ = ["MOTION_BIAS_GAIN", "MOTION_BIAS_PARAM", "motion_bias_ki"]
