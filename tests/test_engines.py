"""The FMUs in the co-simulation engines users run: libcosim (FMI 2.0) and Ecos (FMI 2.0 and
3.0), through testbenches.engines, against the project's own Jacobi master.

For every estimator the whole chain ImuPlant -> ImuSensor -> estimator runs in each engine
on moderate_dynamics (the realistic sensor, seed 0): the contract's accuracy checks pass on the
traces aligned by the Jacobi chain's delay, the first half second holds no false start, and
every output equals the project's Jacobi master bit for bit. Every choice parameter is set in
both engines and takes effect. Where an engine or its runtime is missing, its tests skip with
the reason and the install line (testbenches.engines.engine_reason).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fusion_core import ESTIMATORS
from fusion_core.scenarios import get_scenario
from fusion_core.sensor import SENSOR_PARAMS
from testbenches import engines
from testbenches.master import run_testbench

KEYS = list(engines.ESTIMATOR_FMUS)
RUNS = [(engine, fmi) for engine, versions in engines.ENGINES.items() for fmi in versions]
EARLY_MAX_DEG = 1.0
VEL_AT_10S_MAX = 1.5


def _skip_without(engine: str) -> None:
    why = engines.engine_reason(engine)
    if why:
        pytest.skip(why)


@pytest.mark.heavy
@pytest.mark.xdist_group("engines")  # the docs' engines table takes the same runs
@pytest.mark.parametrize(("engine", "fmi"), RUNS, ids=[f"{e}-fmi{v}" for e, v in RUNS])
@pytest.mark.parametrize("key", KEYS)
def test_the_chain_in_the_engine_holds_the_contract_and_equals_the_jacobi_master(
        built_fmus, engine, fmi, key):
    _skip_without(engine)
    built_fmus.native("fmi3", "ImuPlant")  # both standards' native FMUs built
    runs = engines.engine_runs(built_fmus.directory, "moderate_dynamics", 0, key)
    own = runs[0][2]  # the project's Jacobi master on the native FMI 2.0 FMUs
    r = next(run for name, version, run, _ in runs if (name, version) == (engine, fmi))
    failed = [c.line() for c in r.checks if not c.passed]
    assert not failed, failed
    for name, trace in r.estimate.items():
        assert np.array_equal(trace, own.estimate[name]), name  # bit for bit
    assert r.invalid_samples == own.invalid_samples == 1  # the sensor's start: no sample
    assert engines.early_error_deg(r) <= EARLY_MAX_DEG  # over engines.EARLY_WINDOW
    if key == "poskf":
        assert engines.velocity_error(r, 10.0) <= VEL_AT_10S_MAX


CHOICES = [("sensor", p.name, p.choices) for p in SENSOR_PARAMS if p.choices] + [
    ("estimator", p.name, p.choices)
    for p in ESTIMATORS["kf"].param_specs().values() if p.choices]
"""Every choice parameter of the chain (the sensor's and the estimator's), an FMI Integer."""


@pytest.mark.parametrize("engine", list(engines.ENGINES))
@pytest.mark.parametrize(("component", "name", "items"), CHOICES,
                         ids=[f"{c}.{n}" for c, n, _ in CHOICES])
def test_every_choice_parameter_is_set_in_the_engine_and_takes_effect(
        built_fmus, engine, component, name, items):
    """Each choice set to its last item (an Integer, len(items)) in the engine gives the Jacobi
    master's run with that item by name, and a run other than the default's: the samples for
    a sensor's choice (the master also sets the estimator's gyro_sampling from the sensor's),
    the estimate for the estimator's."""
    _skip_without(engine)
    folder = built_fmus.native("fmi2", "ImuPlant").parent
    value = len(items)
    where = "params" if component == "estimator" else "sensor_params"
    kw = {"duration": 5.0, "evaluate": False}
    run = engines.run_engine(engine, "kf", "roll_sweep", 0, fmu_dir=built_fmus.directory,
                             **{where: {name: value}}, **kw)
    default = engines.run_engine(engine, "kf", "roll_sweep", 0,
                                 fmu_dir=built_fmus.directory, **kw)
    own = run_testbench("kf", "roll_sweep", 0, master="jacobi", fmu_dir=folder,
                        **{where: {name: items[-1]}}, **kw)
    def trace(r: object) -> np.ndarray:
        return r.sample["gyro_x"] if component == "sensor" else r.estimate["roll"]

    assert np.array_equal(trace(run), trace(own))
    assert not np.array_equal(trace(run), trace(default))


def test_a_parameter_an_engine_cannot_set_is_refused_not_ignored(built_fmus):
    """Ecos skips a parameter it cannot set with a warning only; run_engine reads each one
    back and refuses the run."""
    _skip_without("ecos")
    fmu_dir = built_fmus.directory
    with pytest.raises(ValueError, match="no_such_parameter"):
        engines.run_engine("ecos", "kf", "roll_sweep", 0, fmu_dir=fmu_dir, duration=0.1,
                           params={"no_such_parameter": 1.0}, evaluate=False)


# ----- the exported SSP in the engines and as an fmucontainer ------------------------------------
SSP_RUNS = [("libcosim", 2), ("ecos", 2), ("ecos", 3)]


@pytest.mark.parametrize(("engine", "fmi"), SSP_RUNS, ids=[f"{e}-fmi{v}" for e, v in SSP_RUNS])
def test_the_exported_ssp_runs_its_scenario_in_the_engine_as_the_direct_wiring(
        built_fmus, tmp_path, engine, fmi):
    """export-ssp binds each component's parameters to it: the engine runs the exported
    scenario (moderate_dynamics, not the default static one) and the sensor part's seed, and its
    outputs equal the same chain wired directly in the engine, bit for bit."""
    _skip_without(engine)
    from testbenches.ssp import export_ssp

    ssp = export_ssp("ukf", "moderate_dynamics", tmp_path / "ukf.ssp", seed=3,
                     params={"gyro_sampling": "point"}, fmu_dir=built_fmus.directory, fmi=fmi)
    loaded = engines.run_ssp(engine, ssp, "ukf", "moderate_dynamics", 3, duration=10.0)
    direct = engines.run_engine(engine, "ukf", "moderate_dynamics", 3, fmi=fmi, duration=10.0,
                                fmu_dir=built_fmus.directory)
    truth = get_scenario("moderate_dynamics").trajectory().truth(loaded.t[-1:])
    assert loaded.truth["pitch"][-1] == pytest.approx(truth["pitch"][0], abs=1e-12)
    assert np.array_equal(loaded.sample["gyro_x"], direct.sample["gyro_x"])  # the same part
    for name, trace in loaded.estimate.items():
        assert np.array_equal(trace, direct.estimate[name]), name


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("sequential", [True, False], ids=["sequential", "parallel"])
def test_an_fmucontainer_of_the_exported_ssp_equals_the_gauss_seidel_or_jacobi_run(
        built_fmus, tmp_path, sequential, fmi):
    """fmucontainer around plant, sensor and estimator, simulated by fmpy: sequential equals
    the Gauss-Seidel master, parallel the Jacobi master, bit for bit, with the SSP's scenario
    and seed applied and the estimator's outputs exposed."""
    pytest.importorskip("fmu_manipulation_toolbox", reason=engines.INSTALL)
    from testbenches.container import container_from_ssp
    from testbenches.ssp import export_ssp

    ssp = export_ssp("kf", "moderate_dynamics", tmp_path / "kf.ssp", seed=2,
                     fmu_dir=built_fmus.directory)
    mode = "sequential" if sequential else "parallel"
    fmu = container_from_ssp(ssp, tmp_path / f"kf_{mode}_{fmi}.fmu", sequential=sequential,
                             fmi=fmi)
    # in a process of its own, as a user runs it (`fmpy simulate`): the container loads the
    # three FMUs' libraries, which this process may hold already from other tests
    out = tmp_path / "rows.npy"
    script = ("import sys, numpy as np\nfrom fmpy import simulate_fmu\n"
              "np.save(sys.argv[2], simulate_fmu(sys.argv[1], stop_time=5.0, "
              "output_interval=0.01))\n")
    proc = subprocess.run([sys.executable, "-c", script, str(fmu), str(out)],
                          capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = np.load(out)
    master = "gauss-seidel" if sequential else "jacobi"
    own = run_testbench("kf", "moderate_dynamics", 2, duration=5.0, master=master,
                        fmu_dir=built_fmus.native("fmi2", "ImuPlant").parent, evaluate=False)
    first = 1 + (0 if sequential else 1)  # row 0: t = 0; Jacobi's first estimate is of no sample
    for name in ("roll", "pitch", "bias_x", "bias_y"):
        assert np.array_equal(rows[name][first:], own.estimate[name]), name
    assert rows["invalid_samples"][-1] == own.invalid_samples


# ----- docs/guide/engines.md cannot go stale ------------------------------------------------------
PAGE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "engines.md"


def _recipe(heading: str) -> str:
    """The first python block after a heading of the page."""
    text = PAGE.read_text()
    after = text[text.index(f"\n## {heading}\n"):]
    return after.split("```python\n", 1)[1].split("```", 1)[0]


@pytest.mark.parametrize(("engine", "heading"), [("libcosim", "libcosim"), ("ecos", "Ecos")])
def test_the_pages_recipe_runs_the_chain_in_the_engine(built_fmus, tmp_path, monkeypatch,
                                                        engine, heading):
    _skip_without(engine)
    (tmp_path / "dist").symlink_to(built_fmus.directory)
    monkeypatch.chdir(tmp_path)
    scope: dict[str, object] = {}
    exec(compile(_recipe(heading), str(PAGE), "exec"), scope)
    truth = get_scenario("moderate_dynamics").trajectory().truth(np.array([60.0 - 0.02]))
    assert abs(scope["roll"] - truth["roll"][0]) < np.radians(1.0)
