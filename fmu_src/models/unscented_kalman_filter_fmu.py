"""UnscentedKalmanFilter FMU: fusion_core.UnscentedKalmanFilter as an FMI 2.0 co-simulation FMU.

Implements the unscented Kalman filter of Duong Quoc et al., eq. 14-17, on the gravity direction
in the body frame, augmented with three gyro-bias states (scaled sigma points of Wan & van der
Merwe 2000).
"""

from fmu_src.estimator import EstimatorSlave


class UnscentedKalmanFilter(EstimatorSlave):
    """UKF on the gravity direction with gyro-bias states (Duong Quoc et al.)."""

    key = "ukf"
    description = (
        "Unscented Kalman filter for roll and pitch on the gravity direction with three "
        "gyro-bias states: Duong Quoc et al., eq. 14-17. One IMU sample per doStep."
    )
