"""The recommended two-state [angle, bias] Kalman filter for roll and for pitch, for real MEMS
IMUs: the papers' filter (fusion_core.papers.kalman: Gui et al. 2015 eq. 5-26, Das & Mary eq.
16-27, whose equations it uses) with the mechanisms of building_blocks and
fusion_core.measured_vector around it (AngleBiasKalmanFilter).
"""

from __future__ import annotations

import dataclasses
from math import cos, sin, sqrt
from typing import ClassVar, Final

from .base import Estimator, SensorNoise
from .building_blocks import (
    ACC_GATE_PARAMS,
    ACC_LOWPASS_PARAM,
    ADAPTIVE_NOISE_PARAMS,
    BIAS_GATE_PARAM,
    BIAS_INNOVATION_PARAM,
    FACE_SWITCH_COS,
    FACES,
    GROSS_INNOVATION_PARAM,
    MAX_CORRECTION_TIME_PARAM,
    REAL_GYRO_DENSITY,
    REST_PARAMS,
    REST_START,
    ZERO3,
    RestState,
    Vec3,
    adaptive_noise_constants,
    bias_band2,
    body_rotation,
    corrected_quat,
    first_rest,
    gate_bounds2,
    nearest_face,
    quat_from_roll_pitch,
    rest_mean_share,
    rest_start,
    rest_step,
    tilt_innovation,
    zero_rate_psd_param,
    zero_rate_sample,
)
from .kinematics import (
    HALF_PI,
    PI,
    accel_roll_pitch,
    clamp_pitch,
    quat_from_roll_pitch_yaw,
    quat_mul_rotvec,
    quat_roll_pitch,
    rotvec_terms,
    up_terms,
    wrap_angle,
)
from .linalg import mat_t_vec, mat_vec
from .measured_vector import (
    BAND_PARAM,
    BURST_PARAM,
    HELD_PARAM,
    LEAK_PARAM,
    MEASURE_CHECK,
    STRETCH_PARAM,
    fill_noise,
    measure_clipped,
    measure_constants,
    measure_restarted,
    measure_start,
    measure_step,
    measure_turned,
    within_bias_band,
)
from .papers.kalman import RollPitchAxes
from .state import ANGLE, COV, HALF_ANGLE, NONNEG, REAL, REST, UNIT, StateSpec, index
from .types import DEG, Estimate, G, Param

DEG2: Final = DEG * DEG
KALMAN_MAX_CORRECTION_TIME: Final = dataclasses.replace(MAX_CORRECTION_TIME_PARAM, default=30.0)
"""max_correction_time of the Kalman filters (kf, ukf): 30 s, the longest correction time their
measurement noise may reach: R is capped at Q T^2 / dt, with Q the step's angle process noise
(for a random-walk angle, the Kalman gain's time constant is sqrt(R dt / Q)). They learn the gyro
bias in motion too, so what is left of it after a start-up calibration (0.1-0.3 deg/s) times this
bounds the drift while a long disturbance leaves the accelerometer unused. A shorter bound lets
sustained linear acceleration in: the contract's high_dynamics (0.5-0.7 g for seconds) sets the
lower end, BROAD (`broad --cv`) shows no change above it."""
RECOMMENDED_INIT_BIAS_STD: Final = 0.3 * DEG
"""Recommended init_bias_std: the gyro bias a part keeps after its start-up calibration (the
realistic MPU-6050's 0.16 deg/s, 1 sigma, its datasheet's drift over 1 K of warm-up), about two
standard deviations. A larger prior lets the first seconds of motion (a slow translation, a
ramp of linear acceleration the statistic has not yet measured) into the bias."""


def bias_prior(noise: SensorNoise) -> float:
    """The Kalman filters' init_bias_std for a sensor: the larger of the recommended prior and
    the part's bias spread (a part run without its start-up calibration learns its bias from
    the accelerometer where it never rests, instead of holding it near zero)."""
    return max(RECOMMENDED_INIT_BIAS_STD, noise.gyro_bias_std)

RECOMMENDED_R: Final = (0.05 / G) ** 2
"""Recommended R_measure [rad^2]: the variance of one accelerometer sample's tilt, (0.05 m/s^2 /
g)^2 = (0.29 deg)^2, from the accelerometer's noise measured at rest on a real MEMS IMU
(0.045-0.07 m/s^2 per sample on BROAD's)."""


def angle_only_gain(
    P: tuple[float, float, float, float], r: float
) -> tuple[tuple[float, float], tuple[float, float, float, float]]:
    """The update of measurement_gain with the bias left out (K1 = 0, the bias a "consider"
    state: Schmidt 1966): K0 = P00 / S as before, and P <- (I - K H) P (I - K H)^T + K R K^T,
    which for this K is P00 - K0 P00, P01 - K0 P01, P10 - K0 P10, P11."""
    P00, P01, P10, P11 = P
    K0 = P00 / (P00 + r)
    return (K0, 0.0), (P00 - K0 * P00, P01 - K0 * P01, P10 - K0 * P10, P11)


def measured_axis(P: tuple[float, float, float, float], var: float, age: float
                  ) -> tuple[float, float, float, float]:
    """An axis's covariance once its angle is set from a measurement of variance var whose
    samples were turned by the gyro over age [s] on average (0: a rest's mean, not turned): a
    bias error b turned them by -b age, so the angle's variance is var + P11 age^2 and its
    covariance with the bias -age P11, as the propagation's is -t P11; P11 stays."""
    P11 = P[3]
    c = 0.0 - P11 * age
    return (var + P11 * age * age, c, c, P11)


Z_BIAS_REST_ONLY: Final = (
    "while z is the axis nearest to up, a bias about it does not change the accelerometer's "
    "tilt, so only the zero-rate update at rest (rest_time > 0, the default) observes it: 0 "
    "until the sensor has rested or lain on another face (tilt_axes='nearest_face', the "
    "default), and 0 throughout with neither"
)
"""Why bias_z of the [angle, bias] Kalman filter (and of the position filter, whose attitude is
that filter's) can stay 0 (Estimator.ZERO_BIAS)."""


class AngleBiasKalmanFilter(RollPitchAxes, Estimator):
    """The recommended 2-state [angle, gyro bias] Kalman filter for roll and for pitch.

    The papers' filter (fusion_core.papers.kalman: Gui et al. eq. 5-26, Das & Mary eq. 16-27):
    per axis the state [angle, bias], the covariance by their F and Q (predict_covariance), the
    accelerometer's roll and pitch (atan2) as the measurement of the angles (measurement_gain),
    applied only while gate_low <= |acc|/g <= gate_high; the roll innovation wrapped to
    [-pi, pi]. Around it, for real MEMS IMUs:
    - attitude quaternion: roll and pitch are carried by an attitude quaternion with a free yaw,
      turned by the interval's rotation vector (the trapezoid rate with the coning term for
      point samples, the rectangle rule for mean samples, building_blocks.GYRO_SAMPLING_PARAM),
      not by the Euler rates, so that pitch +-90 deg is no singularity;
    - the nearest face: the roll and the pitch filter run on the axes of the face the sensor
      rests on nearest to up (building_blocks.FACES), not on the sensor's own x and y. The
      papers' filters are made for a sensor near level: their accelerometer roll atan2(ay, az)
      is noise at pitch +-90 deg (a sensor resting x-up), where R_measure still trusts it, and
      the accelerometer can teach them only the bias of the x and y gyro axes, while it is the
      horizontal axes whose bias tilts the estimate. On the nearest face every resting
      orientation is the level case; the filters move to a new face once up is 60 deg from the
      old one (_switch_face), carrying every state across exactly. The outputs (roll, pitch,
      biases) are always in the sensor's frame;
    - the measured vector (acc_lowpass > 0; fusion_core.measured_vector): the filter measures a
      second-order low-pass of the gyro-turned specific force (after Laidig & Seel 2023), and
      each step's R is one sample's variance plus the linear acceleration slow enough to reach
      that vector, over g^2, capped at Q T^2 / dt so that the correction time never exceeds
      T = max_correction_time: no disturbance, however long, leaves the filter on the gyro
      alone for longer;
    - rest detection (rest_time > 0; building_blocks.REST_PARAMS): at rest the gyro measures the
      bias directly (H = [0, 1], variance gyro_psd / dt; bias_update). The z-axis bias, which
      the accelerometer's tilt cannot observe, has a state of its own, bias_z (a random walk
      with Q_bias, observed only at rest);
    - adaptive process noise (building_blocks.ADAPTIVE_NOISE_PARAMS): Q_angle grows by
      gyro_scale_std^2 w^2 scale_time while the sensor turns at rate w (the gyro's scale
      uncertainty);
    - a gyro at its rail (gyro_range): the rate beyond it is unknown, so the angles' variance
      grows by it, no bias is learned from the sample and the measured vector starts again;
    - the bias learns from the accelerometer only while the norm of what reaches the measured
      vector (its slow band: measured_vector.gate_norm2; without the vector the raw sample's) is
      within bias_gate of g (Duong Quoc et al.'s real-sensor cutoff), so is the vector's own
      where the slow band is measured (a disturbance the slow band has passed stays in the
      vector for its length), both innovations are within bias_innovation (a larger one is a gross
      attitude error, not a bias drift; no limit by default: BIAS_INNOVATION_PARAM) and the
      measured vector is settled; otherwise the
      biases are consider states (angle_only_gain). A bias learned wrong on a horizontal axis
      and carried to z by a face switch would stay, as bias_z is observed only at rest (a
      second of absurd samples during a slow roll: `imu-fusion battery --motion slow_rotation
      --sensor mpu6050_glitch`);
    - a gross innovation (beyond gross_innovation, more than a held linear acceleration can
      tilt the measured vector by): the attitude is off by at least that much, so the angle's
      variance is raised to the innovation squared before the update (raised_angle_variance).

    Start: the first valid sample sets the angles from the accelerometer and the biases to 0,
    with P = diag(R_measure + ((|a| - g) / g)^2, init_bias_std^2); while the measured vector
    fills, the angles are its tilt, and at the first rest the rest's. The defaults follow from
    the sensor's noise (noise_params). Why each is so: docs/estimators/kf.md, "Start" and "The
    defaults".
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
        *ADAPTIVE_NOISE_PARAMS,
        *ACC_GATE_PARAMS,
        ACC_LOWPASS_PARAM,
        *REST_PARAMS,
        zero_rate_psd_param(),
        Param(
            "init_bias_std", RECOMMENDED_INIT_BIAS_STD,
            "Initial standard deviation of the gyro-bias states (the papers' code starts from "
            "P = 0, their filter, fusion_core.papers.kalman)",
            unit="rad/s", low=0.0, low_open=True, tunable=False, display_unit="deg/s",
        ),
        BIAS_GATE_PARAM,
        BIAS_INNOVATION_PARAM,
        GROSS_INNOVATION_PARAM,
        BAND_PARAM,
        LEAK_PARAM,
        HELD_PARAM,
        BURST_PARAM,
        STRETCH_PARAM,
        KALMAN_MAX_CORRECTION_TIME,
    )
    TWIN: ClassVar[str | None] = "fc_kf"
    BIAS_IN_MOTION: ClassVar[tuple[int, ...]] = (0, 1)
    SCANNED: ClassVar[tuple[str, ...]] = ("Q_bias",)
    GYRO_ONLY: ClassVar[dict[str, float] | None] = {"acc_lowpass": 0.0, "rest_time": 0.0,
                                                    "gate_high": 2.0}
    ZERO_BIAS: ClassVar[dict[str, str]] = {"bias_z": Z_BIAS_REST_ONLY}
    STATE: ClassVar[StateSpec] = {
        "roll": ANGLE, "pitch": HALF_ANGLE, "bias_x": REAL, "bias_y": REAL, "P_roll": COV,
        "P_pitch": COV, "bias_z": REAL, "P_z": NONNEG, "meas": MEASURE_CHECK, "rest": REST,
        "q_att": UNIT, "face": index(len(FACES)),
    }

    @classmethod
    def noise_params(cls, noise: SensorNoise) -> dict[str, float]:
        """Q_angle and gyro_psd (its zero-rate update) = the gyro's PSD, R_measure = the
        variance of one sample's tilt, (acc_sample_std / g)^2, and init_bias_std bias_prior's."""
        gyro_psd = noise.gyro_density * noise.gyro_density
        return {"Q_angle": gyro_psd, "R_measure": (noise.acc_sample_std / G) ** 2,
                "gyro_psd": gyro_psd,
                "init_bias_std": bias_prior(noise)}

    def _configure(self) -> None:
        p = self._params
        self._q_angle = float(p["Q_angle"])
        self._q_bias = float(p["Q_bias"])
        self._r = float(p["R_measure"])
        self.r_step = self._r  # this step's measurement variance (the measured vector's noise)
        self._gate2 = gate_bounds2(p)
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
                                          float(p["slow_band_time"]), self._r,
                                          float(p["gyro_scale_std"]),
                                          float(p["acc_lowpass_stretch"]),
                                          float(p["slow_band_leak"]),
                                          float(p["held_acceleration"]),
                                          float(p["burst_acceleration"]))
        self._longest2 = float(p["max_correction_time"]) ** 2
        self._rail_var = float(p["gyro_range"]) ** 2 / 3.0  # the rate beyond the rail, per axis
        self._bias_band2 = bias_band2(float(p["bias_gate"]))
        self._bias_innovation = float(p["bias_innovation"])
        self._gross_innovation = float(p["gross_innovation"])

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0
        self.bias_x = 0.0
        self.bias_y = 0.0
        self.P_roll = (0.0, 0.0, 0.0, 0.0)
        self.P_pitch = self.P_roll  # one covariance for both axes (see propagate)
        self.r_step = self._r
        self.bias_z = 0.0  # observed only at rest (rest_time > 0)
        self.P_z = 0.0
        self.meas = measure_start(ZERO3, self._measure)  # the measured vector (acc_lowpass > 0)
        self.rest = REST_START  # rest detector (building_blocks.RestState)
        self.q_att = (1.0, 0.0, 0.0, 0.0)  # the attitude, with a free yaw
        self.gain_roll = (0.0, 0.0)
        self.gain_pitch = (0.0, 0.0)
        self.face = 0  # index into FACES of the filters' frame; 0: the sensor's own
        self.q_step = self._q_angle  # this step's angle process noise (propagate sets it)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
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
        # one accelerometer sample's variance for the angles it set (the posterior of that one
        # measurement): with P00 = 0 the filter would be sure of a first sample taken in motion
        # and explain the innovations that follow by a gyro bias. A sample whose norm is off g
        # by d carries at least d of linear acceleration: its tilt is as uncertain as d / g more
        p_a = self._r
        if self._acc_tau > 0.0:
            d = (sqrt(ax * ax + ay * ay + az * az) - G) / G
            p_a += d * d
        self.P_roll = self.P_pitch = (p_a, 0.0, 0.0, p_b)
        self.P_z = p_b

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        face = self.face
        prev = self.gyro_prev
        if face:  # into the face frame
            C = FACES[face]
            ax, ay, az = mat_vec(C, (ax, ay, az))
            gx, gy, gz = mat_vec(C, (gx, gy, gz))
            prev = mat_vec(C, prev)
        self._update(ax, ay, az, gx, gy, gz, dt, prev)
        # up's z in the face frame, cos(roll) cos(pitch), read off the attitude quaternion
        # (the z of quat_gravity_body) without two cosines
        w, x, y, z = self.q_att
        if w * w - x * x - y * y + z * z < FACE_SWITCH_COS:
            self._switch_face()
        if self.face:
            return self._estimate()
        return Estimate(self.roll, self.pitch, (self.bias_x, self.bias_y, self.bias_z))

    def _update(  # type: ignore[override]
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float,
        prev: Vec3,
    ) -> None:
        """One sample in the filters' frame (see the class docstring); prev is the previous gyro
        sample in that frame."""
        bias = (self.bias_x, self.bias_y, self.bias_z)
        phi = body_rotation(prev, (gx, gy, gz), bias, dt, self._trapezoid)
        terms = rotvec_terms(*phi)  # once, for the propagation and the pre-filter
        up = self.propagate(gx, gy, gz, dt, phi, terms)
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
        # at a first rest the angles are its tilt (_zero_rate_update)
        rested = (self._rest_cfg[0] > 0.0 and not clipped
                  and self._zero_rate_update(ax, ay, az, gx, gy, gz, dt))
        filling = False
        reset = rested  # the angles set from a tilt: q rebuilt from them
        # what a zero-rate update moved the angles by; the correction adds to it (correct), and
        # q is turned by the sum
        turn = (self.roll - predicted[0], self.pitch - predicted[1])
        if self._acc_tau > 0.0:
            m = measure_clipped(self.meas) if clipped else self.meas
            self.meas, r, filling = measure_step(m, (ax, ay, az), phi, terms, dt,
                                                 self._measure, self.rest.measured > 0.0)
            # one sample's variance plus the disturbance that reaches the measured vector, up
            # to the longest correction time
            base = self._r
            r = base + (r - self._measure.r)
            cap = self.q_step * self._longest2 / dt
            self.r_step = r if r < cap else (cap if cap > base else base)
            ax, ay, az = self.meas.f
            a2 = ax * ax + ay * ay + az * az
            # the bias gate on what reaches the vector (gate_norm2) and, where that is the slow
            # band, on what the vector still holds, its own norm: after a disturbance the slow
            # band is back within a fraction of a second while the vector holds it for its
            # length, and the attitude that followed the vector drifts back to gravity as it
            # refills, a drift an update would take for a bias. No bias from a vector that is
            # filling (a mean of the first samples, of a motion's start as likely as of rest) or
            # holds turns the gyro did not measure (gyro_range)
            learn_bias = (within_bias_band(self.meas, self._measure, (lo, hi), a2, raw2)
                          and not clipped and not filling and self.meas.settled(self._measure))
        else:  # the raw sample (bias_gate); never a sample at the rail
            a2 = raw2
            learn_bias = lo < raw2 < hi and not clipped
        if self.accel_trusted(a2):
            if not filling:
                turn = self.correct(ax, ay, az, learn_bias, up, turn)
            elif not rested:  # (a first rest's mean, which no gyro error turned, stands)
                # the vector still fills: the attitude is its tilt (as cf's and mgcf's), as
                # uncertain as that vector, its samples turned over their mean age (fill_noise)
                self.roll, self.pitch = accel_roll_pitch(ax, ay, az)
                reset = True
                var, age = fill_noise(self.meas, r, dt, self._measure)
                self.P_roll = measured_axis(self.P_roll, var, age)
                self.P_pitch = measured_axis(self.P_pitch, var, age)
        if reset:
            self.q_att = quat_from_roll_pitch(self.roll, self.pitch)
        elif (self.roll, self.pitch) != predicted:  # q turned by the correction
            self.q_att = corrected_quat(self.q_att, up, self.roll, self.pitch, *turn)

    def _zero_rate_update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> bool:
        """Rest detection; at rest the gyro sample measures the bias (variance gyro_psd/dt):
        the x and y biases through the [angle, bias] filters, bias_z through its own state.
        Returns whether this sample is the first rest's, which set the angles (with the
        measured vector)."""
        rest_time, rest_gyro, rest_acc, gyro_var, bound = self._rest_cfg
        measured = self.rest.measured
        bias = (self.bias_x, self.bias_y, self.bias_z)
        self.rest = rest_step(self.rest, gx, gy, gz, ax, ay, az, bias, dt, rest_gyro, rest_acc,
                              rest_time, bound)
        rested = self._acc_tau > 0.0 and first_rest(measured, self.rest)
        if rested:
            # the measured vector was turned with a bias not measured yet: it starts again from
            # the rest's mean specific force (measured_vector.measure_restarted), the angles
            # from its tilt, as sure of them as that mean is (and independent of the bias)
            f = (self.rest.fx, self.rest.fy, self.rest.fz)
            self.meas = measure_restarted(self.meas, f)
            self.roll, self.pitch = accel_roll_pitch(*f)
            p = self._r * rest_mean_share(dt)
            self.P_roll = measured_axis(self.P_roll, p, 0.0)
            self.P_pitch = measured_axis(self.P_pitch, p, 0.0)
        self.P_z += self._q_bias * dt
        if self.rest.quiet_time >= rest_time:
            r = gyro_var / dt
            if zero_rate_sample(self.rest, r, dt):  # a still gyro's sample
                self.correct_bias(gx, gy, r)
                k = self.P_z / (self.P_z + r)
                self.bias_z += k * (gz - self.bias_z)
                self.P_z -= k * self.P_z
        return rested

    def propagate(
        self, gx: float, gy: float, gz: float, dt: float, phi: Vec3,
        terms: tuple[float, float, float, float],
    ) -> tuple[float, float, float, float]:
        """Time update: the attitude quaternion turned by the interval's rotation vector phi
        (with its rotvec_terms), roll and pitch read off it, P by the papers' F and Q
        (predict_covariance) with the adaptive Q_angle. Returns the turned q's up_terms, which
        the correction measures its innovation from."""
        bx, by, bz = self.bias_x, self.bias_y, self.bias_z
        self.q_att = q = quat_mul_rotvec(self.q_att, phi[0], phi[1], phi[2], terms)
        roll, pitch = quat_roll_pitch(*q)
        self.roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)
        q_angle = self._q_angle
        q_rotation = self._adaptive[0]
        if q_rotation > 0.0:  # gyro_scale_std: a scale error adds up while the sensor turns
            wx, wy, wz = gx - bx, gy - by, gz - bz
            q_angle += q_rotation * (wx * wx + wy * wy + wz * wz)
        self.q_step = q_angle
        self.predict_covariances(dt, q_angle)
        return up_terms(*q)

    def correct(self, ax: float, ay: float, az: float, learn_bias: bool,
                up: tuple[float, float, float, float], moved: tuple[float, float]
                ) -> tuple[float, float]:
        """Measurement update of both axes with the accelerometer's roll and pitch (the biases
        left alone unless learn_bias, bias_gate, and while an innovation exceeds
        bias_innovation). The innovations are the angles from the tilt of the predicted
        attitude (up: its up_terms, propagate's) to the accelerometer's
        (building_blocks.tilt_innovation), less what a zero-rate update moved the angles by
        since (moved). Returns the angles' change since the prediction, that move plus the
        correction (gain times innovation): the turn of q (corrected_quat), which so does not
        wait for the arctangents that read the predicted angles."""
        y_roll, y_pitch = tilt_innovation(ax, ay, az, up)
        moved_roll, moved_pitch = moved
        y_roll -= moved_roll
        y_pitch -= moved_pitch
        gate = self._bias_innovation
        if not (-gate <= y_roll <= gate and -gate <= y_pitch <= gate):
            learn_bias = False  # grossly off: the angle only (bias_innovation)
        gross = self._gross_innovation
        if not -gross <= y_roll <= gross:  # off by more than y: its variance at least y^2
            self.P_roll = raised_angle_variance(self.P_roll, y_roll * y_roll)
        if not -gross <= y_pitch <= gross:
            self.P_pitch = raised_angle_variance(self.P_pitch, y_pitch * y_pitch)
        self.correct_innovation(y_roll, y_pitch, learn_bias)
        return (moved_roll + self.gain_roll[0] * y_roll,
                moved_pitch + self.gain_pitch[0] * y_pitch)

    def correct_innovation(self, y_roll: float, y_pitch: float, learn_bias: bool = True) -> None:
        """Measurement update with given innovations (accelerometer angle - predicted angle);
        with learn_bias False the biases are consider states (angle_only_gain)."""
        self.update_angles(y_roll, y_pitch, None if learn_bias else angle_only_gain)

    def _switch_face(self) -> None:
        """Move the filters to the face nearest to up, once up is more
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
        self.rest = RestState(*turn((r.wx, r.wy, r.wz)), *turn((r.fx, r.fy, r.fz)), r.quiet_time,
                              r.measured, *turn((r.ox, r.oy, r.oz)), *turn((r.rx, r.ry, r.rz)),
                              *turn((r.zx, r.zy, r.zz)))
        P_roll, P_pitch, P_z = self.P_roll, self.P_pitch, self.P_z
        vertical = (max(P_roll[0], P_pitch[0]), 0.0, 0.0, P_z)
        old = (P_roll, P_pitch, vertical)
        # the old axis that each new axis is: the nonzero of row k of D
        source = [j for k in range(3) for j in range(3) if turn_axis(C2, C, k, j) != 0.0]
        self.P_roll, self.P_pitch = old[source[0]], old[source[1]]
        self.P_z = old[source[2]][3]
        self.face = new

    def _estimate(self) -> Estimate:
        if self.face:  # from the face frame back to the sensor's
            C = FACES[self.face]
            cp = cos(self.pitch)
            up = mat_t_vec(C, (-sin(self.pitch), sin(self.roll) * cp, cos(self.roll) * cp))
            roll, pitch = accel_roll_pitch(*up)
            return Estimate(roll, pitch, mat_t_vec(C, (self.bias_x, self.bias_y, self.bias_z)))
        return Estimate(self.roll, self.pitch, (self.bias_x, self.bias_y, self.bias_z))


def raised_angle_variance(P: tuple[float, float, float, float], var: float
                          ) -> tuple[float, float, float, float]:
    """An axis's covariance [P00, P01, P10, P11] with its angle's variance at least var
    (gross_innovation)."""
    return (var, P[1], P[2], P[3]) if var > P[0] else P


def turn_axis(C2: tuple[float, ...], C: tuple[float, ...], k: int, j: int) -> float:
    """Entry (k, j) of C2 C^T for 3x3 matrices given row by row."""
    return C2[3 * k] * C[3 * j] + C2[3 * k + 1] * C[3 * j + 1] + C2[3 * k + 2] * C[3 * j + 2]
