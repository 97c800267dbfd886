"""fusion_core: the project's IMU attitude and position estimators, free of any FMI concern.

Every estimator has the same API: `Estimator(**params)`, `reset()`, `step(acc, gyro, dt)`,
`run(acc, gyro, dt)`, `get_state()` / `set_state()`, and a declarative `PARAMS` table that the
FMU layer (fmu_src) turns into FMU parameters.
"""

from .base import Estimator
from .complementary import ComplementaryFilter
from .kalman import AngleBiasKalmanFilter
from .types import DEG, G, Estimate, InvalidSample, Param

ESTIMATORS: dict[str, type[Estimator]] = {
    "cf": ComplementaryFilter,
    "kf": AngleBiasKalmanFilter,
}

__all__ = [
    "DEG",
    "ESTIMATORS",
    "G",
    "AngleBiasKalmanFilter",
    "ComplementaryFilter",
    "Estimate",
    "Estimator",
    "InvalidSample",
    "Param",
]
