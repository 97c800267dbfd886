"""Rest detection and the zero-angular-rate bias update: the detector's state (RestState), its
step, and what the filters without a bias covariance do at rest (bias_at_rest, the alignment at
an uncalibrated first rest)."""

from __future__ import annotations

from typing import Final, NamedTuple

from ..kinematics import accel_roll_pitch
from ..types import DEG, Param
from .sampling import REAL_GYRO_DENSITY, Vec3, on_the_mark


class RestState(NamedTuple):
    """The rest detector's state: running means of the rate (wx, wy, wz) and of the specific
    force (fx, fy, fz), the quiet time [s], measured: 1.0 once a rest has lasted rest_time (the
    bias has been measured), else 0.0, the mean specific force (ox, oy, oz) and the mean rate
    (rx, ry, rz) where the quiet time had lasted REST_MEAN_TAU (REST_TURN), and the rate's
    short mean (zx, zy, zz) over ZERO_RATE_TAU that a zero-rate update's gate judges. The C twin
    holds the same seventeen numbers in order (fc_real rest[FC_REST_SIZE])."""

    wx: float
    wy: float
    wz: float
    fx: float
    fy: float
    fz: float
    quiet_time: float
    measured: float
    ox: float
    oy: float
    oz: float
    rx: float
    ry: float
    rz: float
    zx: float
    zy: float
    zz: float


REST_START: Final = RestState(*(0.0,) * 17)
"""The rest detector's state before the first sample."""

REST_MEAN_TAU: Final = 0.5
"""Time constant [s] of the running means the rest detector compares each sample with (VQF's
restFilterTau)."""

REST_TURN: Final = 0.1
"""The share of rest_gyro by which the mean specific force may turn while a rest lasts: it must
stay within REST_TURN * rest_gyro * rest_time [rad] (0.3 deg with VQF's thresholds) of its
direction once the quiet time has lasted REST_MEAN_TAU. Until then the reference follows the
mean, which is still settling from the motion before (a 0.5 s mean moves by a tenth of its lag
over the next 1.2 s), so a rest right after a motion is recognised a second or so later than by
the rate thresholds alone. A rest is where the gyro reads its own bias, and the bias it
learns there is off by whatever the sensor still turns. The rate thresholds cannot tell a bias
from a slow turn: near the ends of a slow swing (a ship's roll, an arm tilting at a few deg/s)
the rate stays below rest_gyro for seconds, and the gyro's deviations from their running mean
stay small throughout a smooth rotation. Gravity's direction can: a turn about any horizontal
axis moves it. A tenth of the rate threshold bounds the bias error a rest may teach to a tenth of
what VQF's rule alone admits, and is still some twenty times the noise of a 0.5 s mean of a
consumer MEMS accelerometer (0.003 m/s^2 against 0.05). A turn about gravity itself stays
invisible, and leaves roll and pitch alone.

The mean rate must stay as still, within REST_TURN * rest_gyro of its value at the same
instant: at a still sensor it is the bias, constant to the noise of a 0.5 s mean (a
hundredth of a deg/s on a consumer gyro). At the turning point of a slow swing gravity's
direction stands for a second or so while the rate passes through zero, and the rate's mean
ramps: a swing of 40 deg at 0.02 Hz ramps it by 0.6 deg/s per second, so without this the
rest started there and taught the bias the ramp (testbenches.slow_roll). A tenth of the rate
threshold is the bias error a rest may teach, as above."""

REST_PARAMS: tuple[Param, ...] = (
    Param(
        "rest_time", 1.5,
        "Rest detection: after this long with the gyro and accelerometer within rest_gyro and "
        "rest_acc of their running means (the mean rate below rest_gyro, the mean specific "
        "force not turning) the sensor is at rest, and the gyro, which then reads its own "
        "bias, updates the bias estimate. 0 = off (the papers)",
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
at start-up never meets the turn-on rule: its outputs are those of VQF's rule to the last bit
wherever the sensor is still when the rates say so (tests/test_rest_detection.py). Where it is
not (a slow swing), gravity's direction turns, and a rest, starting or under way, ends
(REST_TURN)."""


ZERO_RATE_SPREAD: Final = 75.0
"""A zero-angular-rate update takes a sample only where the rate's short mean (ZERO_RATE_TAU)
is within sqrt(ZERO_RATE_SPREAD) standard deviations of its white noise (per axis, three axes
together: 5 sigma each) of the rest detector's running mean rate (zero_rate_sample). The
detector calls a rest by thresholds on smoothed rates (rest_gyro, 2 deg/s) so that noise and a
shaky table do not end it; a motion that fades in stays below them for a few tenths of a
second, and a bias that follows the gyro then learns the motion's first turn: on a sensor held
in the hand after a rest (the realistic MPU-6050, even a perfect one), a Kalman filter learned a
bias there which its bias gate (linear acceleration keeps the vector's norm off g) then kept for
the whole run (tests/test_rest_detection.py, a turn that fades in). A still gyro's short mean is
further than five sigma from the mean in a few per million; that of a fading-in turn is tens
of sigma off within a few hundredths of a second. A gyro several times noisier than the
filter's psd says loses a few percent of its rest samples to it, and still measures its
bias."""

ZERO_RATE_TAU: Final = 0.01
"""Time constant [s] of the rate's short mean that the zero-rate update's gate judges
(ZERO_RATE_SPREAD). Judged sample by sample, the gate's width is sqrt(psd / dt): a part
sampled ten times faster lets a turn three times faster through before it shuts, and its
bias learns the first turn of every motion that starts after a rest (tests/test_rest_detection.py,
the gate on a turn that fades in at 50 Hz to 10 kHz). A mean over a fixed time has the same
noise, sqrt(psd / (2 tau)), at every rate above 1 / tau, and a sampling slower than that leaves
it about the sample itself. The time is the one over which a body's first turn rises out of
the gyro's noise: a ramp of alpha [rad/s^2] leaves a mean of time constant tau by
alpha (t - tau), which reaches the gate's c sqrt(psd / (2 tau)) soonest for
tau^(3/2) = c sqrt(psd / 2) / (2 alpha); a hand's first turn (10-50 deg/s^2) on a consumer gyro
(0.005-0.015 deg/s/sqrt(Hz)) gives 5-20 ms, and 10 ms is the middle of that range. Derived, not
fitted."""

CONSTANT_REST_GYRO_VAR: Final = REAL_GYRO_DENSITY * REAL_GYRO_DENSITY
"""The gyro white-noise PSD [rad^2/s] of the filters without a noise model (cf, mgcf) for
zero_rate_sample: a real MEMS IMU's measured density squared (zero_rate_psd_param's default)."""


def zero_rate_sample(rest: RestState, r: float, dt: float) -> bool:
    """Whether the gyro sample rest_step last took may update the bias at rest
    (ZERO_RATE_SPREAD): the squared distance of the rate's short mean (ZERO_RATE_TAU) from the
    rest detector's running mean rate within ZERO_RATE_SPREAD times its white-noise variance
    per axis: r, one sample's (psd / dt), times the share the short mean leaves of it
    (mean_share)."""
    dx, dy, dz = rest.zx - rest.wx, rest.zy - rest.wy, rest.zz - rest.wz
    return dx * dx + dy * dy + dz * dz <= ZERO_RATE_SPREAD * r * mean_share(dt, ZERO_RATE_TAU)


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


def mean_share(dt: float, tau: float) -> float:
    """The share of one sample's white-noise variance left in a first-order running mean of
    time constant tau (gain k = dt / (tau + dt)): k / (2 - k)."""
    k = dt / (tau + dt)
    return k / (2.0 - k)


def rest_mean_share(dt: float) -> float:
    """mean_share of the rest detector's running mean (REST_MEAN_TAU). A filter that takes its
    tilt from a rest's mean specific force is that sure of it."""
    return mean_share(dt, REST_MEAN_TAU)


def rest_start(gx: float, gy: float, gz: float, ax: float, ay: float, az: float) -> RestState:
    """The rest detector's state at the first sample: its means start at that sample, quiet time
    0, the bias not measured yet."""
    return RestState(gx, gy, gz, ax, ay, az, 0.0, 0.0, ax, ay, az, gx, gy, gz, gx, gy, gz)


def rest_step(
    rest: RestState, gx: float, gy: float, gz: float, ax: float, ay: float, az: float,
    bias: Vec3, dt: float, th_gyro: float, th_acc: float, rest_time: float, bound: float,
) -> RestState:
    """One step of the rest detector (REST_PARAMS); bias: the filter's gyro bias estimate in the
    frame of g; returns the new RestState. The caller compares its quiet_time with rest_time.
    Outside a rest the mean rate less the bias must be below th_gyro (plus bound until a first
    rest has measured the bias); a rest, starting or under way, lasts while the rate and the
    specific force stay within their thresholds of their running means and the mean specific
    force and the mean rate within REST_TURN of their values early in the quiet time."""
    wx, wy, wz, fx, fy, fz, quiet, measured, ox, oy, oz, rx, ry, rz, zx, zy, zz = rest
    k = dt / (ZERO_RATE_TAU + dt)
    zx += k * (gx - zx)
    zy += k * (gy - zy)
    zz += k * (gz - zz)
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
    if still and quiet >= REST_MEAN_TAU:  # gravity's direction has not turned (REST_TURN)
        ex, ey, ez = fx - ox, fy - oy, fz - oz
        turn = REST_TURN * th_gyro * rest_time
        still = ex * ex + ey * ey + ez * ez < turn * turn * (fx * fx + fy * fy + fz * fz)
        if still:  # nor has the mean rate ramped
            dx, dy, dz = wx - rx, wy - ry, wz - rz
            ramp = REST_TURN * th_gyro
            still = dx * dx + dy * dy + dz * dz < ramp * ramp
    if still and quiet < rest_time:  # only a mean rate the bias explains may start a rest
        mx, my, mz = wx - bias[0], wy - bias[1], wz - bias[2]
        lim = th_gyro + bound if measured == 0.0 else th_gyro
        still = mx * mx + my * my + mz * mz < lim * lim
    if still and quiet < REST_MEAN_TAU:  # the means settle: the references follow them
        ox, oy, oz = fx, fy, fz
        rx, ry, rz = wx, wy, wz
    quiet = on_the_mark(on_the_mark(quiet + dt, dt, REST_MEAN_TAU), dt, rest_time) if still else 0.0
    return RestState(wx, wy, wz, fx, fy, fz, quiet, 1.0 if quiet >= rest_time else measured,
                     ox, oy, oz, rx, ry, rz, zx, zy, zz)


def first_rest(measured_before: float, rest: RestState) -> bool:
    """True at the sample the first rest is measured: rest_step's flag `measured` is on and was
    off (measured_before) before that step."""
    return measured_before == 0.0 and rest.measured != 0.0


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
    gravity (rest_alignment). A calibrated gyro (a residual of tenths of a deg/s, and BROAD's) never
    meets this, so its outputs are the same to the last bit."""
    if not first_rest(measured_before, rest):
        return False
    mx, my, mz = rest.wx - bias[0], rest.wy - bias[1], rest.wz - bias[2]
    return mx * mx + my * my + mz * mz >= th_gyro * th_gyro


def rest_alignment(rest: RestState) -> tuple[Vec3, float, float, Vec3]:
    """The alignment at an uncalibrated first rest (uncalibrated_first_rest): the gyro bias (the
    rest's mean rate), roll and pitch (accel_roll_pitch of its mean specific force, Gui et al.
    eq. 3-4) and that specific force, which the accelerometer pre-filters start again from."""
    f = (rest.fx, rest.fy, rest.fz)
    roll, pitch = accel_roll_pitch(rest.fx, rest.fy, rest.fz)
    return (rest.wx, rest.wy, rest.wz), roll, pitch, f


def bias_at_rest(bias: Vec3, gx: float, gy: float, gz: float, dt: float, rest_time: float,
                 since: float) -> Vec3:
    """One step of a gyro-bias estimate that follows the gyro while the sensor is at rest
    (rest_step said so for rest_time; since: the time [s] since it did): the zero-angular-rate
    update of the filters without a bias covariance (cf, mgcf). A first-order low-pass whose
    memory grows with the rest's time, from REST_MEAN_TAU to rest_time: at first nearly the
    mean of the rest's samples, the earlier estimate counting as much as the rest detector's own
    running mean, so that a short rest measures the bias about as well as its length allows;
    then a follower of time constant rest_time. A follower of that time constant from the start
    takes only 1 - 1/e of a bias by the end of rest_time; this one takes more of a short rest
    (tests/test_rest_detection.py: a 3 s rest measures the bias to 25 %). A shorter start of
    the memory measures more of a short rest but follows more of the few deg/s at a slow
    swing's end where a rest is taken too early (tests/test_rest_detection.py: the mgcf leaves
    its 1 deg there from 0.1 s)."""
    memory = since + REST_MEAN_TAU
    if memory > rest_time:
        memory = rest_time
    k = dt / (memory + dt)
    bx, by, bz = bias
    return bx + k * (gx - bx), by + k * (gy - by), bz + k * (gz - bz)


def complementary_rest(
    rest: RestState, bias: Vec3, gx: float, gy: float, gz: float, ax: float, ay: float,
    az: float, dt: float, rest_time: float, rest_gyro: float, rest_acc: float, bound: float,
) -> tuple[RestState, Vec3, tuple[float, float, Vec3] | None]:
    """The rest detection of the filters without a bias covariance (cf, mgcf), one sample: the
    detector steps (rest_step); at an uncalibrated first rest they align (rest_alignment),
    otherwise at rest their bias follows the gyro (bias_at_rest) where the sample is one of a
    still gyro (zero_rate_sample with CONSTANT_REST_GYRO_VAR). Returns the detector's state,
    the bias and, where they aligned, (roll, pitch, the specific force the accelerometer
    vector starts again from)."""
    measured = rest.measured
    rest = rest_step(rest, gx, gy, gz, ax, ay, az, bias, dt, rest_gyro, rest_acc, rest_time,
                     bound)
    if uncalibrated_first_rest(measured, rest, bias, rest_gyro):
        bias, roll, pitch, f = rest_alignment(rest)
        return rest, bias, (roll, pitch, f)
    if rest.quiet_time >= rest_time and zero_rate_sample(rest, CONSTANT_REST_GYRO_VAR / dt, dt):
        bias = bias_at_rest(bias, gx, gy, gz, dt, rest_time, rest.quiet_time - rest_time)
    return rest, bias, None
