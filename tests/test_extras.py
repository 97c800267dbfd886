"""The estimators need numpy alone; the commands say in one line which extra is missing."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _run(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                          timeout=120, check=False)


def test_the_estimators_import_without_the_testbench_extra() -> None:
    """With every module of the testbench extra hidden, fusion_core still imports and runs."""
    proc = _run("import sys; from testbenches import EXTRA_MODULES\n"
                "for m in EXTRA_MODULES: sys.modules[m] = None\n"
                "import numpy as np, fusion_core\n"
                "out = fusion_core.ESTIMATORS['kf']().run(np.tile([0, 0, 9.81], (50, 1)), "
                "np.zeros((50, 3)), 0.01)\n"
                "print(len(out['roll']))")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "50"


def test_the_testbench_command_names_the_missing_extra() -> None:
    proc = _run("import sys, runpy; sys.modules['fmpy'] = None; sys.argv = ['x', 'run']\n"
                "runpy.run_module('testbenches', run_name='__main__')")
    assert proc.returncode == 2
    assert proc.stderr.strip() == ("python -m testbenches run needs the testbench extra (pip "
                                   "install 'imu-fusion-fmu[testbench]'); not installed: fmpy")
