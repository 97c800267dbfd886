"""Whether a parameter set keeps the contract: the constraint of the cross-validation's choice
(testbenches.broad.cv).

A scan over BROAD's trials sees one IMU and one lab's motions. The contract's scenarios carry
what those trials cannot: a sensor of the MPU-6050 class (its scale and cross-axis errors, its
noise and range) and motions BROAD lacks (sustained accelerations of seconds, shaking, a gyro at
its rail). A value a fold would choose but the contract's accuracy bounds refuse is none a
default could take, so the cross-validation chooses among the grid points that keep them.

The check is the per-run accuracy part of `make run` (every estimation scenario, seed 0, the
realistic sensor: roll and pitch RMSE within the scenario's bound, no rejected sample), run
through fusion_core as the campaign runs it (testbenches.montecarlo.simulate: the same samples
and outputs as the FMU testbench), without the wall-clock budget.
"""

from __future__ import annotations

from typing import Any

from fusion_core.scenarios import ESTIMATION_SCENARIOS

from .. import contract
from ..montecarlo.plan import Run
from ..montecarlo.simulate import simulate

SEED = 0
"""The part the contract's per-run checks use (`make run`)."""


def contract_failure(key: str, params: dict[str, Any]) -> str | None:
    """The first of the contract's per-run accuracy checks that estimator key with params fails
    (scenario and check, as a line), or None where it keeps every one."""
    for scenario in ESTIMATION_SCENARIOS:
        run = Run(key=f"{key}-{scenario}", estimator=key, scenario=scenario, seed=SEED,
                  duration=None, sensor={}, params=dict(params), varied={})
        result = contract.evaluate(simulate(run), timing=False)
        for check in result.checks:
            if not check.passed:
                return f"{scenario}: {check.line()}"
    return None


__all__ = ["SEED", "contract_failure"]
