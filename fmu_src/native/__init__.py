"""Native FMUs: the models of fusion_core's C twin behind FMI 2.0 and FMI 3.0 plumbing in C.

The C files beside this module are the plumbing, written once per standard as in the Modelica
Association's Reference-FMUs: `fmi2Functions.c` and `fmi3Functions.c` (every FMI function, the
state machine, value-reference and range checks, logging), `fmu_instance.c` (what both share:
the instance, the value table, the FMU state with its header) behind `fmu_model.h`, and one
plain-C model per kind in `models/` (`estimator.c` for all five estimators, `plant.c`,
`sensor.c`). `include/` holds the standard's headers (2-clause BSD, their notice inside).

`build.py` turns each FMU's variable table, the one the pythonfmu FMUs are built from, into the
model's `config.h` (value references, the variable table with ranges, how parameter values fill
the twin's params struct) and into modelDescription.xml for each standard, compiles the binary
and zips the FMU with its sources: one source, three kinds of FMU.
"""
