"""`imu-fusion COMMAND ...` (and `python -m testbenches COMMAND ...`): the project's command line.

  estimate    the estimators on your own recording (CSV, Parquet, HDF5, MAT): estimates as CSV,
              Parquet or HDF5, a plot, and with a reference the RMSE beside VQF's
              (testbenches.estimate).
  build-fmus  build and validate the FMUs (fmu_src.cli; also `python build_fmu.py`).
  run         estimator x scenario x seed runs through the FMUs with the contract checks
              (testbenches.contract_runs); prints the contract table, writes DIR/report.json,
              DIR/report.md and plots; exit status 1 on any FAIL.
  export-ssp  the plant, sensor and estimator FMUs and their connections as an SSP file (and
              as one fmucontainer FMU) that libcosim and Ecos run as exported.
  engines     every estimator's chain in libcosim and Ecos beside the project's Jacobi master
              (testbenches.engines; the engines extra).
  broad       accuracy on BROAD's real recordings beside VQF, Madgwick, Mahony (testbenches.broad).
  noise       noise densities of a static recording (Allan deviation), a preset for every
              estimator and the sensor FMU's parameters for that sensor (testbenches.fit).
  tune        an estimator's tunable parameters fitted to recordings with a reference, validated
              on others (testbenches.fit).
  campaign    a Monte Carlo campaign of seeded runs on Dask, resumable, with percentiles and
              confidence intervals (testbenches.montecarlo).
  battery     every attitude filter beside VQF on a battery of motions x parts of three
              sensor classes (testbenches.battery).
  mechanisms  what each mechanism of the recommended attitude filters is worth out of sample
              (BROAD's motion folds and the battery; testbenches.mechanisms).
  budget      the sensor's error budget: each scenario's RMSE with one group of the IMU's
              errors switched off at a time (testbenches.budget).
  calibrate   a part's calibration from a session of static poses and turns: calibration.json
              for --calibration (testbenches.calibrate).
  crosscheck  the native FMUs with fusion_core's reference results and fmpy's in the FMI
              Cross-Check layout, validated by fmpy's cross-check tools (testbenches.crosscheck).
  docs        the docs' generated figures, tables and pictures checked against (or made again
              by) their commands (testbenches.docs_figures).

`estimate` needs only the estimators (and pyarrow for speed and Parquet, h5py for HDF5, scipy
for MAT, matplotlib for its plot, vqf for the comparison); the other commands need the
testbench extra, and say so where it is missing.
"""

from __future__ import annotations

import argparse
import sys

from fmu_src.cli import add_build_parser

from .estimate import add_estimate_parser

TESTBENCH_COMMANDS = ("run", "export-ssp", "broad", "noise", "tune", "campaign", "battery",
                      "mechanisms", "budget", "crosscheck", "calibrate", "engines")
"""The commands that need the testbench extra."""


def _parser(prog: str) -> argparse.ArgumentParser:
    # The commands are listed once, by argparse from each one's help; the module docstring's
    # last paragraph says what they need.
    parser = argparse.ArgumentParser(
        prog=prog, description="IMU sensor-fusion estimators as FMUs: the project's commands "
        f"(`{prog} COMMAND --help` for one).", epilog=__doc__.strip().split("\n\n")[-1],
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    add_estimate_parser(sub)
    add_build_parser(sub)
    from . import missing_modules

    if not missing_modules():
        from .battery import add_battery_parser
        from .broad.cli import add_broad_parser
        from .budget import add_budget_parser
        from .calibrate.cli import add_calibrate_parser
        from .crosscheck import add_crosscheck_parser
        from .docs_figures import add_docs_parser
        from .engines import add_engines_parser
        from .fit.cli import add_fit_parsers
        from .mechanisms import add_mechanisms_parser
        from .montecarlo.cli import add_campaign_parser
        from .run_cli import add_run_parser
        from .ssp import add_ssp_parser

        for add in (add_run_parser, add_ssp_parser, add_broad_parser, add_fit_parsers,
                    add_campaign_parser, add_battery_parser, add_mechanisms_parser,
                    add_budget_parser,
                    add_crosscheck_parser, add_calibrate_parser, add_engines_parser,
                    add_docs_parser):
            add(sub)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("imu-fusion-fmu")
    except PackageNotFoundError:
        return "(not installed)"


def main(argv: list[str] | None = None, prog: str = "imu-fusion") -> int:
    """Run the command line; return the exit status."""
    from . import INSTALL_HINT, missing_modules

    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] in TESTBENCH_COMMANDS and missing_modules():
        print(f"{prog} {argv[0]} needs the testbench extra ({INSTALL_HINT}); not installed: "
              f"{', '.join(missing_modules())}", file=sys.stderr)
        return 2
    args = _parser(prog).parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, FileNotFoundError, ConnectionError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
