"""Monte Carlo campaigns: `python -m testbenches campaign`, seeded runs by the thousands on Dask.

- plan.py: the run list, estimator x scenario x seed, each seed paired with one point of the
  varied parameters (a Latin hypercube or Sobol design from scipy.stats.qmc), each run with a
  stable key;
- simulate.py: one run, plant -> sensor -> estimator through fusion_core's C twin (or the FMUs
  through fmpy with --fmu), scored by the contract's metrics;
- store.py: every finished batch written at once as a Parquet file (pyarrow), so that nothing
  done is lost and the same command again runs only what is missing;
- runner.py: the batches on Dask's distributed scheduler, a LocalCluster by default or the
  user's own scheduler by address, with retries and a progress bar;
- summary.py: per estimator and scenario the mean, median, 95th and 99th percentiles with
  bootstrap confidence intervals, the contract's verdict on them, and plots;
- cli.py: the command line.
"""
