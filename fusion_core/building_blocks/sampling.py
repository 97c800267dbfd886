"""The gyro sampling rule: what a sensor's gyro sample is, and the rotation over an interval
that follows from it."""

from __future__ import annotations

from typing import Final

from ..kinematics import rotation_increment
from ..types import DEG, Param

REAL_GYRO_DENSITY: Final = 0.008 * DEG
"""Gyro white-noise density [rad/s/sqrt(Hz)] of the recommended zero-rate updates: measured on a
real MEMS IMU at rest (BROAD's myon aktos-t, the first 20 s of 13 trials, median), 1.6 times the
MPU-6050 datasheet's typical 0.005 deg/s/sqrt(Hz): a datasheet's typical figure is a good part's."""

Vec3 = tuple[float, float, float]

ZERO3: Vec3 = (0.0, 0.0, 0.0)

GYRO_SAMPLING_PARAM = Param(
    "gyro_sampling", "point",
    "What the sensor's gyro sample is, which fixes the integration rule: 'point' (the rate at "
    "the sample's instant: the interval is integrated with the rate linear between the previous "
    "and this sample, plus the coning term) or 'mean' (the mean rate over the interval ending at "
    "the sample, as integrating or decimating IMUs deliver: rate times dt is then exact for a "
    "fixed axis)",
    choices=("point", "mean"), tunable=False,
)
"""The gyro sampling property. A point sample is the rate at one instant (an analogue gyro read
by an ADC, the MPU-6050 with its DLPF read at the output rate): the rate between two samples is
best taken linear, and the rotation over the interval is its trapezoid integral with the
two-sample coning term (kinematics.rotation_increment; Heun's method on the Euler rates). A mean
sample (integrating or decimating IMUs, BROAD's myon aktos-t) already is the rotation over the
interval divided by dt: the trapezoid rule would then average two intervals and lag by half a
sample (|omega| dt / 2), and the papers' rectangle rule, rate times dt, is the exact one. The
seed papers integrate with the rectangle rule on every sensor: their preset takes 'mean'."""


def body_rotation(g0: Vec3, g1: Vec3, bias: Vec3, dt: float, trapezoid: bool) -> Vec3:
    """Bias-corrected body rotation vector over one interval: the trapezoid rate with the coning
    term (kinematics.rotation_increment), or the papers' rectangle rule (g1 - bias) dt."""
    b0, b1, b2 = bias
    if trapezoid:
        return rotation_increment(
            g0[0] - b0, g0[1] - b1, g0[2] - b2, g1[0] - b0, g1[1] - b1, g1[2] - b2, dt
        )
    return (g1[0] - b0) * dt, (g1[1] - b1) * dt, (g1[2] - b2) * dt


def on_the_mark(t: float, dt: float, mark: float) -> float:
    """t, a time counted sample by sample, or mark where t is within half a sample (dt) of it.
    A count reaches its mark at the sample nearest to it, whatever the rounding of the sum: in
    single precision 150 steps of 0.01 s sum to just under 1.5 s, and a measured vector or a
    rest timed by the raw sum ends a sample later than in double, which alone moves the float
    build's estimate visibly on high_dynamics. Counts compared with a mark pass through this
    one at each step (measured_vector.measure_step, rest.rest_step)."""
    d = t - mark
    return mark if -0.5 * dt < d < 0.5 * dt else t
