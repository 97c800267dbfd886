"""`python -m testbenches COMMAND ...`: the project's command line (testbenches.cli; also the
console script `imu-fusion`)."""

from __future__ import annotations

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main(prog="python -m testbenches"))
