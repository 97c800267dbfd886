"""fusion_core: the project's IMU attitude and position estimators, free of any FMI concern.

Every estimator has the same API: `Estimator(**params)`, `reset()`, `step(acc, gyro, dt)`,
`run(acc, gyro, dt)`, `get_state()` / `set_state()`, and a declarative `PARAMS` table that the
FMU layer (fmu_src) turns into FMU parameters.
"""

from .base import Estimator
from .complementary import ComplementaryFilter
from .kalman import AngleBiasKalmanFilter
from .mgcf import GainScheduledComplementaryFilter
from .position import PositionKalmanFilter
from .types import DEG, Estimate, G, InvalidSample, Param
from .ukf import UnscentedKalmanFilter

ESTIMATORS: dict[str, type[Estimator]] = {
    "cf": ComplementaryFilter,
    "mgcf": GainScheduledComplementaryFilter,
    "kf": AngleBiasKalmanFilter,
    "ukf": UnscentedKalmanFilter,
    "poskf": PositionKalmanFilter,
}

__all__ = [
    "DEG",
    "ESTIMATORS",
    "AngleBiasKalmanFilter",
    "ComplementaryFilter",
    "Estimate",
    "Estimator",
    "G",
    "GainScheduledComplementaryFilter",
    "InvalidSample",
    "Param",
    "PositionKalmanFilter",
    "UnscentedKalmanFilter",
]
