"""An FMU state serialized in one process and restored in another continues bit for bit: every
model, each kind of FMU (native FMI 2.0 and 3.0, pythonfmu), every preset and every option that
changes what the model derives from its parameters (each mgcf schedule, both propagations, both
tilt axes, both gyro samplings, the sensor's DLPF and jitter), with states taken while aligning,
in motion and at rest (the position filter's stationary queue holding samples).

Two processes, as a tool's checkpoint on disk or a co-simulation master's rollback would use
them: the first runs the recording and serializes states at several steps; the second
instantiates the FMU with its start values only, deserializes and sets each state, and steps on.
A state that held a pointer or an address of the first process (the mgcf's schedule table did)
crashes the second; one that missed a field, or took a derived value stale, continues
differently."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from fusion_core.position import PositionKalmanFilter
from fusion_core.presets import PAPER

SAVE_AT = (5, 60, 150, 420, 700, 930)
"""Steps after which a state is taken: aligning, at rest with the position filter's stationary
queue holding samples, in motion, moving, at rest, late at rest."""
STEPS = 1000

CONFIGS: dict[str, dict[str, dict]] = {
    "ComplementaryFilter": {
        "recommended": {}, "paper": PAPER["cf"], "euler": {"propagation": "euler"},
    },
    "GainScheduledComplementaryFilter": {
        "recommended": {}, "paper": PAPER["mgcf"], "experimental": {"schedule": "experimental"},
        "simulation-point": {"schedule": "simulation", "gyro_sampling": "point"},
    },
    "AngleBiasKalmanFilter": {
        "recommended": {}, "paper": PAPER["kf"], "quaternion-body": {"tilt_axes": "body"},
        "euler-face-mean": {"propagation": "euler", "tilt_axes": "nearest_face",
                            "gyro_sampling": "mean"},
    },
    "UnscentedKalmanFilter": {
        "recommended": {}, "paper": PAPER["ukf"], "mean": {"gyro_sampling": "mean"},
    },
    "PositionKalmanFilter": {
        "recommended": {}, "paper": PAPER["poskf"],
        "always-tilt": {"tilt_update": "always", "attitude": "tilt_stage"},
    },
    "ImuSensor": {
        "realistic": {}, "mean-dlpf-jitter": {"gyro_sampling": "mean", "dlpf_cfg": 3,
                                              "jitter": 1e-4, "calibration": "none"},
    },
    "ImuPlant": {"scenario-4": {"scenario": 4}},
}
"""Per model, the parameter sets a state must survive (by name)."""


def _inputs(name: str, rec: dict) -> dict[str, list[float]]:
    """The model's inputs over the recording, by variable name."""
    if name == "ImuPlant":
        return {}
    if name == "ImuSensor":
        return {**{f"omega_{a}": rec["gyro_meas"][:, i].tolist() for i, a in enumerate("xyz")},
                **{f"f_{a}": rec["acc_meas"][:, i].tolist() for i, a in enumerate("xyz")}}
    return {**{f"acc_{a}": rec["acc_meas"][:, i].tolist() for i, a in enumerate("xyz")},
            **{f"gyro_{a}": rec["gyro_meas"][:, i].tolist() for i, a in enumerate("xyz")},
            "dt": rec["dt"].tolist()}


def _run(mode: str, jobs_file: Path) -> None:
    proc = subprocess.run([sys.executable, str(REPO / "tests" / "fmu_state_processes.py"), mode,
                           str(jobs_file)], cwd=REPO / "tests", capture_output=True, text=True,
                          timeout=900, check=False)
    assert proc.returncode == 0, f"{mode} process ended with {proc.returncode}:\n{proc.stderr}"


@pytest.mark.parametrize("kind", ["fmi2", "fmi3", "pythonfmu"])
def test_a_state_saved_in_one_process_continues_bit_for_bit_in_another(
        built_fmus, fmu_recording, tmp_path, kind):
    jobs = []
    for name, configs in CONFIGS.items():
        path = built_fmus.path(name) if kind == "pythonfmu" else built_fmus.native(kind, name)
        for label, params in configs.items():
            jobs.append({"name": f"{name}-{label}", "fmu": str(path), "params": params,
                         "inputs": _inputs(name, fmu_recording), "steps": STEPS,
                         "save_at": list(SAVE_AT)})
    jobs_file = tmp_path / "jobs.json"
    jobs_file.write_text(json.dumps(jobs))
    _run("save", jobs_file)
    _run("restore", jobs_file)
    for job in jobs:
        reference = json.loads((tmp_path / f"{job['name']}.save.json").read_text())
        restored = json.loads((tmp_path / f"{job['name']}.restore.json").read_text())
        for at in SAVE_AT:
            assert restored[str(at)] == reference[at + 1:], (job["name"], at)


def test_the_position_filters_queue_holds_samples_at_a_saved_step(fmu_recording):
    """The states above include one taken mid-rest, with the stationary queue not empty."""
    f = PositionKalmanFilter()
    held = {}
    for k in range(STEPS):
        f.step(fmu_recording["acc_meas"][k], fmu_recording["gyro_meas"][k],
               fmu_recording["dt"][k])
        if k in SAVE_AT:
            held[k] = len(f.pending)
    assert any(n > 0 for n in held.values()), held
    assert np.isfinite(f.last.roll)
