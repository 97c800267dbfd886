"""Generate the C twin's tables from their Python source: fc_params.h, the parameter structs, from
the PARAMS tables of the estimators and of the sensor model; fc_scenarios.h, the plant's
scenarios, from their signals; fc_state_tables.c, each twin's state layout (fc_state.h), from the
STATE declarations with their checks (fusion_core.state), the C types and sizes read from the
twin's own headers.

One source of truth: every estimator's parameters (names, defaults, ranges, units, choices) are
declared once, in its Python class; this script writes them as C so that the two languages
cannot disagree. tests/test_native.py fails when the file in the repository is stale.

    python -m fusion_core.native.generate           # rewrite the generated files
    python -m fusion_core.native.generate --check   # exit 1 if one is stale
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import Any

from fusion_core.base import COMMON_PARAMS, Estimator
from fusion_core.position import PENDING_MAX
from fusion_core.registry import CLASSES
from fusion_core.sensor import SENSOR_PARAMS, ImuSensorModel
from fusion_core.state import (
    BASE_STATE,
    COV_LOWER,
    COV_UPPER,
    FLAG,
    NONNEG,
    REAL,
    Check,
    Segments,
    count,
    index,
)
from fusion_core.types import ABSENT, Param

HERE = Path(__file__).resolve().parent
OUTPUT = HERE / "fc_params.h"
SCENARIOS_OUTPUT = HERE / "fc_scenarios.h"
STATE_OUTPUT = HERE / "fc_state_tables.c"
LAYOUTS_OUTPUT = HERE / "fc_state_layouts.h"
KINDS = ("constant", "sine", "add", "min_jerk", "product", "swelling_sine")
"""The signal kinds of fusion_core.synthetic (and scenarios.swelling_sine), by their C number."""
TWINS: dict[str, type[Estimator]] = {cls.TWIN: cls for cls in CLASSES if cls.TWIN is not None}
"""Every estimator class by its twin's prefix (fusion_core.registry.CLASSES: the references
first where a recommended filter is built on them)."""
PREFIX = [*TWINS, "fc_sensor"]
"""The C name of each estimator class's twin and of the sensor model."""


def c_double(x: float) -> str:
    """x as a C double literal that parses back to exactly x (repr is the shortest such)."""
    if x == float("inf"):
        return "HUGE_VAL"
    if x == float("-inf"):
        return "-HUGE_VAL"
    text = repr(float(x))
    return text if any(c in text for c in ".e") else text + ".0"


def c_type(p: Param) -> str:
    if p.choices is not None or isinstance(p.default, bool):
        return "int"
    return "long" if isinstance(p.default, int) else "fc_real"


SHARED: dict[str, Param] = {p.name: p for p in COMMON_PARAMS if p.choices is not None}
"""The enumerations every estimator shares (base.COMMON_PARAMS): their choices are #defined once,
FC_GYRO_SAMPLING_POINT, for fc_core's shared stage and every twin."""


def choice_name(prefix: str, p: Param, choice: str) -> str:
    """The #define of one choice of an enumeration parameter: FC_KF_PROPAGATION_QUATERNION, or,
    with the prefix "fc", FC_GYRO_SAMPLING_POINT for one every estimator shares (SHARED)."""
    return f"{prefix.upper()}_{p.name.upper()}_{choice.upper()}"


def c_value(prefix: str, p: Param) -> str:
    if p.choices is not None:
        return choice_name(prefix, p, str(p.default))
    if isinstance(p.default, bool):
        return "1" if p.default else "0"
    if isinstance(p.default, int):
        return f"{p.default}L"
    return c_double(float(p.default))


def comment(p: Param) -> str:
    """The parameter's unit and allowed values, as the C comment beside its field."""
    unit = "" if p.unit == "1" else f" [{p.unit}]"
    return f"{p.allowed()}{unit}"


def struct_lines(struct: str, specs: list[Param], extra: tuple[str, str] | None = None
                 ) -> list[str]:
    """typedef struct struct {...} struct; with a field per parameter, its allowed values beside
    it, and extra, a (declaration, comment) field after them."""
    decls = [(f"    {c_type(p)} {p.name};", comment(p)) for p in specs]
    if extra is not None:
        decls.append((f"    {extra[0]};", extra[1]))
    width = max(len(d) for d, _ in decls)
    return [f"typedef struct {struct} {{", *(f"{d:<{width}}  /* {c} */" for d, c in decls),
            f"}} {struct};", ""]


def input_block() -> list[str]:
    """fc_input_params, the parameters of the input stage every estimator shares
    (base.COMMON_PARAMS: fc_base_configure), with their defaults."""
    out = ["/* ----- the input stage every estimator shares (base.COMMON_PARAMS) " + "-" * 12
           + " */", ""]
    for p in SHARED.values():
        for i, choice in enumerate(p.choices or ()):
            out.append(f"#define {choice_name('fc', p, choice)} {i}")
    out += ["", *struct_lines("fc_input_params", list(COMMON_PARAMS))]
    out += ["/* The defaults: base.COMMON_PARAMS. */",
            "static inline void fc_input_params_default(fc_input_params *p)", "{",
            *(f"    p->{p.name} = {c_value('fc', p)};" for p in COMMON_PARAMS), "}", ""]
    return out


def estimator_block(prefix: str) -> list[str]:
    """prefix's params struct: a field per parameter of its own (the class's PARAMS) and, for an
    estimator, its input stage's in `input`, at the class's defaults (a COMMON parameter the
    class leaves out at base.ABSENT's value)."""
    if prefix == "fc_sensor":
        name, own, common = ImuSensorModel.__name__, list(SENSOR_PARAMS), None
    else:
        cls = TWINS[prefix]
        name, own, common = cls.__name__, list(cls.PARAMS), {p.name: p for p in cls.COMMON}
    out = [f"/* ----- {name} ({prefix}) " + "-" * (80 - len(name) - len(prefix) - 14) + " */", ""]
    for p in own:
        for i, choice in enumerate(p.choices or ()):
            out.append(f"#define {choice_name(prefix, p, choice)} {i}")
    if any(p.choices for p in own):
        out.append("")
    extra = None if common is None else ("fc_input_params input", "the input stage's")
    out += struct_lines(f"{prefix}_params", own, extra)
    out.append(f"/* The defaults: {name}'s. */")
    out.append(f"static inline void {prefix}_params_default({prefix}_params *p)")
    out.append("{")
    for p in own:
        out.append(f"    p->{p.name} = {c_value(prefix, p)};")
    if common is not None:
        out.append("    fc_input_params_default(&p->input);")
        for q in COMMON_PARAMS:
            if q.name not in common:
                out.append(f"    p->input.{q.name} = {c_double(ABSENT[q.name])};  "
                           f"/* {name} has no {q.name} */")
            elif common[q.name].default != q.default:
                out.append(f"    p->input.{q.name} = {c_value('fc', common[q.name])};")
    out.append("}")
    out.append("")
    return out


def render() -> str:
    lines = [
        "/* fc_params.h: the parameters of every estimator of fusion_core's C twin.",
        " *",
        " * GENERATED by `python -m fusion_core.native.generate` from the estimators' PARAMS",
        " * tables, the one source of truth: do not edit by hand. Each field is a parameter of",
        " * the same name; an enumeration is an int whose values are the #defines above its",
        " * struct, in the Python choices' order. An estimator's struct holds its own parameters",
        " * (its class's PARAMS) and, in `input`, those of the input stage every estimator shares",
        " * (fc_input_params: base.COMMON_PARAMS).",
        " */",
        "#ifndef FC_PARAMS_H",
        "#define FC_PARAMS_H",
        "",
        '#include "fc_real.h"',
        "",
    ]
    lines += [
        "/* Sizes the twins' state takes from the Python classes. */",
        f"#define FC_POSKF_PENDING_MAX {PENDING_MAX}  /* position.PENDING_MAX */",
        "",
    ]
    lines += input_block()
    for prefix in PREFIX:
        lines += estimator_block(prefix)
    lines += ["#endif /* FC_PARAMS_H */", ""]
    return "\n".join(lines)


def render_scenarios() -> str:
    """fc_scenarios.h: every scenario's signals as a table of nodes (synthetic.spec_of)."""
    from fusion_core.scenarios import SCENARIOS
    from fusion_core.synthetic import spec_of

    nodes: list[str] = []
    children: list[int] = []

    def node(spec: tuple) -> int:
        kind, *rest = spec
        kids = [node(c) for c in rest if isinstance(c, tuple)]
        params = [float(v) for v in rest if not isinstance(v, tuple)]
        first = len(children)
        children.extend(kids)
        index = len(nodes)
        p = ", ".join(c_double(v) for v in params + [0.0] * (4 - len(params)))
        nodes.append(f"    {{{KINDS.index(kind)}, {{{p}}}, {first}, {len(kids)}}},  /* {kind} */")
        return index

    rows = []
    for sc in SCENARIOS.values():
        tr = sc.trajectory()
        roots = [node(spec_of(sig)) for sig in (tr.roll, tr.pitch, tr.yaw, *tr.pos)]
        rows.append(f"    {{{sc.id}, \"{sc.name}\", {c_double(sc.duration)}, "
                    f"{{{', '.join(str(r) for r in roots)}}}}},")
    lines = [
        "/* fc_scenarios.h: the testbench scenarios (fusion_core/scenarios.py) as data for the C",
        " * twin of the plant: each signal a node (kind, parameters, children).",
        " *",
        " * GENERATED by `python -m fusion_core.native.generate` from the scenarios' signals:",
        " * do not edit by hand. Kinds: "
        + ", ".join(f"{i} {k}" for i, k in enumerate(KINDS)) + ".",
        " */",
        "#ifndef FC_SCENARIOS_H",
        "#define FC_SCENARIOS_H",
        "",
        "typedef struct fc_signal_node {",
        "    int kind;",
        "    double p[4];",
        "    int first_child, n_children;",
        "} fc_signal_node;",
        "",
        "typedef struct fc_scenario_def {",
        "    int id;",
        "    const char *name;",
        "    double duration;",
        "    int signal[6];  /* roll, pitch, yaw, pos x, y, z: root nodes */",
        "} fc_scenario_def;",
        "",
        "static const fc_signal_node FC_NODES[] = {",
        *nodes,
        "};",
        "",
        f"static const int FC_CHILDREN[] = {{{', '.join(str(c) for c in children) or '0'}}};",
        "",
        f"#define FC_N_SCENARIOS {len(rows)}",
        "static const fc_scenario_def FC_SCENARIO_DEFS[FC_N_SCENARIOS] = {",
        *rows,
        "};",
        "",
        "#endif /* FC_SCENARIOS_H */",
        "",
    ]
    return "\n".join(lines)


# ----- fc_state_tables.c -------------------------------------------------------------------------

Entry = tuple[str, str, Check, int | None]
"""One field of a C layout: its name, its member path in the twin's struct, its check, and its
number of values (None: the member's whole size)."""

C_CHECKS: dict[tuple[str, str], Check] = {("fc_ukf", "P"): COV_LOWER,
                                          ("fc_paper_ukf", "P"): COV_LOWER}
"""Where the C twin stores a state field in another form than the Python class: the UKFs' P is
its packed lower triangle (UnscentedKalmanFilter._P), the Python state its 6x6 matrix."""


def _entries(spec: dict[str, Any], prefix: str = "") -> list[Entry]:
    """The layout entries of a STATE declaration: a field per name, a Segments field split into
    its runs of elements."""
    out: list[Entry] = []
    for name, check in spec.items():
        if isinstance(check, Segments):
            start = 0
            for part, n in check.parts:
                label = f"{name}[{start}]" if n == 1 else f"{name}[{start}:{start + n}]"
                out.append((prefix + label, f"{prefix}{name}[{start}]", part, n))
                start += n
        else:
            out.append((prefix + name, prefix + name, check, None))
    return out


def _base_entries(prefix: str = "") -> list[Entry]:
    return _entries(BASE_STATE, prefix + "base.")


def state_layouts() -> dict[str, list[Entry]]:
    """Every twin's state layout: the base state, then the class's STATE (a position filter's,
    whose twin holds its nested filters and its queue in C form, and the sensor's, written out
    here)."""
    layouts: dict[str, list[Entry]] = {}
    for prefix, cls in TWINS.items():
        if cls.HAS_POSITION:
            continue
        entries = _base_entries() + _entries(cls.STATE)
        layouts[prefix] = [(n, path, C_CHECKS.get((prefix, path), check), size)
                           for n, path, check, size in entries]

    def nested(name: str, twin: str) -> list[Entry]:
        return [(f"{name}.{n}", f"{name}.{path}", check, size)
                for n, path, check, size in layouts[twin]]

    axes = {"x": REAL, "P": COV_UPPER}
    layouts["fc_paper_poskf"] = [
        *_base_entries(),
        *_entries({"yaw": TWINS["fc_paper_poskf"].STATE["yaw"], **axes}),
        *nested("tilt", "fc_paper_kf"),
    ]
    layouts["fc_poskf"] = [
        *_base_entries(),
        *_entries({"yaw": TWINS["fc_poskf"].STATE["yaw"], **axes,
                   "quiet_time": NONNEG, "stationary": FLAG, "pending": REAL,
                   "pending_head": index(PENDING_MAX), "pending_count": count(PENDING_MAX),
                   "turned": REAL, "f_mean": REAL, "aligned": FLAG}),
        *nested("tilt", "fc_paper_kf"),
        *nested("att", "fc_kf"),
    ]
    sensor = dict(ImuSensorModel.STATE)
    del sensor["omega_prev"]  # None in Python before the first sample: has_omega_prev in C
    layouts["fc_sensor"] = _entries({**sensor, "has_omega_prev": FLAG, "omega_prev": REAL,
                                     "gyro_filter.started": FLAG, "gyro_filter.state": REAL,
                                     "acc_filter.started": FLAG, "acc_filter.state": REAL})
    return layouts


def _member(ffi: Any, struct: str, path: str) -> tuple[str, int]:
    """The C type name of a member path's values and how many there are from it to the end of
    its member (`x[3]` of a double x[6]: 3)."""
    t = ffi.typeof(struct)
    rows = 1
    for part in path.split("."):
        m = re.fullmatch(r"(\w+)(?:\[(\d+)\])?", part)
        if m is None:
            raise ValueError(f"{struct}: cannot read member path {path!r}")
        t = dict(t.fields)[m.group(1)].type
        if m.group(2) is not None:
            rows = t.length - int(m.group(2))
            t = t.item
    n = rows
    while t.kind == "array":
        n *= t.length
        t = t.item
    return t.cname, n


C_TYPES = {"double": "FC_DOUBLE", "int": "FC_INT", "long": "FC_LONG"}


def render_state_tables() -> str:
    """fc_state_tables.c: every twin's layout as data for fc_state.c."""
    import cffi  # type: ignore[import-untyped]

    from fusion_core.native import cdef

    ffi = cffi.FFI()
    ffi.cdef(cdef())
    lines = [
        "/* fc_state_tables.c: every twin's state layout (fc_state.h): the fields a saved state",
        " * holds, in order, each with its check.",
        " *",
        " * GENERATED by `python -m fusion_core.native.generate` from the STATE declarations of",
        " * the Python classes (fusion_core/state.py), the types and sizes from the twins'",
        " * headers: do not edit by hand.",
        " */",
        "#include <stddef.h>",
        "#include <string.h>",
        "",
        *(f'#include "{prefix}.h"' for prefix in sorted(PREFIX)),
        '#include "fc_state_layouts.h"',
        "",
    ]
    for prefix, entries in state_layouts().items():
        table = prefix.upper()[3:] + "_FIELDS"
        lines.append(f"static const fc_field {table}[] = {{")
        for name, path, check, size in entries:
            cname, n = _member(ffi, prefix, path)
            if cname not in C_TYPES:
                raise ValueError(f"{prefix}.{path} is {cname}: a state field is a double, an "
                                 "int or a long")
            if size is not None and size > n:
                raise ValueError(f"{prefix}.{path}: {size} values, the member has {n}")
            lines.append(f'    {{"{name}", offsetof({prefix}, {path}), {C_TYPES[cname]}, '
                         f"{size or n}, FC_CHECK_{check.kind.upper()}, "
                         f"{c_double(check.high)}}},")
        lines.append("};")
        lines.append(f"const fc_layout {prefix.upper()}_LAYOUT = {{\"{prefix}\", {table}, "
                     f"(int)(sizeof {table} / sizeof {table}[0])}};")
        lines.append("")
    lines += [
        "const fc_layout *fc_state_layout(const char *twin)",
        "{",
        "    const fc_layout *all[] = {"
        + ", ".join(f"&{p.upper()}_LAYOUT" for p in state_layouts()) + "};",
        "    size_t i;",
        "    for (i = 0; twin && i < sizeof all / sizeof all[0]; i++) {",
        "        if (strcmp(all[i]->twin, twin) == 0) {",
        "            return all[i];",
        "        }",
        "    }",
        "    return NULL;",
        "}",
        "",
    ]
    return "\n".join(lines)


def render_state_layouts() -> str:
    """fc_state_layouts.h: the declaration of every twin's layout by name (FC_<TWIN>_LAYOUT),
    for the code that names one (the native FMUs' models)."""
    names = [f"{p.upper()}_LAYOUT" for p in state_layouts()]
    return "\n".join([
        "/* fc_state_layouts.h: every twin's state layout, declared (fc_state.h; the tables are",
        " * fc_state_tables.c).",
        " *",
        " * GENERATED by `python -m fusion_core.native.generate` from the STATE declarations of",
        " * the Python classes: do not edit by hand.",
        " */",
        "#ifndef FC_STATE_LAYOUTS_H",
        "#define FC_STATE_LAYOUTS_H",
        "",
        '#include "fc_state.h"',
        "",
        *(f"extern const fc_layout {n};" for n in names),
        "",
        "#endif",
        "",
    ])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="exit 1 (and say so) if a generated header is not what the Python "
                        "sources give")
    args = parser.parse_args(argv)
    files = {OUTPUT: render(), SCENARIOS_OUTPUT: render_scenarios()}
    if not args.check and OUTPUT.read_text() != files[OUTPUT]:
        OUTPUT.write_text(files[OUTPUT])  # the state tables read the parameter structs from it
    files[STATE_OUTPUT] = render_state_tables()
    files[LAYOUTS_OUTPUT] = render_state_layouts()
    if args.check:
        stale = [p for p, text in files.items()
                 if not p.is_file() or p.read_text() != text]
        for path in stale:
            print(f"{path} is stale: run python -m fusion_core.native.generate", file=sys.stderr)
        return 1 if stale else 0
    for path, text in files.items():
        path.write_text(text)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
