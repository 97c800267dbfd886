"""The gyro's unit found from the recording itself: the unit in which the gyro's integrated turn
explains how the accelerometer sees gravity turn.

A sensor that turns sees gravity turn the other way in its own frame: du/dt = -omega x u for the
unit vector u of gravity in the sensor's frame. So over a short window the accelerometer's
direction at its end is predicted from its direction at the start and the gyro's readings taken
in a unit: in the right unit the prediction meets the measured direction to within the noise and
the linear acceleration; in a unit 57.3 (rad/s against deg/s) or 1000 times off (deg/s against
mdps, as ST's sensors give it) it misses by the turn itself. A rate about the vertical turns
nothing gravity shows, in any unit, and is neither evidence for nor against.

Only windows in which the accelerometer sees gravity turn count: there a wrong unit misses by
about the turn itself (a turn many times too small) or by many times it (too large), while the
right one misses by the noise, the linear acceleration and the gyro's bias over the window. A
window at rest is no evidence: a gyro bias, which turns nothing, would there favour whichever
unit makes the readings smallest. So a recording without turns (a still one) is undecided, and
the caller asks for the unit.

The same prediction tells the gyro's axes from the accelerometer's (gyro_axes): with a sign
flipped or two axes swapped between them, every unit misses by about the turn; the signed order
of the gyro's axes that meets the accelerometer names what differs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

UNITS = {"rad/s": 1.0, "deg/s": np.pi / 180.0, "mdps": np.pi / 180.0e3}
"""The candidate units and their factor to rad/s."""
PRIMARY = ("rad/s", "deg/s")
MILLI = "mdps"
"""The units verdict weighs first, and the one it weighs where neither of those explains the
turn."""
WINDOW_S = 0.25
"""Window over which the gyro's turn is compared with gravity's [s]: long enough that a turn of
a few deg/s moves gravity by more than the accelerometer's noise after the low-pass, short
enough that linear acceleration changes little within it."""
LOWPASS_S = 0.05
"""Moving-average length on the accelerometer before its direction is taken [s]."""
QUIET_G = 0.15
"""Only windows whose two ends read a norm within this fraction of gravity's count: a sample
under strong linear acceleration does not point along gravity."""
MIN_TURN_DEG = 3.0
"""A window counts where the accelerometer sees gravity turn by at least this much [deg]: well
above its noise after the low-pass (about 0.1 deg) and above what a MEMS gyro's bias (a few
deg/s before calibration) adds to the right unit's miss over a window."""
MIN_WINDOWS = 10
"""Fewer counting windows than this: undecided."""
MAX_WINDOWS = 20000
"""At most this many counting windows of a block are compared, spread evenly over it: the
windows start at every sample and overlap, and a median over this many is as sure as over all
of a long recording's (the comparison is most of the time a long file takes to open)."""
MIN_RATIO = 3.0
"""Every other unit's miss must be at least this many times the chosen one's."""


@dataclass(frozen=True)
class UnitEvidence:
    """What the data say: each unit's median miss [deg] over the windows that count, how many
    windows counted, and the unit they point to (None: undecided)."""

    miss_deg: dict[str, float]
    windows: int
    unit: str | None

    def describe(self) -> str:
        misses = ", ".join(f"{u}: {m:.3g} deg" for u, m in self.miss_deg.items())
        return (f"over {self.windows} windows of {WINDOW_S} s, gravity's turn is missed by "
                f"{misses} (median)")

    def undecided(self) -> str:
        """Why the data tell no unit: too few windows turn gravity (a recording at rest), or
        the windows that turn it do not point to one unit (a gyro at its rail for much of
        them, columns that are not the gyro's, linear acceleration in most windows)."""
        if self.windows < MIN_WINDOWS:
            return (f"{self.windows} windows of {WINDOW_S} s turn gravity by {MIN_TURN_DEG:g} "
                    f"deg or more, {MIN_WINDOWS} are needed: too little motion")
        return (f"{self.describe()}: the two smallest within {MIN_RATIO:g} times of each "
                "other, so no unit explains the turn, as where the gyro sits at its rail, the "
                "columns are not the gyro's (raw counts of its converter) or linear "
                "acceleration fills the windows")


def moving_average(x: np.ndarray, n: int) -> np.ndarray:
    """The mean of each row and the n - 1 before it (the first rows: the first full mean); n
    at most the rows there are."""
    n = min(n, len(x))
    if n <= 1:
        return x
    c = np.zeros((len(x) + 1, x.shape[1]))
    np.cumsum(x, axis=0, out=c[1:])
    out = np.empty_like(x)
    np.divide(c[n:] - c[:-n], n, out=out[n - 1:])
    out[:n - 1] = out[n - 1]
    return out


def median_period(dt: np.ndarray) -> float:
    """The median of the periods that are numbers (np.nanmedian's, at a tenth of its time on a
    long block); NaN where none is."""
    numbers = dt[~np.isnan(dt)]
    return float(np.median(numbers)) if len(numbers) else float("nan")


def window_misses(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                  readings: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """Each unit's miss [deg] in every window that counts, for `gyro` [N, 3] (numbers as read),
    `acc` [N, 3] (any unit: only its direction and its norm relative to the median are used)
    and `dt` [N] [s] (rows with a non-finite value are left out: they hold no sample, and the
    next sample's dt spans them); the windows of a recording's blocks are pooled before the
    verdict. `readings`, by name, takes the gyro's rate in rad/s as a matrix times the numbers
    as read in place of the units (gyro_axes: each signed order of its axes)."""
    acc, gyro, dt = (np.asarray(a, dtype=float) for a in (acc, gyro, dt))
    if readings is None:
        readings = {unit: scale * np.eye(3) for unit, scale in UNITS.items()}
    none = {name: np.empty(0) for name in readings}
    finite = np.all(np.isfinite(acc), 1) & np.all(np.isfinite(gyro), 1) & np.isfinite(dt)
    if not finite.all():  # no sample: the dt of the next one spans it (fit.recording._Clock)
        acc, gyro, dt = acc[finite], gyro[finite], dt[finite]
    n = len(dt)
    period = median_period(dt) if n else 0.0
    if not (n > 2 and period > 0.0):
        return none
    k = max(1, round(WINDOW_S / period))
    smooth = moving_average(acc, max(1, round(LOWPASS_S / period)))
    norm = np.linalg.norm(smooth, axis=1)
    g = float(np.median(norm))
    if not g > 0.0 or n <= k:
        return none
    u = smooth / np.where(norm > 0.0, norm, 1.0)[:, None]
    quiet = np.abs(norm / g - 1.0) < QUIET_G
    m = n - k  # the windows start at samples 0 .. m-1 and end k samples later
    usable = np.flatnonzero(quiet[:m] & quiet[k:n])
    ux, uy, uz = (np.ascontiguousarray(u[:, i]) for i in range(3))
    dot = (ux[usable] * ux[usable + k] + uy[usable] * uy[usable + k]
           + uz[usable] * uz[usable + k])
    seen = np.degrees(np.arccos(np.clip(dot, -1.0, 1.0)))
    starts = usable[seen >= MIN_TURN_DEG]
    if len(starts) > MAX_WINDOWS:  # evenly spread over the recording
        starts = starts[np.linspace(0, len(starts) - 1, MAX_WINDOWS).astype(np.int64)]
    ends = starts + k
    gx, gy, gz = (np.ascontiguousarray(gyro[:, i]) for i in range(3))
    v = {name: (ux[starts], uy[starts], uz[starts]) for name in readings}
    for j in range(1, k + 1):  # du/dt = -omega x u, omega at the sample ending each step
        at = starts + j  # one step of every window at once: memory does not grow with k
        w, h = (gx[at], gy[at], gz[at]), dt[at]
        for name, m in readings.items():
            vx, vy, vz = v[name]
            ax, ay, az = (sum(m[r, c] * w[c] for c in range(3) if m[r, c] != 0.0)
                          for r in range(3))
            vx, vy, vz = (vx - (ay * vz - az * vy) * h, vy - (az * vx - ax * vz) * h,
                          vz - (ax * vy - ay * vx) * h)
            length = np.sqrt(vx * vx + vy * vy + vz * vz)
            v[name] = (vx / length, vy / length, vz / length)
    misses: dict[str, np.ndarray] = {}
    for unit, (vx, vy, vz) in v.items():
        cos_miss = np.clip(vx * ux[ends] + vy * uy[ends] + vz * uz[ends], -1.0, 1.0)
        misses[unit] = np.degrees(np.arccos(cos_miss))
    return misses


def verdict(misses: dict[str, np.ndarray]) -> UnitEvidence:
    """The unit the windows' misses point to, over at least MIN_WINDOWS windows (else
    undecided): of rad/s and deg/s the one whose median miss is at least MIN_RATIO times
    smaller than the other's; where neither is, mdps where its miss is that much smaller than
    both. A unit too small reads as no turn and misses by the turn itself, one too large by
    more: so deg/s is told from rad/s, 57 times larger, as before mdps was a candidate, and mdps
    comes in only where both of those fail (a gyro in mdps turns 1000 times too far in deg/s),
    not where deg/s merely misses by more than a third of the turn."""
    windows = len(next(iter(misses.values())))
    median = {unit: float(np.median(m)) if windows else float("nan")
              for unit, m in misses.items()}
    unit = None
    if windows >= MIN_WINDOWS:
        best, other = sorted(PRIMARY, key=lambda x: median[x])
        if median[other] >= MIN_RATIO * max(median[best], 1e-3):
            unit = best
        elif min(median[u] for u in PRIMARY) >= MIN_RATIO * max(median[MILLI], 1e-3):
            unit = MILLI
    return UnitEvidence(median, windows, unit)


def _signed_orders() -> dict[str, np.ndarray]:
    """Every signed order of three axes, by the way it reads ("x, -y, z": the gyro's own y
    negated), the one as read first."""
    import itertools

    out = {}
    for order in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            m = np.zeros((3, 3))
            for row, (col, sign) in enumerate(zip(order, signs, strict=True)):
                m[row, col] = sign
            out[", ".join(("-" if sign < 0 else "") + "xyz"[col]
                          for col, sign in zip(order, signs, strict=True))] = m
    return out


AS_READ = "x, y, z"


def gyro_axes(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray, scales: dict[str, float]
              ) -> tuple[str, str, float, float] | None:
    """Where the gyro's axes, as read, are not the accelerometer's: the signed order of them
    (gyro_axes' "x, -y, z": its y negated) and the unit in which its turn explains the
    accelerometer's turn of gravity at least MIN_RATIO times better than as read in any unit
    of `scales` (name -> factor to rad/s), with the two median misses [deg]; None where the
    axes as read serve as well, or too few windows turn gravity to tell. A sign flipped or two
    axes swapped (a left-handed frame, axes remapped in the gyro but not the accelerometer)
    leaves every unit missing by about the turn, as a wrong unit does."""
    orders = _signed_orders()
    readings = {f"{unit}|{name}": scale * m for unit, scale in scales.items()
                for name, m in orders.items()}
    misses = window_misses(acc, gyro, dt, readings)
    if len(next(iter(misses.values()))) < MIN_WINDOWS:
        return None
    median = {name: float(np.median(m)) for name, m in misses.items()}
    best = min(median, key=lambda name: median[name])
    as_read = min(median[f"{unit}|{AS_READ}"] for unit in scales)
    unit, order = best.split("|")
    if order == AS_READ or as_read < MIN_RATIO * max(median[best], 1e-3):
        return None
    return order, unit, median[best], as_read
