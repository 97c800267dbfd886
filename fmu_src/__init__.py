"""fmu_src: the project's FMI 2.0 co-simulation FMUs, built with pythonfmu.

The plumbing is written once and shared by every FMU (Reference-FMUs style):
  variables.py          the declarative variable table (`Variable`): name, causality, type, unit,
                        display unit, description, start value, allowed range;
  slave.py              `FmuSlave`, the pythonfmu slave base: turns the table into registrations,
                        keeps every callback exception-free, refuses bad parameters with a log
                        message, saves and restores the whole FMU state;
  estimator.py          the estimator helper on top: 6 IMU inputs + dt, the estimate outputs,
                        invalid_samples and one FMU parameter per fusion_core `Param`;
  model_description.py  modelDescription.xml decoration: UnitDefinitions with base units,
                        display units, min/max, enumeration types;
  build.py              building and validating the FMUs (`python build_fmu.py`);
  host.py               a small fmpy host (one instance, one sample per doStep) for tests,
                        examples and benchmarks; not part of an FMU.
Each estimator of fusion_core.registry is an FMU whose slave module is generated from its
entry (names.py); the plant and the sensor are one short module each in fmu_src/models/, whose
file name is the model name in snake_case plus `_fmu` (a unique top-level module name inside
every FMU). A new kind of FMU
(the plant, the sensor) is a variable table plus a Python object with step, set_parameter,
get_state and set_state (`slave.Model`); see tests/test_fmu_base.py for a minimal one.
"""

__all__: list[str] = []
