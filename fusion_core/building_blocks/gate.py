"""The accelerometer's trust: the magnitude gate of the correction, and the gates of the bias
learning (the norm of what reaches the measured vector, the innovation's size)."""

from __future__ import annotations

import math
from typing import Final

from ..types import DEG, G, Param

ACC_GATE_PARAMS: tuple[Param, ...] = (
    Param(
        "gate_low", 0.0,
        "Accelerometer gate, lower bound of |acc|/g: below it the accelerometer correction is "
        "skipped (free fall, strong deceleration); 0 = no lower bound",
        low=0.0, high=1.0,
    ),
    Param(
        "gate_high", 1000.0,
        "Accelerometer gate, upper bound of |acc|/g: above it the accelerometer correction is "
        "skipped (strong linear acceleration); 1000 = no upper bound",
        low=1.0, high=1000.0,  # a reading beyond 1000 g is no reading (base.MAX_ACC_NORM)
    ),
)
"""Gui et al.'s accelerometer-magnitude gate. The papers give no bounds; their filters' 0.9-1.1
g (fusion_core.papers.common) is our reading for the raw accelerometer: it skips samples with
0.1 g or more of linear acceleration along gravity, yet stays open at rest for an uncalibrated
MEMS accelerometer (scale error up to about 3 %). Recommended: open (0 and 1000 g). With the
pre-filter on (ACC_LOWPASS_PARAM) the gate sees the filtered vector, whose norm stays near g
while the raw one swings, and the adaptive noise already weighs a vector off g down by the
linear acceleration it measures; a gate on top changes no error on recordings its choice did
not see (`imu-fusion mechanisms`, docs/results/mechanisms.md), so the recommended filters
keep the parameter for a user's own bounds and close nothing by default."""


def gate_bounds2(params: dict) -> tuple[float, float]:
    """The accelerometer gate (ACC_GATE_PARAMS) as bounds on the squared norm |acc|^2 [m^2/s^4],
    so that the per-sample test needs no square root."""
    return (params["gate_low"] * G) ** 2, (params["gate_high"] * G) ** 2

BIAS_GATE: Final = 0.05
"""Recommended bias_gate: Duong Quoc et al.'s experimental table for their MPU-6050 (section
4.2) stops trusting the accelerometer at rho = 0.05; here only the bias stops learning from it.
The accelerometer sees a gyro bias only as a slow drift of the tilt it measures; a vector whose
norm is 5 % off g carries linear acceleration whose apparent tilt would be taken for that drift,
and with a small Q_bias a bias learned wrong stays wrong for minutes. With the measured vector
the gate judges what reaches it (measured_vector.gate_norm2), so shaking and vibration, which
the vector does not hold, leave the bias free to learn. A resting MEMS accelerometer (scale
error up to 3 % uncalibrated) passes."""

BIAS_GATE_PARAM = Param(
    "bias_gate", BIAS_GATE,
    "Bias learning gate on rho = ||a|/g - 1| of the specific force that reaches the measured "
    "vector (its slow band; without the vector the raw accelerometer sample): at or above it "
    "the accelerometer update leaves the gyro bias alone (the sample measures linear "
    "acceleration, not the drift of the tilt); 0 = off, every update moves the bias (the papers)",
    low=0.0, high=1000.0,
)

BIAS_INNOVATION: Final = 10.0 * DEG
"""bias_innovation where the gate is on (a user's own value; `imu-fusion mechanisms` switches it
on with this). A gyro bias shows in the accelerometer update as a slow drift of the tilt that
each correction takes back: innovations of tenths of a degree (after the pre-filter, BROAD's
largest are a few degrees in the fast trials). An innovation of tens of degrees means the
attitude itself is grossly off (after a stretch of absurd samples, a knock, a restart in
motion); the filters' linear model of the angle-bias coupling does not hold there, and learning
from it winds the bias up to tens or hundreds of deg/s, which then takes minutes to unwind. The
angle is corrected as always; only the bias waits."""

BIAS_INNOVATION_PARAM = Param(
    "bias_innovation", math.pi,
    "Largest tilt innovation the gyro bias learns from: beyond it the attitude is grossly off "
    "(not a bias drift) and the accelerometer update corrects the angle only; pi = no limit "
    "(the papers)",
    unit="rad", low=0.0, low_open=True, high=math.pi, display_unit="deg",
)
"""The gate on bias learning at a gross innovation, off (pi) in every recommended filter: with
bias_gate keeping the bias from learning while linear acceleration reaches the measured vector,
a gate at BIAS_INNOVATION lowers the error neither on BROAD's folds left out (with the grid
chosen again) nor on the battery, nor keeps a contract check, and after a second of absurd
samples the filters come back as soon without it (`python -m testbenches.recovery`), so
`imu-fusion mechanisms` drops it (docs/results/mechanisms.md); the parameter stays for a user's
own value."""


GROSS_INNOVATION: Final = 30.0 * DEG
"""Recommended gross_innovation (the kf's; the ukf turns it off, pi:
docs/results/mechanisms.md). A linear acceleration a held longer than the measured vector's
averaging tilts it by atan(a / g) at most: 30 deg needs 0.58 g held for seconds, more than a
hand or a vehicle holds (a car's hardest braking is about 1 g for a moment, its turns a few
tenths of a g). An innovation beyond it says that the attitude itself is off (after a stretch of
absurd samples, a knock, a restart in motion), not that the specific force carries an
acceleration; the filter's angle variance, small after a long clean run, would then take the
correction time of a filter that trusts its gyro (up to max_correction_time) to come back. The
variance is raised to the innovation squared, the error it at least has, and the accelerometer
takes the attitude back at the pace its measurement noise allows
(`python -m testbenches.recovery`, the battery's glitching part)."""

GROSS_INNOVATION_PARAM = Param(
    "gross_innovation", GROSS_INNOVATION,
    "Tilt innovation beyond which the attitude is taken as grossly off: the angle's variance is "
    "raised to the innovation squared, so that the accelerometer corrects it at once; pi = never "
    "(the papers)",
    unit="rad", low=0.0, low_open=True, high=math.pi, display_unit="deg",
)


def bias_band2(gate: float) -> tuple[float, float]:
    """BIAS_GATE_PARAM as bounds on the raw sample's squared norm: the bias learns while
    lo < |a|^2 < hi (any sample when the gate is 0, off)."""
    if not gate > 0.0:
        return -1.0, math.inf
    return (max(1.0 - gate, 0.0) * G) ** 2, ((1.0 + gate) * G) ** 2
