"""The recommended modified-gain complementary filter: the paper's Mahony-style quaternion PI
filter (fusion_core.papers.mgcf: Duong Quoc et al. eq. 7-13) with a fixed gain and the
mechanisms of building_blocks and fusion_core.measured_vector around it
(GainScheduledComplementaryFilter).
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar, Final

from .base import Estimator, SensorNoise
from .building_blocks import (
    ACC_LOWPASS_PARAM,
    BIAS_GATE_PARAM,
    COMPLEMENTARY_ADAPTIVE_PARAMS,
    MOTION_BIAS_PARAM,
    REST_PARAMS,
    REST_START,
    SLOWEST_CORRECTION,
    ZERO3,
    bias_band2,
    body_rotation,
    complementary_adaptive,
    complementary_rest,
    correction_time,
    motion_bias_ki,
    quat_from_roll_pitch,
    rest_start,
)
from .kinematics import (
    accel_roll_pitch,
    quat_from_roll_pitch_yaw,
    quat_roll_pitch,
    rotvec_terms,
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
    raw_noise,
    within_bias_band,
)
from .papers.mgcf import pi_step
from .state import NONNEG, REAL, REST, UNIT, StateSpec
from .types import Estimate, G, Param

MGCF_ACC_LOWPASS = dataclasses.replace(ACC_LOWPASS_PARAM, default=1.0)
"""The mgcf's acc_lowpass: 1 s, not the 1.5 s of the others. Its integral term (Ki = w0^2)
learns a bias from every error its correction passes, and a longer vector turned by a gyro with
scale errors carries more of them. The cross-validation on BROAD chooses 1 s in every fold
(`python -m testbenches broad DIR --cv`), among the values that keep the contract's bounds and
half the paper's row on moderate_dynamics (testbenches.broad.feasible; tests/test_paper_rows.py).
Without the bias learning in motion (motion_bias_gain 0), 1.5 s leaves that row in pitch."""


MGCF_HELD: Final = dataclasses.replace(HELD_PARAM, default=0.0)
"""The mgcf's held_acceleration: 0, no limit. The cap bounds the slow band's statistic, the
measurement noise of the other filters; the mgcf's is the raw disturbance, which it does not
touch, so here the cap would only decide how long the vector grows, and the vector reaches its
longest at a slow band far below the cap (measured_vector.stretched) unless the sensor turns
faster than any real motion; the parameter stays for a user's own value."""


class GainScheduledComplementaryFilter(Estimator):
    """The recommended modified-gain complementary filter (Duong Quoc et al. eq. 7-13:
    quaternion PI after Mahony et al. 2008).

    Per sample (a valid one after the first):
      v   = R(q)^T e_z, the estimated gravity direction in the body frame;
      e   = f/|f| x v (Mahony's correction term), f the measured vector (below), v taken after
            the gyro prediction to this sample's time (gyro_sampling="point") or from the
            previous attitude (gyro_sampling="mean", Mahony's code);
      Kp  = 2 zeta w0, Ki = w0^2 (w0 fixed: the paper's bands of |a|/g are for a calibrated
            sensor, and with the pre-filter the linear acceleration is gone before they could
            see it);
      b  <- b - Ki e dt (the integral term; b is the gyro-bias estimate, output as bias_*);
      the body rate gyro - b + Kp e rotates q over dt: with gyro_sampling="point" the rate is
      taken linear between the previous and the current gyro sample and integrated with the
      two-sample coning correction (kinematics.rotation_increment); with "mean" q is advanced
      with the current rate by the first-order quaternion rule (papers.mgcf.quat_first_order).
    Roll and pitch come from the quaternion; yaw is carried along but unobservable. Around the
    paper's filter, for real IMUs:
    - the measured vector (acc_lowpass > 0; fusion_core.measured_vector): f is the
      accelerometer low-passed in a frame that turns with the bias-corrected gyro (after Laidig
      & Seel 2023), so linear acceleration averages out instead of reading as tilt; over its
      first time constant it is the running mean of the turned samples, and q is its tilt;
      it grows longer (up to acc_lowpass_stretch times) where the slow band (slow_band_time)
      finds linear acceleration slower than it that the gyro's turn would not explain, once a
      rest has measured the bias (measured_vector, item 4; a hand carrying the sensor back and
      forth over seconds); the measurement noise stays the raw disturbance
      (measured_vector.raw_noise), the slow band only decides the length, with its fast leak
      taken off (slow_band_leak) and without a cap (MGCF_HELD);
    - rest detection (rest_time > 0; building_blocks.REST_PARAMS): at rest the gyro reads its
      own bias, and b follows the gyro with time constant rest_time (a zero-angular-rate update
      of the integral term; Mahony's integral alone needs minutes, and cannot see the bias about
      the vertical at all). A first rest that b misses by rest_gyro or more (a gyro never
      calibrated) aligns the filter instead (building_blocks.uncalibrated_first_rest);
    - adaptive noise, as the cf has it: the pre-filter shortens to the raw sample where no
      linear acceleration above the white noise is measured, and 1/Kp follows
      building_blocks.correction_time (Ki as it is): Kp grows while the sensor turns with a
      clean accelerometer and falls while it accelerates, to 1/max_correction_time;
    - no bias is learned from a gyro sample at its rail (gyro_range) nor from a measured vector
      that still holds its turns;
    - bias learning in motion until the first rest (motion_bias_gain > 0;
      building_blocks.motion_bias): Ki is at least motion_bias_ki of the correction time the
      disturbance sets, where the kf's bias learns (bias_gate on what reaches the vector): the
      paper's w0^2 alone takes minutes to learn what a start-up calibration left.

    Why the defaults are so: docs/estimators/mgcf.md, "The defaults".
    """

    PARAMS = (
        Param(
            "w0", 0.02, "Natural frequency of the PI correction (Kp = 2 zeta w0, Ki = w0^2)",
            unit="rad/s", low=0.0,
        ),
        Param("zeta", 10.0, "Damping ratio of the PI correction (Kp = 2 zeta w0; the paper's 2)",
              low=0.0, high=1000.0),
        MGCF_ACC_LOWPASS,
        *REST_PARAMS,
        *COMPLEMENTARY_ADAPTIVE_PARAMS,
        BAND_PARAM,
        LEAK_PARAM,
        MGCF_HELD,
        BURST_PARAM,
        STRETCH_PARAM,
        MOTION_BIAS_PARAM,
        BIAS_GATE_PARAM,
    )
    TWIN: ClassVar[str | None] = "fc_mgcf"
    BIAS_IN_MOTION: ClassVar[tuple[int, ...]] = (0, 1, 2)
    SCANNED: ClassVar[tuple[str, ...]] = ("w0", "zeta")
    STATE: ClassVar[StateSpec] = {
        "q": UNIT, "bias": REAL, "w0_now": NONNEG, "meas": MEASURE_CHECK, "rest": REST,
    }

    @classmethod
    def noise_params(cls, noise: SensorNoise) -> dict[str, float]:
        """acc_noise = one accelerometer sample's standard deviation over g: the white noise its
        adaptive noise measures the disturbance against (its time constant comes from the bias
        a correction must hold off and from a scan, SCANNED)."""
        return {"acc_noise": noise.acc_sample_std / G}

    def _configure(self) -> None:
        p = self._params
        self._w0 = float(p["w0"])
        self._two_zeta = 2.0 * float(p["zeta"])
        self._acc_tau = float(p["acc_lowpass"])
        self._rest_time = float(p["rest_time"])
        self._rest_gyro = float(p["rest_gyro"])
        self._rest_bias_bound = float(p["rest_bias_bound"])
        self._rest_acc = float(p["rest_acc"])
        # the adaptive noise (building_blocks.ADAPTIVE_NOISE_PARAMS), as in the cf: one sample's
        # variance, the rotation term per (rad/s)^2, the disturbance's averaging time (0: off),
        # the white noise's share of the disturbance statistic, the longest correction time
        self._adaptive = complementary_adaptive(p, self._acc_tau)
        # the slow band only decides the longer vector (measured_vector item 4): the mgcf's
        # noise is the raw disturbance (measured_vector.raw_noise)
        self._measure = measure_constants(self._acc_tau, self._adaptive[2],
                                          float(p["slow_band_time"]), self._adaptive[0],
                                          float(p["gyro_scale_std"]),
                                          float(p["acc_lowpass_stretch"]),
                                          float(p["slow_band_leak"]),
                                          float(p["held_acceleration"]),
                                          float(p["burst_acceleration"]))
        self._motion_gain = float(p["motion_bias_gain"])
        self._bias_band2 = bias_band2(float(p["bias_gate"]))

    def _reset(self) -> None:
        self.q = (1.0, 0.0, 0.0, 0.0)
        self.bias = ZERO3
        self.w0_now = 0.0
        self.meas = measure_start(ZERO3, self._measure)  # the measured vector (acc_lowpass > 0)
        self.rest = REST_START  # rest detector (building_blocks.RestState)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        roll, pitch = accel_roll_pitch(ax, ay, az)
        self.q = quat_from_roll_pitch_yaw(roll, pitch, 0.0)
        self.meas = measure_start((ax, ay, az), self._measure)
        self.rest = rest_start(gx, gy, gz, ax, ay, az)

    def _real_sensor_options(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> tuple[float, float, float, float, bool]:
        """The zero-angular-rate update at rest and the measured vector (see the class
        docstring); returns the specific force the correction is to use, this step's
        measurement variance (acc_noise^2 plus the disturbance that reaches the vector) and
        whether the vector is still filling (measured_vector)."""
        clipped = self.clipped
        if self._rest_time > 0.0 and not clipped:
            self.rest, self.bias, aligned = complementary_rest(
                self.rest, self.bias, gx, gy, gz, ax, ay, az, dt, self._rest_time,
                self._rest_gyro, self._rest_acc, self._rest_bias_bound)
            if aligned is not None:  # an uncalibrated first rest: the attitude is its tilt
                roll, pitch, f = aligned
                self.meas = measure_aligned(self.meas, f)
                self.q = quat_from_roll_pitch(roll, pitch)
        r_ref = self._adaptive[0]
        if self._acc_tau > 0.0:
            phi = body_rotation(self.gyro_prev, (gx, gy, gz), self.bias, dt, self._trapezoid)
            terms = rotvec_terms(*phi)
            m = measure_clipped(self.meas) if clipped else self.meas
            self.meas, _, filling = measure_step(m, (ax, ay, az), phi, terms, dt, self._measure,
                                                 self.rest.measured > 0.0)
            f0, f1, f2 = self.meas.f
            r = raw_noise(self.meas, self._measure)
            return f0, f1, f2, r, filling
        return ax, ay, az, r_ref, False

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        r_ref, q_rotation, _, longest = self._adaptive
        r = r_ref
        raw2 = ax * ax + ay * ay + az * az
        ax, ay, az, r, aligning = self._real_sensor_options(ax, ay, az, gx, gy, gz, dt)
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        w0 = self._w0
        if not norm > 0.0:  # no gravity direction in this sample: gyro only
            w0 = 0.0
        self.w0_now = w0
        if aligning and w0 > 0.0:  # the vector still fills (measured_vector): the mean's tilt
            self.q = q = quat_from_roll_pitch(*accel_roll_pitch(ax, ay, az))
            roll, pitch = quat_roll_pitch(*q)
            return Estimate(roll, pitch, self.bias)
        bx, by, bz = self.bias
        kp = self._two_zeta * w0
        # the adaptive noise: 1/Kp follows building_blocks.correction_time
        if kp * SLOWEST_CORRECTION > 1.0 and (q_rotation > 0.0 or r != r_ref):
            wx, wy, wz = gx - bx, gy - by, gz - bz
            tau = 1.0 / kp
            kp *= tau / correction_time(tau, r / r_ref, q_rotation, wx * wx + wy * wy + wz * wz,
                                        r_ref, dt, longest)
        # the integral term learns nothing from a gyro sample at its rail, nor from a vector
        # still holding its turns
        learn = not self.clipped and (self._acc_tau == 0.0 or self.meas.settled(self._measure))
        w_i = w0  # Ki = w_i^2: the paper's, or more until the first rest (motion_bias)
        kp0 = self._two_zeta * w0
        if learn and kp0 * SLOWEST_CORRECTION > 1.0 and self._learns_in_motion(ax, ay, az, raw2):
            tau_d = 1.0 / kp0  # the disturbance's correction time
            if r != r_ref:
                tau_d = correction_time(tau_d, r / r_ref, 0.0, 0.0, r_ref, dt, longest)
            ki = motion_bias_ki(tau_d, self._motion_gain, dt, 0.5 * self._acc_tau)
            if ki > w0 * w0:
                w_i = math.sqrt(ki)
        q, self.bias = pi_step(self.q, self.bias, self.gyro_prev, (gx, gy, gz), (ax, ay, az),
                               norm, w_i, kp, dt, self._trapezoid, learn)
        self.q = q
        roll, pitch = quat_roll_pitch(*q)
        return Estimate(roll, pitch, self.bias)

    def _learns_in_motion(self, ax: float, ay: float, az: float, raw2: float) -> bool:
        """Whether the integral term learns at motion_bias_ki (building_blocks.motion_bias):
        before the first rest, with the measured vector (ax, ay, az; raw2 the raw sample's
        squared norm) within the bias gate, as the kf's bias learns."""
        if not (self._motion_gain > 0.0 and self._acc_tau > 0.0 and self.rest.measured <= 0.0):
            return False
        a2 = ax * ax + ay * ay + az * az
        return within_bias_band(self.meas, self._measure, self._bias_band2, a2, raw2)

    def _estimate(self) -> Estimate:
        roll, pitch = quat_roll_pitch(*self.q)
        return Estimate(roll, pitch, self.bias)
