"""Fitting the estimators to a user's own sensor: `python -m testbenches noise` and `tune`.

- recording.py: reading a recording (CSV with acc_x..z, gyro_x..z and optional time, dt and
  reference columns, or a BROAD trial, of which `noise` takes the rest segment);
- allan.py: the overlapping Allan deviation (allantools) and the usual slope fits: white noise
  at slope -1/2 (its value at tau = 1 s is the density), rate random walk at +1/2, the bias
  instability at the flat floor;
- noise.py: the `noise` command: densities, biases, plot, a recommended-style preset for every
  estimator (fusion_core.presets.noise_preset, the same derivation as the defaults) and the
  sensor FMU's parameters for that sensor;
- tune.py: the `tune` command: the estimator's tunable parameters fitted to recordings with a
  reference (scipy's bounded Powell method), cross-validated on others;
- cli.py: the two commands' argument parsing.
"""
