"""Reading a recording held as named arrays: HDF5 (as h5py, pandas' HDFStore and MATLAB v7.3
write it) and MATLAB's .mat files (v4 to v7, read with scipy; v7.3 is HDF5).

Every numeric array whose samples run along its longest axis is one column or several:

- a vector of N samples is one column, also stored as an [N, 1] or [1, N] matrix (MATLAB keeps
  every vector as a matrix, and v7.3 stores each matrix transposed);
- an [N, k] matrix (or [k, N]) is k columns, named by the names stored with it (pandas' items,
  a `columns`, `names` or `labels` attribute of k names), else "acc_x", "acc_y", "acc_z" for
  three columns and "data_1" ... "data_k" for any other number, as MATLAB's writetable names
  a matrix's columns; --column maps those;
- a compound dataset (numpy's structured array, pandas' table format) is a column per field;
- a column of dates and times (pandas' datetime64) is seconds since 1970, as the text
  reader's.

Arrays in groups (HDF5) and in structs (MATLAB, also in a struct array's elements; a struct
array of a sample an element, log(i).acc, v5 or v7.3, as a struct of arrays) are found at any
depth, each named by its own name, or by its path ("imu0/acc_x") where another column has that
name. N is the length of the arrays that hold what is read (a recording's IMU, a reference's
pose: WANTED), else the length the most arrays share, the longest of those that tie; arrays of
other lengths are left out, and said. So one file may hold an IMU and a motion capture at their
own rates, read as the recording and as its reference.
Text, cell arrays, references, empty arrays and the groups MATLAB and pandas keep for
themselves (#refs#, #subsystem#, an index's _i_table) hold no samples. A MATLAB table,
timetable or other class object is stored so that only MATLAB reads it: where it is all a file
holds, it is refused saying how to save its columns as arrays.

A unit is read from a dataset's `unit` or `units` attribute (one for all its columns, or one
per column); the sample rate from a scalar `rate`, `fs`, `sample_rate` or `sampling_rate`,
among the root's attributes or the arrays.
"""

from __future__ import annotations

import io
import pickle
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .fit.columns import ALIASES, find_names, norm_name
from .table import DATETIME, TableError, TableSource, ticks_seconds, unit_of

RATE_NAMES = ("rate", "fs", "sample_rate", "sampling_rate")
"""Names of a scalar that states the sample rate [Hz]."""
NAME_ATTRIBUTES = ("columns", "names", "labels", "column_names")
"""Attributes of a matrix that may name its columns."""
HIDDEN = ("#refs#", "#subsystem#", "_i_table")
"""Groups that hold no samples: MATLAB v7.3's referenced data and class objects, pandas'
table index."""
MATLAB_NUMBERS = frozenset({"double", "single", "int8", "uint8", "int16", "uint16", "int32",
                            "uint32", "int64", "uint64"})
"""MATLAB classes of arrays of numbers (not MATLAB_NO_SAMPLES' or a class object)."""
MATLAB_NO_SAMPLES = ("char", "logical", "cell")
"""MATLAB classes of arrays that hold no samples: text, truth values, cells (references)."""
STRUCT_ARRAY = "struct array"
"""What a MATLAB v7.3 struct array not read as samples (_struct_array) is called in a refusal:
its elements are references this reader follows only where each holds a sample."""
MATLAB_HINT = {
    "table": "writetable({var}, 'FILE.csv') saves it as CSV, or s = table2struct({var}, "
             "'ToScalar', true); save('FILE.mat', '-struct', 's') as arrays",
    "timetable": "writetimetable({var}, 'FILE.csv') saves it as CSV (its row times as "
                 "durations or dates, which this reader takes)",
    STRUCT_ARRAY: "save('FILE.mat', '{var}', '-v7') keeps its elements where this reader "
                  "reads them (or save each field's samples as one array)",
}
"""How to save a MATLAB class object's columns as arrays, per class; any other class is asked
for as arrays of numbers."""
_SHOWN = 6
"""At most this many names in a message that lists arrays."""
WANTED = {"imu": ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"),
          "pose": ("roll", "pitch", "q_w", "q_x", "q_y", "q_z")}
"""What a recording's table (open_table's want "imu") and a reference's ("pose") hold, by
which the length of the arrays taken is chosen where arrays of several lengths are stored
(an IMU's and a motion capture's in one file)."""


@dataclass
class _Array:
    """One array of samples: where it is (its path of groups and its name), how to read a
    stretch of it, its shape, the names of its columns where stored, their units."""

    path: tuple[str, ...]
    shape: tuple[int, ...]
    read: Callable[[int, int], np.ndarray]
    """read(lo, hi): the samples lo..hi, [rows] or [rows, k] (a matrix stored [k, N] turned)."""
    names: list[str] | None = None
    units: list[Any] | None = None
    seconds_per_tick: int = 0
    """Ticks per second of a column of dates and times stored as integers (pandas'
    datetime64[ns]: 10**9), 0 for numbers."""


@dataclass
class _Found:
    arrays: list[_Array]
    objects: list[tuple[str, str]]
    """(path, class) of each MATLAB class object, which only MATLAB reads."""
    scalars: dict[str, Any]


def _text(value: Any) -> str:
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


class _NoGlobals(pickle.Unpickler):
    """pandas stores a table's column names pickled (protocol 0): read as lists and strings
    alone, so that a file's bytes cannot name code to run."""

    def find_class(self, module: str, name: str) -> Any:
        raise pickle.UnpicklingError(f"{module}.{name} is no list of names")


def _unpickled(value: Any) -> Any:
    try:
        return _NoGlobals(io.BytesIO(bytes(value))).load()
    except Exception:  # whatever a damaged or foreign pickle raises: no names
        return None


def _names(value: Any, k: int) -> list[str] | None:
    """k column names from an attribute or dataset (bytes, strings, or pandas' pickle)."""
    if value is None:
        return None
    if isinstance(value, bytes | np.bytes_) and value[:1] == b"(":
        value = _unpickled(value)
    try:
        names = [_text(v) for v in np.asarray(value, dtype=object).reshape(-1)]
    except (TypeError, ValueError):
        return None
    return names if len(names) == k and all(names) else None


def _units(value: Any, k: int) -> list[Any] | None:
    if value is None:
        return None
    flat = list(np.asarray(value, dtype=object).reshape(-1))
    return flat * k if len(flat) == 1 else flat if len(flat) == k else None


def _attr(attrs: Any, name: str) -> Any:
    value = attrs.get(name)
    return None if value is None else _text(value) if isinstance(value, bytes | np.bytes_) \
        else value


# ----- HDF5 ---------------------------------------------------------------------------------

def _dataset(path: tuple[str, ...], ds: Any, names: list[str] | None = None,
             units: Any = None, ticks: int = 0) -> _Array:
    if ds.ndim == 1 or ds.shape[0] >= ds.shape[1]:
        def read(lo: int, hi: int) -> np.ndarray:
            return np.asarray(ds[lo:hi])
    else:
        def read(lo: int, hi: int) -> np.ndarray:
            return np.asarray(ds[:, lo:hi]).T

    return _Array(path, tuple(ds.shape), read, names, units, ticks)


def _in_memory(path: tuple[str, ...], a: np.ndarray) -> _Array:
    rows = a if a.ndim == 1 or a.shape[0] >= a.shape[1] else a.T
    return _Array(path, a.shape, lambda lo, hi: rows[lo:hi])


def _field(path: tuple[str, ...], ds: Any, name: str, names: list[str] | None,
           ticks: int = 0, leaf: str | None = None) -> _Array:
    """A compound dataset's field: a column, or k columns where it holds k numbers a row;
    named `leaf` where given (pandas' data column by its own name), else as the field."""
    sub = ds.dtype.fields[name][0].shape
    shape = (ds.shape[0], *sub)

    def read(lo: int, hi: int) -> np.ndarray:
        return np.asarray(ds.fields(name)[lo:hi])

    return _Array((*path, leaf or name), shape, read, names, None, ticks)


def _ticks(dtype_text: Any) -> int:
    """Ticks per second of pandas' datetime64[unit] (stored as int64), 0 for any other type."""
    text = _text(dtype_text or "")
    for unit, per in (("[ns]", 10**9), ("[us]", 10**6), ("[ms]", 10**3), ("[s]", 1)):
        if text.startswith("datetime64") and text.endswith(unit):
            return per
    return 10**9 if text == "datetime64" else 0


def _pandas_fixed(group: Any, path: tuple[str, ...]) -> list[_Array]:
    """pandas' HDFStore fixed format ("frame"): blocks of columns named by their items, and the
    index (axis1), named by its name or "index"."""
    found = []
    index = group.get("axis1")
    if index is not None and index.dtype.kind in "iuf":
        name = _attr(index.attrs, "name")
        kind = _attr(index.attrs, "kind") or ""
        found.append(_dataset((*path, "index" if name in (None, "N.") else name), index,
                              ticks=_ticks(kind)))
    for i in range(int(group.attrs.get("nblocks", 0))):
        values, items = group.get(f"block{i}_values"), group.get(f"block{i}_items")
        if values is None or items is None or values.ndim != 2 or values.dtype.kind not in "iuf":
            continue
        names = _names(items[()], values.shape[1])
        ticks = _ticks(_attr(values.attrs, "value_type"))
        found.append(_dataset((*path, f"block{i}"), values, names, ticks=ticks))
    return found


def _pandas_table(group: Any, path: tuple[str, ...]) -> list[_Array]:
    """pandas' HDFStore table format ("frame_table"): the `table` dataset's fields, each block
    named by the pickled names beside it, the index by the name pandas keeps in `info`."""
    table = group.get("table")
    if table is None or table.dtype.names is None:
        return []
    info = _unpickled(group.attrs.get("info", b"")) or {}
    index_name = (info.get("index") or {}).get("index_name") if isinstance(info, dict) else None
    found = []
    for name in table.dtype.names:
        base, sub = table.dtype.fields[name][0].base, table.dtype.fields[name][0].shape
        if base.kind not in "iuf":
            continue
        k = sub[0] if sub else 1
        names = _names(table.attrs.get(f"{name}_kind"), k)
        ticks = _ticks(_attr(table.attrs, f"{name}_dtype"))
        if name == "index":
            names = [index_name if isinstance(index_name, str) else "index"]
            ticks = _ticks(_attr(table.attrs, "index_kind"))
        leaf = None if sub or not names else names[0]  # a data column, the index: its name
        found.append(_field(path, table, name, names if sub else None, ticks, leaf))
    return found


def _hdf5_found(f: Any) -> _Found:
    import h5py

    arrays: list[_Array] = []
    objects: list[tuple[str, str]] = []
    scalars: dict[str, Any] = {k: v for k, v in f.attrs.items()}

    def visit(group: Any, path: tuple[str, ...]) -> None:
        pandas = _attr(group.attrs, "pandas_type")
        if pandas == "frame":
            arrays.extend(_pandas_fixed(group, path))
            return
        if pandas == "frame_table":
            arrays.extend(_pandas_table(group, path))
            return
        for name, item in group.items():
            if name in HIDDEN or item is None:  # None: a link to nothing
                continue
            where = (*path, name)
            matlab = _attr(item.attrs, "MATLAB_class")
            if isinstance(item, h5py.Group):
                samples = _struct_array(item) if matlab == "struct" else None
                if matlab not in (None, "struct"):
                    objects.append(("/".join(where), matlab))
                elif samples is not None:  # a sample an element (log(i).acc = ...)
                    arrays.extend(_in_memory((*where, k), a) for k, a in samples.items())
                elif matlab == "struct" and _references(item):
                    objects.append(("/".join(where), STRUCT_ARRAY))
                else:
                    visit(item, where)
                continue
            if not isinstance(item, h5py.Dataset) or item.shape is None:
                continue
            if ("MATLAB_object_decode" in item.attrs
                    or matlab not in (None, *MATLAB_NUMBERS, *MATLAB_NO_SAMPLES)):
                objects.append(("/".join(where), matlab or "object"))
                continue
            if matlab in MATLAB_NO_SAMPLES or "MATLAB_empty" in item.attrs:
                continue
            if item.dtype.names:
                for field in item.dtype.names:
                    if item.dtype.fields[field][0].base.kind in "iuf":
                        arrays.append(_field(where, item, field, None))
                continue
            if item.dtype.kind not in "iuf":
                continue
            if item.size == 1:
                scalars.setdefault(name, item[()])
                continue
            k = min(item.shape) if item.ndim == 2 else 1
            names = next((n for a in NAME_ATTRIBUTES
                          if (n := _names(item.attrs.get(a), k)) is not None), None)
            units = item.attrs.get("unit", item.attrs.get("units"))
            arrays.append(_dataset(where, item, names, _units(units, k)))

    visit(f, ())
    return _Found(arrays, objects, scalars)


def _references(group: Any) -> bool:
    """Whether every field of a MATLAB struct (an HDF5 group) is a dataset of two or more
    references: a v7.3 struct array's elements."""
    import h5py

    fields = list(group.values())
    return bool(fields) and all(isinstance(ds, h5py.Dataset) and ds.size >= 2
                                and h5py.check_dtype(ref=ds.dtype) is h5py.Reference
                                for ds in fields)


def _struct_array(group: Any) -> dict[str, np.ndarray] | None:
    """A MATLAB v7.3 struct array of a sample an element as a struct of arrays, as
    _struct_samples makes a v5 one: MATLAB stores a struct array as a group whose every field
    is a dataset of references, an element each (a scalar struct's fields are the arrays
    themselves). None for any other group, or where an element's field is longer than a sample
    or of another shape than the first element's. A field's class is its first element's (a
    field of text is left out); each element is read by HDF5's own calls, a few times faster
    than h5py's objects, which matters at a reference a number (a struct of arrays, or -v7,
    still reads far faster: at once)."""
    import h5py

    fields = dict(group.items())
    if not _references(group) or any(ds.size != next(iter(fields.values())).size
                                     for ds in fields.values()):
        return None
    refs = {name: np.asarray(ds[()]).reshape(-1) for name, ds in fields.items()}
    out = {}
    for name, r in refs.items():
        first = group.file[r[0]]
        if not (isinstance(first, h5py.Dataset) and "MATLAB_empty" not in first.attrs
                and _attr(first.attrs, "MATLAB_class") in MATLAB_NUMBERS):
            continue  # text, a struct: no sample
        shape = first.shape
        if first.size > SAMPLE_WIDTH:
            return None  # a trial an element, not a sample
        values = np.empty((len(r), *shape))
        for i, ref in enumerate(r):
            element = h5py.h5r.dereference(ref, group.file.id)
            if not isinstance(element, h5py.h5d.DatasetID) or element.shape != shape:
                return None  # (read into a buffer of another shape, HDF5 writes past it)
            element.read(h5py.h5s.ALL, h5py.h5s.ALL, values[i])
        out[name] = values.reshape(len(r), -1) if first.size > 1 else values.reshape(-1)
    return out or None


def hdf5_table(path: Path, want: str = "imu") -> TableSource:
    import h5py

    try:
        f = h5py.File(path, "r")
        found = _hdf5_found(f)
    except (OSError, KeyError, ValueError, RuntimeError) as err:  # h5py's, of a damaged file
        raise TableError(f"{path}: not a readable HDF5 file ({err})") from None
    return _table(path, "hdf5", found, owner=f, want=want)


# ----- MATLAB v4 to v7 ------------------------------------------------------------------------

def _opaque_class(value: Any) -> str:
    """The class a scipy MatlabOpaque names: its field `_Class` (scipy 1.18 on), else `s2`
    (the fields before: s0 the name, s1 the type system "MCOS", s2 the class)."""
    fields = value.dtype.names or ()
    for name in ("_Class", "s2"):
        if name in fields and value.size:
            text = _text(value.reshape(-1)[0][name])
            if text:
                return text
    return "object"


SAMPLE_WIDTH = 16
"""The most numbers a struct array's element holds in a field for the field to be one sample
(a time, a vector of three, a quaternion; _struct_samples)."""


def _struct_samples(items: list[Any]) -> dict[str, np.ndarray] | None:
    """A MATLAB struct array of a sample an element (log(i).time, log(i).acc, as a loop that
    logs sample by sample builds it) as a struct of arrays, an element a row (MATLAB's
    [log.time]' and vertcat(log.acc)): every field of numbers of at most SAMPLE_WIDTH of them
    and of one shape in every element, its other fields (text) left out. None for any other
    list: a cell array, a struct array of whole recordings (a trial an element), elements of
    other fields or shapes."""
    if len(items) < 2 or not all(isinstance(x, dict) for x in items):
        return None
    names = list(items[0])
    if any(list(x) != names for x in items):
        return None
    out = {}
    for name in names:
        values = [np.asarray(x[name]) for x in items]
        kinds = {v.dtype.kind for v in values}
        if not kinds <= set("iuf"):
            continue  # text, a nested struct: no sample
        shape = values[0].shape
        if values[0].size > SAMPLE_WIDTH or any(v.shape != shape for v in values):
            return None
        out[name] = np.stack([v.reshape(-1) for v in values])
        if values[0].size == 1:
            out[name] = out[name].reshape(-1)
    return out or None


def _mat_found(data: dict[str, Any]) -> _Found:
    from scipy.io.matlab import MatlabFunction, MatlabOpaque

    arrays: list[_Array] = []
    objects: list[tuple[str, str]] = []
    scalars: dict[str, Any] = {}

    def visit(value: Any, path: tuple[str, ...]) -> None:
        if isinstance(value, dict):
            for name, item in value.items():
                if not name.startswith("__"):
                    visit(item, (*path, name))
        elif isinstance(value, list):  # a struct array's elements, a cell array's cells
            samples = _struct_samples(value)
            if samples is not None:  # a sample an element (log(i).acc = ...)
                visit(samples, path)
                return
            for i, item in enumerate(value):
                if isinstance(item, dict):
                    visit(item, (*path, str(i + 1)))
        elif isinstance(value, MatlabOpaque):
            objects.append(("/".join(path), _opaque_class(value)))
        elif isinstance(value, MatlabFunction):
            return
        elif isinstance(value, np.ndarray | int | float) and not isinstance(value, bool):
            a = np.asarray(value)
            if a.dtype.names:
                for field in a.dtype.names:
                    visit(np.asarray(a[field]), (*path, field))
            elif a.dtype.kind == "O":
                for i, item in enumerate(a.reshape(-1)):
                    if isinstance(item, dict):
                        visit(item, (*path, str(i + 1)))
            elif a.dtype.kind in "iuf" and a.size == 1:
                scalars.setdefault(path[-1], a.reshape(-1)[0])
            elif a.dtype.kind in "iuf" and 0 < a.ndim <= 2:
                arrays.append(_in_memory(path, a))

    visit(data, ())
    return _Found(arrays, objects, scalars)


def mat_table(path: Path, want: str = "imu") -> TableSource:
    import h5py

    if h5py.is_hdf5(path):  # MATLAB v7.3: HDF5, arrays stored transposed
        return hdf5_table(path, want)
    import scipy.io

    try:
        data = scipy.io.loadmat(path, simplify_cells=True)
    except Exception as err:  # scipy raises several types for a damaged file (as broad.data)
        raise TableError(f"{path}: not a readable MATLAB file ({err})") from None
    return _table(path, "mat", _mat_found(data), want=want)


def arrays_table(path: Path, kind: str, arrays: dict[str, np.ndarray]) -> TableSource:
    """Named arrays already in memory (a PX4 log's topic) as a table."""
    found = _Found([], [], {})
    for name, a in arrays.items():
        a = np.asarray(a)
        if a.dtype.kind in "iuf" and 0 < a.ndim <= 2 and a.size > 1:
            found.arrays.append(_in_memory((name,), a))
    return _table(path, kind, found)


# ----- columns ----------------------------------------------------------------------------------

def _length(shape: tuple[int, ...]) -> int | None:
    """The samples an array of this shape holds along its longest axis: a vector's length, a
    matrix's longer side (more rows than columns, or the transpose); None for no samples."""
    if len(shape) == 1:
        return shape[0] if shape[0] > 1 else None
    if len(shape) == 2 and max(shape) > 1 and max(shape) > min(shape):
        return max(shape)
    return None


def _width(a: _Array) -> int:
    return 1 if len(a.shape) == 1 else min(a.shape)


def _column_names(a: _Array) -> list[str]:
    """The names of an array's columns as its own ("acc" -> acc_x, acc_y, acc_z)."""
    k, leaf = _width(a), a.path[-1]
    if a.names is not None and len(a.names) == k:
        return list(a.names)
    if k == 1:
        return [leaf]
    if k == 3:
        return [f"{leaf}_{axis}" for axis in "xyz"]
    return [f"{leaf}_{i + 1}" for i in range(k)]


def _shape_text(a: _Array) -> str:
    return f"{'/'.join(a.path)} {tuple(a.shape)}"


def _listed(items: list[str]) -> str:
    more = len(items) - _SHOWN
    return ", ".join(items[:_SHOWN]) + (f" and {more} more" if more > 0 else "")


def _refusal(path: Path, found: _Found) -> TableError:
    if found.objects:
        where, cls = found.objects[0]
        hint = MATLAB_HINT.get(cls, "save its samples as arrays of numbers (a struct of "
                                    "vectors, or an [N, 3] matrix per sensor) or as CSV")
        hint = hint.format(var=where.rpartition("/")[2])
        what = ("whose elements this reader follows in a -v7.3 file only where each holds a "
                "sample" if cls == STRUCT_ARRAY else "an object only MATLAB reads")
        return TableError(f"{path}: {where} is a MATLAB {cls}, {what}, and the file holds no "
                          f"arrays of samples beside it: {hint}")
    has = _listed([_shape_text(a) for a in found.arrays]) or "nothing"
    return TableError(f"{path}: no array of samples: columns are vectors of one length, or "
                      "matrices of a column per quantity ([N, 3] acc, gyro); it has " + has)


def _rate(found: _Found) -> dict[str, float]:
    for key in RATE_NAMES:
        value = found.scalars.get(key)
        if value is None:
            continue
        value = np.asarray(value)
        if value.size == 1 and value.dtype.kind in "fiu":
            return {"rate": float(value.reshape(-1)[0])}
    return {}


def _read(path: Path, a: _Array, lo: int, hi: int) -> np.ndarray:
    """Rows lo..hi of an array; TableError naming the array and the rows where the file's bytes
    there do not read (h5py's error names neither)."""
    try:
        return a.read(lo, hi)
    except (OSError, KeyError, ValueError, RuntimeError) as err:
        raise TableError(f"{path}: {'/'.join(a.path)}, rows {lo + 1} to {hi}, does not read "
                         f"({err}): the file is damaged (cut, or changed since it was "
                         "written); copy or export it again") from None


def _holds(header: list[str], quantity: str) -> bool:
    """Whether a column's name fits the quantity (its aliases; roll and pitch by their own)."""
    if quantity in ALIASES:
        return bool(find_names(header, quantity))
    return quantity in (norm_name(h) for h in header)


def _columns(used: list[_Array]) -> tuple[list[str], list[tuple[_Array, int, Any]]]:
    """The header of these arrays' columns (_column_names; a path where two share a name) and
    each column's (array, index in it, stated unit)."""
    own = [_column_names(a) for a in used]
    counts = Counter(name for names in own for name in names)
    header, where = [], []
    for a, names in zip(used, own, strict=True):
        units = a.units or [None] * len(names)
        for j, name in enumerate(names):
            header.append("/".join((*a.path[:-1], name)) if counts[name] > 1 else name)
            where.append((a, j, units[j]))
    return header, where


def _table(path: Path, kind: str, found: _Found, owner: Any = None, want: str = "imu"
           ) -> TableSource:
    """The arrays of one length as a table (the module docstring): the length whose columns
    hold the most of what is wanted (WANTED: a recording's IMU, a reference's pose), then the
    one the most arrays share, then the longest; their columns named, each array read once a
    block; TableError where none holds samples."""
    lengths = Counter(n for a in found.arrays if (n := _length(a.shape)) is not None)
    if not lengths:
        raise _refusal(path, found)
    tables = {m: _columns([a for a in found.arrays if _length(a.shape) == m]) for m in lengths}
    n = max(lengths, key=lambda m: (sum(_holds(tables[m][0], q) for q in WANTED.get(want, ())),
                                    lengths[m], m))
    header, where = tables[n]
    left = [a for a in found.arrays if _length(a.shape) not in (None, n)]
    named = []
    for h, (a, _, stated) in zip(header, where, strict=True):
        name, unit = unit_of(h, stated)
        named.append((name, DATETIME if a.seconds_per_tick else unit))

    def column(part: np.ndarray, i: int) -> np.ndarray:
        a, j, _ = where[i]
        if part.ndim == 2:  # [rows, k]
            part = part[:, j]
        if a.seconds_per_tick:
            return ticks_seconds(np.asarray(part, dtype=np.int64), a.seconds_per_tick)
        return np.asarray(part, dtype=float)

    def read(columns: list[int], rows: int) -> Iterator[np.ndarray]:
        arrays = {id(where[i][0]): where[i][0] for i in columns}  # each read once a block
        for lo in range(0, n, rows):
            hi = min(lo + rows, n)
            parts = {key: _read(path, a, lo, hi) for key, a in arrays.items()}
            yield np.column_stack([column(parts[id(where[i][0])], i) for i in columns]) \
                if columns else np.empty((hi - lo, 0))

    source = TableSource(path, header, [nm for nm, _ in named], [u for _, u in named], kind, n,
                         read, lambda row: f"row {row + 1}", _rate(found), owner=owner)
    notes = []
    if left:
        notes.append(f"{len(left)} array(s) of another length than the {n} samples left out: "
                     + _listed([_shape_text(a) for a in left]))
    if found.objects:
        notes.append("left out, as objects only MATLAB reads: "
                     + _listed([f"{w} (a {c})" for w, c in found.objects]))
    source.note = "; ".join(notes)
    return source


__all__ = ["arrays_table", "hdf5_table", "mat_table"]
