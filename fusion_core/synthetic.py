"""Synthetic IMU recordings with exact truth, for tests, the demo table and the plant model.

A trajectory is given by its Euler angles and position as analytic functions of time (value,
first and second derivative). The IMU samples follow from the kinematics, not from finite
differences:
  body rates (inverse Z-Y-X Euler-rate kinematics)
    p = phi_dot - psi_dot sin(theta)
    q = theta_dot cos(phi) + psi_dot sin(phi) cos(theta)
    r = psi_dot cos(phi) cos(theta) - theta_dot sin(phi)
  specific force  f = R^T (a + g e_z), R = Rz(psi) Ry(theta) Rx(phi) (body to world, z up).

Every formula is written once and evaluated two ways: on an array of times with numpy
(`Trajectory.truth`, recordings and tests) and on one float time with plain math
(`Trajectory.truth_at`, the plant FMU's one evaluation per step, where numpy's per-call overhead
on one-element arrays would dominate). A formula sees the difference only through
`Ops` (sin, cos, clip, where, zeros_like); + - * / are IEEE operations in both, and no formula
raises a time-dependent value to a power (on CPUs with AVX-512 numpy computes array powers with
a vectorised pow whose last bit differs from libm's). So both paths give the same floats wherever
numpy's sin and cos are libm's (bit-identical with the numpy builds tested here; within an ulp
otherwise).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

import numpy as np

from .types import MPU6050_ACC_DENSITY, MPU6050_GYRO_DENSITY, G


class Ops(NamedTuple):
    """What a signal's formula uses besides + - * /: numpy's functions for an array of times
    (VECTOR) or plain math for one float time (SCALAR)."""

    sin: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    clip: Callable[[Any, float, float], Any]
    where: Callable[[Any, Any, Any], Any]
    zeros_like: Callable[[Any], Any]


VECTOR = Ops(np.sin, np.cos, np.clip, np.where, np.zeros_like)
SCALAR = Ops(
    math.sin,
    math.cos,
    lambda x, low, high: min(max(x, low), high),  # np.clip of one value
    lambda condition, a, b: a if condition else b,  # np.where of one value
    lambda t: 0.0,
)


class Signal(Protocol):
    """t -> (value, first derivative, second derivative): `s(t)` on an array of times (numpy),
    `s(t, SCALAR)` on one float time (plain floats)."""

    def __call__(self, t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]: ...


def with_spec(f: Signal, *spec: Any) -> Signal:
    """f with its formula as data, `f.spec` = (kind, parameters..., child specs): what the C twin
    of the plant evaluates (fusion_core/native/generate.py writes it into fc_scenarios.h)."""
    setattr(f, "spec", spec)  # noqa: B010 (a Protocol-typed function: no attribute to assign)
    return f


def spec_of(f: Signal) -> tuple[Any, ...]:
    """The formula of a signal made by this module's constructors (with_spec)."""
    return getattr(f, "spec")  # type: ignore[no-any-return]  # noqa: B009


def constant(value: float = 0.0) -> Signal:
    def f(t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]:
        z = ops.zeros_like(t)
        return z + value, z, z

    return with_spec(f, "constant", value)


def sine(amplitude: float, freq: float, phase: float = 0.0, offset: float = 0.0) -> Signal:
    """offset + amplitude sin(2 pi freq t + phase)."""
    w = 2.0 * math.pi * freq

    def f(t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]:
        arg = w * t + phase
        s, c = ops.sin(arg), ops.cos(arg)
        return offset + amplitude * s, amplitude * w * c, -amplitude * w * w * s

    return with_spec(f, "sine", amplitude, w, phase, offset)


def add(*signals: Signal) -> Signal:
    def f(t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]:
        # 0 + s1 + s2 + ... from left to right, as sum() did in Python < 3.12 (from 3.12 on,
        # sum() of floats compensates rounding errors, which numpy's + does not)
        v, dv, ddv = 0.0, 0.0, 0.0
        for s in signals:
            a, da, dda = s(t, ops)
            v, dv, ddv = v + a, dv + da, ddv + dda
        return v, dv, ddv

    return with_spec(f, "add", *(spec_of(s) for s in signals))


def min_jerk(start: float, end: float, t0: float, duration: float) -> Signal:
    """Minimum-jerk move from start to end over [t0, t0 + duration], at rest before and after:
    start + d (10 s^3 - 15 s^4 + 6 s^5), s = (t - t0) / duration, d = end - start."""
    d = end - start

    def f(t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]:
        s = ops.clip((t - t0) / duration, 0.0, 1.0)
        inside = (t > t0) & (t < t0 + duration)
        # the polynomial and its derivatives in s, in Horner form (products and sums only)
        pos = start + d * (s * s * s * (10.0 + s * (-15.0 + 6.0 * s)))
        vel = ops.where(inside, d * (s * s * (30.0 + s * (-60.0 + 30.0 * s))) / duration, 0.0)
        acc = ops.where(inside, d * (s * (60.0 + s * (-180.0 + 120.0 * s))) / duration**2, 0.0)
        return pos, vel, acc

    return with_spec(f, "min_jerk", start, d, t0, duration)


TRUTH_NAMES = (
    "roll", "pitch", "yaw", "omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z",
    "pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z",
)
"""The truth at one time as `Trajectory.truth_at` returns it (the plant FMU's outputs)."""


@dataclass
class Trajectory:
    """Euler angles (roll phi, pitch theta, yaw psi) [rad] and position [m] as signals of time."""

    roll: Signal = field(default_factory=constant)
    pitch: Signal = field(default_factory=constant)
    yaw: Signal = field(default_factory=constant)
    pos: tuple[Signal, Signal, Signal] = field(
        default_factory=lambda: (constant(), constant(), constant())
    )

    def truth(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """Truth at times t: angles, body rates omega [N,3], specific force f [N,3], pos, vel."""
        t = np.asarray(t, dtype=float)
        x, acc = self._evaluate(t, VECTOR)
        acc_world = np.stack(acc, axis=-1)

        def vector(i: int) -> np.ndarray:
            return np.stack(x[i:i + 3], axis=-1)

        return {
            "t": t, "roll": x[0], "pitch": x[1], "yaw": x[2], "omega": vector(3), "f": vector(6),
            "pos": vector(9), "vel": vector(12), "acc": acc_world - np.array([0.0, 0.0, G]),
        }

    def truth_at(self, t: float) -> tuple[float, ...]:
        """Truth at one time t, in plain floats, named by TRUTH_NAMES: the same values as
        truth() at that time, without numpy (the plant FMU calls it once per step)."""
        return self._evaluate(float(t), SCALAR)[0]

    def _evaluate(self, t: Any, ops: Ops) -> tuple[tuple[Any, ...], tuple[Any, Any, Any]]:
        """The truth's components in the order of TRUTH_NAMES, and a + g e_z (world frame)."""
        sin, cos = ops.sin, ops.cos
        phi, dphi, _ = self.roll(t, ops)
        theta, dtheta, _ = self.pitch(t, ops)
        psi, dpsi, _ = self.yaw(t, ops)
        sphi, cphi = sin(phi), cos(phi)
        sth, cth = sin(theta), cos(theta)
        spsi, cpsi = sin(psi), cos(psi)
        omega = (
            dphi - dpsi * sth,
            dtheta * cphi + dpsi * sphi * cth,
            dpsi * cphi * cth - dtheta * sphi,
        )
        pos_x, pos_y, pos_z = self.pos
        px, py, pz = pos_x(t, ops), pos_y(t, ops), pos_z(t, ops)
        ax, ay, az = px[2], py[2], pz[2] + G  # a + g e_z
        # R = Rz Ry Rx; f = R^T (a + g e_z), written out row by row of R^T.
        r00, r01, r02 = cpsi * cth, spsi * cth, -sth
        r10 = cpsi * sth * sphi - spsi * cphi
        r11 = spsi * sth * sphi + cpsi * cphi
        r12 = cth * sphi
        r20 = cpsi * sth * cphi + spsi * sphi
        r21 = spsi * sth * cphi - cpsi * sphi
        r22 = cth * cphi
        f = (
            r00 * ax + r01 * ay + r02 * az,
            r10 * ax + r11 * ay + r12 * az,
            r20 * ax + r21 * ay + r22 * az,
        )
        return (phi, theta, psi, *omega, *f, px[0], py[0], pz[0], px[1], py[1], pz[1]), (ax, ay, az)


@dataclass(frozen=True)
class ImuNoise:
    """White noise densities and constant biases of an IMU (MPU-6050 datasheet defaults).

    A continuous white noise of density n sampled every dt has standard deviation n / sqrt(dt).
    """

    gyro_density: float = MPU6050_GYRO_DENSITY  # rad/s/sqrt(Hz)
    acc_density: float = MPU6050_ACC_DENSITY  # m/s^2/sqrt(Hz)
    gyro_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)  # rad/s
    acc_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)  # m/s^2


MPU6050 = ImuNoise()


def record(
    trajectory: Trajectory,
    duration: float,
    rate: float = 100.0,
    noise: ImuNoise | None = None,
    seed: int = 0,
) -> dict[str, np.ndarray]:
    """Sample the trajectory at `rate` Hz for `duration` s (samples at t = 0, 1/rate, ...).

    Returns the truth (see Trajectory.truth) plus the IMU samples `acc_meas`, `gyro_meas` [N,3]
    and `dt` [N] (dt[0] is one period; the estimators ignore the first sample's dt).
    """
    n = round(duration * rate) + 1
    t = np.arange(n) / rate
    out = trajectory.truth(t)
    acc, gyro = out["f"].copy(), out["omega"].copy()
    if noise is not None:
        rng = np.random.default_rng(seed)
        s = math.sqrt(rate)
        gyro += np.asarray(noise.gyro_bias) + noise.gyro_density * s * rng.standard_normal((n, 3))
        acc += np.asarray(noise.acc_bias) + noise.acc_density * s * rng.standard_normal((n, 3))
    out["acc_meas"] = acc
    out["gyro_meas"] = gyro
    out["dt"] = np.full(n, 1.0 / rate)
    return out


def product(u: Signal, v: Signal) -> Signal:
    """u v, with its derivatives by the product rule."""
    def f(t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]:
        a, da, dda = u(t, ops)
        b, db, ddb = v(t, ops)
        return a * b, da * b + a * db, dda * b + 2 * da * db + a * ddb

    return with_spec(f, "product", spec_of(u), spec_of(v))


def after_rest(trajectory: Trajectory, rest: float, fade: float = 2.0) -> Trajectory:
    """The trajectory still and level for rest seconds, then faded in over fade seconds (every
    signal times a minimum-jerk ramp from 0 to 1): a recording that starts at rest, as most do,
    with a motion that sets in gradually."""
    ramp = min_jerk(0.0, 1.0, rest, fade)
    return Trajectory(roll=product(trajectory.roll, ramp), pitch=product(trajectory.pitch, ramp),
                      yaw=product(trajectory.yaw, ramp),
                      pos=(product(trajectory.pos[0], ramp), product(trajectory.pos[1], ramp),
                           product(trajectory.pos[2], ramp)))


def two_axis_motion() -> Trajectory:
    """Simultaneous roll and pitch (roll 0.5 rad at 0.5 Hz, pitch 0.35 rad at 0.35 Hz)."""
    return Trajectory(roll=sine(0.5, 0.5), pitch=sine(0.35, 0.35))


def demo_motion() -> Trajectory:
    """A 'moderate dynamics' style recording: two-axis tilt plus a little linear acceleration."""
    return Trajectory(
        roll=add(sine(0.35, 0.2), sine(0.1, 0.9, 0.4)),
        pitch=add(sine(0.3, 0.15, 1.0), sine(0.08, 0.7)),
        yaw=sine(0.5, 0.05),
        pos=(sine(0.05, 0.8), sine(0.04, 0.6, 1.3), sine(0.02, 1.0)),
    )
