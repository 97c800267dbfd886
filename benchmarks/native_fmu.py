"""The native FMUs in the `native` section: FMU step cost per kind, the floor, a C host's own loop
and the testbench, all measured in one run beside the pythonfmu FMUs.

fmu_step_us       {kind: {estimator: us}}: one set-inputs / doStep / get-outputs cycle through
                  the ctypes functions fmpy loaded, with ctypes arrays made once and the
                  statuses checked (the testbench master's way), for pythonfmu, native fmi2
                  and native fmi3;
fmu_floor_us      {kind: us}: the same cycle on a floor FMU of that kind whose calls return at
                  once (benchmarks/native_floor.c; fmu.FLOOR_MODULE for pythonfmu): the host's
                  side of every step, which no FMU can go below;
fmu_step_speedup_vs_pythonfmu  {estimator: pythonfmu / native fmi2};
c_host_step_us    {version: {estimator: us}}: the cycle in a C host's own loop
                  (benchmarks/native_host_bench.c, best of its passes): the true cost of a
                  native FMU step, against the C twin's batch run per sample (c_host_vs_twin);
testbench_rtf_1khz {estimator: {native, pythonfmu, ratio}}: plant -> sensor -> estimator at
                  1 kHz, real-time factor of each kind.
"""

from __future__ import annotations

import subprocess
import tempfile
from collections.abc import Callable
from ctypes import byref
from pathlib import Path
from typing import Any

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64, fmi3True, fmi3ValueReference

from fmu_src.host import INPUTS
from testbenches.fmus import direct_calls

from .common import time_interleaved
from .fmu import FMU_NAMES, REPO, FmuPasses, _output_names, build_floor_fmu
from .testbench import testbench_rate

HERE = Path(__file__).resolve().parent
FLOOR = "FmuFloor"


def build_native_floor(out: Path) -> dict[str, Path]:
    """The native floor FMU, FMI 2.0 and 3.0, with the position filter's inputs and outputs."""
    from fmu_src.native.build import NativeModel, build_native, native_model

    variables = tuple(v for v in native_model("PositionKalmanFilter").variables
                      if v.causality in ("input", "output"))
    model = NativeModel(FLOOR, "Benchmark floor: FMI calls that return at once", variables,
                        "floor", source=HERE / "native_floor.c")
    return {v: build_native(model, v, out, windows=False) for v in ("fmi2", "fmi3")}


class Fmi3Passes:
    """FmuPasses for an FMI 3.0 FMU: fmpy's wrapped fmi3SetFloat64 / fmi3DoStep /
    fmi3GetFloat64 on ctypes arrays made once."""

    def __init__(self, key: str, path: Path, data: list[list[float]]) -> None:
        self.key, self.path, self.data = key, path, data
        self.md = read_model_description(str(path))
        self.unzipdir = extract(str(path))
        self.fmu: FMU3Slave | None = None

    def close(self) -> None:
        if self.fmu is not None:
            self.fmu.freeInstance()
            self.fmu = None

    def __call__(self) -> Callable[[], int]:
        self.close()
        fmu = self.fmu = FMU3Slave(guid=self.md.instantiationToken, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName=f"bench-{self.key}")
        fmu.instantiate()
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        by_name = {v.name: v.valueReference for v in self.md.modelVariables}
        in_vr = [by_name[n] for n in INPUTS]
        out_vr = [by_name[n] for n in _output_names(self.key)]
        n_in, n_out = len(in_vr), len(out_vr)
        vr_in = (fmi3ValueReference * n_in)(*in_vr)
        vr_out = (fmi3ValueReference * n_out)(*out_vr)
        values = (fmi3Float64 * n_in)()
        outputs = (fmi3Float64 * n_out)()
        flags = [fmi3Boolean() for _ in range(3)]
        last = fmi3Float64()
        refs = [byref(f) for f in flags] + [byref(last)]
        component, data = fmu.component, self.data
        c_set, c_step, c_get = direct_calls(fmu, "fmi3SetFloat64", "fmi3DoStep",
                                            "fmi3GetFloat64")
        h = 0.01

        def run() -> int:
            t = 0.0
            for sample in data:  # as FmuPasses' low-level host: statuses checked in the loop
                values[:] = sample
                a = c_set(component, vr_in, n_in, values, n_in)
                b = c_step(component, t, h, fmi3True, *refs)
                c = c_get(component, vr_out, n_out, outputs, n_out)
                if a > 1 or b > 1 or c > 1:
                    raise RuntimeError(f"{self.path.name}: an FMI call failed at t = {t}")
                outputs[:]  # read back as Python floats, as a host would
                t += h
            return len(data)

        return run


def _c_host(tmp: Path) -> Path | None:
    from fusion_core.native import compiler

    cc = compiler()
    if cc is None:
        return None
    exe = tmp / "native_host_bench"
    subprocess.run([cc, "-std=c99", "-O2", "-I", str(REPO / "fmu_src" / "native" / "include"),
                    "-o", str(exe), str(HERE / "native_host_bench.c"), "-ldl"],
                   check=True, capture_output=True, text=True)
    return exe


def c_host_steps(keys: tuple[str, ...], native_dir: Path, data: list[list[float]],
                 tmp: Path, passes: int) -> dict[str, dict[str, float]]:
    """{version: {estimator: us per step}} in the C host's own loop."""
    exe = _c_host(tmp)
    if exe is None:
        return {}
    samples = tmp / "samples.bin"
    np.asarray(data, dtype=np.float64).tofile(samples)
    out: dict[str, dict[str, float]] = {}
    for version in ("fmi2", "fmi3"):
        out[version] = {}
        for key in keys:
            path = native_dir / version / f"{FMU_NAMES[key]}.fmu"
            md = read_model_description(str(path))
            unzipdir = extract(str(path), unzipdir=str(tmp / f"{version}-{key}"))
            binary = Path(unzipdir) / "binaries" / (
                "linux64" if version == "fmi2" else "x86_64-linux") / f"{FMU_NAMES[key]}.so"
            by_name = {v.name: v.valueReference for v in md.modelVariables}
            vrs = [str(by_name[n]) for n in _output_names(key)]
            token = md.instantiationToken if version == "fmi3" else md.guid
            proc = subprocess.run([str(exe), version[-1], str(binary), token, str(samples),
                                   str(passes), *vrs], capture_output=True, text=True,
                                  check=True)
            out[version][key] = float(proc.stdout)
    return out


def native_fmu_section(keys: tuple[str, ...], fmu_dir: Path, data: list[list[float]],
                       repeats: int, testbench_s: float, testbench_repeats: int,
                       log: Any = print) -> dict[str, Any]:
    """The native FMUs' keys of the `native` section (see the module docstring). fmu_dir: a
    build_fmu.py --kind all output folder."""
    native_dir = fmu_dir / "native"
    if not (native_dir / "fmi2" / "ImuPlant.fmu").is_file():
        return {"native_fmus": "not built (no C compiler)"}
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="bench_native_fmu_") as tmp_name:
        tmp = Path(tmp_name)
        log("native FMU steps: pythonfmu, native fmi2 and fmi3, and their floors, in turn")
        floors = build_native_floor(tmp / "floor")
        py_floor = build_floor_fmu(tmp / "pyfloor")
        passes: dict[str, Any] = {}
        for key in keys:
            passes[f"pythonfmu.{key}"] = FmuPasses(key, fmu_dir, data, "lowlevel")
            passes[f"fmi2.{key}"] = FmuPasses(key, native_dir / "fmi2", data, "lowlevel")
            passes[f"fmi3.{key}"] = Fmi3Passes(key, native_dir / "fmi3" /
                                               f"{FMU_NAMES[key]}.fmu", data)
        passes["pythonfmu.floor"] = FmuPasses("poskf", fmu_dir, data, "lowlevel", py_floor)
        passes["fmi2.floor"] = FmuPasses("poskf", fmu_dir, data, "lowlevel", floors["fmi2"])
        passes["fmi3.floor"] = Fmi3Passes("poskf", floors["fmi3"], data)
        try:
            timed = time_interleaved(passes, repeats)
        finally:
            for p in passes.values():
                p.close()
        med = {name: v["median_us"] for name, v in timed.items()}
        kinds = ("pythonfmu", "fmi2", "fmi3")
        out["fmu_step_us"] = {k: {key: med[f"{k}.{key}"] for key in keys} for k in kinds}
        out["fmu_floor_us"] = {k: med[f"{k}.floor"] for k in kinds}
        out["fmu_step_speedup_vs_pythonfmu"] = {
            key: med[f"pythonfmu.{key}"] / med[f"fmi2.{key}"] for key in keys}
        log("native FMU steps in a C host's own loop")
        out["c_host_step_us"] = c_host_steps(keys, native_dir, data, tmp, max(repeats, 3))
        log("testbench at 1 kHz: native against pythonfmu FMUs")
        rtf: dict[str, dict[str, float]] = {}
        for key in keys:
            nat = testbench_rate(key, 1000.0, testbench_s, native_dir / "fmi2",
                                 testbench_repeats)["real_time_factor"]
            py = testbench_rate(key, 1000.0, testbench_s, fmu_dir,
                                testbench_repeats)["real_time_factor"]
            rtf[key] = {"native": nat, "pythonfmu": py, "ratio": nat / py}
        out["testbench_rtf_1khz"] = rtf
    return out
