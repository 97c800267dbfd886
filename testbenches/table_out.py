"""Writing a table of float columns block by block: CSV, Parquet or HDF5.

A writer writes to a hidden partial file beside its destination and renames it into place on
`commit()`, so a run that is refused or stopped half way leaves no file that looks complete;
`discard()` removes the partial file. CSV cells are the shortest decimal that reads back as the
same double, so no digit of the estimate is lost: polars' writer (Ryu's digits), which formats
them for less than pyarrow's, where formatting is most of a long run's writing.
"""

from __future__ import annotations

import contextlib
import errno
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

FORMATS = {"csv": ".csv", "parquet": ".parquet", "hdf5": ".h5"}
"""Output format -> file suffix."""
CELL_BYTES = {"csv": 25, "parquet": 8, "hdf5": 8}
"""Bytes a value takes at most in each format (CSV: 17 digits, a sign, an exponent, a comma)."""
CHUNK_ROWS = 1 << 16
"""Rows of an HDF5 dataset's chunk (written whole)."""
FREE_MARGIN = 4
"""A block is written where its disk holds this many times what it may take, chunks included:
the other estimators' writers share the disk, and a library that meets a full disk mid-write
may not recover (HDF5's close, which flushes its cache, crashed the process)."""


def _float64_array(values: np.ndarray) -> Any:
    """A pyarrow float64 array over the values' memory (copied only where not contiguous):
    pyarrow's own conversion imports pandas on its first call, half a second of a command."""
    import pyarrow as pa

    x = np.ascontiguousarray(values, dtype=np.float64)
    return pa.Array.from_buffers(pa.float64(), len(x), [None, pa.py_buffer(x)])


class TableWriter:
    """Columns `names` (float64) appended a block at a time to `path` in `fmt`."""

    def __init__(self, path: Path, fmt: str, names: list[str]) -> None:
        if fmt not in FORMATS:
            raise ValueError(f"output format {fmt!r}: allowed {', '.join(FORMATS)}")
        self.path, self.fmt, self.names = path, fmt, list(names)
        self.partial = path.with_name(f".{path.name}.partial")
        self.rows = 0
        self._sink: Any = None
        self._writer: Any = None
        self._schema: Any = None
        with self._or_discarded():
            self._open()

    @contextlib.contextmanager
    def _or_discarded(self) -> Iterator[None]:
        """An OSError inside (a full disk) raised naming the file, its partial file removed."""
        try:
            yield
        except OSError as err:
            self.discard()
            raise OSError(f"{self.path}: cannot be written ({err})") from None

    def _open(self) -> None:
        fmt = self.fmt
        if fmt == "csv":
            self._sink = self.partial.open("wb")
            self._sink.write((",".join(self.names) + "\n").encode())
        elif fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            # never null (a missing estimate is NaN), so no definition levels are written;
            # a dictionary of doubles that seldom repeat costs 5x the write and saves nothing
            self._schema = pa.schema([pa.field(n, pa.float64(), nullable=False)
                                      for n in self.names])
            self._writer = pq.ParquetWriter(self.partial, self._schema, use_dictionary=False)
        else:
            import h5py

            self._sink = h5py.File(self.partial, "w")
            for n in self.names:
                self._sink.create_dataset(n, shape=(0,), maxshape=(None,), dtype="f8",
                                          chunks=(CHUNK_ROWS,))

    def write(self, columns: list[np.ndarray]) -> None:
        """One block: an array per name, all of one length. OSError naming the file where it
        cannot be written (a full disk), the partial file removed."""
        with self._or_discarded():
            self._write(columns)

    def _write(self, columns: list[np.ndarray]) -> None:
        n = len(columns[0]) if columns else 0
        if n == 0:
            return
        chunks = CHUNK_ROWS * 8 if self.fmt == "hdf5" else 0  # HDF5 writes whole chunks
        need = FREE_MARGIN * len(columns) * (n * CELL_BYTES[self.fmt] + chunks)
        free = shutil.disk_usage(self.partial.parent).free
        if free < need:  # before the library meets a full disk (HDF5's close then crashes)
            raise OSError(errno.ENOSPC, f"{free / 1e6:.1f} MB free on its disk, where a block of "
                          f"{n} rows wants {need / 1e6:.1f} MB: free some, write to another "
                          "disk (--out), or fewer rows or outputs (--every, --outputs)")
        if self.fmt == "hdf5":
            for name, values in zip(self.names, columns, strict=True):
                ds = self._sink[name]
                ds.resize((self.rows + n,))
                ds[self.rows:] = values
        elif self.fmt == "csv":
            try:
                import polars as pl
            except ImportError:  # numpy writes digits that read back as the same, slower
                np.savetxt(self._sink, np.column_stack(columns), delimiter=",", fmt="%.17g")
            else:
                pl.DataFrame(dict(zip(self.names, columns, strict=True))).write_csv(
                    self._sink, include_header=False)
        else:
            import pyarrow as pa

            batch = pa.RecordBatch.from_arrays([_float64_array(c) for c in columns],
                                               schema=self._schema)
            self._writer.write_batch(batch)
        self.rows += n

    def _close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        if self._sink is not None:
            self._sink.close()
            self._sink = None

    def commit(self) -> Path:
        """Close and rename into place; the destination."""
        with self._or_discarded():
            self._close()
            self.partial.replace(self.path)
        return self.path

    def discard(self) -> None:
        """Close and remove the partial file (a close that fails, as on a full disk, too)."""
        try:
            self._close()
        except OSError:
            self._sink = self._writer = None
        self.partial.unlink(missing_ok=True)
