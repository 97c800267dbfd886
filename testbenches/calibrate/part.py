"""Calibrating a simulated part before it is used (`run --calibrate-first`, `campaign
--calibrate-first`): the calibration_session scenario recorded through the same sensor part (its
parameters and seed), calibrated by the calibrate command's own code (its first pose held level,
as `calibrate --level` takes it), the result applied at the estimators' input.

What carries over from the session to the runs is the part's matrices (scale factors,
misalignment, cross-coupling), not its offsets: a MEMS part's biases change from one power-up
and one temperature to the next (the realistic sensor draws what a start-up calibration leaves),
and the estimators learn the gyro's themselves. The session is a recording of its own: the same
part, not the run's samples.
"""

from __future__ import annotations

import functools
import json
from typing import Any

import numpy as np

from fusion_core.calibration import matrix_names

from ..samples import scenario_samples
from .level import level_pose, levelled
from .tedaldi import CalibrationRefused, calibrate_session

SESSION = "calibration_session"


@functools.lru_cache(maxsize=64)
def _part_calibration(sensor_json: str) -> tuple[tuple[str, float], ...]:
    sensor = json.loads(sensor_json)
    _, _, out = scenario_samples(SESSION, sensor["seed"], sensor)
    try:
        session = calibrate_session(out["acc"], out["gyro"], out["dt"],
                                    float(sensor.get("gyro_range", np.radians(2000.0))))
    except CalibrationRefused as err:
        raise CalibrationRefused(f"the calibration session of part seed {sensor.get('seed')} "
                                 f"could not be calibrated: {err}") from None
    # the session's first pose is level (scenarios.CALIBRATION_POSES_DEG), as `calibrate
    # --level` takes it
    acc_fit, gyro_fit, _ = levelled(session.acc, session.gyro,
                                    level_pose([s.acc for s in session.statics]))
    values = dict(zip(matrix_names("acc"), acc_fit.matrix.ravel().tolist(), strict=True))
    values.update(zip(matrix_names("gyro"), gyro_fit.matrix.ravel().tolist(), strict=True))
    return tuple(values.items())


def part_calibration(sensor: dict[str, Any], seed: int) -> dict[str, float]:
    """The estimator parameters that calibrate the part of these sensor parameters and seed
    (its matrices; cached per part, as a worker runs several estimators on one)."""
    key = json.dumps({**sensor, "seed": seed}, sort_keys=True)
    return dict(_part_calibration(key))
