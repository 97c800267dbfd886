"""The native FMUs (FMI 2.0 and 3.0 from the C twin): valid, complete, equal to the pythonfmu FMUs,
and answering a faulty host as docs/interface.md ("FMI calls") says.

Every test here skips with the reason where there is no C compiler (conftest.BuiltFmus.native).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import ESTIMATOR_FMUS, REPO
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.util import read_csv
from fmpy.validation import validate_fmu
from native_fmu import NativeFmu, refused

from fmu_src.build import check
from fmu_src.names import model_names

VERSIONS = ("fmi2", "fmi3")
EXAMPLES = {name: "tilt_motion.csv" for name in ESTIMATOR_FMUS}
EXAMPLES["PositionKalmanFilter"] = "move_2m.csv"
BINARY = {"fmi2": "binaries/linux64", "fmi3": "binaries/x86_64-linux"}


@pytest.fixture(params=VERSIONS)
def version(request: pytest.FixtureRequest) -> str:
    return request.param


@pytest.mark.parametrize("name", model_names())
def test_every_native_fmu_passes_fmpy_validation_and_the_project_checks(built_fmus, version,
                                                                        name):
    path = built_fmus.native(version, name)
    assert validate_fmu(str(path)) == []
    assert check(path) == []


@pytest.mark.parametrize("name", model_names())
def test_a_native_fmu_needs_no_python_and_carries_its_sources(built_fmus, version, name):
    path = built_fmus.native(version, name)
    md = read_model_description(str(path))
    cs = md.coSimulation
    assert cs.needsExecutionTool is False
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        binary = z.read(f"{BINARY[version]}/{name}.so")
    assert b"libpython" not in binary and b"Py_Initialize" not in binary
    sources = {n[len("sources/"):] for n in names if n.startswith("sources/")}
    assert {f"{version}Functions.c", "fmu_instance.c", "config.h", "fc_params.h"} <= sources
    if version == "fmi3":
        assert "buildDescription.xml" in sources
    else:
        listed = md.buildConfigurations[0].sourceFileSets[0].sourceFiles
        assert set(listed) <= sources and f"{version}Functions.c" in listed


def _clean_env() -> dict[str, str]:
    """This process's environment without anything that loads or locates a Python for an FMU."""
    return {k: v for k, v in os.environ.items()
            if k not in ("LD_PRELOAD", "PYTHONHOME", "PYTHONPATH")}


@pytest.fixture(scope="module")
def native_example_runs(built_fmus, tmp_path_factory) -> dict[tuple[str, str], np.ndarray]:
    """Every native estimator FMU, both versions, simulated by fmpy on its example CSV in a
    process with no LD_PRELOAD, PYTHONHOME or PYTHONPATH: nothing there could serve a Python."""
    out = tmp_path_factory.mktemp("native_runs")
    jobs = {f"{name}-{v}": (str(built_fmus.native(v, name)), str(REPO / "examples" / csv))
            for name, csv in EXAMPLES.items() for v in VERSIONS}
    script = (
        "import json, sys, numpy as np\n"
        "from fmpy import simulate_fmu\nfrom fmpy.util import read_csv\n"
        "jobs = json.loads(sys.argv[1])\n"
        "for key, (fmu, csv) in jobs.items():\n"
        "    inp = read_csv(csv)\n"
        "    r = simulate_fmu(fmu, input=inp, output_interval=0.01, stop_time=inp['time'][-1])\n"
        f"    np.save({str(out)!r} + '/' + key + '.npy', r)\n"
    )
    proc = subprocess.run([sys.executable, "-c", script, json.dumps(jobs)], env=_clean_env(),
                          capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    return {tuple(key.split("-")): np.load(out / f"{key}.npy") for key in jobs}


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_native_fmus_equal_the_pythonfmu_fmu_on_the_example(built_fmus, native_example_runs,
                                                            version, name):
    """Every output of the native FMU equals the pythonfmu FMU's (both step the same C twin)."""
    inp = read_csv(REPO / "examples" / EXAMPLES[name])
    ref = simulate_fmu(str(built_fmus.path(name)), input=inp, output_interval=0.01,
                       stop_time=inp["time"][-1])
    got = native_example_runs[(name, version)]
    assert got.dtype.names == ref.dtype.names and len(got) == len(ref) == 1000
    worst = max(float(np.max(np.abs(got[k] - ref[k]))) for k in ref.dtype.names)
    assert worst == 0.0


def _run(fmu: NativeFmu, rec: dict, start: int, stop: int) -> list[tuple[float, ...]]:
    """Steps start..stop-1 of a recording; the estimate after each."""
    out = []
    for k in range(start, stop):
        a, g = rec["acc_meas"][k], rec["gyro_meas"][k]
        fmu.step(0.01 * k, 0.01, acc_x=a[0], acc_y=a[1], acc_z=a[2], gyro_x=g[0], gyro_y=g[1],
                 gyro_z=g[2], dt=rec["dt"][k])
        out.append(tuple(fmu.get(n) for n in ("roll", "pitch", "bias_x", "bias_y", "bias_z")))
    return out


@pytest.mark.parametrize("name", list(ESTIMATOR_FMUS))
def test_a_saved_and_a_serialized_state_continue_bit_for_bit(built_fmus, version, name,
                                                             fmu_recording):
    path = built_fmus.native(version, name)
    fmu = NativeFmu(path, instance="a")
    fmu.instantiate()
    fmu.start()
    _run(fmu, fmu_recording, 0, 400)
    state = fmu.save()
    blob = fmu.serialize(state)
    reference = _run(fmu, fmu_recording, 400, 700)
    fmu.restore(state)
    assert _run(fmu, fmu_recording, 400, 700) == reference
    other = NativeFmu(path, unzipdir=fmu.unzipdir, instance="b")
    other.instantiate()
    other.start()
    other.restore(other.deserialize(blob))
    assert _run(other, fmu_recording, 400, 700) == reference
    for f in (fmu, other):
        f.terminate()
        f.free()


# ----- a faulty host (docs/interface.md, "FMI calls") -------------------------------------------

MISUSE_FMU = "AngleBiasKalmanFilter"


PYTHONFMU_CANNOT = (
    "pythonfmu 0.7 cannot answer with fmi2Error: its wrapper turns a slave's answer into OK, "
    "Discard (do_step returning False) or, for an exception, Fatal, and it checks neither the "
    "call sequence nor the GUID itself"
)


@pytest.fixture(params=[*VERSIONS, "pythonfmu"])
def kf(request: pytest.FixtureRequest, built_fmus) -> NativeFmu:
    """An instantiated kf FMU with logging on (freed after the test): native FMI 2.0 and 3.0,
    and the pythonfmu FMU, which cannot refuse a call (PYTHONFMU_CANNOT: strict xfail, so a
    pythonfmu that learns to refuse shows up as a failure to update this list)."""
    kind = request.param
    if kind == "pythonfmu":
        request.applymarker(pytest.mark.xfail(strict=True, reason=PYTHONFMU_CANNOT))
        path = built_fmus.path(MISUSE_FMU)
    else:
        path = built_fmus.native(kind, MISUSE_FMU)
    fmu = NativeFmu(path)
    fmu.instantiate()
    yield fmu
    fmu.free()


def _errors(fmu: NativeFmu) -> list[str]:
    return [text for status, text in fmu.log if status == 3]


def test_dostep_before_initialisation_is_refused(kf, fmu_recording):
    assert refused(kf.fmu.doStep, 0.0, 0.01)
    assert any("DoStep" in e and "instantiated" in e for e in _errors(kf))
    kf.start()
    _run(kf, fmu_recording, 0, 20)


def test_dostep_after_terminate_is_refused(kf, fmu_recording):
    kf.start()
    _run(kf, fmu_recording, 0, 5)
    kf.terminate()
    assert refused(kf.fmu.doStep, 0.05, 0.01)
    assert any("DoStep" in e and "terminated" in e for e in _errors(kf))
    kf.fmu.reset()
    kf.start()
    _run(kf, fmu_recording, 0, 20)


@pytest.mark.parametrize("h", [0.0, -0.01, float("nan"), float("inf")])
def test_a_communication_step_size_that_is_not_positive_is_refused(kf, fmu_recording, h):
    kf.start()
    before = _run(kf, fmu_recording, 0, 10)[-1]
    assert refused(kf.fmu.doStep, 0.1, h)
    assert any("step size" in e for e in _errors(kf))
    assert tuple(kf.get(n) for n in ("roll", "pitch", "bias_x", "bias_y", "bias_z")) == before
    _run(kf, fmu_recording, 10, 20)


def test_a_dostep_at_a_communication_point_other_than_the_fmus_time_is_refused(
        kf, fmu_recording):
    """doStep must start where the last step ended (or at the start time): a skipped or a
    repeated step is refused with a log line, as the Reference-FMUs do, and changes nothing."""
    kf.start()
    before = _run(kf, fmu_recording, 0, 10)[-1]
    for t in (0.2, 0.0, 0.09):
        assert refused(kf.fmu.doStep, t, 0.01)
    assert sum("communication point" in e for e in _errors(kf)) == 3
    assert tuple(kf.get(n) for n in ("roll", "pitch", "bias_x", "bias_y", "bias_z")) == before
    _run(kf, fmu_recording, 10, 20)  # 0.01 * 10 is the sum of ten steps up to rounding


def _flip_top_bits(state: bytes, offsets: list[int]) -> bytes:
    """The state with the top (sign) bit of the little-endian doubles at these byte offsets
    flipped, its checksum left as it was."""
    out = bytearray(state)
    for at in offsets:
        out[at + 7] ^= 0x80
    return bytes(out)


STATE_HEADER = 88 + 16
"""Bytes before a native state's values: the header (magic, model, format, counts, length,
checksum) and the FMI state and time (fmu_instance.c)."""


def test_a_state_with_one_or_two_words_changed_or_a_byte_more_is_refused(kf, fmu_recording):
    """The checksum is a CRC-64: a sign flip of roll, or of roll and pitch together (which a
    word-wise FNV hash let through, the filter continuing mirrored), is refused, and a state
    must have exactly its length."""
    kf.start()
    _run(kf, fmu_recording, 0, 100)
    good = kf.serialize(kf.save())
    roll, pitch = (STATE_HEADER + 8 * kf.vr(n) for n in ("roll", "pitch"))
    field = len(good) - 8  # the last state field of the filter
    changed = [_flip_top_bits(good, [roll]), _flip_top_bits(good, [roll, pitch]),
               _flip_top_bits(good, [field]), _flip_top_bits(good, [roll, field]),
               good + b"\x00"]
    before = kf.get("roll")
    for data in changed:
        assert refused(kf.deserialize, data)
    assert len(_errors(kf)) == len(changed)
    assert kf.get("roll") == before
    kf.restore(kf.deserialize(good))
    _run(kf, fmu_recording, 100, 120)


def test_setting_an_output_is_refused(kf):
    kf.start()
    assert refused(kf.set, "roll", 1.0)
    assert kf.get("roll") == 0.0
    assert any("roll is an output" in e for e in _errors(kf))


def test_a_fixed_parameter_after_initialisation_is_refused_a_tunable_one_taken(kf):
    fixed = next(v.name for v in kf.md.modelVariables
                 if v.causality == "parameter" and v.variability == "fixed")
    kf.start()
    before = kf.get(fixed)
    assert refused(kf.set, fixed, 2)
    assert kf.get(fixed) == before
    assert any(f"parameter {fixed} is fixed after initialisation" in e for e in _errors(kf))
    kf.set("R_measure", 0.5)  # tunable: taken while running
    assert kf.get("R_measure") == 0.5


@pytest.mark.parametrize("value", [float("nan"), -1.0, -float("inf")])
def test_a_parameter_out_of_range_is_refused_and_the_previous_value_stays(kf, value,
                                                                           fmu_recording):
    if kf.version == "fmi3":
        kf.fmu.enterInitializationMode(startTime=0.0)
    else:
        kf.fmu.setupExperiment(startTime=0.0)
        kf.fmu.enterInitializationMode()
    start = kf.get("R_measure")
    assert refused(kf.set, "R_measure", value)
    assert kf.get("R_measure") == start
    assert any("R_measure" in e and "out of range" in e for e in _errors(kf))
    kf.fmu.exitInitializationMode()
    _run(kf, fmu_recording, 0, 20)


def test_unknown_value_references_are_refused_in_get_and_set(kf):
    kf.start()
    getter = kf.fmu.getFloat64 if kf.version == "fmi3" else kf.fmu.getReal
    setter = kf.fmu.setFloat64 if kf.version == "fmi3" else kf.fmu.setReal
    unknown = len(kf.md.modelVariables) + 7
    assert refused(getter, [unknown])
    assert refused(setter, [unknown], [1.0])
    assert sum("unknown value reference" in e for e in _errors(kf)) == 2
    assert refused(getter, [kf.vr("invalid_samples")])  # an Integer read as a Real
    assert any("invalid_samples" in e for e in _errors(kf))


@pytest.mark.parametrize("kind", [*VERSIONS, pytest.param(
    "pythonfmu", marks=pytest.mark.xfail(strict=True, reason=PYTHONFMU_CANNOT))])
def test_a_wrong_guid_or_instantiation_token_is_refused(built_fmus, kind):
    path = built_fmus.path(MISUSE_FMU) if kind == "pythonfmu" else built_fmus.native(kind,
                                                                                     MISUSE_FMU)
    fmu = NativeFmu(path, token="{not-this-fmu}")
    assert fmu.raw_instantiate() is None
    assert any("{not-this-fmu}" in text for status, text in fmu.log if status == 3)


def test_bytes_this_fmu_did_not_write_are_refused_and_the_state_kept(kf, built_fmus,
                                                                       fmu_recording):
    kf.start()
    _run(kf, fmu_recording, 0, 100)
    good = kf.serialize(kf.save())
    before = kf.get("roll")
    garbage = [b"", b"\x00" * 64, os.urandom(len(good)), good[:-1],
               good[:200] + bytes([good[200] ^ 1]) + good[201:]]
    for data in garbage:
        assert refused(kf.deserialize, data)
    plant = NativeFmu(built_fmus.native(kf.version, "ImuPlant"), instance="plant")
    plant.instantiate()
    plant.start()
    assert refused(kf.deserialize, plant.serialize(plant.save()))
    plant.free()
    assert len(_errors(kf)) == len(garbage) + 1
    assert kf.get("roll") == before
    kf.restore(kf.deserialize(good))
    _run(kf, fmu_recording, 100, 120)


def test_terminate_twice_and_event_mode_are_refused(kf):
    kf.start()
    if kf.version == "fmi3":
        assert refused(kf.fmu.enterEventMode)  # hasEventMode is false
    kf.terminate()
    assert refused(kf.terminate)
    assert any("Terminate" in e and "terminated" in e for e in _errors(kf))


def test_fmpy_compile_rebuilds_every_native_fmu_from_its_own_sources(built_fmus, tmp_path,
                                                                      fmu_recording):
    """The sources inside an FMU are complete: fmpy's CMake build (which reads the FMI 2.0
    SourceFiles and FMI 3.0's buildDescription.xml) rebuilds the binary, and the rebuilt FMU
    gives the same outputs. The first model of each standard is built as `fmpy compile` builds
    it (Release); the others unoptimised (Debug), which compiles in half the time and shows as
    well that the outputs do not depend on the optimisation (no contraction into fused
    multiply-adds at any level)."""
    from fmpy.build import build_platform_binary

    if shutil.which("cmake") is None:
        pytest.skip("cmake is not installed: fmpy compile needs it")
    for version in VERSIONS:
        for i, name in enumerate(model_names()):
            path = built_fmus.native(version, name)
            unzipdir = extract(str(path), unzipdir=str(tmp_path / f"{version}-{name}"))
            binary = Path(unzipdir) / BINARY[version] / f"{name}.so"
            original = binary.read_bytes()
            binary.unlink()
            (tmp_path / f"build-{version}-{name}").mkdir()
            build_platform_binary(unzipdir, build_dir=str(tmp_path / f"build-{version}-{name}"),
                                  configuration="Release" if i == 0 else "Debug")
            assert binary.is_file()
            rebuilt = str(tmp_path / f"rebuilt-{version}-{name}.fmu")
            shutil.make_archive(rebuilt[:-4], "zip", unzipdir)
            os.replace(rebuilt[:-4] + ".zip", rebuilt)
            a = simulate_fmu(str(path), stop_time=2.0, output_interval=0.01)
            b = simulate_fmu(rebuilt, stop_time=2.0, output_interval=0.01)
            assert all(np.array_equal(a[k], b[k]) for k in a.dtype.names), (version, name)
            assert original  # the build made its own binary, not a copy


# ----- a C host, as a tool that is not ours -------------------------------------------------------

HOST_KIND = {"ImuPlant": "plant", "ImuSensor": "sensor"}


@pytest.fixture(scope="module")
def native_host(tmp_path_factory) -> Path:
    """tests/fmu_host/native_host.c, compiled with the system compiler."""
    from fusion_core.native import compiler

    cc = compiler()
    if cc is None:
        pytest.skip("no C compiler: the C host cannot be built")
    exe = tmp_path_factory.mktemp("host") / "native_host"
    subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-g", "-O1", "-I",
                    str(REPO / "fmu_src" / "native" / "include"), "-o", str(exe),
                    str(REPO / "tests" / "fmu_host" / "native_host.c"), "-ldl", "-lm"],
                   check=True, capture_output=True, text=True)
    return exe


@pytest.mark.parametrize("name", model_names())
def test_a_c_host_runs_misuses_saves_restores_and_frees_every_native_fmu(
        built_fmus, native_host, tmp_path, name):
    """The C host loads the binary with no preload and no Python variables, runs 600 samples
    (bad ones among them), saves, serializes, deserializes and restores a state (the run after
    it is repeated bit for bit), commits every misuse of "FMI calls" (each refused with an
    error and a log line, the run going on), frees and exits 0; under valgrind (where it is
    installed) with 0 errors and no definitely lost bytes. Both versions give the same
    outputs."""
    valgrind = shutil.which("valgrind")
    outputs = {}
    for version in VERSIONS:
        path = built_fmus.native(version, name)
        md = read_model_description(str(path))
        unzipdir = extract(str(path), unzipdir=str(tmp_path / version))
        token = md.instantiationToken if version == "fmi3" else md.guid
        reals = [str(v.valueReference) for v in md.modelVariables
                 if v.causality == "output" and v.type in ("Real", "Float64")]
        n_vars = len([v for v in md.modelVariables if v.name != "time"])
        cmd = [str(native_host), version[-1], f"{unzipdir}/{BINARY[version]}/{name}.so", name,
               token, HOST_KIND.get(name, "estimator"), str(n_vars), *reals]
        if valgrind:
            cmd = [valgrind, "-q", "--error-exitcode=9", "--leak-check=full",
                   "--errors-for-leak-kinds=definite", *cmd]
        proc = subprocess.run(cmd, env=_clean_env(), capture_output=True, text=True,
                              timeout=300, check=False)
        assert proc.returncode == 0, proc.stderr
        outputs[version] = [float(x) for x in proc.stdout.split()]
        assert len(outputs[version]) == len(reals) and all(np.isfinite(outputs[version]))
    assert outputs["fmi2"] == outputs["fmi3"]


@pytest.mark.parametrize("estimator", ["ukf", "poskf"])
def test_the_testbench_gives_the_same_trace_on_both_kinds_of_fmu(built_fmus, estimator):
    """testbenches run --kind native and --kind pythonfmu: plant, sensor and estimator of either
    kind give the same truth, samples and estimates, bit for bit, with jittered steps."""
    from testbenches import run_testbench
    from testbenches.fmus import kind_dir

    built_fmus.native("fmi2", "ImuPlant")  # skips without a compiler
    runs = [run_testbench(estimator, "moderate_dynamics", seed=3, duration=8.0, jitter=0.2,
                          fmu_dir=kind_dir(built_fmus.directory, kind), evaluate=False)
            for kind in ("native", "pythonfmu")]
    native, python = runs
    for part in ("truth", "sample", "estimate"):
        a, b = getattr(native, part), getattr(python, part)
        assert a.keys() == b.keys()
        assert all(np.array_equal(a[k], b[k]) for k in a), part
    assert native.invalid_samples == python.invalid_samples


# ----- Windows binaries, run under wine ----------------------------------------------------------

WINDOWS_BINARY = {"fmi2": "binaries/win64", "fmi3": "binaries/x86_64-windows"}


@pytest.fixture(scope="module")
def windows_host(tmp_path_factory) -> Path:
    """tests/fmu_host/native_host.c cross-compiled for Windows: skipped with the reason where
    mingw-w64 or wine is missing (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)."""
    from fmu_src.native.build import MINGW, cross_compiler

    if cross_compiler() is None:
        pytest.skip(f"no {MINGW} (Debian package gcc-mingw-w64-x86-64): the native FMUs carry "
                    "no Windows binary")
    if shutil.which("wine") is None:
        pytest.skip("no wine (Debian package wine64): the Windows binaries cannot be run here")
    exe = tmp_path_factory.mktemp("winhost") / "native_host.exe"
    subprocess.run([MINGW, "-std=c99", "-Wall", "-Wextra", "-Werror", "-O1", "-I",
                    str(REPO / "fmu_src" / "native" / "include"), "-o", str(exe),
                    str(REPO / "tests" / "fmu_host" / "native_host.c")],
                   check=True, capture_output=True, text=True)
    return exe


@pytest.mark.parametrize("name", model_names())
def test_the_windows_binary_of_every_native_fmu_runs_under_wine(built_fmus, windows_host,
                                                                native_host, tmp_path, name):
    """The C host, cross-compiled with mingw-w64, runs each FMU's Windows binary under wine
    (misuses, state round trip, free: exit 0) and gets the Linux binary's outputs within 1e-12
    (the two C libraries' sin, cos and atan2 may differ in the last bit)."""
    env = {**_clean_env(), "WINEDEBUG": "-all"}
    for version in VERSIONS:
        path = built_fmus.native(version, name)
        md = read_model_description(str(path))
        unzipdir = Path(extract(str(path), unzipdir=str(tmp_path / version)))
        token = md.instantiationToken if version == "fmi3" else md.guid
        reals = [str(v.valueReference) for v in md.modelVariables
                 if v.causality == "output" and v.type in ("Real", "Float64")]
        n_vars = str(len([v for v in md.modelVariables if v.name != "time"]))
        kind = HOST_KIND.get(name, "estimator")
        dll = unzipdir / WINDOWS_BINARY[version] / f"{name}.dll"
        assert dll.is_file(), f"{path} has no Windows binary"
        win = subprocess.run(["wine", str(windows_host), version[-1], "Z:" + str(dll), name,
                              token, kind, n_vars, *reals], env=env, capture_output=True,
                             text=True, timeout=300, check=False)
        assert win.returncode == 0, win.stderr[-2000:]
        linux = subprocess.run([str(native_host), version[-1],
                                str(unzipdir / BINARY[version] / f"{name}.so"), name, token,
                                kind, n_vars, *reals], env=env, capture_output=True, text=True,
                               check=True)
        a = np.array(win.stdout.split(), dtype=float)
        b = np.array(linux.stdout.split(), dtype=float)
        assert a.shape == b.shape == (len(reals),)
        assert np.max(np.abs(a - b)) <= 1e-12


def test_the_build_gives_no_compiler_warning(built_fmus):
    """A user's compiler may warn where ours does not, so a warning does not stop a build
    (fmu_src.native.build.CompilerWarning); here, in CI, it fails the suite."""
    assert built_fmus.returncode == 0
    assert "CompilerWarning" not in built_fmus.output, built_fmus.output


def test_the_binaries_go_where_the_host_platform_says(monkeypatch):
    import platform

    from fmu_src.native import build

    monkeypatch.setattr(platform, "system", lambda: "Linux")
    monkeypatch.setattr(platform, "machine", lambda: "x86_64")
    assert build.host_platform()["fmi2"] == "linux64"
    monkeypatch.setattr(platform, "machine", lambda: "riscv64")
    with pytest.raises(RuntimeError, match="no FMU binary folder is known for Linux on riscv64"):
        build.host_platform()
