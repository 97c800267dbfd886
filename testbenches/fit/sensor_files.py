"""A recording as phone apps export it: one file per sensor, in a folder or a zip archive.

Sensor Logger, phyphox and their like write each sensor's readings to a file of its own
(`Accelerometer.csv`, `Gyroscope.csv`, ...), each reading with its time on the phone's one
clock, and export the files together as a zip archive. `open_sensor_files` finds the
accelerometer's file and the gyro's by their names and gives the two as one table (a
testbenches.reader.TableSource) whose rows are theirs in the order of their times: a row of the
accelerometer's file holds no gyro reading and one of the gyro's no accelerometer reading, and
the recording joins them as it joins a logger's rows of their own (each gyro reading a sample,
with the accelerometer's latest; fit.recording).

Which file is which, by its name (case, spaces and punctuation ignored):

- the gyro: a name with "gyro"; a calibrated one before one named "uncalibrated" or "raw";
- the accelerometer: a name with "acc" ("accelerometer", "acceleration"): a "total" one first
  (Sensor Logger's TotalAcceleration.csv, where its Accelerometer.csv leaves gravity out), then a
  calibrated one, then an "uncalibrated" or "raw" one; never one named for linear or user
  acceleration, which phones give without gravity (the recording refuses an accelerometer
  without gravity whatever its name: testbenches.gravity).

The choices line says which files were taken and which were left. Within a file the axes are
the columns named x, y and z (Sensor Logger; phyphox's "X (m/s^2)") or named as in a recording
of both ("Acceleration x (m/s^2)", "Gyroscope x (rad/s)"), and the time is the column named as
a recording's time is (Sensor Logger's `time` in ns, phyphox's `Time (s)`), or the one given.
"""

from __future__ import annotations

import csv
import re
import tempfile
import zipfile
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

import numpy as np

from ..reader import open_table, zipped_table
from ..table import TableError, TableSource
from .columns import ALIASES, find_name, norm_name

TABLE_SUFFIXES = (".csv", ".txt", ".tsv", ".parquet", ".pq")
"""The files of a folder or archive that may be a sensor's table."""
WITHOUT_GRAVITY = ("linear", "user")
"""Words of a file's name that say its acceleration leaves gravity out."""
LESSER = ("uncalibrated", "raw")
"""Words of a file's name that make it the second choice for its sensor."""
KEPT_CHUNKS = 4
"""A read names the file and line of a row among this many of its latest blocks."""
SENSORS = {"acc": "accelerometer", "gyro": "gyro"}


def is_sensor_files(path: Path) -> bool:
    """Whether the path is a folder or a zip archive (read as one file per sensor), not an
    archive of one text file (read as that file: reader.zipped_table)."""
    return path.is_dir() or (path.suffix.lower() == ".zip" and zipfile.is_zipfile(path)
                             and zipped_table(path) is None)


def _rank(sensor: str, name: str) -> int | None:
    """A file's place among the sensor's candidates by its name (0 first), None where the name
    is not that sensor's (the module docstring)."""
    key = re.sub(r"[^a-z0-9]", "", PurePosixPath(name).stem.lower())
    lesser = any(w in key for w in LESSER)
    if sensor == "gyro":
        return (1 if lesser else 0) if "gyro" in key else None
    if "acc" not in key or any(w in key for w in WITHOUT_GRAVITY):
        return None
    return 0 if "total" in key else 2 if lesser else 1


def _listed(path: Path) -> list[str]:
    """The tables a folder or archive holds, as relative paths (hidden files and macOS's
    resource forks left out)."""
    if path.is_dir():
        names = [str(p.relative_to(path).as_posix()) for p in sorted(path.rglob("*"))
                 if p.is_file()]
    else:
        with zipfile.ZipFile(path) as z:
            names = sorted(i.filename for i in z.infolist() if not i.is_dir())
    return [n for n in names if PurePosixPath(n).suffix.lower() in TABLE_SUFFIXES
            and not any(part.startswith((".", "__MACOSX")) for part in PurePosixPath(n).parts)]


def _chosen(path: Path, names: list[str]) -> tuple[dict[str, str], list[str]]:
    """The file of each sensor and the candidates left; TableError where a sensor has none or
    two files of the same rank."""
    chosen, left = {}, []
    for sensor, label in SENSORS.items():
        ranked = sorted((r, n) for n in names if (r := _rank(sensor, n)) is not None)
        if not ranked:
            gravity_free = [n for n in names if _rank("gyro", n) is None
                            and "acc" in n.lower()] if sensor == "acc" else []
            why = (f" ({', '.join(gravity_free)}: named for an acceleration without gravity, "
                   "which the filters cannot use)" if gravity_free else "")
            held = ", ".join(names) or "no table"
            serve = (f"; if {names[0]} holds both sensors, give that file itself (unpacked)"
                     if len(names) == 1 else "")
            raise TableError(
                f"{path}: no file named for the {label}{why}; it holds {held}. A phone app's "
                "export holds one file per sensor, named for it (Accelerometer.csv or "
                f"TotalAcceleration.csv, Gyroscope.csv){serve}")
        best = [n for r, n in ranked if r == ranked[0][0]]
        if len(best) > 1:
            raise TableError(f"{path}: {', '.join(best)} are each named for the {label}: put "
                             "one recording's files in a folder or archive of their own")
        chosen[sensor] = best[0]
        left += [n for _, n in ranked[1:]]
    return chosen, left


PLATFORMS = {"ios": "iOS", "android": "Android"}
"""The platforms a phone app's metadata may name (Sensor Logger's Metadata.csv, `platform`)."""


def _platform(path: Path, names: list[str]) -> str:
    """The platform the export's metadata file names ("" where none does)."""
    for name in names:
        if PurePosixPath(name).stem.lower() != "metadata":
            continue
        if path.is_dir():
            text = (path / name).read_text(errors="replace")
        else:
            with zipfile.ZipFile(path) as z:
                text = z.read(name).decode(errors="replace")
        rows = list(csv.reader(text.splitlines()[:2]))
        if len(rows) == 2:
            cells = dict(zip((c.strip().lower() for c in rows[0]), rows[1], strict=False))
            found = PLATFORMS.get(cells.get("platform", "").strip().lower())
            if found:
                return found
    return ""


@dataclass
class _SensorTable:
    """One sensor's file opened: its table, the columns of its time and three axes, and how it
    is named in messages (the archive's path where it came from one)."""

    table: TableSource
    columns: list[int]
    shown: str

    def error(self, err: TableError) -> TableError:
        """The reader's error, naming the file as the user knows it."""
        return _shown(err, self.table.path, self.shown)


def _shown(err: TableError, file: Path, shown: str) -> TableError:
    """A reader's error about `file` (an archive's member unpacked), naming it `shown`."""
    return TableError(str(err).replace(str(file), shown))


def _open_one(path: Path, member: str, file: Path, sensor: str,
              time_column: str | None) -> _SensorTable:
    shown = str(path / member)
    try:
        table = open_table(file)
    except TableError as err:
        raise _shown(err, file, shown) from None
    t = find_name(table.header, "time", time_column) if time_column else None
    if t is None:
        t = find_name(table.names, "time", time_column)
    label = SENSORS[sensor]
    if t is None:
        raise TableError(f"{shown}: no time column (the header has {', '.join(table.header)}): "
                         f"the {label}'s readings are joined to the other sensor's by their "
                         "times; name it with --time-column")
    axes = [find_name(table.names, f"{sensor}_{a}", more=(a, f"{a}_axis")) for a in "xyz"]
    if None in axes:
        raise TableError(f"{shown}: no column for the {label}'s "
                         + ", ".join(a for a, i in zip("xyz", axes, strict=True) if i is None)
                         + f" axis (the header has {', '.join(table.header)}): name them x, y, "
                         "z")
    return _SensorTable(table, [t, *axes], shown)  # type: ignore[list-item]


def open_sensor_files(path: Path, time_column: str | None = None) -> TableSource:
    """The accelerometer's and the gyro's files of a folder or zip archive as one table
    (the module docstring): its columns time, acc_x, acc_y, acc_z, gyro_x, gyro_y, gyro_z, the
    units the files state, its rows theirs in the order of their times; TableError saying what
    is missing or which files are in doubt."""
    names = _listed(path)
    chosen, left = _chosen(path, names)
    owner = None
    if path.is_dir():
        files = {s: path / n for s, n in chosen.items()}
    else:  # the two members unpacked for the readers, for as long as the table lives
        owner = tempfile.TemporaryDirectory(prefix="imu-fusion-")
        with zipfile.ZipFile(path) as z:
            files = {s: Path(z.extract(n, owner.name)) for s, n in chosen.items()}
    parts = [_open_one(path, chosen[s], files[s], s, time_column) for s in SENSORS]
    acc = parts[0]
    times = [p.table.units[p.columns[0]] for p in parts]
    stated = {u for u in times if u is not None}
    if len(stated) > 1:
        raise TableError(f"{path}: the accelerometer's file states its time in {times[0]}, the "
                         f"gyro's in {times[1]}: the two are joined on one clock")
    time_names = {norm_name(p.table.names[p.columns[0]]) for p in parts}
    time_name = time_names.pop() if len(time_names) == 1 else "time"
    if time_name not in ALIASES["time"]:  # the name given: the table's time is "time"
        time_name = "time"
    header = [acc.table.header[acc.columns[0]],
              *(f"{p.shown.rpartition('/')[2]}: {p.table.header[i]}"
                for p in parts for i in p.columns[1:])]
    units = [stated.pop() if stated else None,
             *(p.table.units[i] for p in parts for i in p.columns[1:])]
    chunks: deque[tuple[int, np.ndarray, np.ndarray]] = deque(maxlen=KEPT_CHUNKS)

    def read(columns: list[int], rows: int) -> Iterator[np.ndarray]:
        chunks.clear()
        for row0, block, origin in _merged(parts, rows):
            chunks.append((row0, *origin))
            yield block[:, columns]

    def where(row: int) -> str:
        for row0, part, part_row in chunks:
            if row0 <= row < row0 + len(part):
                p = parts[int(part[row - row0])]
                return f"{p.shown.rpartition('/')[2]} {p.table.where(int(part_row[row - row0]))}"
        return f"row {row + 1} of the two files in the order of their times"

    note = (f"one file per sensor: the accelerometer's {chosen['acc']}, the gyro's "
            f"{chosen['gyro']}" + (f" ({', '.join(left)} left)" if left else ""))
    platform = _platform(path, names)
    kind = "a folder" if path.is_dir() else "a zip archive"
    return TableSource(path, header, [time_name, "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y",
                                      "gyro_z"], units, kind, None, read, where, note=note,
                       owner=owner, platform=platform)


def _merged(parts: list[_SensorTable], rows: int
            ) -> Iterator[tuple[int, np.ndarray, tuple[np.ndarray, np.ndarray]]]:
    """The two files' rows in the order of their times, `rows` at a time: (first row, block
    [n, 7] of time and the six axes, NaN for the other sensor's, (file, row in it) per row).
    An accelerometer row comes before a gyro row of the same time (the gyro's sample then joins
    it). A row without a time keeps its place in its file (the clock refuses it by its line);
    a file whose time goes back is refused by its line, since the order would hide it."""
    reads = [p.table.blocks(p.columns, rows) for p in parts]
    pending = [np.empty((0, 4)) for _ in parts]
    keys = [np.empty(0) for _ in parts]
    first = [0, 0]   # the file's row of pending's first row
    last = [-np.inf, -np.inf]
    done = [False, False]
    out: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    held = row0 = 0
    while True:
        for i, p in enumerate(parts):
            while not done[i] and len(pending[i]) == 0:
                try:
                    block = next(reads[i], None)
                except TableError as err:
                    raise p.error(err) from None
                if block is None:
                    done[i] = True
                    break
                key = np.fmax.accumulate(np.concatenate([[last[i]], block[:, 0]]))[1:]
                t = block[:, 0]
                back = np.flatnonzero(np.isfinite(t) & (t < np.concatenate([[last[i]], key[:-1]])))
                if back.size:
                    j = int(back[0])
                    raise TableError(f"{p.shown}, {p.table.where(first[i] + j)}: the time goes "
                                     f"back (to {t[j]:.10g}); a sensor's file holds its "
                                     "readings in the order of their times")
                pending[i], keys[i], last[i] = block, key, float(key[-1])
        if all(len(q) == 0 for q in pending):
            break
        if first == [0, 0]:  # nothing taken yet
            _overlap(parts, pending, keys)
        limit = min((keys[i][-1] for i in range(2) if not done[i] and len(keys[i])),
                    default=np.inf)
        taken = []
        for i in range(2):
            k = int(np.searchsorted(keys[i], limit, side="right"))
            rows_i = np.full((k, 7), np.nan)
            rows_i[:, 0] = pending[i][:k, 0]
            rows_i[:, 1 + 3 * i:4 + 3 * i] = pending[i][:k, 1:]
            taken.append((rows_i, keys[i][:k], np.full(k, i, np.int8),
                          first[i] + np.arange(k)))
            pending[i], keys[i], first[i] = pending[i][k:], keys[i][k:], first[i] + k
        order = np.argsort(np.concatenate([t[1] for t in taken]), kind="stable")
        out.append(tuple(np.concatenate([t[j] for t in taken])[order]  # type: ignore[arg-type]
                         for j in (0, 2, 3)))
        held += len(order)
        while held >= rows:
            row0, out, chunk = _cut(row0, out, rows)
            held -= len(chunk[1])
            yield chunk
    if held:
        yield _cut(row0, out, held)[2]


def _overlap(parts: list[_SensorTable], pending: list[np.ndarray], keys: list[np.ndarray]
             ) -> None:
    """TableError where one file's first time comes after the other's first block ends: the
    two are not of one recording on one clock (joined, every gyro reading would take one
    accelerometer reading, or none)."""
    if any(len(k) == 0 for k in keys):
        return
    for i, j in ((0, 1), (1, 0)):
        times = keys[i][np.isfinite(keys[i])]
        start, end = (times[0] if times.size else -np.inf), keys[j][-1]
        if start > end:
            raise TableError(f"{parts[i].shown}: its first time ({start:.10g}) comes after "
                             f"the last of {len(keys[j])} rows of {parts[j].shown} "
                             f"({end:.10g}): the two sensors' files must share one clock and "
                             "one stretch of time")


def _cut(row0: int, out: list[tuple[np.ndarray, np.ndarray, np.ndarray]], n: int
         ) -> tuple[int, list[tuple[np.ndarray, np.ndarray, np.ndarray]],
                    tuple[int, np.ndarray, tuple[np.ndarray, np.ndarray]]]:
    """The first n rows held (as _merged yields them) and what is left."""
    block, part, part_row = (np.concatenate(x) for x in zip(*out, strict=True))
    rest = [(block[n:], part[n:], part_row[n:])] if n < len(block) else []
    return row0 + n, rest, (row0, block[:n], (part[:n], part_row[:n]))
