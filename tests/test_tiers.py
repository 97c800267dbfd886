"""The tiers the suite runs in (Makefile: `make test` on every core with `--dist loadgroup`):
the tests that share one build or one run (an `xdist_group`: the wheel, the benchmarks' run,
the battery's figures) must land on one worker, or each worker makes the build or the run
again and the suite takes minutes longer."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

GROUPED = '''
import os
import pytest

pytestmark = pytest.mark.xdist_group("shared")

def test_one():
    print("worker", os.environ["PYTEST_XDIST_WORKER"])

def test_two():
    print("worker", os.environ["PYTEST_XDIST_WORKER"])
'''
LOOSE = '''
def test_three():
    pass

def test_four():
    pass
'''


@pytest.mark.skipif(importlib.util.find_spec("xdist") is None,
                    reason="pytest-xdist is not installed (the test extra has it)")
def test_an_xdist_group_runs_on_one_worker(tmp_path: Path) -> None:
    (tmp_path / "test_grouped.py").write_text(GROUPED)
    (tmp_path / "test_loose.py").write_text(LOOSE)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-n", "2", "--dist", "loadgroup",
                           "-v", "-p", "no:cacheprovider", str(tmp_path)],
                          cwd=tmp_path, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    workers = {line.split()[0] for line in proc.stdout.splitlines()
               if "PASSED" in line and "test_grouped.py" in line}
    assert len(workers) == 1, (
        f"the two tests of one xdist_group ran on {sorted(workers)}: this pytest and "
        "pytest-xdist do not keep a group together (pyproject.toml says which versions do)\n"
        + proc.stdout[-2000:])
