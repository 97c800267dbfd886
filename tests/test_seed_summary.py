"""testbenches.report.seed_summaries: an estimator or peer over the seeds (the sensor parts)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from testbenches.contract_runs import ContractResult
from testbenches.peer_runs import PeerRun
from testbenches.report import seed_summaries, seed_summary_table


def run(estimator: str, scenario: str, roll: float, pitch: float) -> SimpleNamespace:
    """The parts of a TestbenchResult the summary reads."""
    return SimpleNamespace(estimator=estimator, scenario=scenario,
                           metrics={"rmse_roll_deg": roll, "rmse_pitch_deg": pitch})


def test_the_statistics_are_numpys_over_each_estimator_and_scenario() -> None:
    rng = np.random.default_rng(7)
    rmse = rng.uniform(0.1, 0.6, size=(40, 2))
    runs = [run("ukf", "moderate_dynamics", *v) for v in rmse]
    runs += [run("kf", "roll_sweep", 0.1, 0.1), run("kf", "roll_sweep", 0.3, 0.1)]
    (ukf, kf) = seed_summaries(ContractResult(runs=runs))  # type: ignore[arg-type]
    assert (ukf.name, ukf.scenario, ukf.seeds, ukf.peer) == ("ukf", "moderate_dynamics", 40,
                                                             False)
    assert ukf.mean == pytest.approx(tuple(rmse.mean(axis=0)), abs=1e-15)
    assert ukf.median == pytest.approx(tuple(np.median(rmse, axis=0)), abs=1e-15)
    assert ukf.p95 == pytest.approx(tuple(np.percentile(rmse, 95, axis=0)), abs=1e-15)
    # the UKF's moderate_dynamics bound is its paper row, 0.35/0.41: both axes within it
    inside = np.mean((rmse[:, 0] <= 0.35) & (rmse[:, 1] <= 0.41))
    assert 0.0 < inside < 1.0 and ukf.within == pytest.approx(inside)
    assert kf.within == 0.5  # roll_sweep's 0.25 deg: the second seed's roll is over it


def test_peers_are_summarised_apart_and_without_a_bound_where_they_have_none() -> None:
    peers = [PeerRun("vqf", "moderate_dynamics", s, 0.3 + 0.1 * s, 0.4, None, None)
             for s in range(3)]
    peers += [PeerRun("vqf", "roll_sweep", s, 0.2 * (s + 1), 0.1, (0.25, 0.25), s == 0)
              for s in range(2)]
    result = ContractResult(runs=[run("ukf", "moderate_dynamics", 0.2, 0.2)])  # type: ignore[list-item]
    ours, moderate, sweep = seed_summaries(result, peers)
    assert not ours.peer and moderate.peer and sweep.peer
    assert moderate.within is None and moderate.mean == pytest.approx((0.4, 0.4))
    assert sweep.within == 0.5
    table = seed_summary_table([ours, moderate, sweep])
    lines = table.splitlines()
    assert lines[-2].startswith("vqf (peer)  moderate_dynamics      3")
    assert lines[-2].endswith("-") and lines[-1].endswith("50 %")
