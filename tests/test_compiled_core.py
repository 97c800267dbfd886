"""The mypyc-compiled fusion_core (fmu_src/compiled_core.py, issue 6): every listed module is an
extension module, and its outputs and states are bit for bit those of the pure-Python sources,
for every estimator with its defaults, its real-sensor options and the paper presets, over a
noisy recording with bad samples in it.

The compiled core runs in a subprocess (a process holds one fusion_core); this process runs the
pure-Python one that the editable install points at."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import KEYS, make, noisy_two_axis_recording

import fusion_core.base
from fmu_src.compiled_core import (
    COMPILED_MODULES,
    CompiledCoreError,
    build_compiled_core,
    is_compiled,
    resolve_core,
    shipped_files,
    toolchain_missing,
)
from fusion_core.presets import preset_params

REPO = Path(__file__).resolve().parents[1]

PARAM_SETS: dict[str, list[dict]] = {
    "cf": [{}, {"gyro_sampling": "mean"}, {"propagation": "quaternion"},
           {"acc_lowpass": 0.5}],
    "kf": [{}, {"gyro_sampling": "mean"}, {"propagation": "quaternion"},
           {"acc_lowpass": 0.5}, {"rest_time": 0.3}],
    "mgcf": [{}, {"gyro_sampling": "mean"}, {"schedule": "experimental"},
             {"schedule": "fixed", "w0": 0.0}, {"acc_lowpass": 0.5}, {"rest_time": 0.3}],
    "ukf": [{}, {"gyro_sampling": "mean"}, {"acc_gate": 0.1}, {"acc_lowpass": 0.5},
            {"rest_time": 0.3}, {"alpha": 0.5, "beta": 0.0}],
    "poskf": [{}, {"qr_form": "piecewise_jerk"}, {"qr_form": "diagonal"}, {"zupt": False}],
}
"""Defaults, each option that takes another code path, and (added below) the BROAD preset."""
CASES = [(key, params) for key in KEYS for params in [*PARAM_SETS[key],
                                                      preset_params("paper", key)]]

_SCRIPT = """
import json, sys
import numpy as np
sys.path.insert(0, {tests!r})
from helpers import make
import fusion_core.base
from fmu_src.compiled_core import is_compiled
cases, rec = json.loads(sys.argv[1]), np.load(sys.argv[2])
out = {{"compiled": is_compiled(fusion_core.base), "runs": []}}
for key, params in cases:
    est = make(key, **params)
    res = est.run(rec["acc"], rec["gyro"], rec["dt"])
    out["runs"].append({{"arrays": {{k: v.tolist() for k, v in res.items()}},
                        "state": est.get_state()}})
json.dump(out, sys.stdout)
"""


@pytest.fixture(scope="module")
def compiled_dir() -> Path:
    """The compiled core (built once and cached in build/compiled_core). Skipped only where the
    toolchain is missing (a machine with only Python and pip: no C compiler); with one, a
    build failure fails the tests."""
    missing = toolchain_missing()
    if missing:
        pytest.skip(f"{missing}: the FMUs ship the pure-Python core")
    return build_compiled_core()


def _recording_with_bad_samples(tmp_path: Path) -> Path:
    rec = noisy_two_axis_recording(6.0, seed=3)
    acc, gyro, dt = rec["acc_meas"].copy(), rec["gyro_meas"].copy(), rec["dt"].copy()
    acc[50] = np.nan
    gyro[120, 1] = np.inf
    dt[200] = 0.0
    gyro[300] = 2000.0  # above max_rate
    dt[400] = 5.0  # above max_dt
    path = tmp_path / "rec.npz"
    np.savez(path, acc=acc, gyro=gyro, dt=dt)
    return path


def _run_compiled(compiled_dir: Path, cases: list, rec: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(compiled_dir), str(REPO)])}
    script = _SCRIPT.format(tests=str(REPO / "tests"))
    proc = subprocess.run(
        [sys.executable, "-c", script, json.dumps(cases), str(rec)],
        cwd=compiled_dir, env=env, capture_output=True, text=True, timeout=600, check=False,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout)


def test_every_listed_module_is_an_extension_module_and_the_rest_stays_python(
    compiled_dir: Path,
) -> None:
    names = ", ".join(f"fusion_core.{m}" for m in (*COMPILED_MODULES, "presets", "sensor"))
    code = (f"import importlib; mods = [importlib.import_module(n) for n in '{names}'.split(', ')]"
            "; print(' '.join(m.__file__ for m in mods))")
    proc = subprocess.run(
        [sys.executable, "-c", code], cwd=compiled_dir, capture_output=True, text=True,
        env={**os.environ, "PYTHONPATH": str(compiled_dir)}, timeout=120, check=False,
    )
    assert proc.returncode == 0, proc.stderr
    files = proc.stdout.split()
    n = len(COMPILED_MODULES)
    assert all(f.startswith(str(compiled_dir)) for f in files)
    assert all(f.endswith(".so") or f.endswith(".pyd") for f in files[:n]), files[:n]
    assert all(f.endswith(".py") for f in files[n:]), files[n:]
    first, *runtime = (p.name for p in shipped_files(compiled_dir))
    assert first == "fusion_core"
    assert runtime and all("__mypyc" in name for name in runtime)


def test_this_process_runs_the_pure_python_core() -> None:
    """The reference side of the comparison below must really be the sources."""
    assert not is_compiled(fusion_core.base)


def test_compiled_outputs_and_states_are_bit_identical(compiled_dir: Path, tmp_path: Path) -> None:
    rec_path = _recording_with_bad_samples(tmp_path)
    rec = np.load(rec_path)
    got = _run_compiled(compiled_dir, CASES, rec_path)
    assert got["compiled"] is True
    for (key, params), run in zip(CASES, got["runs"], strict=True):
        est = make(key, **params)
        want = est.run(rec["acc"], rec["gyro"], rec["dt"])
        assert want["rejected"].sum() == 5, (key, params)
        for name, values in want.items():
            have = np.asarray(run["arrays"][name], dtype=values.dtype)
            # exact equality: the same IEEE operations in the same order (NaN never occurs)
            assert np.array_equal(have, values), (key, params, name)
        assert run["state"] == json.loads(json.dumps(est.get_state())), (key, params)


def test_an_unknown_core_choice_names_the_allowed_ones() -> None:
    with pytest.raises(ValueError, match="auto, compiled, python"):
        resolve_core("fast")


def test_python_core_needs_no_compiler() -> None:
    assert resolve_core("python") is None


def test_a_missing_compiler_is_reported_and_auto_falls_back(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
) -> None:
    """With no C compiler: 'compiled' says why, 'auto' warns and ships the pure-Python core."""
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    assert toolchain_missing() == "no C compiler ('" + str(tmp_path / "no-such-cc") + "' not found)"
    with pytest.raises(CompiledCoreError, match="no C compiler"):
        resolve_core("compiled", cache=tmp_path / "cache")
    assert resolve_core("auto", cache=tmp_path / "cache") is None
    assert "using the pure-Python fusion_core: no C compiler" in capsys.readouterr().err
    assert not (tmp_path / "cache").exists()


def test_a_compiler_that_fails_makes_mypyc_fail_with_its_output(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A compiler that exists but fails: the error carries the tail of mypyc's output."""
    if toolchain_missing():
        pytest.skip(f"{toolchain_missing()}")
    monkeypatch.setenv("CC", "false")  # found on PATH, fails every compilation
    with pytest.raises(CompiledCoreError, match="mypyc failed"):
        build_compiled_core(cache=tmp_path / "cache")
    assert not [p for p in (tmp_path / "cache").iterdir() if (p / "COMPLETE").exists()]
