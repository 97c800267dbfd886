"""The recommended position Kalman filter: the paper's [p, v, a] filter per axis
(fusion_core.papers.position: Safitri et al. eq. 20-29, whose equations it uses) with a
zero-velocity update at rest, a tilt stage that takes the accelerometer only at confirmed rest,
and the recommended attitude filter's roll and pitch as its attitude outputs
(PositionKalmanFilter).
"""

from __future__ import annotations

import dataclasses
from math import nan, sqrt
from typing import Any, ClassVar, Final

from .base import Estimator, SensorNoise
from .building_blocks import zero_rate_psd_param
from .kalman import Z_BIAS_REST_ONLY, AngleBiasKalmanFilter
from .kinematics import PI, accel_roll_pitch, roll_pitch_sines, wrap_angle
from .papers.kalman import PAPER_KF_PARAMS, PaperKalmanFilter
from .papers.position import (
    JERK_PARAMS,
    AxisFiltersState,
    axis_filters,
    first_axis_states,
    level_acceleration,
    process_noise,
    yaw_and_level_acceleration,
)
from .state import ANGLE, COV, FLAG, NESTED, NONNEG, REAL, Queue, Segments, StateSpec
from .types import DEG, Estimate, Param

REAL_ACC_DENSITY: Final = 0.0033
"""Accelerometer white-noise density [m/s^2/sqrt(Hz)] of a real MEMS IMU at rest, the
recommended acc_psd's root: the Allan deviation at tau = 1 s on the rest segments of BROAD's
trials (myon aktos-t; `python -m testbenches noise`), the convention of the sensor model (one
sample's standard deviation = density sqrt(rate))."""

PENDING_MAX: Final = 2048
"""Most accelerometer samples the stationary queue holds; when full the oldest is dropped
unapplied. The queue holds zupt_window seconds of samples: 250 at 1 kHz with the default window,
so the bound is met up to 8 kHz. A fixed bound lets the C twin keep the queue in its state
without allocating."""

TILT_PARAMS: Final[tuple[Param, ...]] = tuple(
    dataclasses.replace(p, default=0.0) if p.name == "R_loop_time" else p
    for p in PAPER_KF_PARAMS
)
"""The tilt stage's parameters (a PaperKalmanFilter, passed through): the papers' Q and R. It
sees the accelerometer only at confirmed rest, where the specific force is gravity alone, so it
may trust each sample as the papers do (R 0.03 deg^2 per sample, R_loop_time 0: it converges
within a rest of a fraction of a second); the recommended kf's values are for a filter that
must trust the accelerometer in motion too. The gyro sampling is the sensor's (point samples by
default, as every recommended estimator)."""
TILT_PARAM_NAMES: Final = tuple(p.name for p in TILT_PARAMS)

class PositionKalmanFilter(AxisFiltersState, Estimator):
    """The recommended position filter: Safitri et al.'s [p, v, a] filters with a zero-velocity
    update.

    Per sample:
      1. stationary detector: the sample is quiet when the specific force differs from its
         running mean (time constant zupt_window) by less than zupt_acc, the level-frame
         acceleration is below zupt_level_acc and the bias-corrected rate below zupt_gyro;
         the platform is stationary after zupt_window seconds of quiet samples, unless the
         filter is sure it is gliding (see _slow_enough);
      2. tilt: the papers' Kalman filter (PaperKalmanFilter, driven step by step through its
         tilt-stage methods) propagates roll and pitch with every sample; until its first
         confirmed rest it takes the attitude filter's roll and pitch after each sample (so
         it is aligned over the first samples and corrected in motion, as that filter is, and
         one untrusted first sample fades as it does there), and from then on it takes only
         accelerometer samples confirmed stationary: a quiet sample waits zupt_window seconds in
         a queue and is applied (its innovation taken against the tilt of its own time) only if
         every sample since was quiet too, because the first tens of milliseconds of a smooth
         move are too small to detect and would otherwise be taken for tilt. Yaw is the gyro's
         integral (unobservable: positions are in the start-heading frame);
      3. level-frame acceleration a = R(roll, pitch, yaw) f - g e_z;
      4. per axis [p, v, a]: predict (F eq. 23, the white-jerk Q of eq. 29), update with a
         (H = [0 0 1], R = acc_psd / dt), and while stationary a zero-velocity update
         (H = [0 1 0], z = 0, variance zupt_noise^2) so that velocity does not drift at rest;
         while stationary the gyro also updates the tilt stage's biases (a zero-angular-rate
         update, variance gyro_psd / dt), so the tilt does not drift during the next move.
    The filter starts at position 0 and velocity 0 (the platform at rest, as in the paper).

    Outputs pos, vel [m, m/s] plus roll, pitch and bias, these from the recommended
    AngleBiasKalmanFilter run on the same samples with the same gyro_range, its rail judged on
    the sensor's own axes (Estimator.step_prepared), so that they are the kf's for the same
    sensor: the tilt stage is right for levelling the
    accelerometer between rests (it never takes linear acceleration for tilt), but in continuous
    motion it is gyro-only integration, and an attitude output must be as good as the best
    attitude filter here. The recommended acc_psd and gyro_psd are the noise densities measured
    on a real MEMS IMU, squared.
    """

    HAS_POSITION = True
    PARAMS = (
        *JERK_PARAMS,
        Param(
            "acc_psd", REAL_ACC_DENSITY**2,
            "Accelerometer white-noise power spectral density, R = acc_psd/dt (measured on a real "
            "MEMS IMU: (0.0033 m/s2/sqrt(Hz))^2; MPU-6050 datasheet (400 ug/sqrt(Hz))^2)",
            unit="m2/s3", low=0.0, low_open=True,
        ),
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
        zero_rate_psd_param(),
        *TILT_PARAMS,
    )
    TWIN: ClassVar[str | None] = "fc_poskf"
    BIAS_IN_MOTION: ClassVar[tuple[int, ...]] = (0, 1)
    SCANNED: ClassVar[tuple[str, ...]] = ("q",)
    ZERO_BIAS: ClassVar[dict[str, str]] = {"bias_z": Z_BIAS_REST_ONLY}
    STATE: ClassVar[StateSpec] = {
        "yaw": ANGLE, "states": REAL, "P": COV, "quiet_time": NONNEG, "stationary": FLAG,
        "pending": Queue(Segments(((NONNEG, 1), (REAL, 4))), 5, PENDING_MAX), "turned": REAL,
        "f_mean": REAL, "aligned": FLAG, "tilt_state": NESTED, "attitude_state": NESTED,
    }

    @classmethod
    def noise_params(cls, noise: SensorNoise) -> dict[str, float]:
        """acc_psd = the accelerometer's PSD and gyro_psd the gyro's (its tilt stage keeps the
        papers' Q and R, which the position contract was met with)."""
        return {"acc_psd": noise.acc_density * noise.acc_density,
                "gyro_psd": noise.gyro_density * noise.gyro_density}

    def _configure(self) -> None:
        p = self._params
        tilt_params = {k: p[k] for k in TILT_PARAM_NAMES}
        if not hasattr(self, "tilt"):
            self.tilt = PaperKalmanFilter(max_dt=p["max_dt"], max_rate=p["max_rate"],
                                          gyro_sampling=p["gyro_sampling"], **tilt_params)
            # the attitude outputs: the recommended kf on the same samples, with the gyro range
            # (the rail flag it takes with each sample is this filter's: step_prepared)
            self.att = AngleBiasKalmanFilter(max_dt=p["max_dt"], max_rate=p["max_rate"],
                                             gyro_sampling=p["gyro_sampling"],
                                             gyro_range=p["gyro_range"])
        else:
            for k, v in tilt_params.items():
                self.tilt.set_param(k, v)
            for f in (self.tilt, self.att):
                f.set_param("max_dt", p["max_dt"])
                f.set_param("max_rate", p["max_rate"])
        self._acc_var_density = float(p["acc_psd"])
        self._zupt_var = float(p["zupt_noise"]) ** 2
        self._gyro_var_density = float(p["gyro_psd"])
        # the hot path's constants
        self._zupt_acc = float(p["zupt_acc"])
        self._zupt_level_acc = float(p["zupt_level_acc"])
        self._zupt_gyro = float(p["zupt_gyro"])
        self._window = float(p["zupt_window"])
        self._force_after = float(p["zupt_force_after"])
        # the dt of Q = process_noise("white_jerk", q, dt) and R = acc_psd / dt (0: none yet,
        # since every accepted dt is > 0)
        self._Q_dt = 0.0

    @property
    def attitude_state(self) -> dict:
        return self.att.get_state()

    @attitude_state.setter
    def attitude_state(self, value: dict) -> None:
        self.att.set_state(value)

    def attitude_params(self) -> dict[str, Any]:
        """The parameters of an AngleBiasKalmanFilter whose roll, pitch, bias and rejected
        samples equal this filter's on any samples, to the bit: this filter's input stage
        (COMMON_PARAMS: its sample rules, calibration, mounting and gyro range condition what
        the attitude filter takes, and its sensor_delay turns the outputs ahead) with the
        attitude filter's own parameters. A program that runs both filters on one recording
        may take the kf's outputs from this one's where its kf has these parameters."""
        common = {p.name for p in Estimator.COMMON}
        own = self.params
        return {name: own[name] if name in common else value
                for name, value in self.att.params.items()}

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
        self.aligned = False
        self._sines = (nan, nan, (0.0, 0.0, 0.0, 0.0))  # _tilt_sines' cache: none yet

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
        # The first sample's dt is not used; pass one the filters accept.
        max_dt = self._params["max_dt"]
        self._x, self._P = first_axis_states(self.tilt, ax, ay, az, gx, gy, gz, max_dt,
                                             self._acc_var_density)
        self.att.step_prepared((ax, ay, az), (gx, gy, gz), max_dt, self.clipped)
        self.f_mean = (ax, ay, az)

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
        sc = self._tilt_sines(roll, pitch)
        # the level-frame acceleration with yaw 0 (the yaw turns it about the vertical, which
        # leaves its norm as it is)
        lx, ly, lz = level_acceleration(ax, ay, az, sc[0], sc[1], sc[2], sc[3], 0.0, 1.0)
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
        tilt.propagate(self.gyro_prev, (gx, gy, gz), dt, sc)
        d_roll = tilt.roll - roll
        turned_roll, turned_pitch = self.turned
        turned_roll += d_roll if -PI <= d_roll <= PI else wrap_angle(d_roll)
        turned_pitch = turned_pitch + tilt.pitch - pitch
        self.turned = (turned_roll, turned_pitch)
        if not quiet:
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
                self.aligned = True
        if stationary:
            tilt.correct_bias(gx, gy, self._gyro_var_density / dt)
        tilt.took_sample((gx, gy, gz))
        att = self.att.step_prepared((ax, ay, az), (gx, gy, gz), dt, self.clipped)
        if not self.aligned:
            # Until its first confirmed rest the tilt stage levels with the attitude filter's
            # roll and pitch, which align over the first samples and are corrected in motion:
            # no single sample (a master's start value, a first sample taken in motion) sets
            # the levelling for good
            tilt.roll, tilt.pitch = att[0], att[1]
        # 3. yaw from the gyro, the level-frame acceleration with the new attitude
        self.yaw, acc = yaw_and_level_acceleration(tilt.roll, tilt.pitch, self.yaw, wy, gz,
                                                   (ax, ay, az), dt,
                                                   self._tilt_sines(tilt.roll, tilt.pitch))
        # 4. [p, v, a] filter per axis (eq. 20-29)
        if dt != self._Q_dt:
            p = self._params
            self._Q = process_noise("white_jerk", p["q"], dt)
            self._R = self._acc_var_density / dt
            self._Q_dt = dt
        x, self._P = axis_filters(
            self._x, self._P, self._Q, dt, acc, self._R,
            self._zupt_var if stationary else None,
        )
        self._x = x
        return self._estimate()

    def _tilt_sines(self, roll: float, pitch: float) -> tuple[float, float, float, float]:
        """(sin roll, cos roll, sin pitch, cos pitch) of the tilt stage's angles, computed once
        per pair of angles: the levelling after a sample's update, the next sample's detector
        and its Euler-rate step read the same four (a cache of a function of the two angles,
        so never stale, never saved)."""
        cached = self._sines
        if cached[0] == roll and cached[1] == pitch:
            return cached[2]
        sc = roll_pitch_sines(roll, pitch)
        self._sines = (roll, pitch, sc)
        return sc

    def _estimate(self) -> Estimate:
        x = self._x
        a = self.att.last  # the attitude kf's own output (in the sensor frame)
        return Estimate(a[0], a[1], a[2], (x[0], x[3], x[6]), (x[1], x[4], x[7]))
