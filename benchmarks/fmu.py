"""FMU cost per step: set inputs + doStep + get outputs through fmpy, per estimator FMU.

Two hosts, both fmpy's FMU2Slave:
  api       setReal(list) / doStep / getReal(list), what testbenches.master does: fmpy builds
            ctypes arrays from the lists on every call;
  lowlevel  fmpy's wrapped FMI functions (fmi2SetReal, fmi2DoStep, fmi2GetReal) with ctypes
            arrays allocated once: what a host can save on its own side.
The overhead is the FMU step time less the same estimator's `step` in fusion_core, timed in
turn with it.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fmpy.fmi2 import fmi2Real, fmi2True, fmi2ValueReference

from fmu_src.host import INPUTS, FmuInstance

from .common import time_interleaved
from .estimators import step_pass

REPO = Path(__file__).resolve().parents[1]
FMU_NAMES = {
    "cf": "ComplementaryFilter",
    "mgcf": "GainScheduledComplementaryFilter",
    "kf": "AngleBiasKalmanFilter",
    "ukf": "UnscentedKalmanFilter",
    "poskf": "PositionKalmanFilter",
}
OUTPUTS = ("roll", "pitch", "bias_x", "bias_y", "bias_z")
POSITION_OUTPUTS = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z")


def build_fmus(out: Path) -> Path:
    """Build every FMU with the project's command line (python build_fmu.py --out out)."""
    proc = subprocess.run(
        [sys.executable, "build_fmu.py", "--out", str(out)],
        cwd=REPO, capture_output=True, text=True, timeout=600,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"build_fmu.py failed:\n{proc.stdout}\n{proc.stderr}")
    return out


def _output_names(key: str) -> tuple[str, ...]:
    return OUTPUTS + (POSITION_OUTPUTS if key == "poskf" else ())


class FmuPasses:
    """Pass factory for common.time_interleaved: each call frees the previous FMU instance,
    makes a fresh, initialised one (not timed) and returns the stepping loop; close() frees the
    last one."""

    def __init__(self, key: str, fmu_dir: Path, data: list[list[float]], host: str) -> None:
        if host not in ("api", "lowlevel"):
            raise ValueError(f"host must be 'api' or 'lowlevel', not {host!r}")
        self.path = fmu_dir / f"{FMU_NAMES[key]}.fmu"
        self.key, self.data, self.host = key, data, host
        self.instance: FmuInstance | None = None

    def close(self) -> None:
        if self.instance is not None:
            self.instance.close()
            self.instance = None

    def __call__(self) -> Callable[[], int]:
        self.close()
        inst = self.instance = FmuInstance(
            self.path, instance_name=f"bench-{self.key}", logging_on=False
        )
        fmu, data = inst.fmu, self.data
        in_vr = inst.vr(INPUTS)
        out_vr = inst.vr(_output_names(self.key))
        h = 1.0 / 100.0
        if self.host == "api":
            set_real, do_step, get_real = fmu.setReal, fmu.doStep, fmu.getReal

            def run() -> int:
                t = 0.0
                for sample in data:
                    set_real(in_vr, sample)
                    do_step(t, h)
                    get_real(out_vr)
                    t += h
                return len(data)

            return run
        component = fmu.component
        c_set, c_step, c_get = fmu.fmi2SetReal, fmu.fmi2DoStep, fmu.fmi2GetReal
        n_in, n_out = len(in_vr), len(out_vr)
        vr_in = (fmi2ValueReference * n_in)(*in_vr)
        vr_out = (fmi2ValueReference * n_out)(*out_vr)
        values = (fmi2Real * n_in)()
        outputs = (fmi2Real * n_out)()

        def run_lowlevel() -> int:
            t = 0.0
            for sample in data:
                values[:] = sample
                c_set(component, vr_in, n_in, values)
                c_step(component, t, h, fmi2True)
                c_get(component, vr_out, n_out, outputs)
                outputs[:]  # read back as Python floats, as a host would
                t += h
            return len(data)

        return run_lowlevel


def fmu_steps(
    keys: tuple[str, ...],
    fmu_dir: Path,
    data: list[list[float]],
    core_data: list[tuple[list[float], list[float], float]],
    repeats: int,
) -> dict[str, dict[str, Any]]:
    """{estimator: {"core": fusion_core step, "api": fmpy API, "lowlevel": preallocated}}, the
    three timed in turn (common.time_interleaved) so that the overhead, FMU less core, compares
    passes taken at the same time."""
    out = {}
    for key in keys:
        hosts = {host: FmuPasses(key, fmu_dir, data, host) for host in ("api", "lowlevel")}
        try:
            out[key] = time_interleaved(
                {"core": lambda key=key: step_pass(key, core_data), **hosts}, repeats)
        finally:
            for passes in hosts.values():
                passes.close()
    return out
