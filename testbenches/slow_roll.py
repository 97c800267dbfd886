"""A slow smooth roll from power-up that never rests: the rest detector's hardest case.

40 deg of roll at 0.02 Hz, 200 Hz, 600 s, white noise on both sensors, no gyro bias. At each
turning point gravity stands for a second while the rate ramps through zero, so a detector that
looks at the rate alone takes the turning points for rest and teaches the bias the ramp.
`python -m testbenches.slow_roll` prints each attitude filter's inclination RMSE and largest
error beside VQF's on the same samples (docs/guide/own-sensor.md); tests/test_rest_detection.py
holds the filters to a tenth of VQF's figures.
"""

from __future__ import annotations

import sys

import numpy as np

from fusion_core import G
from fusion_core.registry import ATTITUDE_FILTERS

RATE_HZ = 200.0
SECONDS = 600.0
AMPLITUDE_DEG = 40.0
FREQUENCY_HZ = 0.02
FILTERS = ATTITUDE_FILTERS
"""The registry's attitude filters."""


def recording(seed: int = 0) -> dict[str, np.ndarray]:
    """acc [n, 3], gyro [n, 3], dt [n] and the true up direction in the sensor frame [n, 3]."""
    n = round(RATE_HZ * SECONDS)
    t = np.arange(n) / RATE_HZ
    amp, w = np.radians(AMPLITUDE_DEG), 2 * np.pi * FREQUENCY_HZ
    roll = amp * np.sin(w * t)
    rng = np.random.default_rng(seed)
    acc = np.column_stack([np.zeros(n), G * np.sin(roll), G * np.cos(roll)])
    acc += rng.normal(0.0, 0.03, (n, 3))
    gyro = np.column_stack([amp * w * np.cos(w * t), np.zeros(n), np.zeros(n)])
    gyro += rng.normal(0.0, 0.002, (n, 3))
    up = np.column_stack([np.zeros(n), np.sin(roll), np.cos(roll)])
    return {"acc": acc, "gyro": gyro, "dt": np.full(n, 1.0 / RATE_HZ), "up": up}


def errors(key: str, rec: dict[str, np.ndarray]) -> dict[str, float]:
    """One filter's (recommended preset) inclination RMSE and largest error [deg] and the
    largest bias it learned about x [deg/s]."""
    from fusion_core.registry import create

    from .broad.metric import gravity_from_roll_pitch, inclination_error

    out = create(key).run(rec["acc"], rec["gyro"], rec["dt"])
    err = np.degrees(inclination_error(gravity_from_roll_pitch(out["roll"], out["pitch"]),
                                       rec["up"]))
    return {"rmse": float(np.sqrt(np.mean(err**2))), "max": float(err.max()),
            "bias": float(np.degrees(np.abs(out["bias"][:, 0]).max()))}


def vqf_errors(rec: dict[str, np.ndarray]) -> dict[str, float]:
    """VQF 6D's (package defaults) inclination RMSE and largest error [deg] on the samples."""
    from .broad.metric import inclination_error
    from .peers import run_vqf

    err = np.degrees(inclination_error(run_vqf(rec["acc"], rec["gyro"], RATE_HZ), rec["up"]))
    return {"rmse": float(np.sqrt(np.mean(err**2))), "max": float(err.max())}


def table() -> str:
    """The Markdown table: each filter and VQF."""
    rec = recording()
    rows = ["| filter | inclination RMSE [deg] | largest error [deg] | largest bias learned "
            "[deg/s] |", "|---|---|---|---|"]
    for key in FILTERS:
        e = errors(key, rec)
        rows.append(f"| {key} | {e['rmse']:.3f} | {e['max']:.3f} | {e['bias']:.3f} |")
    v = vqf_errors(rec)
    rows.append(f"| VQF | {v['rmse']:.3f} | {v['max']:.3f} | |")
    return "\n".join(rows)


if __name__ == "__main__":  # pragma: no cover
    print(table())
    sys.exit(0)
