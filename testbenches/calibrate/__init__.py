"""Calibrating the user's IMU: `imu-fusion calibrate` (cli), Tedaldi's static detector (detect)
and calibration (tedaldi), Ferraris's (ferraris). The result is fusion_core.calibration's
calibration.json, which every estimator applies at its input (--calibration)."""
