"""The testbench scenarios: analytic motions with exact truth (plant model of the ImuPlant FMU).

Each scenario has a fixed integer id (the ImuPlant FMU's `scenario` parameter), a name, a default
duration and a Trajectory (fusion_core.synthetic). The ids never change meaning; new scenarios get
new ids.

| id | name              | motion                                                                  |
|----|-------------------|-------------------------------------------------------------------------|
| 0  | static_level      | at rest, level                                                          |
| 1  | static_tilted     | at rest, roll 20 deg, pitch -10 deg                                     |
| 2  | roll_sweep        | roll 45 deg sine at 0.32 Hz (peak rate 1.58 rad/s, T1's 1.6 rad/s)      |
| 3  | pitch_sweep       | pitch 40 deg sine at 0.36 Hz (peak rate 1.58 rad/s)                     |
| 4  | roll_pitch        | roll 30 deg at 0.3 Hz and pitch 20 deg at 0.2 Hz together, slow yaw     |
| 5  | moderate_dynamics | roll/pitch 20-30 deg, rates up to 1.5 rad/s, linear acceleration       |
|    |                   | swelling to 0.25/0.15/0.37 g (x/y/z) every 10 s: rho crosses 0.35      |
| 6  | vibration         | slow tilt plus 61.3/122.6/183.9 Hz vibration of 0.3 g per tone (motor) |
| 7  | high_dynamics     | tilt plus sustained 0.5 g accelerations lasting seconds                 |
| 8  | translation_2m    | 2 m along x, minimum jerk over 3 s, 2 s at rest before and after        |
| 9  | shaking           | a handheld sensor shaken for 90 s: 2.6 g RMS of linear acceleration at |
|    |                   | 2.7-5.2 Hz (peaks near 6 g) while it turns by 20-40 deg                 |
| 10 | gyro_clipping     | fast swings whose rate exceeds +-2000 deg/s for about 8 % of the       |
|    |                   | samples (the realistic sensor's gyro range), over slow tilts            |
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .synthetic import (
    VECTOR,
    Ops,
    Signal,
    Trajectory,
    add,
    constant,
    min_jerk,
    sine,
    with_spec,
)
from .types import DEG, G


def swelling_sine(peak: float, freq: float, env_period: float, phase: float = 0.0) -> Signal:
    """peak * e(t) * sin(2 pi freq t + phase), envelope e = (1 - cos(2 pi t / env_period)) / 2."""
    w = 2.0 * math.pi * freq
    we = 2.0 * math.pi / env_period

    def f(t: Any, ops: Ops = VECTOR) -> tuple[Any, Any, Any]:
        env, arg = we * t, w * t + phase
        ce, se = ops.cos(env), ops.sin(env)
        e, de, dde = 0.5 * (1 - ce), 0.5 * we * se, 0.5 * we**2 * ce
        c, s = ops.cos(arg), ops.sin(arg)
        ds, dds = w * c, -w * w * s
        return peak * e * s, peak * (de * s + e * ds), peak * (dde * s + 2 * de * ds + e * dds)

    return with_spec(f, "swelling_sine", peak, w, we, phase)


def _accel_sine(acc_amplitude: float, freq: float, phase: float = 0.0) -> Signal:
    """A position sine whose acceleration amplitude is acc_amplitude [m/s^2]."""
    return sine(acc_amplitude / (2.0 * math.pi * freq) ** 2, freq, phase)


def _moderate() -> Trajectory:
    # Two-axis tilt of 20-30 deg with rates to ~1.5 rad/s; linear acceleration whose envelope
    # swells from 0 to its peak and back every 10 s: 0.25 g along x, 0.15 g along y and 0.37 g
    # vertically, so rho = ||f|/g - 1| sweeps every band of Duong Quoc's table (0.01, 0.25, 0.35).
    def lin(peak_g: float, freq: float, phase: float) -> Signal:
        return swelling_sine(peak_g * G / (2 * math.pi * freq) ** 2, freq, 10.0, phase)

    return Trajectory(
        roll=add(sine(25 * DEG, 0.35), sine(5 * DEG, 0.13, 0.7)),
        pitch=add(sine(20 * DEG, 0.45, 1.0), sine(8 * DEG, 0.11)),
        yaw=sine(30 * DEG, 0.05),
        pos=(lin(0.25, 0.9, 0.0), lin(0.15, 0.7, 1.1), lin(0.37, 1.1, 0.4)),
    )


def _vibration() -> Trajectory:
    # Motor-like tones (rotor frequency and harmonics), not commensurate with the 100 Hz sample
    # clock: tones at exact multiples of 20 Hz would alias to a pattern repeating every 10
    # samples, which no real motor produces and which any accelerometer gate samples with bias.
    vib = 0.3 * G
    return Trajectory(
        roll=sine(15 * DEG, 0.1),
        pitch=sine(10 * DEG, 0.07, 0.5),
        pos=(
            add(_accel_sine(vib, 61.3), _accel_sine(vib, 183.9, 0.3)),
            _accel_sine(vib, 122.6, 1.2),
            add(_accel_sine(vib, 61.3, 2.0), _accel_sine(vib, 122.6, 0.8)),
        ),
    )


def _high_dynamics() -> Trajectory:
    # Moves of 20 m in 4 s (minimum jerk peak 0.73 g, above 0.5 g for about 1.5 s per move).
    x = add(min_jerk(0.0, 20.0, 2.0, 4.0), min_jerk(0.0, -20.0, 10.0, 4.0))
    y = add(min_jerk(0.0, 12.0, 5.0, 4.0), min_jerk(0.0, -12.0, 13.0, 4.0))
    return Trajectory(
        roll=sine(20 * DEG, 0.2), pitch=sine(15 * DEG, 0.15, 0.3), yaw=sine(20 * DEG, 0.03),
        pos=(x, y, constant()),
    )


def _shaking() -> Trajectory:
    # A hand shaking the sensor (the 2-3 Hz of a wrist, the 4-5 Hz of a tremor), two tones per
    # axis of 1.5 g each: 2.6 g RMS of linear acceleration, 95th percentile 3.8 g, |f| up to
    # 5.6 g, while the sensor turns slowly by 20-40 deg with 5-8 deg of wobble at 3-4 Hz.
    a = 1.5 * G
    return Trajectory(
        roll=add(sine(30 * DEG, 0.23), sine(8 * DEG, 3.1, 0.4)),
        pitch=add(sine(20 * DEG, 0.17, 1.0), sine(6 * DEG, 3.7, 1.1)),
        yaw=add(sine(40 * DEG, 0.05), sine(5 * DEG, 2.9)),
        pos=(
            add(_accel_sine(a, 2.7), _accel_sine(a, 4.1, 0.5)),
            add(_accel_sine(a, 3.3, 1.0), _accel_sine(a, 5.2, 2.0)),
            add(_accel_sine(a, 2.9, 0.3), _accel_sine(a, 4.6, 1.4)),
        ),
    )


def _gyro_clipping() -> Trajectory:
    # Swings of 95 deg at 4 Hz (roll) and 55 deg at 3.4 Hz (pitch) whose envelopes swell every
    # 6 and 9 s: peak rates of 2390 and 1170 deg/s, so the roll rate is beyond +-2000 deg/s for
    # about 8 % of the samples, over slow tilts and a slow sway of the position.
    return Trajectory(
        roll=add(sine(20 * DEG, 0.2), swelling_sine(95 * DEG, 4.0, 6.0)),
        pitch=add(sine(15 * DEG, 0.15, 0.7), swelling_sine(55 * DEG, 3.4, 9.0, 1.0)),
        yaw=sine(30 * DEG, 0.05),
        pos=(sine(0.1, 0.4), sine(0.1, 0.3, 1.0), constant()),
    )


CALIBRATION_POSES_DEG: tuple[tuple[float, float, float], ...] = (
    (0.0, 0.0, 0.0), (90.0, 0.0, 30.0), (180.0, 0.0, -20.0), (270.0, 0.0, 40.0),
    (360.0, -85.0, 0.0), (360.0, 85.0, -30.0), (405.0, 35.0, 20.0), (495.0, -35.0, -40.0),
    (585.0, 35.0, 10.0), (675.0, -35.0, -30.0), (765.0, -35.0, 30.0), (855.0, 35.0, -10.0),
    (945.0, -35.0, 40.0), (1035.0, 35.0, 0.0),
)
"""The calibration session's poses (roll, pitch, yaw in deg, roll unwrapped so that each move
is the short way): each axis up and down (pitch +-85 deg for x), and the eight octants' diagonals
twice; yaw changes with every move, so that the turns are about mixed axes."""
CALIBRATION_HOLD_S = 3.0
CALIBRATION_MOVE_S = 1.6
"""Each pose is held 3 s; each move (90-180 deg) takes 1.6 s, at most 200 deg/s: a hand's pace,
far inside a MEMS gyro's range."""


def _calibration_session() -> Trajectory:
    # A calibration session as Tedaldi et al. (2014) ask for it and a hand makes it: static poses
    # spread over the sphere, minimum-jerk turns between them, no translation.
    signals: list[list[Signal]] = [[constant(a * DEG)] for a in CALIBRATION_POSES_DEG[0]]
    t = CALIBRATION_HOLD_S
    for before, after in itertools.pairwise(CALIBRATION_POSES_DEG):
        for axis in range(3):
            if after[axis] != before[axis]:
                signals[axis].append(min_jerk(0.0, (after[axis] - before[axis]) * DEG, t,
                                              CALIBRATION_MOVE_S))
        t += CALIBRATION_MOVE_S + CALIBRATION_HOLD_S
    roll, pitch, yaw = (add(*s) for s in signals)
    return Trajectory(roll=roll, pitch=pitch, yaw=yaw)


CALIBRATION_DURATION_S = (CALIBRATION_HOLD_S + (len(CALIBRATION_POSES_DEG) - 1)
                          * (CALIBRATION_MOVE_S + CALIBRATION_HOLD_S))


@dataclass(frozen=True)
class Scenario:
    id: int
    name: str
    duration: float
    build: Callable[[], Trajectory]
    description: str
    estimation: bool = True
    """Whether the contract and the campaigns estimate on it (not a calibration session, which
    is what `calibrate` reads)."""

    def trajectory(self) -> Trajectory:
        return self.build()

    def truth(self, t: Any, backend: str = "auto") -> Any:
        """The truth at times t [N] as an [N, 15] array in synthetic.TRUTH_NAMES' order (the
        plant FMU's outputs): through the plant's C twin (fusion_core.native.plant_truth) or
        the Python trajectory, backend as in Estimator.run ("auto": the twin where it loads);
        the same numbers either way (tests/test_native.py)."""
        import numpy as np

        from . import native
        from .base import check_backend

        check_backend(backend)
        t = np.ascontiguousarray(t, dtype=np.float64)
        if backend == "native" or (backend == "auto" and native.available()):
            return native.plant_truth(self.id, t)
        x = self.trajectory().truth(t)
        return np.column_stack([x["roll"], x["pitch"], x["yaw"], *x["omega"].T, *x["f"].T,
                                *x["pos"].T, *x["vel"].T])


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario(0, "static_level", 30.0, Trajectory, "at rest, level"),
        Scenario(
            1, "static_tilted", 30.0,
            lambda: Trajectory(roll=constant(20 * DEG), pitch=constant(-10 * DEG)),
            "at rest, roll 20 deg, pitch -10 deg",
        ),
        Scenario(
            2, "roll_sweep", 30.0, lambda: Trajectory(roll=sine(45 * DEG, 0.32)),
            "roll 45 deg sine at 0.32 Hz (peak rate 1.58 rad/s)",
        ),
        Scenario(
            3, "pitch_sweep", 30.0, lambda: Trajectory(pitch=sine(40 * DEG, 0.36)),
            "pitch 40 deg sine at 0.36 Hz (peak rate 1.58 rad/s)",
        ),
        Scenario(
            4, "roll_pitch", 30.0,
            lambda: Trajectory(
                roll=sine(30 * DEG, 0.3), pitch=sine(20 * DEG, 0.2, 0.5), yaw=sine(20 * DEG, 0.05)
            ),
            "roll 30 deg at 0.3 Hz and pitch 20 deg at 0.2 Hz together",
        ),
        Scenario(
            5, "moderate_dynamics", 60.0, _moderate,
            "roll/pitch 20-30 deg, rates to 1.5 rad/s, linear acceleration swelling to 0.3 g",
        ),
        Scenario(6, "vibration", 30.0, _vibration, "slow tilt with 60-180 Hz vibration of 0.3 g"),
        Scenario(
            7, "high_dynamics", 20.0, _high_dynamics, "tilt with sustained 0.5 g accelerations"
        ),
        Scenario(
            8, "translation_2m", 7.0,
            lambda: Trajectory(pos=(min_jerk(0.0, 2.0, 2.0, 3.0), constant(), constant())),
            "2 m along x, minimum jerk over 3 s, 2 s at rest before and after",
        ),
        Scenario(
            9, "shaking", 90.0, _shaking,
            "handheld shaking: 2.6 g RMS of linear acceleration at 3-5 Hz, turning 20-40 deg",
        ),
        Scenario(
            10, "gyro_clipping", 60.0, _gyro_clipping,
            "swings beyond the gyro's +-2000 deg/s range for about 8 % of the samples",
        ),
        Scenario(
            11, "calibration_session", CALIBRATION_DURATION_S, _calibration_session,
            "14 static poses of 3 s over the sphere, turns of 90-180 deg about mixed axes "
            "between them (testbenches calibrate)", estimation=False,
        ),
    )
}
SCENARIO_BY_ID: dict[int, Scenario] = {s.id: s for s in SCENARIOS.values()}
ESTIMATION_SCENARIOS: tuple[str, ...] = tuple(n for n, s in SCENARIOS.items() if s.estimation)
"""The scenarios the contract, `run`, `budget` and `campaign` estimate on."""


def get_scenario(key: str | int) -> Scenario:
    """A scenario by name or id; ValueError listing the allowed ones otherwise."""
    found = SCENARIO_BY_ID.get(key) if isinstance(key, int) else SCENARIOS.get(key)
    if found is None:
        allowed = ", ".join(f"{s.id}={s.name}" for s in SCENARIOS.values())
        raise ValueError(f"unknown scenario {key!r}: allowed {allowed}")
    return found
