"""Prototypes of two changes that BROAD asks for and that lie outside this module's files,
measured with the same metric (`python -m testbenches.broad_proposals PATH...`).

1. `UkfProposal`: fusion_core.ukf.UnscentedKalmanFilter (Duong Quoc et al. eq. 14-17) with
   adaptive measurement noise, acc_adaptive: R_acc = acc_noise^2 + rho^2 per axis, with
   rho = ||a_f|/g - 1| of the (filtered) vector, instead of Duong Quoc's all-or-nothing gate.
   Measured: 1.62 deg mean against 0.91 without it (the de-weighting inflates the covariance and
   the next sample that passes gets too large a gain), so it is not adopted. The UKF's pre-filter
   and zero-rate update, first measured here, are now the UKF's own parameters (acc_lowpass,
   rest_time, zaru_psd) and its broad preset.
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
from fusion_core.presets import BROAD_UKF
from fusion_core.types import G, Param

from .broad import collect_paths
from .broad_data import load_trial
from .broad_metric import gravity_from_quat, gravity_from_roll_pitch, inclination_rmse_deg


class UkfProposal(UnscentedKalmanFilter):
    """UnscentedKalmanFilter plus adaptive accelerometer noise (module docstring, item 1); off by
    default (then it is the UKF exactly)."""

    PARAMS = (
        *UnscentedKalmanFilter.PARAMS,
        Param("acc_adaptive", False,
              "Adaptive accelerometer noise: R_acc = acc_noise^2 + rho^2 instead of the gate"),
    )

    def _filter_update(
        self, ax: float, ay: float, az: float, gx: float, gy: float, gz: float, dt: float
    ) -> None:
        if self._params["acc_adaptive"]:
            rho = abs(math.sqrt(ax * ax + ay * ay + az * az) / G - 1.0)
            self._r_acc = self._params["acc_noise"] ** 2 + rho * rho
        super()._filter_update(ax, ay, az, gx, gy, gz, dt)


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


PROPOSED_UKF: dict[str, Any] = dict(BROAD_UKF)
"""The UKF's broad preset (fusion_core/presets.py), the base of the proposals."""

VARIANTS: dict[str, tuple[type[Estimator], dict[str, Any]]] = {
    "ukf-broad+lowpass": (UkfProposal, {k: v for k, v in PROPOSED_UKF.items()
                                        if k not in ("rest_time", "zaru_psd")}),
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
