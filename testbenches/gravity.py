"""Whether a recording's accelerometer holds gravity, from the recording itself.

An accelerometer measures specific force: gravity plus the body's linear acceleration. Gravity
is constant in a frame that does not turn with the body; the linear acceleration of a body that
moves about a place averages, over a window, to its change of velocity over the window's
length, which for a hand, a vehicle or a pendulum is small against g over seconds. So the
accelerometer's samples turned by the gyro into the frame of a window's start and averaged keep
a vector of about 1 g where gravity is in them, and next to none where it is not: a phone's
linear or user acceleration (Android's TYPE_LINEAR_ACCELERATION, iOS's userAcceleration,
phyphox's "Linear Acceleration", Sensor Logger's "Accelerometer" file), from which the phone's
own fusion took gravity out. Those files read at a norm that may pass for g
(a hand's motion in m/s2 taken as g), and the filters would then run on no gravity at all.

It is taken in the units chosen for the recording, so it also refuses an accelerometer or gyro
unit, or axes, that are not what they are taken for. A gyro bias turns the averaged samples by
bias x WINDOW_S at most; a gyro's scale error by a fraction of each turn.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fusion_core import G

WINDOW_S = 3.0
"""The averaging window [s]: long enough that a hand's, a pendulum's or a shaker's linear
acceleration averages to a small part of g, short enough that an uncalibrated gyro's bias (a
MEMS part's 20 deg/s at three sigma) turns gravity by little over it (VQF's accelerometer
low-pass is as long)."""
HELD_RANGE = (0.6, 1.5)
"""Where the accelerometer holds gravity, the averaged samples keep about 1 g, less what a gyro's
scale errors and bias turn them by over a window and what linear acceleration adds (BROAD's
trials and the battery's motions and parts, raw MPU-6050 biases and clipping gyros included,
are within 0.1 g of it: tests/test_gravity.py). A linear acceleration alone keeps what a body
holds for seconds: a vehicle's tenths of a g, a hand's hundredths. Outside this range, in g,
the accelerometer is taken to hold no gravity."""
CHECK_RATE_HZ = 200.0
"""Faster recordings are averaged in blocks down to about this rate first: the turn within a
block is small, and the check costs a step per block."""
MAX_WINDOWS = 32
"""At most this many windows, spread over the samples given, are averaged."""


@dataclass(frozen=True)
class HeldGravity:
    """What the accelerometer keeps, turned and averaged over windows: the median [g] and the
    number of windows."""

    g: float
    windows: int

    @property
    def held(self) -> bool:
        """Whether that is gravity (HELD_RANGE)."""
        return HELD_RANGE[0] <= self.g <= HELD_RANGE[1]


def held_gravity(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> HeldGravity | None:
    """The median over windows of WINDOW_S of |mean of the samples turned into the window's
    starting frame| in g (module docstring): about 1 where the accelerometer holds gravity,
    near 0 where it holds only linear acceleration. acc [n, 3] in m/s^2, gyro [n, 3] in rad/s,
    dt [n] in s; samples without a number in every column are left out. None where no window
    has enough valid samples to tell."""
    ok = np.all(np.isfinite(acc), 1) & np.all(np.isfinite(gyro), 1) & np.isfinite(dt) & (dt > 0)
    if ok.sum() < 2:
        return None
    period = float(np.median(dt[ok]))
    block = max(1, round(1.0 / (period * CHECK_RATE_HZ)))
    steps = max(2, round(WINDOW_S / (period * block)))  # blocks per window
    n = len(dt)
    if n < steps * block:  # shorter than a window: the whole as one
        steps = n // block
        if steps < 2:
            return None
    span = steps * block
    starts = np.linspace(0, n - span, min(n // span, MAX_WINDOWS)).astype(int)
    idx = starts[:, None] + np.arange(span)[None, :]  # only the windows' samples are read
    w = len(starts)
    good = ok[idx].reshape(w, steps, block)
    count = good.sum(2)

    def mean(x: np.ndarray) -> np.ndarray:  # block means over the valid samples
        x = np.where(good[..., None], x[idx].reshape(w, steps, block, 3), 0.0).sum(2)
        return x / np.maximum(count, 1)[..., None]

    a, rate = mean(acc), mean(gyro)
    step = np.where(good, dt[idx].reshape(w, steps, block), 0.0).sum(2)
    valid = count > 0
    turned = _turned_sum(a, rate * step[..., None], valid)
    enough = valid.sum(1) >= max(2, steps // 2)
    if not enough.any():
        return None
    kept = np.linalg.norm(turned[enough], axis=1) / valid.sum(1)[enough]
    return HeldGravity(float(np.median(kept)) / G, int(enough.sum()))


def _turned_sum(a: np.ndarray, phi: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """The sum over each window's steps of a [w, k, 3] turned into the window's first frame,
    phi [w, k, 3] each step's rotation vector (the body's turn over it): R_0 = I, the sample
    of step j is R_j a_j, R_{j+1} = R_j exp([phi_j]x) (Rodrigues: scipy's Rotation would import
    scipy.spatial, half a second of every command that opens a recording)."""
    w, k, _ = a.shape
    rot = np.broadcast_to(np.eye(3), (w, 3, 3)).copy()
    total = np.zeros((w, 3))
    angle = np.linalg.norm(phi, axis=2)
    axis = phi / np.where(angle > 1e-12, angle, 1.0)[..., None]
    sin, one_cos = np.sin(angle), 1.0 - np.cos(angle)
    skew = np.zeros((w, k, 3, 3))
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    skew[..., 0, 1], skew[..., 0, 2], skew[..., 1, 2] = -z, y, -x
    skew[..., 1, 0], skew[..., 2, 0], skew[..., 2, 1] = z, -y, x
    inc = np.eye(3) + sin[..., None, None] * skew + one_cos[..., None, None] * (skew @ skew)
    turned = np.where(valid[..., None], a, 0.0)[..., None]
    for j in range(k):
        total += (rot @ turned[:, j])[..., 0]
        rot = rot @ inc[:, j]
    return total
