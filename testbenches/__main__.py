"""`python -m testbenches run ...`: the command line over testbenches' functions.

  run         estimator x scenario x seed runs through the FMUs with the contract checks
              (testbenches.contract_runs); prints the contract table, writes DIR/report.json,
              DIR/report.md and plots; exit status 1 on any FAIL.
  export-ssp  the plant, sensor and estimator FMUs and their connections as an SSP file.
  broad       accuracy on BROAD's real recordings beside VQF, Madgwick, Mahony (testbenches.broad).
  noise       noise densities of a static recording (Allan deviation), a preset for every
              estimator and the sensor FMU's parameters for that sensor (testbenches.fit).
  tune        an estimator's tunable parameters fitted to recordings with a reference, validated
              on others (testbenches.fit).
  campaign    a Monte Carlo campaign of seeded runs on Dask, resumable, with percentiles and
              confidence intervals (testbenches.montecarlo).
  budget      the sensor's error budget: each scenario's RMSE with one group of the IMU's
              errors switched off at a time (testbenches.budget).
"""

from __future__ import annotations

import sys

from . import INSTALL_HINT, missing_modules

if missing_modules():  # one line instead of a traceback from deep inside a command
    print(f"python -m testbenches needs the testbench extra ({INSTALL_HINT}); not installed: "
          f"{', '.join(missing_modules())}", file=sys.stderr)
    sys.exit(2)

import argparse

from .broad.cli import add_broad_parser
from .budget import add_budget_parser
from .fit.cli import add_fit_parsers
from .montecarlo.cli import add_campaign_parser
from .run_cli import add_run_parser
from .ssp import add_ssp_parser

PARSERS = (add_run_parser, add_ssp_parser, add_broad_parser, add_fit_parsers,
           add_campaign_parser, add_budget_parser)
"""Each command's parser, from its own module: each registers its subcommand(s) and the
function that runs it (set_defaults(func=...))."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m testbenches", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    for add in PARSERS:
        add(sub)
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, FileNotFoundError, ConnectionError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
