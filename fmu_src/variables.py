"""The declarative variable table every FMU of the project is built from.

One `Variable` per FMI scalar variable: name, causality, FMI type, description, start value, unit
and display unit (Real), allowed range, and for a choice the item names. `FmuSlave` turns the
table into pythonfmu registrations; `model_description` turns it into the units, ranges and types
that pythonfmu cannot write. Values are held in their FMI form (a choice as its item's value
1..n); `to_model` converts to the value a Python model works with.

A parameter that is a choice among names (gyro_sampling: point or mean) is an FMI Integer with
the range 1..n and the items named in its description ("Allowed: 1 = point, 2 = mean"), not an
FMI Enumeration: the co-simulation engines users run cannot set an Enumeration (libcosim drops
FMI 2.0 Enumeration variables, Ecos skips them), and every tool can set an Integer.
`items_in_description` reads the names back for a host that is given an item's name.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

Causality = Literal["parameter", "input", "output"]
FmiType = Literal["Real", "Integer", "Boolean", "Enumeration"]
Variability = Literal["fixed", "tunable", "discrete", "continuous"]


@dataclass(frozen=True)
class Variable:
    """One row of an FMU's variable table.

    unit is required for Real variables ("1" when dimensionless); display_unit is a friendlier
    unit for tools (deg for rad). low/high are the allowed range, open or closed; closed bounds
    become min/max in modelDescription.xml, and every bound is stated in the description.
    items are the names of the values 1..n of an Enumeration or of an Integer choice.
    """

    name: str
    causality: Causality
    type: FmiType
    description: str
    start: float | int | bool
    unit: str | None = None
    display_unit: str | None = None
    variability: Variability | None = None
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    items: tuple[str, ...] | None = None
    type_name: str | None = None
    initial: Literal["exact", "calculated"] = "exact"
    """An output's initial: exact (its start value is its value until the first step) or
    calculated (the FMU computes it in initialisation from depends_on; no start value is
    written, so a tool reads the value, not a start value that another parameter makes
    wrong)."""
    depends_on: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.type == "Real" and not self.unit:
            raise ValueError(f"Real variable {self.name!r} needs a unit ('1' if dimensionless)")
        if self.type != "Real" and (self.unit or self.display_unit):
            raise ValueError(f"only Real variables have units: {self.name!r} is {self.type}")
        if self.type == "Enumeration" and not (self.items and self.type_name):
            raise ValueError(f"Enumeration {self.name!r} needs items and a type_name")
        if not self.description:
            raise ValueError(f"variable {self.name!r} needs a description")
        if self.initial == "calculated" and self.causality != "output":
            raise ValueError(f"only outputs are calculated in initialisation: {self.name!r}")
        if self.variability is None:
            object.__setattr__(self, "variability", self._default_variability())

    def _default_variability(self) -> Variability:
        if self.causality == "parameter":
            return "tunable"
        return "continuous" if self.type == "Real" else "discrete"

    @property
    def tunable(self) -> bool:
        """Whether a running FMU accepts a new value (parameters only)."""
        return self.causality == "parameter" and self.variability == "tunable"

    def allowed(self) -> str:
        """The allowed values in words, for descriptions and error messages."""
        if self.items:
            return ", ".join(f"{i} = {name}" for i, name in enumerate(self.items, 1))
        if self.type == "Boolean":
            return "true or false"
        lo = "-inf" if self.low is None else repr(self.low)
        hi = "inf" if self.high is None else repr(self.high)
        left = "(" if self.low_open or self.low is None else "["
        right = ")" if self.high_open or self.high is None else "]"
        unit = "" if self.unit in (None, "1") else f" {self.unit}"
        return f"{left}{lo}, {hi}{right}{unit}"

    # ----- value conversion ---------------------------------------------------------------
    def check(self, value: float | int | bool) -> None:
        """Raise ValueError naming the variable and its allowed range if value is outside it
        (NaN always is; an infinite value only where that side is unbounded)."""
        if self.type not in ("Real", "Integer"):
            return
        v = float(value)
        ok = not math.isnan(v)
        if self.low is not None:
            ok = ok and (v > self.low if self.low_open else v >= self.low)
        if self.high is not None:
            ok = ok and (v < self.high if self.high_open else v <= self.high)
        if not ok:
            raise ValueError(
                f"parameter {self.name!r}={value!r} is out of range: allowed {self.allowed()}"
            )

    def to_model(self, value: Any) -> Any:
        """An FMI value in the form the Python model takes; ValueError for an unknown item."""
        if self.items:
            items = self.items
            known = isinstance(value, int) and not isinstance(value, bool)
            if not (known and 1 <= value <= len(items)):
                raise ValueError(
                    f"parameter {self.name!r}={value!r} is not allowed: expected {self.allowed()}"
                )
            return items[value - 1]
        return value

    def coerce(self, value: Any) -> float | int | bool:
        """The value a setter received, converted to this variable's FMI type."""
        if self.type == "Real":
            return float(value)
        if self.type == "Boolean":
            return bool(value)
        return int(value)


def real_input(
    name: str, unit: str, description: str, start: float = 0.0, display_unit: str | None = None
) -> Variable:
    """A continuous Real input."""
    return Variable(name, "input", "Real", description, float(start), unit, display_unit)


def real_output(
    name: str, unit: str, description: str, start: float = 0.0, display_unit: str | None = None,
    depends_on: tuple[str, ...] = (),
) -> Variable:
    """A continuous Real output: initial="exact" with a start value, or, depending on
    parameters (depends_on), initial="calculated" (start is then the value for the parameters'
    start values, held but not written)."""
    return Variable(name, "output", "Real", description, float(start), unit, display_unit,
                    initial="calculated" if depends_on else "exact", depends_on=depends_on)


def integer_output(name: str, description: str, start: int = 0) -> Variable:
    """A discrete Integer output with initial="exact" and a start value."""
    return Variable(name, "output", "Integer", description, int(start))


def parameter_variable(param: Any) -> Variable:
    """The FMU parameter for a fusion_core `Param` (duck-typed: name, default, description,
    unit, low/high, low_open/high_open, choices, display_unit, tunable).

    float -> Real with the Param's unit, int -> Integer, bool -> Boolean, str with choices ->
    Integer 1..n whose items are the choices in order (value 1 = the first; see the module
    docstring for why not an Enumeration). The start value is the Param's default; the
    variability is tunable or fixed as the Param says.
    """
    variability: Variability = "tunable" if param.tunable else "fixed"
    common: dict[str, Any] = {
        "variability": variability,
        "low": param.low,
        "high": param.high,
        "low_open": param.low_open,
        "high_open": param.high_open,
    }
    default = param.default
    if param.choices is not None:
        items = tuple(param.choices)
        var = Variable(
            param.name, "parameter", "Integer", param.description, items.index(default) + 1,
            variability=variability, low=1, high=len(items), items=items,
        )
    elif isinstance(default, bool):
        var = Variable(param.name, "parameter", "Boolean", param.description, default,
                       variability=variability)
    elif isinstance(default, int):
        var = Variable(param.name, "parameter", "Integer", param.description, default, **common)
    elif isinstance(default, float):
        var = Variable(
            param.name, "parameter", "Real", param.description, default, param.unit or "1",
            param.display_unit, **common,
        )
    else:
        raise TypeError(f"parameter {param.name!r} has an unsupported type {type(default)}")
    how = "tunable while running" if param.tunable else "fixed after initialisation"
    text = f"{param.description.rstrip('.')}. Allowed: {var.allowed()}; default {default!r}; {how}"
    return dataclasses.replace(var, description=text)


_ALLOWED_ITEMS = re.compile(r"Allowed: ((?:\d+ = [^,;]+(?:, )?)+);")


def items_in_description(description: str | None) -> tuple[str, ...] | None:
    """The item names of an Integer choice, values 1..n, from its description ("Allowed:
    1 = point, 2 = mean; ..."), or None where the description names none."""
    m = _ALLOWED_ITEMS.search(description or "")
    if m is None:
        return None
    pairs = [part.split(" = ", 1) for part in m.group(1).split(", ")]
    if [int(v) for v, _ in pairs] != list(range(1, len(pairs) + 1)):
        return None
    return tuple(name for _, name in pairs)


def item_value(variable: Any, name: str) -> int:
    """The value 1..n of a choice's item `name`, for a variable as fmpy reads it (an Integer
    choice, or an Enumeration of another FMU); ValueError naming the allowed items."""
    declared = getattr(variable, "declaredType", None)
    items = ([item.name for item in declared.items] if declared is not None and
             getattr(declared, "items", None) else list(
                 items_in_description(getattr(variable, "description", None)) or ()))
    if name not in items:
        raise ValueError(f"{variable.name} = {name!r}: allowed {items or 'a number'}")
    return items.index(name) + 1


_TABLES: dict[str, tuple[Variable, ...]] = {}


def variable_table(key: str, build: Callable[[], tuple[Variable, ...]]) -> tuple[Variable, ...]:
    """The variable table of the FMU model `key`, built by build() the first time only.

    pythonfmu re-executes a slave module's source for every instantiation, and the slave's
    globals are kept alive (slave.FmuSlave.__init_subclass__): a table built in the class body
    would be built, and kept, once per instance (about 20 kB each). This module is imported
    once, so the table is built once per process and every re-executed class shares it."""
    table = _TABLES.get(key)
    if table is None:
        table = _TABLES[key] = build()
    return table
