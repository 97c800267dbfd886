"""A combined motion whose translation is slower than the measured vector: the weakness BROAD's
combined trial (32: rotation at about 2 rad/s with about 1 m/s2 of slow linear acceleration)
shows against VQF, reproduced on the realistic sensor, and held as a target.

A linear acceleration slower than acc_lowpass passes the measured vector whole, and the slow
band (a short low-pass against the full-length one) cannot see what both pass, so the filters
trust a vector that is off. The vector grows longer where the slow band finds more linear
acceleration than the gyro's turn explains, once a rest has measured the gyro bias
(measured_vector, item 4): from a rest, as recordings usually start, cf, kf and ukf are within
VQF's RMSE plus 10 % (the rule of the shaking and gyro_clipping scenarios); the mgcf, whose
vector is shorter, is not yet.
Started in motion the vector keeps its length, and the Kalman filters stay behind; that test
fails the day they reach VQF + 10 % there.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from fusion_core import ESTIMATORS, synthetic
from fusion_core.sensor import ImuSensorModel
from fusion_core.synthetic import Trajectory, after_rest
from testbenches.broad.metric import gravity_from_roll_pitch, inclination_error

RATE = 100.0
DURATION = 120.0
PARTS = range(6)
SETTLE = 5.0
"""Seconds left out at the start: the fill of the measured vector and VQF's start."""


Up = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
"""A filter run: acc, gyro [N, 3], dt [N] -> the up direction [N, 3]."""


def slow_combined(rest: float = 0.0) -> Trajectory:
    """The battery's slow combined motion (testbenches.battery.slow_combined); rest > 0: level
    and still for that long [s], then the motion fades in over 2 s."""
    from testbenches.battery import slow_combined as motion

    return after_rest(motion(), rest) if rest > 0.0 else motion()


def mean_rmse_deg(run: Up, rest: float = 0.0) -> float:
    """The inclination RMSE [deg] after SETTLE (after the rest and SETTLE where the motion
    starts from a rest), averaged over the parts; run(acc, gyro, dt) gives the up direction
    [N, 3]."""
    out = []
    for seed in PARTS:
        rec = synthetic.record(slow_combined(rest), DURATION + rest, RATE, seed=seed)
        s = ImuSensorModel(seed=seed).run(rec["omega"], rec["f"], rec["dt"])
        up = run(s["acc"], s["gyro"], s["dt"])
        err = inclination_error(up, gravity_from_roll_pitch(rec["roll"], rec["pitch"]))
        keep = np.arange(len(err)) / RATE >= rest + SETTLE
        out.append(math.degrees(math.sqrt(float(np.mean(err[keep] ** 2)))))
    return float(np.mean(out))


REST = 3.0
"""The rest a recording from rest starts with [s]: longer than rest_time, so that the filters'
rest detectors measure the gyro bias."""


def ours(key: str) -> Up:
    def run(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> np.ndarray:
        o = ESTIMATORS[key]().run(acc, gyro, dt)
        return gravity_from_roll_pitch(o["roll"], o["pitch"])
    return run


NOT_MET = ("not met yet started in motion, where the vector keeps its length until a rest has "
           "measured the bias: kf 2.85 and ukf 2.75 deg against VQF 1.76 (+10 %: 1.94); the cf "
           "2.62; from a rest all are within (the test below)")


@pytest.mark.parametrize("key", ["kf", "ukf"])
@pytest.mark.xfail(strict=True, reason=NOT_MET)
def test_the_kalman_filters_are_within_vqf_plus_ten_percent_on_slow_combined_motion(
    key: str
) -> None:
    pytest.importorskip("vqf")
    from testbenches.peers import PEERS

    vqf = mean_rmse_deg(lambda acc, gyro, dt: PEERS["vqf"](acc, gyro, RATE))
    mine = mean_rmse_deg(ours(key))
    print(f"\n{key} {mine:.3f} deg against VQF {vqf:.3f}")
    assert mine <= 1.1 * vqf


MGCF_NOT_MET = ("not met yet: the mgcf 2.25 deg (3.16 with the vector kept at acc_lowpass) "
                "against VQF 1.69 (+10 %: 1.86); its vector is 1 s where the others' is 1.5 s, "
                "so at twice its length it is still shorter than VQF's 3 s")


@pytest.mark.parametrize("key", ["cf", pytest.param("mgcf", marks=pytest.mark.xfail(
    strict=True, reason=MGCF_NOT_MET)), "kf", "ukf"])
def test_from_a_rest_every_filter_with_a_slow_band_is_within_vqf_plus_ten_percent(key: str
                                                                                 ) -> None:
    """The same motion after 3 s at rest (VQF 1.69 deg): cf 1.77, kf and ukf 1.81 with the
    longer vector, 2.59 and 2.70 with the vector kept at acc_lowpass."""
    pytest.importorskip("vqf")
    from testbenches.peers import PEERS

    vqf = mean_rmse_deg(lambda acc, gyro, dt: PEERS["vqf"](acc, gyro, RATE), REST)
    mine = mean_rmse_deg(ours(key), REST)
    print(f"\n{key} {mine:.3f} deg against VQF {vqf:.3f}")
    assert mine <= 1.1 * vqf
