"""FMU cost per step: set inputs + doStep + get outputs through fmpy, per estimator FMU.

Two hosts, both fmpy's FMU2Slave:
  api       setReal(list) / doStep / getReal(list), what testbenches.master does: fmpy builds
            ctypes arrays from the lists on every call;
  lowlevel  the FMI functions as the ctypes functions fmpy loaded (fmi2SetReal, fmi2DoStep,
            fmi2GetReal; testbenches.fmus.direct_calls, the statuses checked in the loop) with
            ctypes arrays allocated once: the testbench master's way.
The overhead is the FMU step time less what its doStep runs per sample (the C twin's step
through fusion_core.native.Stepper where it loads, else fusion_core's Python step), timed in
turn with it.

The floor: the same two hosts on `FmuFloor`, an FMU with the estimator FMUs' inputs and outputs
whose set_real, do_step and get_real return at once. Its step time is what fmpy, ctypes and
pythonfmu's C++ wrapper (a Python call per FMI call, with its argument lists and its log-queue
check) cost with no work behind them: no slave of ours can take the overhead below it.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fmpy.fmi2 import fmi2Real, fmi2True, fmi2ValueReference

from fmu_src.host import INPUTS, FmuInstance
from fusion_core.registry import FMU_NAMES
from testbenches.fmus import direct_calls

from .common import time_interleaved
from .estimators import fmu_core_pass

REPO = Path(__file__).resolve().parents[1]
OUTPUTS = ("roll", "pitch", "bias_x", "bias_y", "bias_z")
POSITION_OUTPUTS = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z")
FLOOR_NAME = "FmuFloor"
FLOOR_MODULE = f'''
"""FmuFloor: the benchmark's floor FMU. The estimator FMUs' inputs and outputs, but set_real,
do_step and get_real return at once: timing it times the host and pythonfmu's wrapper only."""
from fmu_src.slave import FmuSlave
from fmu_src.variables import real_input, real_output


class _NoModel:
    def step(self, t, h, values, log):
        return {{}}

    def set_parameter(self, name, value):
        raise ValueError(name)

    def get_state(self):
        return {{}}

    def set_state(self, state):
        pass


class {FLOOR_NAME}(FmuSlave):
    description = "Benchmark floor: FMI calls that return at once"
    VARIABLES = (
        *(real_input(name, "1", "input, ignored") for name in {INPUTS!r}),
        *(real_output(name, "1", "output, always 0") for name in {OUTPUTS + POSITION_OUTPUTS!r}),
    )

    def create_model(self, params):
        return _NoModel()

    def set_real(self, vrs, values):
        pass

    def get_real(self, vrs):
        return [0.0] * len(vrs)

    def do_step(self, current_time, step_size):
        return True
'''
"""Source of the floor FMU's slave module (built by build_floor_fmu)."""


def build_fmus(out: Path) -> Path:
    """Build every FMU with the project's command line (python build_fmu.py --out out)."""
    proc = subprocess.run(
        [sys.executable, "build_fmu.py", "--out", str(out)],
        cwd=REPO, capture_output=True, text=True, timeout=600,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"build_fmu.py failed:\n{proc.stdout}\n{proc.stderr}")
    return out


def build_floor_fmu(out: Path) -> Path:
    """Build FmuFloor.fmu into out (in a subprocess, as build_fmus: the slave module must not be
    imported into the process that loads the FMU) and return its path."""
    with tempfile.TemporaryDirectory(prefix="fmu_floor_src_") as tmp:
        script = Path(tmp) / "fmu_floor_fmu.py"
        script.write_text(FLOOR_MODULE)
        proc = subprocess.run(
            [sys.executable, "-c", "import sys; from pathlib import Path; from fmu_src.build "
             "import build_script; build_script(Path(sys.argv[1]), Path(sys.argv[2]))",
             str(script), str(out)],
            cwd=REPO, capture_output=True, text=True, timeout=600,
        )
    if proc.returncode != 0:
        raise RuntimeError(f"building {FLOOR_NAME} failed:\n{proc.stdout}\n{proc.stderr}")
    return out / f"{FLOOR_NAME}.fmu"


def _output_names(key: str) -> tuple[str, ...]:
    return OUTPUTS + (POSITION_OUTPUTS if key == "poskf" else ())


class FmuPasses:
    """Pass factory for common.time_interleaved: each call frees the previous FMU instance,
    makes a fresh, initialised one (not timed) and returns the stepping loop; close() frees the
    last one. path: another FMU with the same variables (the floor FMU) instead of key's."""

    def __init__(self, key: str, fmu_dir: Path, data: list[list[float]], host: str,
                 path: Path | None = None) -> None:
        if host not in ("api", "lowlevel"):
            raise ValueError(f"host must be 'api' or 'lowlevel', not {host!r}")
        self.path = fmu_dir / f"{FMU_NAMES[key]}.fmu" if path is None else path
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
        c_set, c_step, c_get = direct_calls(fmu, "fmi2SetReal", "fmi2DoStep", "fmi2GetReal")
        n_in, n_out = len(in_vr), len(out_vr)
        vr_in = (fmi2ValueReference * n_in)(*in_vr)
        vr_out = (fmi2ValueReference * n_out)(*out_vr)
        values = (fmi2Real * n_in)()
        outputs = (fmi2Real * n_out)()

        def run_lowlevel() -> int:
            t = 0.0
            for sample in data:  # with the testbench master's calls and status checks
                values[:] = sample
                a = c_set(component, vr_in, n_in, values)
                b = c_step(component, t, h, fmi2True)
                c = c_get(component, vr_out, n_out, outputs)
                if a > 1 or b > 1 or c > 1:
                    raise RuntimeError(f"{self.path.name}: an FMI call failed at t = {t}")
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
    floor: bool = True,
) -> dict[str, dict[str, Any]]:
    """{estimator: {"core": fusion_core step, "api": fmpy API, "lowlevel": preallocated,
    "floor_api", "floor_lowlevel": the floor FMU with this estimator's outputs}}, all timed in
    turn (common.time_interleaved) so that the overhead, FMU less core, and the floor compare
    passes taken at the same time. floor=False leaves the floor out (and does not build it)."""
    out = {}
    with tempfile.TemporaryDirectory(prefix="fmu_floor_") as tmp:
        floor_path = build_floor_fmu(Path(tmp)) if floor else None
        for key in keys:
            hosts = {host: FmuPasses(key, fmu_dir, data, host) for host in ("api", "lowlevel")}
            if floor_path is not None:
                hosts.update({f"floor_{host}": FmuPasses(key, fmu_dir, data, host, floor_path)
                              for host in ("api", "lowlevel")})
            try:
                out[key] = time_interleaved(
                    {"core": lambda key=key: fmu_core_pass(key, core_data), **hosts}, repeats)
            finally:
                for passes in hosts.values():
                    passes.close()
    return out
