"""A recording's table as every reader gives it (testbenches.reader for text, Parquet and Arrow
files, testbenches.array_files for HDF5 and MATLAB files, testbenches.bags for ROS bags): named
columns read in blocks of rows (TableSource), the error that says why a file is no table
(TableError), and the units a column's name or a file's metadata states."""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

BLOCK_ROWS = 1 << 18
"""Rows per block: a few MB per column, few enough Python round trips per million rows."""

UNIT_ALIASES: dict[str, str] = {
    "rad/s": "rad/s", "rads": "rad/s", "rad/sec": "rad/s", "rps": "rad/s", "rads^-1": "rad/s",
    "rads-1": "rad/s", "rad.s-1": "rad/s",
    "deg/s": "deg/s", "°/s": "deg/s", "dps": "deg/s", "deg/sec": "deg/s", "degs": "deg/s",
    "degs^-1": "deg/s", "degs-1": "deg/s", "deg.s-1": "deg/s",
    "mdps": "mdps", "mdeg/s": "mdps", "m°/s": "mdps",
    "g": "g", "gee": "g", "mg": "mg", "milli-g": "mg",
    "m/s2": "m/s2", "m/s^2": "m/s2", "m/s²": "m/s2", "ms^-2": "m/s2", "ms-2": "m/s2",
    "m.s-2": "m/s2", "mps2": "m/s2",
    "s": "s", "sec": "s", "seconds": "s", "ms": "ms", "us": "us", "µs": "us", "ns": "ns",
    **{f"{since}{sep}{unit}": unit for since in ("epoch", "unix") for sep in ("_", "-", "")
       for unit in ("s", "ms", "us", "ns")},
    "m/(s^2)": "m/s2", "m/(s2)": "m/s2",
    "rad": "rad", "deg": "deg", "°": "deg", "1": "1",
}
"""Units a header may state, by their spellings (lower case, spaces removed)."""
OTHER_UNITS = frozenset({"mv", "v", "kpa", "pa", "hpa", "degreescelsius", "°c", "degc",
                         "local_flux*", "ut", "µt", "gauss", "ga", "nounits", "%"})
"""Units of a logger's other sensors (Shimmer's ECG in mV, its pressure in kPa, its temperature
in degrees Celsius, its magnetometer in local_flux*, a counter's "no units"), spelled as
UNIT_ALIASES' are: they make a row of units a row of units, and state nothing here."""
TIME_SCALE = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
"""The units of a time or dt column and their factor to seconds."""
DATETIME = "datetime"
"""The unit of a column of dates and times (ISO 8601 text, a Parquet timestamp), which the
reader gives as seconds since 1970."""
TIME_OF_DAY = "time of day"
"""The unit of a column of times of day without a date ("12:00:00.010", as a logger with a
real-time clock or a spreadsheet's time format writes them), which the reader gives as seconds
since midnight."""
DURATION = "duration"
"""The unit of a column of durations written with their unit ("0.01 sec", as MATLAB's
writetimetable writes a timetable's row times), which the reader gives as seconds."""

_NAME_UNIT = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")
_INDEX = re.compile(r"\w\[\d\]$")
"""An index written onto a name, PX4's "gyro_rad[1]": an axis, not the unit "1" ("q_w [1]")."""


class TableError(ValueError):
    """A file that cannot be read as a table: where, what, and what would serve."""


def unit_named(text: str) -> str | None:
    """The unit a text names (UNIT_ALIASES: "deg/s", "Deg / s", "m/s^2"), None for none."""
    return UNIT_ALIASES.get(text.replace(" ", "").lower())


def bracketed(name: str) -> tuple[str, str] | None:
    """A header cell's name and the text in brackets that ends it ("Gyroscope X (deg/s)" ->
    ("Gyroscope X", "deg/s")), whatever the text; None where none ends it or it is an index
    written onto the name (PX4's "gyro_rad[1]")."""
    m = _NAME_UNIT.match(name.strip())
    if m is None or _INDEX.search(name.strip()):
        return None
    return m.group(1).strip(), m.group(2)


def split_unit(name: str) -> tuple[str, str | None]:
    """A header cell as (name, unit): "Gyroscope X (deg/s)" -> ("Gyroscope X", "deg/s"), "q_w []"
    -> ("q_w", None); a bracketed part that is no unit known here stays in the name."""
    found = bracketed(name)
    if found is not None:
        if not found[1]:  # EuRoC's "q_RS_w []": no unit
            return found[0], None
        unit = unit_named(found[1])
        if unit is not None:
            return found[0], unit
    return name.strip(), None


def unit_of(name: str, stated: Any) -> tuple[str, str | None]:
    """(name, unit) of a column whose metadata may state its unit (bytes or text)."""
    bare, unit = split_unit(name)
    if unit is None and stated is not None:
        unit = unit_named(stated.decode() if isinstance(stated, bytes) else str(stated))
    return bare, unit


@dataclass
class TableSource:
    """A file's table opened for reading in blocks: the header as written, each column's name
    without its unit and the unit it states (None where it states none), the number of rows
    where the format says it (None for text), file-level numbers (`rate`) and the format."""

    path: Path
    header: list[str]
    names: list[str]
    units: list[str | None]
    kind: str
    rows: int | None
    _read: Callable[[list[int], int], Iterator[np.ndarray]]
    _where: Callable[[int], str]
    attrs: dict[str, float] = field(default_factory=dict)

    note: str = ""
    """What the reader did that a user should know (lines before the header skipped)."""

    found: list[str] = field(default_factory=list)
    """What reading the rows found left out, which opening could not see (a compressed stream
    cut short), as reads find it."""

    platform: str = ""
    """The platform a phone app's export says it was recorded on ("iOS", "Android"; "" where it
    says none)."""

    owner: Any = field(default=None, repr=False, compare=False)
    """What must live as long as the table (the unpacked files of a zip archive)."""

    _kept: Any = field(default=None, repr=False, compare=False)
    """(columns, rows, first block, the read after it) of first_block, for blocks to go on."""

    def blocks(self, columns: list[int], rows: int = BLOCK_ROWS) -> Iterator[np.ndarray]:
        """The chosen columns as float64 [n, len(columns)], `rows` rows at a time (the last
        block shorter), from the first row; TableError where a row cannot be read. The first
        call after first_block with its columns and rows goes on with that read."""
        kept = self._kept
        if kept is not None and kept[0] == list(columns) and kept[1] == rows:
            self._kept = None
            return itertools.chain([kept[2]], kept[3])
        return self._read(columns, rows)

    def first_block(self, columns: list[int], rows: int = BLOCK_ROWS) -> np.ndarray | None:
        """blocks(columns, rows)'s first block (None for an empty table), its read kept open so
        that the recording's read that follows does not parse those rows again."""
        read = self._read(columns, rows)
        first = next(read, None)
        self._kept = None if first is None else (list(columns), rows, first, read)
        return first

    def read(self, columns: list[int]) -> np.ndarray:
        """Every row of the chosen columns [N, len(columns)]."""
        parts = list(self.blocks(columns))
        return np.concatenate(parts) if parts else np.empty((0, len(columns)))

    def where(self, row: int) -> str:
        """Where the row (counting from 0) is in the file, as its reader counts: "line 201"."""
        return self._where(row)


def ticks_seconds(ticks: np.ndarray, per_second: int) -> np.ndarray:
    """Integer ticks since an epoch (`per_second` a second: a timestamp's nanoseconds) as
    seconds, the smallest integer (pandas' NaT) NaN: the whole seconds and their fraction
    added, one rounding, as the text reader adds a date's (ticks / per_second rounds the same
    way, but the ticks times 1 / per_second twice)."""
    ticks = np.asarray(ticks, dtype=np.int64)
    seconds = (ticks // per_second).astype(float) + (ticks % per_second) / per_second
    seconds[ticks == np.iinfo(np.int64).min] = np.nan
    return seconds


__all__ = [
    "BLOCK_ROWS",
    "DATETIME",
    "DURATION",
    "OTHER_UNITS",
    "TIME_OF_DAY",
    "TIME_SCALE",
    "UNIT_ALIASES",
    "TableError",
    "TableSource",
    "bracketed",
    "split_unit",
    "ticks_seconds",
    "unit_named",
    "unit_of",
]
