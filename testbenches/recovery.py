"""How each estimator comes back from samples that pass every input rule but are absurd.

`python -m testbenches.recovery` prints, per estimator of the registry (recommended preset):
how far off the attitude is thrown by ABSURD_S of rates up to 300 rad/s and specific force up
to 100 g (every sample valid by the contract, so processed), and how long after them a clean
static tilt (roll 20 deg, pitch -10 deg) takes to bring the inclination error under 1 deg for
good. Seeded: the table is the same on every machine. tests/test_garbage_in.py holds every
estimator to RECOVERY_BOUND_S; docs/results/robustness.md shows the table.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from fusion_core import DEG, G

RATE_HZ = 100.0
ABSURD_S = 1.0
CLEAN_S = 60.0
"""The clean tilt after the absurd samples: longer than the bound, so "never back" shows."""
RECOVERY_BOUND_S = 40.0
"""The most any estimator may take to come back under 1 deg (tests/test_garbage_in.py)."""
ROLL, PITCH = 20 * DEG, -10 * DEG


def absurd_then_tilt(key: str, seed: int = 7) -> dict[str, float]:
    """One estimator's run: the inclination error [deg] at the first clean sample, the time
    [s] after which it stays under 1 deg, and how many samples it rejected (none is meant)."""
    from fusion_core.registry import create

    rng = np.random.default_rng(seed)
    n_bad, n_good = int(ABSURD_S * RATE_HZ), int(CLEAN_S * RATE_HZ)
    up = np.array([-math.sin(PITCH), math.sin(ROLL) * math.cos(PITCH),
                   math.cos(ROLL) * math.cos(PITCH)])
    acc_bad = rng.uniform(-1000.0, 1000.0, size=(n_bad, 3))
    gyro_bad = rng.uniform(-300.0, 300.0, size=(n_bad, 3))
    acc = np.vstack([np.tile(G * up, (5, 1)), acc_bad, np.tile(G * up, (n_good, 1))])
    gyro = np.vstack([np.zeros((5, 3)), gyro_bad, np.zeros((n_good, 3))])
    out = create(key).run(acc, gyro, 1.0 / RATE_HZ)
    r, p = out["roll"][5 + n_bad:], out["pitch"][5 + n_bad:]
    est = np.stack([-np.sin(p), np.sin(r) * np.cos(p), np.cos(r) * np.cos(p)], axis=1)
    err = np.degrees(np.arccos(np.clip(est @ up, -1.0, 1.0)))
    late = np.nonzero(err >= 1.0)[0]
    return {"thrown_deg": float(err[0]),
            "back_after_s": float((late[-1] + 1) / RATE_HZ) if late.size else 0.0,
            "rejected": float(np.sum(out["rejected"]))}


def table() -> str:
    """The Markdown table of every registry estimator's run."""
    from fusion_core.registry import KEYS

    rows = ["| estimator | error after the absurd second [deg] | back under 1 deg after [s] |",
            "|---|---|---|"]
    for key in KEYS:
        got = absurd_then_tilt(key)
        rows.append(f"| {key} | {got['thrown_deg']:.0f} | {got['back_after_s']:.1f} |")
    return "\n".join(rows)


if __name__ == "__main__":  # pragma: no cover
    print(table())
    sys.exit(0)
