"""Mutated FMU states through every native FMU, under AddressSanitizer and UBSan.

tests/native/state_fuzz.c is compiled with each model's own FMU sources (FMI 2.0 and FMI 3.0)
and feeds it mutated states per model and standard (STATES in `make test`, SLOW_STATES in
`make test-slow`), taken from valid ones (before and
during initialisation, aligning, in motion, at rest): bit flips, an extreme value in one variable
or state field, integer fields, the FMI state, the time and header fields out of range,
truncations, lengths off by one, mostly with the checksum recomputed so that the mutation
reaches the field checks. Nothing may read or write outside the FMU's memory (the sanitizers
abort the run), a refused state must come back as an error status with a log line, and an
accepted one must give finite outputs, then and over the next samples.

Where the compiler has no sanitizers the run goes under valgrind with fewer states, or plain
(said in the printed table); where there is no compiler at all, it skips with the reason.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from conftest import REPO

from fmu_src.names import model_names
from fmu_src.native.build import cached_object, native_model, stage_sources
from fusion_core.native import compiler

STATES = 8_000
"""Mutated states per model and standard in `make test`."""
SLOW_STATES = 100_000
"""Mutated states per model and standard in `make test-slow`."""
VALGRIND_STATES = 5_000
"""Under valgrind (no sanitizers in the compiler), which runs some 30 times slower."""
FUZZ_HOST = REPO / "tests" / "native" / "state_fuzz.c"
SANITIZE = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer")
LINE = re.compile(r"tried (\d+) refused (\d+) accepted (\d+) nonfinite (\d+) silent (\d+) "
                  r"state_bytes (\d+)")


def _kind(name: str) -> str:
    return {"ImuSensor": "SENSOR", "ImuPlant": "PLANT"}.get(name, "ESTIMATOR")


def _sanitizers(cc: str, folder: Path) -> bool:
    """Whether cc builds and runs a program with AddressSanitizer and UBSan."""
    src = folder / "probe.c"
    src.write_text("int main(void) { return 0; }\n")
    exe = folder / "probe"
    built = subprocess.run([cc, *SANITIZE, "-o", str(exe), str(src)], capture_output=True,
                           check=False)
    return built.returncode == 0 and subprocess.run([str(exe)], check=False).returncode == 0


def _fuzz(cc: str, name: str, version: str, folder: Path, mode: str, states: int) -> dict:
    sources = folder / f"{name}-{version}"
    files = stage_sources(native_model(name), version, sources)
    shutil.copy(FUZZ_HOST, sources / FUZZ_HOST.name)
    exe = sources / "state_fuzz"
    flags = ["-std=c99", "-O1", "-g", "-ffp-contract=off", "-fno-fast-math",
             *(SANITIZE if mode == "asan" else ()), f"-DFUZZ_FMI={version[-1]}",
             f"-DFUZZ_KIND_{_kind(name)}"]
    # each source through the native build's object cache: what the models share (the FMI
    # plumbing, the twins) is compiled once per standard and kind of model, not per FMU
    objects = [str(cached_object(cc, flags, sources, f, exe.name))
               for f in (FUZZ_HOST.name, *files)]
    link = [cc, *(SANITIZE if mode == "asan" else ()), "-o", str(exe), *objects, "-lm"]
    built = subprocess.run(link, capture_output=True, text=True, check=False)
    assert built.returncode == 0, built.stderr[-3000:]
    states = min(states, VALGRIND_STATES) if mode == "valgrind" else states
    run = [str(exe), str(states), "36"]
    if mode == "valgrind":
        run = ["valgrind", "-q", "--error-exitcode=9", *run]
    proc = subprocess.run(run, capture_output=True, text=True, timeout=1800, check=False,
                          env={**os.environ, "ASAN_OPTIONS": "detect_leaks=1"})
    found = LINE.search(proc.stdout)
    return {"name": name, "version": version, "returncode": proc.returncode,
            "stderr": proc.stderr[-4000:], "counts": tuple(map(int, found.groups()))
            if found else None}


@pytest.mark.parametrize("states", [
    pytest.param(STATES, id="make-test"),
    pytest.param(SLOW_STATES, id="slow", marks=pytest.mark.slow)])
def test_mutated_states_never_crash_or_corrupt_a_native_fmu(states: int) -> None:
    cc = compiler()
    if cc is None:
        pytest.skip("no C compiler (set CC, or install cc, gcc or clang): no native FMUs")
    with tempfile.TemporaryDirectory(prefix="state_fuzz_") as tmp:
        folder = Path(tmp)
        mode = ("asan" if _sanitizers(cc, folder)
                else "valgrind" if shutil.which("valgrind") else "plain")
        jobs = [(name, v) for name in model_names() for v in ("fmi2", "fmi3")]
        with ThreadPoolExecutor(max_workers=max(os.cpu_count() or 1, 1)) as pool:
            results = list(pool.map(lambda job: _fuzz(cc, *job, folder, mode, states), jobs))
    print(f"\nmutated FMU states ({'AddressSanitizer + UBSan' if mode == 'asan' else mode}):")
    print(f"{'model':34s} {'FMI':4s} {'tried':>8s} {'refused':>8s} {'accepted':>8s} "
          f"{'non-finite':>10s} {'state bytes':>11s}")
    for r in results:
        assert r["counts"] is not None and r["returncode"] == 0, (r["name"], r["version"],
                                                                   r["stderr"])
        tried, refused, accepted, nonfinite, silent, size = r["counts"]
        print(f"{r['name']:34s} {r['version'][-1]}.0  {tried:8d} {refused:8d} {accepted:8d} "
              f"{nonfinite:10d} {size:11d}")
        assert nonfinite == 0 and silent == 0
        assert refused > tried // 4 and accepted > tried // 10  # both paths exercised
