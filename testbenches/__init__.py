"""Testbenches: ImuPlant -> ImuSensor -> estimator FMUs in fmpy, checked against the contract.

Modules: fmus (loading FMUs), master (the Gauss-Seidel co-simulation loop), contract (checks and
thresholds, versioned), campaign (estimator x scenario x seed), report (table, JSON, Markdown,
plots). `python -m testbenches` is a thin command line over them.
"""

from .master import TestbenchResult, run_testbench

__all__ = ["TestbenchResult", "run_testbench"]
