"""Recordings of any length and format: read in blocks that give what reading whole gives,
Parquet, HDF5 and MAT beside CSV, outputs in three formats, a refusal that leaves no output
file, and the C twin loaded once however many threads ask at once."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import testbenches.fit.recording as recording
from fusion_core.registry import create
from testbenches.cli import main
from testbenches.fit.recording import RecordingError, open_recording

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"
TRUTH = REPO / "examples" / "tilt_motion_truth.csv"


def _example() -> dict[str, np.ndarray]:
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    return {"time": data[:, 0], "acc": data[:, 1:4], "gyro": data[:, 4:7]}


def test_blocks_of_any_size_give_what_the_whole_file_gives(tmp_path):
    """Blocks of 7 samples (the time carried across each boundary, samples without a time or
    a number inside them) against one block."""
    ex = _example()
    t = ex["time"].copy()
    t[[13, 14, 500]] = np.nan
    gyro = ex["gyro"].copy()
    gyro[[6, 7, 8, 222]] = np.nan
    path = tmp_path / "gappy.csv"
    np.savetxt(path, np.column_stack([t, ex["acc"], gyro]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    source = open_recording(path, gyro_unit="rad/s")
    whole, t_whole = source.load()
    parts = list(source.blocks(rows=7))
    assert all(len(p.dt) == 7 for p, _ in parts[:-1])
    for name in ("acc", "gyro", "dt"):
        got = np.concatenate([getattr(p, name) for p, _ in parts])
        np.testing.assert_array_equal(got, getattr(whole, name))
    np.testing.assert_array_equal(np.concatenate([tt for _, tt in parts]), t_whole)
    assert np.isnan(whole.dt[[13, 14, 500]]).all() and np.isfinite(t_whole).all()
    assert t[12] < t_whole[13] < t_whole[14] < t[15]


@pytest.mark.parametrize("kind", ["csv", "parquet"])
def test_the_read_after_the_first_block_goes_on_from_it(tmp_path, kind):
    """The units are decided on the first block; the recording's read then goes on from it
    rather than parsing it again, and gives what a fresh read gives; a later read starts
    from the first row again."""
    from testbenches.reader import open_table

    ex = _example()
    data = np.column_stack([ex["time"], ex["acc"], ex["gyro"]])
    path = tmp_path / f"rec.{kind}"
    if kind == "csv":
        np.savetxt(path, data, delimiter=",", header="time,ax,ay,az,gx,gy,gz", comments="")
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        pq.write_table(pa.table({n: data[:, i] for i, n in enumerate(
            ["time", "ax", "ay", "az", "gx", "gy", "gz"])}), path)
    table = open_table(path)
    columns = [0, 2, 5]
    fresh = table.read(columns)
    parsed = []  # the rows each read of the file yields
    read = table._read

    def counted(cols, rows):
        for block in read(cols, rows):
            parsed.append(len(block))
            yield block

    table._read = counted
    first = table.first_block(columns, 64)
    assert first is not None and np.array_equal(first, fresh[:64])
    other = list(table.blocks(columns, 32))  # other block rows: a read of its own
    assert np.array_equal(np.concatenate(other), fresh) and sum(parsed) == 64 + len(fresh)
    went_on = list(table.blocks(columns, 64))
    assert np.array_equal(np.concatenate(went_on), fresh) and len(went_on[0]) == 64
    assert sum(parsed) == 2 * len(fresh)  # the first block was not read again
    assert np.array_equal(np.concatenate(list(table.blocks(columns, 64))), fresh)
    assert sum(parsed) == 3 * len(fresh)


def test_a_time_that_goes_back_in_a_later_block_names_its_line(tmp_path):
    ex = _example()
    t = ex["time"].copy()
    t[700] = t[600]
    path = tmp_path / "back.csv"
    np.savetxt(path, np.column_stack([t, ex["acc"], ex["gyro"]]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    with pytest.raises(RecordingError, match=r"line 702: the time .* does not increase from "
                       r".* on line 701"):
        list(open_recording(path, gyro_unit="rad/s").blocks(rows=64))


def test_the_gyro_unit_is_found_past_a_still_start(tmp_path, monkeypatch):
    """The first block is still (no evidence): the windows of later blocks are pooled until
    they tell, and the printout says over how many samples."""
    monkeypatch.setattr(recording, "PREFIX_ROWS", 300)
    ex = _example()
    n_still = 300
    acc = np.vstack([np.tile(ex["acc"][0], (n_still, 1)), ex["acc"]])
    gyro = np.vstack([np.zeros((n_still, 3)), np.degrees(ex["gyro"])])
    t = np.arange(len(acc)) * 0.01
    path = tmp_path / "late.csv"
    np.savetxt(path, np.column_stack([t, acc, gyro]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    source = open_recording(path)
    assert "gyro in deg/s (from the data" in source.choices
    assert "over the first 600 samples" in source.choices or \
        "over the first 900 samples" in source.choices


def _write_formats(tmp_path: Path) -> dict[str, Path]:
    """The example as Parquet (gyro in deg/s stated by field metadata), HDF5 ([N, 3] datasets,
    units as attributes, a time dataset in ms) and MAT v5 (variables, a rate)."""
    import h5py
    import pyarrow as pa
    import pyarrow.parquet as pq
    import scipy.io

    ex = _example()
    paths = {}
    fields = [pa.field("time", pa.float64())]
    fields += [pa.field(f"acc_{a}", pa.float64()) for a in "xyz"]
    fields += [pa.field(f"gyro_{a}", pa.float64(), metadata={"unit": "deg/s"}) for a in "xyz"]
    table = pa.table([ex["time"], *ex["acc"].T, *np.degrees(ex["gyro"]).T],
                     schema=pa.schema(fields))
    paths["parquet"] = tmp_path / "rec.parquet"
    pq.write_table(table, paths["parquet"])
    paths["hdf5"] = tmp_path / "rec.h5"
    with h5py.File(paths["hdf5"], "w") as f:
        f["acc"] = ex["acc"] / 9.80665
        f["acc"].attrs["unit"] = "g"
        f["gyro"] = ex["gyro"]
        f["gyro"].attrs["units"] = "rad/s"
        f["time"] = ex["time"] * 1000.0
        f["time"].attrs["unit"] = "ms"
    paths["mat"] = tmp_path / "rec.mat"
    scipy.io.savemat(paths["mat"], {"acc": ex["acc"], "gyro": ex["gyro"], "rate": 100.0})
    return paths


@pytest.mark.parametrize("kind", ["parquet", "hdf5", "mat"])
def test_parquet_hdf5_and_mat_give_the_csv_files_estimate(tmp_path, capsys, kind):
    path = _write_formats(tmp_path)[kind]
    assert main(["estimate", str(path), "--estimator", "kf", "--out", str(tmp_path),
                 "--no-plots"]) == 0
    said = capsys.readouterr().out
    if kind == "parquet":
        assert "gyro in deg/s (from the header" in said
    if kind == "hdf5":
        assert "acc in g (from the header)" in said
    got = np.loadtxt(tmp_path / "rec_kf.csv", delimiter=",", skiprows=1)
    ex = _example()
    want = create("kf").run(ex["acc"], ex["gyro"], np.full(len(ex["time"]), 0.01))
    np.testing.assert_allclose(got[:, 1], want["roll"], atol=1e-9)
    np.testing.assert_allclose(got[:, 0], ex["time"] - ex["time"][0], atol=1e-9)


def test_outputs_in_every_format_hold_the_same_numbers_every_nth_sample(tmp_path):
    import h5py
    import pyarrow.parquet as pq

    base = ["estimate", str(EXAMPLE), "--estimator", "poskf", "--no-plots"]
    assert main([*base, "--out", str(tmp_path / "csv")]) == 0
    full = np.loadtxt(tmp_path / "csv" / "tilt_motion_poskf.csv", delimiter=",", skiprows=1)
    assert main([*base, "--out", str(tmp_path / "pq"), "--format", "parquet", "--every", "3",
                 "--outputs", "pitch,vel,rejected"]) == 0
    table = pq.read_table(tmp_path / "pq" / "tilt_motion_poskf.parquet")
    assert table.column_names == ["time", "pitch", "vel_x", "vel_y", "vel_z", "rejected"]
    np.testing.assert_array_equal(table.column("pitch").to_numpy(), full[::3, 2])
    np.testing.assert_array_equal(table.column("vel_z").to_numpy(), full[::3, 11])
    assert main([*base, "--out", str(tmp_path / "h5"), "--format", "hdf5"]) == 0
    with h5py.File(tmp_path / "h5" / "tilt_motion_poskf.h5") as f:
        np.testing.assert_array_equal(f["roll"][:], full[:, 1])
        assert list(f) == sorted(["time", "roll", "pitch", "bias_x", "bias_y", "bias_z",
                                  "pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z"])


def test_an_unknown_output_is_refused_naming_the_allowed(tmp_path, capsys):
    assert main(["estimate", str(EXAMPLE), "--outputs", "roll,yaw", "--out", str(tmp_path),
                 "--no-plots"]) == 2
    assert "unknown output 'yaw': allowed all, roll, pitch, bias, pos, vel, rejected" in \
        capsys.readouterr().err


def test_a_refusal_half_way_leaves_no_output_file(tmp_path, monkeypatch, capsys):
    """The time goes back in the third block: refused, and no file that looks complete."""
    import testbenches.table as table

    monkeypatch.setattr(table, "BLOCK_ROWS", 200)
    monkeypatch.setattr(recording, "PREFIX_ROWS", 100)  # the units from the first 100
    ex = _example()
    t = ex["time"].copy()
    t[650] = 0.0
    path = tmp_path / "late_error.csv"
    np.savetxt(path, np.column_stack([t, ex["acc"], ex["gyro"]]), delimiter=",",
               header="time,ax,ay,az,gx,gy,gz", comments="")
    out = tmp_path / "out"
    assert main(["estimate", str(path), "--gyro-unit", "rad/s", "--out", str(out)]) == 2
    assert "line 652: the time 0 s does not increase" in capsys.readouterr().err
    assert list(out.iterdir()) == []


def test_the_plot_and_scores_hold_over_many_blocks(tmp_path, monkeypatch, capsys):
    """Blocks of 64 samples: the same scores as one block, to the last digit printed."""
    import testbenches.table as table

    args = ["estimate", str(EXAMPLE), "--reference", str(TRUTH), "--estimator", "kf,cf",
            "--out", str(tmp_path)]
    assert main(args) == 0
    whole = capsys.readouterr().out.splitlines()
    monkeypatch.setattr(table, "BLOCK_ROWS", 64)
    assert main(args) == 0
    blocks = capsys.readouterr().out.splitlines()
    rows = [r for r in whole if r.split()[0] in ("kf", "cf", "vqf")]
    assert rows and rows == [r for r in blocks if r.split()[0] in ("kf", "cf", "vqf")]
    assert (tmp_path / "tilt_motion.png").stat().st_size > 10_000


def test_the_c_twin_loads_once_for_threads_that_ask_at_once():
    """Eight threads' first estimator runs at once in a fresh interpreter: every one through
    the C twin (a thread that found the library half loaded used to run in Python)."""
    from fusion_core import native

    if not native.available():
        pytest.skip(f"the C twin is unavailable here: {native.reason()}")
    code = (
        "import threading, numpy as np\n"
        "from fusion_core.native import library\n"
        "got = []\n"
        "def ask(): got.append(library.available())\n"
        "threads = [threading.Thread(target=ask) for _ in range(8)]\n"
        "[t.start() for t in threads]; [t.join() for t in threads]\n"
        "print(got.count(True))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert proc.stdout.strip() == "8", proc.stdout + proc.stderr


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_estimate_reads_and_writes_without_importing_pandas(tmp_path, fmt):
    """pyarrow's numpy conversions import pandas where it is installed, half a second of every
    command: the reader and the writers go through buffers instead."""
    code = ("import sys; from testbenches.cli import main; "
            f"s = main(['estimate', {str(EXAMPLE)!r}, '--out', {str(tmp_path)!r}, '--format', "
            f"{fmt!r}, '--no-plots']); print(s, 'pandas' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=REPO, check=False)
    assert proc.stdout.strip().splitlines()[-1] == "0 False", proc.stderr[-500:]
