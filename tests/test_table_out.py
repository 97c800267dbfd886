"""testbenches.table_out: every format gives back the doubles written, to the bit, block after
block; a file appears under its name only when committed."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from testbenches.table_out import FORMATS, TableWriter

NAMES = ["time", "roll", "bias_x"]


def _blocks() -> list[list[np.ndarray]]:
    """Two blocks of awkward doubles: signed zeros, NaN, infinities, the smallest subnormal,
    thirds, large and small magnitudes, and a strided column (as bias[:, 0] is)."""
    rng = np.random.default_rng(3)
    odd = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1 / 3, -2 / 3, 1e22, 1.5e-7,
                    123456789012.345, 0.1])
    wide = rng.normal(size=(len(odd), 3)) * 10.0 ** rng.integers(-12, 12, size=(len(odd), 3))
    first = [np.arange(len(odd)) * 0.01, odd, wide[:, 1]]
    second = [np.arange(5) * 0.01 + 1.0, rng.normal(size=5), np.zeros(5)]
    return [first, second]


def _read(path: Path, fmt: str) -> dict[str, np.ndarray]:
    if fmt == "csv":
        lines = path.read_text().splitlines()
        assert lines[0] == ",".join(NAMES)
        rows = [[float(cell) for cell in line.split(",")] for line in lines[1:]]
        return {n: np.array([r[i] for r in rows]) for i, n in enumerate(NAMES)}
    if fmt == "parquet":
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        return {n: np.asarray(table[n].to_pylist(), dtype=float) for n in NAMES}
    import h5py

    with h5py.File(path, "r") as f:
        return {n: f[n][:] for n in NAMES}


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool(np.all((a.view(np.int64) == b.view(np.int64))
                                              | (np.isnan(a) & np.isnan(b))))


def _gives_back(tmp_path: Path, fmt: str) -> None:
    path = tmp_path / f"out{FORMATS[fmt]}"
    writer = TableWriter(path, fmt, NAMES)
    blocks = _blocks()
    for block in blocks:
        writer.write(block)
    assert not path.exists()  # only the hidden partial file until committed
    assert writer.commit() == path
    assert not writer.partial.exists()
    got = _read(path, fmt)
    for i, name in enumerate(NAMES):
        want = np.concatenate([block[i] for block in blocks])
        assert _same_bits(got[name], want), name


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_each_format_gives_back_the_doubles_written(tmp_path: Path, fmt: str) -> None:
    _gives_back(tmp_path, fmt)


def test_csv_without_polars_gives_back_the_same_doubles(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """Without polars numpy writes %.17g: other text, the same doubles."""
    monkeypatch.setitem(sys.modules, "polars", None)  # import polars raises ImportError
    _gives_back(tmp_path, "csv")


def test_a_discarded_writer_leaves_no_file(tmp_path: Path) -> None:
    path = tmp_path / "out.csv"
    writer = TableWriter(path, "csv", NAMES)
    writer.write(_blocks()[0])
    writer.discard()
    assert list(tmp_path.iterdir()) == []


def test_an_unknown_format_is_refused_naming_the_allowed() -> None:
    with pytest.raises(ValueError, match="output format 'xlsx': allowed csv, parquet, hdf5"):
        TableWriter(Path("out.xlsx"), "xlsx", NAMES)


def _full_disk(monkeypatch: pytest.MonkeyPatch, free: int) -> None:
    """The output disk with `free` bytes left, as shutil.disk_usage reports it."""
    import shutil

    from testbenches import table_out

    usage = shutil.disk_usage(".")
    monkeypatch.setattr(table_out.shutil, "disk_usage",
                        lambda _: usage._replace(free=free))


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_a_block_the_disk_cannot_hold_is_refused_naming_the_file_and_leaves_none(
        tmp_path: Path, fmt: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """On a full disk polars' and pyarrow's writers raised their own errors as tracebacks, and
    HDF5's close, flushing its cache, crashed the process (a segmentation fault, partial files
    left). A block is now refused before it is written where the disk lacks room for it."""
    writer = TableWriter(tmp_path / f"out{FORMATS[fmt]}", fmt, NAMES)
    _full_disk(monkeypatch, 1_000)
    with pytest.raises(OSError, match=rf"out{FORMATS[fmt]}: cannot be written \(\[Errno 28\] "
                       r"0\.0 MB free on its disk, where a block of 12 rows wants"):
        writer.write(_blocks()[0])
    assert list(tmp_path.iterdir()) == []


def test_estimate_on_a_full_disk_says_so_in_one_line_and_leaves_no_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
        ) -> None:
    from testbenches.cli import main

    _full_disk(monkeypatch, 100_000)
    example = Path(__file__).resolve().parents[1] / "examples" / "tilt_motion.csv"
    out = tmp_path / "out"
    assert main(["estimate", str(example), "--format", "hdf5", "--no-plots", "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and ".h5: cannot be written" in err
    assert "Traceback" not in err and list(out.iterdir()) == []
