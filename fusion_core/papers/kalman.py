"""The papers' two-state [angle, bias] Kalman filter, one for roll and one for pitch.

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
biases are exactly the degree filter's times pi/180 (tests/test_kalman.py checks it).

The equations are module functions (predict_covariance, measurement_gain, bias_update): the
recommended filter (fusion_core.kalman) is built on them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar, Final

from ..base import NEVER_ESTIMATED, Estimator
from ..kinematics import (
    HALF_PI,
    PI,
    accel_roll_pitch,
    clamp_pitch,
    euler_step,
    heun_euler_step,
    wrap_angle,
)
from ..state import ANGLE, COV, HALF_ANGLE, REAL, StateSpec
from ..types import DEG, Estimate, G, Param
from .common import PAPER_COMMON, PAPER_GATE, Vec3

DEG2: Final = DEG * DEG
Cov = tuple[float, float, float, float]
"""A 2x2 covariance [[P00, P01], [P10, P11]] as (P00, P01, P10, P11)."""
GainRule = Callable[[Cov, float], tuple[tuple[float, float], Cov]] | None
"""An update's gain and covariance from P and R (measurement_gain, or another rule)."""


def predict_covariance(P: Cov, dt: float, q_angle: float, q_bias: float) -> Cov:
    """F P F' + Q, F = [[1, -dt], [0, 1]], Q = diag(q_angle, q_bias) dt (Das & Mary eq. 19-22)."""
    P00, P01, P10, P11 = P
    return (
        P00 + dt * (dt * P11 - P01 - P10 + q_angle),
        P01 - dt * P11,
        P10 - dt * P11,
        P11 + q_bias * dt,
    )


def measurement_gain(P: Cov, r: float) -> tuple[tuple[float, float], Cov]:
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


def bias_update(angle: float, bias: float, P: Cov, y: float, r: float
                ) -> tuple[float, float, Cov]:
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


PAPER_KF_PARAMS: Final[tuple[Param, ...]] = (
    Param("Q_angle", 0.001 * DEG2,
          "Process noise of the angle per second of integration (Gui et al.: 0.001 deg^2/s)",
          unit="rad2/s", low=0.0, display_unit="deg2/s"),
    Param("Q_bias", 0.003 * DEG2,
          "Process noise of the gyro bias per second (Gui et al.: 0.003 deg^2/s^3)",
          unit="rad2/s3", low=0.0, display_unit="deg2/s3"),
    Param("R_measure", 0.03 * DEG2,
          "Variance of the accelerometer angle at the loop time R_loop_time (Gui et al.: "
          "0.03 deg^2)",
          unit="rad2", low=0.0, low_open=True, display_unit="deg2"),
    Param("R_loop_time", 0.033,
          "Loop time R_measure was tuned at: each step's variance is R_measure R_loop_time / dt, "
          "so the correction keeps the bandwidth Gui et al. tuned at 0.033 s at any rate (0: "
          "R_measure is each sample's variance)",
          unit="s", low=0.0),
    *PAPER_GATE,
)
"""The parameters of PaperKalmanFilter, at the papers' values."""


class RollPitchAxes:
    """The two [angle, bias] filters, roll's and pitch's, updated together: the steps the
    papers' filter and the recommended one (fusion_core.kalman) share.

    The roll and the pitch filter have the same F, Q and R and every update treats both, so
    P_roll == P_pitch: one covariance, computed once (the same numbers as twice). A state
    snapshot with two different ones is still followed axis by axis."""

    roll: float
    pitch: float
    bias_x: float
    bias_y: float
    P_roll: Cov
    P_pitch: Cov
    r_step: float
    gain_roll: tuple[float, float]
    gain_pitch: tuple[float, float]
    _gate2: tuple[float, float]
    _q_bias: float

    def predict_covariances(self, dt: float, q_angle: float) -> None:
        """Both covariances' time update (predict_covariance)."""
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

    def update_angles(self, y_roll: float, y_pitch: float, gain: GainRule = None) -> None:
        """Measurement update of both filters with given innovations (accelerometer angle -
        predicted angle), by gain's rule (None: measurement_gain, eq. 23-27)."""
        gain = gain or measurement_gain
        P, P_pitch = self.P_roll, self.P_pitch
        r = self.r_step
        self.gain_roll, self.P_roll = gain(P, r)
        if P_pitch == P:  # one covariance
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
        """Update with direct measurements z of the x and y gyro bias (variance r each): a
        gyro at rest reads its bias (a zero-angular-rate update)."""
        self.roll, self.bias_x, self.P_roll = bias_update(
            self.roll, self.bias_x, self.P_roll, z_x - self.bias_x, r
        )
        self.pitch, self.bias_y, self.P_pitch = bias_update(
            self.pitch, self.bias_y, self.P_pitch, z_y - self.bias_y, r
        )


NO_Z_BIAS: Final = (f"{NEVER_ESTIMATED}: the papers' filter has no bias state about z, which "
                    "no accelerometer tilt observes")
"""Why bias_z of the papers' per-axis Kalman filter (and of their position filter, whose
attitude is that filter's) is 0 (Estimator.ZERO_BIAS)."""


class PaperKalmanFilter(RollPitchAxes, Estimator):
    """Gui et al. eq. 5-26 / Das & Mary eq. 16-27: a 2-state [angle, bias] Kalman filter for
    roll and one for pitch, as the papers write it.

    Per sample: the angles follow the bias-corrected rates through the Z-Y-X Euler-rate
    kinematics (the papers' rectangle rule, or Heun's method with gyro_sampling="point"), the
    covariance F P F' + Q (predict_covariance); while gate_low <= |acc|/g <= gate_high the
    accelerometer's roll and pitch (atan2) correct both (measurement_gain; the roll innovation
    wrapped to [-pi, pi]). bias_z is 0: no accelerometer tilt observes a bias about z.

    P = 0 at the start, as in the papers' code. The papers give R per sample at their loop time
    (0.033 s) with Q a density (times dt); R_loop_time keeps the correction time constant
    sqrt(R dt / Q_angle) they tuned at any rate: R_k = R_measure R_loop_time / dt, the usual
    continuous-to-discrete rule for a measurement noise, exact at their loop time.

    The position filters level their accelerometer with this filter and drive it sample by
    sample through propagate, accel_trusted, correct, correct_innovation, correct_bias and
    took_sample (the tilt stage: fusion_core.position).
    """

    PARAMS = PAPER_KF_PARAMS
    COMMON = PAPER_COMMON
    TWIN: ClassVar[str | None] = "fc_paper_kf"
    ZERO_BIAS: ClassVar[dict[str, str]] = {"bias_z": NO_Z_BIAS}
    STATE: ClassVar[StateSpec] = {
        "roll": ANGLE, "pitch": HALF_ANGLE, "bias_x": REAL, "bias_y": REAL, "P_roll": COV,
        "P_pitch": COV,
    }

    def _configure(self) -> None:
        p = self._params
        self._q_angle = float(p["Q_angle"])
        self._q_bias = float(p["Q_bias"])
        self._r = float(p["R_measure"])
        self._r_loop = self._r * float(p["R_loop_time"])  # R dt, the same at every rate
        self.r_step = self._r  # this step's measurement variance (propagate sets it)
        self._gate2 = ((p["gate_low"] * G) ** 2, (p["gate_high"] * G) ** 2)

    def _reset(self) -> None:
        self.roll = 0.0
        self.pitch = 0.0
        self.bias_x = 0.0
        self.bias_y = 0.0
        self.P_roll: Cov = (0.0, 0.0, 0.0, 0.0)
        self.P_pitch: Cov = self.P_roll  # one covariance for both axes (see propagate)
        self.r_step = self._r
        self.gain_roll = (0.0, 0.0)  # the last update's gains (diagnostics)
        self.gain_pitch = (0.0, 0.0)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        self.roll, self.pitch = accel_roll_pitch(ax, ay, az)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        self.propagate(self.gyro_prev, (gx, gy, gz), dt)
        if self.accel_trusted(ax * ax + ay * ay + az * az):
            self.correct(ax, ay, az)
        return Estimate(self.roll, self.pitch, (self.bias_x, self.bias_y, 0.0))

    # ----- the tilt stage: the steps one sample takes, for a filter that drives them ---------
    def propagate(self, prev: Vec3, g: Vec3, dt: float,
                  sc: tuple[float, float, float, float] | None = None) -> None:
        """Time update from the previous gyro sample prev to this one, g (Gui et al. eq. 5-22):
        the angles by the Euler-rate kinematics, P by the papers' F and Q; sc: the sines and
        cosines of roll and pitch (kinematics.euler_rates) where the caller has them."""
        bx, by = self.bias_x, self.bias_y
        gx, gy, gz = g
        if self._trapezoid:
            p0, q0, r0 = prev
            roll, pitch = heun_euler_step(self.roll, self.pitch, p0 - bx, q0 - by, r0, gx - bx,
                                          gy - by, gz, dt, sc)
        else:
            roll, pitch = euler_step(self.roll, self.pitch, gx - bx, gy - by, gz, dt, sc)
        self.roll = roll if -PI <= roll <= PI else wrap_angle(roll)
        self.pitch = pitch if -HALF_PI <= pitch <= HALF_PI else clamp_pitch(pitch)
        if self._r_loop > 0.0:
            self.r_step = self._r_loop / dt
        self.predict_covariances(dt, self._q_angle)

    def correct(self, ax: float, ay: float, az: float) -> None:
        """Measurement update of both axes with the accelerometer's roll and pitch (eq. 23-26)."""
        acc_roll, acc_pitch = accel_roll_pitch(ax, ay, az)
        y_roll = acc_roll - self.roll
        if not -PI <= y_roll <= PI:
            y_roll = wrap_angle(y_roll)
        self.correct_innovation(y_roll, acc_pitch - self.pitch)

    def correct_innovation(self, y_roll: float, y_pitch: float) -> None:
        """Measurement update with given innovations (accelerometer angle - predicted angle)."""
        self.update_angles(y_roll, y_pitch)

    def took_sample(self, g: Vec3) -> None:
        """Close a sample the driving filter stepped through the stage by hand: g becomes the
        previous gyro sample and the sample is counted, as step() does."""
        self.gyro_prev = g
        self.n_samples += 1

    def _estimate(self) -> Estimate:
        return Estimate(self.roll, self.pitch, (self.bias_x, self.bias_y, 0.0))


__all__ = ["PaperKalmanFilter", "RollPitchAxes", "bias_update", "measurement_gain",
           "predict_covariance"]
