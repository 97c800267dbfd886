"""What a benchmark run measures and how long it may take: the full and the --quick settings."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

MIN_SAMPLES = 200_000
"""The native section's batch runs (the C twin, VQF's C++ batch): at least this many samples."""
PYTHON_SAMPLES = 20_000
"""The native section's Python core: this many samples."""
CAMPAIGN_PASSES = 2
"""Campaigns per worker count, interleaved (2, 1, 2, 1 workers); the fastest of each counts."""

EVERY_ESTIMATOR: tuple[str, ...] = ()
"""A config's list of estimators that names none: every estimator of fusion_core.registry
(estimator_keys). The registry is read when the suite runs, not here: the command line chooses
its CPU core before any fusion_core module is imported."""


def estimator_keys(keys: tuple[str, ...] = EVERY_ESTIMATOR) -> tuple[str, ...]:
    """keys, or every registry estimator's where keys is EVERY_ESTIMATOR (imports fusion_core)."""
    from fusion_core.registry import KEYS

    return keys or KEYS


@dataclass(frozen=True)
class BenchConfig:
    """Sizes and repeats of one run.

    duration_s: length of the 100 Hz recording the per-sample and FMU timings loop over;
    repeats: timed passes over it (the medians are reported); fmu_dir: prebuilt FMUs (None:
    build them into a temporary folder with build_fmu.py); testbench_s: simulated seconds per
    testbench rate, for each of testbench_estimators; scaling_sizes: sample counts of the `run`
    scaling test; peers: time the peer filters too; sections: which parts to run (all);
    native_samples, python_samples: the native section's batch lengths (the C twin and VQF, the
    Python core); campaign_passes: campaigns per worker count in the campaign section.
    """

    duration_s: float = 60.0
    repeats: int = 7
    fmu_dir: Path | None = None
    testbench_s: dict[float, float] = field(default_factory=lambda: {100.0: 20.0, 1000.0: 5.0})
    testbench_repeats: int = 3
    testbench_estimators: tuple[str, ...] = EVERY_ESTIMATOR
    scaling_sizes: tuple[int, ...] = (1_000, 10_000, 100_000, 1_000_000)
    scaling_estimators: tuple[str, ...] = EVERY_ESTIMATOR
    long_rows: int = 2_000_000
    peers: bool = True
    sections: tuple[str, ...] = ("per_sample", "fmu", "testbench", "native", "campaign",
                                 "scaling", "estimate_2e6")
    campaign_seeds: int = 300
    campaign_passes: int = CAMPAIGN_PASSES
    native_samples: int = MIN_SAMPLES
    python_samples: int = PYTHON_SAMPLES
    quick: bool = False

    @classmethod
    def quick_config(cls, fmu_dir: Path | None = None) -> BenchConfig:
        """The --quick run: shorter recording, fewer repeats, scaling to 1e5 samples (under
        2 minutes on a 2-core machine)."""
        return cls(
            duration_s=20.0,
            repeats=3,
            fmu_dir=fmu_dir,
            testbench_s={100.0: 5.0, 1000.0: 1.0},
            testbench_repeats=1,
            scaling_sizes=(1_000, 10_000, 100_000),
            long_rows=200_000,
            campaign_seeds=60,
            quick=True,
        )
