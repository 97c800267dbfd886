"""The adaptive noise: more process noise while the sensor turns (the gyro's scale-factor
error), more measurement noise while it accelerates (the linear acceleration the pre-filter has
not removed, fusion_core.measured_vector), the raw sample where it measures none; for the
complementary filters, the correction time that follows from that balance."""

from __future__ import annotations

import math
from typing import Any, Final

from ..types import Param

RECOMMENDED_GYRO_SCALE_STD: Final = 0.005
"""Recommended gyro_scale_std: the scale-factor errors of BROAD's gyro, fitted against its optical
reference on the nine trials that turn (testbenches.broad.gyro, no estimator involved;
docs/results/broad.md, "What the errors came from"), are within about half a percent per axis;
an MPU-6050's datasheet tolerance is +-3 % (1 % as 3 sigma)."""

RECOMMENDED_SCALE_TIME: Final = 0.5
"""Recommended scale_time [s]: how long a scale error adds up in one direction, about one swing
of a hand-held or robot motion. Physics leaves its exact value open, and two kinds of evidence
pull it apart: BROAD's folds (smaller scale errors) ask for less (testbenches.broad.cv.CV_GRID
cross-validates it with the other open parameters), while the realistic sensor's scenarios
(scale errors of 1 %) ask for more (`python -m testbenches run --estimator kf --scenario
high_dynamics --seeds 8 --param scale_time=0.25`, and 1). The
process noise a scale error adds belongs to the sensor class, which one IMU's recordings cannot
show; 0.5 s holds on both (docs/results/broad.md)."""

ADAPTIVE_NOISE_PARAMS: Final = (
    Param(
        "gyro_scale_std", RECOMMENDED_GYRO_SCALE_STD,
        "The gyro's scale-factor uncertainty (1 sigma): while the sensor turns at rate w the "
        "attitude's process noise grows by gyro_scale_std^2 w^2 scale_time, so the accelerometer "
        "corrects faster what a scale error adds up (0: the gyro's white noise only, the papers')",
        low=0.0, high=0.5,
    ),
    Param(
        "scale_time", RECOMMENDED_SCALE_TIME,
        "How long a scale error adds up in one direction before the motion turns back (the "
        "correlation time of the rotation-driven process noise)",
        unit="s", low=0.0,
    ),
    Param(
        "disturbance_time", 1.0,
        "Averaging time of the measured linear acceleration: the mean square of the "
        "accelerometer's deviation from its pre-filtered value, above the white noise, is added "
        "to the measurement variance (over g^2), so the correction slows while the sensor "
        "accelerates, and the pre-filter shortens while it measures no more than the white noise; "
        "needs acc_lowpass > 0 (0 = off: constant measurement noise and pre-filter, the papers')",
        unit="s", low=0.0,
    ),
)
"""The adaptive noise (kf, ukf; cf and mgcf through COMPLEMENTARY_ADAPTIVE_PARAMS). A constant Q
and R describe a gyro with white noise only and an accelerometer that measures gravity alone; a
real sensor breaks both in motion, and the balance of the two sets the correction's speed:
- gyro_scale_std, scale_time: a gyro with a scale-factor error s turns the estimate by s times
  every rotation, which a white-noise Q does not know. While the sensor turns at rate w the
  process noise of the attitude grows by gyro_scale_std^2 w^2 scale_time (the variance a scale
  error of that size adds up over scale_time, taken as a white noise), so the accelerometer
  takes over faster in fast rotation;
- disturbance_time: the averaging time of the measured vector's disturbance statistics
  (fusion_core.measured_vector: the linear acceleration that reaches the vector sizes the
  measurement noise, and adaptive_prefilter_time the vector's length). 1 s."""

CONSTANT_NOISE: Final = {"gyro_scale_std": 0.0, "disturbance_time": 0.0}
"""ADAPTIVE_NOISE_PARAMS off: a constant Q and R and a pre-filter of fixed length, as the papers'
filters have them."""


def adaptive_noise_constants(p: Any, acc_tau: float) -> tuple[float, float]:
    """The constants of ADAPTIVE_NOISE_PARAMS from a filter's parameters p and its pre-filter's
    time constant acc_tau: the rotation term of the process noise per (rad/s)^2 and the
    disturbance's averaging time (0: off, also without the pre-filter). The white noise's share
    of the disturbance statistics is the measured vector's (measured_vector.measure_constants)."""
    return (float(p["gyro_scale_std"]) ** 2 * float(p["scale_time"]),
            float(p["disturbance_time"]) if acc_tau > 0.0 else 0.0)

MAX_CORRECTION_TIME_PARAM: Final = Param(
    "max_correction_time", 3.0,
    "The longest correction time constant the adaptive noise may stretch the filter's to while "
    "the sensor accelerates (never shorter than the filter's own): the gyro bias the filter has "
    "not learned leaves an error of that bias times it",
    unit="s", low=0.0,
)
"""Recommended 3 s: the complementary filters learn their bias at rest (cf) or over minutes (mgcf),
so a bias b left by the usual start-up calibration (0.16 deg/s on the realistic MPU-6050, its
datasheet's temperature drift over 1 K of warm-up) costs b times this, 0.5 deg at 3 s. A coarse
scan of the cf on BROAD has its plateau at 3-5 s; 3 keeps that bias error smallest on it."""

COMPLEMENTARY_ADAPTIVE_PARAMS: Final = (
    Param(
        "acc_noise", 0.005,
        "Standard deviation of one accelerometer sample divided by g, the reference of the "
        "adaptive noise (the measured sample noise of a real MEMS IMU)",
        low=1e-6, high=10.0,  # 1 ug, below any accelerometer's noise; its square a normal double
    ),
    *ADAPTIVE_NOISE_PARAMS,
    MAX_CORRECTION_TIME_PARAM,
)
"""The adaptive noise of the complementary filters (cf, mgcf): ADAPTIVE_NOISE_PARAMS, the sample
noise they are measured against and the longest correction time."""


def complementary_adaptive(p: Any, acc_tau: float) -> tuple[float, float, float, float]:
    """The constants of COMPLEMENTARY_ADAPTIVE_PARAMS from a filter's parameters p: one sample's
    variance r, the rotation term per (rad/s)^2, the disturbance's averaging time (0: off, also
    without the pre-filter acc_tau) and the longest correction time."""
    r = float(p["acc_noise"]) ** 2
    return (r, *adaptive_noise_constants(p, acc_tau), float(p["max_correction_time"]))


def correction_time(tau: float, r_ratio: float, q_rotation: float, w2: float, r: float,
                    dt: float, longest: float) -> float:
    """A complementary filter's correction time constant for this step under the adaptive noise
    (ADAPTIVE_NOISE_PARAMS): shorter while the sensor turns with a clean accelerometer, longer
    while it accelerates, up to the larger of tau and longest (MAX_CORRECTION_TIME_PARAM).

    A filter blending gyro and accelerometer with time constant tau is the steady state of a
    Kalman filter with measurement variance r (one sample's) and angle process noise
    q = r dt / tau^2, since tau = sqrt(r dt / q). With the kf's adaptive noise, r grows by the
    ratio r_ratio (the measured vector's noise over r, measured_vector) and q by q_rotation w2
    (the gyro's scale uncertainty while it turns at w), and the time constant by
    sqrt(r_ratio / q_ratio). It is stretched at most to `longest`: a filter that has not learned
    its gyro bias leaves an error of that bias times its time constant."""
    q_ratio = 1.0 + q_rotation * w2 * tau * tau / (r * dt)
    t = tau * math.sqrt(r_ratio / q_ratio)
    cap = longest if longest > tau else tau
    return t if t < cap else cap

SLOWEST_CORRECTION: Final = 1e9
"""Longest correction time constant [s] the adaptive noise stretches (correction_time): a gain
whose time constant is longer (30 years) corrects nothing, and correction_time squares the time
constant, which overflows beyond 1e154 s (a Kp of a subnormal w0)."""

PREFILTER_FULL: Final = 4.0
"""adaptive_prefilter_time reaches the full pre-filter where the disturbance's power is this many
times the white noise's (its RMS twice the noise's): a band of disturbance wide enough that the
pre-filter does not switch on the rounding of the sample times of a noise-free run (contract
T2); docs/estimators/index.md, "Numerical choices beyond the papers", says how it was chosen."""


def adaptive_prefilter_time(tau: float, dist: float, noise: float) -> float:
    """The accelerometer pre-filter's time constant for this step (ADAPTIVE_NOISE_PARAMS'
    disturbance_time): tau times the measured disturbance's excess over the white noise, in
    units of PREFILTER_FULL times the noise, at most tau.

    The pre-filter is there to average linear acceleration away. Where the disturbance statistic
    (measured_vector's raw statistic, against the full-length reference) finds none above the white
    noise, there is nothing for it to average that the filter's own measurement variance does
    not already weigh, and the vector it would give has turned with the gyro for tau, carrying
    the gyro's scale and bias errors of that time: the raw sample is then the better
    measurement. The more disturbance, the longer the pre-filter, up to tau."""
    excess = dist - noise
    if excess <= 0.0:
        return 0.0
    full = PREFILTER_FULL * noise
    if excess >= full:
        return tau
    return tau * (excess / full)
