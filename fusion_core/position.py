"""Position Kalman filter: tilt from the 2-state Kalman filter, then a [p, v, a] filter per axis.

Reference:
  Safitri, Cahyadi, Firmansyah, UAV position estimation, eq. 20-29: per axis the state is
  [p, v, a] with F = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]] (eq. 23), the accelerometer
  observes a (H = [0 0 1]), and the process noise is white jerk of density q (eq. 29):
    Q = q [[dt^5/20, dt^4/8, dt^3/6], [dt^4/8, dt^3/3, dt^2/2], [dt^3/6, dt^2/2, dt]].
  They compare three Q/R forms; their best final error on a 2 m move is 0.0385 m in x.
  The tilt that turns the body specific force into the level frame comes from the
  AngleBiasKalmanFilter (Gui et al. / Das & Mary) run on the same samples.

Implementation: plain floats. The three axes share F, Q, R and their updates, so they share one
covariance P (and one gain per update), kept as its upper triangle
(p00, p01, p02, p11, p12, p22); the `P` attribute shows it as a 3x3 tuple of tuples and the
`states` attribute the per-axis [p, v, a] as lists.
"""

from __future__ import annotations

import dataclasses
import math
from math import cos, sin, sqrt
from typing import Any, ClassVar

from .base import ESTIMATE, Estimator, tuple_new
from .building_blocks import CONSTANT_NOISE, zero_rate_psd_param
from .kalman import PAPER_KF, AngleBiasKalmanFilter
from .kinematics import PI, accel_roll_pitch, wrap_angle
from .state import ANGLE, COV, FLAG, NESTED, NONNEG, REAL, Queue, Segments, StateSpec
from .types import DEG, Estimate, G, Param

REAL_ACC_DENSITY = 0.0033
"""Accelerometer white-noise density [m/s^2/sqrt(Hz)] of a real MEMS IMU at rest, the
recommended acc_psd's root: the Allan deviation at tau = 1 s on the rest segments of 13 BROAD
trials (myon aktos-t; `python -m testbenches noise`: 0.0031-0.0039, median 0.0033), the
convention of the sensor model (one sample's standard deviation = density sqrt(rate))."""

PENDING_MAX = 2048
"""Most accelerometer samples the stationary queue holds (tilt_update="stationary"); when full
the oldest is dropped unapplied. The queue holds zupt_window seconds of samples: 250 at 1 kHz
with the default window, so the bound is met up to 8 kHz. A fixed bound lets the C twin keep
the queue in its state without allocating."""

TILT_PARAMS = ("Q_angle", "Q_bias", "R_measure", "R_loop_time", "gate_low", "gate_high",
               "gyro_sampling")
"""Parameters passed through to the tilt stage (AngleBiasKalmanFilter)."""
TILT_DEFAULTS = {k: PAPER_KF[k] for k in ("Q_angle", "Q_bias", "R_measure", "gate_low",
                                          "gate_high")}
"""The tilt stage's defaults: the papers' values. It sees the accelerometer only at confirmed
rest, where the specific force is gravity alone, so it may trust each sample as the papers do
(R 0.03 deg^2: it converges within a rest of a fraction of a second); the recommended kf's
values are for a filter that must trust the accelerometer in motion too."""
TILT_FIXED = {
    "propagation": "euler", "acc_lowpass": 0.0, "rest_time": 0.0, "init_bias_std": 0.0,
    "tilt_axes": "body", "bias_innovation": math.pi, **CONSTANT_NOISE,
}
"""The tilt stage's other kf options: off. This filter drives the stage step by step (propagate,
correct_innovation, correct_bias) and does its own rest detection and bias updates."""

Sym3 = tuple[float, float, float, float, float, float]
"""A symmetric 3x3 matrix as its upper triangle (m00, m01, m02, m11, m12, m22)."""
Mat3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]
AxisStates = tuple[float, float, float, float, float, float, float, float, float]
"""[p, v, a] of the x, y and z axes, one after the other."""


def process_noise(form: str, q: float, dt: float) -> Sym3:
    """Q of one axis for the named form (Safitri et al.'s three Q/R forms, our reading):

    white_jerk      continuous white jerk of density q, discretised exactly (eq. 29);
    piecewise_jerk  jerk constant over each interval with variance q/dt:
                    q/dt * G G^T, G = [dt^3/6, dt^2/2, dt];
    diagonal        the diagonal of white_jerk only (no correlation between p, v, a).
    """
    d2, d3, d4, d5 = dt * dt, dt**3, dt**4, dt**5
    if form == "piecewise_jerk":
        g0, g1, g2 = d3 / 6.0, d2 / 2.0, dt
        s = q / dt
        return (s * g0 * g0, s * g0 * g1, s * g0 * g2, s * g1 * g1, s * g1 * g2, s * g2 * g2)
    q00, q11, q22 = q * d5 / 20.0, q * d3 / 3.0, q * dt
    if form == "diagonal":
        return (q00, 0.0, 0.0, q11, 0.0, q22)
    return (q00, q * d4 / 8.0, q * d3 / 6.0, q11, q * d2 / 2.0, q22)


def axis_filters(
    x: AxisStates, P: Sym3, Q: Sym3, dt: float, acc: tuple[float, float, float], r: float,
    zupt_r: float | None,
) -> tuple[AxisStates, Sym3]:
    """One sample of the three [p, v, a] filters (eq. 20-29), written out; returns (x, P).

    Predict: x <- F x, P <- F P F^T + Q (F of eq. 23). Update with the level-frame acceleration
    acc (H = [0 0 1], variance r per axis) and, unless zupt_r is None, with velocity 0
    (H = [0 1 0], variance zupt_r). Each update is the standard scalar one, shared by the axes:
    c = P H^T, K = c / (H c + r), x += K (z - H x), P <- P - K c^T.
    """
    p0, v0, a0, p1, v1, a1, p2, v2, a2 = x
    h = 0.5 * dt * dt
    p0 += dt * v0 + h * a0
    v0 += dt * a0
    p1 += dt * v1 + h * a1
    v1 += dt * a1
    p2 += dt * v2 + h * a2
    v2 += dt * a2
    # F P F^T + Q: first R = F P (rows of F times P), then R F^T
    m00, m01, m02, m11, m12, m22 = P
    r00 = m00 + dt * m01 + h * m02
    r01 = m01 + dt * m11 + h * m12
    r02 = m02 + dt * m12 + h * m22
    r11 = m11 + dt * m12
    r12 = m12 + dt * m22
    q00, q01, q02, q11, q12, q22 = Q
    m00 = r00 + dt * r01 + h * r02 + q00
    m01 = r01 + dt * r02 + q01
    m02 = r02 + q02
    m11 = r11 + dt * r12 + q11
    m12 = r12 + q12
    m22 = m22 + q22
    # acceleration update: c = (m02, m12, m22)
    s = m22 + r
    k0, k1, k2 = m02 / s, m12 / s, m22 / s
    y = acc[0] - a0
    p0 += k0 * y
    v0 += k1 * y
    a0 += k2 * y
    y = acc[1] - a1
    p1 += k0 * y
    v1 += k1 * y
    a1 += k2 * y
    y = acc[2] - a2
    p2 += k0 * y
    v2 += k1 * y
    a2 += k2 * y
    # P - K c^T; its column 1 (the zero-velocity update's c) has the entry m12 - k2 m12 below
    # the diagonal (= m12 - k1 m22 above it, but for rounding)
    c2 = m12 - k2 * m12
    m00, m01, m02 = m00 - k0 * m02, m01 - k0 * m12, m02 - k0 * m22
    m11, m12, m22 = m11 - k1 * m12, m12 - k1 * m22, m22 - k2 * m22
    if zupt_r is not None:
        # zero-velocity update: c = (m01, m11, c2), z = 0
        s = m11 + zupt_r
        k0, k1, k2 = m01 / s, m11 / s, c2 / s
        y = 0.0 - v0
        p0 += k0 * y
        v0 += k1 * y
        a0 += k2 * y
        y = 0.0 - v1
        p1 += k0 * y
        v1 += k1 * y
        a1 += k2 * y
        y = 0.0 - v2
        p2 += k0 * y
        v2 += k1 * y
        a2 += k2 * y
        c0, c1 = m01, m11
        m00, m01, m02 = m00 - k0 * c0, m01 - k0 * c1, m02 - k0 * c2
        m11, m12, m22 = m11 - k1 * c1, m12 - k1 * c2, m22 - k2 * c2
    return (p0, v0, a0, p1, v1, a1, p2, v2, a2), (m00, m01, m02, m11, m12, m22)


def level_acceleration(
    ax: float, ay: float, az: float,
    sr: float, cr: float, sp: float, cp: float, sy: float, cy: float,
) -> tuple[float, float, float]:
    """R f - g e_z, R = Rz Ry Rx (body to level frame), for the specific force f; sr, cr, sp, cp,
    sy, cy are the sines and cosines of roll, pitch and yaw."""
    # Ry Rx f
    w = sr * ay + cr * az
    u0 = cp * ax + sp * w
    u1 = cr * ay - sr * az
    u2 = -sp * ax + cp * w
    return cy * u0 - sy * u1, sy * u0 + cy * u1, u2 - G


class PositionKalmanFilter(Estimator):
    """Safitri et al. position Kalman filter with a zero-velocity update.

    Per sample:
      1. stationary detector: the sample is quiet when the specific force differs from its
         running mean (time constant zupt_window) by less than zupt_acc, the level-frame
         acceleration is below zupt_level_acc and the bias-corrected rate below zupt_gyro;
         the platform is stationary after zupt_window seconds of quiet samples, unless the
         filter is sure it is gliding (see _slow_enough);
      2. tilt: an AngleBiasKalmanFilter (same samples) propagates roll and pitch. With
         tilt_update="stationary" (default) it uses only accelerometer samples confirmed
         stationary: a quiet sample waits zupt_window seconds in a queue and is applied (its
         innovation taken against the tilt of its own time) only if every sample since was
         quiet too, because the first tens of milliseconds of a smooth move are too small to
         detect and would otherwise be taken for tilt. "always" is the papers' behaviour.
         Yaw is the gyro's integral (unobservable: positions are in the start-heading frame);
      3. level-frame acceleration a = R(roll, pitch, yaw) f - g e_z;
      4. per axis [p, v, a]: predict (F eq. 23, Q of the chosen form), update with a
         (H = [0 0 1], R = acc_psd / dt), and while stationary a zero-velocity update
         (H = [0 1 0], z = 0, variance zupt_noise^2) so that velocity does not drift at rest;
         while stationary the gyro also updates the tilt stage's biases (zero-angular-rate
         update, zaru), so the tilt does not drift during the next move.
    The filter starts at position 0 and velocity 0 (the platform at rest, as in the paper).

    Outputs pos, vel [m, m/s] plus roll, pitch and bias. With attitude="kf" (recommended) they
    come from an AngleBiasKalmanFilter with its recommended values run on the same samples: the
    tilt stage above is right for levelling the accelerometer between rests (it never takes
    linear acceleration for tilt), but in continuous motion it is gyro-only integration, and an
    attitude output must be as good as the best attitude filter here. With "tilt_stage" (the
    papers') they are the tilt stage's (bias_z = 0). The recommended acc_psd and gyro_psd are
    the noise densities measured on a real MEMS IMU, squared.
    """

    HAS_POSITION = True
    PARAMS = (
        Param(
            "qr_form", "white_jerk",
            "Process-noise form (Safitri et al. Q/R forms): 'white_jerk' (eq. 29), "
            "'piecewise_jerk', 'diagonal'",
            choices=("white_jerk", "piecewise_jerk", "diagonal"),
        ),
        Param("q", 1.0, "Jerk noise power spectral density per axis", unit="m2/s5", low=0.0,
              low_open=True),
        Param(
            "acc_psd", REAL_ACC_DENSITY**2,
            "Accelerometer white-noise power spectral density, R = acc_psd/dt (measured on a real "
            "MEMS IMU: (0.0033 m/s2/sqrt(Hz))^2; MPU-6050 datasheet (400 ug/sqrt(Hz))^2)",
            unit="m2/s3", low=0.0, low_open=True,
        ),
        Param("zupt", True, "Zero-velocity update while the platform is stationary"),
        Param(
            "zupt_acc", 0.2,
            "Stationary detector: threshold on the specific force's change from its running mean",
            unit="m/s2", low=0.0, low_open=True,
        ),
        Param(
            "zupt_level_acc", 0.5,
            "Stationary detector: level-frame acceleration threshold (coarse: it must tolerate "
            "the tilt error it is there to let the filter correct, 0.5 m/s2 ~ 3 deg)",
            unit="m/s2", low=0.0, low_open=True,
        ),
        Param(
            "zupt_gyro", 2.0 * DEG, "Stationary detector: angular-rate threshold",
            unit="rad/s", low=0.0, low_open=True,
        ),
        Param(
            "zupt_window", 0.25, "Stationary detector: how long the sample must stay quiet",
            unit="s", low=0.0,
        ),
        Param(
            "zupt_speed", 0.1,
            "Zero-velocity update: estimated speeds above this (and above 5 sigma) are trusted "
            "as motion at constant velocity, not reset", unit="m/s", low=0.0,
        ),
        Param(
            "zupt_force_after", 2.0,
            "Zero-velocity update: after this long quiet the platform is taken as stationary "
            "whatever the estimated speed", unit="s", low=0.0,
        ),
        Param(
            "zupt_noise", 0.005, "Standard deviation of the zero-velocity pseudo-measurement",
            unit="m/s", low=0.0, low_open=True,
        ),
        Param(
            "zaru", True,
            "Zero-angular-rate update of the tilt stage's gyro biases while stationary",
        ),
        zero_rate_psd_param(),
        Param(
            "tilt_update", "stationary",
            "When the tilt filter uses the accelerometer: 'stationary' or 'always' (the papers')",
            choices=("stationary", "always"),
        ),
        Param(
            "attitude", "kf",
            "Where the roll, pitch and bias outputs come from: 'kf' (an AngleBiasKalmanFilter with "
            "its recommended values on the same samples: accurate in continuous motion) or "
            "'tilt_stage' (the tilt that levels the accelerometer for the position filter; the "
            "papers')",
            choices=("kf", "tilt_stage"), tunable=False,
        ),
        *(
            dataclasses.replace(p, default=TILT_DEFAULTS.get(p.name, p.default))
            for p in AngleBiasKalmanFilter.PARAMS if p.name in TILT_PARAMS
        ),
    )
    TWIN: ClassVar[str | None] = "fc_poskf"
    STATE: ClassVar[StateSpec] = {
        "yaw": ANGLE, "states": REAL, "P": COV, "quiet_time": NONNEG, "stationary": FLAG,
        "pending": Queue(Segments(((NONNEG, 1), (REAL, 4))), 5, PENDING_MAX), "turned": REAL,
        "f_mean": REAL, "tilt_state": NESTED, "attitude_state": NESTED,
    }
    _x: AxisStates  # [p, v, a] of x, y, z
    _P: Sym3  # the covariance the three axes share, packed

    def _configure(self) -> None:
        p = self._params
        tilt_params = {k: p[k] for k in TILT_PARAMS}
        if not hasattr(self, "tilt"):
            self.tilt = AngleBiasKalmanFilter(max_dt=p["max_dt"], max_rate=p["max_rate"],
                                              **TILT_FIXED, **tilt_params)
            # the attitude output (attitude="kf"): the recommended kf on the same samples
            self.att = AngleBiasKalmanFilter(max_dt=p["max_dt"], max_rate=p["max_rate"],
                                             gyro_sampling=p["gyro_sampling"])
        else:
            for k, v in tilt_params.items():
                if k != "gyro_sampling":
                    self.tilt.set_param(k, v)
            for f in (self.tilt, self.att):
                f.set_param("max_dt", p["max_dt"])
                f.set_param("max_rate", p["max_rate"])
        self._own_attitude: bool = p["attitude"] == "kf"
        self._acc_var_density = float(p["acc_psd"])
        self._zupt_var = float(p["zupt_noise"]) ** 2
        self._gyro_var_density = float(p["gyro_psd"])
        # the hot path's constants
        self._zupt_acc = float(p["zupt_acc"])
        self._zupt_level_acc = float(p["zupt_level_acc"])
        self._zupt_gyro = float(p["zupt_gyro"])
        self._window = float(p["zupt_window"])
        self._force_after = float(p["zupt_force_after"])
        self._zupt = bool(p["zupt"])
        self._zaru = bool(p["zaru"])
        self._always: bool = p["tilt_update"] == "always"
        # the dt of Q = process_noise(qr_form, q, dt) and R = acc_psd / dt (0: none yet, since
        # every accepted dt is > 0)
        self._Q_dt = 0.0

    @property
    def attitude_state(self) -> dict:
        return self.att.get_state()

    @attitude_state.setter
    def attitude_state(self, value: dict) -> None:
        self.att.set_state(value)

    @property
    def tilt_state(self) -> dict:
        return self.tilt.get_state()

    @tilt_state.setter
    def tilt_state(self, value: dict) -> None:
        self.tilt.set_state(value)

    @property
    def states(self) -> list[list[float]]:
        """[p, v, a] of the x, y and z axes (a copy)."""
        x = self._x
        return [list(x[0:3]), list(x[3:6]), list(x[6:9])]

    @states.setter
    def states(self, value: list[list[float]]) -> None:
        (p0, v0, a0), (p1, v1, a1), (p2, v2, a2) = value
        self._x = (
            float(p0), float(v0), float(a0), float(p1), float(v1), float(a1),
            float(p2), float(v2), float(a2),
        )

    @property
    def P(self) -> Mat3:
        """The covariance shared by the three axes, 3x3 (of [p, v, a])."""
        m00, m01, m02, m11, m12, m22 = self._P
        return ((m00, m01, m02), (m01, m11, m12), (m02, m12, m22))

    @P.setter
    def P(self, value: Mat3) -> None:
        (m00, m01, m02), (_, m11, m12), (_, _, m22) = value
        self._P = (float(m00), float(m01), float(m02), float(m11), float(m12), float(m22))

    def _reset(self) -> None:
        self.tilt.reset()
        self.att.reset()
        self.yaw = 0.0
        self._x = (0.0,) * 9
        self._P = (0.0,) * 6
        self.quiet_time = 0.0
        self.stationary = False
        # Accelerometer samples waiting for confirmation: (quiet_time when taken, acc roll,
        # acc pitch, `turned` when taken); `turned` sums the gyro propagation of roll and pitch.
        self.pending: list[tuple[float, float, float, float, float]] = []
        self.turned = (0.0, 0.0)
        self.f_mean = (0.0, 0.0, 0.0)

    def _check_nested(self, field: str, snapshot: dict[str, Any], params: dict[str, Any]
                      ) -> None:
        """The tilt stage's and the attitude filter's states: each checked by its filter, with
        the parameters this filter's `params` give them (they are derived, never free)."""
        probe = PositionKalmanFilter(**params)
        nested = probe.tilt if field == "tilt_state" else probe.att
        checked = nested.check_state(snapshot)
        if checked != nested.params:
            diff = sorted(k for k in checked if checked[k] != nested.params[k])
            raise ValueError(f"state field {field!r}: the parameter(s) {', '.join(diff)} differ "
                             "from what the position filter's parameters give")

    def _restored(self) -> None:
        # a json snapshot holds the queue's entries as lists: make them tuples again
        entries: list[Any] = self.pending
        self.pending = [
            (float(t), float(r), float(p), float(r0), float(p0)) for t, r, p, r0, p0 in entries
        ]

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        # The first sample's dt is not used; pass one the tilt stage accepts.
        tilt = self.tilt
        tilt.step((ax, ay, az), (gx, gy, gz), self._params["max_dt"])
        if self._own_attitude:
            self.att.step((ax, ay, az), (gx, gy, gz), self._params["max_dt"])
        self.f_mean = (ax, ay, az)
        roll, pitch, yaw = tilt.roll, tilt.pitch, self.yaw
        lx, ly, lz = level_acceleration(
            ax, ay, az, sin(roll), cos(roll), sin(pitch), cos(pitch), sin(yaw), cos(yaw)
        )
        r = self._acc_var_density * 100.0  # one sample's variance at a nominal 100 Hz
        self._P = (0.0, 0.0, 0.0, 0.0, 0.0, r)
        self._x = (0.0, 0.0, lx, 0.0, 0.0, ly, 0.0, 0.0, lz)

    def _slow_enough(self) -> bool:
        """Whether the estimated speed allows a zero-velocity update.

        An IMU cannot tell gliding at constant velocity from rest: in the middle of a smooth move
        the acceleration passes through zero for longer than the detector window (0.36 s in a 1 m
        move over 3 s). A speed the filter is sure of (above zupt_speed and above 5 standard
        deviations) is not reset; after zupt_force_after seconds of quiet it is, whatever the
        filter believes, so that a drifted velocity cannot lock the update out.
        """
        x = self._x
        speed = sqrt(x[1] * x[1] + x[4] * x[4] + x[7] * x[7])
        sigma = sqrt(self._P[3] + self._zupt_var)
        return speed <= max(self._params["zupt_speed"], 5.0 * sigma)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        tilt = self.tilt
        # 1. stationary detector: the specific force against its own running mean (body frame:
        # a tilt error cannot hide rest from the detector that corrects the tilt), a coarse
        # level-frame acceleration test (a smooth move's acceleration plateau changes the
        # specific force too slowly for the first test), and the bias-corrected rate
        mx, my, mz = self.f_mean
        dx, dy, dz = ax - mx, ay - my, az - mz
        wx, wy = gx - tilt.bias_x, gy - tilt.bias_y
        roll, pitch = tilt.roll, tilt.pitch
        # the level-frame acceleration with yaw 0 (the yaw turns it about the vertical, which
        # leaves its norm as it is)
        lx, ly, lz = level_acceleration(
            ax, ay, az, sin(roll), cos(roll), sin(pitch), cos(pitch), 0.0, 1.0
        )
        quiet = (
            sqrt(dx * dx + dy * dy + dz * dz) < self._zupt_acc
            and sqrt(lx * lx + ly * ly + lz * lz) < self._zupt_level_acc
            and sqrt(wx * wx + wy * wy + gz * gz) < self._zupt_gyro
        )
        window = self._window
        k = dt / window if window > 0.0 else 1.0
        if k > 1.0:
            k = 1.0
        self.f_mean = (mx + k * dx, my + k * dy, mz + k * dz)
        quiet_time = self.quiet_time = self.quiet_time + dt if quiet else 0.0
        stationary = self.stationary = quiet and quiet_time >= window and (
            quiet_time >= self._force_after or self._slow_enough()
        )
        # 2. tilt stage; yaw from the gyro (Euler kinematics, Duong Quoc et al. eq. 2)
        tilt.gyro_prev = self.gyro_prev
        tilt.propagate(gx, gy, gz, dt)
        d_roll = tilt.roll - roll
        turned_roll, turned_pitch = self.turned
        turned_roll += d_roll if -PI <= d_roll <= PI else wrap_angle(d_roll)
        turned_pitch = turned_pitch + tilt.pitch - pitch
        self.turned = (turned_roll, turned_pitch)
        if self._always:
            if tilt.accel_trusted(ax * ax + ay * ay + az * az):
                tilt.correct(ax, ay, az)
        elif not quiet:
            if self.pending:
                self.pending = []
        else:
            pending = self.pending
            if stationary and tilt.accel_trusted(ax * ax + ay * ay + az * az):
                # Only samples that are themselves inside a stationary period (quiet for
                # zupt_window before), so the tail of a deceleration is never taken for tilt.
                if len(pending) >= PENDING_MAX:
                    pending.pop(0)
                pending.append((quiet_time, *accel_roll_pitch(ax, ay, az),
                                turned_roll, turned_pitch))
            while pending and quiet_time - pending[0][0] >= window:
                # Confirmed stationary: its innovation against the tilt of its own time, i.e. the
                # current tilt less the gyro propagation since (Safitri's tilt stage, delayed).
                _, acc_roll, acc_pitch, then_roll, then_pitch = pending.pop(0)
                tilt.correct_innovation(
                    wrap_angle(acc_roll - tilt.roll + turned_roll - then_roll),
                    acc_pitch - tilt.pitch + turned_pitch - then_pitch,
                )
        if stationary and self._zaru:
            tilt.correct_bias(gx, gy, self._gyro_var_density / dt)
        tilt.gyro_prev = (gx, gy, gz)
        tilt.n_samples += 1
        if self._own_attitude:
            self.att.step((ax, ay, az), (gx, gy, gz), dt)
        roll, pitch, yaw = tilt.roll, tilt.pitch, self.yaw
        sr, cr, sp, cp = sin(roll), cos(roll), sin(pitch), cos(pitch)
        if cp > 1e-6 or cp < -1e-6:  # abs(cp) > 1e-6
            yaw += dt * (wy * sr + gz * cr) / cp
            yaw = self.yaw = yaw if -PI <= yaw <= PI else wrap_angle(yaw)
        # 3. level-frame acceleration with the new attitude
        acc = level_acceleration(ax, ay, az, sr, cr, sp, cp, sin(yaw), cos(yaw))
        # 4. [p, v, a] filter per axis (eq. 20-29)
        if dt != self._Q_dt:
            p = self._params
            self._Q = process_noise(p["qr_form"], p["q"], dt)
            self._R = self._acc_var_density / dt
            self._Q_dt = dt
        x, self._P = axis_filters(
            self._x, self._P, self._Q, dt, acc, self._R,
            self._zupt_var if stationary and self._zupt else None,
        )
        self._x = x
        return self._estimate()

    def _estimate(self) -> Estimate:
        x = self._x
        if self._own_attitude:  # the attitude kf's own output (in the sensor frame)
            a = self.att.last
            roll, pitch, bias = a[0], a[1], a[2]
        else:
            t = self.tilt
            roll, pitch, bias = t.roll, t.pitch, (t.bias_x, t.bias_y, 0.0)
        return tuple_new(ESTIMATE, (roll, pitch, bias, (x[0], x[3], x[6]), (x[1], x[4], x[7])))
