"""The accuracy contract over sensor parts (interface v4): the share of parts within each bound,
as delivered (the typical part) and calibrated first (95 %), and the runs behind it equal to
the FMU testbench's."""

from __future__ import annotations

import numpy as np
import pytest

from fusion_core.presets import load_preset
from fusion_core.sensor import sensor_preset
from testbenches import parts
from testbenches.contract import accuracy_limits


def test_the_rule_counts_a_part_within_only_where_roll_and_pitch_both_are() -> None:
    lim = accuracy_limits("kf", "static_level")
    inside, roll_out, pitch_out = (0.5 * lim[0], 0.5 * lim[1]), (2 * lim[0], 0.0), (0.0, 2 * lim[1])
    raw = np.array([inside] * 10 + [roll_out] * 5 + [pitch_out] * 5)  # 50 %: the typical part
    calibrated = np.array([inside] * 19 + [roll_out])  # 95 %
    checks = parts.parts_checks({(False, "kf", "static_level"): raw,
                                 (True, "kf", "static_level"): calibrated})
    assert [c.measured for c in checks] == [50.0, 95.0]
    assert all(c.passed for c in checks)
    short = parts.parts_checks({(True, "kf", "static_level"): calibrated[1:]})[0]
    assert not short.passed and short.measured == pytest.approx(100 * 18 / 19)
    assert "needed at least 95" in short.line() and "of parts" in short.line()
    assert "(not met)" in parts.parts_table({(False, "kf", "static_level"): raw[5:],
                                             (True, "kf", "static_level"): calibrated[1:]})


@pytest.mark.heavy  # a part through the testbench
def test_each_part_is_the_seed_the_testbench_runs() -> None:
    """Part k is seed k of the sensor: the RMSE of part 0 is the seed-0 run's (the FMUs give
    the same to the bit: tests/test_montecarlo.py)."""
    from testbenches.contract import compute_metrics
    from testbenches.montecarlo.plan import Run
    from testbenches.montecarlo.simulate import simulate

    preset, sensor = load_preset("recommended"), sensor_preset("realistic")
    rmse = parts.part_rmse(["kf"], ["static_tilted"], preset, sensor, parts=3)
    assert rmse[(False, "kf", "static_tilted")].shape == (3, 2)
    m = compute_metrics(simulate(Run("x", "kf", "static_tilted", 2, None, sensor,
                                     preset["kf"], {})))
    assert tuple(rmse[(False, "kf", "static_tilted")][2]) == (m["rmse_roll_deg"],
                                                              m["rmse_pitch_deg"])
    assert not np.array_equal(rmse[(False, "kf", "static_tilted")],
                              rmse[(True, "kf", "static_tilted")])  # calibrated first differs
