"""An FMU runs on its own: its resources carry fusion_core, the project need not be installed."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig

import numpy as np

from fmu_src.host import INPUTS

HOST_SCRIPT = r"""
import json, sys
for name in ("fusion_core", "fmu_src"):
    try:
        __import__(name)
    except ImportError:
        pass
    else:
        raise SystemExit(f"{name} is importable outside the FMU: {sys.modules[name].__file__}")
import numpy as np
from fmpy import extract, simulate_fmu

fmu, data_file, unzip, out_file = sys.argv[1:5]
data = np.load(data_file)
names = [n for n in data.files if n != "time"]
signals = np.rec.fromarrays([data["time"]] + [data[n] for n in names], names=["time"] + names)
extract(fmu, unzip)
n = len(data["time"])
result = simulate_fmu(unzip, input=signals, output=["roll", "pitch", "bias_x", "bias_y",
                      "bias_z", "invalid_samples"], output_interval=0.01, stop_time=n * 0.01)
np.save(out_file, np.column_stack([result[k] for k in result.dtype.names]))
print(json.dumps({"fusion_core": sys.modules["fusion_core"].__file__,
                  "sys_path_0": sys.path[0], "fmu_src": sys.modules["fmu_src"].__file__}))
"""

IMU = ("acc_meas", "gyro_meas", "dt")
"""The keys of a synthetic.record() recording that make up the IMU samples."""


def test_fmu_runs_with_the_project_off_sys_path(fmu_path, fmu_key, fmu_recording, fusion_core_run,
                                                tmp_path):
    n = 300
    acc, gyro, dt = (fmu_recording[k][:n] for k in IMU)
    # Sample k is applied at t = k * 0.01 (fmpy sets inputs at the start of each step).
    columns = {"time": np.arange(n) * 0.01}
    columns.update(zip(INPUTS, [*acc.T, *gyro.T, dt], strict=True))
    np.savez(tmp_path / "samples.npz", **columns)
    workdir = tmp_path / "empty"
    workdir.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP")}
    # -S: no site module, so neither the editable install's .pth finder nor the repository;
    # only the third-party packages (fmpy, numpy, scipy) on PYTHONPATH.
    env["PYTHONPATH"] = sysconfig.get_paths()["purelib"]
    unzip = tmp_path / "unzipped"
    proc = subprocess.run(
        [sys.executable, "-S", "-c", HOST_SCRIPT, str(fmu_path), str(tmp_path / "samples.npz"),
         str(unzip), str(tmp_path / "out.npy")],
        cwd=workdir, env=env, capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    where = json.loads(proc.stdout.strip().splitlines()[-1])
    assert where["fusion_core"] == str(unzip / "resources" / "fusion_core" / "__init__.py")
    assert where["fmu_src"] == str(unzip / "resources" / "fmu_src" / "__init__.py")
    out = np.load(tmp_path / "out.npy")
    ref = fusion_core_run(fmu_key, acc, gyro, dt)
    # Row 0 is t = 0 (start values); row k + 1, at t = (k + 1) * 0.01, is sample k's estimate.
    assert out.shape == (n + 1, 7)
    assert np.max(np.abs(out[1:, 1] - ref["roll"])) <= 1e-12
    assert np.max(np.abs(out[1:, 2] - ref["pitch"])) <= 1e-12
    assert np.max(np.abs(out[1:, 3:6] - ref["bias"])) <= 1e-12
    assert np.all(out[:, 6] == 0)
