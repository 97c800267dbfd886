"""FMU test fixtures: the FMUs are built once per test run, by the real command line.

`python build_fmu.py --out <run tmp>` runs in a subprocess (the build imports the slave
modules; the test process then loads them only from the FMUs); under pytest-xdist the workers
share one build. Any test with an `fmu_name` argument runs once per estimator FMU.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from fmu_src.names import estimator_fmus

REPO = Path(__file__).resolve().parents[1]

ESTIMATOR_FMUS: dict[str, str] = estimator_fmus()
"""The estimator FMUs and the fusion_core.ESTIMATORS key each one packages (the registry's)."""


@dataclass(frozen=True)
class BuiltFmus:
    """The outcome of the session's `python build_fmu.py` run."""

    directory: Path
    returncode: int
    output: str

    def path(self, name: str) -> Path:
        """The FMU called name; the test fails (with the build table) if it was not built."""
        path = self.directory / f"{name}.fmu"
        if not path.is_file():
            pytest.fail(f"{name}.fmu was not built; build_fmu.py said:\n{self.output}")
        return path

    def native(self, version: str, name: str) -> Path:
        """The native FMU called name of FMI version "fmi2" or "fmi3": skipped with the reason
        where there is no C compiler (build_fmu.py then builds the pythonfmu FMUs only), a
        failure where there is one and the FMU was not built."""
        from fusion_core.native import compiler

        if compiler() is None:
            pytest.skip("no C compiler (set CC, or install cc, gcc or clang): no native FMUs")
        path = self.directory / "native" / version / f"{name}.fmu"
        if not path.is_file():
            pytest.fail(f"native {version} {name}.fmu was not built; build_fmu.py said:\n"
                        f"{self.output}")
        return path


FMU_BUILDING_FILES = ("test_fmu_state_fuzz.py", "test_fmu_state_processes.py", "test_fmu_c_host.py",
                      "test_native_fmu.py", "test_fmu_build.py")
"""Test files that build FMUs of their own (beside the session's built_fmus)."""


LONG_FIRST = ("test_wheel.py", "test_fmu_state_fuzz.py", "test_docs_figures.py")
"""Files whose tests run for minutes (the wheel builds, the state fuzz, the figures that run
the battery): collected first, so that pytest-xdist starts them first instead of leaving one
worker on them while the other has finished."""


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark `fmu` every test that needs built FMUs: `make test-fast` leaves them out. The
    LONG_FIRST files go to the front (their own order kept)."""
    for item in items:
        if ({"built_fmus", "paper_fmus"} & set(getattr(item, "fixturenames", ()))
                or item.path.name in FMU_BUILDING_FILES):
            item.add_marker(pytest.mark.fmu)
    first = {name: i for i, name in enumerate(LONG_FIRST)}
    items.sort(key=lambda item: first.get(item.path.name, len(first)))


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "fmu_name" in metafunc.fixturenames:
        metafunc.parametrize("fmu_name", list(ESTIMATOR_FMUS))


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """An exclusive lock on path across processes (none where fcntl is missing)."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    with open(path, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _build_once(tmp_path_factory: pytest.TempPathFactory, name: str, *args: str) -> BuiltFmus:
    """`python build_fmu.py --out <folder> ARGS`, run once for the whole test run: the
    pytest-xdist workers' temporary roots share a parent, where the first worker builds under
    a lock and the others take its folder and output."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent
    out, record = root / name, root / f"{name}.json"
    with locked(root / f"{name}.lock"):
        if not record.is_file():
            shutil.rmtree(out, ignore_errors=True)
            out.mkdir(parents=True)
            proc = subprocess.run([sys.executable, "build_fmu.py", "--out", str(out), *args],
                                  cwd=REPO, capture_output=True, text=True, timeout=600)
            record.write_text(json.dumps({"returncode": proc.returncode,
                                          "output": proc.stdout + proc.stderr}))
        done = json.loads(record.read_text())
    return BuiltFmus(out, done["returncode"], done["output"])


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory: pytest.TempPathFactory) -> BuiltFmus:
    """Every FMU, built once for the test run."""
    return _build_once(tmp_path_factory, "fmus")


@pytest.fixture(scope="session")
def paper_fmus(tmp_path_factory: pytest.TempPathFactory) -> BuiltFmus:
    """Every FMU built with --preset paper (the estimators the papers' filters,
    fusion_core.papers; the plant and the sensor as always), once for the test run."""
    return _build_once(tmp_path_factory, "paper_fmus", "--preset", "paper")


@pytest.fixture
def fmu_path(built_fmus: BuiltFmus, fmu_name: str) -> Path:
    """The built FMU of the test's fmu_name."""
    return built_fmus.path(fmu_name)


@pytest.fixture
def fmu_key(fmu_name: str) -> str:
    """The fusion_core.ESTIMATORS key of the test's fmu_name."""
    return ESTIMATOR_FMUS[fmu_name]


@pytest.fixture(scope="session")
def fmu_recording() -> dict:
    """12 s at 100 Hz: at rest, a two-axis tilt with a yaw turn and a 1 m move, at rest again
    for 5.5 s (the rest detector recognises a rest once its running means have settled after the
    move, some 3 s after it); MPU-6050 noise and a constant gyro bias, so that every state of
    every filter is busy (bias estimates, the position filter's stationary queue)."""
    from fusion_core import synthetic

    s = synthetic
    trajectory = s.Trajectory(
        roll=s.add(s.min_jerk(0.0, 0.6, 1.0, 1.5), s.min_jerk(0.0, -0.6, 4.0, 1.5)),
        pitch=s.add(s.min_jerk(0.0, -0.4, 2.0, 1.5), s.min_jerk(0.0, 0.4, 5.0, 1.5)),
        yaw=s.min_jerk(0.0, 0.8, 1.5, 3.0),
        pos=(s.min_jerk(0.0, 1.0, 1.0, 3.0), s.min_jerk(0.0, -0.5, 2.0, 3.0), s.constant()),
    )
    noise = s.ImuNoise(gyro_bias=(0.01, -0.006, 0.004))
    return s.record(trajectory, 11.99, 100.0, noise=noise, seed=7)


@pytest.fixture(scope="session")
def fusion_core_run():
    """fusion_core's run() of an estimator: fusion_core_run(key, acc, gyro, dt, **params) (the
    paper's filter where params say "filter": "paper")."""
    from fusion_core.registry import create

    def run(key: str, acc, gyro, dt, **params) -> dict:
        return create(key, params).run(acc, gyro, dt)

    return run
