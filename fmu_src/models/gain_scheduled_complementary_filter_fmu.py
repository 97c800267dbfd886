"""GainScheduledComplementaryFilter FMU: fusion_core.GainScheduledComplementaryFilter as an FMI
2.0 co-simulation FMU.

Implements the modified-gain complementary filter (MGCF) of Duong Quoc et al., eq. 7-13: a
quaternion PI filter (Mahony, Hamel, Pflimlin 2008) whose natural frequency w0 is scheduled on
rho = | |acc|/g - 1 |. The integral term is the gyro-bias estimate (bias outputs, all three axes).
"""

from fmu_src.estimator import EstimatorSlave


class GainScheduledComplementaryFilter(EstimatorSlave):
    """Gain-scheduled (modified-gain) complementary filter (Duong Quoc et al.)."""

    key = "mgcf"
    description = (
        "Modified-gain (gain-scheduled) complementary filter for roll and pitch: Duong Quoc "
        "et al., eq. 7-13 (quaternion PI filter of Mahony et al. 2008 with w0 scheduled on "
        "||acc|/g - 1|). One IMU sample per doStep."
    )
