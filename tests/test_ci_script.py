"""The CI entry point parses and hands over to `make test`.

fresh-clone-check runs `make run` and `make test` but never `.ci/run` itself, so a broken
script would otherwise be seen first by CI.
"""
import shutil
import subprocess
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / ".ci" / "run"


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_ci_script_parses():
    done = subprocess.run(["bash", "-n", str(SCRIPT)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_ci_script_ends_in_make_test():
    lines = [line.strip() for line in SCRIPT.read_text().splitlines()
             if line.strip() and not line.lstrip().startswith("#")]
    assert lines[-1] == "make test"
    assert "set -euo pipefail" in lines
