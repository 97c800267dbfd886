"""A campaign's results on disk: one Parquet file per finished batch under DIR/runs/.

Each batch is written the moment it arrives (to a temporary name, then renamed, so that a crash
or Ctrl-C leaves whole files only); reading the folder back gives every run done so far, which
is how the same command resumes: it runs only the keys it does not find. A run that failed
after its retries is a row too (status "failed", its error), so it is never silently dropped,
and a resumed campaign does not run it again.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import Any

RUNS = "runs"


def write_batch(out_dir: Path, rows: list[dict[str, Any]]) -> Path:
    """Write one batch's rows as DIR/runs/batch-<uuid>.parquet; return the path."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    folder = out_dir / RUNS
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"batch-{uuid.uuid4().hex}.parquet"
    tmp = path.with_suffix(".tmp")
    pq.write_table(pa.Table.from_pylist(rows), tmp)
    os.replace(tmp, path)
    return path


def read_rows(out_dir: Path) -> list[dict[str, Any]]:
    """Every row written so far (an empty list for a new folder); the last row of a key wins."""
    import pyarrow.parquet as pq

    folder = out_dir / RUNS
    if not folder.is_dir():
        return []
    rows: dict[str, dict[str, Any]] = {}
    for path in sorted(folder.glob("batch-*.parquet")):
        for row in pq.read_table(path).to_pylist():
            rows[row["key"]] = row
    return list(rows.values())


def done_keys(out_dir: Path) -> set[str]:
    """The keys of the runs already in the folder (done or failed)."""
    return {row["key"] for row in read_rows(out_dir)}
