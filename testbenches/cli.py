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
  battery     every attitude filter beside VQF on a battery of motions x parts of several
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
import functools
import importlib
import sys

TESTBENCH_COMMANDS = ("run", "export-ssp", "broad", "noise", "tune", "campaign", "battery",
                      "mechanisms", "budget", "crosscheck", "calibrate", "engines")
"""The commands that need the testbench extra."""
COMMANDS: dict[str, str] = {
    "estimate": "testbenches.estimate:add_estimate_parser",
    "build-fmus": "fmu_src.cli:add_build_parser",
    "run": "testbenches.run_cli:add_run_parser",
    "export-ssp": "testbenches.ssp:add_ssp_parser",
    "broad": "testbenches.broad.cli:add_broad_parser",
    "noise": "testbenches.fit.cli:add_fit_parsers",
    "tune": "testbenches.fit.cli:add_fit_parsers",
    "campaign": "testbenches.montecarlo.cli:add_campaign_parser",
    "battery": "testbenches.battery:add_battery_parser",
    "mechanisms": "testbenches.mechanisms:add_mechanisms_parser",
    "budget": "testbenches.budget:add_budget_parser",
    "crosscheck": "testbenches.crosscheck:add_crosscheck_parser",
    "calibrate": "testbenches.calibrate.cli:add_calibrate_parser",
    "engines": "testbenches.engines:add_engines_parser",
    "docs": "testbenches.docs_figures:add_docs_parser",
}
"""Each command and the function that adds its parser (one may add two), in the order the help
lists them: a command line that names its command imports that command's module only (the
others' imports cost half a second), the help and an unknown command every one."""


def _parser(prog: str, command: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser: with command (one of COMMANDS) only that command's parser,
    else every command's (those of the testbench extra where it is installed)."""
    # The commands are listed once, by argparse from each one's help; the module docstring's
    # last paragraph says what they need.
    parser = argparse.ArgumentParser(
        prog=prog, description="IMU sensor-fusion estimators as FMUs: the project's commands "
        f"(`{prog} COMMAND --help` for one).", epilog=__doc__.strip().split("\n\n")[-1],
        formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False)
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    # no option by a prefix of its name: estimate's `--sensor 0.02` was --sensor-delay
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                parser_class=functools.partial(argparse.ArgumentParser,
                                                               allow_abbrev=False))
    from . import missing_modules

    if command is not None:
        names = [command]
    else:
        lacking = missing_modules()
        names = [n for n in COMMANDS if not (lacking and n in TESTBENCH_COMMANDS)]
    for where in dict.fromkeys(COMMANDS[n] for n in names):  # each adding function once
        module, function = where.split(":")
        getattr(importlib.import_module(module), function)(sub)
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
    args = _parser(prog, argv[0] if argv and argv[0] in COMMANDS else None).parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, OSError) as err:  # what is wrong in the input or the machine: one line
        print(f"error: {err}", file=sys.stderr)
        return 2
