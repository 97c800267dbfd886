"""Whether a reference describes the recording's sensor in the estimators' axes: two laws of
motion that hold in any motion, checked on a recording's first block before it is scored.

1. **The vertical specific force averages gravity.** A body that ends near the height and the
   vertical speed it started with has had, on average, no vertical acceleration, so the
   accelerometer's specific force along the true up direction averages g (to within the
   vertical speed gained over the block, over its length: a hand's 1 m/s over 10 s is 1 %),
   whatever the motion: a pendulum's, a runner's, a shaker's. Along another direction it
   averages g times the cosine of the angle between them, or less: a reference whose up is off
   by tens of degrees (another sensor's axes, a frame turned by 90 deg) shows at once.
2. **The up direction turns as the gyro says.** In the sensor's frame a world-fixed direction
   turns by the opposite of the body's rotation (du/dt = -omega x u, testbenches.gyro_unit).
   Over windows of a quarter second in which the reference's up turns, the gyro predicts where
   it ends; in the sensor's axes the prediction misses by the gyro's errors over the window
   (its bias, scale error, a clipped rate), in another convention (a sign of its own, roll
   and pitch swapped) by about the turn itself.

The accelerometer at rest is no such test: a pendulum's or a shaker's never rests, and its
direction where its norm is near g misses a true reference by tens of degrees. Where a law does
not hold, the reference is refused with the evidence, and with what would serve where the
evidence finds it: a sign turned, roll and pitch swapped, or a mounting (the rotation that best
turns the accelerometer's specific force onto the reference's up, --mounting).
tests/test_reference_axes.py holds every motion and sensor class of the synthetic battery's
true references within both laws' bounds, and those in other axes outside one of them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

VERTICAL_TOLERANCE = 1.0 - math.cos(math.radians(20.0))
"""How far the mean specific force along a reference's up may be from g, as a share of g
(law 1): that of an up direction 20 deg off. A true reference's mean parts from g by the
vertical speed gained over the block, the accelerometer's scale error (a few percent), a
clipped accelerometer and absurd samples; a frame turned by tens of degrees parts it by the
cosine of the turn."""
TURN_MISS_MAX = 0.75
"""The most the gyro's prediction may miss a reference's up by, as a share of the up's own
turn (median over the windows, law 2). A true reference's miss is the gyro's error over a
window (an uncalibrated part's bias of degrees per second, a scale error, a clipped rate): a
fraction of the turn; another convention's is about the turn itself, or more."""
MIN_WINDOWS = 10
"""Fewer windows in which the reference's up turns than this: law 2 says nothing."""

Conventions = dict[str, Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]]
CONVENTIONS: Conventions = {
    "the pitch's sign turned": lambda r, p: (r, -p),
    "the roll's sign turned": lambda r, p: (-r, p),
    "both signs turned": lambda r, p: (-r, -p),
    "roll and pitch swapped": lambda r, p: (p, r),
}
"""Roll and pitch as other conventions write them, tried where a reference fails: what the
refusal names where one of them meets both laws."""


def vertical_share(acc: np.ndarray, up: np.ndarray) -> float:
    """The mean specific force along `up` [N, 3] (unit vectors in the sensor frame), over g, of
    the samples `acc` [N, 3] [m/s^2] where both are numbers (law 1); NaN where none is."""
    from fusion_core.types import G

    along = np.sum(acc * up, axis=1)
    along = along[np.isfinite(along)]
    return float(np.mean(along)) / G if len(along) else float("nan")


def turn_miss(up: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> tuple[int, float]:
    """The windows in which `up` [N, 3] turns (gyro_unit.window_misses', of WINDOW_S) and the
    gyro's miss of its turn over them as a share of the turn itself (medians; law 2), for
    `gyro` [N, 3] in rad/s and `dt` [N] [s]; (windows, NaN) under MIN_WINDOWS."""
    from .gyro_unit import window_misses

    finite = np.all(np.isfinite(up), axis=1)
    misses = window_misses(up[finite], gyro[finite], dt[finite],
                           {"gyro": np.eye(3), "none": np.zeros((3, 3))})  # none: the turn
    windows = len(misses["gyro"])
    if windows < MIN_WINDOWS:
        return windows, float("nan")
    return windows, float(np.median(misses["gyro"]) / np.median(misses["none"]))


def _fails(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray, up: np.ndarray
           ) -> tuple[bool, float, int, float]:
    """Whether the up direction breaks either law, with the evidence: the vertical share,
    the windows and the turn's miss."""
    share = vertical_share(acc, up)
    windows, miss = turn_miss(up, gyro, dt)
    bad = abs(share - 1.0) > VERTICAL_TOLERANCE or (windows >= MIN_WINDOWS
                                                   and miss > TURN_MISS_MAX)
    return bad, share, windows, miss


def mounting_fit(acc: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The rotation M [3, 3] that turns the specific force onto the up direction best (the
    largest mean of up . M acc, law 1's statistic: Kabsch's solution of Wahba's problem)."""
    finite = np.all(np.isfinite(acc), axis=1) & np.all(np.isfinite(up), axis=1)
    u, _, vt = np.linalg.svd(up[finite].T @ acc[finite])
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    return u @ np.diag([1.0, 1.0, d]) @ vt


def mounting_angles(m: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch and yaw [deg] of a rotation as --mounting takes them (Rz(yaw) Ry(pitch)
    Rx(roll), fusion_core.base.mounting_matrix)."""
    return (math.degrees(math.atan2(m[2, 1], m[2, 2])),
            math.degrees(math.asin(max(-1.0, min(1.0, -m[2, 0])))),
            math.degrees(math.atan2(m[1, 0], m[0, 0])))


def _in_degrees(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                angles: tuple[np.ndarray, np.ndarray], share: float) -> bool:
    """Whether roll and pitch `angles` [rad], numbers in degrees read as radians (as numbers
    within pi and pi/2 are where no header states a unit), meet both laws in degrees: read so
    they tilt the up direction off the specific force (law 1 fails, `share`), and in degrees
    they meet both laws, turning where the accelerometer's direction turns. Read in degrees a
    reference is all but level, so that it meets law 1 wherever the sensor is near level, and
    law 2 says nothing of an up direction that barely turns: a reference of another
    convention would meet both, but not turn where the sensor does."""
    from .broad.metric import gravity_from_roll_pitch

    if abs(share - 1.0) <= VERTICAL_TOLERANCE:
        return False
    up = gravity_from_roll_pitch(*np.radians(angles))
    if _fails(acc, gyro, dt, up)[0]:
        return False
    turning = turn_miss(acc, gyro, dt)[0]  # the windows in which the specific force turns
    return turning < MIN_WINDOWS or turn_miss(up, gyro, dt)[0] >= MIN_WINDOWS


def check_axes(path: Path, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray, up: np.ndarray,
               conventions: bool = False, lag: str = "",
               raw: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """RecordingError where the reference's up direction `up` [N, 3] (sensor frame, at the
    samples' times; NaN where it has none) breaks either law on a first block's samples as the
    estimators take them (acc [m/s^2], gyro [rad/s], dt [s]), naming what would serve:
    with `conventions` (a roll and pitch reference) the convention of its angles that meets
    both laws; with `raw` (the samples before a mounting given) the mounting that does;
    `lag` (a clock offset found) as the likelier cause."""
    from .broad.metric import gravity_from_roll_pitch
    from .fit.recording import RecordingError
    from .gyro_unit import WINDOW_S
    from .peer_runs import roll_pitch_from_up

    bad, share, windows, miss = _fails(acc, gyro, dt, up)
    if not bad:
        return
    evidence = [f"along its up direction the accelerometer measures {share:.2f} g on average "
                "(a body's motion averages 1 g)"] if abs(share - 1.0) > VERTICAL_TOLERANCE \
        else []
    if windows >= MIN_WINDOWS and miss > TURN_MISS_MAX:
        evidence.append(f"the gyro's turn misses its up direction's turn by {miss:.0%} of it "
                        f"(median over {windows} windows of {WINDOW_S:g} s)")
    serves = [lag.removeprefix("reference: ")] if lag else []
    if conventions:  # the angles the up direction is of
        angles = roll_pitch_from_up(up)
        serves += [f"they agree with {name} (a convention other than roll about x, then pitch "
                   "about y)" for name, convention in CONVENTIONS.items()
                   if not _fails(acc, gyro, dt, gravity_from_roll_pitch(*convention(*angles)))[0]]
        if _in_degrees(acc, gyro, dt, angles, share):
            serves.append("they agree with roll and pitch in degrees: state the unit in the "
                          "header (roll (deg), pitch (deg)); numbers within pi and pi/2 are "
                          "taken as radians")
    acc0, gyro0 = raw if raw is not None else (acc, gyro)
    m = mounting_fit(acc0, up)
    if not _fails(acc0 @ m.T, gyro0 @ m.T, dt, up)[0]:
        said = ",".join(f"{180.0 if round(a, 1) == -180.0 else round(a, 1) + 0.0:g}"
                        for a in mounting_angles(m))
        serves.append(f"they agree with --mounting {said} (the sensor so turned in the "
                      "reference's axes)")
    raise RecordingError(
        f"{path}: the reference does not describe this sensor in its axes: "
        + "; ".join(evidence)
        + (": " + "; or ".join(serves) if serves else
           ": is it this sensor's reference, its up direction in the sensor's frame (x, y, z "
           "as the recording's columns; roll about x, then pitch about y)?"))
