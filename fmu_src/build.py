"""Build and check the project's FMUs (the library behind `python build_fmu.py`).

The models are fmu_src.names's: every estimator of fusion_core.registry (its slave module
generated from its entry) and the testbench's plant and sensor (fmu_src/models). Each model is
built as up to three kinds of FMU from its one variable table: the pythonfmu FMU
(out_dir/<Name>.fmu) and the native FMI 2.0 and FMI 3.0 FMUs (out_dir/native/fmi2/<Name>.fmu,
out_dir/native/fmi3/<Name>.fmu; fmu_src/native).

A pythonfmu FMU carries in resources/ its slave module, fusion_core (the Python sources and,
where a C compiler built it, the C twin's library beside them: its estimators then step through
the twin, fusion_core.native.Stepper), the runtime part of fmu_src, pythonfmu (added by
pythonfmu's builder) and a requirements.txt with what the host interpreter must provide (numpy,
cffi: nothing the FMUs run imports more). A host of another platform, or without cffi, runs the
Python sources.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import traceback
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .names import PRESET_FILE, write_script

Preset = dict[str, dict[str, Any]]
"""A preset's entries by estimator key (fusion_core.presets.load_preset)."""

HERE = Path(__file__).resolve().parent
RUNTIME_FILES = (
    "__init__.py", "variables.py", "slave.py", "estimator.py", "model_description.py",
    "names.py", "testbench_models.py",
)
"""The part of fmu_src an FMU needs at run time (not the build code, not the other models)."""
REQUIREMENTS = "numpy>=1.24\ncffi>=1.15\n"
"""What the host's Python must provide (resources/requirements.txt); pythonfmu is bundled."""


def fusion_core_dir() -> Path:
    """The fusion_core package the FMUs ship (the one this project imports)."""
    import fusion_core

    return Path(fusion_core.__file__).resolve().parent


def _stage(root: Path, preset: Preset | None) -> list[Path]:
    """Copy what goes into resources/ besides the slave module, with the preset's entries as
    PRESET_FILE (none for the recommended values, the defaults); return the paths."""
    shutil.copytree(fusion_core_dir(), root / "fusion_core",
                    ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    _ship_native_library(root / "fusion_core")
    staged = [root / "fusion_core"]
    (root / "fmu_src").mkdir()
    for name in RUNTIME_FILES:
        shutil.copy2(HERE / name, root / "fmu_src" / name)
    (root / "requirements.txt").write_text(REQUIREMENTS)
    staged += [root / "fmu_src", root / "requirements.txt"]
    if preset and any(preset.values()):  # what it was built with, read by the slave when it runs
        (root / PRESET_FILE).write_text(json.dumps(preset, indent=1))
        staged.append(root / PRESET_FILE)
    return staged


def _ship_native_library(core: Path) -> None:
    """Put the C twin's library, built for this platform, beside the FMU's fusion_core sources
    (fusion_core.native.PREBUILT), where it can be built: the FMU's estimators then step
    through it (fusion_core.native.Stepper); a host of another platform, or without cffi, runs
    the Python core. The declarations go beside it (write_declarations): an FMU's process then
    loads them instead of parsing the headers, and writes nothing into the host's cache."""
    from fusion_core import native
    from fusion_core.native.library import write_declarations

    if native.reason() is not None:
        return
    shutil.copy2(native.library_path(), core / "native" / native.PREBUILT.name)
    write_declarations(core / "native")  # the headers' declarations, loaded without parsing


def build(name: str, out_dir: Path, preset: Preset | None = None) -> Path:
    """Build the pythonfmu FMU called name into out_dir/<name>.fmu with the preset's estimator
    class and start values (None: the recommended ones) and return its path."""
    with tempfile.TemporaryDirectory(prefix="fmu_script_") as tmp:
        script = write_script(name, Path(tmp))
        path = build_script(script, out_dir, preset)
    if path.name != f"{name}.fmu":
        raise RuntimeError(f"{script.name} built {path.name}: its class must be {name}")
    return path


def build_script(script: Path, out_dir: Path, preset: Preset | None = None) -> Path:
    """Build the FMU of one slave module (any FmuSlave subclass) into out_dir; the FMU is
    named after the class. The module name must be unique among the FMUs of a process.

    The slave module is built from a copy beside the staged resources: pythonfmu's builder
    instantiates the slave with the module's folder as its resources, so the slave reads the
    preset it is built with from there, as it reads it from the FMU's resources when it runs."""
    from pythonfmu import FmuBuilder

    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="fmu_stage_") as tmp:
        files = _stage(Path(tmp), preset)
        shutil.copy2(script, Path(tmp) / script.name)
        path = FmuBuilder.build_FMU(Path(tmp) / script.name, dest=out_dir, project_files=files)
    return Path(path)


def check(path: Path) -> list[str]:
    """fmpy's validation problems plus the project's own: every variable has a description,
    every Real variable a unit."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    problems = list(validate_fmu(str(path)))
    if problems:
        return problems
    md = read_model_description(str(path))
    for v in md.modelVariables:
        if not (v.description or "").strip():
            problems.append(f"variable {v.name!r} has no description")
        if v.type == "Real" and not v.unit:
            problems.append(f"Real variable {v.name!r} has no unit")
    if not (md.description or "").strip():
        problems.append("the model description has no description attribute")
    return problems


KINDS = ("all", "pythonfmu", "native")
"""What build_all builds: every kind of FMU, the pythonfmu ones only, or the native ones only."""


def default_kind() -> str:
    """"all" where a C compiler exists or the wheel carries the native FMUs, else
    "pythonfmu"."""
    from fusion_core.native import compiler

    from .names import model_names
    from .native.prebuilt import prebuilt_fmu

    if compiler() or prebuilt_fmu(model_names()[0], "fmi2", "recommended"):
        return "all"
    return "pythonfmu"


@dataclass
class BuildResult:
    """One row of the build table."""

    name: str
    core: str = "python"  # what its estimators step with: "native" (the C twin) or "python"
    kind: str = "pythonfmu"  # "pythonfmu", "fmi2" or "fmi3"
    path: Path | None = None
    size: int = 0
    variables: int = 0
    problems: list[str] = field(default_factory=list)


def build_all(
    names: Iterable[str], out_dir: Path, preset: str = "recommended", kind: str | None = None,
    calibration: Path | None = None,
) -> list[BuildResult]:
    """Build and check each FMU; a failed build is a problem of its row, not an exception.
    preset: the estimators' start values, a name or a JSON file (fusion_core.presets.load_preset;
    ValueError for a bad one); kind: one of KINDS (None: default_kind()); calibration: a part's
    calibration.json, whose acc_cal and gyro_cal become every estimator's start values."""
    from fusion_core.calibration import Calibration
    from fusion_core.presets import load_preset

    kind = kind or default_kind()
    if kind not in KINDS:
        raise ValueError(f"kind {kind!r}: allowed {', '.join(KINDS)}")
    names = list(names)
    entries = load_preset(preset)
    if calibration is not None:  # start values of one's own: the prebuilt FMUs cannot serve
        cal = Calibration.read(calibration).params()
        entries = {key: {**values, **cal} for key, values in entries.items()}
        preset = f"{preset} with {calibration}"
    results = []
    if kind != "native":
        results += [_build_and_check(name, out_dir, entries) for name in names]
    if kind != "pythonfmu":  # the compiler runs in processes of its own: one thread per core
        jobs = [(name, version) for version in ("fmi2", "fmi3") for name in names]
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
            results += pool.map(
                lambda job: _build_native_and_check(*job, out_dir, entries, preset), jobs)
    return results


def _build_native_and_check(name: str, version: str, out_dir: Path, preset: Preset,
                            preset_name: str = "recommended") -> BuildResult:
    """One row of the build table for a native FMU (out_dir/native/<version>/<name>.fmu):
    compiled, or where no compiler exists the wheel's copy for a named preset."""
    from fusion_core.native import compiler

    from .native.build import build_native, native_model
    from .native.prebuilt import copy_prebuilt

    if compiler() is None:
        return _checked(BuildResult(name, core="native", kind=version),
                        lambda: copy_prebuilt(name, version, preset_name, out_dir / "native"))
    return _checked(BuildResult(name, core="native", kind=version),
                    lambda: build_native(native_model(name, preset), version,
                                         out_dir / "native"))


def _build_and_check(name: str, out_dir: Path, preset: Preset) -> BuildResult:
    """One row of the build table for a pythonfmu FMU."""
    from fusion_core import native

    return _checked(BuildResult(name, core="python" if native.reason() else "native"),
                    lambda: build(name, out_dir, preset))


def _checked(result: BuildResult, make: Callable[[], Path]) -> BuildResult:
    """result filled in: the FMU make() builds, its size, variables and problems (a failed
    build is a problem of its row, not an exception)."""
    from fmpy import read_model_description

    try:
        result.path = make()
        result.size = result.path.stat().st_size
        result.variables = len(read_model_description(str(result.path)).modelVariables)
        result.problems = check(result.path)
    except Exception as err:
        last = traceback.format_exception_only(type(err), err)[-1].strip()
        result.problems = [f"build failed: {last}"]
    return result


def format_table(results: Sequence[BuildResult]) -> str:
    """The build table: FMU, kind, fusion_core it runs, size, number of variables, validation
    problems."""
    rows = [("FMU", "kind", "core", "size", "variables", "validation problems")]
    for r in results:
        first = r.problems[0] if r.problems else ""
        count = f"{len(r.problems)}" + (f": {first}" if first else "")
        size = f"{r.size / 1024:.0f} kB" if r.path else "-"
        rows.append((r.name, r.kind, r.core, size, str(r.variables) if r.path else "-", count))
    widths = [max(len(row[i]) for row in rows) for i in range(5)]
    lines = []
    for i, row in enumerate(rows):
        cells = [row[0].ljust(widths[0]), row[1].ljust(widths[1]), row[2].ljust(widths[2]),
                 row[3].rjust(widths[3]), row[4].rjust(widths[4]), row[5]]
        lines.append("  ".join(cells).rstrip())
        if i == 0:
            lines.append("  ".join("-" * w for w in (*widths, len(rows[0][5]))))
    for r in results:
        lines += [f"{r.name} ({r.kind}): {p}" for p in r.problems[1:]]
    return "\n".join(lines)
