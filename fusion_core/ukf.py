"""The recommended unscented Kalman filter on the gravity direction, augmented with the gyro
bias: the paper's filter (fusion_core.papers.ukf: Duong Quoc et al. eq. 14-17, whose equations
and their derivation it uses) with the mechanisms of building_blocks and
fusion_core.measured_vector around it (UnscentedKalmanFilter).
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar, Final

from .base import Estimator, SensorNoise
from .building_blocks import (
    ACC_LOWPASS_PARAM,
    ADAPTIVE_NOISE_PARAMS,
    BIAS_GATE_PARAM,
    BIAS_INNOVATION_PARAM,
    GROSS_INNOVATION_PARAM,
    REAL_GYRO_DENSITY,
    REST_PARAMS,
    REST_START,
    adaptive_noise_constants,
    bias_band2,
    body_rotation,
    first_rest,
    rest_mean_share,
    rest_start,
    rest_step,
    zero_rate_psd_param,
    zero_rate_sample,
)
from .kalman import KALMAN_MAX_CORRECTION_TIME, RECOMMENDED_INIT_BIAS_STD, bias_prior
from .kinematics import rotvec_terms
from .linalg import cholesky3, packed_diagonal, packed_index
from .measured_vector import (
    BAND_PARAM,
    BURST_PARAM,
    HELD_PARAM,
    LEAK_PARAM,
    MEASURE_CHECK,
    STRETCH_PARAM,
    fill_noise,
    gate_norm2,
    measure_clipped,
    measure_constants,
    measure_restarted,
    measure_start,
    measure_step,
)
from .papers.ukf import (
    N_STATE,
    SIGMA_PARAMS,
    GravityDirectionState,
    measurement_update,
    predicted_covariance,
    rotation_terms,
    sigma_predict,
    unscented_constants,
)
from .state import COV, REAL, REST, UNIT, Segments, StateSpec
from .types import DEG, Estimate, G, Param

ACC_GATE: Final = 1.0
"""The update is skipped while the measured vector's norm is off g by a whole g or more
(||f|/g - 1| >= 1): a vector of 2 g is no gravity direction, and one near 0 (free fall) none
either."""

UKF_GROSS_INNOVATION: Final = dataclasses.replace(GROSS_INNOVATION_PARAM, default=math.pi)
"""The ukf's gross_innovation: pi, never (the papers). Raising the direction's variance after an
innovation beyond 30 deg lowers the error neither on BROAD's folds left out (with the grid
chosen again) nor on any cell of the battery, its glitching part included, nor keeps a contract
check, and after a second of absurd samples the ukf is back under 1 deg as soon without it
(`python -m testbenches.recovery`). So `imu-fusion mechanisms` drops it (the kf keeps it:
docs/results/mechanisms.md); the parameter stays for a user's own value."""

UKF_HELD: Final = dataclasses.replace(HELD_PARAM, default=0.0)
"""The ukf's held_acceleration: 0, no cap on the slow band's statistic. The cap keeps absurd
samples from counting as more than a held acceleration; with a burst's samples kept out of the
measured vector (burst_acceleration), the ukf's cap lowers the error neither on the battery nor
on BROAD's folds left out with the grid chosen again, so `imu-fusion mechanisms` drops it (the
kf's folds keep it: docs/results/mechanisms.md); the parameter stays for a user's own value."""


def raised_direction_variance(P: tuple[float, ...], var: float) -> tuple[float, ...]:
    """The packed lower triangle P of [X, b] with each of X's variances at least var
    (gross_innovation; the kf's raised_angle_variance)."""
    out = list(P)
    for k in (packed_index(i, i) for i in range(3)):
        if var > out[k]:
            out[k] = var
    return tuple(out)


def measured_covariance(P: tuple[float, ...], X: tuple[float, float, float], var: float,
                        age: float) -> tuple[float, ...]:
    """The packed lower triangle P of [X, b] once X is taken from a measured vector of variance
    var per axis whose samples the gyro turned over age [s] on average (0: a rest's mean, which
    no gyro error turned): a bias error db turned them by dX = -age [X]x db, so
    P_XX = var I + age^2 [X]x P_bb [X]x^T and P_Xb = -age [X]x P_bb, as the propagation's
    covariance of X with b is after a time age (kalman.measured_axis, per axis); P_bb stays."""
    x0, x1, x2 = X
    S = ((0.0, -x2, x1), (x2, 0.0, -x0), (-x1, x0, 0.0))  # [X]x
    B = [[P[packed_index(3 + i, 3 + j)] for j in range(3)] for i in range(3)]
    M = [[S[i][0] * B[0][j] + S[i][1] * B[1][j] + S[i][2] * B[2][j] for j in range(3)]
         for i in range(3)]  # [X]x P_bb
    a2 = age * age
    out = list(P)
    for i in range(3):
        for j in range(3):
            out[packed_index(3 + j, i)] = 0.0 - age * M[i][j]
        for k in range(i + 1):
            s = a2 * (M[i][0] * S[k][0] + M[i][1] * S[k][1] + M[i][2] * S[k][2])
            out[packed_index(i, k)] = var + s if k == i else s
    return tuple(out)


class UnscentedKalmanFilter(GravityDirectionState, Estimator):
    """The recommended UKF on the gravity direction with three gyro-bias states (Duong Quoc et
    al. eq. 14-17).

    State x = [X (3), b (3)]; covariance P (6x6, packed).
    Predict: each sigma point is rotated by its own bias-corrected rotation increment
      (exp(-[phi_i]x) X_i; the trapezoid rate with the coning term for point samples, the
      rectangle rule for mean samples), b_i unchanged; Q = gyro_psd dt (I - X X^T) for X (the
      gyro noise turns X only perpendicular to itself) and bias_psd dt I for b.
    Update: z = f/g, h(x) = X, R = r I (f the measured vector), skipped while ||f|/g - 1| >=
      ACC_GATE; X renormalised after.
    Around the paper's filter, for real IMUs, as the kf has them: the measured vector
    (acc_lowpass > 0; fusion_core.measured_vector) with its noise (R from the slow linear
    acceleration that reaches it, capped at max_correction_time), the gyro's scale uncertainty
    while it turns (building_blocks.ADAPTIVE_NOISE_PARAMS), a gyro at its rail (the rate beyond
    it grows Q, no bias is learned), rest detection with a zero-rate update of the bias states
    (rest_time > 0), and the bias learned only while the slow band of the measured vector
    (measured_vector.gate_norm2; without the vector the raw sample) is within bias_gate of g,
    the measured and the predicted gravity direction within bias_innovation (no limit by
    default: BIAS_INNOVATION_PARAM) and the measured
    vector settled (else the biases are consider states). While the measured vector fills, X
    is its direction, with that vector's variance and the covariance with the bias of the turn
    a bias error gave its samples, and at the first rest the rest's mean direction with that
    mean's variance and no covariance with the bias, as in the kf (kalman.AngleBiasKalmanFilter;
    measured_covariance).
    No unit-norm pseudo-measurement (the paper's |X|^2 = 1 row; why: docs/estimators/ukf.md).
    The defaults follow from the sensor's noise (noise_params): docs/estimators/ukf.md, "The
    defaults".
    Output: roll = atan2(X2, X3), pitch = atan2(-X1, sqrt(X2^2 + X3^2)); bias = b.
    """

    PARAMS = (
        Param(
            "gyro_psd", REAL_GYRO_DENSITY**2,
            "Gyro white-noise power spectral density driving the gravity direction (process "
            "noise; the datasheet's rate-noise density squared)",
            unit="rad2/s", low=0.0, low_open=True, display_unit="deg2/s",
        ),
        Param(
            "bias_psd", (1e-4 * DEG) ** 2,
            "Gyro bias random-walk power spectral density (process noise of the bias states; "
            "the random-walk density squared)",
            unit="rad2/s3", low=0.0, display_unit="deg2/s3",
        ),
        Param(
            "acc_noise", 0.005,
            "Standard deviation of one accelerometer sample divided by g (noise and unmodelled "
            "linear acceleration)",
            low=1e-6, high=10.0,  # 1 ug, below any accelerometer's noise
        ),
        Param(
            "init_bias_std", RECOMMENDED_INIT_BIAS_STD,
            "Initial standard deviation of each gyro-bias state",
            unit="rad/s", low=0.0, low_open=True, tunable=False,
        ),
        *SIGMA_PARAMS,
        *ADAPTIVE_NOISE_PARAMS,
        ACC_LOWPASS_PARAM,
        *REST_PARAMS,
        zero_rate_psd_param("zaru_psd"),
        BIAS_GATE_PARAM,
        BIAS_INNOVATION_PARAM,
        UKF_GROSS_INNOVATION,
        BAND_PARAM,
        LEAK_PARAM,
        UKF_HELD,
        BURST_PARAM,
        STRETCH_PARAM,
        KALMAN_MAX_CORRECTION_TIME,
    )
    TWIN: ClassVar[str | None] = "fc_ukf"
    BIAS_IN_MOTION: ClassVar[tuple[int, ...]] = (0, 1, 2)
    SCANNED: ClassVar[tuple[str, ...]] = ("bias_psd",)
    GYRO_ONLY: ClassVar[dict[str, float] | None] = {"acc_lowpass": 0.0, "rest_time": 0.0}
    STATE: ClassVar[StateSpec] = {
        "x": Segments(((UNIT, 3), (REAL, 3))), "P": COV, "meas": MEASURE_CHECK, "rest": REST,
    }

    @classmethod
    def noise_params(cls, noise: SensorNoise) -> dict[str, float]:
        """gyro_psd and zaru_psd = the gyro's PSD, acc_noise = one accelerometer sample's
        standard deviation over g, init_bias_std the kf's (kalman.bias_prior)."""
        gyro_psd = noise.gyro_density * noise.gyro_density
        return {"gyro_psd": gyro_psd, "zaru_psd": gyro_psd, "acc_noise": noise.acc_sample_std / G,
                "init_bias_std": bias_prior(noise)}

    def _configure(self) -> None:
        p = self._params
        self._gamma, self._w, self._w_mu = unscented_constants(
            float(p["alpha"]), float(p["beta"]), float(p["kappa"]))
        self._q_gyro = float(p["gyro_psd"])
        self._q_bias = float(p["bias_psd"])
        self._r_acc = float(p["acc_noise"]) ** 2
        # the adaptive noise (building_blocks.ADAPTIVE_NOISE_PARAMS): Q's rotation term per
        # (rad/s)^2, the disturbance's averaging time (0: off), the white noise's share of the
        # disturbance statistic (3 axes of one sample's variance, (acc_noise g)^2)
        self._adaptive = adaptive_noise_constants(p, float(p["acc_lowpass"]))
        self._measure = measure_constants(float(p["acc_lowpass"]), self._adaptive[1],
                                          float(p["slow_band_time"]), self._r_acc,
                                          float(p["gyro_scale_std"]),
                                          float(p["acc_lowpass_stretch"]),
                                          float(p["slow_band_leak"]),
                                          float(p["held_acceleration"]),
                                          float(p["burst_acceleration"]))
        self._longest2 = float(p["max_correction_time"]) ** 2
        self._rail_var = float(p["gyro_range"]) ** 2 / 3.0  # the rate beyond the rail, per axis
        self._bias_band2 = bias_band2(float(p["bias_gate"]))
        gate = float(p["bias_innovation"])
        # cos of the largest innovation angle the bias learns from (-2: every one)
        self._cos_innovation = math.cos(gate) if gate < math.pi else -2.0
        gross = float(p["gross_innovation"])
        self._cos_gross = math.cos(gross) if gross < math.pi else -2.0  # -2: never

    def _reset(self) -> None:
        self.x = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        self._P: tuple[float, ...] = (0.0,) * 21  # packed lower triangle of the 6x6 P
        # the measured vector (acc_lowpass > 0)
        self.meas = measure_start((0.0, 0.0, 0.0), self._measure)
        self.rest = REST_START  # the rest detector's means, quiet time, measured (rest_time > 0)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        n = math.sqrt(ax * ax + ay * ay + az * az)
        self.x = [ax / n, ay / n, az / n, 0.0, 0.0, 0.0]
        # X from one accelerometer sample: its noise, per axis; b: the prior on the bias.
        # A sample whose norm is off g by d carries at least d of linear acceleration: with the
        # measured vector, its X is as uncertain as d / g more (kalman.AngleBiasKalmanFilter).
        p_x = self._params["acc_noise"] ** 2
        if self._params["acc_lowpass"] > 0.0:
            d = (n - G) / G
            p_x += d * d
        p_b = self._params["init_bias_std"] ** 2
        self._P = packed_diagonal((p_x, p_x, p_x, p_b, p_b, p_b))
        self.meas = measure_start((ax, ay, az), self._measure)
        self.rest = rest_start(gx, gy, gz, ax, ay, az)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        self._update(ax, ay, az, gx, gy, gz, dt)
        return self._estimate()

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        """The sample around the paper's filter: the measured vector (acc_lowpass,
        fusion_core.measured_vector: the filter then measures the low-passed specific force,
        with the noise that reaches it, up to max_correction_time), a gyro at its rail
        (gyro_range: no bias learned, X's uncertainty grows) and, at rest, a zero-rate update
        of the bias states."""
        p = self._params
        lo, hi = self._bias_band2
        clipped = self.clipped
        raw2 = ax * ax + ay * ay + az * az
        if p["acc_lowpass"] > 0.0:
            phi = body_rotation(self.gyro_prev, (gx, gy, gz), (self.x[3], self.x[4], self.x[5]),
                                dt, self._trapezoid)
            terms = rotvec_terms(*phi)  # once, for the measured vector's low-passes
            m = measure_clipped(self.meas) if clipped else self.meas
            self.meas, r, filling = measure_step(m, (ax, ay, az), phi, terms, dt, self._measure,
                                                 self.rest.measured > 0.0)
            # the bias gate on what reaches the vector (gate_norm2); no bias from a vector that
            # is filling (a mean of the first samples, of a motion's start as likely as of rest)
            # or holds turns the gyro did not measure (gyro_range)
            n2 = gate_norm2(self.meas, self._measure, raw2)
            learn_bias = (lo < n2 < hi and not clipped and not filling
                          and self.meas.settled(self._measure))
            fill = fill_noise(self.meas, r, dt, self._measure) if filling else None
            self._filter_update(*self.meas.f, gx, gy, gz, dt, learn_bias, r, fill)
        else:  # the raw sample (bias_gate); never a sample at the rail
            learn_bias = lo < raw2 < hi and not clipped
            self._filter_update(ax, ay, az, gx, gy, gz, dt, learn_bias)
        if p["rest_time"] > 0.0 and not clipped:
            x = self.x
            measured = self.rest.measured
            self.rest = rest_step(self.rest, gx, gy, gz, ax, ay, az, (x[3], x[4], x[5]), dt,
                                  p["rest_gyro"], p["rest_acc"], p["rest_time"],
                                  p["rest_bias_bound"])
            if p["acc_lowpass"] > 0.0 and first_rest(measured, self.rest):
                # the measured vector was turned with a bias not measured yet: it starts again
                # from the rest's mean specific force (measured_vector.measure_restarted), X
                # from its direction, as sure of it as that mean is (and independent of the bias)
                f = (self.rest.fx, self.rest.fy, self.rest.fz)
                self.meas = measure_restarted(self.meas, f)
                n = math.sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
                self.x = [f[0] / n, f[1] / n, f[2] / n, x[3], x[4], x[5]]
                self._P = measured_covariance(self._P, (self.x[0], self.x[1], self.x[2]),
                                              p["acc_noise"] ** 2 * rest_mean_share(dt), 0.0)
            if self.rest.quiet_time >= p["rest_time"]:
                r = p["zaru_psd"] / dt
                if zero_rate_sample(self.rest, r, dt):  # a still gyro's sample
                    self._zero_rate_update((gx, gy, gz), r)

    def _zero_rate_update(self, z: tuple[float, float, float], r: float) -> None:
        """At rest the gyro reads its bias: a linear Kalman update with z = gyro, h(x) = b
        (variance r per axis), then X renormalised. With S = P_bb + r I = L L^T and
        Y = L^-1 P_b. (the bias rows of P): K (z - b) = Y^T L^-1 (z - b), K P_b. = Y^T Y, which
        is symmetric as computed. A P_bb that rounding made indefinite skips the update."""
        P = self._P
        r3 = (P[15], P[16], P[17], P[18], P[19], P[20])  # row 5 of the packed lower triangle
        L = cholesky3(P[9] + r, P[13], P[14] + r, P[18], P[19], P[20] + r)
        if L is None:
            return
        l00, l10, l11, l20, l21, l22 = L
        x = self.x
        cols = []  # L^-1 applied to each column of P_b. (j = 0..5) and to the innovation
        for j in range(N_STATE + 1):
            if j < N_STATE:
                c0, c1, c2 = P[packed_index(3, j)], P[packed_index(4, j)], r3[j]
            else:
                c0, c1, c2 = z[0] - x[3], z[1] - x[4], z[2] - x[5]
            y0 = c0 / l00
            y1 = (c1 - l10 * y0) / l11
            cols.append((y0, y1, (c2 - l20 * y0 - l21 * y1) / l22))
        v0, v1, v2 = cols[N_STATE]
        x = [x[i] + (cols[i][0] * v0 + cols[i][1] * v1 + cols[i][2] * v2) for i in range(N_STATE)]
        self._P = tuple(
            P[packed_index(i, j)]
            - (cols[i][0] * cols[j][0] + cols[i][1] * cols[j][1] + cols[i][2] * cols[j][2])
            for i in range(N_STATE) for j in range(i + 1)
        )
        n = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        self.x = [x[0] / n, x[1] / n, x[2] / n, x[3], x[4], x[5]]

    def _filter_update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float,
        learn_bias: bool, r: float | None = None, fill: tuple[float, float] | None = None,
    ) -> None:
        """One sample of the paper's UKF (eq. 14-17) with the recommended noise: predict
        (rotation_terms, sigma_predict), the process noise with the gyro's scale uncertainty
        and the rate beyond a rail (predicted_covariance), then the update with f/g
        (measurement_update; the bias states as consider states unless learn_bias) of variance
        r per axis, at most max_correction_time's (acc_noise^2 unless given); fill: while the
        measured vector fills, its variance and its samples' mean age (fill_noise), and X is its
        direction instead (as the other filters' attitude is its tilt then)."""
        x = self.x
        b0, b1, b2 = x[3], x[4], x[5]
        terms = rotation_terms(self.gyro_prev, (gx, gy, gz), dt, self._trapezoid)
        pred = sigma_predict(x, self._P, terms, dt, self._gamma, self._w, self._w_mu, False)
        X0, X1, X2 = pred.X
        n = math.sqrt(X0 * X0 + X1 * X1 + X2 * X2)
        inv = 1.0 / n
        q_gyro = self._q_gyro
        q_rotation = self._adaptive[0]
        if q_rotation > 0.0:  # gyro_scale_std: a scale error adds up while the sensor turns
            wx, wy, wz = gx - b0, gy - b1, gz - b2
            q_gyro += q_rotation * (wx * wx + wy * wy + wz * wz)
        if self.clipped:  # at the rail the rate beyond it is unknown (gyro_range)
            q_gyro += self._rail_var * dt
        P = predicted_covariance(pred, self._P, (X0 * inv, X1 * inv, X2 * inv), q_gyro * dt,
                                 self._q_bias * dt)
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        gate = abs(norm / G - 1.0) < ACC_GATE and norm > 0.0
        if gate and fill is not None:  # the vector still fills: X is its direction, as
            # uncertain as that vector, its samples turned over their mean age
            X0, X1, X2, n = ax, ay, az, norm
            P = measured_covariance(P, (X0 / n, X1 / n, X2 / n), *fill)
        elif gate:
            dot = ax * X0 + ay * X1 + az * X2
            if dot < self._cos_innovation * norm * n:
                learn_bias = False  # grossly off: X only (bias_innovation)
            if dot < self._cos_gross * norm * n:  # off by more than gross_innovation: X's
                # variance at least the squared distance of the two directions
                P = raised_direction_variance(P, 2.0 - 2.0 * (dot / (norm * n)))
            if r is None:
                r = self._r_acc
            else:  # the longest correction time: r at most q T^2 / dt (max_correction_time)
                cap = q_gyro * self._longest2 / dt
                r = r if r < cap else (cap if cap > self._r_acc else self._r_acc)
            X0, X1, X2, b0, b1, b2, P = measurement_update(
                pred, (b0, b1, b2), P, (ax, ay, az), r, self._w, self._w_mu, None, learn_bias)
            n = math.sqrt(X0 * X0 + X1 * X1 + X2 * X2)
        self.x = [X0 / n, X1 / n, X2 / n, b0, b1, b2]
        self._P = P
