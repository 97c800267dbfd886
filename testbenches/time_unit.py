"""The unit of a time or dt column whose file does not state it: the unit in which its steps are
a rate an IMU is sampled at, and where two units give such rates, the one in which the gyro's
turn explains the accelerometer's (testbenches.gyro_unit).

Loggers write their time stamps in seconds, in milliseconds (a microcontroller's millis()), in
microseconds (micros()) or in nanoseconds (Android's and ROS's event times), mostly without
saying which. Taken in the wrong unit every step is a thousand times (or a million) too long or
too short: the estimators then reject every sample (a dt beyond max_dt) or integrate the gyro's
turn a thousand times too small, and neither says why. The units are a thousand times apart
and the rates IMUs are logged at span about as much, so the median step alone leaves one unit
for most files: a step of 10 is 100 Hz in ms (0.1 Hz in s, 100 kHz in us). Where it leaves two
(a step of 0.05: 20 Hz in s or 20 kHz in ms) the data decide as they decide the gyro's unit: in
the right time unit one gyro unit explains how the accelerometer sees gravity turn, while a
time unit a thousand times off makes the integrated turn a thousand times off, which no gyro
unit explains (but mdps, a thousand times smaller than deg/s, in a time unit a thousand times
too long: such a file fits both, and is refused). A recording without turns cannot tell, and is
refused with the candidates.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .gyro_unit import MIN_WINDOWS, UnitEvidence, verdict, window_misses
from .table import TIME_SCALE

RATE_RANGE = (2.0, 50_000.0)
"""The sample rates [Hz] an IMU recording may have, [low, high): from two samples a second,
twice the slowest the estimators accept (max_dt, 1 s), to 50 kHz, beyond the fastest output
rate of MEMS IMUs (32 kHz). A step then leaves two units only where it is below 50 Hz in the
longer one (and so above 2 kHz in the shorter): a file at 50 Hz or more reads as one unit."""


DAY_S = 86_400.0
"""Seconds in a day: the unit of a spreadsheet's dates and times saved as numbers, and the
step by which a time of day starts again at midnight."""


@dataclass(frozen=True)
class TimeUnit:
    """The unit chosen for a time or dt column, its factor to seconds and how it was chosen."""

    unit: str
    scale: float
    how: str


def median_step(t: np.ndarray) -> float:
    """The median of a time column's rising steps (numbers as read; NaN where none rises): a
    wrap or a glitch back leaves it as it is."""
    steps = np.diff(t[np.isfinite(t)])
    rising = steps[steps > 0.0]
    return float(np.median(rising)) if len(rising) else float("nan")


def rate_in(step: float, unit: str) -> float:
    """The sample rate [Hz] a median step of `step` (numbers as read) is in `unit`."""
    return 1.0 / (step * TIME_SCALE[unit])


def candidates(step: float) -> list[str]:
    """The units in which a median step of `step` (as read) is a rate within RATE_RANGE."""
    low, high = RATE_RANGE
    if not (np.isfinite(step) and step > 0.0):
        return []
    return [u for u in TIME_SCALE if low <= rate_in(step, u) < high]


def rates(step: float, units: list[str]) -> str:
    """"100 Hz in ms or 1e+05 Hz in us"."""
    return listed([f"{rate_in(step, u):.4g} Hz in {u}" for u in units])


def listed(items: list[str]) -> str:
    """"a, b or c" (the units a message offers)."""
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} or {items[-1]}"


def _why_not(e: UnitEvidence) -> str:
    """Why a candidate time unit's data point to no gyro unit."""
    if e.windows < MIN_WINDOWS:
        return f"{e.windows} windows turn gravity, {MIN_WINDOWS} are needed"
    misses = ", ".join(f"{u}: {m:.3g} deg" for u, m in e.miss_deg.items())
    return f"no gyro unit explains gravity's turn (median miss {misses})"


def time_unit(column: str, step: float, dt_of: Callable[[float], np.ndarray], acc: np.ndarray,
              gyro: np.ndarray) -> TimeUnit | str:
    """The unit of a time or dt `column` that states none, from its median step `step` (numbers
    as read) and, where two units give IMU rates, from the data: `dt_of(scale)` gives each
    sample's dt [s] in a unit of that factor, acc and gyro [N, 3] the samples as read. A str
    says why no unit can be chosen and what would serve."""
    found = candidates(step)
    if not found:
        days = 1.0 / (step * DAY_S) if np.isfinite(step) and step > 0.0 else float("nan")
        spreadsheet = (f"; in days it is {days:.4g} Hz: a spreadsheet's dates and times saved "
                       "as numbers (days since 1899-12-30)? Format the column as a date and time "
                       "(yyyy-mm-dd hh:mm:ss.000) before saving it" if
                       RATE_RANGE[0] <= days < RATE_RANGE[1] else "")
        return (f"the {column} column states no unit, and its median step {step:.4g} is a rate "
                f"no IMU has in any of s, ms, us, ns ({rates(step, list(TIME_SCALE))}): give "
                f"--time-unit, or --rate HZ{spreadsheet}")
    if len(found) == 1:
        u = found[0]
        return TimeUnit(u, TIME_SCALE[u], f"from its steps: a median step of {step:.4g} is "
                        f"{rate_in(step, u):.4g} Hz in {u}, and no IMU's rate in "
                        + listed([v for v in TIME_SCALE if v != u]))
    evidence: dict[str, UnitEvidence] = {}
    for u in found:
        evidence[u] = verdict(window_misses(acc, gyro, dt_of(TIME_SCALE[u])))
    decided = [u for u in found if evidence[u].unit is not None]
    if len(decided) == 1:
        u = decided[0]
        others = "; ".join(f"in {v} ({rate_in(step, v):.4g} Hz) {_why_not(evidence[v])}"
                           for v in found if v != u)
        return TimeUnit(u, TIME_SCALE[u], f"from the data: a median step of {step:.4g} is "
                        f"{rate_in(step, u):.4g} Hz in {u}, where the gyro's turn explains "
                        f"gravity's; {others}")
    why = "; ".join(f"in {u}, {_why_not(evidence[u])}" for u in found) if not decided else (
        "the gyro's turn explains gravity's " + " and ".join(
            f"in {u} (the gyro in {evidence[u].unit})" for u in decided))
    return (f"the {column} column states no unit, and its median step {step:.4g} is "
            f"{rates(step, found)}; {why}: give --time-unit " + listed(found))
