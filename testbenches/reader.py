"""Reading a recording's table as a logger or a spreadsheet wrote it.

`read_table` reads a delimited text file: the encoding (UTF-8 with or without a byte-order mark,
else Latin-1), the delimiter (comma, semicolon, tab or bar; a decimal comma with semicolons) and
the header row are found from the file; a unit stated in a column's name ("Gyroscope X (deg/s)",
"acc_x [m/s^2]") is read off it. Values become floats; an empty cell, NaN or inf is kept as
not-a-number (the estimators reject such a sample and count it, so one bad row does not refuse
a file); text where a number belongs is refused naming the file's line, the column and the
value. Line numbers are the file's, counting the header as line 1.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DELIMITERS = ",;\t|"

UNIT_ALIASES: dict[str, str] = {
    "rad/s": "rad/s", "rads": "rad/s", "rad/sec": "rad/s", "rps": "rad/s",
    "deg/s": "deg/s", "°/s": "deg/s", "dps": "deg/s", "deg/sec": "deg/s", "degs": "deg/s",
    "g": "g", "gee": "g",
    "m/s2": "m/s2", "m/s^2": "m/s2", "m/s²": "m/s2", "ms^-2": "m/s2", "ms-2": "m/s2",
    "m.s-2": "m/s2", "mps2": "m/s2",
    "s": "s", "sec": "s", "seconds": "s", "ms": "ms", "us": "us", "µs": "us", "ns": "ns",
    "rad": "rad", "deg": "deg", "°": "deg", "1": "1",
}
"""Units a header may state, by their spellings (lower case, spaces removed)."""
TIME_SCALE = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}

_NAME_UNIT = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")


class TableError(ValueError):
    """A file that cannot be read as a table: where, what, and what would serve."""


@dataclass
class Table:
    """A recording's table: the header as written, each column's name without its unit and
    the unit it states (None where it states none), the values [rows, columns] (NaN where a
    cell held none) and each row's line in the file."""

    path: Path
    header: list[str]
    names: list[str]
    units: list[str | None]
    data: np.ndarray
    lines: np.ndarray
    delimiter: str

    def column(self, index: int) -> np.ndarray:
        return self.data[:, index]


def split_unit(name: str) -> tuple[str, str | None]:
    """A header cell as (name, unit): "Gyroscope X (deg/s)" -> ("Gyroscope X", "deg/s"); a
    bracketed part that is no unit known here stays in the name."""
    m = _NAME_UNIT.match(name.strip())
    if m:
        unit = UNIT_ALIASES.get(m.group(2).replace(" ", "").lower())
        if unit is not None:
            return m.group(1).strip(), unit
    return name.strip(), None


def _decode(path: Path) -> str:
    raw = path.read_bytes()
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _delimiter(text: str, path: Path) -> str:
    """The delimiter that splits the header and the first rows into the same number (> 1) of
    cells."""
    lines = [line for line in text.splitlines()[:20] if line.strip()]
    if not lines:
        raise TableError(f"{path}: empty file")
    best, best_cells = None, 1
    for d in DELIMITERS:
        counts = [len(next(csv.reader([line], delimiter=d))) for line in lines]
        if len(set(counts)) == 1 and counts[0] > best_cells:
            best, best_cells = d, counts[0]
    if best is None:
        raise TableError(f"{path}: no delimiter splits the header and the first rows alike "
                         f"(tried comma, semicolon, tab and bar); line 1 reads {lines[0][:80]!r}")
    return best


def read_table(path: str | Path) -> Table:
    """The table of a delimited text file (the module docstring); TableError saying where and
    what is wrong."""
    path = Path(path)
    if not path.is_file():
        raise TableError(f"{path}: no such file")
    text = _decode(path)
    delimiter = _delimiter(text, path)
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    header: list[str] | None = None
    rows: list[list[str]] = []
    lines: list[int] = []
    for line_no, row in enumerate(reader, 1):
        if not row or not any(c.strip() for c in row):
            continue
        if header is None:
            header = [c.strip() for c in row]
            continue
        if len(row) != len(header):
            raise TableError(f"{path}, line {line_no}: {len(row)} values where the header has "
                             f"{len(header)} columns")
        rows.append(row)
        lines.append(reader.line_num)
    if header is None:
        raise TableError(f"{path}: empty file")
    if not rows:
        raise TableError(f"{path}: a header and no samples")
    decimal_comma = delimiter == ";" and _decimal_comma(rows)
    if decimal_comma:
        rows = [[c.replace(",", ".") for c in row] for row in rows]
    try:  # numpy's own conversion where every cell is a number
        data = np.array(rows, dtype=float)
    except ValueError:  # cell by cell: empty cells as NaN, text refused by line and column
        data = np.empty((len(rows), len(header)))
        for i, row in enumerate(rows):
            for j, cell in enumerate(row):
                data[i, j] = _number(cell, path, lines[i], header[j])
    names, units = zip(*(split_unit(h) for h in header), strict=True)
    return Table(path, header, list(names), list(units), data, np.asarray(lines), delimiter)


def _decimal_comma(rows: list[list[str]]) -> bool:
    sample = [c for row in rows[:50] for c in row if c.strip()]
    return any("," in c for c in sample) and not any("." in c for c in sample)


def _number(cell: str, path: Path, line: int, column: str) -> float:
    text = cell.strip()
    if not text:
        return float("nan")  # a missing value: that sample is rejected and counted
    try:
        return float(text)
    except ValueError:
        raise TableError(f"{path}, line {line}, column {column!r}: {cell.strip()[:40]!r} is not "
                         "a number (a number serves; an empty cell or NaN marks a missing "
                         "value, whose sample is rejected and counted)") from None
