"""What the papers' reference filters share: their parameters beside their own, the gate and the
integration rule at the papers' values."""

from __future__ import annotations

import dataclasses
from typing import Final

from ..base import COMMON_PARAMS
from ..building_blocks import ACC_GATE_PARAMS, GYRO_SAMPLING_PARAM
from ..types import Param

Vec3 = tuple[float, float, float]

PAPER_GATE: Final[tuple[Param, ...]] = tuple(
    dataclasses.replace(p, default={"gate_low": 0.9, "gate_high": 1.1}[p.name])
    for p in ACC_GATE_PARAMS
)
"""The accelerometer-magnitude gate at 0.9-1.1 g. Gui et al. gate the accelerometer without
giving bounds in the text: these are our reading."""
PAPER_SAMPLING: Final = dataclasses.replace(GYRO_SAMPLING_PARAM, default="mean")
"""The papers integrate each gyro sample with the rectangle rule (rate times dt), exact for the
interval means that gyro_sampling="mean" describes."""
PAPER_COMMON: Final[tuple[Param, ...]] = tuple(
    PAPER_SAMPLING if p.name == "gyro_sampling" else p
    for p in COMMON_PARAMS if p.name != "gyro_range"
)
"""The parameters every estimator shares, at the papers' rules: the rectangle rule
(PAPER_SAMPLING), and no gyro_range: the papers' filters know no gyro range, and no sample is at
a rail for them."""
