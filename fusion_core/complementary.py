"""The recommended complementary filter for roll and pitch: the papers' filter
(fusion_core.papers.complementary: Gui et al. 2015 eq. 1-2, Das & Mary eq. 1) with the
mechanisms of building_blocks and fusion_core.measured_vector around it (ComplementaryFilter).
"""

from __future__ import annotations

import dataclasses
from math import sqrt
from typing import ClassVar, Final

from .base import Estimator, SensorNoise
from .building_blocks import (
    ACC_GATE_PARAMS,
    ACC_LOWPASS_PARAM,
    BIAS_GATE_PARAM,
    BIAS_INNOVATION_PARAM,
    COMPLEMENTARY_ADAPTIVE_PARAMS,
    MOTION_BIAS_PARAM,
    REST_PARAMS,
    REST_START,
    ZERO3,
    bias_band2,
    body_rotation,
    complementary_adaptive,
    complementary_rest,
    corrected_quat,
    correction_time,
    gate_bounds2,
    motion_bias_ki,
    quat_from_roll_pitch,
    rest_start,
    tilt_innovation,
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
from .measured_vector import (
    BAND_PARAM,
    BURST_PARAM,
    HELD_PARAM,
    LEAK_PARAM,
    MEASURE_CHECK,
    STRETCH_PARAM,
    measure_aligned,
    measure_clipped,
    measure_constants,
    measure_start,
    measure_step,
    within_bias_band,
)
from .state import ANGLE, HALF_ANGLE, REAL, REST, UNIT, StateSpec
from .types import Estimate, G, Param

CF_HELD: Final = dataclasses.replace(HELD_PARAM, default=0.0)
"""The cf's held_acceleration: 0, no cap on the slow band's statistic. The cap keeps absurd
samples from counting as more than a held acceleration; with a burst's samples kept out of the
measured vector (burst_acceleration) and a zero-rate update that takes no motion's start for
rest (building_blocks.ZERO_RATE_TAU), the cf's cap lowers the error neither on the battery nor
on BROAD's folds left out with the grid chosen again, so `imu-fusion mechanisms` drops it (the
kf's folds keep it: docs/results/mechanisms.md); the parameter stays for a user's own value."""


class ComplementaryFilter(Estimator):
    """The recommended complementary filter (Gui et al. 2015 eq. 1-2; Das & Mary eq. 1).

    Per sample: the gyro turns an attitude quaternion (with a free yaw) by the interval's
    rotation vector (the trapezoid rate with the coning term for point samples, the rectangle
    rule for mean samples: building_blocks.GYRO_SAMPLING_PARAM), so that pitch +-90 deg is no
    singularity; then, when gate_low <= |f|/g <= gate_high, roll and pitch are blended with the
    measured vector's: angle = a angle_pred + (1 - a) acc_angle with a = tau / (tau + dt) from
    each sample's own dt (written as angle_pred + (1 - a) y with y = acc_angle - angle_pred the
    angle between the two tilts in [-pi, pi], building_blocks.tilt_innovation, so roll does not
    jump at +-180 deg; the quaternion is turned by the blend's step, corrected_quat). Around the
    papers' blend, for real IMUs:
    - the measured vector (acc_lowpass > 0; fusion_core.measured_vector): the gate and the
      blend use the accelerometer low-passed in a frame that turns with the gyro (second
      order, after Laidig & Seel 2023); while it fills (after the first sample, and after a
      gyro sample at its rail) it is the mean of the samples so far, and the attitude is its
      tilt;
    - rest detection (rest_time > 0; building_blocks.REST_PARAMS): at rest the gyro reads its
      own bias, and a bias estimate b follows it with time constant rest_time; the filter
      integrates gyro - b and outputs b, so an uncalibrated gyro's error b tau is gone. A first
      rest that b misses by rest_gyro or more (a gyro never calibrated) aligns the filter
      instead: b becomes the rest's mean rate and the tilt its mean specific force's
      (building_blocks.uncalibrated_first_rest);
    - adaptive noise (building_blocks.ADAPTIVE_NOISE_PARAMS, the kf's, with acc_noise the sample
      noise they are measured against): tau follows the Kalman balance of the gyro's scale
      uncertainty against the measured vector's noise (building_blocks.correction_time):
      shorter while the sensor turns with a clean accelerometer, longer while it accelerates,
      up to max_correction_time. A gyro sample at its rail (gyro_range) measures no bias at rest
      and restarts the measured vector;
    - bias learning in motion until the first rest (motion_bias_gain > 0;
      building_blocks.motion_bias): b <- b - Ki e dt, e = f/|f| x v the tilt innovation as a
      body rate (Mahony's, v the estimated gravity direction), Ki from the correction time the
      disturbance sets (motion_bias_ki), where the kf's bias learns (bias_gate,
      bias_innovation, a settled vector, no sample at the rail).

    Why the defaults are so: docs/estimators/cf.md, "The defaults".
    """

    PARAMS = (
        Param(
            "tau", 1.0, "Complementary-filter time constant, a = tau/(tau+dt) (Gui et al. eq. 2; "
            "their 0.75 s)",
            unit="s", low=0.0, low_open=True,
        ),
        *ACC_GATE_PARAMS,
        ACC_LOWPASS_PARAM,
        *REST_PARAMS,
        *COMPLEMENTARY_ADAPTIVE_PARAMS,
        BAND_PARAM,
        LEAK_PARAM,
        CF_HELD,
        BURST_PARAM,
        STRETCH_PARAM,
        MOTION_BIAS_PARAM,
        BIAS_GATE_PARAM,
        BIAS_INNOVATION_PARAM,
    )
    TWIN: ClassVar[str | None] = "fc_cf"
    BIAS_IN_MOTION: ClassVar[tuple[int, ...]] = ()
    SCANNED: ClassVar[tuple[str, ...]] = ("tau",)
    GYRO_ONLY: ClassVar[dict[str, float] | None] = {"acc_lowpass": 0.0, "gate_high": 2.0}
    STATE: ClassVar[StateSpec] = {
        "roll": ANGLE, "pitch": HALF_ANGLE, "meas": MEASURE_CHECK, "q_att": UNIT, "bias": REAL,
        "rest": REST,
    }

    @classmethod
    def noise_params(cls, noise: SensorNoise) -> dict[str, float]:
        """acc_noise = one accelerometer sample's standard deviation over g: the white noise its
        adaptive noise measures the disturbance against (its time constant comes from the bias
        a correction must hold off and from a scan, SCANNED)."""
        return {"acc_noise": noise.acc_sample_std / G}

    def _configure(self) -> None:
        p = self._params
        self._tau = float(p["tau"])
        self._gate_low2, self._gate_high2 = gate_bounds2(p)
        self._acc_tau = float(p["acc_lowpass"])
        self._rest = (float(p["rest_time"]), float(p["rest_gyro"]), float(p["rest_acc"]),
                      float(p["rest_bias_bound"]))
        # the adaptive noise (building_blocks.ADAPTIVE_NOISE_PARAMS): one sample's variance, the
        # rotation term per (rad/s)^2, the disturbance's averaging time (0: off), the white
        # noise's share of the disturbance statistic and the longest correction time
        self._adaptive = complementary_adaptive(p, self._acc_tau)
        self._measure = measure_constants(self._acc_tau, self._adaptive[2],
                                          float(p["slow_band_time"]), self._adaptive[0],
                                          float(p["gyro_scale_std"]),
                                          float(p["acc_lowpass_stretch"]),
                                          float(p["slow_band_leak"]),
                                          float(p["held_acceleration"]),
                                          float(p["burst_acceleration"]))
        self._motion_gain = float(p["motion_bias_gain"])
        self._bias_band2 = bias_band2(float(p["bias_gate"]))
        self._bias_innovation = float(p["bias_innovation"])

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0
        self.meas = measure_start(ZERO3, self._measure)  # the measured vector (acc_lowpass > 0)
        self.q_att = (1.0, 0.0, 0.0, 0.0)  # the attitude, with a free yaw
        self.bias = ZERO3  # gyro bias measured at rest (rest_time > 0)
        self.rest = REST_START  # rest detector (building_blocks.RestState)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        self.roll, self.pitch = accel_roll_pitch(ax, ay, az)
        self.meas = measure_start((ax, ay, az), self._measure)
        self.q_att = quat_from_roll_pitch_yaw(self.roll, self.pitch, 0.0)
        self.rest = rest_start(gx, gy, gz, ax, ay, az)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        rest_time = self._rest[0]
        clipped = self.clipped  # at the gyro's rail: no rate measured (gyro_range)
        if rest_time > 0.0 and not clipped:  # at rest the gyro reads its bias: follow it
            self.rest, self.bias, aligned = complementary_rest(
                self.rest, self.bias, gx, gy, gz, ax, ay, az, dt, rest_time, self._rest[1],
                self._rest[2], self._rest[3])
            if aligned is not None:  # an uncalibrated first rest: the attitude is its tilt
                self.roll, self.pitch, f = aligned
                self.meas = measure_aligned(self.meas, f)
                self.q_att = quat_from_roll_pitch(self.roll, self.pitch)
        bias = self.bias
        bx, by, bz = bias
        r_ref, q_rotation, _, longest = self._adaptive
        r = r_ref
        aligning = False
        phi = body_rotation(self.gyro_prev, (gx, gy, gz), bias, dt, self._trapezoid)
        terms = rotvec_terms(*phi)  # once, for the pre-filter and the propagation
        raw2 = ax * ax + ay * ay + az * az
        if self._acc_tau > 0.0:  # the filter and its gate use the measured vector
            m = measure_clipped(self.meas) if clipped else self.meas
            self.meas, r, aligning = measure_step(m, (ax, ay, az), phi, terms, dt,
                                                  self._measure, self.rest.measured > 0.0)
            ax, ay, az = self.meas.f
        # the attitude turned, the correction from the angle between the two tilts and q turned
        # by it (building_blocks.attitude)
        self.q_att = q = quat_mul_rotvec(self.q_att, phi[0], phi[1], phi[2], terms)
        up = up_terms(*q)
        roll, pitch = quat_roll_pitch(*q)
        if self._gate_low2 <= ax * ax + ay * ay + az * az <= self._gate_high2:
            y_roll, y_pitch = tilt_innovation(ax, ay, az, up)
            tau = self._tau
            if q_rotation > 0.0 or r != r_ref:  # the adaptive noise shortens the correction
                wx, wy, wz = gx - bx, gy - by, gz - bz
                tau = correction_time(tau, r / r_ref, q_rotation, wx * wx + wy * wy + wz * wz,
                                      r_ref, dt, longest)
            k = 1.0 if aligning else dt / (tau + dt)  # 1 - a, Gui et al. eq. 2
            if self._learns_in_motion(ax, ay, az, raw2, y_roll, y_pitch, aligning, clipped):
                tau_d = self._tau  # the disturbance's correction time, without the rotation's
                if r != r_ref:
                    tau_d = correction_time(tau_d, r / r_ref, 0.0, 0.0, r_ref, dt, longest)
                ki_dt = motion_bias_ki(tau_d, self._motion_gain, dt, 0.5 * self._acc_tau) * dt
                # Mahony's e = f/|f| x v, v the estimated gravity direction (up_terms): the
                # innovation as a body rate at any attitude
                inv = 1.0 / sqrt(ax * ax + ay * ay + az * az)
                nx, ny, nz = ax * inv, ay * inv, az * inv
                vx, vy, vz = -up[2], up[0], up[1]
                ex, ey, ez = ny * vz - nz * vy, nz * vx - nx * vz, nx * vy - ny * vx
                self.bias = (bx - ki_dt * ex, by - ki_dt * ey, bz - ki_dt * ez)
            dr, dp = k * y_roll, k * y_pitch
            roll += dr
            pitch += dp
            self.q_att = corrected_quat(q, up, roll, pitch, dr, dp)
        self.roll = roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)
        return Estimate(roll, pitch, self.bias)

    def _learns_in_motion(self, ax: float, ay: float, az: float, raw2: float, y_roll: float,
                          y_pitch: float, aligning: bool, clipped: bool) -> bool:
        """Whether this correction teaches the bias (building_blocks.motion_bias): before the
        first rest, on a settled measured vector (ax, ay, az; raw2 the raw sample's squared
        norm) within the bias gates, no sample at the rail."""
        if not (self._motion_gain > 0.0 and self._acc_tau > 0.0 and self.rest.measured <= 0.0
                and not aligning and not clipped and self.meas.settled(self._measure)):
            return False
        gate = self._bias_innovation
        if not (-gate <= y_roll <= gate and -gate <= y_pitch <= gate):
            return False
        a2 = ax * ax + ay * ay + az * az
        return a2 > 0.0 and within_bias_band(self.meas, self._measure, self._bias_band2, a2, raw2)

    def _estimate(self) -> Estimate:
        return Estimate(self.roll, self.pitch, self.bias)


__all__ = ["ComplementaryFilter"]
