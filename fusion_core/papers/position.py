"""The paper's position Kalman filter: the tilt from the papers' 2-state Kalman filter, then a
[p, v, a] filter per axis.

Reference:
  Safitri, Cahyadi, Firmansyah, UAV position estimation, eq. 20-29: per axis the state is
  [p, v, a] with F = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]] (eq. 23), the accelerometer
  observes a (H = [0 0 1]), and the process noise is white jerk of density q (eq. 29):
    Q = q [[dt^5/20, dt^4/8, dt^3/6], [dt^4/8, dt^3/3, dt^2/2], [dt^3/6, dt^2/2, dt]].
  They compare three Q/R forms; their best final error on a 2 m move is 0.0385 m in x.
  The tilt that turns the body specific force into the level frame comes from the papers'
  Kalman filter (Gui et al. / Das & Mary, fusion_core.papers.kalman) run on the same samples.

Implementation: plain floats. The three axes share F, Q, R and their updates, so they share one
covariance P (and one gain per update), kept as its upper triangle
(p00, p01, p02, p11, p12, p22); the `P` attribute shows it as a 3x3 tuple of tuples and the
`states` attribute the per-axis [p, v, a] as lists. The equations are module functions
(process_noise, axis_filters, level_acceleration): the recommended filter
(fusion_core.position) is built on them.
"""

from __future__ import annotations

from math import cos, sin
from typing import Any, ClassVar, Final

from ..base import Estimator
from ..kinematics import PI, roll_pitch_sines, wrap_angle
from ..state import ANGLE, COV, NESTED, REAL, StateSpec
from ..types import MPU6050_ACC_DENSITY, Estimate, G, Param
from .common import PAPER_COMMON, Vec3
from .kalman import NO_Z_BIAS, PAPER_KF_PARAMS, PaperKalmanFilter

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


def yaw_and_level_acceleration(roll: float, pitch: float, yaw: float, wy: float, gz: float,
                               a: Vec3, dt: float,
                               sc: tuple[float, float, float, float] | None = None
                               ) -> tuple[float, Vec3]:
    """Yaw from the gyro over dt (the Z-Y-X Euler-rate kinematics, Duong Quoc et al. eq. 2, with
    wy the bias-corrected y rate; held where cos(pitch) is 0) and the level-frame acceleration
    of the specific force a with the new attitude (level_acceleration); sc: (sin roll,
    cos roll, sin pitch, cos pitch) where the caller has them."""
    sr, cr, sp, cp = roll_pitch_sines(roll, pitch) if sc is None else sc
    if cp > 1e-6 or cp < -1e-6:  # abs(cp) > 1e-6
        yaw += dt * (wy * sr + gz * cr) / cp
        yaw = yaw if -PI <= yaw <= PI else wrap_angle(yaw)
    return yaw, level_acceleration(a[0], a[1], a[2], sr, cr, sp, cp, sin(yaw), cos(yaw))


QR_FORMS: Final = ("white_jerk", "piecewise_jerk", "diagonal")
"""Safitri et al.'s three Q/R forms (process_noise)."""
JERK_PARAMS: Final[tuple[Param, ...]] = (
    Param("q", 1.0, "Jerk noise power spectral density per axis", unit="m2/s5", low=0.0,
          low_open=True),
)
TILT_PARAM_NAMES: Final = tuple(p.name for p in PAPER_KF_PARAMS)
"""The parameters of the tilt stage (PaperKalmanFilter) a position filter passes through."""


class AxisFiltersState:
    """The state both position filters hold: the tilt stage (a PaperKalmanFilter, its state the
    field tilt_state), the [p, v, a] of the three axes (_x, shown as `states`) and their shared
    covariance (_P, shown as the 3x3 `P`)."""

    tilt: PaperKalmanFilter
    _x: AxisStates
    _P: Sym3

    @property
    def tilt_state(self) -> dict:
        return self.tilt.get_state()

    @tilt_state.setter
    def tilt_state(self, value: dict) -> None:
        self.tilt.set_state(value)

    @property
    def states(self) -> list[list[float]]:
        """[p, v, a] of the x, y and z axes (a copy)."""
        return axis_lists(self._x)

    @states.setter
    def states(self, value: list[list[float]]) -> None:
        self._x = axis_tuple(value)

    @property
    def P(self) -> Mat3:
        """The covariance shared by the three axes, 3x3 (of [p, v, a])."""
        return sym3_matrix(self._P)

    @P.setter
    def P(self, value: Mat3) -> None:
        self._P = sym3_packed(value)


class PaperPositionKalmanFilter(AxisFiltersState, Estimator):
    """Safitri et al. eq. 20-29: a [p, v, a] Kalman filter per axis on the level-frame
    acceleration, as the paper writes it.

    Per sample: the tilt stage (the papers' Kalman filter, PaperKalmanFilter, on the same
    samples and with every accelerometer sample its gate lets through) gives roll and pitch;
    yaw is the gyro's integral (Euler kinematics; unobservable: positions are in the
    start-heading frame); a = R(roll, pitch, yaw) f - g e_z; per axis predict (F eq. 23, Q of
    the chosen form) and update with a (H = [0 0 1], R = acc_psd / dt). The filter starts at
    position 0 and velocity 0 (the platform at rest, as in the paper). Roll, pitch and bias are
    the tilt stage's (bias_z 0).
    """

    HAS_POSITION = True
    PARAMS = (
        Param("qr_form", "white_jerk",
              "Process-noise form (Safitri et al.'s Q/R forms): 'white_jerk' (eq. 29), "
              "'piecewise_jerk', 'diagonal'", choices=QR_FORMS),
        *JERK_PARAMS,
        Param("acc_psd", MPU6050_ACC_DENSITY**2,
              "Accelerometer white-noise power spectral density, R = acc_psd/dt (the MPU-6050 "
              "datasheet's (400 ug/sqrt(Hz))^2)", unit="m2/s3", low=0.0, low_open=True),
        *PAPER_KF_PARAMS,
    )
    COMMON = PAPER_COMMON
    TWIN: ClassVar[str | None] = "fc_paper_poskf"
    GYRO_ONLY: ClassVar[dict[str, float] | None] = {}  # its tilt stage's gate takes 3 g out
    ZERO_BIAS: ClassVar[dict[str, str]] = {"bias_z": NO_Z_BIAS}
    STATE: ClassVar[StateSpec] = {"yaw": ANGLE, "states": REAL, "P": COV, "tilt_state": NESTED}

    def _configure(self) -> None:
        p = self._params
        tilt_params = {k: p[k] for k in TILT_PARAM_NAMES}
        if not hasattr(self, "tilt"):
            self.tilt = PaperKalmanFilter(max_dt=p["max_dt"], max_rate=p["max_rate"],
                                          gyro_sampling=p["gyro_sampling"], **tilt_params)
        else:
            for k, v in tilt_params.items():
                self.tilt.set_param(k, v)
            self.tilt.set_param("max_dt", p["max_dt"])
            self.tilt.set_param("max_rate", p["max_rate"])
        self._acc_var_density = float(p["acc_psd"])
        self._Q_dt = 0.0  # the dt of Q and R (0: none yet, since every accepted dt is > 0)

    def _reset(self) -> None:
        self.tilt.reset()
        self.yaw = 0.0
        self._x = (0.0,) * 9
        self._P = (0.0,) * 6

    def _check_nested(self, field: str, snapshot: dict[str, Any], params: dict[str, Any]
                      ) -> None:
        """The tilt stage's state, checked by its filter with the parameters this filter's
        `params` give it (they are derived, never free)."""
        nested = type(self)(**params).tilt
        checked = nested.check_state(snapshot)
        if checked != nested.params:
            diff = sorted(k for k in checked if checked[k] != nested.params[k])
            raise ValueError(f"state field {field!r}: the parameter(s) {', '.join(diff)} differ "
                             "from what the position filter's parameters give")

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        self._x, self._P = first_axis_states(self.tilt, ax, ay, az, gx, gy, gz,
                                             self._params["max_dt"], self._acc_var_density)

    def _advance(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> Estimate:
        tilt = self.tilt
        wy = gy - tilt.bias_y  # the bias before this sample's update, for the yaw rate
        tilt.propagate(self.gyro_prev, (gx, gy, gz), dt)
        if tilt.accel_trusted(ax * ax + ay * ay + az * az):
            tilt.correct(ax, ay, az)
        tilt.took_sample((gx, gy, gz))
        self.yaw, acc = yaw_and_level_acceleration(tilt.roll, tilt.pitch, self.yaw, wy, gz,
                                                   (ax, ay, az), dt)
        if dt != self._Q_dt:
            p = self._params
            self._Q = process_noise(p["qr_form"], p["q"], dt)
            self._R = self._acc_var_density / dt
            self._Q_dt = dt
        self._x, self._P = axis_filters(self._x, self._P, self._Q, dt, acc, self._R, None)
        return self._estimate()

    def _estimate(self) -> Estimate:
        x = self._x
        t = self.tilt
        return Estimate(t.roll, t.pitch, (t.bias_x, t.bias_y, 0.0), (x[0], x[3], x[6]),
                        (x[1], x[4], x[7]))


def first_axis_states(tilt: PaperKalmanFilter, ax: float, ay: float, az: float, gx: float,
                      gy: float, gz: float, dt: float, acc_var_density: float
                      ) -> tuple[AxisStates, Sym3]:
    """The [p, v, a] filters' start from the first sample: the tilt stage initialised with it
    (dt, which the first sample does not use, one the stage accepts), position and velocity 0,
    a the sample's level-frame acceleration with one sample's variance at a nominal 100 Hz."""
    tilt.step((ax, ay, az), (gx, gy, gz), dt)
    roll, pitch = tilt.roll, tilt.pitch
    lx, ly, lz = level_acceleration(ax, ay, az, sin(roll), cos(roll), sin(pitch), cos(pitch),
                                    sin(0.0), cos(0.0))
    r = acc_var_density * 100.0
    return (0.0, 0.0, lx, 0.0, 0.0, ly, 0.0, 0.0, lz), (0.0, 0.0, 0.0, 0.0, 0.0, r)


def axis_lists(x: AxisStates) -> list[list[float]]:
    """[p, v, a] of the x, y and z axes as lists."""
    return [list(x[0:3]), list(x[3:6]), list(x[6:9])]


def axis_tuple(value: list[list[float]]) -> AxisStates:
    """axis_lists' inverse."""
    (p0, v0, a0), (p1, v1, a1), (p2, v2, a2) = value
    return (float(p0), float(v0), float(a0), float(p1), float(v1), float(a1),
            float(p2), float(v2), float(a2))


def sym3_matrix(P: Sym3) -> Mat3:
    """A packed symmetric 3x3 matrix as a 3x3 tuple of tuples."""
    m00, m01, m02, m11, m12, m22 = P
    return ((m00, m01, m02), (m01, m11, m12), (m02, m12, m22))


def sym3_packed(value: Mat3) -> Sym3:
    """sym3_matrix's inverse (the upper triangle)."""
    (m00, m01, m02), (_, m11, m12), (_, _, m22) = value
    return (float(m00), float(m01), float(m02), float(m11), float(m12), float(m22))


__all__ = ["PaperPositionKalmanFilter", "axis_filters", "level_acceleration", "process_noise",
           "yaw_and_level_acceleration"]
