"""AngleBiasKalmanFilter FMU: fusion_core.AngleBiasKalmanFilter as an FMI 2.0 co-simulation FMU.

Implements the two-state [angle, gyro bias] Kalman filter of W. Gui, Y. Tang, S. Mukhopadhyay
(2015), eq. 5-26, written scalar by scalar in Das & Mary, eq. 16-27: one filter for roll
(estimating the x gyro bias) and one for pitch (the y gyro bias). bias_z is unobservable from
the accelerometer's tilt: it is 0 until rest detection (on by default) estimates it at rest.
"""

from fmu_src.estimator import EstimatorSlave


class AngleBiasKalmanFilter(EstimatorSlave):
    """[angle, bias] Kalman filter per axis (Gui, Tang, Mukhopadhyay 2015; Das & Mary)."""

    key = "kf"
    description = (
        "Two-state [angle, gyro bias] Kalman filter for roll and pitch: W. Gui, Y. Tang, "
        "S. Mukhopadhyay (2015), eq. 5-26; Das & Mary, eq. 16-27. One IMU sample per doStep."
    )
