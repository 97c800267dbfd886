"""The C twin on an Arm Cortex-M under QEMU: the build, the run and the report of `make embedded`
(testbenches.embedded.cli).

For each target (TARGETS) the twins are cross-compiled with the desktop's floating-point rules
(-ffp-contract=off, no fast-math) together with bench_main.c, startup.c, mps2.ld and the
generated bench_data.h: a few thousand samples of a contract scenario and, where BROAD_DIR
holds BROAD trials, of one trial, with the desktop build's estimates for every estimator, and
tables of arguments and glibc results for every libm function the twins call. QEMU runs the
program on the MPS2 board of the target's core with semihosting and -icount (SysTick then
counts instructions; a loop of a known number of instructions calibrates the count). The
result, per target and estimator: the largest difference from the desktop build on every
output, the instructions per sample, RAM per instance (sizeof of the twin's struct: its
parameters and state) and flash (arm-none-eabi-size of the twin's objects); per libm function,
how many results differ from glibc's. It is printed and written to build/embedded/report.json.

Where the tools are missing it says which Debian packages to install and exits 0.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import math
import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.registry import REGISTRY

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
TWIN = REPO / "fusion_core" / "native"
OUT = REPO / "build" / "embedded"
RATE = 100.0
"""The contract scenarios' sample rate [Hz]."""
N = 1500
"""Samples per recording (flash holds the recordings and the desktop's estimates)."""
LIBM_N = 1000
TWINS = {e.key: e.twin for e in REGISTRY if e.twin is not None}
"""Every registry estimator with a C twin, key -> the twin's prefix: the runs of bench_main.c,
in this order (BENCH_RUN_ALL in the generated bench_data.h)."""
ESTIMATORS = tuple(TWINS)
LIBM = ("sin", "cos", "tan", "asin", "atan2", "exp", "log", "pow", "hypot", "sqrt", "atan")
"""The libm functions the twins call that may round differently (bench_main.c's order)."""
CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-ffunction-sections",
          "-fdata-sections", "-Wall", "-Wno-unused-function")
PACKAGES = "gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"


@dataclass(frozen=True)
class Target:
    name: str
    cpu_flags: tuple[str, ...]
    machine: str
    real: str  # the twins' real type


TARGETS = (
    Target("cortex-m7-double", ("-mcpu=cortex-m7", "-mfpu=fpv5-d16", "-mfloat-abi=hard",
                                "-mthumb"), "mps2-an500", "double"),
    Target("cortex-m4f-float", ("-mcpu=cortex-m4", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard",
                                "-mthumb"), "mps2-an386", "float"),
)


def missing_tools() -> list[str]:
    """The tools `make embedded` needs that are not on the PATH."""
    return [t for t in ("arm-none-eabi-gcc", "arm-none-eabi-size", "qemu-system-arm")
            if shutil.which(t) is None]


def twin_sources() -> list[Path]:
    """Every twin source the estimators need (not the sensor, plant and state tables)."""
    from fusion_core.native.library import SOURCES

    skip = {"fc_noise.c", "fc_sensor.c", "fc_plant.c", "fc_state.c", "fc_state_tables.c"}
    return [TWIN / s for s in SOURCES if s not in skip]


# ----- data ------------------------------------------------------------------------------------

def recordings() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """(name, acc, gyro, dt) of N samples: moderate_dynamics through the realistic sensor (seed
    0), and the first trial in BROAD_DIR where there is one."""
    _, _, out = realistic_samples("moderate_dynamics", duration=N / RATE)
    recs = [("moderate_dynamics", out["acc"], out["gyro"], out["dt"])]
    broad = os.environ.get("BROAD_DIR")
    if broad and Path(broad).is_dir():
        from ..broad.data import load_trial
        from ..broad.run import collect_paths

        files = collect_paths([Path(broad)])
        if files:
            trial = load_trial(files[0])
            start = len(trial.acc) // 3  # in motion, past the trial's opening rest
            sl = slice(start, start + N)
            recs.append((f"broad_{files[0].stem}", trial.acc[sl], trial.gyro[sl],
                         np.full(N, 1.0 / trial.rate)))
    return recs


def realistic_samples(scenario: str, seed: int = 0, duration: float | None = None) -> Any:
    """A scenario through the realistic sensor part of a seed: times, truth and samples
    (testbenches.samples, the campaigns' data flow)."""
    from fusion_core.sensor import sensor_preset

    from ..samples import scenario_samples

    return scenario_samples(scenario, seed, sensor_preset("realistic"), duration)


def desktop_table(key: str, acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray,
                  params: dict[str, Any] | None = None) -> np.ndarray:
    """[N, 11]: an estimator's estimates (roll, pitch, bias, pos, vel; fc_estimate's order)
    from the desktop's double C twin."""
    from fusion_core.registry import create

    out = create(key, params or {}).run(acc, gyro, dt, backend="native")
    table = np.zeros((len(acc), 11))
    table[:, 0], table[:, 1], table[:, 2:5] = out["roll"], out["pitch"], out["bias"]
    if "pos" in out:
        table[:, 5:8], table[:, 8:11] = out["pos"], out["vel"]
    return table


def desktop_estimates(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """[5, N, 11]: every estimator's desktop_table with the recommended parameters."""
    return np.array([desktop_table(key, acc, gyro, dt) for key in ESTIMATORS])


def libm_table() -> np.ndarray:
    """[len(LIBM), LIBM_N, 3]: arguments (x, y) in the ranges the twins use and glibc's result
    (the desktop's libm, called directly)."""
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    rng = np.random.default_rng(11)
    table = np.zeros((len(LIBM), LIBM_N, 3))
    for f, name in enumerate(LIBM):
        fn = getattr(libm, name)
        two = name in ("atan2", "pow", "hypot")
        fn.argtypes = [ctypes.c_double] * (2 if two else 1)
        fn.restype = ctypes.c_double
        x = {"sin": rng.uniform(-4.0, 4.0, LIBM_N), "cos": rng.uniform(-4.0, 4.0, LIBM_N),
             "tan": rng.uniform(-1.5, 1.5, LIBM_N), "asin": rng.uniform(-1.0, 1.0, LIBM_N),
             "atan2": rng.normal(0.0, 5.0, LIBM_N), "exp": rng.uniform(-30.0, 5.0, LIBM_N),
             "log": np.exp(rng.uniform(-10.0, 10.0, LIBM_N)),
             "pow": rng.normal(0.0, 3.0, LIBM_N), "hypot": rng.normal(0.0, 5.0, LIBM_N),
             "sqrt": np.exp(rng.uniform(-20.0, 10.0, LIBM_N)),
             "atan": rng.normal(0.0, 2.0, LIBM_N)}[name]
        y = (np.where(rng.random(LIBM_N) < 0.8, 2.0, 5.0) if name == "pow"
             else rng.normal(0.0, 5.0, LIBM_N) if two else np.zeros(LIBM_N))
        table[f, :, 0], table[f, :, 1] = x, y
        table[f, :, 2] = [fn(a, b) if two else fn(a) for a, b in zip(x, y, strict=True)]
    return table


def _c_array(values: np.ndarray) -> str:
    flat = np.asarray(values, dtype=float).ravel()
    return ",".join(float(v).hex() if math.isfinite(v) else ("NAN" if math.isnan(v) else
                    ("INFINITY" if v > 0 else "-INFINITY")) for v in flat)


def write_data(folder: Path) -> list[str]:
    """bench_data.h: the recordings, the desktop's estimates, the libm tables; their names."""
    recs = recordings()
    lines = ["/* generated by testbenches.embedded: do not edit */", "#ifndef BENCH_DATA_H",
             "#define BENCH_DATA_H", '#include "fc_real.h"',
             *(f'#include "{twin}.h"' for twin in TWINS.values()),
             "#define BENCH_RUN_ALL() do { " + " ".join(
                 f'RUN({twin}, "{key}", {i});' for i, (key, twin) in enumerate(TWINS.items()))
             + " } while (0)",
             f"#define BENCH_N {N}",
             f"#define BENCH_RECORDINGS {len(recs)}", f"#define BENCH_LIBM_N {LIBM_N}",
             f"#define BENCH_LIBM_FUNCTIONS {len(LIBM)}",
             "static const char *const bench_recordings[BENCH_RECORDINGS] = {"
             + ",".join(f'"{r[0]}"' for r in recs) + "};",
             "static const char *const bench_libm_names[BENCH_LIBM_FUNCTIONS] = {"
             + ",".join(f'"{n}"' for n in LIBM) + "};"]
    acc = np.array([r[1] for r in recs])
    gyro = np.array([r[2] for r in recs])
    dt = np.array([r[3] for r in recs])
    expected = np.array([desktop_estimates(r[1], r[2], r[3]) for r in recs])
    lines += [
        f"static const fc_real bench_acc[BENCH_RECORDINGS][BENCH_N][3] = {{{_c_array(acc)}}};",
        f"static const fc_real bench_gyro[BENCH_RECORDINGS][BENCH_N][3] = {{{_c_array(gyro)}}};",
        f"static const fc_real bench_dt[BENCH_RECORDINGS][BENCH_N] = {{{_c_array(dt)}}};",
        f"static const double bench_expected[BENCH_RECORDINGS][{len(ESTIMATORS)}][BENCH_N][11]"
        f" = {{{_c_array(expected)}}};",
        f"static const double bench_libm[BENCH_LIBM_FUNCTIONS][BENCH_LIBM_N][3] = "
        f"{{{_c_array(libm_table())}}};",
        "#endif"]
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "bench_data.h").write_text("\n".join(lines) + "\n")
    return [r[0] for r in recs]


# ----- build and run ---------------------------------------------------------------------------

def _run(cmd: list[str], **kw: Any) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False, **kw)
    if proc.returncode != 0:
        said = (proc.stdout + proc.stderr)[-3000:]
        raise RuntimeError(f"{' '.join(cmd[:3])} ... failed:\n{said}")
    return proc


def real_flags(target: Target, twin: bool = True) -> list[str]:
    """The real type's flags: for float, FC_REAL_FLOAT, and for the twins' sources single
    precision literals too (not for the bench's own tables, which hold the desktop's doubles)."""
    if target.real != "float":
        return []
    return ["-DFC_REAL_FLOAT=1", *(["-fsingle-precision-constant"] if twin else [])]


def _objects(target: Target, folder: Path) -> list[Path]:
    """The twins' objects for a target (in folder/obj_<target>)."""
    objects = folder / f"obj_{target.name}"
    objects.mkdir(parents=True, exist_ok=True)
    out = []
    for source in twin_sources():
        obj = objects / (source.stem + ".o")
        _run(["arm-none-eabi-gcc", *target.cpu_flags, *CFLAGS, *real_flags(target), "-c",
              "-I", str(TWIN), str(source), "-o", str(obj)])
        out.append(obj)
    return out


def build(target: Target, folder: Path) -> Path:
    """The bench program's ELF for a target."""
    elf = folder / f"bench_{target.name}.elf"
    cmd = ["arm-none-eabi-gcc", *target.cpu_flags, *CFLAGS, *real_flags(target, twin=False),
           "--specs=rdimon.specs", "-T", str(HERE / "mps2.ld"), "-Wl,--gc-sections",
           "-I", str(TWIN), "-I", str(folder), str(HERE / "startup.c"),
           str(HERE / "bench_main.c"), *map(str, _objects(target, folder)), "-lm", "-o", str(elf)]
    _run(cmd)
    return elf


def flash_sizes(target: Target, folder: Path) -> dict[str, int]:
    """Code and constant data [bytes] of each estimator's twin: its objects' text + data
    (arm-none-eabi-size), fc_core included, as a firmware that uses that estimator alone
    links them."""
    from fmu_src.native.build import twin_closure

    objects = folder / f"obj_{target.name}"  # built by build()
    sizes: dict[str, int] = {}
    for key in ESTIMATORS:
        files = ["fc_core.c", *twin_closure(TWINS[key])]
        out = _run(["arm-none-eabi-size", "-t",
                    *(str(objects / (Path(f).stem + ".o")) for f in files)]).stdout
        total = out.strip().splitlines()[-1].split()
        sizes[key] = int(total[0]) + int(total[1])  # text + data
    return sizes


def run_qemu(target: Target, elf: Path, timeout: float = 900.0) -> str:
    """The program's console output under QEMU (semihosting, instruction counting)."""
    proc = subprocess.run(["qemu-system-arm", "-M", target.machine, "-nographic", "-semihosting",
                           "-icount", "shift=0", "-kernel", str(elf)],
                          capture_output=True, text=True, timeout=timeout, check=False)
    if "DONE" not in proc.stdout:
        raise RuntimeError(f"QEMU ({target.machine}) did not finish the bench:\n"
                           f"{(proc.stdout + proc.stderr)[-3000:]}")
    return proc.stdout


def parse(output: str, flash: dict[str, int]) -> dict[str, Any]:
    """The report of one target from the program's lines."""
    cal = re.search(r"^CAL (\d+) (\d+)$", output, re.M)
    assert cal is not None
    insns_per_tick = int(cal.group(2)) / int(cal.group(1))
    estimators: dict[str, Any] = {}
    for m in re.finditer(r"^RESULT (\S+) (\S+) (\d+) (\d+) (\S+) (\S+) (\S+) (\S+) (\S+) "
                         r"(-?\d+) (-?\d+)$", output, re.M):
        rec, key = m.group(1), m.group(2)
        diffs = [float(m.group(i)) for i in range(5, 10)]
        e = estimators.setdefault(key, {"max_abs_diff": 0.0, "ram_bytes": int(m.group(4)),
                                        "flash_bytes": flash[key], "recordings": {}})
        e["recordings"][rec] = {
            "max_abs_diff": dict(zip(("roll", "pitch", "bias", "pos", "vel"), diffs,
                                     strict=True)),
            "samples_differing": int(m.group(10)), "first_differing": int(m.group(11)),
            "insns_per_sample": int(m.group(3)) * insns_per_tick / N}
        e["max_abs_diff"] = max(e["max_abs_diff"], *diffs)
    for e in estimators.values():
        e["insns_per_sample"] = float(np.mean([r["insns_per_sample"]
                                               for r in e["recordings"].values()]))
    libm = {m.group(1): {"differing": int(m.group(2)), "of": int(m.group(3)),
                         "worst_ulp": float(m.group(4))}
            for m in re.finditer(r"^LIBM (\S+) (\d+) (\d+) (\S+)$", output, re.M)}
    return {"estimators": estimators, "libm": libm, "insns_per_tick": insns_per_tick}


def report_lines(report: dict[str, Any]) -> list[str]:
    lines = []
    for target, r in report.items():
        lines.append(f"{target}:")
        lines.append(f"  {'estimator':<9}{'max |diff|':>12}{'insns/sample':>14}"
                     f"{'RAM [B]':>10}{'flash [B]':>11}")
        for key, e in r["estimators"].items():
            lines.append(f"  {key:<9}{e['max_abs_diff']:>12.3g}{e['insns_per_sample']:>14.0f}"
                         f"{e['ram_bytes']:>10}{e['flash_bytes']:>11}")
        differing = {n: v for n, v in r["libm"].items() if v["differing"]}
        if not r["libm"]:
            continue
        lines.append("  libm against glibc: " + (", ".join(
            f"{n} differs in {v['differing']} of {v['of']} (up to {v['worst_ulp']:.2g} ulp)"
            for n, v in differing.items()) or "every result the same"))
    return lines


def build_example(target: Target, folder: Path) -> str:
    """examples/mcu_main_loop.c for a target, run under QEMU: what it says at its end."""
    elf = folder / f"mcu_main_loop_{target.name}.elf"
    _run(["arm-none-eabi-gcc", *target.cpu_flags, *CFLAGS, "--specs=rdimon.specs", "-T",
          str(HERE / "mps2.ld"), "-Wl,--gc-sections", "-I", str(TWIN), str(HERE / "startup.c"),
          str(REPO / "examples" / "mcu_main_loop.c"), *map(str, _objects(target, folder)),
          "-lm", "-o", str(elf)])
    proc = subprocess.run(["qemu-system-arm", "-M", target.machine, "-nographic",
                           "-semihosting", "-kernel", str(elf)],
                          capture_output=True, text=True, timeout=300, check=False)
    if proc.returncode != 0 or "roll" not in proc.stdout:
        raise RuntimeError(f"the example did not run: {(proc.stdout + proc.stderr)[-2000:]}")
    return proc.stdout.strip().splitlines()[-1]

