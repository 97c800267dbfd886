"""PositionKalmanFilter FMU: fusion_core.PositionKalmanFilter as an FMI 2.0 co-simulation FMU.

Implements the position Kalman filter of Safitri, Cahyadi, Firmansyah, eq. 20-29 (per axis a
[p, v, a] state with white-jerk process noise, the accelerometer observing a), with the tilt
from the [angle, bias] Kalman filter of Gui, Tang, Mukhopadhyay (2015) and a zero-velocity
update at rest. Outputs pos_x..z and vel_x..z besides the attitude and the gyro bias, which
are the [angle, bias] Kalman filter's.
"""

from fmu_src.estimator import EstimatorSlave


class PositionKalmanFilter(EstimatorSlave):
    """[p, v, a] position Kalman filter per axis (Safitri, Cahyadi, Firmansyah)."""

    key = "poskf"
    description = (
        "Position and velocity Kalman filter with a zero-velocity update: Safitri, Cahyadi, "
        "Firmansyah, eq. 20-29; tilt from the Gui, Tang, Mukhopadhyay (2015) [angle, bias] "
        "Kalman filter. One IMU sample per doStep."
    )
