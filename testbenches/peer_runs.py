"""Public filters on the contract's own samples: `python -m testbenches run --peers vqf,...`.

A FAIL in the contract table means more once one knows whether the best public filters pass the
same check. Each peer (testbenches.peers: VQF, Madgwick, Mahony with their packages' defaults)
runs on the very samples the estimator FMUs get for that scenario and seed: the plant's truth
through the sensor model with the run's sensor parameters and seed (montecarlo.simulate's path,
which tests/test_montecarlo.py holds equal to the FMU testbench's). A peer is scored by the
contract's own metric (contract.attitude_errors: roll and pitch RMSE after the same settling
time) against the same bounds. moderate_dynamics is bounded per estimator class (the papers'
rows), so a peer gets its numbers there but no verdict. The peers never change the exit status:
they are a reference, not a product.

Only the zero-jitter testbench has one sample rate, which the peers need; `run --jitter` with
`--peers` is refused.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from . import contract
from .samples import RATE, scenario_samples

Peer = Callable[[np.ndarray, np.ndarray, float], np.ndarray]


@dataclass(frozen=True)
class PeerRun:
    """One peer on one scenario and seed: roll and pitch RMSE [deg] and, where the scenario's
    bound does not depend on the estimator class, the bound and the verdict."""

    peer: str
    scenario: str
    seed: int
    rmse_roll_deg: float
    rmse_pitch_deg: float
    allowed: tuple[float, float] | None
    passed: bool | None

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def roll_pitch_from_up(up: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch [rad] of up directions in the sensor frame [N, 3]: the inverse of
    docs/interface.md's resting specific force, as kinematics.accel_roll_pitch."""
    up = np.asarray(up, dtype=float)
    return (np.arctan2(up[:, 1], up[:, 2]),
            np.arctan2(-up[:, 0], np.sqrt(up[:, 1] ** 2 + up[:, 2] ** 2)))


def peer_limits(scenario: str) -> tuple[float, float] | None:
    """The scenario's accuracy bound for a peer: None where the contract bounds each estimator
    class on its own (moderate_dynamics)."""
    return contract.ACCURACY.get(scenario)


def run_peers(
    peers: dict[str, Peer], scenarios: Iterable[str], seeds: int, sensor: dict[str, Any],
    duration: float | None = None, calibrate_first: bool = False,
) -> list[PeerRun]:
    """Every peer on every scenario and seed (0 .. seeds-1) of the contract run; with
    calibrate_first on the samples calibrated as the estimators calibrate them (each part's
    matrices from its own calibration session: testbenches.calibrate.part)."""
    from fusion_core.synthetic import TRUTH_NAMES

    rows = []
    for scenario in scenarios:
        for seed in range(seeds):
            t, truth_array, sample = scenario_samples(scenario, seed, sensor, duration)
            truth = {n: truth_array[:, i] for i, n in enumerate(TRUTH_NAMES)}
            acc, gyro = sample["acc"], sample["gyro"]
            if calibrate_first:
                acc, gyro = _calibrated(acc, gyro, sensor, seed)
            for name, peer in peers.items():
                roll, pitch = roll_pitch_from_up(peer(acc, gyro, RATE))
                err_roll, err_pitch, keep = contract.attitude_errors(scenario, t, truth, roll,
                                                                     pitch)
                rmse = (contract.scored_rmse(err_roll, keep), contract.scored_rmse(err_pitch, keep))
                allowed = peer_limits(scenario)
                passed = None if allowed is None else bool(
                    rmse[0] <= allowed[0] and rmse[1] <= allowed[1]
                )
                rows.append(PeerRun(name, scenario, seed, *rmse, allowed, passed))
    return rows


def _calibrated(acc: np.ndarray, gyro: np.ndarray, sensor: dict[str, Any], seed: int
                ) -> tuple[np.ndarray, np.ndarray]:
    from fusion_core.calibration import Calibration

    from .calibrate.part import part_calibration

    return Calibration.from_params(part_calibration(sensor, seed)).apply(acc, gyro)


def peer_table(rows: list[PeerRun]) -> str:
    """The peers' rows as a text table, one line per peer, scenario and seed."""
    lines = ["Public filters on the same samples (reference only: not part of the verdict)",
             f"{'peer':<9} {'scenario':<18} {'seed':>4}  {'RMSE roll/pitch [deg]':>22}  "
             f"{'allowed':>11}  verdict"]
    for r in rows:
        allowed = "-" if r.allowed is None else f"{r.allowed[0]:g}/{r.allowed[1]:g}"
        verdict = "-" if r.passed is None else ("PASS" if r.passed else "FAIL")
        lines.append(f"{r.peer:<9} {r.scenario:<18} {r.seed:>4}  "
                     f"{r.rmse_roll_deg:>10.3f}/{r.rmse_pitch_deg:<11.3f}  {allowed:>11}  "
                     f"{verdict}")
    return "\n".join(lines)
