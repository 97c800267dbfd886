"""Testbenches: ImuPlant -> ImuSensor -> estimator FMUs in fmpy, checked against the contract.

Modules: fmus (loading FMUs), master (the Gauss-Seidel co-simulation loop), contract (checks and
thresholds, versioned), campaign (estimator x scenario x seed), report (table, JSON, Markdown,
plots). `python -m testbenches` is a thin command line over them.

The estimators (fusion_core) need numpy alone; the testbenches need the `testbench` extra
(`pip install 'imu-fusion-fmu[testbench]'`, which `make` installs): missing_modules says what
of it is not installed.
"""

from __future__ import annotations

import importlib.util
from typing import Any

EXTRA_MODULES = ("fmpy", "pythonfmu", "tqdm", "matplotlib", "dask", "distributed", "pyarrow",
                 "h5py", "scipy", "allantools")
"""The modules of the `testbench` extra (pyproject.toml)."""
INSTALL_HINT = "pip install 'imu-fusion-fmu[testbench]'"


def missing_modules() -> list[str]:
    """The modules of the testbench extra that are not installed."""
    return [m for m in EXTRA_MODULES if importlib.util.find_spec(m) is None]


def __getattr__(name: str) -> Any:
    # run_testbench and TestbenchResult on first use: importing the package needs no extra
    if name in ("TestbenchResult", "run_testbench"):
        from . import master

        return getattr(master, name)
    raise AttributeError(f"module 'testbenches' has no attribute {name!r}")


__all__ = ["EXTRA_MODULES", "INSTALL_HINT", "TestbenchResult", "missing_modules",
           "run_testbench"]
