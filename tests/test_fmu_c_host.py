"""A C host (tests/fmu_host/fmu_host.c) runs the estimator FMUs' linux64 binaries like a
Modelica tool or Simulink on Linux: libpython preloaded, fmi2Instantiate ... fmi2DoStep ...
fmi2FreeInstance, and gets exactly the outputs of the fmpy run."""

from __future__ import annotations

import subprocess
import sys
import sysconfig
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy import extract

from fmu_src.host import INPUTS, FmuInstance
from fusion_core.native import compiler

HOST_SOURCE = Path(__file__).parent / "fmu_host" / "fmu_host.c"
N_STEPS = 500
REALS = ("roll", "pitch", "bias_x", "bias_y", "bias_z")


def shared_libpython() -> Path | None:
    """The interpreter's shared library, or None when Python is linked statically."""
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        return None
    libdir = Path(sysconfig.get_config_var("LIBDIR") or "")
    for name in (sysconfig.get_config_var("INSTSONAME"), sysconfig.get_config_var("LDLIBRARY")):
        if name and (libdir / name).is_file():
            return libdir / name
    return None


COMPILER = compiler()  # the one the C twin is built with: $CC, else cc, gcc or clang
LIBPYTHON = shared_libpython()
pytestmark = [
    pytest.mark.skipif(COMPILER is None,
                       reason="no C compiler (set CC, or install cc, gcc or clang)"),
    pytest.mark.skipif(
        LIBPYTHON is None,
        reason=f"no shared libpython for {sys.version.split()[0]}: a pythonfmu FMU needs one in "
        "a C host",
    ),
]


@pytest.fixture(scope="module")
def host(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """fmu_host.c compiled with the system C compiler and fmpy's FMI 2.0 headers."""
    exe = tmp_path_factory.mktemp("c_host") / "fmu_host"
    include = Path(fmpy.__file__).parent / "c-code"
    subprocess.run([COMPILER, "-std=c99", "-Wall", "-Wextra", "-Werror", "-O1", "-I",
                    str(include), "-o", str(exe), str(HOST_SOURCE), "-ldl"], check=True)
    return exe


def host_environment(preload: bool = True) -> dict[str, str]:
    """What a tool started outside any Python environment needs: libpython preloaded,
    PYTHONHOME (the interpreter's prefix, for its standard library) and PYTHONPATH with numpy
    and scipy (the venv's site-packages, not the repository: fusion_core comes from the FMU)."""
    env = {
        "PATH": "/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "PYTHONHOME": sys.base_prefix,
        "PYTHONPATH": sysconfig.get_paths()["purelib"],
    }
    if preload:
        env["LD_PRELOAD"] = str(LIBPYTHON)
    return env


def run_host(host: Path, fmu: Path, workdir: Path, samples: np.ndarray, *extra: str,
             env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    unzip = Path(extract(str(fmu), str(workdir / "unzipped")))
    md = fmpy.read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    binary = unzip / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    lines = "\n".join(" ".join(f"{x:.17g}" for x in row) for row in samples) + "\n"
    return subprocess.run(
        [str(host), str(binary), (unzip / "resources").as_uri(), md.guid,
         ",".join(str(vr[n]) for n in INPUTS), ",".join(str(vr[n]) for n in REALS),
         str(vr["invalid_samples"]), *extra],
        input=lines, capture_output=True, text=True, cwd=workdir,
        env=host_environment() if env is None else env, timeout=300,
    )


def samples_of(fmu_recording: dict) -> np.ndarray:
    acc, gyro, dt = (fmu_recording[k][:N_STEPS] for k in ("acc_meas", "gyro_meas", "dt"))
    return np.column_stack([acc, gyro, dt])


def test_c_host_outputs_equal_the_fmpy_run(host, fmu_path, fmu_recording, tmp_path):
    samples = samples_of(fmu_recording)
    samples[100, 0] = np.nan  # and a rejected sample on the way
    proc = run_host(host, fmu_path, tmp_path, samples)
    # Every fmi2 call returned fmi2OK up to and including fmi2FreeInstance:
    assert f"{N_STEPS} steps" in proc.stderr, proc.stderr
    assert "rejected" in proc.stderr  # the warning came through the FMI logger callback
    got = np.loadtxt(proc.stdout.splitlines())
    with FmuInstance(fmu_path) as fmu:
        ref = fmu.run_samples(samples[:, 0:3], samples[:, 3:6], samples[:, 6])
    assert got.shape == (N_STEPS, len(REALS) + 1)
    expected = np.column_stack([ref["roll"], ref["pitch"], ref["bias"], ref["invalid_samples"]])
    assert np.array_equal(got, expected)


def test_c_host_fails_to_load_without_libpython(host, built_fmus, fmu_recording, tmp_path):
    proc = run_host(host, built_fmus.path("AngleBiasKalmanFilter"), tmp_path,
                    samples_of(fmu_recording)[:5], env=host_environment(preload=False))
    assert proc.returncode == 2
    assert "undefined symbol: _Py" in proc.stderr or "undefined symbol: Py" in proc.stderr


def test_c_host_exits_cleanly_after_finalizing_python(host, built_fmus, fmu_recording, tmp_path):
    proc = run_host(host, built_fmus.path("AngleBiasKalmanFilter"), tmp_path,
                    samples_of(fmu_recording), "--finalize-python")
    assert proc.returncode == 0, proc.stderr
