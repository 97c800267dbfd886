"""Files as loggers write them: the column names of ROS, phone apps and microcontroller
sketches, a preamble or comments before the header, numpy's commented header, no header at all,
a line after the table, and the accelerometer and gyro on rows of their own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from testbenches.fit.recording import RecordingError, open_recording

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"
HEADER = "ax,ay,az,gx,gy,gz"


def _example() -> tuple[np.ndarray, np.ndarray]:
    """The example's time [s] and its six IMU columns."""
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    return data[:, 0], data[:, 1:7]


def _write(path: Path, time_name: str, t: np.ndarray, imu: np.ndarray) -> Path:
    np.savetxt(path, np.column_stack([t, imu]), delimiter=",", header=f"{time_name},{HEADER}",
               comments="", fmt="%.10g")
    return path


@pytest.mark.parametrize("header", [
    "%time,field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z,"
    "field.angular_velocity.x,field.angular_velocity.y,field.angular_velocity.z",  # ROS topic
    "Time,AccX,AccY,AccZ,GyroX,GyroY,GyroZ",
    "timeStamp,accelX,accelY,accelZ,rotationRateX,rotationRateY,rotationRateZ",
    "timestamp,accelerometerAccelerationX,accelerometerAccelerationY,"
    "accelerometerAccelerationZ,gyro_x,gyro_y,gyro_z",  # iOS SensorLog
    "time,AcX,AcY,AcZ,GyX,GyY,GyZ",  # the Arduino MPU-6050 example's names
])
def test_the_names_loggers_give_their_columns_are_found(tmp_path, header):
    """The column names of a ROS topic's CSV, microcontroller sketches and phone apps."""
    t, imu = _example()
    path = tmp_path / "named.csv"
    np.savetxt(path, np.column_stack([t, imu]), delimiter=",", header=header, comments="",
               fmt="%.10g")
    source = open_recording(path)
    names = header.split(",")
    assert source.rate == pytest.approx(100.0)
    assert f"acc_x={names[1]!r}" in source.choices and f"gyro_z={names[6]!r}" in source.choices


def test_the_arduino_examples_raw_counts_are_named_for_what_they_are(tmp_path):
    """The Arduino MPU-6050 example prints AcX..GyZ as the converter's counts (16384 per g at
    +-2 g, 131 per deg/s at +-250 deg/s) beside its temperature: no column was found ("no
    column for acc_x, ..."); they are, the counts are refused as counts naming --counts, and
    with it they are read (the gyro's scale checked against the data as a unit is)."""
    t, imu = _example()
    counts = np.column_stack([t * 1e3, imu[:, :3] / 9.80665 * 16384, np.full(len(t), 3000.0),
                              np.degrees(imu[:, 3:]) * 131.0])
    path = tmp_path / "sketch.csv"
    np.savetxt(path, np.round(counts), delimiter=",", comments="", fmt="%d",
               header="millis,AcX,AcY,AcZ,Tmp,GyX,GyY,GyZ")
    with pytest.raises(RecordingError, match="that is about 16384, a MEMS part's raw counts "
                                             r"per g .*give --counts PER_G,PER_DPS"):
        open_recording(path)
    # --counts reads them: the gyro's scale checked against the data, wrong counts refused
    source = open_recording(path, counts=(16384.0, 131.0))
    assert ("acc in g (from its counts, 16384 per g, --counts); gyro in deg/s (from its "
            "counts, 131 per deg/s, --counts, and the data agree)") in source.choices
    rec, _ = source.load()
    np.testing.assert_allclose(rec.acc, imu[:, :3], atol=9.80665 / 16384)
    np.testing.assert_allclose(rec.gyro, imu[:, 3:], atol=np.radians(1 / 131.0))
    with pytest.raises(RecordingError, match=r"median norm is 78.46 m/s2 in the unit g \(from "
                                             r"its counts, 2048 per g, --counts\), .* about "
                                             r"1.639e\+04 counts per g \(16384: give --counts "
                                             r"16384,...\)"):
        open_recording(path, counts=(2048.0, 131.0))
    with pytest.raises(RecordingError, match=r"the gyro's counts per deg/s \(16.4, --counts\) "
                                             "contradict the data"):
        open_recording(path, counts=(16384.0, 16.4))
    with pytest.raises(RecordingError, match="leave --acc-unit and --gyro-unit out"):
        open_recording(path, counts=(16384.0, 131.0), gyro_unit="deg/s")
    stated = tmp_path / "stated.csv"
    stated.write_text(path.read_text().replace("AcX,AcY,AcZ", "AcX (g),AcY (g),AcZ (g)", 1))
    with pytest.raises(RecordingError, match=r"--counts is given, but the header states the "
                                             r"unit\(s\) g"):
        open_recording(stated, counts=(16384.0, 131.0))


@pytest.mark.parametrize("before", [
    "# Logged by MyLogger v1.2\n# sensor: MPU6050 at 100 Hz\n#\n",
    "Device,MPU6050\nRate,100\n\n",
    "// firmware 2.1\nstarted 2024-05-01 12:00\n",
])
def test_lines_before_the_header_are_skipped_and_said(tmp_path, before):
    """A logger's preamble (comments, a device and its settings as key,value rows, free
    text): the table starts at the first line whose cells the rows after it share, and the
    choices say which lines were skipped; the samples are those of the plain file."""
    plain = open_recording(EXAMPLE).load()[0]
    path = tmp_path / "preamble.csv"
    path.write_text(before + EXAMPLE.read_text())
    source = open_recording(path)
    rec, _ = source.load()
    header_line = before.count("\n") + 1
    assert f"the header on line {header_line}, line" in source.choices
    np.testing.assert_array_equal(rec.acc, plain.acc)
    np.testing.assert_array_equal(rec.dt, plain.dt)


def test_numpys_commented_header_is_the_header_and_a_file_without_one_is_refused(tmp_path):
    """np.savetxt(header=...) writes "# time,acc_x,...": that is the header where its cells are
    the rows'. Without any header the first row's numbers are no names: refused, saying so."""
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    path = tmp_path / "saved.csv"
    np.savetxt(path, data, delimiter=",", header=EXAMPLE.read_text().splitlines()[0])
    assert path.read_text().startswith("# time,")
    rec, _ = open_recording(path).load()
    np.testing.assert_array_equal(rec.acc, open_recording(EXAMPLE).load()[0].acc)
    bare = tmp_path / "bare.csv"
    np.savetxt(bare, data, delimiter=",")
    with pytest.raises(RecordingError, match="line 1: numbers where a header row naming the "
                       "columns belongs"):
        open_recording(bare)


@pytest.mark.parametrize("footer", ["END OF LOG\n", "END OF LOG", "Total: 1000 samples\r\n\n"])
def test_a_line_of_text_after_the_table_is_left_out_as_a_footer(tmp_path, footer):
    """A summary line a logger appends ("END OF LOG") is no sample: it was refused; it is left
    out, naming it."""
    path = tmp_path / "trailer.csv"
    path.write_text(EXAMPLE.read_text() + footer, newline="")
    whole, _ = open_recording(EXAMPLE).load()
    opened = open_recording(path)
    rec, _ = opened.load()
    np.testing.assert_array_equal(rec.gyro, whole.gyro)
    assert rec.valid.all()
    assert (f"line 1002, the last, is text after the table ({footer.strip()!r}): left out as a "
            "footer") in opened.choices


def test_a_text_column_s_last_row_is_no_footer(tmp_path):
    """A row with a text column (a status) has the header's width: read, not left out."""
    lines = EXAMPLE.read_text().splitlines()
    path = tmp_path / "status.csv"
    path.write_text("\n".join([lines[0] + ",status"] + [x + ",OK" for x in lines[1:]]))
    whole, _ = open_recording(EXAMPLE).load()
    opened = open_recording(path)
    rec, _ = opened.load()
    np.testing.assert_array_equal(rec.gyro, whole.gyro)
    assert "footer" not in opened.choices


def test_accelerometer_and_gyro_on_rows_of_their_own_are_joined(tmp_path):
    """A logger that writes each sensor's reading as it comes (the gyro 4 ms after the
    accelerometer): each gyro row is a sample with the accelerometer's latest row, so the
    samples are the example's own, in blocks of any size. Without a time column nothing joins
    them: refused, saying why."""
    t, imu = _example()
    rows = np.full((2 * len(t), 7), np.nan)
    rows[0::2, 0], rows[0::2, 1:4] = t, imu[:, :3]
    rows[1::2, 0], rows[1::2, 4:7] = t + 0.004, imu[:, 3:]
    path = tmp_path / "interleaved.csv"
    np.savetxt(path, rows, delimiter=",", header="time," + HEADER, comments="", fmt="%.17g")
    plain = _write(tmp_path / "plain.csv", "time", t, imu)
    want, _ = open_recording(plain).load()
    source = open_recording(path)
    assert "the accelerometer and the gyro on rows of their own" in source.choices
    for size in (None, 7):
        parts = list(source.blocks(rows=size))
        for name in ("acc", "gyro"):
            got = np.concatenate([getattr(p, name) for p, _ in parts])
            np.testing.assert_array_equal(got, getattr(want, name))
        np.testing.assert_allclose(np.concatenate([p.dt for p, _ in parts]), want.dt,
                                   atol=1e-12)  # the 4 ms shift rounds the times apart
        np.testing.assert_allclose(np.concatenate([tt for _, tt in parts]), t + 0.004)
    no_time = tmp_path / "no_time.csv"
    np.savetxt(no_time, rows[:, 1:], delimiter=",", header=HEADER, comments="", fmt="%.17g")
    with pytest.raises(RecordingError, match=r"on rows of their own .* a time column joins "
                       "them"):
        open_recording(no_time, rate=100.0)


def test_milli_g_and_milli_deg_per_s_are_found_and_raw_counts_refused_with_why(tmp_path):
    """ST's sensors give mg and mdps: found from the norm and from the turn, the samples those
    of the example in SI. Raw counts (16384 per g) are no unit: refused, saying what they are."""
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    g = 9.80665
    plain = open_recording(EXAMPLE).load()[0]
    milli = tmp_path / "milli.csv"
    np.savetxt(milli, np.column_stack([data[:, 0], data[:, 1:4] / g * 1e3,
                                       np.degrees(data[:, 4:7]) * 1e3]),
               delimiter=",", header="time," + HEADER, comments="", fmt="%.17g")
    source = open_recording(milli)
    rec, _ = source.load()
    assert "acc in mg (from its median norm" in source.choices
    assert "gyro in mdps (from the data" in source.choices
    np.testing.assert_allclose(rec.acc, plain.acc, rtol=1e-12)
    np.testing.assert_allclose(rec.gyro, plain.gyro, rtol=1e-12, atol=1e-15)
    counts = tmp_path / "counts.csv"
    np.savetxt(counts, np.column_stack([data[:, 0], np.round(data[:, 1:4] / g * 16384),
                                        np.round(np.degrees(data[:, 4:7]) * 131)]),
               delimiter=",", header="time," + HEADER, comments="", fmt="%.10g")
    with pytest.raises(RecordingError, match="about 16384, a MEMS part's raw counts per g"):
        open_recording(counts)


@pytest.mark.parametrize("compress", ["gzip", "bz2", "lzma"])
def test_a_compressed_file_reads_as_the_text_it_holds(tmp_path, compress):
    """Datasets and long logs ship as .csv.gz (.bz2, .xz): the same samples to the bit, and a
    bad cell still named by its line."""
    import importlib

    module = importlib.import_module(compress)
    text = EXAMPLE.read_text()
    path = tmp_path / "example.csv.z"
    with module.open(path, "wt") as f:
        f.write(text)
    rec, _ = open_recording(path).load()
    plain, _ = open_recording(EXAMPLE).load()
    np.testing.assert_array_equal(rec.acc, plain.acc)
    np.testing.assert_array_equal(rec.dt, plain.dt)
    lines = text.splitlines()
    cells = lines[500].split(",")
    lines[500] = ",".join([cells[0], "abc", *cells[2:]])
    with module.open(path, "wt") as f:
        f.write("\n".join(lines))
    assert "the first: line 501, column 'acc_x': 'abc' is not a number" in _no_row(path)


@pytest.mark.parametrize("name,content,serves", [
    ("book.xlsx", b"PK\x03\x04 a workbook", "save the sheet as CSV"),
    ("export.json", b'[{"sensor": "Accelerometer", "x": "0.1"}]', "export the recording as CSV"),
    ("00000042.BIN", b"\xa3\x95\x80\x80" + bytes(64), "an ArduPilot DataFlash log.*"
     "mavlogdump.py --types IMU --format csv"),
])
def test_a_workbook_or_json_is_refused_saying_what_serves(tmp_path, name, content, serves):
    """Files that are no table, told by their first bytes: refused saying what would serve
    (a flight controller's binary log was read as text: 'no delimiter splits a header')."""
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(RecordingError, match=serves):
        open_recording(path)


def _motive(path: Path) -> Path:
    """The example's truth as OptiTrack Motive exports a rigid body: a settings line, a blank
    line, then the header on five rows (type, name, id, Rotation/Position over X, Y, Z, W), in
    Motive's y-up world."""
    truth = np.genfromtxt(REPO / "examples" / "tilt_motion_truth.csv", delimiter=",",
                          names=True)
    r, p = truth["roll"] / 2, truth["pitch"] / 2
    qw, qx, qy, qz = (np.cos(r) * np.cos(p), np.sin(r) * np.cos(p), np.cos(r) * np.sin(p),
                      -np.sin(r) * np.sin(p))
    c, s = np.cos(-np.pi / 4), np.sin(-np.pi / 4)  # the z-up world turned -90 deg about x
    quat = np.column_stack([c * qx + s * qw, c * qy - s * qz, c * qz + s * qy, c * qw - s * qx])
    lines = ["Format Version,1.23,Take Name,Take 1,Capture Frame Rate,100.000000,Rotation Type,"
             "Quaternion,Length Units,Meters,Coordinate Space,Global", "",
             ",,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body",
             ",,imu,imu,imu,imu,imu,imu,imu", ",,1,1,1,1,1,1,1",
             ",,Rotation,Rotation,Rotation,Rotation,Position,Position,Position",
             "Frame,Time (Seconds),X,Y,Z,W,X,Y,Z"]
    lines += [f"{i},{t:.6f}," + ",".join(f"{v:.8f}" for v in q) + ",0.1,1.0,0.2"
              for i, (t, q) in enumerate(zip(truth["time"], quat, strict=True))]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_motion_capture_export_with_its_header_on_rows_is_a_reference(tmp_path, capsys):
    """OptiTrack Motive writes its header on five rows: the quaternion's columns are named X, Y,
    Z, W under "Rotation". The stacked rows name them "Rotation X" ...; its y-up world is found
    as any other; scored, it gives what the truth file gives."""
    from testbenches.cli import main

    scores = []
    for reference in (REPO / "examples" / "tilt_motion_truth.csv", _motive(tmp_path / "m.csv")):
        assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference",
                     str(reference), "--no-plots", "--out", str(tmp_path)]) == 0
        said = capsys.readouterr().out
        scores.append(float(next(r for r in said.splitlines() if r.startswith("kf ")).split()[2]))
    assert "world frame's up is +y" in said
    assert scores[1] == pytest.approx(scores[0], abs=1e-3)


@pytest.mark.parametrize("where", ["below", "above"])
def test_a_row_of_units_beside_the_names_states_them(tmp_path, where):
    """A logger's (or Vicon's) row of units under or over the names: the units, not a row of
    data, and not part of the names."""
    t, imu = _example()
    names, units = "time," + HEADER, "s,g,g,g,deg/s,deg/s,deg/s"
    rows = "\n".join(",".join(f"{v:.10g}" for v in row)
                     for row in np.column_stack([t, imu[:, :3] / 9.80665, np.degrees(imu[:, 3:])]))
    head = f"{names}\n{units}" if where == "below" else f"{units}\n{names}"
    path = tmp_path / "units.csv"
    path.write_text(f"{head}\n{rows}\n")
    source = open_recording(path)
    assert "acc in g (from the header)" in source.choices and "deg/s (from the header" in \
        source.choices
    np.testing.assert_allclose(source.load()[0].acc, imu[:, :3], rtol=1e-9)


@pytest.mark.parametrize("padded", [False, True])
def test_missing_value_marks_are_missing_in_either_reader(tmp_path, padded):
    """NULL, N/A and their kin mark a missing value: pyarrow's reader took them so, Python's
    (which reads padded cells) refused them. Both reject and count the sample now."""
    lines = EXAMPLE.read_text().splitlines()
    pad = " " if padded else ""
    for row, mark in ((5, "NULL"), (6, "N/A"), (7, "#N/A")):
        cells = lines[row].split(",")
        cells[2] = f"{pad}{mark}{pad}"
        lines[row] = ",".join(cells)
    path = tmp_path / "marks.csv"
    path.write_text("\n".join(lines))
    rec, _ = open_recording(path).load()
    assert list(np.flatnonzero(~rec.valid)) == [4, 5, 6]


@pytest.mark.parametrize("time_form", ["seconds", "time of day", "date and time"])
def test_padded_cells_are_read_by_pyarrows_reader_to_the_same_bits(tmp_path, monkeypatch,
                                                                   time_form):
    """A sketch that prints ", " between its values pads every cell: such a file went to
    Python's reader whole, four times the time of pyarrow's on a long log (400k rows: 17 s
    against 3.3 s). pyarrow's reader takes padded numbers, and padded times as text it
    trims and rewrites; the samples and times are those Python's reader gives, to the bit."""
    import testbenches.reader as reader

    t, imu = _example()
    stamps = {"seconds": [f"{v:.2f}" for v in t],
              "time of day": [f"12:00:{v:06.3f}" for v in t],
              "date and time": [f"2024-05-01 12:00:{v:06.3f}" for v in t]}[time_form]
    path = tmp_path / "padded.csv"
    path.write_text("time, " + ", ".join(HEADER.split(",")) + "\n" + "".join(
        f"{s}, " + ", ".join(f"{v:.10g}" for v in row) + "\n"
        for s, row in zip(stamps, imu, strict=True)))
    calls: list[int] = []
    python_parts = reader._python_parts
    monkeypatch.setattr(reader, "_python_parts",
                        lambda *a, **k: calls.append(1) or python_parts(*a, **k))
    arrow, arrow_t = open_recording(path, gyro_unit="rad/s").load()
    assert not calls
    monkeypatch.setattr(reader, "_has_pyarrow", lambda: False)
    python, python_t = open_recording(path, gyro_unit="rad/s").load()
    assert calls
    np.testing.assert_array_equal(arrow_t, python_t)
    for name in ("acc", "gyro", "dt"):
        np.testing.assert_array_equal(getattr(arrow, name), getattr(python, name))


def test_a_padded_header_of_quoted_names_is_read(tmp_path):
    """`"time", "acc_x", ...`: a quote after the space that pads a cell is no quote to
    Python's csv module, so the names kept their quotes and none was found ("no column for
    acc_x, ..."). The header's cells are read with the padding skipped."""
    t, imu = _example()
    path = tmp_path / "quoted.csv"
    path.write_text(", ".join(f'"{n}"' for n in ("time", *HEADER.split(","))) + "\n" + "".join(
        f"{s:.2f}, " + ", ".join(f"{v:.10g}" for v in row) + "\n"
        for s, row in zip(t, imu, strict=True)))
    source = open_recording(path, gyro_unit="rad/s")
    assert "acc_x='ax'" in source.choices and "time='time'" in source.choices


@pytest.mark.parametrize("style", ["rule", "markdown"])
def test_a_rule_under_the_header_is_no_row_of_names(tmp_path, style):
    """A serial monitor's table (a row of dashes under the names) or a Markdown one (|---|)."""
    t, imu = _example()
    rows = np.column_stack([t, imu])
    if style == "rule":
        text = "time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z\n" + ",".join(["----"] * 7) + "\n"
        text += "\n".join(",".join(f"{v:.10g}" for v in r) for r in rows)
    else:
        text = "| time | acc_x | acc_y | acc_z | gyro_x | gyro_y | gyro_z |\n" + \
            "|" + ":---|" * 7 + "\n"
        text += "\n".join("| " + " | ".join(f"{v:.10g}" for v in r) + " |" for r in rows)
    path = tmp_path / "table.txt"
    path.write_text(text + "\n")
    rec, _ = open_recording(path).load()
    np.testing.assert_allclose(rec.acc, imu[:, :3], rtol=1e-9)


def _rows(path: Path, header: str, rows: list[str], before: str = "") -> Path:
    path.write_text(before + header + "\n" + "\n".join(rows) + "\n")
    return path


def test_flight_logs_columns_with_an_index_and_a_unit_word_are_found(tmp_path):
    """PX4's sensor_combined as ulog2csv writes it ("gyro_rad[0]", "accelerometer_m_s2[0]", the
    time in us) and ArduPilot's IMU messages as mavlogdump writes them ("GyrX", "AccX" beside a
    temperature "T" and the time "timestamp"): both read as the example's samples in their
    z-down FRD frame, units from the names where they give them."""
    t, imu = _example()
    frd = imu * [1, -1, -1, 1, -1, -1]
    cells = [[f"{v:.17g}" for v in r] for r in frd]
    px4 = _rows(tmp_path / "sensor_combined.csv",
                "timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2],gyro_integral_dt,"
                "accelerometer_m_s2[0],accelerometer_m_s2[1],accelerometer_m_s2[2]",
                [",".join([str(round(ti * 1e6)), *c[3:], "10000", *c[:3]])
                 for ti, c in zip(t, cells, strict=True)])
    ardupilot = _rows(tmp_path / "imu.csv", "timestamp,TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,T",
                      [",".join([f"{ti:.17g}", str(round(ti * 1e6)), "0", *c[3:], *c[:3], "35.2"])
                       for ti, c in zip(t, cells, strict=True)])
    want = open_recording(EXAMPLE).load()[0]
    for path in (px4, ardupilot):
        source = open_recording(path)
        assert "time='timestamp'" in source.choices
        rec, _ = source.load()
        np.testing.assert_array_equal(rec.acc, frd[:, :3])
        np.testing.assert_array_equal(rec.gyro, frd[:, 3:])
        np.testing.assert_allclose(rec.dt[1:], want.dt[1:], rtol=1e-6)
    px4_choices = open_recording(px4).choices
    assert "acc in m/s2 (from the header)" in px4_choices  # "m_s2" in the name
    assert "gyro_x='gyro_rad[0]'" in px4_choices


def test_a_device_prefix_and_a_units_row_of_other_sensors_are_read_through(tmp_path):
    """Shimmer's export: Excel's "sep=" line, tab-separated quoted names that carry the device's
    name and "_CAL", a row of units that also holds another sensor's (mV), a tab closing every
    line."""
    t, imu = _example()
    names = ["Timestamp_CAL", "Accel_LN_X_CAL", "Accel_LN_Y_CAL", "Accel_LN_Z_CAL",
             "Gyro_X_CAL", "Gyro_Y_CAL", "Gyro_Z_CAL", "ECG_CAL"]
    units = ["ms", "m/(s^2)", "m/(s^2)", "m/(s^2)", "deg/s", "deg/s", "deg/s", "mV"]
    rows = ["\t".join([f"{ti * 1e3:.3f}", *(f"{v:.17g}" for v in r[:3]),
                       *(f"{np.degrees(v):.17g}" for v in r[3:]), "1.0", ""])
            for ti, r in zip(t, imu, strict=True)]
    path = _rows(tmp_path / "shimmer.csv",
                 "\t".join(f'"Shimmer_A1B2_{n}"' for n in names) + "\t\n"
                 + "\t".join(f'"{u}"' for u in units) + "\t", rows, before='"sep=\t"\n')
    source = open_recording(path)
    assert "gyro in deg/s (from the header" in source.choices
    assert "acc_x='Shimmer_A1B2_Accel_LN_X_CAL'" in source.choices
    rec, _ = source.load()
    want = open_recording(EXAMPLE).load()[0]
    np.testing.assert_allclose(rec.acc, want.acc, atol=1e-12)
    np.testing.assert_allclose(rec.gyro, want.gyro, rtol=1e-12, atol=1e-15)


def test_a_g_force_column_is_the_accelerometer_not_a_linear_acceleration(tmp_path):
    """Physics Toolbox's "Multi Record": the g-force gFx beside ax, which leaves gravity out."""
    t, imu = _example()
    rows = [",".join([f"{ti:.17g}", *(f"{v / 9.80665:.17g}" for v in r[:3]), "0.01", "0.02", "0.03",
                      *(f"{v:.17g}" for v in r[3:])]) for ti, r in zip(t, imu, strict=True)]
    path = _rows(tmp_path / "toolbox.csv", "time,gFx,gFy,gFz,ax,ay,az,wx,wy,wz", rows)
    source = open_recording(path)
    assert "acc_x='gFx'" in source.choices and "acc in g" in source.choices
    np.testing.assert_allclose(source.load()[0].acc, open_recording(EXAMPLE).load()[0].acc,
                               rtol=1e-12)


def test_a_clock_in_an_unstated_unit_is_named_and_an_index_is_no_unit(tmp_path):
    """Xsens's SampleTimeFine counts ticks of 100 us (MT Manager) or 1 us (Movella DOT): the
    refusal names it and what each is; given as us it is read. A unit "[1]" after a space
    stays a unit, where "[1]" written onto a name is an axis."""
    t, imu = _example()
    rows = [",".join([str(i), str(round(ti * 1e6)), *(f"{v:.17g}" for v in r)])
            for i, (ti, r) in enumerate(zip(t, imu, strict=True))]
    path = _rows(tmp_path / "dot.csv", "PacketCounter,SampleTimeFine,Acc_X,Acc_Y,Acc_Z,Gyr_X,"
                 "Gyr_Y,Gyr_Z", rows)
    with pytest.raises(RecordingError, match=r"'PacketCounter' counts samples.*'SampleTimeFine' "
                       r"is Xsens's clock, in ticks of 100 us .* 1 us"):
        open_recording(path)
    rec, _ = open_recording(path, time_column="SampleTimeFine", time_unit="us").load()
    np.testing.assert_allclose(rec.dt[1:], open_recording(EXAMPLE).load()[0].dt[1:], rtol=1e-6)

    from testbenches.table import split_unit

    assert split_unit("q_w [1]") == ("q_w", "1")
    assert split_unit("gyro_rad[1]") == ("gyro_rad[1]", None)

    from testbenches.fit.columns import norm_name

    # a quaternion's index is no axis: PX4's q[0] is w, Eigen's and scipy's q[0] is x
    assert norm_name("q[0]") == "q[0]" and norm_name("gyro_rad[0]") == "gyro_rad_x"


@pytest.mark.parametrize("codec,delimiter,compress", [
    ("utf-16", "\t", False),  # Excel's "Unicode Text": a byte-order mark, tabs
    ("utf-16-le", ",", False),  # no mark
    ("utf-16-be", ",", True),  # gzip'd
])
def test_a_utf16_file_reads_as_the_text_it_holds(tmp_path, codec, delimiter, compress):
    """Windows' "Unicode" (UTF-16, as Excel's Unicode Text and PowerShell's redirection write
    it) reads as the UTF-8 file does, and a bad cell is still named by its line; read as bytes
    its header was the characters between zero bytes."""
    import gzip

    text = EXAMPLE.read_text().replace(",", delimiter)
    raw = text.encode(codec)
    path = tmp_path / "unicode.txt"
    path.write_bytes(gzip.compress(raw) if compress else raw)
    rec, _ = open_recording(path).load()
    want = open_recording(EXAMPLE).load()[0]
    np.testing.assert_array_equal(rec.acc, want.acc)
    np.testing.assert_array_equal(rec.dt, want.dt)
    lines = text.splitlines(keepends=True)
    lines[5] = lines[5].replace("0.0", "x.0", 1)
    bad = tmp_path / "bad.txt"
    bad.write_bytes("".join(lines).encode(codec))
    assert "the first: line 6, column 'time': 'x.04' is not a number" in _no_row(bad)


def test_a_rate_the_preamble_states_times_a_file_without_a_time_column(tmp_path):
    """Xsens MT Manager's export: "// Update Rate: 100.0Hz" before a header of PacketCounter,
    SampleTimeFine (ticks its file does not size) and the axes; the rate times the samples and
    is said. Two rates stated, or none, leave the file without a time, refused as before; a
    time column governs where there is one."""
    _, imu = _example()
    rows = ["\t".join([str(i), str(1000 + 100 * i), *(f"{v:.17g}" for v in r)])
            for i, r in enumerate(imu)]
    header = "PacketCounter\tSampleTimeFine\tAcc_X\tAcc_Y\tAcc_Z\tGyr_X\tGyr_Y\tGyr_Z"
    path = _rows(tmp_path / "mt.txt", header, rows,
                 before="// Start Time: Unknown\n// Update Rate: 100.0Hz\n// Filter Profile: "
                        "General\n")
    source = open_recording(path)
    assert "time from the rate the file states (100 Hz)" in source.choices
    rec, _ = source.load()
    np.testing.assert_array_equal(rec.acc, open_recording(EXAMPLE).load()[0].acc)
    np.testing.assert_allclose(rec.dt[1:], 0.01)
    twice = _rows(tmp_path / "twice.txt", header, rows,
                  before="// Update Rate: 100.0Hz\n// Sample rate: 50 Hz\n")
    with pytest.raises(RecordingError, match="no time or dt column"):
        open_recording(twice)
    timed = tmp_path / "timed.csv"
    timed.write_text("# sample rate: 50 Hz\n" + EXAMPLE.read_text())
    assert "rate the file states" not in open_recording(timed).choices
    np.testing.assert_array_equal(open_recording(timed).load()[0].dt,
                                  open_recording(EXAMPLE).load()[0].dt)


@pytest.mark.parametrize("name,scale", [
    ("Elapsed time (s)", 1.0),
    ("Time since start in ms", 1e3),  # AndroSensor's
    ("seconds_elapsed", 1.0),  # Sensor Logger's
])
def test_an_elapsed_time_is_the_time(tmp_path, name, scale):
    """A time column named for the time since the start is the time, in its name's unit."""
    t, imu = _example()
    rows = [",".join([f"{ti * scale:.10g}", *(f"{v:.17g}" for v in r)])
            for ti, r in zip(t, imu, strict=True)]
    source = open_recording(_rows(tmp_path / "elapsed.csv", f"{name},{HEADER}", rows))
    assert f"time={name!r}" in source.choices
    np.testing.assert_allclose(source.load()[0].dt[1:], 0.01, rtol=1e-6)


def test_a_name_the_header_gives_twice_is_refused_not_chosen(tmp_path):
    """Two columns named acc_x (a second sensor's, or a gyro column misnamed): which one is
    meant no rule can say, so the file is refused naming both, not read from the first."""
    lines = EXAMPLE.read_text().splitlines()
    path = _rows(tmp_path / "twice.csv", lines[0] + ",acc_x", [line + ",0" for line in lines[1:]])
    with pytest.raises(RecordingError, match=r"2 columns' names fit acc_x alike \(columns 2 "
                       r"'acc_x', 9 'acc_x'\).*one name, which no --column can tell apart: "
                       r"rename them apart in the file's header"):
        open_recording(path)


@pytest.mark.parametrize("above,names,taken", [
    # a spreadsheet's merged cells: the group's name in its first cell alone
    (",Accelerometer,,,Gyroscope,,", "time,x,y,z,x,y,z", "acc_y='Accelerometer y'"),
    ("time,Accelerometer,,,Gyroscope,,", ",x,y,z,x,y,z", "gyro_z='Gyroscope z'"),
    (",Accelerometer,,,Gyroscope,,", "time,X (m/s^2),Y (m/s^2),Z (m/s^2),X (rad/s),Y (rad/s),"
     "Z (rad/s)", "gyro_y='Gyroscope Y (rad/s)'"),
    # a title, or a device's name, in the first cell, padded to the table's width
    ("IMU log,,,,,,", "time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z", "time='time'"),
    (",,,IMU log,,,", "time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z", "acc_z='acc_z'"),
    ("Device,MPU6050,,,,,", "time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z", "acc_x='acc_x'"),
])
def test_a_row_above_the_names_names_groups_only_where_the_names_repeat(tmp_path, above,
                                                                        names, taken):
    """A row of text above the names names the groups of the columns whose names repeat (x, y,
    z under "Accelerometer" and "Gyroscope", a merged cell's name written in its first cell
    and spanning the cells after it that repeat names; a name of its own, the time's, takes
    none). Above names that do not repeat it is a title or a device's name, as a spreadsheet
    pads it with commas: the names are read as they are, not the first run into it (which
    lost the time's column)."""
    t, imu = _example()
    path = _rows(tmp_path / "grouped.csv", names,
                 [",".join(f"{v:.10g}" for v in row) for row in np.column_stack([t, imu])],
                 before=above + "\n")
    source = open_recording(path)
    assert taken in source.choices and "time in s" in source.choices
    rec, _ = source.load()
    np.testing.assert_allclose(rec.acc, imu[:, :3], rtol=1e-9)
    np.testing.assert_allclose(rec.gyro, imu[:, 3:], rtol=1e-9)


def test_names_that_repeat_with_no_groups_above_are_refused_saying_what_serves(tmp_path):
    """x, y, z for the accelerometer's columns and again for the gyro's, nothing above them:
    which is which no name can say, and no --column either."""
    t, imu = _example()
    path = _rows(tmp_path / "xyz.csv", "time,x,y,z,x,y,z",
                 [",".join(f"{v:.10g}" for v in row) for row in np.column_stack([t, imu])])
    with pytest.raises(RecordingError, match=r"'x', 'y', 'z' each name more than one column, "
                       r"which no --column can tell apart: rename them apart.*\"Accelerometer\" "
                       r"over"):
        open_recording(path)


def test_a_time_that_does_not_rise_gives_way_to_one_that_does(tmp_path):
    """A logger's whole epoch seconds beside its milliseconds: the seconds repeat a hundred
    times, the milliseconds rise, so they are the time, and the choices say why. Where no other
    time rises the file is refused as before."""
    t, imu = _example()
    rows = [",".join([str(1_700_000_000 + int(ti)), f"{ti * 1e3:.0f}", *(f"{v:.17g}" for v in r)])
            for ti, r in zip(t, imu, strict=True)]
    path = _rows(tmp_path / "two.csv", f"timestamp,time_ms,{HEADER}", rows)
    source = open_recording(path)
    assert "'timestamp' does not rise from row to row, 'time_ms' does" in source.choices
    assert "time='time_ms'" in source.choices
    np.testing.assert_allclose(source.load()[0].dt[1:], 0.01, rtol=1e-9)
    alone = _rows(tmp_path / "alone.csv", f"timestamp,note,{HEADER}",
                  [",".join([row.split(",")[0], "0", *row.split(",")[2:]]) for row in rows])
    with pytest.raises(RecordingError, match="repeats"):
        open_recording(alone)


def test_a_gyro_axis_of_the_other_sign_is_found_and_given_axes_serve(tmp_path):
    """The gyro's y negated (a left-handed frame, a remap in one sensor only): every unit
    missed gravity's turn by about the turn, and with --gyro-unit given it ran 20 deg off,
    nothing said. It is refused naming the order that explains the turn, and with
    --gyro-axes x,-y,z it reads as the example."""
    lines = EXAMPLE.read_text().splitlines()
    rows = []
    for line in lines[1:]:
        cells = line.split(",")
        cells[5] = repr(-float(cells[5]))
        rows.append(",".join(cells))
    path = _rows(tmp_path / "flipped.csv", lines[0], rows)
    for unit in ("auto", "rad/s"):
        with pytest.raises(RecordingError, match=r"axes as \(x, -y, z\) in rad/s .* give "
                                                 r"--gyro-axes x,-y,z"):
            open_recording(path, gyro_unit=unit)
    source = open_recording(path, gyro_axes="x,-y,z")
    assert "its axes as the accelerometer's x, -y, z (given)" in source.choices
    np.testing.assert_array_equal(source.load()[0].gyro, open_recording(EXAMPLE).load()[0].gyro)
    with pytest.raises(RecordingError, match="each once"):
        open_recording(path, gyro_axes="x,x,z")


def _names_and_file(path: Path, header: list[str], columns: list[np.ndarray]) -> Path:
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=",".join(header),
               comments="", fmt="%.17g")
    return path


@pytest.mark.parametrize("kind", ["euroc", "plotjuggler", "sensorlog"])
def test_robotics_datasets_and_topic_exports_are_read_as_written(tmp_path, kind):
    """EuRoC's and TUM-VI's imu0/data.csv ("#timestamp [ns]", "w_RS_S_x [rad s^-1]", "a_RS_S_x
    [m s^-2]"), PlotJuggler's export of a ROS topic ("/imu/angular_velocity/x", timed by its
    "__time") and iOS SensorLog's clocks ("gyroTimestamp_sinceReboot(s)" beside its
    accelerometer's): the example's own samples, at its rate, each column named in the
    choices."""
    t, imu = _example()
    acc, gyro = imu[:, :3], imu[:, 3:]
    if kind == "euroc":
        header = ["#timestamp [ns]", *(f"w_RS_S_{a} [rad s^-1]" for a in "xyz"),
                  *(f"a_RS_S_{a} [m s^-2]" for a in "xyz")]
        cols = [np.round(1.4e18 + t * 1e9), gyro, acc]
        time = "timestamp [ns]"
    elif kind == "plotjuggler":
        header = ["__time", *(f"/imu/angular_velocity/{a}" for a in "xyz"), "/imu/header/stamp",
                  *(f"/imu/linear_acceleration/{a}" for a in "xyz"),
                  *(f"/imu/orientation/{c}" for c in "wxyz")]
        one, zero = np.ones_like(t), np.zeros_like(t)
        cols = [1.7e9 + t, gyro, 1.7e9 + t, acc, one, zero, zero, zero]
        time = "__time"  # PlotJuggler's timeline: on every row of an export of several topics
    else:
        header = ["loggingSample(N)", "accelerometerTimestamp_sinceReboot(s)",
                  *(f"accelerometerAcceleration{a}(G)" for a in "XYZ"),
                  "gyroTimestamp_sinceReboot(s)", *(f"gyroRotation{a}(rad/s)" for a in "XYZ")]
        cols = [np.arange(len(t)), 5000.0 + t, -acc / 9.80665, 5000.001 + t, gyro]
        time = "gyroTimestamp_sinceReboot(s)"
    source = open_recording(_names_and_file(tmp_path / f"{kind}.csv", header, cols))
    rec, _ = source.load()
    assert source.rate == pytest.approx(100.0)
    assert f"time={time!r}" in source.choices
    assert "gyro in rad/s" in source.choices and "acc in " in source.choices
    np.testing.assert_allclose(rec.acc, acc, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(rec.gyro, gyro, rtol=1e-12)
    np.testing.assert_allclose(rec.dt[1:], np.diff(t), atol=1e-6)


def test_a_ros_messages_own_stamp_is_the_time_not_when_it_was_received(tmp_path):
    """rostopic's CSV holds when the bag received each message ("%time") beside the message's
    own stamp ("field.header.stamp", both in ns). Messages arrive in bursts (here four at a
    time over USB, each a little later): the receive time would integrate the gyro over steps
    of 0 and 40 ms. The stamp is the time."""
    t, imu = _example()
    stamp = np.round(1.6e18 + t * 1e9)
    received = stamp[(np.arange(len(t)) // 4) * 4 + 3] + 2e6 + np.arange(len(t)) % 4 * 1e3
    header = ["%time", "field.header.seq", "field.header.stamp",
              *(f"field.angular_velocity.{a}" for a in "xyz"),
              *(f"field.linear_acceleration.{a}" for a in "xyz")]
    path = _names_and_file(tmp_path / "ros.csv", header,
                           [received, np.arange(len(t)), stamp, imu[:, 3:], imu[:, :3]])
    source = open_recording(path)
    assert "time='field.header.stamp'" in source.choices
    np.testing.assert_allclose(source.load()[0].dt[1:], np.diff(t), atol=1e-6)


def test_a_euroc_or_ros_ground_truth_is_a_reference(tmp_path, capsys):
    """A reference as robotics datasets and ROS write it: EuRoC's state_groundtruth_estimate0
    ("q_RS_w []": a unit left empty), a motion-capture TransformStamped ("transform.rotation")
    and a PoseStamped ("pose.orientation"). Scored, each gives what the truth file gives."""
    from scipy.spatial.transform import Rotation

    from testbenches.cli import main

    truth = np.genfromtxt(REPO / "examples" / "tilt_motion_truth.csv", delimiter=",",
                          names=True)
    xyzw = Rotation.from_euler("xyz", np.column_stack(
        [truth["roll"], truth["pitch"], truth["yaw"]])).as_quat()
    t = truth["time"]
    files = {
        "euroc.csv": (["#timestamp", "p_RS_R_x [m]", *(f"q_RS_{c} []" for c in "wxyz"),
                       "b_w_RS_S_x [rad s^-1]"],
                      [t, 0 * t, xyzw[:, 3], xyzw[:, :3], 0 * t + 0.02]),
        "vicon.csv": (["%time", "field.header.stamp", "field.transform.translation.x",
                       *(f"field.transform.rotation.{c}" for c in "xyzw")],
                      [t + 1e-4, t, 0 * t, xyzw]),
        "pose.csv": (["%time", "field.header.stamp", "field.pose.position.x",
                      *(f"field.pose.orientation.{c}" for c in "xyzw")],
                     [t + 1e-4, t, 0 * t, xyzw]),
    }
    scores = []
    for name, (header, cols) in {"truth": (None, None), **files}.items():
        reference = (REPO / "examples" / "tilt_motion_truth.csv" if header is None
                     else _names_and_file(tmp_path / name, header, cols))
        assert main(["estimate", str(EXAMPLE), "--estimator", "kf", "--reference",
                     str(reference), "--no-plots", "--out", str(tmp_path / "out")]) == 0
        said = capsys.readouterr().out
        scores.append(float(next(r for r in said.splitlines() if r.startswith("kf ")).split()[2]))
    assert scores[1:] == pytest.approx([scores[0]] * 3, abs=1e-3)


def test_two_topics_with_the_same_field_are_refused_naming_both(tmp_path):
    """PlotJuggler's export of two IMU topics: "/imu/data/angular_velocity/x" and
    "/imu/data_raw/angular_velocity/x" are the same field; which one is meant no rule can say,
    so the file is refused naming both and how to give the one meant."""
    t, imu = _example()
    header = ["__time", *(f"/imu/{topic}/{field}/{a}" for topic in ("data", "data_raw")
                          for field in ("angular_velocity", "linear_acceleration")
                          for a in "xyz")]
    cols = [t, imu[:, 3:], imu[:, :3], imu[:, 3:], imu[:, :3]]
    path = _names_and_file(tmp_path / "two.csv", header, cols)
    with pytest.raises(RecordingError, match=r"2 columns' names fit acc_x alike \(columns 5 "
                       r"'/imu/data/linear_acceleration/x', 11 "
                       r"'/imu/data_raw/linear_acceleration/x'\).*--column acc_x=NAME"):
        open_recording(path)
    given = {f"{s}_{a}": f"/imu/data/{f}/{a}" for s, f in (("acc", "linear_acceleration"),
                                                            ("gyro", "angular_velocity"))
             for a in "xyz"}
    rec, _ = open_recording(path, columns=given).load()
    np.testing.assert_array_equal(rec.acc, imu[:, :3])


@pytest.mark.parametrize("kind", ["time", "dt"])
def test_rows_of_another_topic_take_no_time_from_the_samples(tmp_path, kind):
    """A merged export (PlotJuggler's of several topics, a union of timetables) writes the
    rows of another sensor between the IMU's, their IMU cells empty. Each such row is a sample
    the estimators reject and count, and the next sample's dt spans it: the samples' dt are the
    IMU's own (with dt from one row to the next, every IMU row lost the time since the other
    topic's row, and the recording ran tens of degrees off)."""
    t, imu = _example()
    other = t[:-1] + 0.0037  # a 2nd topic's row between each two IMU rows
    times = np.concatenate([t, other])
    order = np.argsort(times, kind="stable")
    rows = np.full((len(times), 7), np.nan)
    rows[:len(t), 1:] = imu
    rows = rows[order]
    if kind == "time":
        rows[:, 0] = times[order]
    else:
        rows[:, 0] = np.diff(np.concatenate([[times[order][0] - 0.01], times[order]]))
    path = tmp_path / "merged.csv"
    np.savetxt(path, rows, delimiter=",", header=f"{kind},{HEADER}", comments="", fmt="%.17g")
    source = open_recording(path, gyro_unit="rad/s" if kind == "dt" else "auto")
    rec, _ = source.load()
    assert source.rate == pytest.approx(100.0)
    samples = rec.valid
    assert samples.sum() == len(t)
    np.testing.assert_allclose(rec.dt[samples][1:], np.diff(t), atol=1e-9)
    assert "the next sample's dt spans them" in source.summary(len(rec.dt), 0.0,
                                                              int((~samples).sum()))


def test_a_sample_after_a_dropout_spans_it_at_a_given_rate(tmp_path):
    """Timed by a rate, five rows a logger wrote without numbers are five sample periods: the
    next sample's dt is six of them, so the gyro's turn over the gap is not lost."""
    _, imu = _example()
    imu = imu.copy()
    imu[100:105] = np.nan
    path = tmp_path / "dropout.csv"
    np.savetxt(path, imu, delimiter=",", header=HEADER, comments="", fmt="%.17g")
    rec, _ = open_recording(path, rate=100.0).load()
    assert np.isnan(rec.dt[100:105]).all()
    assert rec.dt[105] == pytest.approx(0.06)
    np.testing.assert_array_equal(np.delete(rec.dt, np.s_[100:106]), 0.01)


@pytest.mark.parametrize("time_text", [False, True])
def test_matlabs_exported_timetable_is_read(tmp_path, time_text):
    """MATLAB's writetimetable of a timetable with matrix variables (as MATLAB Mobile's sensor
    log gives them): "Acceleration_1".."_3", "AngularVelocity_1".."_3" are the axes x, y, z,
    and the row times are durations written with their unit ("0.01 sec"), read as seconds;
    a cell in another unit is refused naming its line."""
    t, imu = _example()
    header = ",".join(["Time", *(f"Acceleration_{k}" for k in (1, 2, 3)),
                       *(f"AngularVelocity_{k}" for k in (1, 2, 3))])
    lines = [header] + [",".join([f"{ti:.2f} sec" if time_text else f"{ti:.2f}",
                                  *(f"{v:.17g}" for v in row)])
                        for ti, row in zip(t, imu, strict=True)]
    path = tmp_path / "timetable.csv"
    path.write_text("\n".join(lines) + "\n")
    source = open_recording(path)
    rec, times = source.load()
    assert "acc_x='Acceleration_1'" in source.choices
    assert "gyro_z='AngularVelocity_3'" in source.choices
    if time_text:
        assert "time from its durations" in source.choices
    np.testing.assert_array_equal(rec.acc, imu[:, :3])
    np.testing.assert_allclose(times, t, atol=1e-12)
    if time_text:
        lines[7] = lines[7].replace(" sec", " ms")
        path.write_text("\n".join(lines) + "\n")
        assert "the first: line 8, column 'Time': '0.06 ms' is not a duration in sec" in \
            _no_row(path)


def test_a_quaternions_four_matlab_columns_are_no_axes(tmp_path):
    """"Orientation_1".."_4" (a quaternion, w or x first) are not read as axes: only a name with
    exactly the three columns _1, _2, _3 is."""
    from testbenches.fit.columns import name_forms

    forms = name_forms(["Orientation_1", "Orientation_2", "Orientation_3", "Orientation_4",
                        "Acceleration_1", "Acceleration_2", "Acceleration_3"])
    assert forms[3] == ["orientation_1", "orientation_2", "orientation_3", "orientation_4",
                        "acceleration_x", "acceleration_y", "acceleration_z"]


def test_a_labview_measurement_file_is_read_after_its_headers(tmp_path):
    """LabVIEW's .lvm: a file header and a segment header (each closed by ***End_of_Header***,
    the segment's rows as wide as the table's), then "X_Value" (the waveforms' time) and the
    channels' names."""
    t, imu = _example()
    head = ("LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\nX_Columns\tOne\n"
            "***End_of_Header***\t\n\n"
            "Channels\t6\t\t\t\t\t\t\n" + "Samples" + "\t1000" * 6 + "\t\n"
            + "Delta_X" + "\t0.010000" * 6 + "\t\n***End_of_Header***\t\t\t\t\t\t\t\n"
            "X_Value\tAcc X\tAcc Y\tAcc Z\tGyro X\tGyro Y\tGyro Z\tComment\n")
    rows = ["\t".join([f"{ti:.6f}", *(f"{v:.10g}" for v in row), ""])
            for ti, row in zip(t, imu, strict=True)]
    path = tmp_path / "session.lvm"
    path.write_text(head + "\n".join(rows) + "\n")
    source = open_recording(path)
    rec, _ = source.load()
    assert "time='X_Value'" in source.choices and "acc_x='Acc X'" in source.choices
    assert source.rate == pytest.approx(100.0)
    np.testing.assert_allclose(rec.acc, imu[:, :3], rtol=1e-9)


def test_one_numbered_sensor_is_read_and_two_are_refused_naming_both(tmp_path):
    """A logger of several IMUs numbers each ("acc1_x", "gyro1_x"): one sensor so numbered is
    read; two are refused naming both columns, and --column gives the one meant."""
    t, imu = _example()
    one = ",".join(["time", *(f"{s}1_{a}" for s in ("acc", "gyro") for a in "xyz")])
    path = _names_and_file(tmp_path / "one.csv", one.split(","), [t, imu])
    source = open_recording(path)
    assert "acc_x='acc1_x'" in source.choices
    np.testing.assert_array_equal(source.load()[0].gyro, imu[:, 3:])
    two = one.split(",") + [f"{s}2_{a}" for s in ("acc", "gyro") for a in "xyz"]
    path = _names_and_file(tmp_path / "two.csv", two, [t, imu, imu * 1.01])
    with pytest.raises(RecordingError, match=r"2 columns' names fit acc_x alike \(columns 2 "
                       r"'acc1_x', 8 'acc2_x'\)"):
        open_recording(path)
    given = {f"{s}_{a}": f"{s}2_{a}" for s in ("acc", "gyro") for a in "xyz"}
    np.testing.assert_array_equal(open_recording(path, columns=given).load()[0].acc,
                                  imu[:, :3] * 1.01)


def _ulog(path: Path, topic: str = "sensor_combined") -> Path:
    """The example as PX4 logs it (ULog: its file header, flag bits, the topic's format, its
    subscription, one data message per sample; FRD, z down), written by the format's spec."""
    import struct

    t, imu = _example()
    frd = np.array([1.0, -1.0, -1.0])

    def message(kind: str, payload: bytes) -> bytes:
        return struct.pack("<HB", len(payload), ord(kind)) + payload

    fields = ("uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
              "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"
              "uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;"
              "uint8_t gyro_clipping;uint8_t accel_calibration_count;"
              "uint8_t gyro_calibration_count;")
    out = [b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0), message("B", bytes(40)),
           message("F", f"{topic}:{fields}".encode()),
           message("A", struct.pack("<BH", 0, 0) + topic.encode())]
    for ti, row in zip(t, imu, strict=True):
        body = struct.pack("<Q3fIi3fIBBBB", round(ti * 1e6), *(row[3:] * frd), 10000, 0,
                           *(row[:3] * frd), 10000, 0, 0, 1, 1)
        out.append(message("D", struct.pack("<H", 0) + body))
    path.write_bytes(b"".join(out))
    return path


def test_a_px4_flight_log_is_read_as_ulog2csv_writes_its_imu(tmp_path):
    """A ULog's sensor_combined topic (pyulog), its columns as ulog2csv names them: the
    example's samples in PX4's z-down frame (float32, as PX4 logs them), at 100 Hz from the
    timestamp in us. A log without the topic is refused naming it."""
    pytest.importorskip("pyulog", reason="pyulog reads PX4 logs (testbench extra)")
    source = open_recording(_ulog(tmp_path / "flight.ulg"))
    rec, _ = source.load()
    assert "gyro_x='gyro_rad[0]'" in source.choices and "time in us" in source.choices
    assert "topic sensor_combined (1000 messages); read as PX4 ULog" in source.choices
    _, imu = _example()
    np.testing.assert_allclose(rec.acc, imu[:, :3] * [1, -1, -1], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(rec.dt[1:], 0.01, atol=1e-9)
    with pytest.raises(RecordingError, match="a PX4 log without the sensor_combined topic"):
        open_recording(_ulog(tmp_path / "other.ulg", topic="vehicle_status"))


def test_two_sensors_rows_interleaved_are_refused_not_read_as_one(tmp_path):
    """ArduPilot logs each of its IMUs in IMU messages numbered by "I": exported together,
    their rows alternate, and read as one sensor they were one at twice the rate, its samples
    alternating between the two parts (read without a word). Refused naming the numbers; one
    IMU's rows (every I 0) are read."""
    t, imu = _example()
    header = ["TimeUS", "I", "GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ"]
    one = np.column_stack([np.round(t * 1e6), np.zeros(len(t)), imu[:, 3:], imu[:, :3]])
    two = np.empty((2 * len(t), one.shape[1]))
    two[0::2], two[1::2] = one, one
    two[1::2, 0] += 1500.0
    two[1::2, 1] = 1.0
    two[1::2, 2:5] += 0.05
    path = _names_and_file(tmp_path / "two.csv", header, [two])
    with pytest.raises(RecordingError, match=r"the rows are 2 sensors', as 'I' numbers them "
                       r"\(0 on 1000 rows, 1 on 1000 rows"):
        open_recording(path)
    rec, _ = open_recording(_names_and_file(tmp_path / "one.csv", header, [one])).load()
    np.testing.assert_array_equal(rec.gyro, imu[:, 3:])


def test_a_unit_the_reader_does_not_know_is_named_in_the_refusal(tmp_path):
    """"Gyro X (1/s)": the unknown unit kept the column from its name; the refusal names it and
    what serves, and the columns so mapped are read (the data telling the unit)."""
    t, imu = _example()
    header = ["Time (s)", *(f"Acc {a} (m/s2)" for a in "XYZ"), *(f"Gyro {a} (1/s)" for a in "XYZ")]
    path = _names_and_file(tmp_path / "units.csv", header, [t, imu])
    with pytest.raises(RecordingError, match=r"\('Gyro X \(1/s\)', 'Gyro Y \(1/s\)', 'Gyro Z "
                       r"\(1/s\)' state the unit '1/s', which this reader does not know: map "
                       r"each column with --column QUANTITY=NAME and give its unit"):
        open_recording(path)
    given = {f"gyro_{a.lower()}": f"Gyro {a} (1/s)" for a in "XYZ"}
    source = open_recording(path, columns=given)
    assert "gyro in rad/s (from the data" in source.choices
    np.testing.assert_array_equal(source.load()[0].gyro, imu[:, 3:])


def test_a_plotjuggler_export_of_an_imu_and_a_mocap_topic_serves_as_both(tmp_path, capsys):
    """PlotJuggler's export of two topics: the rows are the union of both topics' messages,
    each topic's columns and its own header stamp empty on the other's rows, "__time" on all.
    The file is the recording (its IMU topic, timed by __time) and the reference (its mocap
    topic) at once, and scores as the example with its truth does."""
    from testbenches.cli import main

    t, imu = _example()
    truth = np.loadtxt(REPO / "examples" / "tilt_motion_truth.csv", delimiter=",", skiprows=1)
    at = truth[:-1, 0] + 0.004  # the mocap's own instants, between the IMU's
    r, p, y = (np.interp(at, truth[:, 0], truth[:, k]) / 2 for k in (1, 2, 3))
    quat = np.column_stack([  # x, y, z, w of Z-Y-X roll, pitch, yaw
        np.sin(r) * np.cos(p) * np.cos(y) - np.cos(r) * np.sin(p) * np.sin(y),
        np.cos(r) * np.sin(p) * np.cos(y) + np.sin(r) * np.cos(p) * np.sin(y),
        np.cos(r) * np.cos(p) * np.sin(y) - np.sin(r) * np.sin(p) * np.cos(y),
        np.cos(r) * np.cos(p) * np.cos(y) + np.sin(r) * np.sin(p) * np.sin(y)])
    header = ["__time", *(f"/imu/angular_velocity/{a}" for a in "xyz"),
              *(f"/imu/linear_acceleration/{a}" for a in "xyz"), "/imu/header/stamp",
              "/vicon/body/header/stamp", *(f"/vicon/body/transform/rotation/{c}" for c in "xyzw")]
    imu_rows = np.full((len(t), len(header)), np.nan)
    imu_rows[:, 0], imu_rows[:, 1:4], imu_rows[:, 4:7], imu_rows[:, 7] = t, imu[:, 3:], \
        imu[:, :3], t
    mocap = np.full((len(at), len(header)), np.nan)
    mocap[:, 0], mocap[:, 8], mocap[:, 9:] = at, at, quat
    rows = np.concatenate([imu_rows, mocap])
    path = _names_and_file(tmp_path / "export.csv", header,
                           [rows[np.argsort(rows[:, 0], kind="stable")]])
    assert main(["estimate", str(path), "--estimator", "kf", "--reference", str(path),
                 "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    said = capsys.readouterr().out
    assert "time='__time'" in said
    kf = float(next(x for x in said.splitlines() if x.startswith("kf ")).split()[2])
    assert kf == pytest.approx(0.5996, abs=0.01)


def _no_row(path: Path) -> str:
    """What reading a file with one line that is no row says of it (the line a sample without
    numbers)."""
    rec, _ = open_recording(path).load()
    assert (~rec.valid).sum() == 1
    assert "1 line(s) no row of the table, taken as samples without a number" in rec.described
    return rec.described


def _cut(path: Path, tail: bytes, *, cut: int = 40, nul: int = 0, crlf: bool = False) -> Path:
    """The example as a logger that lost power leaves it: its last `cut` bytes not written,
    `nul` NUL bytes after them (a preallocated file's unwritten rest); `tail` appended first."""
    text = EXAMPLE.read_bytes() + tail
    if crlf:
        text = text.replace(b"\n", b"\r\n")
    path.write_bytes(text[:len(text) - cut] + b"\0" * nul)
    return path


@pytest.mark.parametrize("nul", [0, 4096])
@pytest.mark.parametrize("padded", [False, True])  # pyarrow's reader, Python's
@pytest.mark.parametrize("crlf", [False, True])
def test_a_last_line_cut_mid_write_and_nul_padding_are_left_out_and_said(tmp_path, nul,
                                                                          padded, crlf):
    """Power lost mid-write: the last line cut short, NULs after it on an SD card. The file
    was refused naming its last line; the rows before it are read now, and both are said."""
    whole, _ = open_recording(EXAMPLE).load()
    source = EXAMPLE.read_bytes()
    if padded:  # a cell with spaces around it: Python's reader
        source = source.replace(b",0.01\n", b", 0.01\n", 3)
    path = tmp_path / "cut.csv"
    path.write_bytes(source)
    path = _cut(path, b"", nul=nul, crlf=crlf)
    opened = open_recording(path, gyro_unit="rad/s")
    rec, _ = opened.load()
    assert len(rec.dt) == len(whole.dt) - 1
    np.testing.assert_array_equal(rec.acc, whole.acc[:-1])
    np.testing.assert_array_equal(rec.gyro, whole.gyro[:-1])
    assert "line 1001, the last, cut short (5 of 8 values: a logger stopped mid-write): " \
           "left out" in opened.choices
    assert (f"{nul} NUL bytes after the last line" in opened.choices) == bool(nul)


def test_nul_padding_after_whole_lines_is_ignored_and_said(tmp_path):
    whole, _ = open_recording(EXAMPLE).load()
    opened = open_recording(_cut(tmp_path / "padded.csv", b"", cut=0, nul=100000))
    rec, _ = opened.load()
    np.testing.assert_array_equal(rec.gyro, whole.gyro)
    assert "100000 NUL bytes after the last line" in opened.choices
    assert "cut short" not in opened.choices


def test_a_whole_last_line_without_a_line_end_is_read(tmp_path):
    whole, _ = open_recording(EXAMPLE).load()
    opened = open_recording(_cut(tmp_path / "noeol.csv", b"", cut=1))
    rec, _ = opened.load()
    np.testing.assert_array_equal(rec.gyro, whole.gyro)
    assert "cut short" not in opened.choices


@pytest.mark.parametrize("dt,cut,value,why", [
    (b"0.01", 2, "0.0", "has fewer digits than that column's value on each of the 100 lines "
                        "before it"),
    (b"1.00e-02", 2, "1.00e-0", "has fewer digits than that column's value on each of the "
                                "100 lines before it"),
    (b"1.00e-02", 3, "1.00e-", "is no number"),
])
def test_a_last_line_of_every_value_its_last_cut_mid_write_is_left_out(tmp_path, dt, cut,
                                                                       value, why):
    """Cut after the last delimiter, a line has the header's width: its last value, shorter
    than the column's format writes it, was kept as a wrong number ('0.01' read as 0.0,
    '1.00e-02' as 1) or refused the file."""
    whole, _ = open_recording(EXAMPLE).load()
    path = tmp_path / "cut.csv"
    text = EXAMPLE.read_bytes().replace(b",0.01\n", b"," + dt + b"\n")
    path.write_bytes(text[:-cut])
    opened = open_recording(path)
    rec, _ = opened.load()
    np.testing.assert_array_equal(rec.dt, whole.dt[:-1])
    np.testing.assert_array_equal(rec.gyro, whole.gyro[:-1])
    assert ("line 1001, the last, cut mid-write (no line end after it, and its last value "
            f"{value!r} {why}): left out") in opened.choices


@pytest.mark.parametrize("last", [b"0.500000", b"-0.500000", b"12.500000"])
def test_a_whole_last_value_of_another_sign_or_size_is_no_cut(tmp_path, last):
    """A fixed format's width changes with the sign and the integer part, not its decimals:
    such a last value without a line end is read."""
    rows = [f"{k / 100:.2f},0.1,0.2,9.8,0.01,-0.02,{-0.3 - k / 1000:.6f}" for k in range(50)]
    path = tmp_path / "fixed.csv"
    path.write_bytes(("time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z\n" + "\n".join(rows)
                      + "\n0.50,0.1,0.2,9.8,0.01,-0.02,").encode() + last)
    opened = open_recording(path, gyro_unit="rad/s")
    rec, _ = opened.load()
    assert len(rec.dt) == 51 and rec.gyro[-1, 2] == float(last)
    assert "cut" not in opened.choices


@pytest.mark.parametrize("padded", [False, True])  # pyarrow's reader, then Python's; Python's
@pytest.mark.parametrize("line,says", [
    ("4.98,-0.2,0.1", "line 500: 3 value(s) where the header has 8 columns ('4.98,-0.2,0.1')"),
    ("4.98,-0.2,0.1,9.8,0.01,0.02,0.03,0.014.99,0.1,0.2,9.8,0.01,0.02,0.03,0.01",
     "line 500: 15 value(s) where the header has 8 columns"),
    ("4.98,-0.2,0.1,9$8,0.01,0.02,0.03,0.01", "line 500, column 'acc_z': '9$8' is not a "
                                              "number"),
    ("time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z,dt", "line 500: the header again (a logger "
                                                       "restarted and wrote on)"),
])
def test_a_line_that_is_no_row_is_a_sample_without_numbers(tmp_path, padded, line, says):
    """A serial link's lost or garbled bytes make a line no row of the table (too few or too
    many values, text in a cell, the header written again): the file was refused naming the
    line; the line is now a sample without numbers, rejected and counted, and said."""
    whole, _ = open_recording(EXAMPLE).load()
    lines = EXAMPLE.read_text().splitlines(keepends=True)
    if padded:
        lines = [x.replace(",0.01\n", ", 0.01\n") for x in lines]
    path = tmp_path / "garbled.csv"
    path.write_text("".join([*lines[:499], line + "\n", *lines[500:]]))
    opened = open_recording(path, gyro_unit="rad/s")
    rec, _ = opened.load()
    assert len(rec.dt) == len(whole.dt) and (~rec.valid).sum() == 1 and not rec.valid[498]
    keep = np.arange(len(whole.dt)) != 498
    np.testing.assert_array_equal(rec.gyro[keep], whole.gyro[keep])
    assert ("1 sample(s) without a number in every column" in rec.described
            and "1 line(s) no row of the table, taken as samples without a number (a "
                f"logger's garbled or lost bytes; the first: {says}" in rec.described)


@pytest.mark.parametrize("pyarrow", [True, False])
def test_a_byte_that_is_no_utf8_character_makes_its_line_no_row(tmp_path, monkeypatch,
                                                               pyarrow):
    """A serial link's garbled byte that is no UTF-8 character, past the lines the encoding
    was found from, was a refusal naming neither file nor line ("'utf-8' codec can't decode
    byte 0xb7 in position 4223"); it makes its cell no number, and its line a sample without
    numbers, said, by either reader."""
    import testbenches.reader as reader

    if not pyarrow:
        monkeypatch.setattr(reader, "_has_pyarrow", lambda: False)
    lines = EXAMPLE.read_bytes().split(b"\n")
    lines[900] = lines[900].replace(b".", b"\xb7", 1)
    path = tmp_path / "garbled.csv"
    path.write_bytes(b"\n".join(lines))
    rec, _ = open_recording(path, gyro_unit="rad/s").load()
    assert len(rec.dt) == 1000 and np.flatnonzero(~rec.valid).tolist() == [899]
    assert ("1 line(s) no row of the table, taken as samples without a number (a logger's "
            "garbled or lost bytes; the first: line 901, column 'time': '8\ufffd99' is not a "
            "number") in rec.described


@pytest.mark.parametrize("least", [1, 10**6])
def test_pyarrows_reader_goes_on_after_each_line_that_is_no_row(tmp_path, monkeypatch, least):
    """Where pyarrow's reader meets a line that is no row, it reads that batch again with the
    lines of another count of cells made rows without numbers, and where it still meets one,
    Python's reader takes over and pyarrow's goes on after it once Python's has read
    RESUME_ROWS (a long log with a garbled line is read at pyarrow's speed but for that
    stretch): the samples are the same as Python's reader gives throughout, a blank line and
    lines of every kind of fault between."""
    import testbenches.reader as reader

    monkeypatch.setattr(reader, "RESUME_ROWS", least)
    arrow, started = reader._arrow_parts, []

    def counted(*args, mended=None):
        started.append((args[-1], mended is not None))  # the lines it skips, mended or not
        return arrow(*args, mended=mended)

    monkeypatch.setattr(reader, "_arrow_parts", counted)
    lines = EXAMPLE.read_text().splitlines(keepends=True)
    bad = {200: "4.98,-0.2\n", 450: "x,1,2,3,4,5,6,7\n", 700: lines[0], 900: "1,2,3\n"}
    text = [bad.get(k, x) for k, x in enumerate(lines)]
    text.insert(600, "\n")
    path = tmp_path / "garbled.csv"
    path.write_text("".join(text))
    rec, _ = open_recording(path, gyro_unit="rad/s").load()
    keep = np.ones(len(lines) - 1, bool)
    keep[[k - 1 for k in bad]] = False
    np.testing.assert_array_equal(rec.valid, keep)
    whole, _ = open_recording(EXAMPLE).load()
    np.testing.assert_array_equal(rec.gyro[keep], whole.gyro[keep])
    np.testing.assert_array_equal(rec.acc[keep], whole.acc[keep])
    assert "4 line(s) no row of the table" in rec.described
    assert "the first: line 201: 2 value(s)" in rec.described
    # Python's from the batch that failed through the line and `least` rows; pyarrow's again
    # after them, and where it fails again within them (such lines come often), on that batch
    # and to the end with every such line mended (_Mended)
    runs = [(1, False), (201, False), (201, True)] if least == 1 else [(1, False)]
    assert started[:len(runs)] == runs and started[len(runs)] == (1, False)  # then `whole`



def _both_readers(path, monkeypatch):
    """The recording as read with pyarrow's reader (batches of 4 kB: many per file), and
    as Python's reader reads it throughout."""
    import testbenches.reader as reader

    monkeypatch.setattr(reader, "ARROW_BLOCK", 1 << 12)
    arrow, _ = open_recording(path, gyro_unit="rad/s").load()
    with monkeypatch.context() as m:
        m.setattr(reader, "_has_pyarrow", lambda: False)
        python, _ = open_recording(path, gyro_unit="rad/s").load()
    return arrow, python


def test_lines_that_are_no_row_every_few_rows_are_read_by_pyarrow(tmp_path, monkeypatch):
    """A serial link that garbles a line every hundred rows (too few values, two rows run
    together, a byte in a number, text in a cell, the header again, a line of delimiters
    alone) leaves Python's reader one stretch to read: once the next such line comes within
    the rows it read, pyarrow's reads them as rows without numbers (_Mended), in CRLF files
    too, and the samples and what is said are those of Python's reader throughout."""
    import testbenches.reader as reader

    parsed = []
    python = reader._python_parts

    def counted(*args, **kwargs):
        for part in python(*args, **kwargs):
            parsed.append(len(part))
            yield part

    lines = EXAMPLE.read_text().splitlines()
    faults = ["4.98,-0.2", ",,,", lines[0], "1,2,3,4,5,6,7,8,9" + lines[300],
              lines[400].replace(".", "$", 2), "x" + lines[500][1:], "   "]
    for k in range(100, 1000, 100):
        lines[k] = faults[k // 100 % len(faults)]
    for end in ("\n", "\r\n"):
        path = tmp_path / "garbled.csv"
        path.write_bytes((end.join(lines) + end).encode())
        parsed.clear()
        with monkeypatch.context() as m:
            m.setattr(reader, "_python_parts", counted)
            m.setattr(reader, "ARROW_BLOCK", 1 << 12)
            m.setattr(reader, "RESUME_ROWS", 150)
            arrow, _ = open_recording(path, gyro_unit="rad/s").load()
        assert len(parsed) == 1 and parsed[0] < 400  # Python's reader: its first stretch
        _, python_alone = _both_readers(path, monkeypatch)
        for name in ("acc", "gyro", "dt", "valid"):
            np.testing.assert_array_equal(getattr(arrow, name), getattr(python_alone, name))
        assert arrow.described == python_alone.described
        assert (~arrow.valid).sum() == 6 and len(arrow.dt) == 997  # 3 blank, 6 garbled
        assert ("6 line(s) no row of the table, taken as samples without a number (a "
                "logger's garbled or lost bytes; the first: line 201: the header again") \
            in arrow.described


@pytest.mark.parametrize("delimiter", [",", "\t"])
def test_a_row_of_empty_cells_is_a_sample_to_either_reader(tmp_path, monkeypatch, delimiter):
    """A row of the header's count of empty cells is a sample without numbers to both
    readers, and where Python's reader takes over from pyarrow's (at a cell that is no
    number, batches later) it starts at the row pyarrow's reached: Python's reader took the row
    for a blank line, so it started one row late and a sample was lost (tabs, which are
    white space as well as the delimiter, too)."""
    lines = EXAMPLE.read_text().splitlines(keepends=True)
    lines.insert(100, ",,,,,,,\n")
    lines[800] = lines[800].replace(",", "$", 1)
    path = tmp_path / "empty_row.csv"
    path.write_text("".join(lines).replace(",", delimiter))
    arrow, python = _both_readers(path, monkeypatch)
    for rec in (arrow, python):
        assert len(rec.dt) == 1001 and np.flatnonzero(~rec.valid).tolist() == [99, 799]
    np.testing.assert_array_equal(arrow.gyro, python.gyro)
    whole, _ = open_recording(EXAMPLE).load()
    np.testing.assert_array_equal(arrow.gyro[arrow.valid], np.delete(whole.gyro, 798, axis=0))


def test_a_logger_that_restarted_and_wrote_on_is_refused_saying_to_split_the_file(tmp_path):
    """A logger restarted appends its header and a time from 0 again: the header is a line
    that is no row, and the time going back is refused saying what it is; two rows out of
    order are not taken for a restart."""
    lines = EXAMPLE.read_text().splitlines(keepends=True)
    path = tmp_path / "restarted.csv"
    path.write_text("".join(lines + lines[:300]))
    with pytest.raises(RecordingError, match=r"line 1003: the time 0 s does not increase from "
                       r"9\.99 s on line 1001; a time that starts again is a recording written "
                       r"on after another \(a logger that restarted and appended to the same "
                       r"file\): split the file there"):
        open_recording(path).load()
    lines[500], lines[501] = lines[501], lines[500]
    path.write_text("".join(lines))
    with pytest.raises(RecordingError, match=r"line 502: the time 4\.99 s does not increase "
                       r"from 5 s on line 501$"):
        open_recording(path).load()


def test_more_lines_that_are_no_rows_than_one_in_a_hundred_refuse_the_file(tmp_path):
    """Many lines that are no row say the file is not the table its header describes: refused
    naming the line that tipped it."""
    lines = EXAMPLE.read_text().splitlines(keepends=True)
    for k in (200, 210, 220, 230, 240):
        lines[k] = "garbled\n"
    path = tmp_path / "garbled.csv"
    path.write_text("".join(lines))
    with pytest.raises(RecordingError, match=r"line 231: 1 value\(s\) where the header has 8 "
                       r"columns \('garbled'\); 4 of 230 rows are no row of the table \(more "
                       r"than 1% of them, which would be taken as samples without a number\)"):
        open_recording(path, gyro_unit="rad/s").load()


def _long_example(rows: int = 60000) -> tuple[str, np.ndarray]:
    """The example's rows over and over, timed on (several of bz2's 900 kB blocks)."""
    _, imu = _example()
    imu = np.tile(imu, (rows // len(imu) + 1, 1))[:rows]
    t = np.arange(rows) * 0.01
    lines = [f"time,{HEADER}"] + [",".join(f"{v:.10g}" for v in (t[i], *imu[i]))
                                  for i in range(rows)]
    return "\n".join(lines) + "\n", imu


@pytest.mark.parametrize("compress", ["gzip", "bz2", "lzma"])
def test_a_compressed_file_cut_short_is_read_up_to_the_cut_and_said(tmp_path, compress):
    """A .csv.gz (.bz2, .xz) whose copy, download or logger stopped: a traceback ('Compressed
    file ended before the end-of-stream marker was reached'). The whole lines before the cut
    are read now, the one it fell in left out, and the read says so."""
    import importlib

    text, imu = _long_example()
    whole = importlib.import_module(compress).compress(text.encode())
    path = tmp_path / "cut.csv.z"
    path.write_bytes(whole[:len(whole) * 2 // 3])
    source = open_recording(path, gyro_unit="rad/s")
    rec, _ = source.load()
    n = len(rec.dt)
    assert 0 < n < len(imu)
    np.testing.assert_array_equal(rec.gyro, imu[:n, 3:])
    said = source.summary(n, 0.0, 0)
    kind = {"lzma": "xz"}.get(compress, compress)
    assert f"its {kind} stream ends before its end (the file was cut" in said
    assert "read up to the cut" in said


@pytest.mark.parametrize("compress", ["gzip", "bz2", "lzma"])
@pytest.mark.parametrize("ending,says", [
    ("0.0", "line 1001, the last, cut mid-write (no line end after it, and its last value "
            "'0.0' has fewer digits than that column's value on each of the 100 lines before "
            "it): left out"),
    ("", "line 1001, the last, cut short (5 of 8 values: a logger stopped mid-write): left out"),
    ("END OF LOG\n", "line 1002, the last, is text after the table ('END OF LOG'): left out as "
                     "a footer"),
    ("\x00" * 300_000, "300000 NUL bytes after the last line (the unwritten rest of a "
                       "preallocated file): ignored"),
], ids=["value_cut", "line_cut", "footer", "nul_padding"])
def test_a_compressed_file_s_last_line_as_a_logger_stopped_is_read_as_the_plain_file(
        tmp_path, compress, ending, says):
    """What a logger leaves when it stops mid-write (a last value cut, a last line cut short,
    a footer, NUL padding) is found in a compressed copy of its file as in the file: the last
    line was read as it stood there (a cut value as the wrong number, silently), a footer as
    a line that is no row."""
    import importlib

    text = EXAMPLE.read_text()
    if ending == "0.0":  # the last value, 0.01, cut to 0.0
        text = text.rstrip("\n")[:-1]
    elif ending == "":  # the last line cut after its fifth value
        text = text[:text.rstrip("\n").rfind("\n") + 1] + ",".join(
            text.rstrip("\n").rsplit("\n", 1)[1].split(",")[:5])
    else:
        text += ending
    plain = tmp_path / "logged.csv"
    plain.write_text(text)
    packed = tmp_path / "logged.csv.z"
    packed.write_bytes(importlib.import_module(compress).compress(text.encode()))
    got = [open_recording(path, gyro_unit="rad/s") for path in (plain, packed)]
    (rec, _), (packed_rec, _) = (source.load() for source in got)
    for name in ("acc", "gyro", "dt", "valid"):
        np.testing.assert_array_equal(getattr(packed_rec, name), getattr(rec, name))
    assert says in rec.described and says in packed_rec.described


def test_a_compressed_file_cut_before_its_first_line_or_damaged_is_refused(tmp_path):
    import gzip

    whole = gzip.compress(EXAMPLE.read_bytes())
    cut = tmp_path / "cut.csv.gz"
    cut.write_bytes(whole[:12])
    with pytest.raises(RecordingError, match=r"its gzip stream ends before its end \(the file "
                       r"was cut.*before any whole line"):
        open_recording(cut)
    damaged = tmp_path / "damaged.csv.gz"
    damaged.write_bytes(whole[:2000] + bytes(range(256)) * 8 + whole[4048:])
    with pytest.raises(RecordingError, match=r"its gzip stream cannot be decompressed .*: the "
                       "file is damaged"):
        open_recording(damaged).load()


@pytest.mark.parametrize("kind", ["parquet", "h5", "mat"])
def test_a_binary_file_cut_short_is_refused_in_one_line(tmp_path, kind):
    """Parquet, HDF5 and MATLAB files cut before their end cannot be read up to the cut (their
    index is at the end, or the file states its length): refused naming the format. A cut HDF5
    file was a traceback (h5py's OSError, from the BROAD trial check that runs first)."""
    import h5py
    import pyarrow as pa
    import pyarrow.parquet as pq
    import scipy.io

    from testbenches.broad.data import NotABroadTrial, load_trial

    data = np.genfromtxt(EXAMPLE, delimiter=",", names=True)
    columns = {n: data[n] for n in data.dtype.names}
    whole = tmp_path / f"whole.{kind}"
    if kind == "parquet":
        pq.write_table(pa.table(columns), whole)
    elif kind == "h5":
        with h5py.File(whole, "w") as f:
            for name, values in columns.items():
                f[name] = values
    else:
        scipy.io.savemat(whole, columns)
    assert len(open_recording(whole).load()[0].dt) == len(data)
    raw = whole.read_bytes()
    cut = tmp_path / f"cut.{kind}"
    cut.write_bytes(raw[:len(raw) * 2 // 3])
    with pytest.raises(RecordingError, match=r"cut\.\w+: not a readable"):
        open_recording(cut).load()
    if kind != "parquet":
        with pytest.raises(NotABroadTrial, match="not a BROAD trial: "):
            load_trial(cut)


def test_a_zip_archive_of_one_text_file_is_read_as_that_file(tmp_path):
    """A recording zipped to be sent (with macOS's resource fork beside it) is read as the text
    file it holds, its end looked at as that file's (a last value cut mid-write left out): it
    was refused as a phone app's export without a file named for the accelerometer. An
    archive of two files is still an export, and a workbook still refused."""
    import zipfile

    text = EXAMPLE.read_text().rstrip("\n")[:-1]  # its last value, 0.01, cut to 0.0
    plain = tmp_path / "logged.csv"
    plain.write_text(text)
    packed = tmp_path / "logged.zip"
    with zipfile.ZipFile(packed, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("recording/logged.csv", text)
        z.writestr("__MACOSX/recording/._logged.csv", b"\x00\x05\x16\x07")
    (rec, _), (packed_rec, _) = (open_recording(p, gyro_unit="rad/s").load()
                                 for p in (plain, packed))
    assert len(packed_rec.dt) == 999
    for name in ("acc", "gyro", "dt", "valid"):
        np.testing.assert_array_equal(getattr(packed_rec, name), getattr(rec, name))
    assert "line 1001, the last, cut mid-write" in packed_rec.described
    with zipfile.ZipFile(packed, "a") as z:
        z.writestr("notes.txt", "held by hand\n")
    with pytest.raises(RecordingError, match="no file named for the accelerometer"):
        open_recording(packed).load()
    workbook = tmp_path / "sheet.xlsx"
    with zipfile.ZipFile(workbook, "w") as z:
        z.writestr("[Content_Types].xml", "<Types/>")
        z.writestr("xl/worksheets/sheet1.xml", "<worksheet/>")
    with pytest.raises(RecordingError, match="a spreadsheet workbook"):
        open_recording(workbook).load()


def test_a_zip_archive_cut_short_is_refused_as_cut_not_as_a_workbook(tmp_path):
    import zipfile

    whole = tmp_path / "export.zip"
    with zipfile.ZipFile(whole, "w") as z:
        z.write(EXAMPLE, "Accelerometer.csv")
    raw = whole.read_bytes()
    cut = tmp_path / "cut.zip"
    cut.write_bytes(raw[:len(raw) * 2 // 3])
    with pytest.raises(RecordingError, match=r"cut\.zip: a zip archive that does not open: cut "
                       "or damaged"):
        open_recording(cut)


@pytest.mark.parametrize("style", ["savetxt", "aligned", "tabs"])
def test_cells_split_by_runs_of_spaces_are_read(tmp_path, style):
    """numpy.savetxt's default (a space, its header a '# ' comment), a C printf's aligned
    columns and tabs with spaces: refused ('no delimiter splits a header ...'), read now as the
    comma-separated file is; a bad cell is named by its line and column as there."""
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    names = EXAMPLE.read_text().splitlines()[0].split(",")
    path = tmp_path / f"{style}.txt"
    if style == "savetxt":
        np.savetxt(path, data, header=" ".join(names))
    elif style == "aligned":
        path.write_text("".join(f"{n:>16}" for n in names) + "\n" + "".join(
            "".join(f"{v:16.10f}" for v in row) + "\n" for row in data))
    else:
        path.write_text("\t".join(names) + "\n" + "".join(
            " \t".join(f"{v:.10g}" for v in row) + "  \n" for row in data))
    rec, _ = open_recording(path).load()
    plain, _ = open_recording(EXAMPLE).load()
    np.testing.assert_allclose(rec.acc, plain.acc, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(rec.gyro, plain.gyro, rtol=1e-9, atol=1e-9)
    lines = path.read_text().splitlines()
    lines[500] = lines[500].replace(lines[500].split()[1], "abc", 1)
    path.write_text("\n".join(lines) + "\n")
    assert "the first: line 501, column 'acc_x': 'abc' is not a number" in _no_row(path)


@pytest.mark.parametrize("point", [".", ","])
def test_a_tum_trajectory_is_a_reference(tmp_path, capsys, point):
    """TUM's ground truth ('# timestamp tx ty tz qx qy qz qw', spaces between, w last) is a
    reference: scored, it gives what the truth file gives. With a decimal comma too (and the
    recording written so): the comma was taken for the delimiter, each cell two numbers."""
    from scipy.spatial.transform import Rotation

    from testbenches.cli import main

    truth = np.genfromtxt(REPO / "examples" / "tilt_motion_truth.csv", delimiter=",",
                          names=True)
    xyzw = Rotation.from_euler("xyz", np.column_stack(
        [truth["roll"], truth["pitch"], truth["yaw"]])).as_quat()
    rows = np.column_stack([truth["time"], np.zeros((len(xyzw), 3)), xyzw])
    tum = tmp_path / "groundtruth.txt"
    tum.write_text("# timestamp tx ty tz qx qy qz qw\n" + "".join(
        " ".join(f"{v:.9f}".replace(".", point) for v in row) + "\n" for row in rows))
    recording = tmp_path / "imu.txt"
    names = EXAMPLE.read_text().splitlines()[0].split(",")
    recording.write_text(" ".join(names) + "\n" + "".join(
        " ".join(f"{v:.10g}".replace(".", point) for v in row) + "\n"
        for row in np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)))
    scores = []
    for reference in (REPO / "examples" / "tilt_motion_truth.csv", tum):
        assert main(["estimate", str(recording), "--estimator", "kf", "--reference",
                     str(reference), "--no-plots", "--out", str(tmp_path / "out")]) == 0
        said = capsys.readouterr().out
        scores.append(float(next(r for r in said.splitlines() if r.startswith("kf ")).split()[2]))
    assert scores[1] == pytest.approx(scores[0], abs=1e-3)


@pytest.mark.parametrize("where", ["rows", "header", "both"])
def test_a_delimiter_after_the_last_cell_of_the_rows_or_the_header_is_read_through(tmp_path,
                                                                                 where):
    """A sketch that prints a comma after every value and its header without one: the first
    row was taken for the header ('no column for acc_x ...: the header has 0, 0.0281...')."""
    lines = EXAMPLE.read_text().splitlines()
    ends = {"rows": (False, True), "header": (True, False), "both": (True, True)}[where]
    lines = [line + ("," if ends[k > 0] else "") for k, line in enumerate(lines)]
    path = tmp_path / "trailing.csv"
    path.write_text("\n".join(lines) + "\n")
    rec, _ = open_recording(path).load()
    plain, _ = open_recording(EXAMPLE).load()
    np.testing.assert_array_equal(rec.gyro, plain.gyro)
    np.testing.assert_array_equal(rec.dt, plain.dt)


def test_a_time_of_too_few_digits_is_refused_saying_why_and_a_rate_serves(tmp_path):
    """Seconds since 1970 written with C's %g (six significant digits: steps of 1000 s) hold one
    number over the whole file: refused, saying the time has too few digits and that a rate
    spaces the samples; given, it does."""
    t, imu = _example()
    path = _rows(tmp_path / "epoch.csv", "time," + HEADER,
                 [f"{1.7e9 + ti:g}," + ",".join(f"{v:.10g}" for v in row)
                  for ti, row in zip(t, imu, strict=True)])
    with pytest.raises(RecordingError, match=r"line 3: the time 1.7e\+09 s repeats .*one number "
                       r"over the first 1000 rows: written with too few digits.*--rate HZ"):
        open_recording(path)
    rec, _ = open_recording(path, rate=100.0).load()
    np.testing.assert_allclose(rec.acc, imu[:, :3], rtol=1e-9)
