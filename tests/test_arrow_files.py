"""Parquet and Arrow IPC (Feather) recordings as data tools write them: an IMU's vectors as a
struct of x, y, z or a list of three numbers a row (pandas writes a column of arrays so), an
Arrow file's batches of any size, and Feather v1: each gives the samples the CSV gives, and a
null or short vector is a sample without numbers."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from testbenches.fit.recording import open_recording
from testbenches.reader import open_table

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
feather = pytest.importorskip("pyarrow.feather")

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"


def _example() -> np.ndarray:
    return np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)


def _samples(path: Path) -> tuple[np.ndarray, ...]:
    rec, t = open_recording(path, gyro_unit="rad/s").load()
    return rec.acc, rec.gyro, rec.dt, t


def _same_as_csv(path: Path) -> None:
    for got, want in zip(_samples(path), _samples(EXAMPLE), strict=True):
        np.testing.assert_array_equal(got, want)


def _columns(ex: np.ndarray) -> dict[str, np.ndarray]:
    return {"time": ex[:, 0], **{f"acc_{a}": ex[:, 1 + i] for i, a in enumerate("xyz")},
            **{f"gyro_{a}": ex[:, 4 + i] for i, a in enumerate("xyz")}}


def test_arrow_ipc_files_of_any_batches_and_feather_v1(tmp_path):
    table = pa.table(_columns(_example()))
    for name, options in (("one.feather", {}), ("chunks.arrow", {"chunksize": 77}),
                          ("zstd.arrow", {"chunksize": 300, "compression": "zstd"}),
                          ("v1.feather", {"version": 1})):
        path = tmp_path / name
        with warnings.catch_warnings():  # pyarrow's, writing v1
            warnings.simplefilter("ignore", DeprecationWarning)
            feather.write_feather(table, path, **options)
        _same_as_csv(path)
        blocks = list(open_table(path).blocks([1, 2], rows=128))
        assert [len(b) for b in blocks] == [128] * 7 + [104]


def test_vectors_as_structs_and_lists(tmp_path):
    ex = _example()
    acc, gyro = ex[:, 1:4], ex[:, 4:7]
    kinds = {
        "struct": lambda v: pa.StructArray.from_arrays([pa.array(v[:, i]) for i in range(3)],
                                                       ["x", "y", "z"]),
        "fixed": lambda v: pa.FixedSizeListArray.from_arrays(pa.array(v.reshape(-1)), 3),
        "list": lambda v: pa.array(list(v), pa.list_(pa.float64())),
    }
    for kind, make in kinds.items():
        path = tmp_path / f"{kind}.parquet"
        pq.write_table(pa.table({"time": ex[:, 0], "acc": make(acc), "gyro": make(gyro)}), path,
                       row_group_size=300)
        _same_as_csv(path)
    header = open_table(tmp_path / "struct.parquet").header
    assert header == ["time", "acc.x", "acc.y", "acc.z", "gyro.x", "gyro.y", "gyro.z"]
    assert open_table(tmp_path / "list.parquet").header == [
        "time", "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"]


def test_a_null_or_short_vector_is_a_sample_without_numbers(tmp_path):
    ex = _example()
    rows = [list(v) for v in ex[:, 1:4]]
    rows[10], rows[20], rows[25] = None, rows[20][:2], [*rows[25], 0.0]
    structs = pa.array([None if i == 30 else {"x": v[0], "y": v[1], "z": v[2]}
                        for i, v in enumerate(ex[:, 4:7])])
    path = tmp_path / "gaps.parquet"
    pq.write_table(pa.table({"time": ex[:, 0], "acc": pa.array(rows, pa.list_(pa.float64())),
                             "gyro": structs}), path)
    table = open_table(path)
    assert table.header[1:4] == ["acc_x", "acc_y", "acc_z"]
    got = table.read(list(range(1, 7)))
    bad = np.isnan(got).any(axis=1)
    assert list(np.flatnonzero(bad)) == [10, 20, 25, 30]
    np.testing.assert_array_equal(got[~bad], ex[~bad, 1:7])


def test_a_timestamp_column_gives_the_seconds_iso_dates_give(tmp_path):
    """A Parquet timestamp[ns] and the same instants as ISO 8601 text in a CSV: the same
    seconds to the bit (both the whole seconds plus their fraction; the Parquet reader took
    nanoseconds times 1e-9 and parted by up to 4.8e-7 s)."""
    import datetime as dt

    ex = _example()
    ns = 1714564800 * 10**9 + np.round(ex[:, 0] * 1000).astype(np.int64) * 10**6
    csv = tmp_path / "iso.csv"
    lines = ["time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z"]
    for n, row in zip(ns, ex, strict=True):
        stamp = dt.datetime(1970, 1, 1) + dt.timedelta(microseconds=int(n // 1000))
        lines.append(",".join([stamp.isoformat(timespec="milliseconds"),
                               *(repr(float(v)) for v in row[1:7])]))
    csv.write_text("\n".join(lines) + "\n")
    columns = {**_columns(ex), "time": pa.array(ns, pa.timestamp("ns"))}
    parquet = tmp_path / "stamps.parquet"
    pq.write_table(pa.table(columns), parquet)
    for got, want in zip(_samples(parquet), _samples(csv), strict=True):
        np.testing.assert_array_equal(got, want)
