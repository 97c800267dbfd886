"""What a restored state may hold: one check per state field, for both twins.

An estimator declares its state as `STATE = {name: check}` (base.Estimator): the attributes that
the samples change, each with the check a restored value must pass. `Estimator.set_state` applies
the checks before it takes anything, and `python -m fusion_core.native.generate` writes the same
checks into the C twin's state layouts (fc_state_tables.c), which the native FMUs apply to a
deserialized state. So a state written by another process, another version or by hand is
either one the filter could have reached, or refused with the field named.

The checks are what the filters' arithmetic needs, not what a particular run reaches: every value
finite; angles in their ranges; quaternions and directions of unit norm; variances, times and mean
squares not negative; covariances symmetric with a non-negative diagonal; flags 0 or 1; counts
and indices integers in range. Magnitudes are bounded by STATE_BOUND, far beyond any physical
value of these filters, so that the product of two state values cannot overflow to infinity.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

STATE_BOUND: Final = 1e75
"""Largest magnitude of a restored real value: a product of four of them stays a finite double
(the filters multiply a few state values together; the UKF with a bias of 1e125 rad/s overflows),
and no quantity of these filters (rates in rad/s, specific forces in m/s^2, positions in m,
variances of any of them) comes near it."""
UNIT_TOLERANCE: Final = 1e-6
"""How far a unit vector's norm may be from 1. The filters renormalise every step, so a state
they wrote is within a few 1e-16 of 1; the tolerance admits states written with fewer digits."""
SYMMETRY_TOLERANCE: Final = 1e-9
"""How far a covariance's (i, j) and (j, i) may differ, relative to the larger of the two and the
geometric mean of the variances i and j: the filters compute the two by different formulas, which
round apart by an ulp or two."""
CORRELATION_TOLERANCE: Final = 1e-3
"""How far a covariance's correlation |P_ij| / sqrt(P_ii P_jj) may exceed 1 (Cauchy-Schwarz,
which every covariance obeys): the filters' own stay below 1 (the UKF's up to 0.99975 on BROAD,
every step of both presets); an off-diagonal entry far beyond its variances makes the matrix
indefinite, and the UKF's sigma points overflow."""
COUNT_MAX: Final = 2.0**53
"""Largest count a state may hold: every integer up to it is a double exactly (the C twin's
serialised state is doubles)."""

KINDS: Final = ("real", "nonneg", "angle", "half_angle", "flag", "count", "index", "unit", "cov",
                "cov_lower", "cov_upper", "nested")
"""The kinds of check, in the order of fc_state.h's fc_check."""


@dataclass(frozen=True)
class Check:
    """The check of one state field (or of a run of its elements, `Segments`).

    kind: real (finite, |x| <= STATE_BOUND), nonneg (and >= 0), angle (|x| <= pi), half_angle
    (|x| <= pi/2), flag (0 or 1), count (an integer in [0, high], high 0: COUNT_MAX), index (an
    integer in [0, high)), unit (a vector of norm 1 within UNIT_TOLERANCE), cov (a symmetric
    matrix, row by row, bounded, with a non-negative diagonal), cov_lower / cov_upper (its lower /
    upper triangle packed row by row; the C twin's form), nested (another estimator's state,
    checked by that estimator)."""

    kind: str
    high: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown state check {self.kind!r}: expected one of {KINDS}")


@dataclass(frozen=True)
class Segments:
    """Checks of consecutive runs of a vector's elements: ((check, length), ...)."""

    parts: tuple[tuple[Check, int], ...]

    @property
    def length(self) -> int:
        return sum(n for _, n in self.parts)


@dataclass(frozen=True)
class Queue:
    """A list of at most `most` entries, each `width` numbers that pass `entry`."""

    entry: Check | Segments
    width: int
    most: int


REAL: Final = Check("real")
NONNEG: Final = Check("nonneg")
ANGLE: Final = Check("angle")
HALF_ANGLE: Final = Check("half_angle")
FLAG: Final = Check("flag")
COUNT: Final = Check("count")
UNIT: Final = Check("unit")
COV: Final = Check("cov")
COV_LOWER: Final = Check("cov_lower")
COV_UPPER: Final = Check("cov_upper")
NESTED: Final = Check("nested")


def index(n: int) -> Check:
    """An index into a table of n entries: an integer in [0, n)."""
    return Check("index", float(n))


def count(most: int) -> Check:
    """A count of at most `most`."""
    return Check("count", float(most))


REST: Final = Segments(((REAL, 6), (NONNEG, 1), (FLAG, 1), (REAL, 9)))
"""The rest detector's state (building_blocks.RestState): the running means of the rate and of
the specific force, the quiet time [s], whether a rest has measured the bias, the mean specific
force and the mean rate where the quiet time had lasted REST_MEAN_TAU, and the rate's short
mean (ZERO_RATE_TAU)."""

BASE_STATE: Final[dict[str, Check | Segments | Queue]] = {
    "initialized": FLAG, "n_samples": COUNT, "n_rejected": COUNT, "gyro_prev": REAL,
}
"""The state every estimator has (base.Estimator), the C twin's fc_base."""

FieldCheck = Check | Segments | Queue
StateSpec = dict[str, FieldCheck]


def _numbers(name: str, value: Any) -> list[float]:
    """The numbers of a state value, flattened (bools as 0/1); ValueError for anything else."""
    if isinstance(value, bool):
        return [float(value)]
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, (list, tuple)):
        out: list[float] = []
        for v in value:
            out.extend(_numbers(name, v))
        return out
    raise ValueError(f"state field {name!r} holds {type(value).__name__} {value!r}: expected "
                     "numbers")


def _same_shape(value: Any, template: Any) -> bool:
    """Whether value nests like template: a list of as many elements, each like the template's,
    where the template has a list; a number where it has a number."""
    if isinstance(template, (list, tuple)):
        return (isinstance(value, (list, tuple)) and len(value) == len(template)
                and all(_same_shape(v, t) for v, t in zip(value, template, strict=True)))
    return isinstance(value, (bool, int, float))


def _shape(value: Any) -> str:
    """A value's nesting shape, for messages: 3x3, 4, scalar."""
    if isinstance(value, (list, tuple)):
        inner = _shape(value[0]) if value else "scalar"
        return str(len(value)) + ("" if inner == "scalar" else "x" + inner)
    return "scalar"


def check_values(name: str, check: Check | Segments, xs: Sequence[float]) -> None:
    """ValueError naming the field and what is allowed, unless the flat values xs pass."""
    if isinstance(check, Segments):
        if len(xs) != check.length:
            raise ValueError(f"state field {name!r} has {len(xs)} values, not {check.length}")
        start = 0
        for part, n in check.parts:
            check_values(f"{name}[{start}:{start + n}]", part, xs[start:start + n])
            start += n
        return
    kind = check.kind
    for i, x in enumerate(xs):
        where = name if len(xs) == 1 else f"{name}[{i}]"
        if not math.isfinite(x):
            raise ValueError(f"state field {where} = {x!r} is not finite")
        if abs(x) > STATE_BOUND:
            raise ValueError(f"state field {where} = {x!r} is beyond +-{STATE_BOUND:g}")
        bad = {
            "nonneg": lambda v: v < 0.0,
            "angle": lambda v: abs(v) > math.pi,
            "half_angle": lambda v: abs(v) > 0.5 * math.pi,
            "flag": lambda v: v not in (0.0, 1.0),
            "count": lambda v: v < 0.0 or v != math.floor(v)
            or v > (check.high or COUNT_MAX),
            "index": lambda v: v < 0.0 or v != math.floor(v) or v >= check.high,
        }.get(kind)
        if bad is not None and bad(x):
            raise ValueError(f"state field {where} = {x!r} is not allowed: {describe(check)}")
    if kind == "unit":
        norm = math.sqrt(sum(x * x for x in xs))
        if not abs(norm - 1.0) <= UNIT_TOLERANCE:
            raise ValueError(f"state field {name} has norm {norm!r}: a unit vector is required "
                             f"(within {UNIT_TOLERANCE:g})")
    if kind in ("cov", "cov_lower", "cov_upper"):
        n = matrix_size(kind, len(xs))
        at = lambda i, j: element_index(kind, n, i, j)  # noqa: E731
        for i in range(n):
            if xs[at(i, i)] < 0.0:
                raise ValueError(f"state field {name} has a negative variance {xs[at(i, i)]!r} "
                                 "on its diagonal")
        for i in range(n):
            for j in range(i):
                a, b = xs[at(i, j)], xs[at(j, i)]
                root = math.sqrt(xs[at(i, i)] * xs[at(j, j)])
                if abs(a - b) > SYMMETRY_TOLERANCE * max(abs(a), abs(b), root):
                    raise ValueError(f"state field {name} is not symmetric ({a!r} against "
                                     f"{b!r})")
                if abs(a) > (1.0 + CORRELATION_TOLERANCE) * root:
                    raise ValueError(f"state field {name} is no covariance: its ({i}, {j}) "
                                     f"entry {a!r} exceeds sqrt of the variances' product "
                                     f"{root!r}")


def matrix_size(kind: str, length: int) -> int:
    """The size n of a covariance stored in `length` values of a cov kind."""
    n = math.isqrt(length) if kind == "cov" else (math.isqrt(8 * length + 1) - 1) // 2
    if (n * n if kind == "cov" else n * (n + 1) // 2) != length:
        raise ValueError(f"{length} values are no covariance of kind {kind!r}")
    return n


def element_index(kind: str, n: int, i: int, j: int) -> int:
    """Where entry (i, j) of an n x n covariance is stored: row by row for cov; cov_lower holds
    row r as (r, 0..r), cov_upper as (r, r..n-1), so (i, j) and (j, i) are the same value."""
    if kind == "cov":
        return i * n + j
    if kind == "cov_lower":
        r, c = max(i, j), min(i, j)
        return r * (r + 1) // 2 + c
    r, c = min(i, j), max(i, j)
    return r * n - r * (r - 1) // 2 + (c - r)


def describe(check: Check) -> str:
    """What a check allows, for error messages."""
    return {
        "real": f"finite, within +-{STATE_BOUND:g}",
        "nonneg": f"finite, 0 to {STATE_BOUND:g}",
        "angle": "an angle in [-pi, pi]",
        "half_angle": "an angle in [-pi/2, pi/2]",
        "flag": "0 or 1",
        "count": f"an integer from 0 to {check.high or COUNT_MAX:g}",
        "index": f"an integer from 0 to {check.high - 1:g}",
        "unit": "a unit vector",
        "cov": "a symmetric matrix with a non-negative diagonal",
        "cov_lower": "a covariance's lower triangle with a non-negative diagonal",
        "cov_upper": "a covariance's upper triangle with a non-negative diagonal",
        "nested": "another estimator's state",
    }[check.kind]


def check_field(name: str, check: FieldCheck, value: Any, template: Any) -> None:
    """ValueError unless `value` has the shape of `template` (the field's value in a new
    estimator) and passes `check`."""
    if isinstance(check, Queue):
        if not isinstance(value, (list, tuple)) or len(value) > check.most:
            raise ValueError(f"state field {name!r} must be a list of at most {check.most} "
                             "entries")
        for i, entry in enumerate(value):
            if not isinstance(entry, (list, tuple)) or len(entry) != check.width:
                raise ValueError(f"state field {name}[{i}] must be {check.width} numbers")
            check_values(f"{name}[{i}]", check.entry, _numbers(name, entry))
        return
    if isinstance(check, Check) and check.kind == "nested":
        if not isinstance(value, dict):
            raise ValueError(f"state field {name!r} must be an estimator state (a dict), not "
                             f"{type(value).__name__}")
        return
    xs = _numbers(name, value)
    if not _same_shape(value, template):
        raise ValueError(f"state field {name!r} has shape {_shape(value)}, not "
                         f"{_shape(template)}")
    check_values(name, check, xs)
