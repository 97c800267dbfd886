"""Real-sensor building blocks that every estimator shares, beside its paper's own equations.

The seed papers assume a calibrated sensor whose accelerometer measures gravity and whose gyro
sample is a point value. Real MEMS IMUs break each assumption in a known way, and each block
below answers one of them the same way in every estimator:

- the gyro sampling rule (GYRO_SAMPLING_PARAM): point samples or interval means;
- the accelerometer-magnitude gate (ACC_GATE_PARAMS): skip the correction when |a| is far from g;
- the accelerometer pre-filter (ACC_LOWPASS_PARAM, lowpass_specific_force): low-pass the specific
  force in a frame that turns with the gyro, so linear acceleration averages out (Laidig & Seel
  2023, VQF);
- rest detection for a zero-angular-rate bias update (REST_PARAMS, rest_step; VQF's detector);
- adaptive noise (ADAPTIVE_NOISE_PARAMS, fusion_core.measured_vector; correction_time for the
  complementary filters): more process noise while the sensor turns (the gyro's scale-factor
  error), more measurement noise while it accelerates (the linear acceleration the pre-filter
  has not removed), the raw sample where it measures none;
- quaternion propagation of Euler-angle filters (quat_from_roll_pitch), free of the pitch
  +-90 deg singularity of the Euler rates;
- the nearest face (FACES, nearest_face): per-axis tilt filters run in the sensor frame turned
  by the right-angle rotation that brings the axis nearest to up onto z, so that a sensor resting
  on any face is the level case for them.

An accelerometer sample whose norm is zero (or that base.Estimator.step took as no reading)
carries no gravity direction: every block below skips it, and so does every correction.

Quaternion propagation: the papers integrate the Euler rates (Duong Quoc eq. 2), whose
tan(pitch) term is singular at pitch +-90 deg: a sensor that turns through the vertical (every
rotation trial of BROAD does) loses the attitude there, and the innovation of roll, which the
accelerometer cannot observe near pitch +-90 deg, cannot bring it back. The recommended cf and kf
keep an attitude quaternion q (yaw free, unobservable), turn it by the bias-corrected rotation
vector of each interval (the quaternion filters' rule, kinematics.rotation_increment), take roll
and pitch from it, apply their paper's correction to roll and pitch, and rebuild q from the
corrected roll and pitch with yaw 0 (quat_from_roll_pitch: the free yaw does not change roll or
pitch). The correction law, its gains and its covariance are the paper's.
"""

from __future__ import annotations

import math
from math import cos, sin
from typing import Any, Final

from .kinematics import (
    accel_roll_pitch,
    rotate_back,
    rotation_increment,
)
from .types import DEG, G, Param

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

ACC_GATE_PARAMS: tuple[Param, ...] = (
    Param(
        "gate_low", 0.5,
        "Accelerometer gate, lower bound of |acc|/g: below it the accelerometer correction is "
        "skipped (free fall, strong deceleration)",
        low=0.0, low_open=True, high=1.0,
    ),
    Param(
        "gate_high", 2.0,
        "Accelerometer gate, upper bound of |acc|/g: above it the accelerometer correction is "
        "skipped (strong linear acceleration)",
        low=1.0, high=1000.0,  # a reading beyond 1000 g is no reading (base.MAX_ACC_NORM)
    ),
)
"""Gui et al.'s accelerometer-magnitude gate. The papers give no bounds. Recommended, 0.5 g to
2 g: with the pre-filter on (ACC_LOWPASS_PARAM) the gate sees the filtered vector, whose norm
stays near g while the raw one swings, so only gross disturbances need closing it; a narrow gate
then only adds rejections. The papers' filters' 0.9-1.1 g (fusion_core.papers.common) is our
reading for the raw accelerometer: it skips samples with 0.1 g or more of linear acceleration
along gravity, yet stays open at rest for an uncalibrated MEMS accelerometer (scale error up to
about 3 %)."""

ACC_LOWPASS_PARAM = Param(
    "acc_lowpass", 1.5,
    "Accelerometer pre-filter length: the specific force is low-passed in a frame that turns "
    "with the gyro (two stages of acc_lowpass / 2 each: fusion_core.measured_vector), so linear "
    "acceleration averages out and gravity does not lag the rotation (Laidig & Seel 2023, VQF); "
    "the filter and its gate then use the filtered vector. 0 = off: each raw sample (the papers)",
    unit="s", low=0.0,
)
"""Recommended: 1.5 s. Physics brackets it: long enough to average the swing of a hand-held
translation (a second or more), short against the drift that a gyro scale error of 1-3 % turns
into the vector while the sensor turns; within that bracket the value is the one
leave-one-motion-fold-out cross-validation on BROAD chooses for cf, kf and ukf (`python -m
testbenches broad DIR --cv`, testbenches.broad.cv, whose report gives the figures). The mgcf
keeps 1 s (mgcf.MGCF_ACC_LOWPASS)."""
"""The accelerometer pre-filter. Laidig & Seel (VQF: Highly accurate IMU orientation estimation
with bias estimation and magnetic disturbance rejection, Information Fusion 91, 2023) low-pass
filter the accelerometer in an almost inertial frame given by the gyro strapdown integration:
there the gravity part is constant, and the linear acceleration of a body that ends where it
started averages to (velocity change) / (time), so a low-pass with a time constant of seconds
removes most of it, without the lag that a body-frame low-pass has while the sensor turns. Here
the filtered vector is kept in body axes and turned with the gyro's rotation increment each
sample (a world-fixed vector seen from the body), which is the same filter. Each paper's filter is
then unchanged: it takes the filtered vector where it took the raw sample. Measured on BROAD's
real recordings (testbenches/broad): the fast-translation trials, whose raw accelerometer
swings between 0.02 g and 5 g, drop from tens of degrees to below 1 deg of inclination error."""

RestState = tuple[float, float, float, float, float, float, float, float]
"""The rest detector's state: running means of the rate (3) and of the specific force (3), the
quiet time [s], and 1.0 once a rest has lasted rest_time (the bias has been measured), else 0.0."""
REST_START: Final = (0.0,) * 8
"""The rest detector's state before the first sample."""
REST_MEAN_TAU: Final = 0.5
"""Time constant [s] of the running means the rest detector compares each sample with (VQF's
restFilterTau)."""

REST_PARAMS: tuple[Param, ...] = (
    Param(
        "rest_time", 1.5,
        "Rest detection: after this long with the gyro and accelerometer within rest_gyro and "
        "rest_acc of their running means (and the mean rate below rest_gyro) the sensor is at "
        "rest, and the gyro, which then reads its own bias, updates the bias estimate. "
        "0 = off (the papers)",
        unit="s", low=0.0,
    ),
    Param(
        "rest_gyro", 2.0 * DEG, "Rest detection: angular-rate threshold",
        unit="rad/s", low=0.0, low_open=True, display_unit="deg/s",
    ),
    Param(
        "rest_acc", 0.5,
        "Rest detection: threshold on the specific force's deviation from its running mean",
        unit="m/s2", low=0.0, low_open=True,
    ),
    Param(
        "rest_bias_bound", 20.0 * DEG,
        "Rest detection: the largest turn-on gyro bias the sensor may have. Until a first rest "
        "has measured the bias, a mean rate within rest_gyro plus this of the bias estimate may "
        "start a rest; after it, the mean rate less the bias estimate must be below rest_gyro "
        "(0: rest_gyro alone, VQF's rule)",
        unit="rad/s", low=0.0, display_unit="deg/s",
    ),
)
"""Rest detection for a zero-angular-rate bias update. A still sensor's gyro reads its bias: an
uncalibrated MEMS gyro's turn-on bias (tenths of a deg/s) times a correction time constant of
seconds is a tilt error of tenths of a degree, and about z the bias is
not observable from the accelerometer at all while the sensor is level. The detector is VQF's
(Laidig & Seel 2023): the rate and the specific force must stay within the thresholds of their
running means (time constant REST_MEAN_TAU) for rest_time; its defaults (2 deg/s, 0.5 m/s^2,
1.5 s) are VQF's restThGyr, restThAcc and restMinT. The papers have no rest detection
(rest_time = 0).

VQF also requires the mean rate itself to be below restThGyr, so that a slow steady rotation,
which the deviations do not see, is not taken for rest. Against the raw rate that rule also
refuses the rest of a still gyro whose bias exceeds the threshold: an MPU-6050 as delivered
(turn-on bias +-20 deg/s in its datasheet) is then never measured at rest, and a complementary
filter, which learns its bias nowhere else, stays degrees off at rest. So here the mean rate is
taken less the filter's bias estimate, and before the first rest a mean rate the turn-on bias
can explain (rest_bias_bound: the datasheet's 20 deg/s) may start one; a filter without a bias
covariance then aligns at such a first rest (uncalibrated_first_rest). A rest under way lasts
while the deviations stay small, so that the bias estimate can converge in it. A gyro calibrated
at start-up never meets either rule: its outputs are those of VQF's rule to the last bit
(tests/test_rest_detection.py)."""


def zero_rate_psd_param(name: str = "gyro_psd") -> Param:
    """The gyro white-noise PSD of the zero-angular-rate update at rest (REST_PARAMS), whose
    measurement variance is PSD / dt; default REAL_GYRO_DENSITY squared. The UKF names it
    zaru_psd, since its gyro_psd is its process noise."""
    return Param(
        name, REAL_GYRO_DENSITY**2,
        "Gyro white-noise power spectral density of the zero-angular-rate update at rest: its "
        "variance is this / dt (the rate-noise density squared; measured on a real MEMS IMU: "
        "(0.008 deg/s/sqrt(Hz))^2)",
        unit="rad2/s", low=0.0, low_open=True, display_unit="deg2/s",
    )


def quat_from_roll_pitch(roll: float, pitch: float) -> tuple[float, float, float, float]:
    """The attitude quaternion (w, x, y, z) of roll and pitch with yaw 0 (the module docstring):
    kinematics.quat_from_roll_pitch_yaw(roll, pitch, 0.0), written without the yaw's terms (the
    same doubles, two sine-cosine pairs instead of three). The yaw of the filters' quaternion is
    free: a turn about world z changes only the first two rows of the rotation matrix, and roll
    and pitch are read from the third, so rebuilding q with yaw 0 leaves every later roll and
    pitch as it was."""
    cr, sr = cos(0.5 * roll), sin(0.5 * roll)
    cp, sp = cos(0.5 * pitch), sin(0.5 * pitch)
    return cr * cp, sr * cp, cr * sp, -(sr * sp)


def gate_bounds2(params: dict) -> tuple[float, float]:
    """The accelerometer gate (ACC_GATE_PARAMS) as bounds on the squared norm |acc|^2 [m^2/s^4],
    so that the per-sample test needs no square root."""
    return (params["gate_low"] * G) ** 2, (params["gate_high"] * G) ** 2


def body_rotation(g0: Vec3, g1: Vec3, bias: Vec3, dt: float, trapezoid: bool) -> Vec3:
    """Bias-corrected body rotation vector over one interval: the trapezoid rate with the coning
    term (kinematics.rotation_increment), or the papers' rectangle rule (g1 - bias) dt."""
    b0, b1, b2 = bias
    if trapezoid:
        return rotation_increment(
            g0[0] - b0, g0[1] - b1, g0[2] - b2, g1[0] - b0, g1[1] - b1, g1[2] - b2, dt
        )
    return (g1[0] - b0) * dt, (g1[1] - b1) * dt, (g1[2] - b2) * dt


def lowpass_specific_force(f: Vec3, phi: Vec3, a: Vec3, dt: float, tau: float,
                           terms: tuple[float, float, float, float]) -> Vec3:
    """One step of the accelerometer pre-filter (ACC_LOWPASS_PARAM): the filtered specific force
    f turned with the body by phi, then blended with the new sample a, k = dt / (tau + dt);
    terms: kinematics.rotvec_terms(*phi), which the caller also turns its attitude or a second
    pre-filter with."""
    f0, f1, f2 = rotate_back(f, phi, terms)
    k = dt / (tau + dt)
    return f0 + k * (a[0] - f0), f1 + k * (a[1] - f1), f2 + k * (a[2] - f2)


def rest_start(gx: float, gy: float, gz: float, ax: float, ay: float, az: float) -> RestState:
    """The rest detector's state at the first sample: its means start at that sample, quiet time
    0, the bias not measured yet."""
    return gx, gy, gz, ax, ay, az, 0.0, 0.0


def rest_step(
    rest: RestState, gx: float, gy: float, gz: float, ax: float, ay: float, az: float,
    bias: Vec3, dt: float, th_gyro: float, th_acc: float, rest_time: float, bound: float,
) -> RestState:
    """One step of the rest detector (REST_PARAMS). rest = (running mean of the rate (3), of the
    specific force (3), quiet time [s], bias measured (1.0) or not (0.0)); bias: the filter's gyro
    bias estimate in the frame of g; returns the new tuple. The caller compares the quiet time
    (element 6) with rest_time. Outside a rest the mean rate less the bias must be below th_gyro
    (plus bound until a first rest has measured the bias); a rest under way lasts while the rate
    and the specific force stay within their thresholds of their running means."""
    wx, wy, wz, fx, fy, fz, quiet, measured = rest
    k = dt / (REST_MEAN_TAU + dt)
    wx += k * (gx - wx)
    wy += k * (gy - wy)
    wz += k * (gz - wz)
    fx += k * (ax - fx)
    fy += k * (ay - fy)
    fz += k * (az - fz)
    th_g2 = th_gyro * th_gyro
    dx, dy, dz = gx - wx, gy - wy, gz - wz
    ex, ey, ez = ax - fx, ay - fy, az - fz
    still = dx * dx + dy * dy + dz * dz < th_g2 and ex * ex + ey * ey + ez * ez < th_acc * th_acc
    if still and quiet < rest_time:  # only a mean rate the bias explains may start a rest
        mx, my, mz = wx - bias[0], wy - bias[1], wz - bias[2]
        lim = th_gyro + bound if measured == 0.0 else th_gyro
        still = mx * mx + my * my + mz * mz < lim * lim
    quiet = quiet + dt if still else 0.0
    return wx, wy, wz, fx, fy, fz, quiet, (1.0 if quiet >= rest_time else measured)


def first_rest(measured_before: float, rest: RestState) -> bool:
    """True at the sample the first rest is measured: rest_step's flag rest[7] is on and was off
    (measured_before) before that step."""
    return measured_before == 0.0 and rest[7] != 0.0


def uncalibrated_first_rest(measured_before: float, rest: RestState, bias: Vec3,
                            th_gyro: float) -> bool:
    """True at the sample a first rest begins (rest_step's quiet time has just reached
    rest_time; no rest before it: measured_before, the flag before that step, is 0) with a mean
    rate that the bias estimate misses by th_gyro or more: a gyro that was not calibrated, whose
    rest only REST_PARAMS' rest_bias_bound admitted. Such a bias, up to the datasheet's 20 deg/s,
    has turned the tilt by up to its size times the time before this rest (a few degrees to tens)
    and would take rest_time more to learn by bias_at_rest, while the tilt error it leaves in the
    attitude and the turned accelerometer pre-filter decays only with the correction's time
    constant. So a filter without a bias covariance (cf, mgcf) then aligns, as an inertial
    system does at standstill: the rest's mean rate is its bias and its mean specific force is
    gravity
    (rest_alignment). A calibrated gyro (a residual of tenths of a deg/s, and BROAD's) never
    meets this, so its outputs are the same to the last bit."""
    if not first_rest(measured_before, rest):
        return False
    mx, my, mz = rest[0] - bias[0], rest[1] - bias[1], rest[2] - bias[2]
    return mx * mx + my * my + mz * mz >= th_gyro * th_gyro


def rest_alignment(rest: RestState) -> tuple[Vec3, float, float, Vec3]:
    """The alignment at an uncalibrated first rest (uncalibrated_first_rest): the gyro bias (the
    rest's mean rate), roll and pitch (accel_roll_pitch of its mean specific force, Gui et al.
    eq. 3-4) and that specific force, which the accelerometer pre-filters start again from."""
    f = (rest[3], rest[4], rest[5])
    roll, pitch = accel_roll_pitch(rest[3], rest[4], rest[5])
    return (rest[0], rest[1], rest[2]), roll, pitch, f


def bias_at_rest(bias: Vec3, gx: float, gy: float, gz: float, dt: float, rest_time: float
                 ) -> Vec3:
    """One step of a gyro-bias estimate that follows the gyro while the sensor is at rest
    (rest_step said so for rest_time): a first-order low-pass with time constant rest_time, the
    zero-angular-rate update of the filters without a bias covariance (cf, mgcf)."""
    k = dt / (rest_time + dt)
    bx, by, bz = bias
    return bx + k * (gx - bx), by + k * (gy - by), bz + k * (gz - bz)


def complementary_rest(
    rest: RestState, bias: Vec3, gx: float, gy: float, gz: float, ax: float, ay: float,
    az: float, dt: float, rest_time: float, rest_gyro: float, rest_acc: float, bound: float,
) -> tuple[RestState, Vec3, tuple[float, float, Vec3] | None]:
    """The rest detection of the filters without a bias covariance (cf, mgcf), one sample: the
    detector steps (rest_step); at an uncalibrated first rest they align (rest_alignment),
    otherwise at rest their bias follows the gyro (bias_at_rest). Returns the detector's state,
    the bias and, where they aligned, (roll, pitch, the specific force the accelerometer
    vector starts again from)."""
    measured = rest[7]
    rest = rest_step(rest, gx, gy, gz, ax, ay, az, bias, dt, rest_gyro, rest_acc, rest_time,
                     bound)
    if uncalibrated_first_rest(measured, rest, bias, rest_gyro):
        bias, roll, pitch, f = rest_alignment(rest)
        return rest, bias, (roll, pitch, f)
    if rest[6] >= rest_time:
        bias = bias_at_rest(bias, gx, gy, gz, dt, rest_time)
    return rest, bias, None


RECOMMENDED_GYRO_SCALE_STD: Final = 0.005
"""Recommended gyro_scale_std: the scale-factor errors of BROAD's gyro, fitted against its optical
reference on the nine trials that turn (testbenches.broad.gyro, no estimator involved), are
-0.53 to +0.74 % per axis; an MPU-6050's datasheet tolerance is +-3 % (1 % as 3 sigma)."""
RECOMMENDED_SCALE_TIME: Final = 0.5
"""Recommended scale_time [s]: how long a scale error adds up in one direction, about one swing
of a hand-held or robot motion (physics leaves its exact value open: a coarse scan of the kf on
BROAD has a plateau around it, whose middle this is)."""

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
times the white noise's (its RMS twice the noise's). 1 to 8 give the same BROAD mean and the same
testbench verdicts; below 4 the pre-filter switches within so narrow a band of disturbance that a
noise-free run's RMSE moves by up to 30 % with the sample times (contract T2), from 4 on by at
most 5 %."""


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


BIAS_GATE: Final = 0.05
"""Recommended bias_gate: Duong Quoc et al.'s experimental table for their MPU-6050 (section
4.2) stops trusting the accelerometer at rho = 0.05; here only the bias stops learning from it.
The accelerometer sees a gyro bias only as a slow drift of the tilt it measures; a sample whose
norm is 5 % off g carries linear acceleration (or vibration) whose apparent tilt would be taken
for that drift, and with a small Q_bias a bias learned wrong stays wrong for minutes. A resting
MEMS accelerometer (scale error up to 3 % uncalibrated) passes."""
BIAS_GATE_PARAM = Param(
    "bias_gate", BIAS_GATE,
    "Bias learning gate on rho = ||a|/g - 1| of the raw accelerometer sample: at or above it "
    "the accelerometer update leaves the gyro bias alone (the sample measures linear "
    "acceleration, not the drift of the tilt); 0 = off, every update moves the bias (the papers)",
    low=0.0, high=1000.0,
)


BIAS_INNOVATION: Final = 10.0 * DEG
"""Recommended bias_innovation. A gyro bias shows in the accelerometer update as a slow drift of
the tilt that each correction takes back: innovations of tenths of a degree (after the
pre-filter, BROAD's largest are a few degrees in the fast trials). An innovation of tens of
degrees means the attitude itself is grossly off (after a stretch of absurd samples, a knock,
a restart in motion); the filters' linear model of the angle-bias coupling does not hold there,
and learning from it winds the bias up to tens or hundreds of deg/s, which then takes minutes to
unwind (measured after 1 s of absurd but accepted samples: kf not back under 1 deg within 120 s;
with the gate, 14 s). The angle is corrected as always; only the bias waits."""
BIAS_INNOVATION_PARAM = Param(
    "bias_innovation", BIAS_INNOVATION,
    "Largest tilt innovation the gyro bias learns from: beyond it the attitude is grossly off "
    "(not a bias drift) and the accelerometer update corrects the angle only; pi = no limit "
    "(the papers)",
    unit="rad", low=0.0, low_open=True, high=math.pi, display_unit="deg",
)


def bias_band2(gate: float) -> tuple[float, float]:
    """BIAS_GATE_PARAM as bounds on the raw sample's squared norm: the bias learns while
    lo < |a|^2 < hi (any sample when the gate is 0, off)."""
    if not gate > 0.0:
        return -1.0, math.inf
    return (max(1.0 - gate, 0.0) * G) ** 2, ((1.0 + gate) * G) ** 2


Mat9 = tuple[float, float, float, float, float, float, float, float, float]

FACES: Final[tuple[Mat9, ...]] = (
    (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),  # z up: the identity
    (1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0),  # -z up: roll 180 deg
    (0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0),  # x up: the axes cycled, (y, z, x)
    (0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0),  # -x up
    (0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0),  # y up: (z, x, y)
    (0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0),  # -y up
)
"""The six faces a sensor can rest on, each as the rotation C (row by row) from the sensor frame
to a face frame whose z axis is that face's up axis: v_face = C v_sensor. Every C is a signed
permutation with determinant +1, so turning a vector into a face frame and back is exact."""

FACE_SWITCH_COS: Final = 0.5
"""A filter on a face moves to the nearest face once up is more than 60 deg from the face's z
axis (its z component below cos 60 deg). The nearest face is then at most 54.7 deg away (the
cube's diagonal), so the switch has a margin and cannot chatter, and the filter's pitch and roll
stay within 60 deg of level, far from the Euler angles' singularity at 90 deg."""


def nearest_face(ux: float, uy: float, uz: float) -> int:
    """Index into FACES of the face whose up axis is nearest the direction (ux, uy, uz)
    (sensor frame, any length); z up where the direction is zero."""
    ax, ay, az = abs(ux), abs(uy), abs(uz)
    if az >= ax and az >= ay:
        return 0 if uz >= 0.0 else 1
    if ax >= ay:
        return 2 if ux > 0.0 else 3
    return 4 if uy > 0.0 else 5


def mat_vec(m: Mat9, v: Vec3) -> Vec3:
    """m v for a 3x3 matrix m given row by row."""
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)


def mat_t_vec(m: Mat9, v: Vec3) -> Vec3:
    """m^T v for a 3x3 matrix m given row by row."""
    x, y, z = v
    return (m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z)
