"""Synthetic IMU recordings with exact truth, for tests, the demo table and the plant model.

A trajectory is given by its Euler angles and position as analytic functions of time (value,
first and second derivative). The IMU samples follow from the kinematics, not from finite
differences:
  body rates (inverse Z-Y-X Euler-rate kinematics)
    p = phi_dot - psi_dot sin(theta)
    q = theta_dot cos(phi) + psi_dot sin(phi) cos(theta)
    r = psi_dot cos(phi) cos(theta) - theta_dot sin(phi)
  specific force  f = R^T (a + g e_z), R = Rz(psi) Ry(theta) Rx(phi) (body to world, z up).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .types import DEG, G

Signal = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
"""t -> (value, first derivative, second derivative)."""


def constant(value: float = 0.0) -> Signal:
    def f(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = np.zeros_like(t)
        return z + value, z, z

    return f


def sine(amplitude: float, freq: float, phase: float = 0.0, offset: float = 0.0) -> Signal:
    """offset + amplitude sin(2 pi freq t + phase)."""
    w = 2.0 * math.pi * freq

    def f(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s, c = np.sin(w * t + phase), np.cos(w * t + phase)
        return offset + amplitude * s, amplitude * w * c, -amplitude * w * w * s

    return f


def add(*signals: Signal) -> Signal:
    def f(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        parts = [s(t) for s in signals]
        return tuple(sum(p[i] for p in parts) for i in range(3))  # type: ignore[return-value]

    return f


def min_jerk(start: float, end: float, t0: float, duration: float) -> Signal:
    """Minimum-jerk move from start to end over [t0, t0 + duration], at rest before and after."""
    d = end - start

    def f(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = np.clip((t - t0) / duration, 0.0, 1.0)
        inside = (t > t0) & (t < t0 + duration)
        pos = start + d * (10 * s**3 - 15 * s**4 + 6 * s**5)
        vel = np.where(inside, d * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration, 0.0)
        acc = np.where(inside, d * (60 * s - 180 * s**2 + 120 * s**3) / duration**2, 0.0)
        return pos, vel, acc

    return f


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
        phi, dphi, _ = self.roll(t)
        theta, dtheta, _ = self.pitch(t)
        psi, dpsi, _ = self.yaw(t)
        sphi, cphi = np.sin(phi), np.cos(phi)
        sth, cth = np.sin(theta), np.cos(theta)
        spsi, cpsi = np.sin(psi), np.cos(psi)
        omega = np.stack(
            [
                dphi - dpsi * sth,
                dtheta * cphi + dpsi * sphi * cth,
                dpsi * cphi * cth - dtheta * sphi,
            ],
            axis=-1,
        )
        px, py, pz = (s(t) for s in self.pos)
        pos = np.stack([px[0], py[0], pz[0]], axis=-1)
        vel = np.stack([px[1], py[1], pz[1]], axis=-1)
        acc_world = np.stack([px[2], py[2], pz[2] + G], axis=-1)  # a + g e_z
        # R = Rz Ry Rx; f = R^T (a + g e_z), written out row by row of R^T.
        r00, r01, r02 = cpsi * cth, spsi * cth, -sth
        r10 = cpsi * sth * sphi - spsi * cphi
        r11 = spsi * sth * sphi + cpsi * cphi
        r12 = cth * sphi
        r20 = cpsi * sth * cphi + spsi * sphi
        r21 = spsi * sth * cphi - cpsi * sphi
        r22 = cth * cphi
        ax, ay, az = acc_world[..., 0], acc_world[..., 1], acc_world[..., 2]
        f = np.stack(
            [r00 * ax + r01 * ay + r02 * az, r10 * ax + r11 * ay + r12 * az,
             r20 * ax + r21 * ay + r22 * az],
            axis=-1,
        )
        return {
            "t": t, "roll": phi, "pitch": theta, "yaw": psi, "omega": omega, "f": f,
            "pos": pos, "vel": vel, "acc": acc_world - np.array([0.0, 0.0, G]),
        }


@dataclass(frozen=True)
class ImuNoise:
    """White noise densities and constant biases of an IMU (MPU-6050 datasheet defaults).

    A continuous white noise of density n sampled every dt has standard deviation n / sqrt(dt).
    """

    gyro_density: float = 0.005 * DEG  # rad/s/sqrt(Hz)
    acc_density: float = 400e-6 * G  # m/s^2/sqrt(Hz)
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
