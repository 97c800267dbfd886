"""Several FMU instances in one process stay independent; instantiate/free does not leak."""

from __future__ import annotations

import gc
import os
from collections.abc import Callable

import numpy as np
import pytest
from conftest import ESTIMATOR_FMUS

from fmu_src.host import FmuInstance
from fusion_core import synthetic

INSTANCES = (
    ("ComplementaryFilter", "cf", {}, 1),
    ("ComplementaryFilter", "cf", {"tau": 0.3}, 2),
    ("GainScheduledComplementaryFilter", "mgcf", {}, 3),
    ("AngleBiasKalmanFilter", "kf", {}, 4),
    ("AngleBiasKalmanFilter", "kf", {"R_measure": 3e-5, "gyro_sampling": "mean"}, 5),
    ("UnscentedKalmanFilter", "ukf", {}, 6),
    ("PositionKalmanFilter", "poskf", {}, 7),
    ("PositionKalmanFilter", "poskf", {"zupt_window": 0.5}, 8),
)
"""8 instances: all five kinds, three of them twice, each with its own parameters and seed."""
N_SAMPLES = 500
MEMORY_CYCLES = 200
MEMORY_LIMIT = 5 * 2**20
"""RSS growth allowed over MEMORY_CYCLES instantiate/free cycles [bytes] (the issue's figure)."""


def record(seed: int) -> dict:
    noise = synthetic.ImuNoise(gyro_bias=(0.01, -0.006, 0.004))
    return synthetic.record(
        synthetic.demo_motion(), (N_SAMPLES - 1) / 100.0, 100.0, noise=noise, seed=seed
    )


def test_eight_instances_in_one_process_match_separate_runs(built_fmus, fusion_core_run):
    recordings = [record(seed) for *_, seed in INSTANCES]
    # Separate runs: one instance alive at a time.
    separate = []
    for (name, _, params, seed), rec in zip(INSTANCES, recordings, strict=True):
        with FmuInstance(built_fmus.path(name), f"alone{seed}", params) as fmu:
            separate.append(fmu.run_samples(rec["acc_meas"], rec["gyro_meas"], rec["dt"]))
    # Together: all eight alive, stepped in lockstep, sample by sample.
    fmus = [
        FmuInstance(built_fmus.path(name), f"together{seed}", params)
        for name, _, params, seed in INSTANCES
    ]
    try:
        rows = [[] for _ in fmus]
        for i in range(N_SAMPLES):
            for fmu, rec, out in zip(fmus, recordings, rows, strict=True):
                out.append(fmu.run_samples(rec["acc_meas"][i:i + 1], rec["gyro_meas"][i:i + 1],
                                           rec["dt"][i:i + 1]))
    finally:
        for fmu in fmus:
            fmu.close()
    for (name, key, params, seed), rec, alone, parts in zip(
        INSTANCES, recordings, separate, rows, strict=True
    ):
        together = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
        for k in alone:
            assert np.array_equal(together[k], alone[k]), f"{name} seed {seed}: {k}"
        ref = fusion_core_run(key, rec["acc_meas"], rec["gyro_meas"], rec["dt"], **params)
        assert np.array_equal(together["roll"], ref["roll"]), f"{name} seed {seed}"
        assert np.array_equal(together["bias"], ref["bias"]), f"{name} seed {seed}"


def resident_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def rss_growth(cycle: Callable[[int], None]) -> int:
    """Resident memory [bytes] that MEMORY_CYCLES calls of cycle(i) add, after 10 warm-up calls
    (imports, first-time allocations)."""
    for i in range(10):
        cycle(i)
    gc.collect()
    before = resident_bytes()
    for i in range(MEMORY_CYCLES):
        cycle(i)
    gc.collect()
    return resident_bytes() - before


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="needs Linux /proc")
def test_instantiate_free_cycles_do_not_grow_memory(built_fmus, tmp_path):
    from fmpy import extract

    rec = record(1)
    args = rec["acc_meas"][:10], rec["gyro_meas"][:10], rec["dt"][:10]
    unzip = {
        name: extract(str(built_fmus.path(name)), str(tmp_path / name))
        for name in ("AngleBiasKalmanFilter", "UnscentedKalmanFilter")
    }

    def cycle(i: int) -> None:
        name = "AngleBiasKalmanFilter" if i % 2 else "UnscentedKalmanFilter"
        with FmuInstance(built_fmus.path(name), f"cycle{i}", unzip_dir=unzip[name]) as fmu:
            fmu.run_samples(*args)

    growth = rss_growth(cycle)
    print(f"RSS growth over {MEMORY_CYCLES} instantiate/free cycles: {growth / 2**20:.2f} MiB")
    assert growth < MEMORY_LIMIT


@pytest.mark.slow
@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="needs Linux /proc")
@pytest.mark.parametrize("name", [*ESTIMATOR_FMUS, "ImuPlant", "ImuSensor"])
def test_200_instantiate_free_cycles_of_each_fmu_grow_its_memory_by_less_than_5_mb(
    built_fmus, tmp_path, name: str
) -> None:
    """Each FMU on its own: MEMORY_CYCLES instantiate / initialise / 10 doSteps / terminate /
    free cycles in one process (the FMU extracted once, as an importer caches it)."""
    from fmpy import extract

    unzip = extract(str(built_fmus.path(name)), str(tmp_path / name))

    def cycle(i: int) -> None:
        with FmuInstance(built_fmus.path(name), f"cycle{i}", unzip_dir=unzip) as fmu:
            for k in range(10):
                fmu.fmu.doStep(k * 0.01, 0.01)

    growth = rss_growth(cycle)
    print(f"{name}: RSS growth over {MEMORY_CYCLES} cycles: {growth / 2**20:.2f} MiB")
    assert growth < MEMORY_LIMIT
