"""The C twin (fusion_core/native) equals the Python reference: parity of every twin, preset and
kind of bad sample to 1e-12, state handover both ways, generated parameters up to date, and no
memory error under valgrind. Skipped, with the reason, where the twin cannot be built."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import make, state_numbers
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fusion_core import ESTIMATORS, InvalidSample, native, registry, synthetic
from fusion_core.calibration import Calibration
from fusion_core.native.estimators import param_field, param_struct
from fusion_core.presets import PRESETS, preset_params
from fusion_core.types import ABSENT

REPO = Path(__file__).resolve().parents[1]
NATIVE = REPO / "fusion_core" / "native"
TOL = 0.0
"""The twins agree bit for bit (the same operations in the same order, no fused multiply-add):
every comparison of their numbers is an equality."""
TWIN_KEYS = [k for k, cls in ESTIMATORS.items() if cls.TWIN is not None]

PART_CALIBRATION = Calibration(
    acc_matrix=(1.023, 0.004, -0.002, 0.003, 0.981, 0.006, -0.005, 0.002, 1.012),
    acc_offset=(0.12, -0.07, 0.21),
    gyro_matrix=(1.028, 0.003, 0.001, -0.004, 0.982, 0.002, 0.002, -0.003, 1.004),
    gyro_offset=(0.011, -0.018, 0.006),
).params()
"""A part's calibration of the size imucal's example session has (scales of +2.8 %, -1.8 %)."""

needs_twin = pytest.mark.skipif(not native.available(),
                                reason=f"no native backend: {native.reason()}")


def mixed_recording(seed: int = 3) -> dict[str, np.ndarray]:
    """20 s at 100 Hz: rotation, a 1 m move (linear acceleration), rest; a near-zero
    accelerometer stretch; NaN, inf, huge and bad-dt samples sprinkled in; a gyro bias."""
    s = synthetic
    trajectory = s.Trajectory(
        roll=s.add(s.min_jerk(0.0, 1.2, 1.0, 2.0), s.min_jerk(0.0, -1.2, 9.0, 2.0)),
        pitch=s.add(s.min_jerk(0.0, -1.5, 3.0, 2.0), s.min_jerk(0.0, 1.5, 11.0, 2.0)),
        yaw=s.min_jerk(0.0, 2.0, 2.0, 6.0),
        pos=(s.min_jerk(0.0, 1.0, 5.0, 3.0), s.constant(), s.constant()),
    )
    rec = s.record(trajectory, 19.99, 100.0, noise=s.ImuNoise(gyro_bias=(0.01, -0.006, 0.004)),
                   seed=seed)
    acc, gyro, dt = rec["acc_meas"].copy(), rec["gyro_meas"].copy(), rec["dt"].copy()
    acc[1500:1530] = 0.0  # free fall: no gravity direction
    for i in range(40, len(dt), 37):
        kind = (i // 37) % 7
        if kind == 0:
            acc[i, 0] = np.nan
        elif kind == 1:
            gyro[i, 2] = -np.inf
        elif kind == 2:
            dt[i] = 0.0
        elif kind == 3:
            dt[i] = 5.0
        elif kind == 4:
            acc[i] = (1e300, -1e300, 1e-320)
        elif kind == 5:
            gyro[i] = (1e4, 0.0, 0.0)
        else:
            dt[i] = np.nan
    return {"acc": acc, "gyro": gyro, "dt": dt}


def assert_same(py: dict, c: dict) -> None:
    for name in py:
        assert py[name].shape == c[name].shape, name
        if py[name].dtype == bool:
            assert np.array_equal(py[name], c[name]), name
        else:
            assert np.max(np.abs(py[name] - c[name]), initial=0.0) <= TOL, name


def assert_same_snapshot(sa: dict, sb: dict, where: str = "") -> None:
    assert sa["params"] == sb["params"], where
    for name, value in sa["state"].items():
        other = sb["state"][name]
        if isinstance(value, dict):  # a nested estimator (the position filter's Kalman filters)
            assert_same_snapshot(value, other, f"{where}{name}.")
        elif isinstance(value, list) and all(isinstance(v, list) for v in value):
            assert len(value) == len(other), where + name  # the position filter's queue
            assert np.allclose(value, other, rtol=0.0, atol=TOL) if value else True, where + name
        else:  # a number, a vector or a Measure (vectors and numbers): compare the numbers
            assert np.allclose(state_numbers(value), state_numbers(other), rtol=0.0,
                               atol=TOL), where + name


def assert_same_state(a: object, b: object) -> None:
    assert_same_snapshot(a.get_state(), b.get_state())  # type: ignore[attr-defined]


def test_the_generated_parameter_header_is_up_to_date() -> None:
    proc = subprocess.run([sys.executable, "-m", "fusion_core.native.generate", "--check"],
                          cwd=REPO, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr


def test_backend_names_are_checked_and_auto_falls_back_to_python() -> None:
    rec = mixed_recording()
    est = make("poskf")
    with pytest.raises(ValueError, match="backend='cuda' is not allowed"):
        est.run(rec["acc"][:5], rec["gyro"][:5], rec["dt"][:5], backend="cuda")

    class Tuned(ESTIMATORS["kf"]):  # type: ignore[misc,valid-type]
        """A subclass may change the math: it never runs natively."""

    with pytest.raises(ValueError, match="Tuned has no C twin"):
        Tuned().run(rec["acc"][:5], rec["gyro"][:5], rec["dt"][:5], backend="native")
    auto = Tuned().run(rec["acc"][:50], rec["gyro"][:50], rec["dt"][:50])
    assert np.isfinite(auto["roll"]).all()


def test_every_twin_of_the_registry_is_in_the_library_by_its_files_alone() -> None:
    """library.SOURCES and HEADERS come from the directory (no hand list to extend): every
    class's TWIN prefix names a source and a header there, each header after those it
    includes."""
    from fusion_core.native import library
    from fusion_core.registry import CLASSES

    for cls in CLASSES:
        assert f"{cls.TWIN}.c" in library.SOURCES and f"{cls.TWIN}.h" in library.HEADERS
    for i, name in enumerate(library.HEADERS):
        text = (library.HERE / name).read_text()
        for included in re.findall(r'#include "(fc_\w+\.h)"', text):
            assert included in library.DATA_HEADERS or included in library.HEADERS[:i], name


def test_available_and_reason_agree() -> None:
    assert native.available() == (native.reason() is None)


@needs_twin
def test_the_declarations_are_parsed_once_and_a_damaged_cache_is_made_again(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import cffi

    from fusion_core.native.library import cdef, declarations

    monkeypatch.setenv("FUSION_CORE_NATIVE_CACHE", str(tmp_path))
    text = cdef()
    first = declarations(text)
    (kept,) = (tmp_path / "ffi").glob("_fc_ffi_*.py")
    parsed = []
    monkeypatch.setattr(cffi.FFI, "cdef", lambda self, t: parsed.append(t))
    again = declarations(text)  # from the cache: nothing parsed
    assert parsed == []
    assert again.sizeof("fc_ukf") == first.sizeof("fc_ukf")
    assert again.offsetof("fc_kf", "last") == first.offsetof("fc_kf", "last")
    lib = again.dlopen(str(native.library_path()))
    assert lib.FC_BAD_DT == native.lib_and_ffi()[0].FC_BAD_DT
    kept.write_text("this is not python (")
    monkeypatch.undo()
    monkeypatch.setenv("FUSION_CORE_NATIVE_CACHE", str(tmp_path))
    repaired = declarations(text)  # parsed again and written again
    assert repaired.sizeof("fc_ukf") == first.sizeof("fc_ukf")
    assert "this is not python" not in kept.read_text()


@needs_twin
@pytest.mark.parametrize("cls", [c for c in registry.CLASSES if c.TWIN is not None],
                         ids=lambda c: c.TWIN)
def test_the_c_defaults_are_the_python_defaults(cls: type) -> None:
    """Every twin's T_params_default (fc_params.h) gives its class's defaults, and a shared
    parameter the class leaves out (a paper filter's gyro_range) at base.ABSENT's value."""
    lib, ffi = native.lib_and_ffi()
    prefix = cls.TWIN
    twin = ffi.new(f"{prefix} *")
    getattr(lib, f"{prefix}_init")(twin, ffi.NULL)
    for name, spec in cls.param_specs().items():
        *path, field = param_field(cls, name).split(".")
        c_value = getattr(param_struct(twin.params, path), field)
        expected = spec.choices.index(spec.default) if spec.choices else spec.default
        assert c_value == expected, name
    for name, value in ABSENT.items():  # a shared parameter the class leaves out
        if name not in cls.param_specs():
            assert getattr(twin.params.input, name) == value, name


@needs_twin
@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("key", TWIN_KEYS)
@pytest.mark.parametrize("extra", [{}, {"gyro_sampling": "mean"},
                                   {"mount_pitch": -np.pi / 2, "mount_yaw": 0.3},
                                   {"sensor_delay": 2.4e-3, "mount_roll": 0.4},
                                   {**PART_CALIBRATION, "mount_yaw": 0.3}])
def test_python_and_native_runs_are_equal(key: str, preset: str, extra: dict) -> None:
    rec = mixed_recording()
    params = {**preset_params(preset, key), **extra}
    py, c = make(key, **params), make(key, **params)
    out_py = py.run(rec["acc"], rec["gyro"], rec["dt"], backend="python")
    out_c = c.run(rec["acc"], rec["gyro"], rec["dt"], backend="native")
    assert out_py["rejected"].sum() > 40  # the bad samples were there, and rejected
    assert_same(out_py, out_c)
    assert_same_state(py, c)


@needs_twin
@pytest.mark.parametrize("key", TWIN_KEYS)
def test_a_sensor_on_its_side_switches_faces_the_same_way(key: str) -> None:
    """The recording turned x-up, no mounting: the Kalman filter changes faces on the way."""
    rec = mixed_recording()
    m = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    with np.errstate(invalid="ignore"):  # the NaN and inf samples stay bad samples
        acc, gyro = rec["acc"] @ m, rec["gyro"] @ m
    py, c = make(key), make(key)
    out_py = py.run(acc, gyro, rec["dt"], backend="python")
    out_c = c.run(acc, gyro, rec["dt"], backend="native")
    assert_same(out_py, out_c)
    assert_same_state(py, c)


@needs_twin
@pytest.mark.parametrize("key", TWIN_KEYS)
@pytest.mark.parametrize("first", ["python", "native"])
@pytest.mark.parametrize("delay", [0.0, 2.4e-3])
def test_a_run_hands_its_state_over_to_the_other_backend(key: str, first: str, delay: float
                                                         ) -> None:
    rec = mixed_recording()
    acc, gyro, dt = rec["acc"], rec["gyro"], rec["dt"]
    whole = make(key, sensor_delay=delay).run(acc, gyro, dt, backend="python")
    est = make(key, sensor_delay=delay)
    second = "native" if first == "python" else "python"
    head = est.run(acc[:900], gyro[:900], dt[:900], backend=first)
    snapshot = est.get_state()
    other = make(key, sensor_delay=delay)
    other.set_state(snapshot)
    tail = other.run(acc[900:], gyro[900:], dt[900:], backend=second)
    for name in ("roll", "pitch", "bias"):
        joined = np.concatenate([head[name], tail[name]])
        assert np.max(np.abs(joined - whole[name])) <= TOL, name
    # and step() continues from a native run exactly as from a Python one
    est_py = make(key, sensor_delay=delay)
    est_py.run(acc[:900], gyro[:900], dt[:900], backend="python")
    est_c = make(key, sensor_delay=delay)
    est_c.run(acc[:900], gyro[:900], dt[:900], backend="native")
    for i in range(900, 960):
        a, b = est_py.step(acc[i], gyro[i], 0.01), est_c.step(acc[i], gyro[i], 0.01)
        assert abs(a.roll - b.roll) <= TOL and abs(a.pitch - b.pitch) <= TOL


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
value = st.one_of(
    st.floats(-30.0, 30.0), finite, st.sampled_from([np.nan, np.inf, -np.inf, 0.0, 1e-320]),
)
sample = st.tuples(
    st.tuples(value, value, value), st.tuples(value, value, value),
    st.one_of(st.floats(1e-4, 0.05), st.sampled_from([0.0, -1.0, 2.0, np.nan, 1e-12])),
)


@needs_twin
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(samples=st.lists(sample, min_size=1, max_size=60), key=st.sampled_from(TWIN_KEYS),
       preset=st.sampled_from(sorted(PRESETS)), delay=st.sampled_from([0.0, 0.004]))
def test_random_short_recordings_give_equal_outputs(samples: list, key: str, preset: str,
                                                    delay: float) -> None:
    acc = np.array([s[0] for s in samples], dtype=float)
    gyro = np.array([s[1] for s in samples], dtype=float)
    dt = np.array([s[2] for s in samples], dtype=float)
    params = {**preset_params(preset, key), "sensor_delay": delay,
              **(PART_CALIBRATION if delay else {})}
    with np.errstate(all="ignore"):
        out_py = make(key, **params).run(acc, gyro, dt, backend="python")
        out_c = make(key, **params).run(acc, gyro, dt, backend="native")
    assert_same(out_py, out_c)


def memcheck_twins(host: str) -> str:
    """memcheck_host.c's memcheck_twins.h: every twin of the registry (recommended and the
    papers'), its header and a CHECK_TWIN in CHECK_ALL_TWINS() with the VARIANT_<twin> the host
    defines for it, or none (its defaults twice)."""
    from fusion_core.registry import CLASSES

    twins = [c.TWIN for c in CLASSES if c.TWIN is not None]
    variants = set(re.findall(r"#define VARIANT_(\w+)", host))
    checks = " ".join(f"CHECK_TWIN({t}, {f'VARIANT_{t}' if t in variants else '(void)0'});"
                      for t in twins)
    return "\n".join([*(f'#include "{t}.h"' for t in twins),
                      f"#define CHECK_ALL_TWINS() do {{ {checks} }} while (0)", ""])


def test_the_memcheck_host_checks_every_twin_of_the_registry() -> None:
    host = (REPO / "tests" / "native" / "memcheck_host.c").read_text()
    header = memcheck_twins(host)
    from fusion_core.registry import CLASSES

    twins = {cls.TWIN for cls in CLASSES}
    for twin in twins:
        assert f"CHECK_TWIN({twin}, " in header, twin
    # a variant is optional; one for a twin the registry no longer has is stale
    assert set(re.findall(r"#define VARIANT_(\w+)", host)) <= twins


@pytest.mark.heavy
@needs_twin
@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is not installed")
def test_valgrind_finds_no_memory_error_in_a_native_run(tmp_path: Path) -> None:
    cc = native.compiler()
    assert cc is not None
    exe = tmp_path / "memcheck_host"
    sources = [str(NATIVE / s) for s in native.SOURCES]
    host = REPO / "tests" / "native" / "memcheck_host.c"
    (tmp_path / "memcheck_twins.h").write_text(memcheck_twins(host.read_text()))
    subprocess.run([cc, "-std=c99", "-O1", "-g", "-ffp-contract=off", f"-I{NATIVE}",
                    f"-I{tmp_path}",
                    str(REPO / "tests" / "native" / "memcheck_host.c"), *sources, "-lm",
                    "-o", str(exe)], check=True)
    proc = subprocess.run(["valgrind", "-q", "--error-exitcode=3", "--leak-check=full",
                           str(exe)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "non-finite estimates: 0" in proc.stdout


@needs_twin
@pytest.mark.parametrize("schedule", ["simulation", "experimental", "fixed"])
def test_every_schedule_of_the_papers_mgcf_is_equal(schedule: str) -> None:
    rec = mixed_recording()
    py = make("mgcf", filter="paper", schedule=schedule)
    c = make("mgcf", filter="paper", schedule=schedule)
    assert_same(py.run(rec["acc"], rec["gyro"], rec["dt"], backend="python"),
                c.run(rec["acc"], rec["gyro"], rec["dt"], backend="native"))
    assert_same_state(py, c)


@needs_twin
def test_the_embedded_example_builds_and_converges(tmp_path: Path) -> None:
    """examples/embedded_kf.c, built as its comment says: 10 deg of roll within 0.1 deg."""
    cc = native.compiler()
    assert cc is not None
    exe = tmp_path / "embedded_kf"
    subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", f"-I{NATIVE}",
                    str(REPO / "examples" / "embedded_kf.c"), str(NATIVE / "fc_core.c"),
                    str(NATIVE / "fc_paper_kf.c"), str(NATIVE / "fc_kf.c"), "-lm", "-o",
                    str(exe)], check=True)
    last = subprocess.run([str(exe)], capture_output=True, text=True, check=True
                          ).stdout.splitlines()[-1]
    roll = float(last.split("roll=")[1].split()[0])
    assert abs(roll - 10.0) < 0.1, last


@needs_twin
@pytest.mark.parametrize("params", [{"alpha": 0.3, "beta": 0.0, "kappa": -2.0},
                                    {"alpha": 1.0, "beta": 0.5, "kappa": 1.0}])
def test_ukf_sigma_point_settings_are_equal(params: dict) -> None:
    """Other sigma-point spreads, beta < alpha^2 among them (a negative central weight, where
    S may not be positive definite and the general solve takes over)."""
    rec = mixed_recording()
    py, c = make("ukf", **params), make("ukf", **params)
    assert_same(py.run(rec["acc"], rec["gyro"], rec["dt"], backend="python"),
                c.run(rec["acc"], rec["gyro"], rec["dt"], backend="native"))
    assert_same_state(py, c)


@needs_twin
def test_ukf_with_a_covariance_made_indefinite_takes_the_same_square_root() -> None:
    """P pushed just below positive definite: both twins fall back to the Jacobi square root."""
    rec = mixed_recording()
    acc, gyro, dt = rec["acc"], rec["gyro"], rec["dt"]
    base = make("ukf")
    base.run(acc[:300], gyro[:300], dt[:300], backend="python")
    P = np.array(base.P)
    w, V = np.linalg.eigh(P)
    P = P - (w[0] + 1e-12 * w[-1]) * np.outer(V[:, 0], V[:, 0])
    P = 0.5 * (P + P.T)
    assert np.min(np.linalg.eigvalsh(P)) < 0.0
    snapshot = base.get_state()
    snapshot["state"]["P"] = P.tolist()
    py, c = make("ukf"), make("ukf")
    py.set_state(snapshot)
    c.set_state(snapshot)
    assert_same(py.run(acc[300:400], gyro[300:400], dt[300:400], backend="python"),
                c.run(acc[300:400], gyro[300:400], dt[300:400], backend="native"))
    assert_same_state(py, c)


@needs_twin
@pytest.mark.parametrize("which", ["recommended", "paper"])
def test_poskf_hands_over_a_filled_stationary_queue(which: str) -> None:
    """Split where the position filter's queue of unconfirmed rest samples is not empty: the
    queue, the nested Kalman filters and the [p, v, a] filters all cross to the other backend
    (the paper's filter, which has no queue, late in the recording)."""
    rec = mixed_recording()
    acc, gyro, dt = rec["acc"], rec["gyro"], rec["dt"]
    params = {"filter": which}
    probe = make("poskf", **params)
    split = None
    for i in range(len(dt)):
        try:
            probe.step(acc[i], gyro[i], dt[i])
        except InvalidSample:  # a bad sample of the recording
            continue
        if which == "paper" or len(probe.pending) > 5:
            split = i + 1
            if i > 1700:
                break
    assert split is not None
    whole = make("poskf", **params).run(acc, gyro, dt, backend="python")
    est = make("poskf", **params)
    head = est.run(acc[:split], gyro[:split], dt[:split], backend="python")
    assert which == "paper" or est.pending
    tail = est.run(acc[split:], gyro[split:], dt[split:], backend="native")
    for name in ("roll", "pitch", "bias", "pos", "vel"):
        joined = np.concatenate([head[name], tail[name]])
        assert np.max(np.abs(joined - whole[name])) <= TOL, name


@needs_twin
def test_the_counter_based_noise_is_the_same_in_c() -> None:
    """fusion_core.noise and fc_noise.c: the same 64-bit hashes and libm's log and cos, so the
    same normals; any block of samples, any starting k."""
    from fusion_core import noise

    for seed, stream, k0 in ((0, 0, 0), (12345, 1, 0), (2**31 - 1, 0, 10**9)):
        py = noise.normals(seed, stream, k0, 300, 19)
        c = native.normals(seed, stream, k0, 300, 19)
        assert np.max(np.abs(py - c)) <= TOL
    assert np.array_equal(noise.normals(7, 0, 100, 5, 19), noise.normals(7, 0, 0, 105, 19)[100:])


SENSOR_CASES = [
    {}, {"gyro_sampling": "mean", "jitter": 0.001, "dlpf_cfg": 3},
    {"dlpf_cfg": -1, "bits": 0, "calibration": "none"}, {"dlpf_cfg": 6, "gyro_bias_psd": 1e-6},
    {"calibration": "perfect", "dlpf_cfg": -1, "gyro_scale_std": 0.0, "acc_bias_psd": 1e-4},
    {"gyro_bias_instability": 0.0, "acc_bias_instability": 0.0, "acc_psd": 0.0},
]
"""The twin computes only the deviates of the terms that are on: every case has some off."""


@needs_twin
@pytest.mark.parametrize("steps", ["varying", "fixed"])
@pytest.mark.parametrize("params", SENSOR_CASES)
def test_the_sensor_model_twin_draws_the_same_samples(params: dict, steps: str) -> None:
    """fc_sensor.c against fusion_core.sensor: noise, per-run errors, bias walk and instability,
    DLPF (delay and biquad forms), jitter, saturation (the rates and forces reach past the
    ranges) and quantisation; then a handover of the state mid-run, both ways. Fixed steps, in
    runs of equal h, take the twin's path that computes an interval's constants once."""
    from fusion_core.sensor import ImuSensorModel

    rng = np.random.default_rng(0)
    n = 2000
    omega = rng.normal(0.0, 10.0, (n, 3))
    f = rng.normal(0.0, 60.0, (n, 3))
    h = rng.uniform(0.002, 0.02, n) if steps == "varying" else np.repeat([0.01, 0.0035], n // 2)
    py, c = ImuSensorModel(seed=3, **params), ImuSensorModel(seed=3, **params)
    a, b = py.run(omega, f, h, backend="python"), c.run(omega, f, h, backend="native")
    for name in a:
        assert np.max(np.abs(a[name] - b[name])) <= TOL, name
    assert py.get_state() == c.get_state()
    whole = ImuSensorModel(seed=3, **params).run(omega, f, h, backend="python")
    mixed = ImuSensorModel(seed=3, **params)
    head = mixed.run(omega[:900], f[:900], h[:900], backend="native")
    tail = mixed.run(omega[900:], f[900:], h[900:], backend="python")
    for name in whole:
        joined = np.concatenate([head[name], tail[name]])
        assert np.max(np.abs(joined - whole[name])) <= TOL, name


@needs_twin
def test_the_plant_twin_gives_every_scenarios_truth() -> None:
    """fc_plant.c with fc_scenarios.h (generated from the scenarios' signals) against
    Trajectory.truth_at, the plant FMU's own call, over each scenario and past its end."""
    from fusion_core.scenarios import SCENARIOS

    for sc in SCENARIOS.values():
        t = np.linspace(0.0, 1.2 * sc.duration, 1501)
        python = np.array([sc.trajectory().truth_at(x) for x in t.tolist()])
        assert np.max(np.abs(native.plant_truth(sc.id, t) - python)) <= TOL, sc.name
    with pytest.raises(ValueError, match="unknown scenario id 99"):
        native.plant_truth(99, np.zeros(1))


def test_a_scenarios_truth_is_the_same_from_either_backend():
    """Scenario.truth(t, backend): the plant's C twin and the Python trajectory agree."""
    from fusion_core.scenarios import SCENARIOS

    if not native.available():
        pytest.skip(f"the native twin is not available: {native.reason()}")
    t = np.linspace(0.0, 20.0, 2001)
    for sc in SCENARIOS.values():
        a, b = sc.truth(t, backend="native"), sc.truth(t, backend="python")
        assert a.shape == b.shape == (2001, 15)
        assert np.max(np.abs(a - b)) <= 1e-12, sc.name


@needs_twin
def test_the_twins_sizes_are_the_python_classes():
    """The C twin's queue bound and estimate size follow the Python side (generated, derived)."""
    from fusion_core.position import PENDING_MAX

    _, ffi = native.lib_and_ffi()
    assert native.poskf_pending_max() == PENDING_MAX
    assert ffi.sizeof("fc_estimate") == 8 * native.ESTIMATE_FIELDS
