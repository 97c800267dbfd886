"""Position Kalman filter: tilt from the 2-state Kalman filter, then a [p, v, a] filter per axis.

Reference:
  Safitri, Cahyadi, Firmansyah, UAV position estimation, eq. 20-29: per axis the state is
  [p, v, a] with F = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]] (eq. 23), the accelerometer
  observes a (H = [0 0 1]), and the process noise is white jerk of density q (eq. 29):
    Q = q [[dt^5/20, dt^4/8, dt^3/6], [dt^4/8, dt^3/3, dt^2/2], [dt^3/6, dt^2/2, dt]].
  They compare three Q/R forms; their best final error on a 2 m move is 0.0385 m in x.
  The tilt that turns the body specific force into the level frame comes from the
  AngleBiasKalmanFilter (Gui et al. / Das & Mary) run on the same samples.
"""

from __future__ import annotations

import functools
import math

from .base import Estimator
from .kalman import AngleBiasKalmanFilter
from .kinematics import accel_roll_pitch, wrap_angle
from .types import DEG, Estimate, G, Param

TILT_PARAMS = ("Q_angle", "Q_bias", "R_measure", "gate_low", "gate_high", "integration")
"""Parameters passed through to the tilt stage (AngleBiasKalmanFilter)."""

Mat3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


@functools.lru_cache(maxsize=16)  # one entry per (form, q, dt): dt is constant in most runs
def process_noise(form: str, q: float, dt: float) -> Mat3:
    """Q of one axis for the named form (Safitri et al.'s three Q/R forms, our reading):

    white_jerk      continuous white jerk of density q, discretised exactly (eq. 29);
    piecewise_jerk  jerk constant over each interval with variance q/dt:
                    q/dt * G G^T, G = [dt^3/6, dt^2/2, dt];
    diagonal        the diagonal of white_jerk only (no correlation between p, v, a).
    """
    d2, d3, d4, d5 = dt * dt, dt**3, dt**4, dt**5
    if form == "piecewise_jerk":
        g = (d3 / 6.0, d2 / 2.0, dt)
        s = q / dt
        return tuple(tuple(s * gi * gj for gj in g) for gi in g)  # type: ignore[return-value]
    full = (
        (q * d5 / 20.0, q * d4 / 8.0, q * d3 / 6.0),
        (q * d4 / 8.0, q * d3 / 3.0, q * d2 / 2.0),
        (q * d3 / 6.0, q * d2 / 2.0, q * dt),
    )
    if form == "diagonal":
        return ((full[0][0], 0.0, 0.0), (0.0, full[1][1], 0.0), (0.0, 0.0, full[2][2]))
    return full


def predict(P: Mat3, Q: Mat3, dt: float) -> Mat3:
    """F P F^T + Q for F of eq. 23, written out (P symmetric)."""
    h = 0.5 * dt * dt
    (p00, p01, p02), (_, p11, p12), (_, _, p22) = P
    r00 = p00 + dt * p01 + h * p02
    r01 = p01 + dt * p11 + h * p12
    r02 = p02 + dt * p12 + h * p22
    r11 = p11 + dt * p12
    r12 = p12 + dt * p22
    n00 = r00 + dt * r01 + h * r02 + Q[0][0]
    n01 = r01 + dt * r02 + Q[0][1]
    n02 = r02 + Q[0][2]
    n11 = r11 + dt * r12 + Q[1][1]
    n12 = r12 + Q[1][2]
    n22 = p22 + Q[2][2]
    return ((n00, n01, n02), (n01, n11, n12), (n02, n12, n22))


def scalar_update(
    P: Mat3, states: list[list[float]], j: int, z: tuple[float, float, float], r: float
) -> Mat3:
    """Update every axis with a measurement of its state j (value z[axis], variance r).

    The three axes share F, Q, R and P, so they share the gain K = P[:, j] / (P[j][j] + r).
    Updates `states` (per axis [p, v, a]) in place and returns the new P = P - K P[j, :].
    """
    col = (P[0][j], P[1][j], P[2][j])
    s = col[j] + r
    K = (col[0] / s, col[1] / s, col[2] / s)
    for axis, x in enumerate(states):
        y = z[axis] - x[j]
        x[0] += K[0] * y
        x[1] += K[1] * y
        x[2] += K[2] * y
    (p00, p01, p02), (p10, p11, p12), (p20, p21, p22) = P
    k0, k1, k2 = K
    c0, c1, c2 = col
    return (
        (p00 - k0 * c0, p01 - k0 * c1, p02 - k0 * c2),
        (p10 - k1 * c0, p11 - k1 * c1, p12 - k1 * c2),
        (p20 - k2 * c0, p21 - k2 * c1, p22 - k2 * c2),
    )


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

    Outputs pos, vel [m, m/s] plus the tilt stage's roll, pitch, bias (bias_z = 0).
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
            "acc_psd", (400e-6 * G) ** 2,
            "Accelerometer white-noise power spectral density, R = acc_psd/dt (MPU-6050: "
            "(400 ug/sqrt(Hz))^2)",
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
        Param(
            "gyro_psd", (0.005 * DEG) ** 2,
            "Gyro white-noise power spectral density, for the zero-rate update (MPU-6050: "
            "(0.005 deg/s/sqrt(Hz))^2)",
            unit="rad2/s", low=0.0, low_open=True, display_unit="deg2/s",
        ),
        Param(
            "tilt_update", "stationary",
            "When the tilt filter uses the accelerometer: 'stationary' or 'always' (the papers')",
            choices=("stationary", "always"),
        ),
        *(
            p for p in AngleBiasKalmanFilter.PARAMS
            if p.name in TILT_PARAMS
        ),
    )
    STATE = (
        "yaw", "states", "P", "quiet_time", "stationary", "pending", "turned", "f_mean",
        "tilt_state",
    )

    def _configure(self) -> None:
        p = self._params
        tilt_params = {k: p[k] for k in TILT_PARAMS}
        if not hasattr(self, "tilt"):
            self.tilt = AngleBiasKalmanFilter(max_dt=p["max_dt"], **tilt_params)
        else:
            for k, v in tilt_params.items():
                if k != "integration":
                    self.tilt.set_param(k, v)
            self.tilt.set_param("max_dt", p["max_dt"])
        self._acc_var_density = p["acc_psd"]
        self._zupt_var = p["zupt_noise"] ** 2
        self._gyro_var_density = p["gyro_psd"]

    @property
    def tilt_state(self) -> dict:
        return self.tilt.get_state()

    @tilt_state.setter
    def tilt_state(self, value: dict) -> None:
        self.tilt.set_state(value)

    def _reset(self) -> None:
        self.tilt.reset()
        self.yaw = 0.0
        self.states = [[0.0, 0.0, 0.0] for _ in range(3)]
        self.P = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        self.quiet_time = 0.0
        self.stationary = False
        # Accelerometer samples waiting for confirmation: (quiet_time when taken, acc roll,
        # acc pitch, `turned` when taken); `turned` sums the gyro propagation of roll and pitch.
        self.pending: list[tuple[float, float, float, float, float]] = []
        self.turned = (0.0, 0.0)
        self.f_mean = (0.0, 0.0, 0.0)

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        # The first sample's dt is not used; pass one the tilt stage accepts.
        self.tilt.step((ax, ay, az), (gx, gy, gz), self._params["max_dt"])
        self.f_mean = (ax, ay, az)
        a = self._level_acceleration(ax, ay, az)
        r = self._acc_var_density * 100.0  # one sample's variance at a nominal 100 Hz
        self.P = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, r))
        for axis in range(3):
            self.states[axis][2] = a[axis]

    def _level_acceleration(self, ax: float, ay: float, az: float) -> tuple[float, float, float]:
        """R(roll, pitch, yaw) f - g e_z, R = Rz Ry Rx (body to level frame)."""
        sr, cr = math.sin(self.tilt.roll), math.cos(self.tilt.roll)
        sp, cp = math.sin(self.tilt.pitch), math.cos(self.tilt.pitch)
        sy, cy = math.sin(self.yaw), math.cos(self.yaw)
        # Ry Rx f
        u0 = cp * ax + sp * (sr * ay + cr * az)
        u1 = cr * ay - sr * az
        u2 = -sp * ax + cp * (sr * ay + cr * az)
        return cy * u0 - sy * u1, sy * u0 + cy * u1, u2 - G

    def _slow_enough(self) -> bool:
        """Whether the estimated speed allows a zero-velocity update.

        An IMU cannot tell gliding at constant velocity from rest: in the middle of a smooth move
        the acceleration passes through zero for longer than the detector window (0.36 s in a 1 m
        move over 3 s). A speed the filter is sure of (above zupt_speed and above 5 standard
        deviations) is not reset; after zupt_force_after seconds of quiet it is, whatever the
        filter believes, so that a drifted velocity cannot lock the update out.
        """
        speed = math.sqrt(sum(x[1] * x[1] for x in self.states))
        sigma = math.sqrt(self.P[1][1] + self._zupt_var)
        return speed <= max(self._params["zupt_speed"], 5.0 * sigma)

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        p = self._params
        tilt = self.tilt
        # 1. stationary detector: the specific force against its own running mean (body frame:
        # a tilt error cannot hide rest from the detector that corrects the tilt), a coarse
        # level-frame acceleration test (a smooth move's acceleration plateau changes the
        # specific force too slowly for the first test), and the bias-corrected rate
        mx, my, mz = self.f_mean
        wx, wy = gx - tilt.bias_x, gy - tilt.bias_y
        a_prev = self._level_acceleration(ax, ay, az)
        quiet = (
            math.sqrt((ax - mx) ** 2 + (ay - my) ** 2 + (az - mz) ** 2) < p["zupt_acc"]
            and math.sqrt(a_prev[0] ** 2 + a_prev[1] ** 2 + a_prev[2] ** 2) < p["zupt_level_acc"]
            and math.sqrt(wx * wx + wy * wy + gz * gz) < p["zupt_gyro"]
        )
        k = min(1.0, dt / p["zupt_window"]) if p["zupt_window"] > 0.0 else 1.0
        self.f_mean = (mx + k * (ax - mx), my + k * (ay - my), mz + k * (az - mz))
        self.quiet_time = self.quiet_time + dt if quiet else 0.0
        self.stationary = quiet and self.quiet_time >= p["zupt_window"] and (
            self.quiet_time >= p["zupt_force_after"] or self._slow_enough()
        )
        # 2. tilt stage; yaw from the gyro (Euler kinematics, Duong Quoc et al. eq. 2)
        tilt.gyro_prev = self.gyro_prev
        roll0, pitch0 = tilt.roll, tilt.pitch
        tilt.propagate(gx, gy, gz, dt)
        turned = (
            self.turned[0] + wrap_angle(tilt.roll - roll0),
            self.turned[1] + tilt.pitch - pitch0,
        )
        self.turned = turned
        norm2 = ax * ax + ay * ay + az * az
        acc_ok = tilt.accel_trusted(norm2)
        if p["tilt_update"] == "always":
            if acc_ok:
                tilt.correct(ax, ay, az)
        elif not quiet:
            self.pending = []
        else:
            if acc_ok and self.stationary:
                # Only samples that are themselves inside a stationary period (quiet for
                # zupt_window before), so the tail of a deceleration is never taken for tilt.
                self.pending.append((self.quiet_time, *accel_roll_pitch(ax, ay, az), *turned))
            while self.pending and self.quiet_time - self.pending[0][0] >= p["zupt_window"]:
                # Confirmed stationary: its innovation against the tilt of its own time, i.e. the
                # current tilt less the gyro propagation since (Safitri's tilt stage, delayed).
                _, acc_roll, acc_pitch, turned_roll, turned_pitch = self.pending.pop(0)
                tilt.correct_innovation(
                    wrap_angle(acc_roll - tilt.roll + turned[0] - turned_roll),
                    acc_pitch - tilt.pitch + turned[1] - turned_pitch,
                )
        if self.stationary and p["zaru"]:
            tilt.correct_bias(gx, gy, self._gyro_var_density / dt)
        tilt.gyro_prev = (gx, gy, gz)
        tilt.n_samples += 1
        cp = math.cos(tilt.pitch)
        if abs(cp) > 1e-6:
            sr, cr = math.sin(tilt.roll), math.cos(tilt.roll)
            self.yaw = wrap_angle(self.yaw + dt * (wy * sr + gz * cr) / cp)
        # 3. level-frame acceleration with the new attitude
        a = self._level_acceleration(ax, ay, az)
        # 4. [p, v, a] filter per axis (eq. 20-29)
        h = 0.5 * dt * dt
        for x in self.states:
            x[0] += dt * x[1] + h * x[2]
            x[1] += dt * x[2]
        P = predict(self.P, process_noise(p["qr_form"], p["q"], dt), dt)
        P = scalar_update(P, self.states, 2, a, self._acc_var_density / dt)
        if self.stationary and p["zupt"]:
            P = scalar_update(P, self.states, 1, (0.0, 0.0, 0.0), self._zupt_var)
        self.P = P

    def _estimate(self) -> Estimate:
        t = self.tilt
        s = self.states
        return Estimate(
            t.roll, t.pitch, (t.bias_x, t.bias_y, 0.0),
            (s[0][0], s[1][0], s[2][0]), (s[0][1], s[1][1], s[2][1]),
        )
