"""An FMU state serialized in one process and restored in another continues bit for bit: every
model, each kind of FMU (native FMI 2.0 and 3.0, pythonfmu), both presets (the paper's filters
built with --preset paper) and options that change what the model derives from its parameters
(each schedule of the paper's mgcf, both gyro samplings, the sensor's DLPF and jitter), with
states taken while aligning, in motion and at rest (the position filter's stationary queue
holding samples).

Two processes, as a tool's checkpoint on disk or a co-simulation master's rollback would use
them: the first runs the recording and serializes states at several steps; the second
instantiates the FMU with its start values only, deserializes and sets each state, and steps on.
A state that held a pointer or an address of the first process (a schedule table would)
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

SAVE_AT = (5, 60, 150, 420, 700, 930)
"""Steps after which a state is taken: aligning, at rest with the position filter's stationary
queue holding samples, in motion, moving, at rest, late at rest."""
STEPS = 1000

CONFIGS: dict[str, dict[str, dict]] = {
    "ComplementaryFilter": {
        "recommended": {}, "mean": {"gyro_sampling": "mean"}, "paper": {},
        "paper-point": {"gyro_sampling": "point"},
    },
    "GainScheduledComplementaryFilter": {
        "recommended": {}, "no-prefilter": {"acc_lowpass": 0.0}, "paper": {},
        "paper-experimental": {"schedule": "experimental"},
        "paper-fixed-point": {"schedule": "fixed", "gyro_sampling": "point"},
    },
    "AngleBiasKalmanFilter": {
        "recommended": {}, "mean-no-rest": {"gyro_sampling": "mean", "rest_time": 0.0},
        "paper": {}, "paper-per-sample-r": {"R_loop_time": 0.0},
    },
    "UnscentedKalmanFilter": {
        "recommended": {}, "mean": {"gyro_sampling": "mean"}, "paper": {},
        "paper-no-norm-row": {"norm_noise": 0.0},
    },
    "PositionKalmanFilter": {
        "recommended": {}, "paper": {}, "paper-diagonal": {"qr_form": "diagonal"},
    },
    "ImuSensor": {
        "realistic": {}, "mean-dlpf-jitter": {"gyro_sampling": "mean", "dlpf_cfg": 3,
                                              "jitter": 1e-4, "calibration": "none"},
    },
    "ImuPlant": {"scenario-4": {"scenario": 4}},
}
"""Per model, the parameter sets a state must survive (by name; those named paper* on the FMU
built with --preset paper, the paper's filter)."""


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
        built_fmus, paper_fmus, fmu_recording, tmp_path, kind):
    jobs = []
    for name, configs in CONFIGS.items():
        for label, params in configs.items():
            fmus = paper_fmus if label.startswith("paper") else built_fmus
            path = fmus.path(name) if kind == "pythonfmu" else fmus.native(kind, name)
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
