"""fusion_core: the project's IMU attitude and position estimators, free of any FMI concern.

Every estimator has the same API: `Estimator(**params)`, `reset()`, `step(acc, gyro, dt)`,
`run(acc, gyro, dt)`, `get_state()` / `set_state()`, and a declarative `PARAMS` table that the
FMU layer (fmu_src) turns into FMU parameters. The estimators are listed once, in
fusion_core.registry.
"""

from .base import Estimator
from .complementary import ComplementaryFilter
from .kalman import AngleBiasKalmanFilter
from .mgcf import GainScheduledComplementaryFilter
from .position import PositionKalmanFilter
from .registry import ESTIMATORS, REGISTRY
from .types import DEG, Estimate, G, InvalidSample, Param
from .ukf import UnscentedKalmanFilter

__all__ = [
    "DEG",
    "ESTIMATORS",
    "REGISTRY",
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
