"""Two-state [angle, bias] Kalman filter, one for roll and one for pitch.

References:
  W. Gui, Y. Tang, S. Mukhopadhyay (2015), eq. 5-26: x = [angle, bias], F = [[1, -dt], [0, 1]],
  B = [dt, 0], H = [1, 0], Q = diag(Q_angle, Q_bias) dt, R = R_measure; Q_angle = 0.001,
  Q_bias = 0.003, R_measure = 0.03 (angles in degrees); loop time 0.033 s.
  Das & Mary, eq. 16-27: the same filter written scalar by scalar (P00..P11, K0, K1), with a
  temporary copy of P in the covariance update. Jain & Epelbaum (EE444) derive the same
  covariance propagation from the continuous Pdot = A P + P A' + Q (rotomotion tilt.c).

Units. The papers feed the filter degrees and deg/s, and their Q and R are tuned for that. This
class works in radians; its defaults are the papers' numbers times (pi/180)^2 (Q_angle in rad^2/s,
Q_bias in rad^2/s^3, R_measure in rad^2). Scaling every angle-like state by k = pi/180 scales P,
Q and R by k^2 and leaves the gain K unchanged, so on the same samples this filter's angles and
biases are exactly the degree filter's times pi/180 (tests/test_kalman.py checks it to 1e-9 deg).
"""

from __future__ import annotations

import dataclasses
from math import cos, pi, sin, sqrt
from typing import Any, ClassVar, Final

from .base import ESTIMATE, Estimator, tuple_new
from .building_blocks import (
    ACC_GATE_PARAMS,
    ACC_LOWPASS_PARAM,
    ADAPTIVE_NOISE_PARAMS,
    BIAS_GATE_PARAM,
    BIAS_INNOVATION_PARAM,
    CONSTANT_NOISE,
    FACE_SWITCH_COS,
    FACES,
    GYRO_SAMPLING_PARAM,
    MAX_CORRECTION_TIME_PARAM,
    NO_RAIL,
    PROPAGATION_PARAM,
    REAL_GYRO_DENSITY,
    REST_PARAMS,
    REST_START,
    ZERO3,
    Vec3,
    adaptive_noise_constants,
    bias_band2,
    body_rotation,
    first_rest,
    gate_bounds2,
    mat_t_vec,
    mat_vec,
    nearest_face,
    quat_from_roll_pitch,
    rest_start,
    rest_step,
    zero_rate_psd_param,
)
from .kinematics import (
    HALF_PI,
    PI,
    accel_roll_pitch,
    clamp_pitch,
    euler_step,
    heun_euler_step,
    quat_from_roll_pitch_yaw,
    quat_mul_rotvec,
    quat_roll_pitch,
    rotvec_terms,
    wrap_angle,
)
from .measured_vector import (
    BAND_PARAM,
    MEASURE_CHECK,
    measure_clipped,
    measure_constants,
    measure_restarted,
    measure_start,
    measure_step,
    measure_turned,
)
from .state import ANGLE, COV, HALF_ANGLE, NONNEG, REAL, REST, UNIT, StateSpec, index
from .types import DEG, Estimate, G, Param

DEG2: Final = DEG * DEG
KALMAN_MAX_CORRECTION_TIME: Final = dataclasses.replace(MAX_CORRECTION_TIME_PARAM, default=30.0)
"""max_correction_time of the Kalman filters (kf, ukf): 30 s, the longest correction time their
measurement noise may reach: R is capped at Q T^2 / dt, with Q the step's angle process noise
(for a random-walk angle, the Kalman gain's time constant is sqrt(R dt / Q)). They learn the gyro
bias in motion too, so what is left of it after a start-up calibration (0.1-0.3 deg/s) times this
bounds the drift while a long disturbance leaves the accelerometer unused. A shorter bound lets
sustained linear acceleration in: on the contract's high_dynamics (0.5-0.7 g for seconds, 6
parts) the ukf's pitch RMSE is 4.9 deg at 20 s, 4.4 at 30 s, 4.15 at 40-60 s, against its 5 deg
bound; BROAD's mean moves by 0.001 deg from 30 to 60 s."""
RECOMMENDED_INIT_BIAS_STD: Final = 0.3 * DEG
"""Recommended init_bias_std: the gyro bias a part keeps after its start-up calibration (the
realistic MPU-6050's 0.16 deg/s, 1 sigma, its datasheet's drift over 1 K of warm-up), about two
standard deviations. A larger prior lets the first seconds of motion (a slow translation, a
ramp of linear acceleration the statistic has not yet measured) into the bias."""
PAPER_KF: Final[dict[str, Any]] = {
    "Q_angle": 0.001 * DEG2, "Q_bias": 0.003 * DEG2, "R_measure": 0.03 * DEG2,
    "R_loop_time": 0.033, **CONSTANT_NOISE, "gate_low": 0.9,
    "gate_high": 1.1, "acc_lowpass": 0.0, "rest_time": 0.0, "init_bias_std": 0.0, "bias_gate": 0.0,
    "bias_innovation": pi, "propagation": "euler", "tilt_axes": "body",
    "gyro_sampling": "mean", "sensor_delay": 0.0, **NO_RAIL,
}
"""Gui et al. eq. 5-26, Das & Mary eq. 16-27: Q_angle 0.001, Q_bias 0.003, R 0.03 in degrees
(times (pi/180)^2 here), tuned at Gui et al.'s loop time of 0.033 s (R_loop_time: the same
correction time constant at any rate, AngleBiasKalmanFilter), P = 0 at the start, the
Euler rates, the rectangle rule; their Q and R are constants (gyro_scale_std and
disturbance_time 0)."""

RECOMMENDED_R: Final = (0.05 / G) ** 2
"""Recommended R_measure [rad^2]: the variance of one accelerometer sample's tilt, (0.05 m/s^2 /
g)^2 = (0.29 deg)^2, from the accelerometer's noise measured at rest on a real MEMS IMU
(0.045-0.07 m/s^2 per sample on BROAD's)."""


def predict_covariance(
    P: tuple[float, float, float, float], dt: float, q_angle: float, q_bias: float
) -> tuple[float, float, float, float]:
    """F P F' + Q, F = [[1, -dt], [0, 1]], Q = diag(q_angle, q_bias) dt (Das & Mary eq. 19-22)."""
    P00, P01, P10, P11 = P
    return (
        P00 + dt * (dt * P11 - P01 - P10 + q_angle),
        P01 - dt * P11,
        P10 - dt * P11,
        P11 + q_bias * dt,
    )


def measurement_gain(
    P: tuple[float, float, float, float], r: float
) -> tuple[tuple[float, float], tuple[float, float, float, float]]:
    """Gain and covariance of the update with an angle measurement (Das & Mary eq. 23-27).

    S = P00 + R; K = [P00, P10] / S; P <- (I - K H) P using the old P values (the papers'
    temporaries), not values already overwritten. Returns K = (K0, K1) and the new P; the state
    update is angle += K0 y, bias += K1 y with the innovation y = acc_angle - angle.
    """
    P00, P01, P10, P11 = P
    S = P00 + r
    K0 = P00 / S
    K1 = P10 / S
    return (K0, K1), (P00 - K0 * P00, P01 - K0 * P01, P10 - K1 * P00, P11 - K1 * P01)


def angle_only_gain(
    P: tuple[float, float, float, float], r: float
) -> tuple[tuple[float, float], tuple[float, float, float, float]]:
    """The update of measurement_gain with the bias left out (K1 = 0, the bias a "consider"
    state: Schmidt 1966): K0 = P00 / S as before, and P <- (I - K H) P (I - K H)^T + K R K^T,
    which for this K is P00 - K0 P00, P01 - K0 P01, P10 - K0 P10, P11."""
    P00, P01, P10, P11 = P
    K0 = P00 / (P00 + r)
    return (K0, 0.0), (P00 - K0 * P00, P01 - K0 * P01, P10 - K0 * P10, P11)


def bias_update(
    angle: float, bias: float, P: tuple[float, float, float, float], y: float, r: float
) -> tuple[float, float, tuple[float, float, float, float]]:
    """Update with a direct bias measurement, H = [0, 1], innovation y (standard Kalman form)."""
    P00, P01, P10, P11 = P
    S = P11 + r
    K0 = P01 / S
    K1 = P11 / S
    return (
        angle + K0 * y,
        bias + K1 * y,
        (P00 - K0 * P10, P01 - K0 * P11, P10 - K1 * P10, P11 - K1 * P11),
    )


class AngleBiasKalmanFilter(Estimator):
    """Gui et al. / Das & Mary 2-state Kalman filter, one for roll and one for pitch.

    State per axis [angle, gyro bias]; the roll filter estimates the x gyro bias, the pitch filter
    the y gyro bias. bias_z is 0: a bias about z does not change the accelerometer's tilt, so it
    is unobservable here.

    Propagation: the bias-corrected body rate (gx - bias_x, gy - bias_y, gz) drives the full Z-Y-X
    Euler-rate kinematics (Heun's method with the previous and current sample, or the papers'
    rectangle rule with gyro_sampling="mean"), so roll and pitch do not couple when they move
    together; the covariance follows the papers' F (their model, with the per-axis bias entering
    with -dt). For roll-only motion this is exactly the papers' algorithm.

    Measurement: roll and pitch from the accelerometer (atan2), applied only while
    gate_low <= |acc|/g <= gate_high (the accelerometer-magnitude gate; outside it the filter
    only predicts). The innovation is wrapped to [-pi, pi].

    Initialisation: the first valid sample sets the angles from the accelerometer and the biases
    to 0. With init_bias_std > 0 (recommended) P starts as diag(R_measure, init_bias_std^2): the
    angles as sure as one accelerometer sample, the bias as its prior (with a small, physical
    Q_bias a zero prior would keep the bias from ever moving); with init_bias_std = 0, P = 0
    like the papers' reference code.

    Options for real sensors, all on by default (the `paper` preset turns them off, and then the
    filter is exactly the papers'):
    - acc_lowpass > 0: the accelerometer is low-passed in a frame that turns with the gyro
      (building_blocks.ACC_LOWPASS_PARAM, after Laidig & Seel 2023) before the gate and the
      measurement, so linear acceleration averages out instead of reading as tilt;
    - rest_time > 0: while a rest detector (building_blocks.REST_PARAMS) says the sensor is still,
      a zero-angular-rate update: the gyro measures the bias directly (H = [0, 1], variance
      gyro_psd / dt; the standard Kalman update, bias_update). The z-axis bias, which the
      accelerometer's tilt cannot observe, then gets a state of its own, bias_z (a random walk
      with Q_bias, observed only at rest), used in the propagation and output as bias_z; with
      rest detection off bias_z stays 0 as before;
    - propagation="quaternion": roll and pitch are carried by an attitude quaternion with a free
      yaw instead of the Euler rates (building_blocks.PROPAGATION_PARAM), so that pitch +-90 deg
      is no singularity; the covariance and the measurement update are the papers';
    - tilt_axes="nearest_face": the roll and the pitch filter run on the axes of the face the
      sensor rests on nearest to up (building_blocks.FACES), not on the sensor's own x and y.
      The papers' filters are made for a sensor near level: their accelerometer roll
      atan2(ay, az) is noise at pitch +-90 deg (a sensor resting x-up), where R_measure still
      trusts it, and the accelerometer can only teach them the bias of the x and y gyro axes,
      while it is the horizontal axes whose bias tilts the estimate (x-up: y and z). On the
      nearest face every resting orientation is the level case; the filters move to a new face
      once up is 60 deg from the old one (_switch_face), carrying every state across exactly.
      The outputs (roll, pitch, biases) are always in the sensor's frame.

    Recommended values (the defaults), from sensor physics: Q_angle = the gyro's noise PSD and
    R_measure = the variance of one accelerometer sample's tilt (RECOMMENDED_R), which together
    give a correction time constant sqrt(R dt / Q_angle) of 2.2 s at 285.7 Hz and 3.7 s at 100
    Hz (the papers' numbers, tuned at 30 Hz, give 0.3 s at 285.7 Hz); gyro_psd (the zero-rate
    update) the same PSD; init_bias_std = 0.3 deg/s (RECOMMENDED_INIT_BIAS_STD), with the angles'
    first variance R (one sample's) plus ((|a| - g) / g)^2; the
    pre-filter, rest detection and quaternion propagation as building_blocks recommends, on the
    nearest face; the bias learns from the accelerometer only while the raw sample's norm is
    within 5 % of g (bias_gate, building_blocks.BIAS_GATE_PARAM: Duong Quoc et al.'s real-sensor
    cutoff) and while both innovations are within 10 deg (bias_innovation,
    building_blocks.BIAS_INNOVATION: a larger one is a gross attitude error, not a bias drift).
    Q_bias, from a coarse scan on BROAD (1e-6 / 1e-8 / 1e-10 deg^2/s^3: 0.73 / 0.62 / 0.62 deg):
    the accelerometer's error after the pre-filter is coloured (residual linear acceleration),
    so a bias random walk sized from the gyro's real drift (3e-6 deg^2/s^3) lets it steer the
    bias in motion with a time constant of seconds; 1e-8 leaves the bias to the rest updates.
    The papers' values (Q_angle 0.001, Q_bias 0.003, R 0.03 in degrees, P = 0 at the start) are
    presets.PAPER_KF, with R_loop_time = 0.033 s: Gui et al. chose them "after many trials" at
    that loop time, and with Q a density (times dt, eq. 5-26) but R per sample the same R at
    a faster rate gives a shorter correction time constant sqrt(R dt / Q_angle) (0.55 s at
    100 Hz instead of their 1.0 s), so a filter that follows more linear acceleration; R_loop_time
    keeps the time constant they tuned (R_k = R_measure R_loop_time / dt, the usual
    continuous-to-discrete rule for a measurement noise, exact at their loop time).
    The recommended R_measure is a measured per-sample variance (R_loop_time = 0).

    Adaptive noise (recommended; off in the papers' filter): building_blocks.ADAPTIVE_NOISE_PARAMS.
    Q_angle grows by gyro_scale_std^2 w^2 scale_time while the sensor turns at rate w (the gyro's
    scale uncertainty); the filter measures the vector of fusion_core.measured_vector, a
    second-order low-pass of the gyro-turned specific force, and each step's R is one sample's
    variance plus the linear acceleration slow enough to reach that vector, over g^2 (shaking
    and vibration, which the low-pass removes, do not count), capped at Q T^2 / dt so that the
    correction time never exceeds T = max_correction_time; the vector shortens to the raw
    sample where no disturbance above the white noise is measured
    (building_blocks.adaptive_prefilter_time). No bias is learned from a vector that is still
    filling, or that holds samples turned by a gyro at its rail (gyro_range), and a clipped
    sample grows the angles' variance by the rate beyond the rail. On the testbench (realistic
    sensor, seed 0, against constant Q, R and pre-filter) high_dynamics 6.9/6.6 -> 2.8/4.2 deg
    (`python -m testbenches run --estimator kf`); on BROAD 0.512 deg in sample, 0.532
    cross-validated (`python -m testbenches broad DIR --cv`).

    Parameters: Q_angle [rad^2/s], Q_bias [rad^2/s^3], R_measure [rad^2], R_loop_time [s];
    gyro_scale_std, scale_time [s], disturbance_time [s], slow_band_time [s],
    max_correction_time [s]; gate_low, gate_high; acc_lowpass [s]; rest_time [s], rest_gyro
    [rad/s], rest_acc [m/s^2], gyro_psd [rad^2/s]; init_bias_std [rad/s]; bias_gate;
    bias_innovation [rad]; propagation; tilt_axes; gyro_sampling; max_dt [s], max_rate [rad/s].
    """

    PARAMS = (
        Param(
            "Q_angle", REAL_GYRO_DENSITY**2,
            "Process noise of the angle per second of integration: the gyro's noise PSD "
            "((0.008 deg/s/sqrt(Hz))^2; papers' 0.001 deg^2/s)",
            unit="rad2/s", low=0.0, display_unit="deg2/s",
        ),
        Param(
            "Q_bias", 1e-8 * DEG2,
            "Process noise of the gyro bias per second (1e-8 (deg/s)^2/s; papers' 0.003)",
            unit="rad2/s3", low=0.0, display_unit="deg2/s3",
        ),
        Param(
            "R_measure", RECOMMENDED_R,
            "Variance of the accelerometer angle measurement ((0.29 deg)^2; papers' 0.03 deg^2)",
            unit="rad2", low=0.0, low_open=True, display_unit="deg2",
        ),
        Param(
            "R_loop_time", 0.0,
            "Loop time R_measure was tuned at (0: R_measure is each sample's variance, whatever "
            "the rate; > 0: each step's variance is R_measure R_loop_time / dt, so the "
            "correction keeps the bandwidth it was tuned for at any rate; papers' 0.033 s)",
            unit="s", low=0.0,
        ),
        *ADAPTIVE_NOISE_PARAMS,
        *ACC_GATE_PARAMS,
        ACC_LOWPASS_PARAM,
        *REST_PARAMS,
        zero_rate_psd_param(),
        Param(
            "init_bias_std", RECOMMENDED_INIT_BIAS_STD,
            "Initial standard deviation of the gyro-bias states (0: P = 0 at the first sample, "
            "the papers' code)",
            unit="rad/s", low=0.0, tunable=False, display_unit="deg/s",
        ),
        BIAS_GATE_PARAM,
        BIAS_INNOVATION_PARAM,
        PROPAGATION_PARAM,
        Param(
            "tilt_axes", "nearest_face",
            "The axes of the roll and the pitch filter: 'body' (the sensor's x and y, the "
            "papers'; on a sensor resting on another face they lose the tilt near pitch +-90 deg "
            "and cannot learn the bias of the horizontal z axis) or 'nearest_face' (the sensor "
            "frame turned by the right-angle rotation that brings the axis nearest to up onto z, "
            "chosen again past 60 deg: every resting face is the level case; takes effect with "
            "propagation='quaternion')",
            choices=("body", "nearest_face"), tunable=False,
        ),
        GYRO_SAMPLING_PARAM,
        BAND_PARAM,
        KALMAN_MAX_CORRECTION_TIME,
    )
    TWIN: ClassVar[str | None] = "fc_kf"
    STATE: ClassVar[StateSpec] = {
        "roll": ANGLE, "pitch": HALF_ANGLE, "bias_x": REAL, "bias_y": REAL, "P_roll": COV,
        "P_pitch": COV, "bias_z": REAL, "P_z": NONNEG, "meas": MEASURE_CHECK, "rest": REST,
        "q_att": UNIT, "face": index(len(FACES)),
    }

    def _configure(self) -> None:
        p = self._params
        self._q_angle = float(p["Q_angle"])
        self._q_bias = float(p["Q_bias"])
        self._r = float(p["R_measure"])
        self._r_loop = self._r * float(p["R_loop_time"])  # R dt, the same at every rate
        self.r_step = self._r  # this step's measurement variance (set by propagate if R_loop_time)
        self._gate2 = gate_bounds2(p)
        self._trapezoid: bool = p["gyro_sampling"] == "point"
        self._acc_tau = float(p["acc_lowpass"])
        # the zero-rate update's constants, read together
        self._rest_cfg = (
            float(p["rest_time"]), float(p["rest_gyro"]), float(p["rest_acc"]),
            float(p["gyro_psd"]), float(p["rest_bias_bound"]),
        )
        # the adaptive noise (building_blocks.ADAPTIVE_NOISE_PARAMS): Q's rotation term per
        # (rad/s)^2, the disturbance's averaging time (0: off), the white noise's share
        self._adaptive = adaptive_noise_constants(p, self._acc_tau)
        self._measure = measure_constants(self._acc_tau, self._adaptive[1],
                                          float(p["slow_band_time"]), self._r)
        self._longest2 = float(p["max_correction_time"]) ** 2
        self._rail_var = float(p["gyro_range"]) ** 2 / 3.0  # the rate beyond the rail, per axis
        self._quaternion: bool = p["propagation"] == "quaternion"
        # the faces need the attitude quaternion to carry the state across (with the Euler rates
        # the filters stay on the sensor's axes)
        self._faces: bool = p["tilt_axes"] == "nearest_face" and self._quaternion
        self._bias_band2 = bias_band2(float(p["bias_gate"]))
        self._bias_innovation = float(p["bias_innovation"])
        # any real-sensor option on (else the papers' filter: the short path of _advance)
        self._options = self._quaternion or self._acc_tau > 0.0 or float(p["rest_time"]) > 0.0

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0
        self.bias_x = 0.0
        self.bias_y = 0.0
        self.P_roll = (0.0, 0.0, 0.0, 0.0)
        self.P_pitch = self.P_roll  # one covariance for both axes (see propagate)
        self.r_step = self._r
        self.bias_z = 0.0  # only with rest detection (rest_time > 0); else 0: unobservable
        self.P_z = 0.0
        self.meas = measure_start(ZERO3, self._measure)  # the measured vector (acc_lowpass > 0)
        self.rest = REST_START  # rest detector (building_blocks.RestState)
        self.q_att = (1.0, 0.0, 0.0, 0.0)  # attitude, propagation="quaternion" only
        self.gain_roll = (0.0, 0.0)
        self.gain_pitch = (0.0, 0.0)
        self.face = 0  # index into FACES of the filters' frame (tilt_axes); 0: the sensor's own
        self.q_step = self._q_angle  # this step's angle process noise (propagate sets it)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        if self._faces:
            self.face = nearest_face(ax, ay, az)
            if self.face:
                C = FACES[self.face]
                ax, ay, az = mat_vec(C, (ax, ay, az))
                gx, gy, gz = mat_vec(C, (gx, gy, gz))
        self.roll, self.pitch = accel_roll_pitch(ax, ay, az)
        self.meas = measure_start((ax, ay, az), self._measure)
        self.rest = rest_start(gx, gy, gz, ax, ay, az)
        self.q_att = quat_from_roll_pitch_yaw(self.roll, self.pitch, 0.0)
        p_b = self._params["init_bias_std"] ** 2
        if p_b > 0.0:
            # one accelerometer sample's variance for the angles it set (the posterior of that
            # one measurement): with P00 = 0 the filter would be sure of a first sample taken
            # in motion and explain the innovations that follow by a gyro bias. A sample whose
            # norm is off g by d carries at least d of linear acceleration: its tilt is as
            # uncertain as d / g more
            p_a = self._r
            if self._acc_tau > 0.0:
                d = (sqrt(ax * ax + ay * ay + az * az) - G) / G
                p_a += d * d
            self.P_roll = self.P_pitch = (p_a, 0.0, 0.0, p_b)
            self.P_z = p_b

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        if self._options:
            face = self.face
            prev = self.gyro_prev
            if face:  # into the face frame (tilt_axes)
                C = FACES[face]
                ax, ay, az = mat_vec(C, (ax, ay, az))
                gx, gy, gz = mat_vec(C, (gx, gy, gz))
                prev = mat_vec(C, prev)
            self._update_with_options(ax, ay, az, gx, gy, gz, dt, prev)
            # up's z in the face frame, cos(roll) cos(pitch), read off the attitude quaternion
            # (the z of quat_gravity_body) without two cosines
            if self._faces:
                w, x, y, z = self.q_att
                if w * w - x * x - y * y + z * z < FACE_SWITCH_COS:
                    self._switch_face()
            if self.face:
                return self._estimate()
        else:
            self.propagate(gx, gy, gz, dt)
            low2, high2 = self._gate2
            norm2 = ax * ax + ay * ay + az * az
            if low2 <= norm2 <= high2:  # accel_trusted, written out
                lo, hi = self._bias_band2
                self.correct(ax, ay, az, lo < norm2 < hi)
        return tuple_new(
            ESTIMATE, (self.roll, self.pitch, (self.bias_x, self.bias_y, self.bias_z), None, None)
        )

    def _update_with_options(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float,
        prev: Vec3,
    ) -> None:
        """One sample with the real-sensor options (see the class docstring), in the filters'
        frame; prev is the previous gyro sample in that frame."""
        phi = terms = None
        if self._quaternion or self._acc_tau > 0.0:
            bias = (self.bias_x, self.bias_y, self.bias_z)
            phi = body_rotation(prev, (gx, gy, gz), bias, dt, self._trapezoid)
            terms = rotvec_terms(*phi)  # once, for the propagation and the pre-filter
        self.propagate(gx, gy, gz, dt, phi, terms)
        clipped = self.clipped  # at the gyro's rail: the rate beyond it is unknown (gyro_range)
        if clipped:
            grow = self._rail_var * dt * dt
            P, P_pitch = self.P_roll, self.P_pitch
            self.P_roll = (P[0] + grow, P[1], P[2], P[3])
            self.P_pitch = (self.P_roll if P_pitch == P
                            else (P_pitch[0] + grow, P_pitch[1], P_pitch[2], P_pitch[3]))
        predicted = (self.roll, self.pitch)
        raw2 = ax * ax + ay * ay + az * az
        lo, hi = self._bias_band2
        # the raw sample, before the pre-filter (bias_gate); never a sample at the rail
        learn_bias = lo < raw2 < hi and not clipped
        if self._rest_cfg[0] > 0.0 and not clipped:  # rest_time
            self._zero_rate_update(ax, ay, az, gx, gy, gz, dt)
        if self._acc_tau > 0.0:
            assert phi is not None and terms is not None  # computed above whenever acc_tau > 0
            m = measure_clipped(self.meas) if clipped else self.meas
            self.meas, r, filling = measure_step(m, (ax, ay, az), phi, terms, dt,
                                                 self._measure)
            # one sample's variance (or the papers' R_loop_time rule) plus the disturbance that
            # reaches the measured vector, up to the longest correction time
            base = self._r_loop / dt if self._r_loop > 0.0 else self._r
            r = base + (r - self._measure.r)
            cap = self.q_step * self._longest2 / dt
            self.r_step = r if r < cap else (cap if cap > base else base)
            # no bias from a vector that is filling (a mean of the first samples, of a motion's
            # start as likely as of rest) or holds turns the gyro did not measure (gyro_range)
            learn_bias = learn_bias and not filling and self.meas.settled(self._measure)
            ax, ay, az = self.meas.f
        if self.accel_trusted(ax * ax + ay * ay + az * az):
            self.correct(ax, ay, az, learn_bias)
        if self._quaternion and (self.roll, self.pitch) != predicted:
            self.q_att = quat_from_roll_pitch(self.roll, self.pitch)

    def _zero_rate_update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        """Rest detection; at rest the gyro sample measures the bias (variance gyro_psd/dt):
        the x and y biases through the [angle, bias] filters, bias_z through its own state."""
        rest_time, rest_gyro, rest_acc, gyro_var, bound = self._rest_cfg
        measured = self.rest[7]
        bias = (self.bias_x, self.bias_y, self.bias_z)
        self.rest = rest_step(self.rest, gx, gy, gz, ax, ay, az, bias, dt, rest_gyro, rest_acc,
                              rest_time, bound)
        if self._acc_tau > 0.0 and first_rest(measured, self.rest):
            # the measured vector was turned with a bias not measured yet: it starts again from
            # the rest's mean specific force (measured_vector.measure_restarted), the angles
            # from its tilt
            f = (self.rest[3], self.rest[4], self.rest[5])
            self.meas = measure_restarted(self.meas, f)
            self.roll, self.pitch = accel_roll_pitch(*f)
        self.P_z += self._q_bias * dt
        if self.rest[6] >= rest_time:
            r = gyro_var / dt
            self.correct_bias(gx, gy, r)
            k = self.P_z / (self.P_z + r)
            self.bias_z += k * (gz - self.bias_z)
            self.P_z -= k * self.P_z

    def propagate(
        self, gx: float, gy: float, gz: float, dt: float, phi: Vec3 | None = None,
        terms: tuple[float, float, float, float] | None = None,
    ) -> None:
        """Time update: angles by the Euler-rate kinematics (or, with propagation="quaternion",
        by the attitude quaternion turned by the rotation vector phi of the interval, computed
        here when not given, with its rotvec_terms), P by the papers' F and Q
        (predict_covariance)."""
        bx, by, bz = self.bias_x, self.bias_y, self.bias_z
        if self._quaternion:
            if phi is None:
                phi = body_rotation(self.gyro_prev, (gx, gy, gz), (bx, by, bz), dt,
                                    self._trapezoid)
            self.q_att = quat_mul_rotvec(self.q_att, phi[0], phi[1], phi[2], terms)
            roll, pitch = quat_roll_pitch(*self.q_att)
        elif self._trapezoid:
            p0, q0, r0 = self.gyro_prev
            roll, pitch = heun_euler_step(
                self.roll, self.pitch, p0 - bx, q0 - by, r0 - bz, gx - bx, gy - by, gz - bz, dt
            )
        else:
            roll, pitch = euler_step(self.roll, self.pitch, gx - bx, gy - by, gz - bz, dt)
        self.roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)
        if self._r_loop > 0.0:
            self.r_step = self._r_loop / dt
        q_angle = self._q_angle
        q_rotation = self._adaptive[0]
        if q_rotation > 0.0:  # gyro_scale_std: a scale error adds up while the sensor turns
            wx, wy, wz = gx - bx, gy - by, gz - bz
            q_angle += q_rotation * (wx * wx + wy * wy + wz * wz)
        self.q_step = q_angle
        # The roll and the pitch filter have the same F, Q and R and every update treats both,
        # so P_roll == P_pitch: one covariance, computed once (the same numbers as twice). A
        # state snapshot with two different ones is still followed axis by axis.
        P, P_pitch = self.P_roll, self.P_pitch
        self.P_roll = predict_covariance(P, dt, q_angle, self._q_bias)
        if P_pitch == P:
            self.P_pitch = self.P_roll
        else:
            self.P_pitch = predict_covariance(P_pitch, dt, q_angle, self._q_bias)

    def accel_trusted(self, norm2: float) -> bool:
        """Whether the accelerometer gate is open for a sample of squared norm norm2."""
        low2, high2 = self._gate2
        return low2 <= norm2 <= high2

    def correct(self, ax: float, ay: float, az: float, learn_bias: bool = True) -> None:
        """Measurement update of both axes with the accelerometer's roll and pitch (the biases
        left alone unless learn_bias, bias_gate, and while an innovation exceeds
        bias_innovation)."""
        acc_roll, acc_pitch = accel_roll_pitch(ax, ay, az)
        y_roll = acc_roll - self.roll
        if not -PI <= y_roll <= PI:
            y_roll = wrap_angle(y_roll)
        y_pitch = acc_pitch - self.pitch
        gate = self._bias_innovation
        if not (-gate <= y_roll <= gate and -gate <= y_pitch <= gate):
            learn_bias = False  # grossly off: the angle only (bias_innovation)
        self.correct_innovation(y_roll, y_pitch, learn_bias)

    def correct_innovation(self, y_roll: float, y_pitch: float, learn_bias: bool = True) -> None:
        """Measurement update with given innovations (accelerometer angle - predicted angle);
        with learn_bias False the biases are consider states (angle_only_gain)."""
        gain = measurement_gain if learn_bias else angle_only_gain
        P, P_pitch = self.P_roll, self.P_pitch
        r = self.r_step
        self.gain_roll, self.P_roll = gain(P, r)
        if P_pitch == P:  # one covariance (see propagate)
            self.gain_pitch, self.P_pitch = self.gain_roll, self.P_roll
        else:
            self.gain_pitch, self.P_pitch = gain(P_pitch, r)
        K0, K1 = self.gain_roll
        roll = self.roll + K0 * y_roll
        self.bias_x += K1 * y_roll
        K0, K1 = self.gain_pitch
        pitch = self.pitch + K0 * y_pitch
        self.bias_y += K1 * y_pitch
        self.roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)

    def correct_bias(self, z_x: float, z_y: float, r: float) -> None:
        """Update with direct measurements z of the x and y gyro bias (variance r each).

        Used as a zero-angular-rate update: a gyro at rest reads its bias.
        """
        self.roll, self.bias_x, self.P_roll = bias_update(
            self.roll, self.bias_x, self.P_roll, z_x - self.bias_x, r
        )
        self.pitch, self.bias_y, self.P_pitch = bias_update(
            self.pitch, self.bias_y, self.P_pitch, z_y - self.bias_y, r
        )

    def _switch_face(self) -> None:
        """Move the filters to the face nearest to up (tilt_axes="nearest_face"), once up is more
        than 60 deg from the current face's z axis (FACE_SWITCH_COS).

        Every state is turned by D = C_new C_old^T, a signed permutation: the attitude (its yaw
        is free, so it restarts at 0), the biases, the pre-filtered specific force and the rest
        detector's means. The [angle, bias] covariance of an axis that stays horizontal goes with
        it; the axis that was vertical brings only its bias variance P_z, with the larger of the
        two angle variances (no accelerometer update had measured a tilt about it)."""
        roll, pitch = self.roll, self.pitch
        cp = cos(pitch)
        C = FACES[self.face]
        up = (-sin(pitch), sin(roll) * cp, cos(roll) * cp)
        new = nearest_face(*mat_t_vec(C, up))
        if new == self.face:
            return
        C2 = FACES[new]

        def turn(v: Vec3) -> Vec3:
            return mat_vec(C2, mat_t_vec(C, v))

        self.roll, self.pitch = accel_roll_pitch(*turn(up))
        self.q_att = quat_from_roll_pitch_yaw(self.roll, self.pitch, 0.0)
        self.bias_x, self.bias_y, self.bias_z = turn((self.bias_x, self.bias_y, self.bias_z))
        self.meas = measure_turned(self.meas, turn)
        r = self.rest
        self.rest = (*turn((r[0], r[1], r[2])), *turn((r[3], r[4], r[5])), r[6], r[7])
        P_roll, P_pitch, P_z = self.P_roll, self.P_pitch, self.P_z
        vertical = (max(P_roll[0], P_pitch[0]), 0.0, 0.0, P_z)
        old = (P_roll, P_pitch, vertical)
        # the old axis that each new axis is: the nonzero of row k of D
        source = [j for k in range(3) for j in range(3) if turn_axis(C2, C, k, j) != 0.0]
        self.P_roll, self.P_pitch = old[source[0]], old[source[1]]
        self.P_z = old[source[2]][3]
        self.face = new

    def _estimate(self) -> Estimate:
        if self.face:  # from the face frame back to the sensor's (tilt_axes)
            C = FACES[self.face]
            cp = cos(self.pitch)
            up = mat_t_vec(C, (-sin(self.pitch), sin(self.roll) * cp, cos(self.roll) * cp))
            roll, pitch = accel_roll_pitch(*up)
            return Estimate(roll, pitch, mat_t_vec(C, (self.bias_x, self.bias_y, self.bias_z)))
        return Estimate(self.roll, self.pitch, (self.bias_x, self.bias_y, self.bias_z))


def turn_axis(C2: tuple[float, ...], C: tuple[float, ...], k: int, j: int) -> float:
    """Entry (k, j) of C2 C^T for 3x3 matrices given row by row."""
    return C2[3 * k] * C[3 * j] + C2[3 * k + 1] * C[3 * j + 1] + C2[3 * k + 2] * C[3 * j + 2]
