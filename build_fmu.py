"""Build the project's FMUs: `python build_fmu.py [--out DIR] [--only NAME ...]`.

Builds every FMU (or the named ones) into dist/ (or DIR), validates each with
fmpy.validation.validate_fmu plus the project's checks (every variable described, every Real
with a unit), prints a table (FMU, size, variables, validation problems) and exits with status 1
if any FMU failed to build or has a problem. A thin layer over fmu_src.build.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fmu_src.build import build_all, format_table, model_names


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("dist"), help="output folder (dist)")
    parser.add_argument(
        "--only", nargs="+", metavar="NAME", choices=model_names(),
        help=f"build only these FMUs (of {', '.join(model_names())})",
    )
    args = parser.parse_args(argv)
    results = build_all(args.only or model_names(), args.out)
    print(format_table(results))
    return 1 if any(r.problems for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
