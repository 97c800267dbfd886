"""`imu-fusion build-fmus` (and `python build_fmu.py`): build the project's FMUs.

Builds every model (or the named ones) as each kind of FMU: pythonfmu (DIR/NAME.fmu) and native
FMI 2.0 and FMI 3.0 from the C twin (DIR/native/fmi2/NAME.fmu, DIR/native/fmi3/NAME.fmu); --kind
all (the default where a C compiler exists), pythonfmu or native. The pythonfmu FMUs carry the C
twin's library beside fusion_core's sources where a compiler built it (fmu_src.build). Start
values: the estimators' --preset (recommended, the defaults; paper, the papers' own filters; or
a JSON file). Validates each FMU with fmpy.validation.validate_fmu plus the project's checks
(every variable described, every Real with a unit), prints a table (FMU, kind, core, size,
variables, validation problems) and exits with status 1 if any FMU failed to build or has a
problem.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

NEEDS = {"all": ("fmpy", "pythonfmu"), "pythonfmu": ("fmpy", "pythonfmu"), "native": ("fmpy",)}
"""What building each kind needs beyond the estimators (the testbench extra has both): fmpy
validates every FMU, pythonfmu builds its own kind."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """build_fmu.py's options."""
    from .build import KINDS
    from .names import model_names

    parser.add_argument("--out", type=Path, default=Path("dist"), help="output folder (dist)")
    parser.add_argument(
        "--only", nargs="+", metavar="NAME", choices=model_names(),
        help=f"build only these FMUs (of {', '.join(model_names())})",
    )
    parser.add_argument(
        "--kind", choices=KINDS, default=None,
        help="which FMUs: all (pythonfmu, native FMI 2.0 and 3.0; the default where a C "
        "compiler exists, else pythonfmu), pythonfmu, or native",
    )
    parser.add_argument(
        "--calibration", type=Path, default=None, metavar="FILE.json",
        help="a part's calibration (calibration.json): acc_cal and gyro_cal as every estimator "
        "FMU's start values",
    )
    parser.add_argument(
        "--preset", default="recommended",
        help="the estimators' start values: recommended (the defaults), paper (the seed papers' "
        "own filters), or a JSON file of parameters per estimator",
    )


def add_build_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """The build-fmus subcommand of the console script."""
    p = sub.add_parser("build-fmus", help="build and validate the FMUs",
                       description=__doc__.splitlines()[0])
    add_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Build, print the table; the exit status."""
    from .build import build_all, default_kind, format_table
    from .names import model_names

    if args.out.exists() and not args.out.is_dir():
        print(f"error: --out {args.out} is a file: the FMUs go to a folder", file=sys.stderr)
        return 2
    kind = args.kind or default_kind()
    missing = [m for m in NEEDS[kind] if importlib.util.find_spec(m) is None]
    if missing:
        print(f"building {kind} FMUs needs {' and '.join(missing)} (the testbench extra: "
              "pip install 'imu-fusion-fmu[testbench]')", file=sys.stderr)
        return 2
    try:
        if kind == "pythonfmu" and args.kind is None:
            print("no C compiler found: building the pythonfmu FMUs only", file=sys.stderr)
        results = build_all(args.only or model_names(), args.out, args.preset, kind,
                            calibration=args.calibration)
    except (ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(format_table(results))
    return 1 if any(r.problems for r in results) else 0


def main(argv: list[str] | None = None) -> int:
    """`python build_fmu.py`: the same command alone."""
    parser = argparse.ArgumentParser(prog="build_fmu.py", description=__doc__.splitlines()[0])
    add_arguments(parser)
    return run(parser.parse_args(argv))
