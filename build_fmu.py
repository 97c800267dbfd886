"""Build the project's FMUs: `python build_fmu.py [--out DIR] [--only NAME ...] [--kind K]
[--preset P]` (the same as `imu-fusion build-fmus`; fmu_src/cli.py)."""

from __future__ import annotations

import sys

from fmu_src.cli import main

if __name__ == "__main__":
    sys.exit(main())
