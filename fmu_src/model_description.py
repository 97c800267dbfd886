"""modelDescription.xml decoration: what pythonfmu cannot write, added from the variable table.

pythonfmu writes names, causality, variability, initial, start and description. This adds
  <UnitDefinitions>  one <Unit> per unit used, with its SI <BaseUnit> exponents (a declared
                     dimensionless unit "1" with an empty BaseUnit) and its <DisplayUnit>s with
                     their factor (deg: 180/pi per power of rad);
  <TypeDefinitions>  one Enumeration type per enumeration parameter;
  per variable       unit, displayUnit, min and max (closed bounds of the allowed range; open
                     bounds are stated in the description only, since min/max are inclusive).
Unit strings use the Modelica syntax: "m/s2", "rad2/s3", "1". FMI 2.0 BaseUnit exponents are
integers, so every unit must have integer SI exponents: a noise density such as
rad/(s.sqrt(Hz)) = rad.s^-1/2 is refused at build time, and the parameters are declared as
power spectral densities instead (rad2/s, the density squared).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from fractions import Fraction
from xml.etree.ElementTree import Element, SubElement

from .variables import Variable

BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
"""The SI base units an FMI 2.0 <BaseUnit> has exponents for, in schema order."""

Dimension = dict[str, Fraction]

_SYMBOLS: dict[str, tuple[Dimension, float]] = {
    "m": ({"m": Fraction(1)}, 1.0),
    "s": ({"s": Fraction(1)}, 1.0),
    "kg": ({"kg": Fraction(1)}, 1.0),
    "A": ({"A": Fraction(1)}, 1.0),
    "K": ({"K": Fraction(1)}, 1.0),
    "mol": ({"mol": Fraction(1)}, 1.0),
    "cd": ({"cd": Fraction(1)}, 1.0),
    "rad": ({"rad": Fraction(1)}, 1.0),
    "deg": ({"rad": Fraction(1)}, math.pi / 180.0),
    "Hz": ({"s": Fraction(-1)}, 1.0),
    "N": ({"kg": Fraction(1), "m": Fraction(1), "s": Fraction(-2)}, 1.0),
}
"""Unit symbols: SI exponents and the value of one unit in SI (deg = pi/180 rad)."""

_TOKEN = re.compile(r"\s*(sqrt\(|[A-Za-z]+-?\d*|1|\(|\)|/|\.)")


class UnitError(ValueError):
    """A unit string this module cannot read."""


def parse_unit(unit: str) -> tuple[Dimension, float]:
    """SI exponents and scale of a Modelica-style unit string ("1" is dimensionless)."""
    tokens = _tokenize(unit)
    dim, scale, rest = _expression(tokens, unit)
    if rest:
        raise UnitError(f"unit {unit!r}: unexpected {''.join(rest)!r}")
    return {k: v for k, v in dim.items() if v != 0}, scale


def _tokenize(unit: str) -> list[str]:
    tokens, pos = [], 0
    while pos < len(unit.rstrip()):
        m = _TOKEN.match(unit, pos)
        if m is None:
            raise UnitError(f"unit {unit!r}: cannot read {unit[pos:]!r}")
        tokens.append(m.group(1))
        pos = m.end()
    return tokens


def _combine(a: Dimension, b: Dimension, sign: int) -> Dimension:
    out = dict(a)
    for k, v in b.items():
        out[k] = out.get(k, Fraction(0)) + sign * v
    return out


def _expression(tokens: list[str], unit: str) -> tuple[Dimension, float, list[str]]:
    """product ['/' factor]; a product is factors joined by '.'."""
    dim, scale, tokens = _factor(tokens, unit)
    while tokens and tokens[0] == ".":
        d, s, tokens = _factor(tokens[1:], unit)
        dim, scale = _combine(dim, d, 1), scale * s
    if tokens and tokens[0] == "/":
        d, s, tokens = _factor(tokens[1:], unit)
        dim, scale = _combine(dim, d, -1), scale / s
    return dim, scale, tokens


def _factor(tokens: list[str], unit: str) -> tuple[Dimension, float, list[str]]:
    if not tokens:
        raise UnitError(f"unit {unit!r} ends too early")
    head, tokens = tokens[0], tokens[1:]
    if head in ("(", "sqrt("):
        dim, scale, tokens = _expression(tokens, unit)
        if not tokens or tokens[0] != ")":
            raise UnitError(f"unit {unit!r}: missing ')'")
        tokens = tokens[1:]
        if head == "sqrt(":
            dim, scale = {k: v / 2 for k, v in dim.items()}, math.sqrt(scale)
        return dim, scale, tokens
    if head == "1":
        return {}, 1.0, tokens
    m = re.fullmatch(r"([A-Za-z]+)(-?\d*)", head)
    if m is None or m.group(1) not in _SYMBOLS:
        raise UnitError(f"unit {unit!r}: unknown symbol {head!r}")
    power = int(m.group(2)) if m.group(2) else 1
    dim, scale = _SYMBOLS[m.group(1)]
    return {k: v * power for k, v in dim.items()}, scale**power, tokens


def base_unit_attributes(unit: str) -> dict[str, str]:
    """The <BaseUnit> attributes of a unit; UnitError when an exponent is not an integer."""
    dim, scale = parse_unit(unit)
    halves = {k: str(v) for k, v in dim.items() if v.denominator != 1}
    if halves:
        raise UnitError(
            f"unit {unit!r} has non-integer SI exponents {halves}, which an FMI 2.0 <BaseUnit> "
            "cannot hold: declare the power spectral density (the density squared, e.g. rad2/s "
            "for rad/(s.sqrt(Hz))) instead"
        )
    attrs = {k: str(int(dim[k])) for k in BASE_UNITS if k in dim}
    if scale != 1.0:
        attrs["factor"] = repr(scale)
    return attrs


def display_factor(unit: str, display_unit: str) -> float:
    """FMI DisplayUnit factor: display value = factor * value (same dimension required)."""
    dim, scale = parse_unit(unit)
    ddim, dscale = parse_unit(display_unit)
    if dim != ddim:
        raise UnitError(f"display unit {display_unit!r} does not fit unit {unit!r}")
    return scale / dscale


def unit_definitions(variables: Sequence[Variable]) -> Element:
    """<UnitDefinitions> for every unit and display unit the Real variables use."""
    units: dict[str, list[str]] = {}
    for v in variables:
        if v.type == "Real" and v.unit:
            displays = units.setdefault(v.unit, [])
            if v.display_unit and v.display_unit not in displays:
                displays.append(v.display_unit)
    root = Element("UnitDefinitions")
    for name in sorted(units):
        node = SubElement(root, "Unit", {"name": name})
        SubElement(node, "BaseUnit", base_unit_attributes(name))
        for display in units[name]:
            SubElement(
                node, "DisplayUnit",
                {"name": display, "factor": repr(display_factor(name, display))},
            )
    return root


def type_definitions(variables: Sequence[Variable], version: str = "2.0") -> Element | None:
    """<TypeDefinitions> with one enumeration type per enumeration variable (FMI 2.0's
    SimpleType/Enumeration or FMI 3.0's EnumerationType, by version), or None."""
    enums = [v for v in variables if v.type == "Enumeration"]
    if not enums:
        return None
    root = Element("TypeDefinitions")
    for v in enums:
        attrs = {"name": v.type_name or "", "description": f"Choices of {v.name}"}
        if version == "3.0":
            enum = SubElement(root, "EnumerationType", attrs)
        else:
            enum = SubElement(SubElement(root, "SimpleType", attrs), "Enumeration")
        for value, item in enumerate(v.items or (), 1):
            SubElement(enum, "Item", {"name": item, "value": str(value)})
    return root


def number(x: float | int | bool, kind: str) -> str:
    """A value of a variable of type kind as modelDescription.xml writes it (a Real by repr,
    which round-trips every double)."""
    if kind == "Boolean":
        return "true" if x else "false"
    if kind in ("Integer", "Enumeration"):
        return str(int(x))
    return repr(float(x))


def type_attributes(v: Variable, start: bool = True) -> dict[str, str]:
    """The attributes a variable's type carries: its enumeration type, unit and display unit,
    the closed bounds of its range and (start) its start value. FMI 2.0 writes them on the
    type element inside <ScalarVariable>, FMI 3.0 on the variable's own element; every writer
    of a model description (decorate for the pythonfmu FMUs, fmu_src.native.build for the
    native ones) takes them from here."""
    attrs: dict[str, str] = {}
    if v.type == "Enumeration":
        attrs["declaredType"] = v.type_name or ""
    if v.type == "Real":
        attrs["unit"] = v.unit or "1"
        if v.display_unit:
            attrs["displayUnit"] = v.display_unit
    if v.type in ("Real", "Integer"):
        if v.low is not None and not v.low_open:
            attrs["min"] = number(v.low, v.type)
        if v.high is not None and not v.high_open:
            attrs["max"] = number(v.high, v.type)
    if start:
        attrs["start"] = number(v.start, v.type)
    return attrs


def initial_unknowns(variables: Sequence[Variable]) -> list[tuple[Variable, list[int]]]:
    """The outputs calculated in initialisation, each with the 0-based positions in
    `variables` of what it depends on (ModelStructure's InitialUnknowns)."""
    position = {v.name: i for i, v in enumerate(variables)}
    return [(v, [position[d] for d in v.depends_on]) for v in variables
            if v.causality == "output" and v.initial == "calculated"]


def decorate(root: Element, variables: Sequence[Variable]) -> None:
    """Add units, types and ranges to pythonfmu's <fmiModelDescription> element, in place,
    and the InitialUnknowns pythonfmu does not write."""
    by_name = {v.name: v for v in variables}
    index = [child.tag for child in root].index("CoSimulation") + 1
    blocks = [unit_definitions(variables), type_definitions(variables)]
    for block in (b for b in blocks if b is not None):
        root.insert(index, block)
        index += 1
    for sv in root.iter("ScalarVariable"):
        v = by_name[sv.get("name", "")]
        typed = sv[0]
        if v.type == "Enumeration":
            typed.tag = "Enumeration"
        # pythonfmu writes a start where FMI wants one, with 16 significant digits, which do
        # not round-trip every double: ours instead
        attrs = type_attributes(v, start=typed.get("start") is not None)
        typed.attrib.clear()
        typed.attrib.update(attrs)
    unknowns = initial_unknowns(variables)
    if unknowns:
        index = {sv.get("name"): i for i, sv in enumerate(root.iter("ScalarVariable"), 1)}
        structure = root.find("ModelStructure")
        assert structure is not None
        node = structure.find("InitialUnknowns")
        if node is None:
            node = SubElement(structure, "InitialUnknowns")
        for v, _ in unknowns:
            deps = " ".join(str(index[d]) for d in v.depends_on)
            SubElement(node, "Unknown", {"index": str(index[v.name]), "dependencies": deps})


def project_version() -> str:
    """The installed project's version (the FMU's version attribute)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("imu-fusion-fmu")
    except PackageNotFoundError:
        return "0+unknown"
