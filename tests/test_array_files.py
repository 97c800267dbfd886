"""HDF5 and MATLAB recordings as users write them (testbenches.array_files): MATLAB's vectors
as [N, 1] or [1, N] matrices (v7.3 stores every matrix transposed), arrays in groups and in
structs at any depth, compound datasets, pandas' HDFStore (fixed and table formats, written
here with the layout and attributes pandas writes, pytables not being a dependency), a matrix
whose columns an attribute names: each gives the samples the CSV gives. Arrays of another
length, two sensors' alike names and MATLAB's class objects are refused saying what to do."""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from testbenches.fit.recording import RecordingError, open_recording

h5py = pytest.importorskip("h5py")
scipy_io = pytest.importorskip("scipy.io")

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"
NAMES = ["time", "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt"]


def _example() -> np.ndarray:
    return np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)


def _samples(path: Path, **options: object) -> tuple[np.ndarray, ...]:
    rec, t = open_recording(path, gyro_unit="rad/s", **options).load()
    return rec.acc, rec.gyro, rec.dt, t


def _same_as_csv(path: Path, **options: object) -> None:
    for got, want in zip(_samples(path, **options), _samples(EXAMPLE), strict=True):
        np.testing.assert_array_equal(got, want)


def _matlab_v73(path: Path, variables: dict[str, np.ndarray]) -> Path:
    """A MATLAB v7.3 file as MATLAB writes one: HDF5 after a 512-byte header, each variable a
    dataset of its MATLAB_class, every matrix stored transposed ([N, 1] as [1, N])."""
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, value in variables.items():
            matrix = value.reshape(-1, 1) if value.ndim == 1 else value
            f[name] = matrix.T
            f[name].attrs["MATLAB_class"] = np.bytes_(b"double")
        label = f.create_dataset("label", data=np.frombuffer("imu".encode("utf-16-le"),
                                                             dtype=np.uint16).reshape(-1, 1))
        label.attrs["MATLAB_class"] = np.bytes_(b"char")
    return _matlab_header(path)


def _matlab_header(path: Path) -> Path:
    """MATLAB v7.3's 128-byte header written into an HDF5 file's 512-byte user block."""
    with path.open("r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(124)
                + b"\x00\x02IM")
    return path


def test_matlab_v73_column_vectors_and_transposed_matrices(tmp_path):
    """A [N, 1] time in MATLAB is [1, N] in the file: it was no column ("no time or dt
    column"), and the [N, 3] matrices, stored [3, N], are read along their long side."""
    ex = _example()
    path = _matlab_v73(tmp_path / "rec.mat", {"time": ex[:, 0], "acc": ex[:, 1:4],
                                              "gyro": ex[:, 4:7]})
    _same_as_csv(path)


def test_arrays_in_groups_and_structs_at_any_depth(tmp_path):
    ex = _example()
    h5 = tmp_path / "groups.h5"
    with h5py.File(h5, "w") as f:
        f["session/imu/time"] = ex[:, 0]
        f["session/imu/acc"] = ex[:, 1:4]
        f["session/imu/gyro"] = ex[:, 4:7]
        f["session/notes"] = np.bytes_(b"hand-held")
    _same_as_csv(h5)
    sensors = tmp_path / "sensors.h5"  # a group per sensor, a dataset per axis
    with h5py.File(sensors, "w") as f:
        for i, axis in enumerate("xyz"):
            f[f"accelerometer/{axis}"] = ex[:, 1 + i]
            f[f"gyroscope/{axis}"] = ex[:, 4 + i]
        f["timestamp"] = ex[:, 0]
    _same_as_csv(sensors)
    mat = tmp_path / "struct.mat"  # a struct, and a struct in a 1x1 struct array
    scipy_io.savemat(mat, {"log": {"imu": {"time": ex[:, :1], "acc": ex[:, 1:4],
                                           "gyro": ex[:, 4:7]}, "label": "bench"}})
    _same_as_csv(mat)
    cells = tmp_path / "cells.mat"
    scipy_io.savemat(cells, {"log": np.array([{"time": ex[:, :1], "acc": ex[:, 1:4],
                                               "gyro": ex[:, 4:7]}], dtype=object)})
    _same_as_csv(cells)


def _matlab_v73_struct_array(path: Path, name: str, elements: list[dict[str, Any]]) -> Path:
    """A MATLAB v7.3 file of a 1xN struct array `name` as MATLAB writes one: a group whose
    fields are datasets of references, an element each, to arrays in #refs# (each stored
    transposed; a str as char)."""
    with h5py.File(path, "w", userblock_size=512) as f:
        group = f.create_group(name)
        group.attrs["MATLAB_class"] = np.bytes_(b"struct")
        for field in elements[0]:
            made = []
            for i, element in enumerate(elements):
                text = isinstance(element[field], str)
                data = (np.frombuffer(element[field].encode("utf-16-le"), dtype=np.uint16)
                        if text else np.asarray(element[field], dtype=float))
                # MATLAB's matrix (a vector a row), stored transposed
                value = f.create_dataset(f"#refs#/{field}{i}", data=np.atleast_2d(data).T)
                value.attrs["MATLAB_class"] = np.bytes_(b"char" if text else b"double")
                made.append(value.ref)
            group.create_dataset(field, data=np.array(made, dtype=h5py.ref_dtype).reshape(-1, 1))
    return _matlab_header(path)


def test_a_struct_array_of_a_sample_an_element(tmp_path):
    """A loop that logs sample by sample builds a 1xN struct array (log(i).time, log(i).acc):
    it was 1000 structs of 3 values each ("no column for acc_x ...: the header has log/1/acc,
    log/1/gyro, log/2/acc, ..."), saved -v7.3 nothing ("no array of samples ...; it has
    nothing"); each field is a column of N rows, as [log.time]' is in MATLAB, its text fields
    left out. A struct array of whole recordings (a trial an element) is still each element's
    own arrays (here the longer trial's, the other's left out by their length)."""
    ex = _example()
    samples = [{"time": row[0], "acc": row[1:4], "gyro": row[4:7], "note": "ok"} for row in ex]
    _same_as_csv(_matlab_v73_struct_array(tmp_path / "v73.mat", "log", samples))
    whole = [{"time": rows[:, 0], "acc": rows[:, 1:4], "gyro": rows[:, 4:7]}
             for rows in (ex, ex[:500])]  # -v7.3, a trial an element: refused saying how to save
    trials = _matlab_v73_struct_array(tmp_path / "trials73.mat", "trials", whole)
    with pytest.raises(RecordingError, match=r"trials is a MATLAB struct array, whose elements "
                       r"this reader follows in a -v7.3 file only where each holds a sample.*"
                       r"save\('FILE.mat', 'trials', '-v7'\)"):
        _samples(trials)
    samples = np.zeros((1, len(ex)), dtype=[("time", object), ("acc", object),
                                            ("gyro", object), ("note", object)])
    for i, row in enumerate(ex):
        samples[0, i] = (row[0], row[1:4], row[4:7], "ok")
    path = tmp_path / "samples.mat"
    scipy_io.savemat(path, {"log": samples})
    _same_as_csv(path)
    trials = np.zeros((1, 2), dtype=[("time", object), ("acc", object), ("gyro", object)])
    trials[0, 0] = (ex[:, :1], ex[:, 1:4], ex[:, 4:7])
    trials[0, 1] = (ex[:500, :1], ex[:500, 1:4], ex[:500, 4:7])
    two = tmp_path / "trials.mat"
    scipy_io.savemat(two, {"trials": trials})
    _same_as_csv(two)


def test_a_compound_dataset_and_a_matrix_whose_columns_are_named(tmp_path):
    ex = _example()
    compound = tmp_path / "compound.h5"
    rows = np.zeros(len(ex), dtype=[(n, "f8") for n in NAMES])
    for j, name in enumerate(NAMES):
        rows[name] = ex[:, j]
    with h5py.File(compound, "w") as f:
        f["data"] = rows
    _same_as_csv(compound)
    matrix = tmp_path / "matrix.h5"  # its units per column: g and deg/s, read off them
    scaled = np.column_stack([ex[:, 0], ex[:, 1:4] / 9.80665, np.degrees(ex[:, 4:7])])
    with h5py.File(matrix, "w") as f:
        f["imu"] = scaled
        f["imu"].attrs["columns"] = ["t", "ax", "ay", "az", "gx", "gy", "gz"]
        f["imu"].attrs["units"] = ["s", "g", "g", "g", "deg/s", "deg/s", "deg/s"]
    rec, _ = open_recording(matrix).load()
    np.testing.assert_allclose(rec.acc, ex[:, 1:4], rtol=1e-14)
    np.testing.assert_allclose(rec.gyro, ex[:, 4:7], rtol=1e-14)


def _pickled(names: list[str]) -> np.bytes_:
    return np.bytes_(pickle.dumps(names, protocol=0))


def test_pandas_hdfstore_fixed_and_table_formats(tmp_path):
    """df.to_hdf(path, key="imu") and the same with format="table", the index the time
    (df.set_index("time")) and a column of datetime64[ns] beside it."""
    ex = _example()
    fixed = tmp_path / "fixed.h5"
    with h5py.File(fixed, "w") as f:
        g = f.create_group("imu")
        g.attrs.update({"pandas_type": np.bytes_(b"frame"), "nblocks": np.int64(1),
                        "ndim": np.int64(2)})
        g["axis0"] = np.array([n.encode() for n in NAMES[1:]])
        g["axis1"] = ex[:, 0]
        g["axis1"].attrs.update({"kind": np.bytes_(b"float"), "name": np.bytes_(b"time")})
        g["block0_items"] = np.array([n.encode() for n in NAMES[1:]])
        g["block0_values"] = ex[:, 1:]
    _same_as_csv(fixed)
    table = tmp_path / "table.h5"
    stamp = 1714521600 * 10**9 + np.round(ex[:, 0] * 100).astype(np.int64) * 10**7
    with h5py.File(table, "w") as f:
        g = f.create_group("imu")
        g.attrs.update({"pandas_type": np.bytes_(b"frame_table"),
                        "info": np.bytes_(pickle.dumps({"index": {"index_name": "n"}},
                                                       protocol=0))})
        rows = np.zeros(len(ex), dtype=[("index", "<i8"), ("values_block_0", "<f8", (7,)),
                                        ("values_block_1", "<i8", (1,))])
        rows["index"] = np.arange(len(ex))
        rows["values_block_0"] = ex[:, [1, 2, 3, 4, 5, 6, 0]]
        rows["values_block_1"] = stamp[:, None]
        g["table"] = rows
        g["table"].attrs.update({
            "values_block_0_kind": _pickled(["acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y",
                                             "gyro_z", "seconds"]),
            "values_block_1_kind": _pickled(["stamp"]),
            "values_block_1_dtype": np.bytes_(b"datetime64[ns]"),
            "index_kind": np.bytes_(b"integer")})
    acc, gyro, dt, _ = _samples(table, time_column="stamp")
    want = _samples(EXAMPLE)
    np.testing.assert_array_equal(acc, want[0])
    np.testing.assert_array_equal(gyro, want[1])
    np.testing.assert_allclose(dt, want[2], atol=5e-7)  # epoch seconds: steps of 2.4e-7 s
    from testbenches.reader import open_table

    opened = open_table(table)
    assert opened.header == ["n", "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z",
                             "seconds", "stamp"]
    assert opened.units[-1] == "datetime"
    assert opened.read([8])[0, 0] == 1714521600.0  # seconds since 1970, whole


def test_names_pickled_with_code_are_not_run(tmp_path):
    """pandas keeps a table's names pickled: a pickle that names a function is not loaded
    (the columns get their field's names), so a file cannot run code."""
    ex = _example()
    path = tmp_path / "evil.h5"
    marker = tmp_path / "ran"
    evil = (b"cos\nsystem\n(V" + f"touch {marker}".encode() + b"\ntR.")
    with h5py.File(path, "w") as f:
        g = f.create_group("imu")
        g.attrs["pandas_type"] = np.bytes_(b"frame_table")
        rows = np.zeros(len(ex), dtype=[("values_block_0", "<f8", (7,))])
        rows["values_block_0"] = ex[:, :7]
        g["table"] = rows
        g["table"].attrs["values_block_0_kind"] = np.bytes_(evil)
    with pytest.raises(RecordingError, match="values_block_0_1, values_block_0_2"):
        open_recording(path)
    assert not marker.exists()


def test_arrays_of_another_length_are_said_where_a_sensor_is_missing(tmp_path):
    ex = _example()
    path = tmp_path / "rates.h5"
    with h5py.File(path, "w") as f:
        f["acc"] = np.repeat(ex[:, 1:4], 2, axis=0)
        f["acc_time"] = np.arange(2 * len(ex)) * 0.005
        f["gyro"] = ex[:, 4:7]
    with pytest.raises(RecordingError, match=r"no column for gyro_x, gyro_y, gyro_z: .*"
                       r"\(1 array\(s\) of another length than the 2000 samples left out: "
                       r"gyro \(1000, 3\)\)"):
        open_recording(path)


def test_two_sensors_alike_are_refused_naming_both(tmp_path):
    ex = _example()
    path = tmp_path / "two.h5"
    with h5py.File(path, "w") as f:
        for imu in ("imu0", "imu1"):
            f[f"{imu}/time"] = ex[:, 0]
            f[f"{imu}/acc"] = ex[:, 1:4]
            f[f"{imu}/gyro"] = ex[:, 4:7]
    with pytest.raises(RecordingError, match=r"2 columns' names fit acc_x alike \(columns 1 "
                       r"'imu0/acc_x', 8 'imu1/acc_x'\)"):
        open_recording(path)
    columns = {f"{q}_{a}": f"imu1/{q}_{a}" for q in ("acc", "gyro") for a in "xyz"}
    _same_as_csv(path, columns={**columns, "time": "imu1/time"})


def test_a_matrix_of_unnamed_columns_is_refused_naming_its_columns(tmp_path):
    ex = _example()
    path = tmp_path / "matrix.mat"
    scipy_io.savemat(path, {"data": ex[:, :7]})
    with pytest.raises(RecordingError, match=r"the header has data_1, data_2, data_3, data_4, "
                                             r"data_5, data_6, data_7; .* --column"):
        open_recording(path)
    columns = dict(zip(NAMES[:7], (f"data_{j}" for j in range(1, 8)), strict=True))
    _same_as_csv(path, columns=columns)


def test_matlab_class_objects_are_refused_saying_how_to_save_them(tmp_path):
    from scipy.io.matlab import MatlabOpaque

    from testbenches.array_files import _mat_found, _table
    from testbenches.table import TableError

    path = _matlab_v73(tmp_path / "tt.mat", {})
    with h5py.File(path, "r+") as f:
        del f["label"]
        tt = f.create_dataset("TT", data=np.zeros((1, 6), dtype=np.uint32))
        tt.attrs["MATLAB_class"] = np.bytes_(b"timetable")
        tt.attrs["MATLAB_object_decode"] = np.int32(3)
        f["#subsystem#/MCOS"] = np.zeros(100)
    with pytest.raises(RecordingError, match=r"TT is a MATLAB timetable, an object only MATLAB "
                       r"reads, .* writetimetable\(TT, 'FILE.csv'\)"):
        open_recording(path)
    table = np.empty((1,), dtype=[("s0", "O"), ("s1", "O"), ("s2", "O"), ("arr", "O")])
    table[0] = (b"T", b"MCOS", b"table", None)  # scipy's opaque object, as loadmat gives it
    with pytest.raises(TableError, match=r"T is a MATLAB table, .* writetable\(T, 'FILE.csv'\)"):
        _table(tmp_path / "t.mat", "mat", _mat_found({"T": table.view(MatlabOpaque)}))


def test_a_damaged_hdf5_file_is_refused_naming_the_array_and_rows(tmp_path):
    """A changed byte in a compressed chunk (h5py: "filter returned failure during read",
    naming neither file nor dataset), and links to nothing beside the arrays (a traceback)."""
    ex = _example()
    path = tmp_path / "damaged.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("time", data=ex[:, 0], chunks=(100,), compression="gzip")
        f.create_dataset("acc", data=ex[:, 1:4], chunks=(100, 3), compression="gzip")
        f.create_dataset("gyro", data=ex[:, 4:7], chunks=(100, 3), compression="gzip")
        f["old"] = h5py.SoftLink("/nowhere")
        f["elsewhere"] = h5py.ExternalLink("missing.h5", "/x")
        chunk = f["gyro"].id.get_chunk_info(0)
    _same_as_csv(path)
    with path.open("r+b") as f:
        f.seek(chunk.byte_offset + chunk.size // 2)
        f.write(b"\xff\x00\xff\x00")
    with pytest.raises(RecordingError, match=r"damaged.h5: gyro, rows 1 to \d+, does not read "
                       r"\(.*\): the file is damaged"):
        open_recording(path, gyro_unit="rad/s").load()


def test_an_imu_and_a_motion_capture_at_their_own_rates_in_one_file(tmp_path, capsys):
    """Arrays of two lengths: the recording takes those that hold the IMU, the reference those
    that hold the pose, though the motion capture's are more (the arrays the most share were
    taken: "no column for acc_x ... 3 array(s) of another length left out: imu/acc ...")."""
    from testbenches.cli import main

    ex = _example()
    truth = np.genfromtxt(REPO / "examples" / "tilt_motion_truth.csv", delimiter=",",
                          names=True)
    half = 0.5
    cr, sr = np.cos(half * truth["roll"]), np.sin(half * truth["roll"])
    cp, sp = np.cos(half * truth["pitch"]), np.sin(half * truth["pitch"])
    cy, sy = np.cos(half * truth["yaw"]), np.sin(half * truth["yaw"])
    quat = {"q_w": cr * cp * cy + sr * sp * sy, "q_x": sr * cp * cy - cr * sp * sy,
            "q_y": cr * sp * cy + sr * cp * sy, "q_z": cr * cp * sy - sr * sp * cy}
    path = tmp_path / "both.h5"
    with h5py.File(path, "w") as f:
        f["imu/time"] = ex[:, 0]
        f["imu/acc"] = ex[:, 1:4]
        f["imu/gyro"] = ex[:, 4:7]
        f["mocap/time"] = truth["time"][::2]
        for name, values in quat.items():
            f[f"mocap/{name}"] = values[::2]
    _same_as_csv(path)
    assert main(["estimate", str(path), "--estimator", "kf", "--reference", str(path),
                 "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    row = next(r for r in capsys.readouterr().out.splitlines() if r.startswith("kf "))
    assert float(row.split()[2]) == pytest.approx(0.5996, abs=0.002)  # the CSV's: 0.5996


def test_a_sensors_three_columns_mapped_at_once(tmp_path, capsys):
    """--column acc=NAME maps NAME_x, NAME_y, NAME_z (as the header spells them), acc=X,Y,Z
    three names: a Simulink "Structure With Time" log's values_1 ... values_6 and one of two
    IMUs in three options instead of seven."""
    from testbenches.cli import main
    from testbenches.fit.recording import parse_columns

    ex = _example()
    simulink = tmp_path / "simout.mat"
    scipy_io.savemat(simulink, {"simout": {"time": ex[:, :1], "signals": {
        "values": ex[:, 1:7], "dimensions": 6, "label": "imu"}, "blockName": "m/To Workspace"}})
    columns = parse_columns(["acc=values_1,values_2,values_3", "gyro=values_4, values_5, "
                             "values_6"])
    _same_as_csv(simulink, columns=columns)
    two = tmp_path / "two.h5"
    with h5py.File(two, "w") as f:
        for imu in ("imu0", "imu1"):
            f[f"{imu}/time"] = ex[:, 0]
            f[f"{imu}/acc"] = ex[:, 1:4] * (1.0 if imu == "imu1" else 2.0)
            f[f"{imu}/gyro"] = ex[:, 4:7]
    _same_as_csv(two, columns=parse_columns(["acc=imu1/acc", "gyro=imu1/gyro",
                                             "time=imu1/time"]))
    assert main(["estimate", str(simulink), "--column", "acc=values_1,values_2", "--out",
                 str(tmp_path)]) == 2
    assert ("--column 'acc=values_1,values_2': a sensor's columns are one name (acc=NAME, for "
            "NAME_x, NAME_y, NAME_z) or three (acc=X,Y,Z)") in capsys.readouterr().err


def test_a_table_of_text_named_as_a_workbook_is_read_and_a_web_page_refused(tmp_path):
    """An export that names its CSV or tab-separated table .xls (so that a spreadsheet opens
    it) was refused as a workbook by its name alone; it is read as the text it is, and says
    so. A web page's table so named, an old workbook (OLE2) and a zip archive are still
    refused, saying to save the sheet as CSV."""
    text = EXAMPLE.read_bytes()
    for suffix, content in ((".xls", text), (".xls", text.replace(b",", b"\t")),
                            (".xlsx", text), (".ods", text)):
        path = tmp_path / f"export{suffix}"
        path.write_bytes(content)
        source = open_recording(path, gyro_unit="rad/s")
        assert f"named {suffix} but text: read as text" in source.choices
        _same_as_csv(path)
    for name, content in (("page.xls", b"<html><table><tr><td>time</td></tr></table></html>\n"),
                          ("old.xls", b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + bytes(600))):
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(RecordingError,
                           match=r"a spreadsheet workbook .* save the sheet as CSV"):
            open_recording(path)


def test_a_file_under_another_formats_suffix_is_read_as_what_it_holds(tmp_path):
    """A CSV saved as .h5, .mat, .parquet or .feather was refused in the named format's words
    ("file signature not found"), a MATLAB file saved as .csv as text ("no delimiter
    splits ..."), an Arrow file as .parquet as Parquet, HDF5 after a user block of 8 kB as
    .dat as text ("line 1 reads '\\x00\\x00...'"): the first bytes decide, the suffix only where
    they name no format."""
    import pyarrow as pa
    import pyarrow.feather as feather

    ex = _example()
    text = EXAMPLE.read_bytes()
    for suffix in (".h5", ".mat", ".parquet", ".feather"):
        path = tmp_path / f"renamed{suffix}"
        path.write_bytes(text)
        source = open_recording(path, gyro_unit="rad/s")
        assert f"named {suffix} but text: read as text" in source.choices
        _same_as_csv(path)
    mat = tmp_path / "matlab.csv"
    scipy_io.savemat(tmp_path / "m.mat", {"time": ex[:, 0], "acc": ex[:, 1:4],
                                         "gyro": ex[:, 4:7]})
    mat.write_bytes((tmp_path / "m.mat").read_bytes())
    _same_as_csv(mat)
    arrow = tmp_path / "arrow.parquet"
    feather.write_feather(pa.table(dict(zip(NAMES[:7], ex[:, :7].T, strict=True))), arrow)
    _same_as_csv(arrow)
    v73 = _matlab_v73(tmp_path / "v73.dat", {"time": ex[:, 0], "acc": ex[:, 1:4],
                                              "gyro": ex[:, 4:7]})
    _same_as_csv(v73)
    block = tmp_path / "userblock.dat"  # HDF5 after a user block of another size than MATLAB's
    with h5py.File(block, "w", userblock_size=8192) as f:
        f["time"], f["acc"], f["gyro"] = ex[:, 0], ex[:, 1:4], ex[:, 4:7]
    _same_as_csv(block)
