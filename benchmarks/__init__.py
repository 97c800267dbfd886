"""Speed benchmarks: our estimators and FMUs against peer filters (issue 6).

`python -m benchmarks [--quick] [--out DIR]` (or `make bench`) measures, on one realistic 100 Hz
recording (fusion_core.scenarios "moderate_dynamics" with MPU-6050 noise):

  per_sample_us   median us per `step` call of cf, mgcf, kf, ukf, poskf in a Python loop, and per
                  update call of the peers of the `bench` extra (filterpy UKF, ahrs Mahony,
                  Madgwick and EKF, imufusion, VQF), in the same run;
  per_sample_us_stream  the same through Estimator.stream() (the C twin's step), beside VQF's
                  update() in the same run;
  fmu_step_us     set inputs + doStep + get outputs through fmpy, per estimator FMU, and the
                  overhead above per_sample_us;
  testbench       steps per second and real-time factor of the plant -> sensor -> estimator
                  testbench at 100 Hz and 1 kHz;
  scaling         time per sample and peak memory of `run` over 1e3 ... 1e6 samples;
and prints a table with every target beside its measurement, and writes DIR/bench.json.

Each module is one concern; `run_benchmarks(BenchConfig(...))` runs them all and is what the
command line and the tests call. Timings are medians of several repeats with the garbage
collector off (like timeit); nothing here asserts a timing.
"""

from typing import Any

from .config import BenchConfig

__all__ = ["BenchConfig", "run_benchmarks"]


def __getattr__(name: str) -> Any:
    # run_benchmarks on first use: importing the package does not import fusion_core
    if name == "run_benchmarks":
        from .suite import run_benchmarks

        return run_benchmarks
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
