"""A campaign's runs on Dask's distributed scheduler, in batches, resumable.

`scheduler="local"` starts a LocalCluster of `workers` processes, one thread each (the runs are
CPU-bound and the estimators hold no lock to share); an address ("HOST:PORT" or
"tcp://HOST:PORT") connects to a scheduler the user runs (`dask scheduler`, `dask worker
ADDRESS` on each machine, with this project installed there). Runs go in batches, one task per
batch, that shrink as the campaign goes (BATCHES_PER_WORKER). Each run is tried 1 + retries
times inside its batch; a run that still raises becomes a "failed" row with its error. Dask
itself retries a batch whose worker died. Every batch is written as Parquet the moment it
returns (store.py).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .plan import Run
from .simulate import METRICS, run_row
from .store import done_keys, write_batch

BATCHES_PER_WORKER = 4
"""Guided batches: each takes 1/(BATCHES_PER_WORKER x workers) of the runs not yet handed out,
so they shrink as the campaign goes, at most MAX_BATCH runs and at least MIN_BATCH (fewer in a
campaign too small to give every worker that many). The large first ones keep the scheduler's
per-task cost (about a millisecond) small beside the runs (milliseconds each natively); the
small last ones let the workers finish together, instead of one idling while another works
through a last batch as large as the first."""
MIN_BATCH = 8
MAX_BATCH = 200
CONNECT_TIMEOUT_S = 10
"""How long to wait for the user's own scheduler before saying it does not answer [s]."""


def failed_row(run: Run, error: str, attempts: int) -> dict[str, Any]:
    row: dict[str, Any] = {"key": run.key, "estimator": run.estimator, "scenario": run.scenario,
                           "seed": run.seed, "status": "failed", "error": error,
                           "attempts": attempts}
    row.update({f"vary_{k}": float(v) for k, v in run.varied.items()})
    row.update({k: math.nan for k in METRICS})
    row["seconds"] = math.nan
    return row


def run_batch(runs: Sequence[Run], retries: int, fmu_dir: str | None = None
              ) -> list[dict[str, Any]]:
    """The rows of a batch of runs (a Dask task)."""
    rows = []
    for run in runs:
        error = ""
        for attempt in range(1, retries + 2):
            try:
                row = run_row(run, fmu_dir)
                row["attempts"] = attempt
                break
            except Exception as err:  # recorded, never dropped
                error = f"{type(err).__name__}: {err}"
        else:
            row = failed_row(run, error, retries + 1)
        rows.append(row)
    return rows


def connect(scheduler: str = "local", workers: int = 2, timeout: float = CONNECT_TIMEOUT_S
            ) -> tuple[Any, Any]:
    """A Dask client (and its LocalCluster, or None for the user's own scheduler); a
    ConnectionError that says what to do where no scheduler answers at the address."""
    from dask.distributed import Client, LocalCluster

    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=logging.ERROR)
        return Client(cluster), cluster
    address = scheduler if "://" in scheduler else f"tcp://{scheduler}"
    try:
        return Client(address, timeout=f"{timeout}s"), None
    except OSError as err:  # refused, unknown host, timed out
        raise ConnectionError(
            f"--scheduler {scheduler}: no Dask scheduler answers at {address} within "
            f"{timeout:g} s ({err}). Start one there (`dask scheduler`, then `dask "
            "worker ADDRESS` on each machine) or use --scheduler local for a LocalCluster"
        ) from err


def batches(runs: Sequence[Run], workers: int, size: int | None = None) -> list[list[Run]]:
    """The runs in Dask tasks: guided sizes (BATCHES_PER_WORKER), or `size` runs each."""
    share = BATCHES_PER_WORKER * workers
    smallest = min(MIN_BATCH, math.ceil(len(runs) / share))
    out, start = [], 0
    while start < len(runs):
        n = size or min(MAX_BATCH, max(smallest, math.ceil((len(runs) - start) / share)))
        out.append(list(runs[start:start + n]))
        start += n
    return out


def execute(runs: Sequence[Run], out_dir: Path, scheduler: str = "local", workers: int = 2,
            batch_size: int | None = None, retries: int = 2, fmu_dir: str | None = None,
            progress: Callable[[int], None] | None = None, log: Callable[[str], None] = print
            ) -> dict[str, Any]:
    """Run what out_dir does not hold yet; return what was done (counts and seconds)."""
    import time

    from dask.distributed import as_completed

    if workers < 1 or retries < 0 or (batch_size is not None and batch_size < 1):
        raise ValueError(f"workers={workers}, retries={retries}, batch_size={batch_size}: "
                         "allowed workers and batch_size of at least 1, retries of at least 0")
    done = done_keys(out_dir)
    todo = [r for r in runs if r.key not in done]
    stats: dict[str, Any] = {"planned": len(runs), "already_done": len(runs) - len(todo),
                             "ran": 0, "failed": 0, "seconds": 0.0}
    if not todo:
        log(f"all {len(runs)} runs are in {out_dir}: nothing to run")
        return stats
    t0 = time.perf_counter()
    client, cluster = connect(scheduler, workers)
    try:
        n_workers = max(1, len(client.scheduler_info().get("workers", {})) or workers)
        dashboard = client.scheduler_info().get("services", {}).get("dashboard")
        log(f"Dask: {n_workers} worker(s)"
            + (f", dashboard {client.dashboard_link}" if dashboard else ", no dashboard"))
        parts = batches(todo, n_workers, batch_size)
        futures = [client.submit(run_batch, part, retries, fmu_dir, pure=False, retries=1)
                   for part in parts]
        for future in as_completed(futures):
            rows = future.result()
            write_batch(out_dir, rows)
            stats["ran"] += len(rows)
            stats["failed"] += sum(r["status"] == "failed" for r in rows)
            if progress is not None:
                progress(len(rows))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    stats["seconds"] = time.perf_counter() - t0
    return stats
