"""The one list of the project's estimators: every other list, table, help string and test
parametrisation derives from REGISTRY.

An entry names an estimator's key (the short name the commands and presets use), its class (the
recommended filter), its reference class (the seed paper's filter, fusion_core.papers), what it
estimates and whether its attitude comes from a measured vector of its own (the four attitude
filters; the position filter's attitude is a kf's). Each class's C twin prefix is its TWIN; the
FMU's model name is the recommended class's name, whichever of the two an FMU runs.

A parameter set chooses between the two classes with the key FILTER ("filter": "paper" runs the
reference; create, estimator_class), so that the choice travels with the parameters through
presets, campaigns and FMU builds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

from .base import Estimator
from .complementary import ComplementaryFilter
from .kalman import AngleBiasKalmanFilter
from .madgwick import MadgwickFilter
from .mgcf import GainScheduledComplementaryFilter
from .papers import (
    PaperComplementaryFilter,
    PaperGainScheduledFilter,
    PaperKalmanFilter,
    PaperPositionKalmanFilter,
    PaperUnscentedKalmanFilter,
)
from .position import PositionKalmanFilter
from .ukf import UnscentedKalmanFilter

FILTER = "filter"
"""The key of a parameter set that chooses the class: FILTERS[0] (the default) or FILTERS[1]."""
FILTERS = ("recommended", "paper")


class PaperRow(NamedTuple):
    """A row of Duong Quoc et al.'s Table 1 (moderate dynamics, after the first seconds): the
    roll and pitch RMSE [deg] a filter is held to, and whose row it is."""

    roll: float
    pitch: float
    of: str
    """The paper's name of the filter whose row it is (CCF, MGCF, UKF)."""


CCF_ROW = PaperRow(1.84, 2.03, "CCF")
"""The conventional complementary filter's row: the cf's, and the one the paper's table gives
the Kalman filters it has no row for (kf, poskf)."""


class Bench(NamedTuple):
    """An estimator's speed targets in `make bench` (benchmarks.report)."""

    step_us: float
    """Python `step` per sample [us], at most (the interpreted reference)."""
    native_us: float
    """The C twin's batch run per sample [us], at most."""
    vqf_ratio: float
    """The C twin's batch run per sample as a multiple of VQF's C++ updateBatch in the same
    run, at most."""


@dataclass(frozen=True)
class Entry:
    """One estimator of the project: everything the commands, the FMUs, the contract, the
    benchmarks and the tests need to know of it beyond its class."""

    key: str
    cls: type[Estimator]
    reference: type[Estimator] | None
    """The seed paper's filter (fusion_core.papers), or None where the class is itself its
    paper's filter at its paper's values: the paper preset then runs the class with the papers'
    rules (presets.PAPER_RULES)."""
    title: str
    """What it is, for help strings and tables."""
    cites: str
    """The papers and equations it implements, for tables (README's)."""
    attitude_filter: bool
    """Whether it is one of the attitude filters with a measured vector of its own (cf, mgcf, kf,
    ukf), the ones whose scanned defaults `broad --cv` cross-validates."""
    fmu_text: str
    """Its FMU's modelDescription text: what it estimates, after which paper and equations
    (fmu_src builds the FMU from the entry; a paper's filter adds a note)."""
    paper_row: PaperRow | None
    """The paper's moderate-dynamics row it is held to (testbenches.contract), None for an
    estimator no seed paper has a row for (no contract row is invented for it)."""
    bench: Bench
    moderate_not_met: str | None = None
    """Where its defaults do not meet the contract's target on moderate dynamics yet (half its
    paper row, contract.DEFAULTS_MODERATE_SHARE): why (tests/test_paper_rows.py expects the
    failure)."""

    @property
    def twin(self) -> str | None:
        """The C twin's prefix (fusion_core/native), or None."""
        return self.cls.TWIN

    @property
    def paper_class(self) -> type[Estimator]:
        """The class the paper preset ("filter": "paper") runs: the reference, or the class
        itself where the entry has none."""
        return self.reference or self.cls

    @property
    def fmu(self) -> str:
        """The FMU's model name: the recommended class's name (fmu_src.names)."""
        return self.cls.__name__


REGISTRY: tuple[Entry, ...] = (
    Entry("cf", ComplementaryFilter, PaperComplementaryFilter,
          title="complementary filter (Gui et al. 2015)",
          cites="Gui, Tang, Mukhopadhyay 2015 eq. 1-2; Das & Mary eq. 1", attitude_filter=True,
          fmu_text="Complementary filter for roll and pitch from a 6-axis IMU: W. Gui, Y. Tang, "
          "S. Mukhopadhyay (2015), eq. 1-2; Das & Mary, eq. 1. One IMU sample per doStep; "
          "the gyro bias measured at rest (rest_time > 0) is subtracted and output.",
          paper_row=CCF_ROW, bench=Bench(step_us=1.0, native_us=0.2, vqf_ratio=0.75)),
    Entry("mgcf", GainScheduledComplementaryFilter, PaperGainScheduledFilter,
          title="modified-gain complementary filter (Duong Quoc et al.)",
          cites="Duong Quoc et al. eq. 7-13", attitude_filter=True,
          fmu_text="Modified-gain (gain-scheduled) complementary filter for roll and pitch: "
          "Duong Quoc et al., eq. 7-13 (quaternion PI filter of Mahony et al. 2008 with w0 "
          "scheduled on ||acc|/g - 1|). One IMU sample per doStep.",
          paper_row=PaperRow(1.07, 1.32, "MGCF"),
          bench=Bench(step_us=5.0, native_us=0.25, vqf_ratio=0.9)),
    Entry("kf", AngleBiasKalmanFilter, PaperKalmanFilter,
          title="2-state angle/bias Kalman filter (Gui et al., Das & Mary)",
          cites="Gui et al. eq. 5-26; Das & Mary eq. 16-27", attitude_filter=True,
          fmu_text="Two-state [angle, gyro bias] Kalman filter for roll and pitch: W. Gui, "
          "Y. Tang, S. Mukhopadhyay (2015), eq. 5-26; Das & Mary, eq. 16-27. One IMU sample "
          "per doStep.",
          paper_row=CCF_ROW, bench=Bench(step_us=2.0, native_us=0.2, vqf_ratio=0.75)),
    Entry("ukf", UnscentedKalmanFilter, PaperUnscentedKalmanFilter,
          title="unscented Kalman filter (Duong Quoc et al.)",
          cites="Duong Quoc et al. eq. 14-17", attitude_filter=True,
          fmu_text="Unscented Kalman filter for roll and pitch on the gravity direction with "
          "three gyro-bias states: Duong Quoc et al., eq. 14-17. One IMU sample per doStep.",
          paper_row=PaperRow(0.35, 0.41, "UKF"),
          bench=Bench(step_us=25.0, native_us=1.0, vqf_ratio=3.7),
          moderate_not_met="not met yet on seed 0's part: the realistic gyro's scale and "
          "cross-axis errors make what is left (on the ideal sensor it is met), its cross-axis "
          "errors most (`python -m testbenches budget`), which the UKF's bias states chase; "
          "docs/guide/campaigns.md has the share of 200 parts that meet it, and VQF's"),
    Entry("poskf", PositionKalmanFilter, PaperPositionKalmanFilter,
          title="position Kalman filter (Safitri et al.)",
          cites="Safitri, Cahyadi, Firmansyah eq. 20-29, tilt from `kf`", attitude_filter=False,
          fmu_text="Position and velocity Kalman filter with a zero-velocity update: Safitri, "
          "Cahyadi, Firmansyah, eq. 20-29; tilt from the Gui, Tang, Mukhopadhyay (2015) "
          "[angle, bias] Kalman filter. One IMU sample per doStep.",
          paper_row=CCF_ROW, bench=Bench(step_us=10.0, native_us=0.4, vqf_ratio=1.5)),
    Entry("madgwick", MadgwickFilter, None,
          title="Madgwick's gradient-descent filter (Madgwick et al. 2011)",
          cites="Madgwick, Harrison, Vaidyanathan 2011; Madgwick 2010 eq. 12-13, 25-26, 33-34",
          attitude_filter=False,
          fmu_text="Madgwick's gradient-descent orientation filter, IMU form, for roll and pitch: "
          "S. Madgwick, A. Harrison, R. Vaidyanathan (2011); Madgwick (2010), eq. 12-13, 25-26, "
          "33-34, at its paper's gain beta = 0.033 rad/s. One IMU sample per doStep; no "
          "gyro-bias state.",
          paper_row=None, bench=Bench(step_us=0.5, native_us=0.1, vqf_ratio=0.5)),
)
"""Every estimator, in the order of the tables."""

ESTIMATORS: dict[str, type[Estimator]] = {}
"""key -> class."""
KEYS: tuple[str, ...] = ()
"""Every estimator's key."""
ATTITUDE_FILTERS: tuple[str, ...] = ()
"""The keys of the attitude filters with a measured vector of their own."""
FMU_NAMES: dict[str, str] = {}
"""key -> FMU model name."""
REFERENCES: dict[str, type[Estimator]] = {}
"""key -> reference class (the seed paper's filter), for the entries that have one."""
ENTRY: dict[str, Entry] = {}
CLASSES: tuple[type[Estimator], ...] = ()
"""Every estimator class, recommended and reference (each has a C twin)."""


def _derive() -> None:
    """The tables above, from REGISTRY: at import and after register (the dicts in place)."""
    global KEYS, ATTITUDE_FILTERS, CLASSES
    ESTIMATORS.clear()
    ESTIMATORS.update({e.key: e.cls for e in REGISTRY})
    FMU_NAMES.clear()
    FMU_NAMES.update({e.key: e.fmu for e in REGISTRY})
    REFERENCES.clear()
    REFERENCES.update({e.key: e.reference for e in REGISTRY if e.reference is not None})
    ENTRY.clear()
    ENTRY.update({e.key: e for e in REGISTRY})
    KEYS = tuple(ESTIMATORS)
    ATTITUDE_FILTERS = tuple(e.key for e in REGISTRY if e.attitude_filter)
    CLASSES = tuple(c for e in REGISTRY for c in (e.cls, e.reference) if c is not None)


_derive()


def register(entry: Entry) -> None:
    """Add an estimator to REGISTRY and to every table derived from it: for a test, or an
    estimator kept outside the project, before any other module of the project is imported
    (presets, the commands, the FMU builders and the testbenches take their lists from the
    registry when they are imported; fusion_core.REGISTRY, bound when the package was imported,
    keeps the tuple it had). ValueError for a key, FMU name or class already registered."""
    global REGISTRY
    taken = [what for what, clash in (("key", entry.key in ENTRY),
                                      ("FMU name", entry.fmu in FMU_NAMES.values()),
                                      ("class", entry.cls in CLASSES)) if clash]
    if taken:
        raise ValueError(f"estimator {entry.key!r} ({entry.cls.__name__}): its "
                         f"{' and '.join(taken)} is already registered")
    REGISTRY = (*REGISTRY, entry)
    _derive()


def estimator_class(key: str, params: dict[str, Any] | None = None) -> type[Estimator]:
    """The class a parameter set for estimator key runs: the reference where params say
    "filter": "paper", else the recommended class. ValueError for an unknown key or filter."""
    if key not in ENTRY:
        raise ValueError(f"unknown estimator {key!r}: allowed {keys_help()}")
    choice = (params or {}).get(FILTER, FILTERS[0])
    if choice not in FILTERS:
        raise ValueError(f"{key}: {FILTER}={choice!r} is not allowed: expected "
                         f"{' or '.join(repr(f) for f in FILTERS)}")
    entry = ENTRY[key]
    return entry.paper_class if choice == FILTERS[1] else entry.cls


def create(key: str, params: dict[str, Any] | None = None) -> Estimator:
    """A new estimator of key with params (their FILTER entry chooses the class)."""
    params = dict(params or {})
    cls = estimator_class(key, params)
    params.pop(FILTER, None)
    return cls(**params)


def key_of(cls: type[Estimator]) -> str:
    """The key of a recommended or reference class."""
    for e in REGISTRY:
        if cls is e.cls or cls is e.reference:
            return e.key
    raise ValueError(f"{cls.__name__} is not a registered estimator class")


def keys_help() -> str:
    """The estimator keys as a help string lists them: "cf, mgcf, kf, ukf, poskf"."""
    return ", ".join(KEYS)


__all__ = ["ATTITUDE_FILTERS", "CCF_ROW", "CLASSES", "ESTIMATORS", "FILTER", "FILTERS", "FMU_NAMES",
           "KEYS", "REFERENCES", "REGISTRY", "Bench", "Entry", "PaperRow", "create",
           "estimator_class", "key_of", "keys_help", "register"]
