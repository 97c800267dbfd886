"""Build the native FMUs: FMI 2.0 and FMI 3.0 co-simulation FMUs from fusion_core's C twin.

For each model the FMU's variable table (the one its pythonfmu FMU is built from) becomes
- `config.h`: MODEL_IDENTIFIER and MODEL_TOKEN, one VR_<name> per variable (the value references
  of the pythonfmu FMU: table order), the variable table with start values and ranges, and
  `params_from_values`, which fills the C twin's params struct from the values (enumerations
  1..n -> the C choice 0..n-1);
- `modelDescription.xml` for FMI 2.0 and for FMI 3.0, with the same names, units, ranges,
  descriptions and start values as the pythonfmu FMU's;
and the FMU is a zip of that description, the binary for this platform (and for Windows where
mingw-w64 is installed), and its complete C sources (FMI 2.0 SourceFiles, FMI 3.0
sources/buildDescription.xml), so that a tool can rebuild it (`fmpy compile`).

FMI 3.0 variables stay scalars with the pythonfmu FMUs' names, not arrays: the testbench, fmpy's
CSV input and output, Simulink's FMU block and the FMI 2.0 FMUs then read and write the same
names, and a model's three kinds of FMU can be swapped without touching a connection.
"""

from __future__ import annotations

import hashlib
import importlib
import math
import os
import platform
import re
import shutil
import subprocess
import tempfile
import uuid
import warnings
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any
from xml.dom import minidom
from xml.etree.ElementTree import Element, SubElement, tostring

from fusion_core.native import compiler as twin_compiler
from fusion_core.native.generate import c_double

from ..model_description import (
    initial_unknowns,
    project_version,
    type_attributes,
    type_definitions,
    unit_definitions,
)
from ..names import MODELS_DIR, estimator_fmus, script_name
from ..variables import Variable

HERE = Path(__file__).resolve().parent
TWIN_DIR = HERE.parents[1] / "fusion_core" / "native"
VERSIONS = ("fmi2", "fmi3")
PLATFORMS = {
    ("Linux", "x86_64"): {"fmi2": "linux64", "fmi3": "x86_64-linux", "suffix": ".so"},
    ("Linux", "aarch64"): {"fmi2": "aarch64-linux", "fmi3": "aarch64-linux", "suffix": ".so"},
    ("Darwin", "x86_64"): {"fmi2": "darwin64", "fmi3": "x86_64-darwin", "suffix": ".dylib"},
    ("Darwin", "arm64"): {"fmi2": "aarch64-darwin", "fmi3": "aarch64-darwin", "suffix": ".dylib"},
    ("Windows", "AMD64"): {"fmi2": "win64", "fmi3": "x86_64-windows", "suffix": ".dll"},
}
"""Binary folders per (operating system, machine) as platform.system() and platform.machine()
name them, per FMI version (FMI 2.0's standard names where it has one, else the platform tuple
FMPy and FMI 3.0 use), and the binary's file suffix."""
WINDOWS = PLATFORMS[("Windows", "AMD64")]
"""The cross-compiled Windows binary's folders."""


class CompilerWarning(UserWarning):
    """The C compiler warned while building a native FMU: the build goes on (a user's compiler
    may know warnings ours does not); the test suite, run in CI, turns it into an error."""


def host_platform() -> dict[str, str]:
    """The binary folders of the machine this builds on (PLATFORMS); RuntimeError naming the
    platform where no FMU binary folder is known for it."""
    key = (platform.system(), platform.machine())
    if key not in PLATFORMS:
        raise RuntimeError(f"no FMU binary folder is known for {key[0]} on {key[1]}: the native "
                           f"FMUs are built for {', '.join(f'{s} {m}' for s, m in PLATFORMS)}")
    return PLATFORMS[key]
CFLAGS = ("-std=c99", "-O2", "-shared", "-ffp-contract=off", "-fno-fast-math",
          "-fvisibility=hidden", "-Wall", "-Wextra")
"""As the C twin's (no fused multiply-add, no fast-math: equal to the Python reference); only
the FMI functions are exported."""
MINGW = "x86_64-w64-mingw32-gcc"
"""Debian's mingw-w64 cross compiler (package gcc-mingw-w64-x86-64), for the Windows binary."""
TOKEN_NAMESPACE = uuid.UUID("5b0b7a52-6a3e-4c1e-9a8f-1b7d3a0c2f10")
LOG_CATEGORIES = (
    ("logStatusWarning", "Warnings: a rejected IMU sample (the filter state is kept)"),
    ("logStatusError", "Errors: a refused call (wrong state, unknown value reference, value out "
                       "of range, a state this FMU did not write)"),
    ("logEvents", "Other messages"),
)
KIND_SOURCES = {
    "estimator": ("fc_core.c", "fc_state_tables.c"),
    "plant": ("fc_plant.c",),
    "sensor": ("fc_sensor.c", "fc_noise.c", "fc_state_tables.c"),
}
"""The C twin's sources each kind of model needs besides its own file (and fc_state.c, which the
FMU state of every model needs)."""


@dataclass(frozen=True)
class NativeModel:
    """What a native FMU is built from: its name, description, variable table, kind
    (estimator, plant or sensor) and, for an estimator, the C twin's prefix (fc_kf)."""

    name: str
    description: str
    variables: tuple[Variable, ...]
    kind: str
    prefix: str = ""
    params: tuple = ()  # the fusion_core Params that fill the twin's params struct
    fields: tuple[str, ...] = ()  # where each of them goes in the struct (default: its name)
    source: Path | None = None  # the model's C file, if not models/<kind>.c

    @property
    def token(self) -> str:
        """The FMI 2.0 guid and FMI 3.0 instantiationToken: a hash of everything a host reads
        from modelDescription.xml, so that an FMU of another table or version is told apart."""
        text = repr((self.name, project_version(), self.variables))
        return "{" + str(uuid.uuid5(TOKEN_NAMESPACE, text)) + "}"

    def twin_sources(self) -> tuple[str, ...]:
        kind = KIND_SOURCES.get(self.kind, ())
        own = tuple(s for s in twin_closure(self.prefix) if s not in kind) if self.prefix else ()
        return (*kind, *own)


def twin_closure(prefix: str) -> tuple[str, ...]:
    """The C files of an estimator's twin: its own, then those of the twins it includes (a
    recommended filter is built on its paper's equations, a position filter on its Kalman
    filters), read off the #include lines of the twins' sources and headers; not fc_core.c and
    fc_state.c, which every estimator FMU compiles anyway."""
    out: list[str] = []
    todo = [prefix]
    while todo:
        name = todo.pop(0)
        if f"{name}.c" in out or name in ("fc_core", "fc_state", "fc_params"):
            continue
        out.append(f"{name}.c")
        text = "".join((TWIN_DIR / f"{name}{ext}").read_text() for ext in (".c", ".h"))
        todo += [m for m in re.findall(r'#include "(fc_\w+)\.h"', text)
                 if (TWIN_DIR / f"{m}.c").is_file()]
    return tuple(out)


def native_model(name: str, preset: dict[str, dict[str, Any]] | None = None) -> NativeModel:
    """The NativeModel of the FMU called name (fmu_src.names: an estimator of the registry,
    with the estimator class and start values of the preset's entry for it, None: the
    recommended ones, fusion_core.presets.load_preset; or the plant or the sensor)."""
    from fusion_core.native.estimators import param_field
    from fusion_core.registry import ENTRY
    from fusion_core.sensor import SENSOR_PARAMS

    from ..estimator import estimator_table, model_description

    key = estimator_fmus().get(name)
    if key is not None:
        estimator, variables = estimator_table(key, (preset or {}).get(key, {}))
        params = tuple(estimator.param_specs().values())
        return NativeModel(name, model_description(ENTRY[key].fmu_text, estimator), variables,
                           "estimator", estimator.TWIN or "", params,
                           tuple(param_field(estimator, p.name) for p in params))
    if not (MODELS_DIR / script_name(name)).is_file():
        raise ValueError(f"{name} has no native model")
    cls = getattr(importlib.import_module(f"fmu_src.models.{script_name(name)[:-3]}"), name)
    if name == "ImuSensor":
        return NativeModel(name, cls.description, cls.VARIABLES, "sensor", "", SENSOR_PARAMS)
    if name == "ImuPlant":
        return NativeModel(name, cls.description, cls.VARIABLES, "plant")
    raise ValueError(f"{name} has no native model")


# ----- config.h ----------------------------------------------------------------------------------

def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _variable_row(v: Variable) -> str:
    kind = {"Real": "FMU_REAL", "Integer": "FMU_INTEGER", "Boolean": "FMU_BOOLEAN",
            "Enumeration": "FMU_ENUMERATION"}[v.type]
    causality = {"parameter": "FMU_PARAMETER", "input": "FMU_INPUT", "output": "FMU_OUTPUT"}
    if v.type == "Enumeration":
        low, high, low_open, high_open = 1.0, float(len(v.items or ())), False, False
    else:
        low = -math.inf if v.low is None else float(v.low)
        high = math.inf if v.high is None else float(v.high)
        low_open, high_open = v.low_open, v.high_open
    return (f"    {{{_c_string(v.name)}, {kind}, {causality[v.causality]}, {int(v.tunable)}, "
            f"{c_double(float(v.start))}, {c_double(low)}, {c_double(high)}, "
            f"{int(low_open)}, {int(high_open)}}},")


def _param_assignment(p, field: str) -> str:
    if p.choices is not None:
        return f"    p->{field} = (int)v[VR_{p.name}] - 1;"
    if isinstance(p.default, bool):
        return f"    p->{field} = v[VR_{p.name}] != 0.0;"
    if isinstance(p.default, int):
        return f"    p->{field} = (long)v[VR_{p.name}];"
    return f"    p->{field} = v[VR_{p.name}];"


def render_config(model: NativeModel) -> str:
    """The model's config.h."""
    from fusion_core.synthetic import TRUTH_NAMES

    lines = [
        f"/* config.h: the native FMU {model.name}.",
        " *",
        " * GENERATED by fmu_src/native/build.py from the FMU's variable table (the one its",
        " * pythonfmu FMU is built from): do not edit by hand. */",
        "#ifndef CONFIG_H",
        "#define CONFIG_H",
        "",
        "#include <math.h>",
        "",
        '#include "fmu_model.h"',
    ]
    if model.prefix:
        lines.append(f'#include "{model.prefix}.h"')
    if model.kind == "sensor":
        lines.append('#include "fc_sensor.h"')
    lines += [
        "",
        f"#define MODEL_IDENTIFIER {_c_string(model.name)}",
        f"#define MODEL_TOKEN {_c_string(model.token)}",
        "",
        "enum value_reference {",
        *(f"    VR_{v.name} = {i}," for i, v in enumerate(model.variables)),
        "};",
        f"#define N_VARIABLES {len(model.variables)}",
        "",
        "/* name, type, causality, tunable, start, low, high, low open, high open */",
        "static const fmu_variable VARIABLES[N_VARIABLES] = {",
        *(_variable_row(v) for v in model.variables),
        "};",
        "",
    ]
    if model.kind == "estimator":
        names = {v.name for v in model.variables}
        lines += [
            f"#define FC_T {model.prefix}",
            f"#define FC_PARAMS {model.prefix}_params",
            f"#define FC_INIT {model.prefix}_init",
            f"#define FC_CONFIGURE {model.prefix}_configure",
            f"#define FC_STEP {model.prefix}_step",
            f"#define FC_RESTORED {model.prefix}_restored",
            f"#define FC_LAYOUT {model.prefix.upper()}_LAYOUT",
            f"#define HAS_POSITION {int('pos_x' in names)}",
            "",
        ]
    if model.params:
        struct = f"{model.prefix or 'fc_sensor'}_params"
        lines += [
            f"/* The twin's {struct} from the parameter values (a field no variable sets, such",
            " * as a paper filter's gyro_range, at its default). */",
            f"static void params_from_values({struct} *p, const double *v)",
            "{",
            f"    {struct}_default(p);",
            *(_param_assignment(p, field) for p, field in
              zip(model.params, model.fields or [p.name for p in model.params], strict=True)),
            "}",
            "",
        ]
    if model.kind == "plant":
        lines += [
            "/* The output of each fc_plant_truth value, in its order (synthetic.TRUTH_NAMES). */",
            "static const int TRUTH_VR[] = {"
            + ", ".join(f"VR_{n}" for n in TRUTH_NAMES) + "};",
            "",
        ]
    lines += ["#endif /* CONFIG_H */", ""]
    return "\n".join(lines)


# ----- modelDescription.xml ----------------------------------------------------------------------

def _header(root: Element, model: NativeModel) -> None:
    root.set("description", model.description)
    root.set("author", "imu-fusion-fmu contributors")
    root.set("license", "MIT")
    root.set("version", project_version())
    root.set("generationTool", f"imu-fusion-fmu {project_version()} (fmu_src/native)")
    root.set("generationDateAndTime",
             datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z"))
    root.set("variableNamingConvention", "flat")


def _log_categories(parent: Element) -> None:
    cats = SubElement(parent, "LogCategories")
    for name, text in LOG_CATEGORIES:
        SubElement(cats, "Category", {"name": name, "description": text})


def _pretty(root: Element) -> bytes:
    return minidom.parseString(tostring(root, encoding="unicode")).toprettyxml(
        indent="  ", encoding="UTF-8")


def _description_body(root: Element, model: NativeModel, version: str) -> Element:
    """What both standards' modelDescription.xml hold after CoSimulation, in order: the unit
    and type definitions, the log categories, the default experiment; returns the (empty)
    ModelVariables element."""
    units = model.variables
    if version == "3.0":  # the independent variable, time, has a unit of its own
        units = (*units, Variable("time", "input", "Real", "the independent variable", 0.0, "s"))
    root.append(unit_definitions(units))
    types = type_definitions(model.variables, version)
    if types is not None:
        root.append(types)
    _log_categories(root)
    SubElement(root, "DefaultExperiment",
               {"startTime": "0.0", "stopTime": "10.0", "stepSize": "0.01"})
    return SubElement(root, "ModelVariables")


def _variable_attributes(vr: int, v: Variable) -> dict[str, str]:
    """The attributes every standard gives a variable: name, value reference (its position in
    the table), description, causality, variability and, for an output, initial."""
    attrs = {"name": v.name, "valueReference": str(vr), "description": v.description,
             "causality": v.causality, "variability": v.variability or "continuous"}
    if v.causality == "output":
        attrs["initial"] = v.initial
    return attrs


def fmi2_model_description(model: NativeModel, sources: Sequence[str]) -> bytes:
    """modelDescription.xml of the FMI 2.0 co-simulation FMU."""
    root = Element("fmiModelDescription", {"fmiVersion": "2.0", "modelName": model.name,
                                           "guid": model.token})
    _header(root, model)
    root.set("numberOfEventIndicators", "0")
    cs = SubElement(root, "CoSimulation", {
        "modelIdentifier": model.name,
        "needsExecutionTool": "false",
        "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "false",
        "maxOutputDerivativeOrder": "0",
        "canRunAsynchronuously": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "false",
    })
    files = SubElement(cs, "SourceFiles")
    for name in sources:
        SubElement(files, "File", {"name": name})
    variables = _description_body(root, model, "2.0")
    for vr, v in enumerate(model.variables):
        sv = SubElement(variables, "ScalarVariable", _variable_attributes(vr, v))
        SubElement(sv, v.type, type_attributes(v, start=v.initial == "exact"))
    structure = SubElement(root, "ModelStructure")
    outs = SubElement(structure, "Outputs")
    for vr, v in enumerate(model.variables):  # FMI 2.0 counts variables from 1
        if v.causality == "output":
            SubElement(outs, "Unknown", {"index": str(vr + 1)})
    unknowns = initial_unknowns(model.variables)
    if unknowns:
        node = SubElement(structure, "InitialUnknowns")
        for v, deps in unknowns:
            SubElement(node, "Unknown", {"index": str(model.variables.index(v) + 1),
                                         "dependencies": " ".join(str(d + 1) for d in deps)})
    return _pretty(root)


FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
              "Enumeration": "Enumeration"}
"""The FMI 3.0 type of each FMI 2.0 type of the variable tables."""


def fmi3_model_description(model: NativeModel) -> bytes:
    """modelDescription.xml of the FMI 3.0 co-simulation FMU."""
    root = Element("fmiModelDescription", {"fmiVersion": "3.0", "modelName": model.name,
                                           "instantiationToken": model.token})
    _header(root, model)
    SubElement(root, "CoSimulation", {
        "modelIdentifier": model.name,
        "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true",
        "canHandleVariableCommunicationStepSize": "true",
        "providesIntermediateUpdate": "false",
        "canReturnEarlyAfterIntermediateUpdate": "false",
        "hasEventMode": "false",
    })
    variables = _description_body(root, model, "3.0")
    SubElement(variables, "Float64", {
        "name": "time", "valueReference": str(len(model.variables)), "causality": "independent",
        "variability": "continuous", "unit": "s",
        "description": "Simulation time (the independent variable; value reference after the "
                       "model's variables, which keep the FMI 2.0 FMUs' references)"})
    for vr, v in enumerate(model.variables):
        attrs = _variable_attributes(vr, v)
        attrs.update(type_attributes(v, start=v.initial == "exact"))
        SubElement(variables, FMI3_TYPES[v.type], attrs)
    structure = SubElement(root, "ModelStructure")
    for vr, v in enumerate(model.variables):
        if v.causality == "output":
            SubElement(structure, "Output", {"valueReference": str(vr)})
    for v, deps in initial_unknowns(model.variables):
        SubElement(structure, "InitialUnknown", {
            "valueReference": str(model.variables.index(v)),
            "dependencies": " ".join(str(d) for d in deps)})
    return _pretty(root)


def fmi3_build_description(model: NativeModel, sources: Sequence[str]) -> bytes:
    """sources/buildDescription.xml of the FMI 3.0 FMU."""
    root = Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    config = SubElement(root, "BuildConfiguration", {"modelIdentifier": model.name})
    files = SubElement(config, "SourceFileSet", {"language": "C99"})
    for name in sources:
        SubElement(files, "SourceFile", {"name": name})
    return _pretty(root)


# ----- compile and package -----------------------------------------------------------------------

def cross_compiler() -> str | None:
    """mingw-w64's gcc for the Windows binary, where it is installed."""
    return shutil.which(MINGW)


def stage_sources(model: NativeModel, version: str, folder: Path) -> list[str]:
    """Write the FMU's C sources into folder; return the files to compile, in order."""
    folder.mkdir(parents=True, exist_ok=True)
    plumbing = f"{version}Functions.c"
    source = model.source or HERE / "models" / f"{model.kind}.c"
    own = source.name
    compiled = [plumbing, "fmu_instance.c", "fc_state.c", own, *model.twin_sources()]
    shutil.copy2(HERE / plumbing, folder / plumbing)
    shutil.copy2(HERE / "fmu_instance.c", folder / "fmu_instance.c")
    shutil.copy2(HERE / "fmu_model.h", folder / "fmu_model.h")
    shutil.copy2(source, folder / own)
    for header in (HERE / "include").glob(f"{version}*.h"):
        shutil.copy2(header, folder / header.name)
    for path in TWIN_DIR.glob("*.h"):
        shutil.copy2(path, folder / path.name)
    for name in ("fc_state.c", *model.twin_sources()):
        shutil.copy2(TWIN_DIR / name, folder / name)
    (folder / "config.h").write_text(render_config(model))
    return compiled


def object_cache() -> Path:
    """Where compiled objects are kept by content (beside the C twin's library: build/ in a
    checkout), so that the sources every FMU shares (the FMI plumbing, the twins) are compiled
    once for all FMUs, presets and builds, and only a model's own configured file each time."""
    from fusion_core.native.library import cache_dir

    return cache_dir().parent / "fmu-objects"


def _run(cmd: list[str], what: str) -> None:
    """Run a compiler command: RuntimeError with its last lines where it fails, a
    CompilerWarning with what it said where it warns."""
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-15:])
        raise RuntimeError(f"compiling {what} failed ({' '.join(cmd)}):\n{tail}")
    said = (proc.stdout + proc.stderr).strip()
    if said:
        warnings.warn(f"compiling {what} gave warnings:\n{said}", CompilerWarning, stacklevel=3)


def cached_object(cc: str, flags: Sequence[str], sources: Path, name: str, what: str) -> Path:
    """sources/name compiled (cc -c) into the object cache, unless an object of the same
    compiler, flags, source and headers is there already. Its key holds every header of the
    staged folder (config.h, the one file that differs between FMUs, only where the source
    names it), so that a change to any of them compiles again."""
    text = (sources / name).read_bytes()
    h = hashlib.sha256("\0".join((cc, *flags, name)).encode() + b"\0" + text)
    for header in sorted(sources.glob("*.h")):
        if header.name != "config.h" or b'"config.h"' in text:
            h.update(header.name.encode() + b"\0" + header.read_bytes())
    obj = object_cache() / f"{h.hexdigest()[:32]}.o"
    if not obj.is_file():
        obj.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(suffix=".o", dir=obj.parent)
        os.close(fd)
        try:
            _run([cc, *flags, "-I", str(sources), "-c", "-o", tmp, str(sources / name)],
                 f"{name} of {what}")
            os.replace(tmp, obj)  # atomic: a parallel build never links half an object
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return obj


def compile_binary(cc: str, sources: Path, files: Sequence[str], target: Path,
                   windows: bool = False) -> None:
    """Compile the FMU's sources into target (a shared library), each through the object
    cache, and link them; RuntimeError with the compiler's last lines when it fails."""
    target.parent.mkdir(parents=True, exist_ok=True)
    flags = [*(f for f in CFLAGS if f != "-shared"), *([] if windows else ["-fPIC"])]
    objects = [cached_object(cc, flags, sources, f, target.name) for f in files]
    _run([cc, "-shared", *(["-static-libgcc"] if windows else []), "-o", str(target),
          *(str(o) for o in objects), "-lm"], target.name)


def build_native(model: NativeModel, version: str, out_dir: Path,
                 cc: str | None = None, windows: bool | None = None) -> Path:
    """Build out_dir/<version>/<name>.fmu for one model and FMI version ("fmi2" or "fmi3");
    with a Windows binary too where mingw-w64 is installed (windows=None) or as asked."""
    cc = cc or twin_compiler()
    if cc is None:
        raise RuntimeError("no C compiler found (set CC, or install cc, gcc or clang)")
    mingw = cross_compiler() if windows is None else (cross_compiler() if windows else None)
    if windows and mingw is None:
        raise RuntimeError(f"no Windows cross compiler: install {MINGW} (Debian: "
                           "gcc-mingw-w64-x86-64)")
    target = out_dir / version / f"{model.name}.fmu"
    with tempfile.TemporaryDirectory(prefix="native_fmu_") as tmp:
        root = Path(tmp)
        sources = root / "sources"
        files = stage_sources(model, version, sources)
        if version == "fmi2":
            (root / "modelDescription.xml").write_bytes(fmi2_model_description(model, files))
        else:
            (root / "modelDescription.xml").write_bytes(fmi3_model_description(model))
            (sources / "buildDescription.xml").write_bytes(fmi3_build_description(model, files))
        host = host_platform()
        builds = [(host, cc)] + ([(WINDOWS, mingw)] if mingw and host is not WINDOWS else [])
        for folder, compiler_path in builds:
            binary = root / "binaries" / folder[version] / (model.name + folder["suffix"])
            compile_binary(compiler_path, sources, files, binary, folder is WINDOWS)
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_zip = tempfile.mkstemp(suffix=".fmu", dir=target.parent)
        os.close(fd)
        with zipfile.ZipFile(tmp_zip, "w", zipfile.ZIP_DEFLATED) as fmu:
            for path in sorted(root.rglob("*")):
                if path.is_file():
                    fmu.write(path, path.relative_to(root).as_posix())
        os.replace(tmp_zip, target)
    return target
