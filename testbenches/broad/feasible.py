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
and outputs as the FMU testbench), without the wall-clock budget; and on moderate_dynamics the
share of the paper's row the defaults owe (contract.defaults_moderate_limits, where they meet
it: the mgcf's 1.5 s vector leaves it, pitch 0.69 against 0.66 deg).
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
    """The first of the contract's per-run accuracy checks (and the defaults' share of the
    paper's moderate_dynamics row) that estimator key with params fails (scenario and check, as
    a line), or None where it keeps every one."""
    for scenario in ESTIMATION_SCENARIOS:
        run = Run(key=f"{key}-{scenario}", estimator=key, scenario=scenario, seed=SEED,
                  duration=None, sensor={}, params=dict(params), varied={})
        result = contract.evaluate(simulate(run), timing=False)
        checks = list(result.checks)
        owed = contract.defaults_moderate_limits(key) if scenario == "moderate_dynamics" else None
        if owed is not None:
            share = f"{contract.DEFAULTS_MODERATE_SHARE:g} of the paper's row"
            checks += [contract.Check(f"defaults' {axis} RMSE", measured <= limit, measured,
                                      limit, "deg", share)
                       for axis, measured, limit in (
                           ("roll", result.metrics["rmse_roll_deg"], owed[0]),
                           ("pitch", result.metrics["rmse_pitch_deg"], owed[1]))]
        for check in checks:
            if not check.passed:
                return f"{scenario}: {check.line()}"
    return None


__all__ = ["SEED", "contract_failure"]
