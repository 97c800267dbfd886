"""Complementary filter for roll and pitch.

References:
  W. Gui, Y. Tang, S. Mukhopadhyay (2015), complementary filter vs Kalman filter for tilt,
  eq. 1-2: angle = a (angle + gyro dt) + (1 - a) acc_angle, a = tau / (tau + dt),
  tau = 0.75 s (a = 0.96 at their loop time dt = 0.03 s).
  Das & Mary, low-cost IMU filtering, eq. 1 (the same filter).
"""

from __future__ import annotations

from typing import Final

from .base import ESTIMATE, INTEGRATION_PARAM, Estimator, tuple_new
from .kinematics import (
    HALF_PI,
    PI,
    accel_roll_pitch,
    atan2,
    clamp_pitch,
    euler_step,
    heun_euler_step,
    quat_from_roll_pitch_yaw,
    quat_mul_rotvec,
    quat_roll_pitch,
    rotate_back,
    rotation_increment,
    wrap_angle,
)
from .types import DEG, MPU6050_GYRO_DENSITY, Estimate, G, Param

Vec3 = tuple[float, float, float]
ZERO3: Vec3 = (0.0, 0.0, 0.0)
NO_BIAS: Final[tuple[float, ...]] = ZERO3
"""ZERO3 as the compiled core's constant (no module-dict look-up): the CF's bias output."""

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

# ----- real-sensor options shared by cf, kf and mgcf (all off by default: the papers) -----------
ACC_LOWPASS_PARAM = Param(
    "acc_lowpass", 0.0,
    "Accelerometer pre-filter time constant: the specific force is low-passed in a frame that "
    "turns with the gyro, so linear acceleration averages out and gravity does not lag the "
    "rotation (Laidig & Seel 2023, VQF); the filter and its gate then use the filtered vector. "
    "0 = off: each raw sample (the papers)",
    unit="s", low=0.0,
)
"""The accelerometer pre-filter. Laidig & Seel (VQF: Highly accurate IMU orientation estimation
with bias estimation and magnetic disturbance rejection, Information Fusion 91, 2023) low-pass
filter the accelerometer in an almost inertial frame given by the gyro strapdown integration:
there the gravity part is constant, and the linear acceleration of a body that ends where it
started averages to (velocity change) / (time), so a low-pass with a time constant of seconds
removes most of it, without the lag that a body-frame low-pass has while the sensor turns. Here
the filtered vector is kept in body axes and turned with the gyro's rotation increment each
sample (a world-fixed vector seen from the body), which is the same filter. Each paper's filter is
then unchanged: it takes the filtered vector where it took the raw sample. Measured on BROAD's
real recordings (testbenches/broad.py): the fast-translation trials, whose raw accelerometer
swings between 0.02 g and 5 g, drop from tens of degrees to below 1 deg of inclination error."""

PROPAGATION_PARAM = Param(
    "propagation", "euler",
    "How the gyro carries roll and pitch between samples: 'euler' (the Z-Y-X Euler-rate "
    "kinematics, singular at pitch +-90 deg) or 'quaternion' (an attitude quaternion with a free "
    "yaw, turned by each interval's rotation vector: exact in every orientation)",
    choices=("euler", "quaternion"), tunable=False,
)
"""Propagation of the Euler-angle filters (cf, kf). The papers integrate the Euler rates
(Duong Quoc eq. 2), whose tan(pitch) term is singular at pitch +-90 deg: a sensor that turns
through the vertical (every rotation trial of BROAD does) loses the attitude there, and the
innovation of roll, which the accelerometer cannot observe near pitch +-90 deg, cannot bring it
back. With 'quaternion' the filter keeps an attitude quaternion q (yaw free, unobservable), turns
it by the bias-corrected rotation vector of each interval (the same integration rule as the
quaternion filters, kinematics.rotation_increment), takes roll and pitch from it, applies its
paper's correction to roll and pitch, and rebuilds q from the corrected roll and pitch and q's own
yaw. The correction law, its gains and its covariance are the paper's."""

RestState = tuple[float, float, float, float, float, float, float]
"""The rest detector's state: running means of the rate (3) and of the specific force (3), and
the quiet time [s]."""
REST_MEAN_TAU: Final = 0.5
"""Time constant [s] of the running means the rest detector compares each sample with (VQF's
restFilterTau)."""

REST_PARAMS: tuple[Param, ...] = (
    Param(
        "rest_time", 0.0,
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
)
"""Rest detection for a zero-angular-rate bias update. A still sensor's gyro reads its bias: an
uncalibrated MEMS gyro's turn-on bias (0.1-0.5 deg/s on BROAD's IMU, 0.5 deg/s about z) times a
correction time constant of seconds is a tilt error of tenths of a degree, and about z the bias is
not observable from the accelerometer at all while the sensor is level. The detector is VQF's
(Laidig & Seel 2023): the rate and the specific force must stay within the thresholds of their
running means (time constant REST_MEAN_TAU) for rest_time; its defaults (2 deg/s, 0.5 m/s^2)
are VQF's restThGyr and restThAcc."""


def zero_rate_psd_param(name: str = "gyro_psd") -> Param:
    """The gyro white-noise PSD of the zero-angular-rate update at rest (REST_PARAMS), whose
    measurement variance is PSD / dt; default the MPU-6050's. The UKF names it zaru_psd, since
    its gyro_psd is its process noise."""
    return Param(
        name, MPU6050_GYRO_DENSITY**2,
        "Gyro white-noise power spectral density of the zero-angular-rate update at rest: its "
        "variance is this / dt (the rate-noise density squared; MPU-6050: "
        "(0.005 deg/s/sqrt(Hz))^2)",
        unit="rad2/s", low=0.0, low_open=True, display_unit="deg2/s",
    )


def quat_yaw(w: float, x: float, y: float, z: float) -> float:
    """Yaw of a unit quaternion (body to world, Z-Y-X Euler), the companion of
    kinematics.quat_roll_pitch."""
    return atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quat_with_roll_pitch(
    q: tuple[float, float, float, float], roll: float, pitch: float
) -> tuple[float, float, float, float]:
    """The attitude with the given roll and pitch and q's yaw (PROPAGATION_PARAM)."""
    return quat_from_roll_pitch_yaw(roll, pitch, quat_yaw(*q))


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


def lowpass_specific_force(f: Vec3, phi: Vec3, a: Vec3, dt: float, tau: float) -> Vec3:
    """One step of the accelerometer pre-filter (ACC_LOWPASS_PARAM): the filtered specific force
    f turned with the body by phi, then blended with the new sample a, k = dt / (tau + dt)."""
    f0, f1, f2 = rotate_back(f, phi)
    k = dt / (tau + dt)
    return f0 + k * (a[0] - f0), f1 + k * (a[1] - f1), f2 + k * (a[2] - f2)


def rest_step(
    rest: RestState, gx: float, gy: float, gz: float, ax: float, ay: float, az: float,
    dt: float, th_gyro: float, th_acc: float,
) -> RestState:
    """One step of the rest detector (REST_PARAMS). rest = (running mean of the rate (3), of the
    specific force (3), quiet time [s]); returns the new tuple. The caller compares the quiet time
    (the last element) with rest_time."""
    wx, wy, wz, fx, fy, fz, quiet = rest
    k = dt / (REST_MEAN_TAU + dt)
    wx += k * (gx - wx)
    wy += k * (gy - wy)
    wz += k * (gz - wz)
    fx += k * (ax - fx)
    fy += k * (ay - fy)
    fz += k * (az - fz)
    th_g2 = th_gyro * th_gyro
    still = (
        (gx - wx) ** 2 + (gy - wy) ** 2 + (gz - wz) ** 2 < th_g2
        and wx * wx + wy * wy + wz * wz < th_g2
        and (ax - fx) ** 2 + (ay - fy) ** 2 + (az - fz) ** 2 < th_acc * th_acc
    )
    return wx, wy, wz, fx, fy, fz, (quiet + dt if still else 0.0)


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

    Options for real sensors, off by default (then the filter is exactly the papers'): with
    acc_lowpass > 0 the accelerometer is first low-passed in a frame that turns with the gyro
    (ACC_LOWPASS_PARAM, after Laidig & Seel 2023), and the gate and the blend use that vector;
    propagation="quaternion" carries roll and pitch through an attitude quaternion instead of the
    Euler rates (PROPAGATION_PARAM), so that pitch +-90 deg is no singularity.

    Parameters: tau [s] time constant (0.75); gate_low, gate_high accelerometer gate (|acc|/g);
    acc_lowpass [s] (0: off); propagation; integration; max_dt [s].
    """

    PARAMS = (
        Param(
            "tau", 0.75, "Complementary-filter time constant, a = tau/(tau+dt) (Gui et al. eq. 2)",
            unit="s", low=0.0, low_open=True,
        ),
        *ACC_GATE_PARAMS,
        ACC_LOWPASS_PARAM,
        PROPAGATION_PARAM,
        INTEGRATION_PARAM,
    )
    STATE = ("roll", "pitch", "acc_f", "q_att")

    def _configure(self) -> None:
        p = self._params
        self._tau = float(p["tau"])
        self._gate_low2, self._gate_high2 = gate_bounds2(p)
        self._trapezoid: bool = p["integration"] == "trapezoid"
        self._acc_tau = float(p["acc_lowpass"])
        self._quaternion: bool = p["propagation"] == "quaternion"
        # both options need the rotation vector of each interval; the papers' filter does not
        self._rotating = self._quaternion or self._acc_tau > 0.0

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0
        self.acc_f = ZERO3  # the pre-filtered specific force (acc_lowpass > 0)
        self.q_att = (1.0, 0.0, 0.0, 0.0)  # attitude, propagation="quaternion" only

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        self.roll, self.pitch = accel_roll_pitch(ax, ay, az)
        self.acc_f = (ax, ay, az)
        self.q_att = quat_from_roll_pitch_yaw(self.roll, self.pitch, 0.0)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        if self._rotating:
            phi = body_rotation(self.gyro_prev, (gx, gy, gz), ZERO3, dt, self._trapezoid)
            if self._acc_tau > 0.0:  # the filter and its gate use the pre-filtered vector
                self.acc_f = lowpass_specific_force(self.acc_f, phi, (ax, ay, az), dt,
                                                    self._acc_tau)
                ax, ay, az = self.acc_f
        if self._quaternion:  # (then self._rotating: phi is this interval's rotation)
            self.q_att = quat_mul_rotvec(self.q_att, *phi)
            roll, pitch = quat_roll_pitch(*self.q_att)
        elif self._trapezoid:
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
            if self._quaternion:
                self.q_att = quat_with_roll_pitch(self.q_att, roll, pitch)
        self.roll = roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)
        return tuple_new(ESTIMATE, (roll, pitch, NO_BIAS, None, None))

    def _estimate(self) -> Estimate:
        return Estimate(self.roll, self.pitch, ZERO3)


__all__ = [
    "ACC_GATE_PARAMS",
    "ACC_LOWPASS_PARAM",
    "PROPAGATION_PARAM",
    "REST_PARAMS",
    "ComplementaryFilter",
    "body_rotation",
    "gate_bounds2",
    "lowpass_specific_force",
    "quat_with_roll_pitch",
    "quat_yaw",
    "rest_step",
]
