"""The wheel carries the compiled twin and the native FMUs: built here, installed into a fresh
virtual environment and used with no C compiler on the PATH; the sdist builds a pure wheel
where no compiler exists."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest
from conftest import locked

from fmu_src.names import model_names
from fusion_core import native

REPO = Path(__file__).resolve().parents[1]

pytestmark = [
    pytest.mark.heavy,
    pytest.mark.xdist_group("wheel"),  # one worker builds the dists once (`--dist loadgroup`)
    pytest.mark.skipif(native.compiler() is None,
                       reason="building the platform wheel needs a C compiler"),
]

USE = """
import shutil, sys
import numpy as np
import fusion_core
from fusion_core import native
assert shutil.which("cc") is None and shutil.which("gcc") is None, "a compiler is visible"
assert native.available(), native.reason()
assert native.library_path().parent.name == "native", native.library_path()
assert native.library.stream_reason() is None, native.library.stream_reason()
rng = np.random.default_rng(0)
acc = np.array([0.0, 0.0, 9.81]) + 0.05 * rng.standard_normal((400, 3))
gyro = 0.01 * rng.standard_normal((400, 3))
dt = np.full(400, 0.01)
for key, cls in fusion_core.ESTIMATORS.items():
    out = cls().run(acc, gyro, dt, backend="native")
    stream, python = cls().stream(), cls()
    for a, g, h in zip(acc.tolist(), gyro.tolist(), dt.tolist()):
        assert stream.step(a, g, h) == python.step(a, g, h), key
    assert float(out["roll"][-1]) == python.last.roll, key
print("native run and stream:", ", ".join(fusion_core.ESTIMATORS))
"""


def _build(args: list[str], env: dict[str, str], cwd: Path) -> None:
    proc = subprocess.run([sys.executable, "-m", "build", "--no-isolation", *args],
                          cwd=cwd, env=env, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]


def _without_compiler(bin_dir: Path) -> dict[str, str]:
    """An environment whose PATH holds only bin_dir (no cc, gcc or clang) and no CC."""
    env = {k: v for k, v in os.environ.items() if k not in ("CC", "PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = str(bin_dir)
    return env


@pytest.fixture(scope="module")
def dists(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sdist, and the platform wheel built from it, with this checkout's compiler."""
    if shutil.which("pyproject-build") is None and _missing("build"):
        pytest.skip("the build frontend is not installed (the test extra has it)")
    out = tmp_path_factory.mktemp("dist")
    # one sdist build in this checkout at a time: the build writes its egg-info and a staging
    # folder into the checkout, which another worker's build would tar half-removed
    (REPO / "build").mkdir(exist_ok=True)
    with locked(REPO / "build" / ".sdist.lock"):
        _build(["--outdir", str(out), str(REPO)], dict(os.environ), REPO)
    return out


def _missing(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module) is None


def test_the_wheel_carries_the_library_and_both_presets_native_fmus(dists: Path) -> None:
    (wheel,) = dists.glob("*.whl")
    assert wheel.name.endswith(".whl") and "-cp310-abi3-" in wheel.name
    assert not wheel.name.endswith("-any.whl"), wheel.name
    names = zipfile.ZipFile(wheel).namelist()
    assert "fusion_core/native/libfusion_core.so" in names
    assert "fusion_core/native/_fc_stream.abi3.so" in names  # stream()'s entry point
    assert "fusion_core/native/fc_kf.h" in names  # the binding's declarations
    assert any(n.startswith("fusion_core/native/_fc_ffi_") and n.endswith(".py")
               for n in names)  # ... as cffi's module, loaded without parsing them
    for preset in ("recommended", "paper"):
        for version in ("fmi2", "fmi3"):
            assert f"fmu_src/native/prebuilt/{preset}/{version}/UnscentedKalmanFilter.fmu" in names


def test_installed_without_a_compiler_the_twin_runs_and_native_fmus_build(
        dists: Path, tmp_path: Path) -> None:
    (wheel,) = dists.glob("*.whl")
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=False)  # this environment's pip installs into it (--python)
    bin_dir = env_dir / "bin"
    proc = subprocess.run([sys.executable, "-m", "pip", "--python", str(bin_dir / "python"),
                           "install", "--quiet", str(wheel), "fmpy"],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    env = _without_compiler(bin_dir) | {"HOME": str(tmp_path),
                                        "FUSION_CORE_NATIVE_CACHE": str(tmp_path / "cache")}
    proc = subprocess.run([str(bin_dir / "python"), "-c", USE], cwd=tmp_path, env=env,
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert not (tmp_path / "cache").exists()  # nothing was built: the wheel's library served
    proc = subprocess.run([str(bin_dir / "imu-fusion"), "build-fmus", "--kind", "native",
                           "--preset", "paper", "--out", str(tmp_path / "fmus")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    built = sorted(p.name for p in (tmp_path / "fmus" / "native" / "fmi3").glob("*.fmu"))
    assert built == sorted(f"{name}.fmu" for name in model_names()), built
    mine = tmp_path / "mine.json"  # a preset of one's own is compiled in: it needs a compiler
    mine.write_text('{"kf": {"Q_angle": 0.002}}')
    proc = subprocess.run([str(bin_dir / "imu-fusion"), "build-fmus", "--kind", "native",
                           "--only", "AngleBiasKalmanFilter", "--preset", str(mine),
                           "--out", str(tmp_path / "mine")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, check=False)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "no C compiler found" in proc.stdout + proc.stderr


def test_the_sdist_builds_a_pure_wheel_where_no_compiler_exists(
        dists: Path, tmp_path: Path) -> None:
    (sdist,) = dists.glob("*.tar.gz")
    with tarfile.open(sdist) as tar:
        tar.extractall(tmp_path, filter="data")
    (source,) = (p for p in tmp_path.iterdir() if p.is_dir())
    out = tmp_path / "out"
    _build(["--wheel", "--outdir", str(out), str(source)],
           _without_compiler(Path(sys.executable).parent), source)
    (wheel,) = out.glob("*.whl")
    assert wheel.name.endswith("-py3-none-any.whl"), wheel.name
    names = zipfile.ZipFile(wheel).namelist()
    assert "fusion_core/native/libfusion_core.so" not in names
    assert "fusion_core/native/fc_core.c" in names  # the twin builds where a compiler appears
