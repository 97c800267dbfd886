"""Accuracy on BROAD's real recordings (Laidig et al., Data 2021, CC BY 4.0), beside VQF,
Madgwick and Mahony: `python -m testbenches broad PATH...`.

- data: read any BROAD trial file (HDF5 or MATLAB v5) into arrays, with the sensor's sampling
  property (the gyro sample is the interval's mean rate);
- metric: the dataset's inclination error;
- peers: the public filters run on the same samples;
- run: plan the columns (estimator x preset, peers) and evaluate them over trials;
- report: the table, report.json, report.md and the bar chart;
- cli: the command line.
"""
