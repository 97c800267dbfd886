"""ComplementaryFilter FMU: fusion_core.ComplementaryFilter as an FMI 2.0 co-simulation FMU.

Implements W. Gui, Y. Tang, S. Mukhopadhyay (2015), complementary filter for tilt, eq. 1-2
(angle = a (angle + gyro dt) + (1 - a) acc_angle, a = tau / (tau + dt)); the same filter as
Das & Mary, eq. 1. The papers' filter has no gyro-bias state; with rest detection (on by
default) the bias outputs are the gyro's reading at rest, which the filter subtracts.
"""

from fmu_src.estimator import EstimatorSlave


class ComplementaryFilter(EstimatorSlave):
    """Complementary filter for roll and pitch (Gui, Tang, Mukhopadhyay 2015; Das & Mary)."""

    key = "cf"
    description = (
        "Complementary filter for roll and pitch from a 6-axis IMU: W. Gui, Y. Tang, "
        "S. Mukhopadhyay (2015), eq. 1-2; Das & Mary, eq. 1. One IMU sample per doStep; "
        "the gyro bias measured at rest (rest_time > 0) is subtracted and output."
    )
