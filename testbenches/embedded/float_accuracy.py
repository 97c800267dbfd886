"""What the float build of the twins costs in accuracy, measured on this machine.

The twins compiled with FC_REAL_FLOAT (fc_real.h: float variables, the float libm functions,
single-precision literals) into a desktop library of their own, run through cffi beside the
double build on
- every contract scenario through the realistic sensor (seed 0): the roll and pitch RMSE against
  the truth, float and double, and their difference;
- every BROAD trial in BROAD_DIR: the inclination RMSE against the optical reference;
- 10^6 samples (roll_pitch, 10^4 s at 100 Hz): the largest difference between the float and the
  double estimate over the run and over its last tenth (a divergence grows; rounding does not).
The desktop's float arithmetic is the IEEE single precision a Cortex-M4F's FPU computes; the
float libm functions are glibc's here and newlib's there (the microcontroller run measures its
own difference from the desktop's double build beside this).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.native.library import CFLAGS, cdef, compiler, declarations

from .build import ESTIMATORS, OUT, desktop_table, realistic_samples, twin_sources

REAL_FLAGS = ("-DFC_REAL_FLOAT=1", "-fsingle-precision-constant")
LONG_SAMPLES = 1_000_000


class FloatTwin:
    """The float build's estimators through cffi."""

    def __init__(self, folder: Path = OUT) -> None:
        cc = compiler()
        if cc is None:
            raise RuntimeError("no C compiler found: the float build cannot be measured")
        folder.mkdir(parents=True, exist_ok=True)
        lib = folder / "libfusion_core_float.so"
        subprocess.run([cc, *CFLAGS, *REAL_FLAGS, "-o", str(lib), *map(str, twin_sources()),
                        "-lm"], check=True, capture_output=True, text=True)
        self.ffi = declarations(cdef("float"))
        self.lib = self.ffi.dlopen(str(lib))

    def run(self, key: str, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
            params: dict[str, Any] | None = None) -> np.ndarray:
        """[N, 11] estimates (roll, pitch, bias, pos, vel) of the float build."""
        from fusion_core.native.estimators import twin_params
        from fusion_core.registry import create

        ffi, lib = self.ffi, self.lib
        est = create(key, params or {})  # the values, checked as the double build's are
        prefix = type(est).TWIN
        p = twin_params(ffi, est)
        f = ffi.new(f"{prefix} *")
        getattr(lib, f"{prefix}_init")(f, p)
        n = len(acc)
        a = np.ascontiguousarray(acc, dtype=np.float32)
        g = np.ascontiguousarray(gyro, dtype=np.float32)
        d = np.ascontiguousarray(dt, dtype=np.float32)
        out = ffi.new("fc_estimate[]", n)
        rejected = ffi.new("unsigned char[]", n)
        getattr(lib, f"{prefix}_run")(f, n, ffi.cast("float *", a.ctypes.data),
                                      ffi.cast("float *", g.ctypes.data),
                                      ffi.cast("float *", d.ctypes.data), out, rejected)
        return np.frombuffer(ffi.buffer(out), dtype=np.float32).reshape(n, 11).astype(float)


def contract_scenarios(twin: FloatTwin) -> dict[str, Any]:
    """Per scenario and estimator: roll and pitch RMSE [deg] of both builds and the largest
    difference of the two RMSEs."""
    from fusion_core.scenarios import ESTIMATION_SCENARIOS
    from fusion_core.synthetic import TRUTH_NAMES

    from .. import contract

    rows: dict[str, Any] = {}
    for name in ESTIMATION_SCENARIOS:
        t, truth_array, out = realistic_samples(name)
        truth = {n: truth_array[:, i] for i, n in enumerate(TRUTH_NAMES)}
        for key in ESTIMATORS:
            both = {}
            for build, est in (("double", desktop_table(key, out["acc"], out["gyro"], out["dt"])),
                               ("float", twin.run(key, out["acc"], out["gyro"], out["dt"]))):
                er, ep, keep = contract.attitude_errors(name, t, truth, est[:, 0], est[:, 1])
                both[build] = (contract.scored_rmse(er, keep), contract.scored_rmse(ep, keep))
            diff = max(abs(both["float"][i] - both["double"][i]) for i in range(2))
            rows.setdefault(name, {})[key] = {"double": both["double"], "float": both["float"],
                                              "rmse_diff_deg": diff}
    return rows


def broad_trials(twin: FloatTwin, folder: Path) -> dict[str, Any]:
    """Per BROAD trial and attitude estimator: the inclination RMSE [deg] of both builds."""
    from ..broad.data import load_trial
    from ..broad.metric import gravity_from_quat, gravity_from_roll_pitch, inclination_rmse_deg
    from ..broad.run import collect_paths

    rows: dict[str, Any] = {}
    for path in collect_paths([folder]):
        trial = load_trial(path)
        dt = np.full(trial.n, trial.dt)
        params = {"gyro_sampling": trial.gyro_sampling, "sensor_delay": trial.sensor_delay}
        ref = gravity_from_quat(trial.opt_quat)
        for key in ESTIMATORS:
            res = {}
            for build, est in (("double", desktop_table(key, trial.acc, trial.gyro, dt, params)),
                               ("float", twin.run(key, trial.acc, trial.gyro, dt, params))):
                res[build] = inclination_rmse_deg(gravity_from_roll_pitch(est[:, 0], est[:, 1]),
                                                  ref, trial.movement)
            rows.setdefault(trial.name, {})[key] = {
                **res, "rmse_diff_deg": abs(res["float"] - res["double"])}
    return rows


def long_run(twin: FloatTwin) -> dict[str, Any]:
    """10^6 samples of roll_pitch: the largest roll/pitch difference [deg] between the builds
    over the whole run and over its last tenth, and whether every float output stayed finite."""
    from ..samples import forget

    _, _, out = realistic_samples("roll_pitch", duration=LONG_SAMPLES / 100.0)
    rows: dict[str, Any] = {}
    for key in ESTIMATORS:
        d = desktop_table(key, out["acc"], out["gyro"], out["dt"])
        f = twin.run(key, out["acc"], out["gyro"], out["dt"])
        diff = np.degrees(np.max(np.abs(f[:, :2] - d[:, :2]), axis=1))
        tail = diff[int(0.9 * len(diff)):]
        rows[key] = {"max_diff_deg": float(np.max(diff)), "last_tenth_max_diff_deg":
                     float(np.max(tail)), "finite": bool(np.all(np.isfinite(f)))}
    forget()  # a million samples need not stay in the process
    return rows


def measure(folder: Path = OUT) -> dict[str, Any]:
    """Everything above (the float library built in folder); BROAD where BROAD_DIR holds
    trials."""
    twin = FloatTwin(folder)
    result: dict[str, Any] = {"contract_scenarios": contract_scenarios(twin),
                              "long_run": long_run(twin)}
    broad = os.environ.get("BROAD_DIR")
    if broad and Path(broad).is_dir():
        result["broad"] = broad_trials(twin, Path(broad))
    return result


def summary_lines(result: dict[str, Any]) -> list[str]:
    lines = ["float against double (desktop, IEEE single precision):"]
    for label, key in (("contract scenarios", "contract_scenarios"), ("BROAD trials", "broad")):
        if key not in result:
            lines.append(f"  {label}: not measured (set BROAD_DIR to BROAD's trials)")
            continue
        worst = {k: max(r[k]["rmse_diff_deg"] for r in result[key].values())
                 for k in ESTIMATORS}
        lines.append(f"  {label}, largest RMSE difference [deg]: "
                     + ", ".join(f"{k} {v:.2g}" for k, v in worst.items()))
    lines.append(f"  {LONG_SAMPLES:.0e} samples, largest difference [deg] (last tenth): "
                 + ", ".join(f"{k} {v['max_diff_deg']:.2g} ({v['last_tenth_max_diff_deg']:.2g})"
                             + ("" if v["finite"] else " NOT FINITE")
                             for k, v in result["long_run"].items()))
    return lines
