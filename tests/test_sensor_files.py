"""A phone app's export, one file per sensor in a folder or a zip archive (Sensor Logger,
phyphox), reads as the one file that holds the same rows would: the files are chosen by their
names, their rows joined in the order of their times; what is in doubt is refused, naming the
file and its line."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest

from fusion_core import G
from testbenches import battery
from testbenches.fit.recording import RecordingError, open_recording

EPOCH_NS = 1_698_501_144_401_773_000


def _part() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A hand-held part's times [s], accelerometer, gyro and its gravity [m/s2]."""
    t, truth, s = battery.part_samples("handheld_slow", "mpu6050", 2)
    r, p = truth["roll"], truth["pitch"]
    gravity = G * np.stack([-np.sin(p), np.sin(r) * np.cos(p), np.cos(r) * np.cos(p)], axis=1)
    return t, s["acc"], s["gyro"], gravity


def _phyphox(folder: Path, t: np.ndarray, acc: np.ndarray, gyro: np.ndarray) -> Path:
    folder.mkdir()
    for name, unit, tt, v in (("Accelerometer", "m/s^2", t, acc),
                              ("Gyroscope", "rad/s", t + 0.004, gyro)):
        np.savetxt(folder / f"{name}.csv", np.column_stack([tt, v]), delimiter=",", fmt="%.9E",
                   header=",".join(f'"{c}"' for c in ("Time (s)", f"X ({unit})", f"Y ({unit})",
                                                       f"Z ({unit})")), comments="")
    (folder / "meta").mkdir()
    (folder / "meta" / "device.csv").write_text('"property","value"\n"deviceModel","Pixel"\n')
    return folder


def _sensor_logger(folder: Path, files: dict[str, tuple[np.ndarray, np.ndarray]]) -> Path:
    """Sensor Logger's files: time in ns since 1970, seconds_elapsed, then z, y, x."""
    folder.mkdir()
    for name, (t, v) in files.items():
        ns = EPOCH_NS + np.round(t * 1e9).astype(np.int64)
        lines = [f"{n},{(n - EPOCH_NS) / 1e9 + 0.2:.6f},{z:.9g},{y:.9g},{x:.9g}"
                 for n, (x, y, z) in zip(ns, v, strict=True)]
        (folder / f"{name}.csv").write_text("time,seconds_elapsed,z,y,x\n" + "\n".join(lines))
    return folder


def _zipped(folder: Path) -> Path:
    path = folder.with_suffix(".zip")
    with zipfile.ZipFile(path, "w") as z:
        for f in sorted(folder.rglob("*")):
            z.write(f, f.relative_to(folder).as_posix())
    return path


def test_a_folder_and_its_zip_read_as_the_one_file_of_their_rows(tmp_path):
    """phyphox's export (Time (s), X (m/s^2)...; a gyro 4 ms after the accelerometer) reads to
    the bit as one file whose rows are the two files' in the order of their times."""
    t, acc, gyro, _ = _part()
    folder = _phyphox(tmp_path / "phyphox", t, acc, gyro)
    one = tmp_path / "one.csv"
    rows = np.full((2 * len(t), 7), np.nan)
    rows[0::2, 0], rows[0::2, 1:4] = t, acc
    rows[1::2, 0], rows[1::2, 4:7] = t + 0.004, gyro
    lines = ["time (s),acc_x (m/s2),acc_y (m/s2),acc_z (m/s2),gyro_x (rad/s),gyro_y (rad/s),"
             "gyro_z (rad/s)"]
    lines += [",".join("" if np.isnan(v) else f"{v:.9E}" for v in row) for row in rows]
    one.write_text("\n".join(lines))
    expected, t_expected = open_recording(one).load()
    for path in (folder, _zipped(folder)):
        source = open_recording(path)
        rec, t_read = source.load()
        assert "the accelerometer's Accelerometer.csv, the gyro's Gyroscope.csv" in source.choices
        assert "acc_x='Accelerometer.csv: X (m/s^2)'" in source.choices
        np.testing.assert_array_equal(rec.acc, expected.acc)
        np.testing.assert_array_equal(rec.gyro, expected.gyro)
        np.testing.assert_array_equal(rec.dt, expected.dt)
        np.testing.assert_array_equal(t_read, t_expected)


def test_polar_sensor_loggers_files_are_read_by_the_sensors_clock(tmp_path):
    """Polar Sensor Logger writes ACC and GYRO files of `Phone timestamp;sensor timestamp
    [ns];X [mg];...` (X [dps] for the gyro): no time column was found ("name it with
    --time-column"). The sensor's clock is the time; the phone's, when the packets came, is
    not taken while the sensor's is there."""
    t, acc, gyro, _ = _part()
    folder = tmp_path / "polar"
    folder.mkdir()
    start = np.datetime64("2022-05-10T12:00:00", "ms")
    for name, unit, values in (("ACC", "mg", acc / G * 1e3), ("GYRO", "dps", np.degrees(gyro))):
        phone = [str(start + np.timedelta64(int(k // 10 * 100), "ms")) for k in range(len(t))]
        sensor = EPOCH_NS + np.round(t * 1e9).astype(np.int64)
        lines = [f"Phone timestamp;sensor timestamp [ns];X [{unit}];Y [{unit}];Z [{unit}]"]
        lines += [f"{p};{s};" + ";".join(f"{v:.6f}" for v in row)
                  for p, s, row in zip(phone, sensor, values, strict=True)]
        (folder / f"Polar_Sense_B5A0D123_20220510_120000_{name}.txt").write_text(
            "\n".join(lines) + "\n")
    source = open_recording(folder)
    rec, _ = source.load()
    assert "time='sensor timestamp [ns]'" in source.choices
    assert "acc in mg (from the header); gyro in deg/s (from the header" in source.choices
    assert source.rate == pytest.approx(1.0 / np.median(np.diff(t)), rel=1e-6)
    np.testing.assert_allclose(rec.acc[1:], acc[1:], atol=1e-5)


def test_sensor_loggers_total_acceleration_is_taken_and_its_accelerometer_refused(tmp_path):
    """Sensor Logger's Accelerometer.csv leaves gravity out, TotalAcceleration.csv holds it:
    the total one is taken and the others are said to be left; without it the accelerometer
    file is refused as one without gravity (here by its norm, 0.38 m/s2)."""
    t, acc, gyro, gravity = _part()
    files = {"Accelerometer": (t, acc - gravity), "TotalAcceleration": (t, acc),
             "Gyroscope": (t + 0.003, gyro), "GyroscopeUncalibrated": (t + 0.003, gyro + 0.01),
             "Gravity": (t, gravity)}
    source = open_recording(_sensor_logger(tmp_path / "all", files))
    rec, _ = source.load()
    assert ("the accelerometer's TotalAcceleration.csv, the gyro's Gyroscope.csv "
            "(Accelerometer.csv, GyroscopeUncalibrated.csv left)") in source.choices
    assert "time in ns" in source.choices and source.rate == pytest.approx(100.0)
    np.testing.assert_allclose(rec.acc, acc, rtol=1e-8)  # each gyro row with the reading before it
    del files["TotalAcceleration"]
    with pytest.raises(RecordingError, match="linear or user acceleration"):
        open_recording(_sensor_logger(tmp_path / "no_total", files))


@pytest.mark.parametrize("names,message", [
    (("Linear Acceleration", "Gyroscope"), r"no file named for the accelerometer \(Linear "
     r"Acceleration.csv: named for an acceleration without gravity"),
    (("Accelerometer",), "no file named for the gyro"),
    (("Accelerometer", "accel", "Gyroscope"), "Accelerometer.csv, accel.csv are each named for "
     "the accelerometer"),
])
def test_files_that_cannot_be_told_apart_or_are_missing_are_refused(tmp_path, names, message):
    t, acc, gyro, _ = _part()
    folder = tmp_path / "export"
    folder.mkdir()
    for name in names:
        v = gyro if "Gyro" in name else acc
        np.savetxt(folder / f"{name}.csv", np.column_stack([t, v]), delimiter=",",
                   header="time,x,y,z", comments="")
    with pytest.raises(RecordingError, match=message):
        open_recording(folder)


def test_a_time_that_goes_back_or_files_of_two_clocks_are_refused_by_file_and_line(tmp_path):
    """Joined in the order of their times, a file whose time goes back would be silently
    reordered: refused by its line, the archive's member named (not where it was unpacked). Two
    files that share no stretch of time are no one recording."""
    t, acc, gyro, _ = _part()
    folder = _phyphox(tmp_path / "back", t, acc, gyro)
    lines = (folder / "Gyroscope.csv").read_text().splitlines()
    lines[100], lines[101] = lines[101], lines[100]
    (folder / "Gyroscope.csv").write_text("\n".join(lines))
    archive = _zipped(folder)
    with pytest.raises(RecordingError, match=rf"{archive}/Gyroscope.csv, line 102: the time goes "
                                             "back"):
        open_recording(archive)
    late = _phyphox(tmp_path / "late", t, acc, gyro)
    np.savetxt(late / "Gyroscope.csv", np.column_stack([t + 1e4, gyro]), delimiter=",",
               header="time,x,y,z", comments="")
    with pytest.raises(RecordingError, match="must share one clock"):
        open_recording(late)


def test_an_ios_export_is_refused_until_the_accelerometers_sign_is_given(tmp_path):
    """iOS gives the negative of specific force unless the app turned it, and a negated
    accelerometer reads as the phone upside down, its gyro explaining every turn: the data
    cannot tell. Sensor Logger's metadata names the platform, not the setting."""
    t, acc, gyro, _ = _part()
    android = open_recording(_sensor_logger(tmp_path / "android", {
        "TotalAcceleration": (t, acc), "Gyroscope": (t + 0.003, gyro)})).load()[0]
    folder = _sensor_logger(tmp_path / "ios", {"TotalAcceleration": (t, -acc),
                                               "Gyroscope": (t + 0.003, gyro)})
    (folder / "Metadata.csv").write_text("version,device name,recording time,platform\n"
                                         "3,iPhone,2023-10-28_13-52-24,ios\n")
    with pytest.raises(RecordingError, match=r"recorded on iOS.*give --acc-sign -1"):
        open_recording(folder)
    source = open_recording(folder, acc_sign="-1")
    assert "sign -1 (given)" in source.choices
    np.testing.assert_array_equal(source.load()[0].acc, android.acc)


def test_ios_sensorlogs_columns_are_core_motions_negative_in_g(tmp_path):
    """SensorLog (iOS only) writes Core Motion's accelerometer: in g, -1 g up at rest."""
    t, acc, gyro, _ = _part()
    path = tmp_path / "sensorlog.csv"
    np.savetxt(path, np.column_stack([t, -acc / G, gyro]), delimiter=",", comments="",
               header="loggingTime(s),accelerometerAccelerationX(G),accelerometerAccelerationY(G),"
               "accelerometerAccelerationZ(G),gyroRotationX(rad/s),gyroRotationY(rad/s),"
               "gyroRotationZ(rad/s)", fmt="%.17g")
    source = open_recording(path, time_column="loggingTime")
    assert "sign -1 (iOS's Core Motion" in source.choices
    np.testing.assert_allclose(source.load()[0].acc, acc, rtol=1e-12)
