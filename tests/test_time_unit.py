"""A time column in whatever unit a logger wrote it: milliseconds and nanoseconds as loggers
write them without a unit, the data deciding where two units give IMU rates, a recording that
cannot tell refused with the candidates, a given or stated unit whose rate no IMU has refused,
a reference in the recording's unit, and dates and times."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from testbenches.cli import main
from testbenches.fit.recording import RecordingError, concatenate, open_recording
from testbenches.time_unit import RATE_RANGE, candidates

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"
TRUTH = REPO / "examples" / "tilt_motion_truth.csv"
HEADER = "ax,ay,az,gx,gy,gz"


def _example(every: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The example's time [s] and its six IMU columns (every `every`th sample)."""
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)[::every]
    return data[:, 0], data[:, 1:7]


def _write(path: Path, time_name: str, t: np.ndarray, imu: np.ndarray) -> Path:
    np.savetxt(path, np.column_stack([t, imu]), delimiter=",", header=f"{time_name},{HEADER}",
               comments="", fmt="%.10g")
    return path


def _read(path: Path, **options: str) -> tuple[object, np.ndarray, np.ndarray]:
    source = open_recording(path, **options)
    rec, t = source.load()
    return source, rec, t


@pytest.mark.parametrize(("unit", "factor"), [("ms", 1e3), ("us", 1e6), ("ns", 1e9)])
def test_time_stamps_in_ms_us_or_ns_without_a_unit_are_read_as_such(tmp_path, unit, factor):
    """A logger's millis(), micros() or event times: the steps are an IMU's rate in one unit
    only, so the recording reads as the same one in seconds, and the choices say why."""
    t, imu = _example()
    seconds, rec_s, t_s = _read(_write(tmp_path / "s.csv", "time", t, imu))
    source, rec, got_t = _read(_write(tmp_path / f"{unit}.csv", "timestamp",
                                      np.round(t * factor), imu))
    assert source.rate == pytest.approx(100.0) and source.time_unit == unit
    assert f"time in {unit} (from its steps: a median step of" in source.choices
    np.testing.assert_allclose(got_t, t_s, atol=1e-9)
    np.testing.assert_allclose(rec.dt[1:], rec_s.dt[1:], atol=1e-9)
    assert seconds.time_unit == "s" and "time in s (from its steps" in seconds.choices


def test_a_dt_column_and_a_name_may_carry_the_unit(tmp_path):
    """dt in ms without a unit is found as the time is; time_ms states its unit by name, as
    t_ms does (it was no time column: "no time or dt column: give the sample rate ...")."""
    t, imu = _example()
    source, _, _ = _read(_write(tmp_path / "dt.csv", "dt", np.full(len(t), 10.0), imu))
    assert source.rate == pytest.approx(100.0) and "dt in ms" in source.choices
    for name in ("time_ms", "t_ms"):
        source, _, _ = _read(_write(tmp_path / f"{name}.csv", name, t * 1e3, imu))
        assert source.time_unit == "ms" and "time in ms (from the header)" in source.choices


@pytest.mark.parametrize(("name", "unit", "scale"), [
    ("Timestamp(epoch_ms)", "ms", 1e3), ("unix_time_ms", "ms", 1e3), ("Epoch (s)", "s", 1.0),
    ("epoch", "s", 1.0), ("timestamp (unix_us)", "us", 1e6)])
def test_a_time_named_as_since_1970_is_the_time(tmp_path, name, unit, scale):
    """A logger's time named for its epoch ("Timestamp(epoch_ms)", as an ESP32 sketch writes
    it; "unix_time_ms"; "epoch") was no time column: "no time or dt column: give the sample
    rate ...". It is the time, in the unit its name states, else the one its steps give."""
    t, imu = _example()
    path = tmp_path / "epoch.csv"
    np.savetxt(path, np.column_stack([(1.7e9 + t) * scale, imu]), delimiter=",",
               header=f"{name},{HEADER}", comments="", fmt=["%.6f"] + ["%.10g"] * 6)
    source, rec, _ = _read(path)
    assert source.time_unit == unit and f"time='{name}'" in source.choices
    np.testing.assert_allclose(rec.dt[1:], np.diff(t), atol=2e-6)


def test_where_two_units_give_imu_rates_the_data_decide(tmp_path):
    """A step of 0.05 is 20 Hz in s or 20 kHz in ms: in ms the gyro's turn is a thousand times
    too small in any gyro unit, in s one unit explains gravity's turn."""
    t, imu = _example(every=5)
    assert candidates(0.05) == ["s", "ms"]
    source, _, _ = _read(_write(tmp_path / "slow.csv", "time", t, imu))
    assert source.time_unit == "s" and source.rate == pytest.approx(20.0)
    assert "time in s (from the data: a median step of 0.05 is 20 Hz in s" in source.choices


def test_a_still_recording_with_two_candidate_units_is_refused_with_both(tmp_path):
    """At rest nothing turns, so nothing tells 20 Hz in s from 20 kHz in ms: refused, naming
    both, and --time-unit serves."""
    n = 400
    rng = np.random.default_rng(1)
    imu = np.column_stack([rng.normal(0, 0.02, (n, 2)), 9.81 + rng.normal(0, 0.02, n),
                           rng.normal(0, 0.001, (n, 3))])
    path = _write(tmp_path / "still.csv", "time", np.arange(n) * 0.05, imu)
    with pytest.raises(RecordingError, match=r"20 Hz in s or 2e\+04 Hz in ms.*--time-unit s or "
                       r"ms"):
        open_recording(path, gyro_unit="rad/s")
    source = open_recording(path, gyro_unit="rad/s", time_unit="s")
    assert source.rate == pytest.approx(20.0) and "time in s (given)" in source.choices


def test_a_unit_whose_rate_no_imu_has_is_refused(tmp_path):
    """A given unit, or one the header states, that makes a step of 10 ms 0.1 Hz: refused with
    the unit that fits (every sample would otherwise be rejected as dt > max_dt)."""
    t, imu = _example()
    path = _write(tmp_path / "ms.csv", "time", t * 1e3, imu)
    with pytest.raises(RecordingError, match=r"0.1 Hz in s \(given\).*in ms it is 100 Hz: give "
                       r"--time-unit ms"):
        open_recording(path, time_unit="s")
    stated = _write(tmp_path / "stated.csv", "time (s)", t * 1e3, imu)
    with pytest.raises(RecordingError, match=r"\(from the header\).*correct the unit in the "
                       "header"):
        open_recording(stated)
    with pytest.raises(RecordingError, match="--time-unit ms contradicts the header"):
        open_recording(stated, time_unit="ms")
    assert RATE_RANGE[0] > 1.0  # max_dt: a slower rate's every sample is rejected


def test_a_reference_in_the_recordings_unit_is_matched(tmp_path, capsys):
    """Recording and reference both in ms without a unit: the scores are those of the same
    files in seconds."""
    t, imu = _example()
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)[:, :3]
    for name, factor in (("s", 1.0), ("ms", 1e3)):
        rec = _write(tmp_path / f"rec_{name}.csv", "time", t * factor, imu)
        ref = tmp_path / f"ref_{name}.csv"
        np.savetxt(ref, np.column_stack([truth[:, 0] * factor, truth[:, 1:]]), delimiter=",",
                   header="time,roll,pitch", comments="", fmt="%.10g")
        assert main(["estimate", str(rec), "--reference", str(ref), "--estimator", "kf",
                     "--out", str(tmp_path / name), "--no-plots", "--no-vqf"]) == 0
    said = capsys.readouterr().out
    rows = [line.split()[2] for line in said.splitlines() if line.startswith("kf ")]
    assert len(rows) == 2 and rows[0] == rows[1]


def _iso(t: np.ndarray, zone: str = "", sep: str = "T") -> list[str]:
    start = np.datetime64("2024-05-01T12:00:00", "us")
    return [str(start + np.timedelta64(round(v * 1e6), "us")).replace("T", sep) + zone
            for v in t]


def test_dates_and_times_are_seconds_since_1970_beside_a_reference_in_them(tmp_path, capsys):
    """ISO 8601 time stamps (a space for the T, with a zone or without, then UTC; a reference
    with Z): the score is that of the same files in seconds, and a cell that is no date and
    time is refused by its line."""
    t, imu = _example()
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)[:, :3]
    rec = tmp_path / "dated.csv"
    stamps = _iso(t, sep=" ")
    stamps[1::2] = [s + "+00:00" for s in stamps[1::2]]  # mixed: Python's reader takes them
    rec.write_text("timestamp," + HEADER + "\n" + "".join(
        f"{s}," + ",".join(f"{v:.10g}" for v in row) + "\n"
        for s, row in zip(stamps, imu, strict=True)))
    ref = tmp_path / "ref.csv"
    ref.write_text("time,roll,pitch\n" + "".join(
        f"{s},{r:.17g},{p:.17g}\n"
        for s, r, p in zip(_iso(truth[:, 0], "Z"), truth[:, 1], truth[:, 2], strict=True)))
    plain = _write(tmp_path / "plain.csv", "time", t, imu)
    plain_ref = tmp_path / "plain_ref.csv"
    np.savetxt(plain_ref, truth, delimiter=",", header="time,roll,pitch", comments="",
               fmt="%.17g")
    for r, f in ((rec, ref), (plain, plain_ref)):
        assert main(["estimate", str(r), "--reference", str(f), "--estimator", "kf", "--out",
                     str(tmp_path / r.stem), "--no-plots", "--no-vqf"]) == 0
    said = capsys.readouterr().out
    assert "time from its dates and times (seconds since 1970, UTC)" in said
    rows = [line.split()[2] for line in said.splitlines() if line.startswith("kf ")]
    assert len(rows) == 2 and rows[0] == rows[1]
    lines = rec.read_text().splitlines()
    lines[300] = "noon" + lines[300][lines[300].index(","):]
    rec.write_text("\n".join(lines) + "\n")
    said = open_recording(rec).load()[0].described
    assert "1 line(s) no row of the table, taken as samples without a number (a logger's " \
           "garbled or lost bytes; the first: line 301, column 'timestamp': 'noon' is not a " \
           "date and time" in said


def test_a_microcontrollers_counter_that_starts_again_goes_on(tmp_path):
    """micros() is 32 bits and starts again every 71.6 minutes: a fall by 2^32 us to one
    period is the counter going on, in the first block or a later one, and the read says so;
    a time that really goes back is still refused by its line."""
    t, imu = _example()
    _, _, t_plain = _read(_write(tmp_path / "s.csv", "time", t, imu))
    ticks = (2**32 - 5_000_000 + np.round(t * 1e6).astype(np.int64)) % 2**32
    path = _write(tmp_path / "micros.csv", "micros", ticks, imu)
    source = open_recording(path)
    assert source.time_unit == "us" and "time in us (from the header)" in source.choices
    for rows in (None, 64):  # the wrap inside the first block, then between blocks
        parts = list(source.blocks(rows=rows))
        got = np.concatenate([tt for _, tt in parts])
        np.testing.assert_allclose(got - got[0], t_plain - t_plain[0], atol=1e-9)
        dt = np.concatenate([p.dt for p, _ in parts])
        assert np.all(np.isfinite(dt)) and np.allclose(dt[1:], 0.01, atol=1e-9)
    rec, _ = source.load()
    assert "counter started again 1 time(s)" in rec.described
    ticks[300:] -= 3_000_000  # back by 3 s before the wrap: no wrap
    with pytest.raises(RecordingError, match="does not increase"):
        open_recording(_write(tmp_path / "back.csv", "micros", ticks % 2**32, imu)).load()


def test_a_16_bit_counter_that_starts_again_goes_on(tmp_path):
    """A timer's 16-bit count of ms starts again every 65.5 s: a fall by 2^16 ms from below
    it was refused as a recording written on after another ("split the file there"); of us,
    every 6.5 samples at 100 Hz. A 32-bit counter past 2^16 that falls by as much goes back
    in time, and is still refused."""
    t, imu = _example()
    _, _, t_plain = _read(_write(tmp_path / "s.csv", "time", t, imu))
    for unit, ticks in (("ms", (60_000 + np.round(t * 1e3).astype(np.int64)) % 2**16),
                        ("us", np.round(t * 1e6).astype(np.int64) % 2**16)):
        path = _write(tmp_path / f"{unit}16.csv", f"time_{unit}", ticks, imu)
        source = open_recording(path, gyro_unit="rad/s")
        assert source.time_unit == unit
        for rows in (None, 64):
            got = np.concatenate([tt for _, tt in source.blocks(rows=rows)])
            np.testing.assert_allclose(got - got[0], t_plain - t_plain[0], atol=1e-9)
        rec, _ = source.load()
        assert f"the time's 16-bit counter started again {1 if unit == 'ms' else 152} " \
               "time(s), taken as going on" in rec.described
    ticks = 100_000 + np.round(t * 1e3).astype(np.int64)  # a 32-bit ms counter past 2^16
    ticks[556:] -= 2**16
    with pytest.raises(RecordingError, match="does not increase"):
        open_recording(_write(tmp_path / "back.csv", "time_ms", ticks, imu),
                       gyro_unit="rad/s").load()


@pytest.mark.parametrize("start", [12 * 3600.0, 86400.0 - 5.0])
def test_a_time_of_day_reads_as_seconds_since_midnight_and_passes_midnight(tmp_path, start):
    """A logger's real-time clock or a spreadsheet's time format: "12:00:00.010", no date. A
    recording that passes midnight goes on (the read says so); a cell that is no time of day is
    refused by its line, and a time unit given for it is refused."""
    t, imu = _example()
    day = (start + t) % 86400.0
    stamps = [f"{int(s // 3600):02d}:{int(s % 3600 // 60):02d}:{s % 60:06.3f}" for s in day]
    lines = ["time," + HEADER] + [f"{s}," + ",".join(f"{v:.10g}" for v in row)
                                  for s, row in zip(stamps, imu, strict=True)]
    path = tmp_path / "clock.csv"
    path.write_text("\n".join(lines))
    source, rec, _ = _read(path)
    assert "time from its times of day" in source.choices and source.rate == pytest.approx(100.0)
    np.testing.assert_allclose(rec.dt[1:], np.diff(t), atol=1e-9)
    assert ("passed midnight 1 time(s)" in rec.described) == (start > 12 * 3600.0)
    with pytest.raises(RecordingError, match="--time-unit s is given, but the time column holds "
                                             "times of day"):
        open_recording(path, time_unit="s")
    lines[300] = "noon," + lines[300].split(",", 1)[1]
    path.write_text("\n".join(lines))
    assert "no row of the table, taken as samples without a number (a logger's garbled or " \
           "lost bytes; the first: line 301, column 'time': 'noon' is not a time of day" in \
           _read(path)[1].described


def test_a_repeated_time_is_refused_with_the_rate_and_a_given_rate_serves(tmp_path):
    """A logger's millisecond stamps at 1.6 kHz repeat: the file was refused with no way to read
    it but editing, since a time column took precedence over --rate. The refusal now says how
    often the time repeats and the rate on average; --rate spaces the samples by the rate, the
    time left, and says so."""
    _, imu = _example()
    stamps = np.floor(np.arange(len(imu)) / 1.6).astype(int)  # ms at 1.6 kHz
    path = _write(tmp_path / "ms.csv", "time_ms", stamps, imu)
    with pytest.raises(RecordingError, match=r"line 3: the time 0 s repeats the time 0 s on "
                                             r"line 2 \(375 of the first 999 steps are 0.*"
                                             r"give --rate 1601"):
        open_recording(path, gyro_unit="rad/s")
    source = open_recording(path, gyro_unit="rad/s", rate=1600.0)
    assert "time from the rate given (1600 Hz), the file's time column left" in source.choices
    rec, _ = source.load()
    np.testing.assert_array_equal(rec.dt, np.full(len(imu), 1 / 1600.0))
    with pytest.raises(RecordingError, match="--rate is given, but so is --time-unit"):
        open_recording(path, rate=1600.0, time_unit="ms")


def test_a_time_coarser_than_the_samples_is_sized_by_its_mean_step(tmp_path):
    """Whole epoch seconds at 100 Hz rise by 1 a hundred rows apart: sized by that tick the
    time was taken as ms and the refusal offered --rate 1.11e+05; by its mean step it is
    seconds, and the rate offered is the samples' (111 Hz over the first 9 s: the last
    second's rows count, not its span)."""
    t, imu = _example()
    path = _write(tmp_path / "epoch.csv", "timestamp", 1_700_000_000 + np.floor(t), imu)
    with pytest.raises(RecordingError, match=r"the time 1\.7e\+09 s repeats .* give --rate 111 "):
        open_recording(path)


def test_a_given_rate_that_contradicts_a_time_that_serves_is_refused(tmp_path):
    """--rate overrides a file's time column, for a time that cannot serve: given with one that
    can, at another rate (200 Hz on the example's 100 Hz, with --gyro-unit so that no other
    evidence refuses it), the estimators integrated the gyro over half the time, said only as
    'time from the rate given'. Refused now, with the column's rate; within 2 % it is taken."""
    t, imu = _example()
    path = _write(tmp_path / "timed.csv", "time", t, imu)
    with pytest.raises(RecordingError, match=r"--rate 200 contradicts its time column 'time', "
                                             r"whose steps give 100 Hz: leave --rate out"):
        open_recording(path, gyro_unit="rad/s", rate=200.0)
    source = open_recording(path, gyro_unit="rad/s", rate=101.0)
    assert "time from the rate given (101 Hz)" in source.choices


@pytest.mark.parametrize("at", [500, 499, 0])  # in a block, the first of the second, the first
def test_a_row_written_twice_is_rejected_and_counted_not_a_refusal(tmp_path, at):
    """A logger that writes a row twice (its time and every number): the file was refused
    ('the time 4.99 s repeats ...'). The row is now a sample without a time, which the
    estimators reject and count, said apart from rows without numbers; the rest as without it,
    across a block's edge too."""
    t, imu = _example()
    rows = np.insert(np.arange(len(t)), at + 1, at)
    path = _write(tmp_path / "twice.csv", "time", t[rows], imu[rows])
    source = open_recording(path)
    parts = list(source.blocks(500))
    rec = concatenate([p for p, _ in parts])
    assert len(rec.dt) == len(t) + 1 and int((~rec.valid).sum()) == 1
    assert not rec.valid[at + 1]
    kept = np.delete(np.arange(len(rec.dt)), at + 1)
    once = _read(_write(tmp_path / "once.csv", "time", t, imu))[1]
    np.testing.assert_array_equal(rec.gyro[kept], once.gyro)
    np.testing.assert_array_equal(rec.dt[kept][1:], once.dt[1:])
    said = source.summary(len(rec.dt), 0.0, 1)
    assert "1 row(s) repeat the row before them, time and numbers" in said
    assert "without a number in every column" not in said


@pytest.mark.parametrize("form", ["%Y-%m-%dT%H:%M:%S.%f", "%Y/%m/%d %H:%M:%S.%f",
                                  "%d.%m.%Y %H:%M:%S,%f"])
def test_dates_and_times_as_locales_write_them_are_read_at_pyarrows_speed(tmp_path,
                                                                          monkeypatch, form):
    """The year first with slashes (East Asian locales) and the day first with dots and a
    decimal comma (German, with semicolons and decimal commas in the numbers as well): the
    same times as ISO 8601, through pyarrow's reader (rewritten as ISO 8601 for it), not
    Python's. A day and month with slashes is refused: it reads either way."""
    import datetime as dt

    import testbenches.reader as reader

    t, imu = _example()
    start = dt.datetime(2024, 5, 1, 23, 59, 55)  # across midnight
    stamps = [(start + dt.timedelta(seconds=float(s))).strftime(form)[:-3] for s in t]
    comma = "," in form
    rows = [";".join([s, *(f"{v:.10g}".replace(".", ",") for v in row)]) if comma else
            ",".join([s, *(f"{v:.10g}" for v in row)]) for s, row in zip(stamps, imu, strict=True)]
    path = tmp_path / "dates.csv"
    path.write_text("\n".join([f"time{';' if comma else ','}"
                               + HEADER.replace(",", ";" if comma else ","), *rows]) + "\n")
    monkeypatch.setattr(reader, "_python_parts", None)  # pyarrow's reader alone
    source, rec, times = _read(path)
    assert "time from its dates and times" in source.choices
    np.testing.assert_allclose(times - times[0], t - t[0], atol=1e-6)
    assert times[0] == pytest.approx(start.replace(tzinfo=dt.timezone.utc).timestamp())
    np.testing.assert_allclose(rec.gyro, imu[:, 3:], rtol=1e-9)
    us = tmp_path / "us.csv"
    us.write_text("time,ax,ay,az,gx,gy,gz\n" + "".join(
        f"05/01/2024 12:00:{k / 100:05.2f},0,0,9.8,0,0,0\n" for k in range(50)))
    with pytest.raises(RecordingError, match=r"column 'time': dates with the day and the "
                       r"month before the year \('05/01/2024 12:00:00.00'\), which read as "
                       r"the month first or the day first alike"):
        open_recording(us).load()
    beside = tmp_path / "beside.csv"  # such a column is refused only where it is read
    beside.write_text("date,time,ax,ay,az,gx,gy,gz\n" + "".join(
        f"05/01/2024 12:00:{k / 100:05.2f},{k / 100},0,0,9.8,0,0,0\n" for k in range(50)))
    rec, times = open_recording(beside, gyro_unit="rad/s").load()
    np.testing.assert_allclose(times, np.arange(50) / 100)


@pytest.mark.parametrize("form", ["%Y-%m-%dT%H:%M:%S.%f", "%Y/%m/%d %H:%M:%S.%f", "%H:%M:%S.%f",
                                  "%d.%m.%Y %H:%M:%S.%f", "%Y-%m-%d %H:%M:%S:%f"])
def test_dates_and_times_are_the_same_seconds_to_either_reader(tmp_path, monkeypatch, form):
    """pyarrow's reader and Python's give a date's or a time of day's seconds to the last bit:
    its whole seconds and its fraction added (one rounding); pyarrow's took its nanoseconds
    times 1e-9, which rounds twice, so that the samples' dt parted by up to 5e-7 s."""
    import datetime as dt

    import testbenches.reader as reader

    t, imu = _example()
    start = dt.datetime(2024, 5, 1, 12, 0, 0)
    stamps = [(start + dt.timedelta(seconds=float(s))).strftime(form)[:-3] for s in t]
    path = tmp_path / "dates.csv"
    path.write_text("\n".join([f"time,{HEADER}", *(",".join([s, *(f"{v:.10g}" for v in row)])
                                                  for s, row in zip(stamps, imu, strict=True))])
                    + "\n")
    arrow, arrow_t = open_recording(path, gyro_unit="rad/s").load()
    monkeypatch.setattr(reader, "_has_pyarrow", lambda: False)
    python, python_t = open_recording(path, gyro_unit="rad/s").load()
    np.testing.assert_array_equal(arrow_t, python_t)
    np.testing.assert_array_equal(arrow.dt, python.dt)


@pytest.mark.parametrize("form", ["{h}:{m:02d}:{s:02d}:{ms:03d}",
                                  "{h:02d}:{m:02d}:{s:02d}:{ms:03d}",
                                  "{h}:{m:02d}:{s:02d}.{ms:03d}"])
def test_a_physics_toolbox_time_of_day_reads_alike_in_either_reader(tmp_path, monkeypatch, form):
    """Physics Toolbox Sensor Suite writes the milliseconds after a colon ("9:05:00:010"), and
    some loggers an hour of one digit: a time of day pyarrow's reader does not parse. The file
    was refused ("'17:36:12:010' is not a number"); it is read as times of day, to the same
    seconds in either reader (the other forms rewritten for pyarrow's, not left to Python's)."""
    import testbenches.reader as reader

    t, imu = _example()
    ms = np.round((9 * 3600 + 5 * 60 + t) * 1000).astype(int)
    stamps = [form.format(h=k // 3_600_000, m=k // 60_000 % 60, s=k // 1000 % 60, ms=k % 1000)
              for k in ms]
    path = tmp_path / "ptb.csv"
    path.write_text("\n".join([f"time,{HEADER}", *(",".join([s, *(f"{v:.10g}" for v in row)])
                                                   for s, row in zip(stamps, imu, strict=True))])
                    + "\n")
    calls = []
    monkeypatch.setattr(reader, "_python_parts",
                        lambda *a, **k: calls.append(1) or iter(()))  # pyarrow's alone
    source = open_recording(path, gyro_unit="rad/s")
    arrow, arrow_t = source.load()
    assert not calls and "time from its times of day" in source.choices
    np.testing.assert_allclose(arrow_t, ms / 1000.0, rtol=0, atol=1e-9)
    monkeypatch.undo()
    monkeypatch.setattr(reader, "_has_pyarrow", lambda: False)
    python, python_t = open_recording(path, gyro_unit="rad/s").load()
    np.testing.assert_array_equal(arrow_t, python_t)
    np.testing.assert_array_equal(arrow.dt, python.dt)


def test_a_timecode_is_no_time_of_day():
    """A video timecode's frames after a colon ("01:00:00:12", two digits) are no milliseconds:
    only three digits after the seconds' colon are."""
    from testbenches.reader import seconds_of_day

    assert seconds_of_day("01:00:00:12") is None
    assert seconds_of_day("01:00:00:120") == 3600.12
    assert seconds_of_day("1:00:00,5") == 3600.5


def test_a_spreadsheets_dates_saved_as_numbers_are_named_in_the_refusal(tmp_path):
    """A sheet's date and time column saved as numbers (days since 1899-12-30: 45413.5...)
    steps by 1.16e-7 at 100 Hz, a rate in no unit the reader takes: refused, naming what it
    likely is and how to save it."""
    t, imu = _example()
    days = 45413.5 + t / 86400.0
    path = tmp_path / "sheet.csv"
    np.savetxt(path, np.column_stack([days, imu]), delimiter=",", header=f"time,{HEADER}",
               comments="", fmt=["%.10f"] + ["%.10g"] * 6)
    with pytest.raises(RecordingError, match=r"in days it is 100 Hz: a spreadsheet's dates and "
                       r"times saved as numbers \(days since 1899-12-30\)\? Format the column "
                       r"as a date and time"):
        open_recording(path)


def test_gaps_in_the_time_are_said(tmp_path):
    """Samples a logger dropped or a pause leave a step of several periods: the estimators
    integrate the next sample over it, or reject it past their max_dt, and the read said
    neither. It says how many, the longest and where, in blocks as whole; a clock's jitter,
    rows without numbers and rows without a time are no gap."""
    t, imu = _example()
    t = t.copy()
    t[300:] += 0.04  # four samples' time dropped before line 302
    t[700:] += 300.0  # a pause of five minutes before line 702
    source = open_recording(_write(tmp_path / "gaps.csv", "time", t, imu), gyro_unit="rad/s")
    rec, _ = source.load()
    assert ("2 gap(s) in the time of 2.5 sample periods or more (samples dropped, a pause; the "
            "longest 300 s, before the sample on line 702): the estimators integrate the sample "
            "after a gap over it, or reject it where the gap exceeds their max_dt (1 s)"
            in rec.described)
    list(source.blocks(rows=64))
    assert source.summary(0, 0.0, 0).endswith(rec.described[rec.described.index("; 2 gap"):])
    t = _example()[0] + np.random.default_rng(0).uniform(-0.004, 0.004, len(t))
    holes = imu.copy()
    holes[400:403, 0] = np.nan  # three rows without numbers: samples said on their own, as
    t[500:502] = np.nan  # are two rows without a time
    plain, _ = open_recording(_write(tmp_path / "jitter.csv", "time", t, holes),
                              gyro_unit="rad/s").load()
    assert "gap" not in plain.described and "5 sample(s) without a number" in plain.described
