"""The shaking and gyro_clipping scenarios: what they hold, and every default attitude estimator
within VQF + 10 % over 20 parts of the realistic sensor (testbenches.contract.SHAKING,
GYRO_CLIPPING)."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from fusion_core import ESTIMATORS, G
from fusion_core.registry import ATTITUDE_FILTERS
from fusion_core.scenarios import SCENARIOS
from fusion_core.synthetic import TRUTH_NAMES
from fusion_core.types import DEG
from testbenches import contract
from testbenches.montecarlo.simulate import scenario_samples

PARTS = 20
VQF_CONSTANTS = {"shaking": contract.VQF_SHAKING, "gyro_clipping": contract.VQF_GYRO_CLIPPING}


def test_shaking_is_sustained_multi_g_linear_acceleration() -> None:
    sc = SCENARIOS["shaking"]
    t = np.arange(0.0, sc.duration, 0.01)
    x = sc.trajectory().truth(t)
    f = np.linalg.norm(x["f"], axis=1) / G
    assert sc.duration >= 60.0
    assert 3.5 < np.percentile(f, 95) < 4.5 and 5.0 < f.max() < 6.5


def test_gyro_clipping_exceeds_the_gyro_range_for_about_8_percent() -> None:
    sc = SCENARIOS["gyro_clipping"]
    t = np.arange(0.0, sc.duration, 0.01)
    rate = np.abs(sc.trajectory().truth(t)["omega"])
    assert 0.06 < np.mean((rate > 2000.0 * DEG).any(axis=1)) < 0.10


def _mean_rmse(make, scenario: str) -> np.ndarray:
    rows = []
    for seed in range(PARTS):
        t, truth_array, s = scenario_samples(scenario, seed, {})
        truth = {n: truth_array[:, i] for i, n in enumerate(TRUTH_NAMES)}
        out = make(s)
        err_r, err_p, keep = contract.attitude_errors(scenario, t, truth, out[0], out[1])
        rows.append((contract.scored_rmse(err_r, keep), contract.scored_rmse(err_p, keep)))
    return np.mean(rows, axis=0)


@pytest.mark.parametrize("scenario", ["shaking", "gyro_clipping"])
@pytest.mark.parametrize("key", ATTITUDE_FILTERS)
def test_every_default_is_within_vqf_plus_ten_percent_over_20_parts(key: str,
                                                                   scenario: str) -> None:
    def run(s):
        out = ESTIMATORS[key]().run(s["acc"], s["gyro"], s["dt"])
        return out["roll"], out["pitch"]

    roll, pitch = _mean_rmse(run, scenario)
    limit = contract.ACCURACY[scenario]
    assert roll <= limit[0] and pitch <= limit[1], (roll, pitch, limit)


@pytest.mark.skipif(importlib.util.find_spec("vqf") is None,
                    reason="vqf is not installed (pip install -e '.[bench]')")
@pytest.mark.parametrize("scenario", ["shaking", "gyro_clipping"])
def test_the_bounds_are_vqfs_own_figures(scenario: str) -> None:
    from testbenches.peer_runs import roll_pitch_from_up
    from testbenches.peers import PEERS

    def run(s):
        return roll_pitch_from_up(PEERS["vqf"](s["acc"], s["gyro"], 100.0))

    measured = _mean_rmse(run, scenario)
    assert np.allclose(measured, VQF_CONSTANTS[scenario], rtol=1e-3), measured
