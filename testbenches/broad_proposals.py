"""Prototypes of two changes that BROAD asks for and that lie outside this module's files,
measured with the same metric (`python -m testbenches.broad_proposals PATH...`).

1. `UkfProposal`: fusion_core.ukf.UnscentedKalmanFilter (Duong Quoc et al. eq. 14-17) with the
   three real-sensor options that cf, kf and mgcf got as parameters:
   - acc_lowpass: the accelerometer pre-filter (fusion_core.complementary.ACC_LOWPASS_PARAM,
     after Laidig & Seel 2023): the measurement z = acc/g is the specific force low-passed in a
     frame that turns with the bias-corrected gyro;
   - rest_time (rest_gyro, rest_acc): a zero-angular-rate update at rest, the linear Kalman update
     z = gyro, h(x) = b, R = zaru_noise^2 / dt I3 (complementary.REST_PARAMS);
   - acc_adaptive: adaptive measurement noise, R_acc = acc_noise^2 + rho^2 per axis, with
     rho = ||a_f|/g - 1| of the (filtered) vector: a linear acceleration of at least rho g acts,
     so the direction of a/g is off by up to about rho; instead of Duong Quoc's all-or-nothing gate
     the sample is de-weighted smoothly.
   The subclass only wraps `_update` (and sets the UKF's per-sample accelerometer variance
   `_r_acc`), so it follows the UKF's own code; it is a measurement device, not a product.
2. `low_acc_gyro_only`: INTERFACE.md rejects a whole sample whose accelerometer norm is below
   0.1 g, gyro included. On BROAD's fast trials the sensor reads below 0.1 g for tens of samples
   at a time while it turns at 400 deg/s, so every estimator loses those rotations. The mixin
   accepts such a sample (it still rejects NaN, inf and bad dt) and lets the filter integrate the
   gyro and skip the accelerometer (its gate or pre-filter takes care of the small norm): the
   behaviour the contract's "skip or de-weight the accelerometer" clause describes for a norm far
   from g.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core import ESTIMATORS, UnscentedKalmanFilter
from fusion_core.base import Estimator
from fusion_core.complementary import (
    ACC_LOWPASS_PARAM,
    REST_PARAMS,
    body_rotation,
    lowpass_specific_force,
    rest_step,
)
from fusion_core.types import DEG, G, Param

from .broad import collect_paths
from .broad_data import load_trial
from .broad_metric import gravity_from_quat, gravity_from_roll_pitch, inclination_rmse_deg


class UkfProposal(UnscentedKalmanFilter):
    """UnscentedKalmanFilter plus acc_lowpass, a zero-rate update at rest and adaptive R (module
    docstring, item 1). All three are off by default (then it is the UKF exactly)."""

    PARAMS = (
        *UnscentedKalmanFilter.PARAMS,
        ACC_LOWPASS_PARAM,
        *REST_PARAMS,
        Param("zaru_noise", 0.005 * DEG,
              "Gyro white-noise density for the zero-angular-rate update at rest",
              unit="rad/(s.sqrt(Hz))", low=0.0, low_open=True),
        Param("acc_adaptive", False,
              "Adaptive accelerometer noise: R_acc = acc_noise^2 + rho^2 instead of the gate"),
    )
    STATE = (*UnscentedKalmanFilter.STATE, "acc_f", "rest")

    def _reset(self) -> None:
        super()._reset()
        self.acc_f = (0.0, 0.0, 0.0)
        self.rest = (0.0,) * 7

    def _init(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float) -> None:
        super()._init(ax, ay, az, gx, gy, gz)
        self.acc_f = (ax, ay, az)
        self.rest = (gx, gy, gz, ax, ay, az, 0.0)

    def _update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        p = self._params
        if p["acc_lowpass"] > 0.0:
            bias = (self.x[3], self.x[4], self.x[5])
            phi = body_rotation(self.gyro_prev, (gx, gy, gz), bias, dt,
                                p["integration"] == "trapezoid")
            self.acc_f = lowpass_specific_force(self.acc_f, phi, (ax, ay, az), dt,
                                                p["acc_lowpass"])
            fx, fy, fz = self.acc_f
        else:
            fx, fy, fz = ax, ay, az
        if p["acc_adaptive"]:
            rho = abs(math.sqrt(fx * fx + fy * fy + fz * fz) / G - 1.0)
            self._r_acc = p["acc_noise"] ** 2 + rho * rho
        super()._update(fx, fy, fz, gx, gy, gz, dt)
        if p["rest_time"] > 0.0:
            self.rest = rest_step(self.rest, gx, gy, gz, ax, ay, az, dt, p["rest_gyro"],
                                  p["rest_acc"])
            if self.rest[6] >= p["rest_time"]:
                self._zero_rate_update((gx, gy, gz), p["zaru_noise"] ** 2 / dt)

    def _zero_rate_update(self, z: tuple[float, float, float], r: float) -> None:
        """Linear Kalman update with z = gyro, h(x) = b (the last three states)."""
        x = np.asarray(self.x, dtype=float)
        P = np.asarray(self.P, dtype=float)
        S = P[3:, 3:] + r * np.eye(3)
        K = np.linalg.solve(S, P[3:, :]).T
        x = x + K @ (np.asarray(z) - x[3:])
        P = P - K @ P[3:, :]
        x[:3] /= np.linalg.norm(x[:3])
        self.x = x.tolist()
        self.P = (0.5 * (P + P.T)).tolist()


class LowAccGyroOnly:
    """Mixin (module docstring, item 2): a sample whose accelerometer norm is below 0.1 g is
    processed (gyro integrated, accelerometer skipped by the filter's gate or pre-filter) instead
    of rejected. NaN, inf and a bad dt are still rejected."""

    def _check_values(self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float,
                      dt: float) -> None:
        if math.isfinite(ax + ay + az + gx + gy + gz + dt) and 0.0 < dt <= self._params["max_dt"]:
            return
        super()._check_values(ax, ay, az, gx, gy, gz, dt)  # type: ignore[misc]


def low_acc_gyro_only(cls: type[Estimator]) -> type[Estimator]:
    """cls with the LowAccGyroOnly mixin."""
    return type(f"{cls.__name__}LowAccGyroOnly", (LowAccGyroOnly, cls), {})


PROPOSED_UKF: dict[str, Any] = {
    "integration": "rectangle",
    "gyro_noise": 0.008 * DEG,
    "bias_noise": 1e-4 * DEG,
    "acc_noise": 0.005,
    "acc_gate": 1.0,
    "acc_lowpass": 1.0,
    "rest_time": 1.5,
    "zaru_noise": 0.008 * DEG,
}
"""The proposal's parameters: noise densities of BROAD's IMU measured at rest (as in the broad
preset of kf, fusion_core/presets.py), VQF's rest detector, the same pre-filter as kf and mgcf,
and the gate opened (the pre-filter removes what it was there for)."""

VARIANTS: dict[str, tuple[type[Estimator], dict[str, Any]]] = {
    "ukf-broad+lowpass": (UkfProposal, {k: v for k, v in PROPOSED_UKF.items()
                                        if k not in ("rest_time", "zaru_noise")}),
    "ukf-broad+lowpass+rest": (UkfProposal, PROPOSED_UKF),
    "ukf-broad+lowpass+rest+adaptiveR": (UkfProposal, {**PROPOSED_UKF, "acc_adaptive": True}),
}
"""Named prototype runs: (class, parameters)."""


def add_low_acc_variants(presets: dict[str, dict[str, Any]]) -> None:
    """Add 'KEY-broad+lowacc' runs: each estimator of `presets` with the LowAccGyroOnly mixin."""
    for key, params in presets.items():
        VARIANTS[f"{key}-broad+lowacc"] = (low_acc_gyro_only(ESTIMATORS[key]), params)


def evaluate_variants(
    paths: Sequence[str | Path], names: Sequence[str]
) -> dict[str, dict[str, float]]:
    """Inclination RMSE [deg] per trial (rows) and variant (columns)."""
    out: dict[str, dict[str, float]] = {}
    for f in collect_paths(paths):
        trial = load_trial(f)
        g_ref = gravity_from_quat(trial.opt_quat)
        row = {}
        for name in names:
            cls, params = VARIANTS[name]
            est = cls(**params).run(trial.acc, trial.gyro, trial.dt)
            g = gravity_from_roll_pitch(est["roll"], est["pitch"])
            row[name] = inclination_rmse_deg(g, g_ref, trial.movement)
        out[trial.name] = row
        print(trial.name, " ".join(f"{k}={v:.3f}" for k, v in row.items()), file=sys.stderr,
              flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    """python -m testbenches.broad_proposals PATH... [--only NAME,NAME]: the prototype table."""
    import argparse

    from fusion_core.presets import PRESETS

    parser = argparse.ArgumentParser(prog="python -m testbenches.broad_proposals",
                                     description=__doc__)
    parser.add_argument("paths", nargs="+", type=Path)
    parser.add_argument("--only", default=None, help="comma list of variant names")
    args = parser.parse_args(argv)
    add_low_acc_variants({k: PRESETS["broad"][k] for k in ("cf", "mgcf", "kf")})
    VARIANTS["ukf-proposal+lowacc"] = (low_acc_gyro_only(UkfProposal),
                                       VARIANTS["ukf-broad+lowpass+rest"][1])
    names = args.only.split(",") if args.only else list(VARIANTS)
    table = evaluate_variants(args.paths, names)
    width = max(len(n) for n in names) + 1
    print(f"{'trial':<36}" + "".join(f"{n:>{width}}" for n in names))
    for trial, row in table.items():
        print(f"{trial:<36}" + "".join(f"{row[n]:>{width}.3f}" for n in names))
    means = {n: float(np.mean([row[n] for row in table.values()])) for n in names}
    print(f"{'mean':<36}" + "".join(f"{means[n]:>{width}.3f}" for n in names))
    return 0


if __name__ == "__main__":
    sys.exit(main())
