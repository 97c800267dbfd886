"""The one list of the project's estimators: every other list, table, help string and test
parametrisation derives from REGISTRY.

An entry names an estimator's key (the short name the commands and presets use), its class, what
it estimates and whether its attitude comes from a measured vector of its own (the four attitude
filters; the position filter's attitude is a kf's). The C twin's prefix is the class's TWIN and
the FMU's model name is the class's name.
"""

from __future__ import annotations

from dataclasses import dataclass

from .base import Estimator
from .complementary import ComplementaryFilter
from .kalman import AngleBiasKalmanFilter
from .mgcf import GainScheduledComplementaryFilter
from .position import PositionKalmanFilter
from .ukf import UnscentedKalmanFilter


@dataclass(frozen=True)
class Entry:
    """One estimator of the project."""

    key: str
    cls: type[Estimator]
    title: str
    """What it is, for help strings and tables."""
    attitude_filter: bool
    """Whether it is one of the attitude filters with a measured vector of its own (cf, mgcf, kf,
    ukf), the ones whose scanned defaults `broad --cv` cross-validates."""

    @property
    def twin(self) -> str | None:
        """The C twin's prefix (fusion_core/native), or None."""
        return self.cls.TWIN

    @property
    def fmu(self) -> str:
        """The FMU's model name (fmu_src/models)."""
        return self.cls.__name__


REGISTRY: tuple[Entry, ...] = (
    Entry("cf", ComplementaryFilter, "complementary filter (Gui et al. 2015)", True),
    Entry("mgcf", GainScheduledComplementaryFilter,
          "modified-gain complementary filter (Duong Quoc et al.)", True),
    Entry("kf", AngleBiasKalmanFilter, "2-state angle/bias Kalman filter (Gui et al., Das & Mary)",
          True),
    Entry("ukf", UnscentedKalmanFilter, "unscented Kalman filter (Duong Quoc et al.)", True),
    Entry("poskf", PositionKalmanFilter, "position Kalman filter (Safitri et al.)", False),
)
"""Every estimator, in the order of the tables."""

ESTIMATORS: dict[str, type[Estimator]] = {e.key: e.cls for e in REGISTRY}
"""key -> class."""
KEYS: tuple[str, ...] = tuple(ESTIMATORS)
"""Every estimator's key."""
ATTITUDE_FILTERS: tuple[str, ...] = tuple(e.key for e in REGISTRY if e.attitude_filter)
"""The keys of the attitude filters with a measured vector of their own."""
FMU_NAMES: dict[str, str] = {e.key: e.fmu for e in REGISTRY}
"""key -> FMU model name."""


def keys_help() -> str:
    """The estimator keys as a help string lists them: "cf, mgcf, kf, ukf, poskf"."""
    return ", ".join(KEYS)


__all__ = ["ATTITUDE_FILTERS", "ESTIMATORS", "FMU_NAMES", "KEYS", "REGISTRY", "Entry",
           "keys_help"]
