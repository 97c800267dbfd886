"""The built FMUs: validation, variables, units, descriptions, resources, the build command."""

from __future__ import annotations

import importlib.util
import math
import re
import shutil
import zipfile
from pathlib import Path

import pytest
from conftest import ESTIMATOR_FMUS
from fmpy import read_model_description
from fmpy.validation import validate_fmu

import fusion_core
from fmu_src.build import check
from fmu_src.variables import items_in_description
from fusion_core import native
from fusion_core.native.library import cdef, declarations_name

REPO = Path(__file__).resolve().parents[1]
DEG = 180.0 / math.pi

INTERFACE = {
    # name: (causality, type, unit, display unit); INTERFACE.md, estimator FMUs
    "acc_x": ("input", "Real", "m/s2", None),
    "acc_y": ("input", "Real", "m/s2", None),
    "acc_z": ("input", "Real", "m/s2", None),
    "gyro_x": ("input", "Real", "rad/s", "deg/s"),
    "gyro_y": ("input", "Real", "rad/s", "deg/s"),
    "gyro_z": ("input", "Real", "rad/s", "deg/s"),
    "dt": ("input", "Real", "s", None),
    "roll": ("output", "Real", "rad", "deg"),
    "pitch": ("output", "Real", "rad", "deg"),
    "bias_x": ("output", "Real", "rad/s", "deg/s"),
    "bias_y": ("output", "Real", "rad/s", "deg/s"),
    "bias_z": ("output", "Real", "rad/s", "deg/s"),
    "invalid_samples": ("output", "Integer", None, None),
}
POSITION = {
    **{f"pos_{a}": ("output", "Real", "m", None) for a in "xyz"},
    **{f"vel_{a}": ("output", "Real", "m/s", None) for a in "xyz"},
}
BASE_UNITS = {
    # unit: SI exponents of its <BaseUnit>
    "m/s2": {"m": 1, "s": -2},
    "rad/s": {"rad": 1, "s": -1},
    "s": {"s": 1},
    "rad": {"rad": 1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "1": {},
    "rad2/s": {"rad": 2, "s": -1},
    "rad2/s3": {"rad": 2, "s": -3},
    "rad2": {"rad": 2},
    "m2/s5": {"m": 2, "s": -5},
    "m2/s3": {"m": 2, "s": -3},
}


EXPECTED_CORE = "python" if native.reason() else "native"
"""What a pythonfmu FMU's estimators step with: the C twin's library it carries wherever a C
compiler built it (a machine with only Python and pip has none: the Python sources)."""


def test_build_command_builds_every_fmu_without_problems(built_fmus):
    assert built_fmus.returncode == 0, built_fmus.output
    lines = built_fmus.output.splitlines()
    assert lines[0].split() == ["FMU", "kind", "core", "size", "variables", "validation",
                                "problems"]
    for name in ESTIMATOR_FMUS:
        row = next(line.split() for line in lines if line.startswith(name + " "))
        assert row[1:3] == ["pythonfmu", EXPECTED_CORE], row  # no silent fallback
        assert row[-1] == "0", row  # validation problems
        assert (built_fmus.directory / f"{name}.fmu").stat().st_size > 0


@pytest.mark.skipif(EXPECTED_CORE == "python",
                    reason=f"{native.reason()}: the FMUs carry the Python sources only")
def test_each_fmu_carries_the_c_twins_library_beside_the_sources(fmu_path):
    """resources/ holds every fusion_core source, the C twin's sources and the library built
    from them (fusion_core.native.PREBUILT), and asks the host for cffi to load it."""
    with zipfile.ZipFile(fmu_path) as z:
        names = set(z.namelist())
        requirements = z.read("resources/requirements.txt").decode()
    for module in ("base", "kalman", "ukf", "native/__init__"):
        assert f"resources/fusion_core/{module}.py" in names
    assert "resources/fusion_core/native/fc_kf.c" in names
    assert f"resources/fusion_core/native/{native.PREBUILT.name}" in names
    # and its declarations as cffi's module for these headers, loaded without parsing them
    assert f"resources/fusion_core/native/{declarations_name(cdef())}.py" in names
    assert "cffi" in requirements


def test_fmu_passes_fmpy_validation(fmu_path):
    assert validate_fmu(str(fmu_path)) == []


def test_every_variable_has_a_description(fmu_path):
    md = read_model_description(str(fmu_path))
    assert [v.name for v in md.modelVariables if not (v.description or "").strip()] == []


def test_every_real_has_a_declared_unit_with_base_units(fmu_path):
    md = read_model_description(str(fmu_path))
    units = {u.name: u for u in md.unitDefinitions}
    for v in md.modelVariables:
        if v.type == "Real":
            assert v.unit in units, v.name
    for name, unit in units.items():
        assert name in BASE_UNITS, f"unexpected unit {name}"
        assert unit.baseUnit is not None, name
        got = {k: getattr(unit.baseUnit, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd",
                                                      "rad")}
        assert {k: e for k, e in got.items() if e} == BASE_UNITS[name], name
        assert unit.baseUnit.factor == 1.0 and unit.baseUnit.offset == 0.0


def test_display_units_convert_radians_to_degrees(fmu_path):
    md = read_model_description(str(fmu_path))
    for unit in md.unitDefinitions:
        for display in unit.displayUnits:
            power = 2 if display.name.startswith("deg2") else 1
            assert display.name.startswith("deg"), display.name
            assert display.factor == pytest.approx(DEG**power, rel=1e-15)


def test_variables_follow_the_interface(fmu_path, fmu_key):
    md = read_model_description(str(fmu_path))
    expected = dict(INTERFACE)
    if fusion_core.ESTIMATORS[fmu_key].HAS_POSITION:
        expected.update(POSITION)
    got = {
        v.name: (v.causality, v.type, v.unit, v.displayUnit)
        for v in md.modelVariables if v.causality != "parameter"
    }
    assert got == expected
    for v in md.modelVariables:
        if v.causality == "output":
            assert v.initial == "exact" and v.start is not None, v.name
            assert v.variability == ("discrete" if v.type == "Integer" else "continuous")
        if v.causality == "input":
            assert v.start is not None
    assert {u.variable.name for u in md.outputs} == {
        n for n, row in expected.items() if row[0] == "output"
    }


def test_every_tuning_parameter_is_an_fmu_parameter(fmu_path, fmu_key):
    md = read_model_description(str(fmu_path))
    params = {v.name: v for v in md.modelVariables if v.causality == "parameter"}
    specs = fusion_core.ESTIMATORS[fmu_key].param_specs()
    assert list(params) == list(specs)
    for name, spec in specs.items():
        v = params[name]
        assert v.variability == ("tunable" if spec.tunable else "fixed"), name
        if spec.choices is not None:  # an Integer choice: every engine can set it
            items = items_in_description(v.description)
            assert v.type == "Integer" and items == tuple(spec.choices), name
            assert (v.min, v.max) == ("1", str(len(items))), name
            assert items[int(v.start) - 1] == spec.default
        elif isinstance(spec.default, bool):
            assert v.type == "Boolean" and v.start == str(spec.default).lower(), name
        else:
            assert v.type == "Real" and float(v.start) == spec.default, name  # exact
            assert v.unit == spec.unit and v.displayUnit == spec.display_unit, name
            if spec.low is not None and not spec.low_open:
                assert float(v.min) == spec.low
            if spec.high is not None and not spec.high_open:
                assert float(v.max) == spec.high
        assert spec.description.rstrip(".") in v.description


def test_model_description_names_the_paper(fmu_path, fmu_key):
    """The FMU's description is its registry entry's text, which cites its paper's
    equations."""
    from fusion_core.registry import ENTRY

    md = read_model_description(str(fmu_path))
    assert md.description == ENTRY[fmu_key].fmu_text
    assert re.search(r"eq\. \d+", md.description), md.description


def test_state_capabilities_are_declared(fmu_path):
    cs = read_model_description(str(fmu_path)).coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert cs.needsExecutionTool and cs.canHandleVariableCommunicationStepSize


def test_fmu_carries_fusion_core_and_requirements(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        names = set(z.namelist())
        requirements = z.read("resources/requirements.txt").decode().split()
        module = z.read("resources/slavemodule.txt").decode().strip()
    core = REPO / "fusion_core"
    assert {f"resources/fusion_core/{p.name}" for p in core.glob("*.py")} <= names
    assert "resources/fmu_src/slave.py" in names
    assert f"resources/{module}.py" in names
    assert "binaries/linux64/" + fmu_path.stem + ".so" in names
    assert sorted(r.split(">=")[0] for r in requirements) == ["cffi", "numpy"]


def test_slave_modules_have_unique_names(built_fmus):
    modules = []
    for name in ESTIMATOR_FMUS:
        with zipfile.ZipFile(built_fmus.path(name)) as z:
            modules.append(z.read("resources/slavemodule.txt").decode().strip())
    assert len(set(modules)) == len(modules)
    assert not {"fusion_core", "fmu_src", "pythonfmu"} & set(modules)


def test_check_reports_a_real_without_unit(built_fmus, tmp_path):
    broken = tmp_path / "ComplementaryFilter.fmu"
    with zipfile.ZipFile(built_fmus.path("ComplementaryFilter")) as src, \
            zipfile.ZipFile(broken, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'<Real unit="s" start="0.01"/>', b'<Real start="0.01"/>')
            dst.writestr(item, data)
    assert check(broken) == ["Real variable 'dt' has no unit"]


def test_build_command_exits_non_zero_on_a_validation_problem(
    built_fmus, tmp_path, monkeypatch, capsys
):
    spec = importlib.util.spec_from_file_location("build_fmu_cli", REPO / "build_fmu.py")
    cli = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cli)

    def build_copy(name: str, out_dir: Path, preset: object = None) -> Path:  # no rebuild
        out_dir.mkdir(parents=True, exist_ok=True)
        return Path(shutil.copy(built_fmus.path(name), out_dir))

    def one_problem(path: Path) -> list[str]:
        return ["The unit \"x\" of variable \"dt\" is not defined."]

    monkeypatch.setattr("fmu_src.build.build", build_copy)
    args = ["--out", str(tmp_path), "--only", "ComplementaryFilter", "--kind", "pythonfmu"]
    assert cli.main(args) == 0
    monkeypatch.setattr("fmu_src.build.check", one_problem)
    assert cli.main(args) == 1
    assert "1: The unit" in capsys.readouterr().out


def test_the_paper_preset_builds_the_papers_filters(paper_fmus, fmu_recording):
    """build_fmu.py --preset paper: every estimator FMU runs its paper's filter
    (fusion_core.papers) under the same model name: that class's parameters at the preset's
    values, and fusion_core's outputs with that preset, pythonfmu and native alike."""
    import numpy as np

    from fmu_src.host import FmuInstance
    from fusion_core.presets import preset_params
    from fusion_core.registry import ENTRY, FILTER, create

    acc, gyro, dt = (fmu_recording[k][:300] for k in ("acc_meas", "gyro_meas", "dt"))
    for name, key in ESTIMATOR_FMUS.items():
        entry = preset_params("paper", key)
        want = create(key, entry).run(acc, gyro, dt)
        paper = ENTRY[key].paper_class  # the reference, else the class itself
        specs = paper.param_specs()
        for fmu in (paper_fmus.path(name), paper_fmus.native("fmi2", name)):
            md = read_model_description(str(fmu))
            assert md.modelName == name
            assert paper.__name__ in md.description or ENTRY[key].reference is None
            starts = {v.name: v.start for v in md.modelVariables if v.causality == "parameter"}
            assert set(starts) == set(specs), (name, set(starts) ^ set(specs))
            for p, value in {**{n: s.default for n, s in specs.items()}, **entry}.items():
                if p != FILTER and not isinstance(value, str):
                    assert float(starts[p]) == float(value), (name, p)
            with FmuInstance(fmu) as instance:
                out = instance.run_samples(acc, gyro, dt)
            assert np.array_equal(out["roll"], want["roll"]), (name, fmu)
            assert np.array_equal(out["bias"], want["bias"]), (name, fmu)


def test_two_presets_built_in_one_process_keep_their_own_start_values(tmp_path):
    """build_all for the recommended values, then for the paper's, in this process: each FMU
    carries its own preset's class and start values (no table of the first build is reused)."""
    from fmu_src.build import build_all
    from fusion_core.registry import ESTIMATORS, REFERENCES

    names = ["ComplementaryFilter", "UnscentedKalmanFilter"]
    for preset, classes in (("recommended", ESTIMATORS), ("paper", REFERENCES),
                            ("recommended", ESTIMATORS)):
        out = tmp_path / preset
        rows = build_all(names, out, preset=preset, kind="pythonfmu")
        assert all(not r.problems for r in rows), [r.problems for r in rows]
        for name in names:
            cls = classes[ESTIMATOR_FMUS[name]]
            md = read_model_description(str(out / f"{name}.fmu"))
            starts = {v.name: v.start for v in md.modelVariables if v.causality == "parameter"}
            assert set(starts) == set(cls.param_specs()), (preset, name)
            for p, spec in cls.param_specs().items():
                if isinstance(spec.default, float):
                    assert float(starts[p]) == spec.default, (preset, name, p)


def test_every_registry_estimator_is_an_fmu_built_from_its_entry(tmp_path):
    """No estimator has a slave module of its own on disk: the registry entry is the FMU
    (fmu_src.names.estimator_script), so adding an estimator adds its FMU."""
    from fmu_src.names import MODELS_DIR, estimator_fmus, model_names, write_script
    from fusion_core.registry import REGISTRY

    assert {e.fmu for e in REGISTRY} <= set(model_names())
    on_disk = {p.name for p in MODELS_DIR.glob("*_fmu.py")}
    for entry in REGISTRY:
        script = write_script(entry.fmu, tmp_path)
        assert script.name not in on_disk
        spec = importlib.util.spec_from_file_location(script.stem, script)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        cls = getattr(module, entry.fmu)
        assert (cls.key, cls.description) == (entry.key, entry.fmu_text)
    assert estimator_fmus() == {e.fmu: e.key for e in REGISTRY}
    with pytest.raises(ValueError, match="no FMU called 'Nothing'"):
        write_script("Nothing", tmp_path)
