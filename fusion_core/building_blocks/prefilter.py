"""The accelerometer pre-filter: the specific force low-passed in a frame that turns with the
gyro (after Laidig & Seel 2023); fusion_core.measured_vector builds the filters' measured vector
from it."""

from __future__ import annotations

from ..linalg import Mat9, mat_vec
from ..types import Param
from .sampling import Vec3

ACC_LOWPASS_PARAM = Param(
    "acc_lowpass", 1.5,
    "Accelerometer pre-filter length: the specific force is low-passed in a frame that turns "
    "with the gyro (two stages of acc_lowpass / 2 each: fusion_core.measured_vector), so linear "
    "acceleration averages out and gravity does not lag the rotation (Laidig & Seel 2023, VQF); "
    "the filter and its gate then use the filtered vector. 0 = off: each raw sample (the papers)",
    unit="s", low=0.0,
)
"""Recommended: 1.5 s. Physics brackets it: long enough to average the swing of a hand-held
translation (a second or more), short against the drift that a gyro scale error of 1-3 % turns
into the vector while the sensor turns; within that bracket the value is the one
leave-one-motion-fold-out cross-validation on BROAD chooses for cf, kf and ukf (`python -m
testbenches broad DIR --cv`, testbenches.broad.cv, whose report gives the figures). The mgcf
keeps 1 s (mgcf.MGCF_ACC_LOWPASS)."""
"""The accelerometer pre-filter. Laidig & Seel (VQF: Highly accurate IMU orientation estimation
with bias estimation and magnetic disturbance rejection, Information Fusion 91, 2023) low-pass
filter the accelerometer in an almost inertial frame given by the gyro strapdown integration:
there the gravity part is constant, and the linear acceleration of a body that ends where it
started averages to (velocity change) / (time), so a low-pass with a time constant of seconds
removes most of it, without the lag that a body-frame low-pass has while the sensor turns. Here
the filtered vector is kept in body axes and turned with the gyro's rotation increment each
sample (a world-fixed vector seen from the body), which is the same filter. Each paper's filter is
then unchanged: it takes the filtered vector where it took the raw sample. BROAD's
fast-translation trials, whose raw accelerometer swings between 0.02 g and 5 g, show what it
does (`imu-fusion broad DIR`; docs/results/broad.md)."""


def lowpass_specific_force(f: Vec3, turn: Mat9, a: Vec3, k: float) -> Vec3:
    """One step of the accelerometer pre-filter (ACC_LOWPASS_PARAM): the filtered specific force
    f turned with the body by turn (kinematics.rotation_back_matrix of the interval's rotation,
    built once for every vector it turns), then blended with the new sample a by
    k = dt / (tau + dt)."""
    f0, f1, f2 = mat_vec(turn, f)
    return f0 + k * (a[0] - f0), f1 + k * (a[1] - f1), f2 + k * (a[2] - f2)
