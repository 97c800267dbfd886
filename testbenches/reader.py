"""Reading a recording's table as a logger, a spreadsheet or a data tool wrote it.

`open_table(path)` opens a file as named columns read in blocks of rows, so that a recording of
any length is read in bounded memory:

- delimited text (CSV and its kin), also compressed (gzip, bz2 or xz: .csv.gz and the like,
  told by the file's first bytes; a stream cut before its end read up to the cut, and said
  in TableSource.found): the encoding (UTF-8 with or without a byte-order mark,
  UTF-16 as Windows' "Unicode" exports write it, else Latin-1), the line end (a line feed,
  with a carriage return before it or not, or a carriage return alone), the delimiter (comma,
  semicolon, tab or bar, one after the rows' or the header's last cell read through; else
  runs of spaces; a decimal comma where the numbers have one) and the header row are
  found from the file's start (after LabVIEW's ***End_of_Header*** lines); pyarrow's CSV reader
  parses it (numbers with spaces around them too; dates and times so padded, or in other
  forms than ISO 8601's, as text it rewrites), and where it cannot (text where a number
  belongs, a row of the wrong length) the file is read by Python's csv module, which names
  the file's line, the column and the value; a last line a logger cut short mid-write and
  the NUL bytes of a preallocated file's unwritten rest are left out, and said
  (`TableSource.note`);
- a column of ISO 8601 dates and times ("2024-05-01T12:00:00.010", with a zone or without one,
  then taken as UTC) as seconds since 1970, as a Parquet timestamp column;
- a column of durations written with their unit ("0.01 sec", as MATLAB's writetimetable writes
  a timetable's row times) as seconds;
- Parquet and Arrow IPC (Feather): its columns (a timestamp column as seconds), a struct of
  numbers or a list of k numbers a row as a column per number;
- a spreadsheet workbook or JSON is refused, saying to save or export it as CSV (a table of
  text named .xls is read as text), and an
  ArduPilot DataFlash log saying which tool exports its IMU;
- a PX4 flight log (ULog, read with pyulog): its sensor_combined topic, named as ulog2csv
  names its columns;
- HDF5 (that is not a BROAD trial) and MATLAB .mat: their arrays of samples, at any depth of
  groups or structs, by testbenches.array_files (vectors, matrices of a column per quantity,
  compound datasets, pandas' HDFStore).

A header may span several rows (motion capture's: OptiTrack Motive names a rigid body's
quaternion X, Y, Z, W under a row of "Rotation"): its names are its last row of text, each after
the group the row above names ("Rotation X"). A unit stated in a column's name ("Gyroscope X
(deg/s)", "acc_x [m/s^2]"), in a row of units under or over the names or, in Parquet and HDF5,
in the column's `unit` or `units` metadata, is read off it. Values become floats; an empty
cell, NaN or inf is kept as not-a-number (the estimators reject such a sample and count it, so
one bad row does not refuse a file). Line numbers are the file's, counting the header as line 1;
other formats count rows from 1.
"""

from __future__ import annotations

import collections
import csv
import datetime as dt
import io
import re
import warnings
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from .array_files import arrays_table, hdf5_table, mat_table
from .table import (
    BLOCK_ROWS,
    DATETIME,
    DURATION,
    OTHER_UNITS,
    TIME_OF_DAY,
    TIME_SCALE,
    TableError,
    TableSource,
    split_unit,
    ticks_seconds,
    unit_named,
    unit_of,
)

DELIMITERS = ",;\t|"
COMMENTS = ("#", "//")
"""A line that starts with one of these before the header is a comment (numpy.savetxt writes
its header as "# time,acc_x,...", which is taken as the header where the rows follow it). Not
"%": a ROS topic's CSV header starts "%time"."""
MISSING_VALUES = ("", "#n/a", "#n/a n/a", "#na", "-1.#ind", "-1.#qnan", "-nan", "1.#ind",
                  "1.#qnan", "n/a", "na", "null", "nan")
"""Cells that mark a missing value, case ignored: pyarrow's CSV reader's own marks, which
Python's reader takes as well. Its sample is rejected and counted; a row of them is a row of
data, not a header's row of names."""
HEADER_CHECK = 20
"""The header must split into as many cells as this many lines after it, but for
HEADER_CHECK_ODD of them (a line a logger garbled: a sample without numbers, _python_parts)."""
HEADER_CHECK_ODD = 1
PREAMBLE_LINES = 30
"""The header is looked for among the first this many lines that are not comments."""
SNIFF_BYTES = 1 << 16
"""How much of a text file's start the delimiter, encoding and header are found from."""



def open_table(path: str | Path, want: str = "imu") -> TableSource:
    """The file's table (the module docstring), by its content and suffix; TableError saying
    what is wrong. `want` ("imu" or "pose") chooses among the arrays of an HDF5 or MATLAB
    file those of the length that holds it (array_files.WANTED)."""
    path = Path(path)
    if not path.is_file():
        raise TableError(f"{path}: no such file")
    suffix = path.suffix.lower()
    with path.open("rb") as f:
        head = f.read(TEXT_CHECK)
    magic = head[:8]
    binary = _binary_format(head)
    named_other = suffix in BINARY_SUFFIXES or (  # a workbook's name on a table of text
        suffix in SHEET_SUFFIXES and not magic.startswith(b"PK\x03\x04")
        and not head.lstrip().startswith(b"<"))  # (an HTML page so named is refused)
    if binary is None and named_other and _text_like(head):
        source = _text(path)  # a CSV renamed (or saved under the wrong name): read as it is
        source.note = "; ".join(filter(None, [f"named {suffix} but text: read as text",
                                              source.note]))
        return source
    binary = binary or BINARY_SUFFIXES.get(suffix)
    if binary == "parquet":
        return _parquet(path)
    if binary == "arrow":
        return _arrow_ipc(path)
    if binary == "hdf5":
        return hdf5_table(path, want)
    if binary == "mat":
        return mat_table(path, want)
    if suffix == ".zip" and not zipfile.is_zipfile(path):  # one that opens: a workbook's text
        raise TableError(f"{path}: a zip archive that does not open: cut or damaged (no "
                         "directory of its files at its end): copy or download it again")
    if ((magic.startswith(b"PK\x03\x04") and zipped_table(path) is None)
            or suffix in SHEET_SUFFIXES):
        raise TableError(f"{path}: a spreadsheet workbook (or another zip archive), which is no "
                         "table this reader takes: save the sheet as CSV (a zip archive of a "
                         "phone app's files serves under a .zip name)")
    if magic.startswith(ULOG_MAGIC):
        return _ulog(path)
    if magic.startswith(b"\xa3\x95") and suffix in (".bin", ".log"):
        raise TableError(f"{path}: an ArduPilot DataFlash log, which is no table this reader "
                         "takes: export its IMU messages with pymavlink's mavlogdump.py "
                         "--types IMU --format csv FILE.bin > imu.csv (ArduPilot logs z down: "
                         "--mounting 180,0,0)")
    if magic.lstrip()[:1] in (b"[", b"{") and suffix in (".json", ".jsonl", ".ndjson"):
        raise TableError(f"{path}: JSON, which is no table this reader takes: export the "
                         "recording as CSV (phone apps offer both)")
    return _text(path)


SHEET_SUFFIXES = (".xlsx", ".xls", ".ods")
"""A spreadsheet workbook's names: refused (save the sheet as CSV) unless the file is text,
as an export that names a CSV or a tab-separated table .xls so that a spreadsheet opens it."""
BINARY_SUFFIXES = {".parquet": "parquet", ".pq": "parquet", ".feather": "arrow",
                   ".arrow": "arrow", ".ipc": "arrow", ".h5": "hdf5", ".hdf5": "hdf5",
                   ".mat": "mat"}
"""The formats a suffix names, where the file's first bytes name none (a MATLAB v4 file has no
magic bytes); the first bytes decide where they name one (a file saved under another
suffix), and a file of such a suffix whose first bytes are text is read as text."""
TEXT_CHECK = 1 << 14
"""How many of a file's first bytes tell text from a binary format (past the last place an
HDF5 signature is looked for, HDF5_SIGNATURE_AT)."""


def _binary_format(head: bytes) -> str | None:
    """The binary format a file's first bytes name: Parquet, Arrow IPC (Feather), HDF5 (also
    after a user block, as MATLAB v7.3's 512-byte header) or MATLAB v5; None for none of
    them."""
    if head.startswith(b"PAR1"):
        return "parquet"
    if head.startswith(ARROW_MAGIC):
        return "arrow"
    if any(head[at:at + 8] == HDF5_SIGNATURE for at in HDF5_SIGNATURE_AT):
        return "hdf5"
    if head.startswith(b"MATLAB 5.0 MAT-file"):
        return "mat"
    return None


HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
HDF5_SIGNATURE_AT = (0, 512, 1024, 2048, 4096, 8192)
"""Where HDF5 looks for its superblock's signature: at 0 or after a user block of 512 bytes
times a power of two (MATLAB v7.3 writes 512; h5py's userblock_size takes any such size).
The first TEXT_CHECK bytes, which decide the format, reach past the last listed."""


def _text_like(head: bytes) -> bool:
    """Whether a file's first bytes are text: no NUL byte, or UTF-16's byte-order mark."""
    return head.startswith((b"\xff\xfe", b"\xfe\xff")) or (bool(head) and b"\x00" not in head)


ULOG_MAGIC = b"ULog\x01\x12\x35"
ULOG_TOPIC = "sensor_combined"
"""The topic of a PX4 log that holds its IMU's samples (as ulog2csv names its columns)."""


def _ulog(path: Path) -> TableSource:
    """A PX4 flight log's sensor_combined topic, its columns as ulog2csv names them
    (`timestamp` in us, `gyro_rad[0]`, `accelerometer_m_s2[0]`), read with pyulog."""
    try:
        from pyulog import ULog
    except ImportError:
        raise TableError(f"{path}: a PX4 flight log (ULog), which takes the pyulog package to "
                         "read (pip install pyulog)") from None
    try:
        log = ULog(str(path), [ULOG_TOPIC])
    except Exception as err:  # pyulog raises what its parser meets: an unreadable log
        raise TableError(f"{path}: not a readable PX4 log ({err})") from None
    found = [d for d in log.data_list if d.name == ULOG_TOPIC]
    if not found:
        raise TableError(f"{path}: a PX4 log without the {ULOG_TOPIC} topic (its IMU's "
                         "samples as the estimators take them)")
    arrays = {k: np.asarray(v) for k, v in found[0].data.items()}
    source = arrays_table(path, "PX4 ULog", arrays)
    source.note = f"topic {ULOG_TOPIC} ({len(arrays['timestamp'])} messages)"
    return source


COMPRESSIONS = {b"\x1f\x8b": "gzip", b"BZh": "bz2", b"\xfd7zXZ\x00": "xz"}
"""A compressed text file's magic bytes and its compression: read as the text it holds."""


ZIPPED_SUFFIXES = (".csv", ".txt", ".tsv", ".dat")
"""The suffixes of the one file a zip archive may hold to be read as that text file (a
recording zipped to be sent); an archive of more files is a phone app's export."""


def zipped_table(path: Path) -> str | None:
    """The one text file a zip archive holds (ZIPPED_SUFFIXES; macOS's resource forks and
    hidden files aside), None for any other archive or file."""
    if not zipfile.is_zipfile(path):
        return None
    with zipfile.ZipFile(path) as z:
        names = [i.filename for i in z.infolist() if not i.is_dir()
                 and not any(part.startswith((".", "__MACOSX")) for part in i.filename.split("/"))]
    if len(names) == 1 and Path(names[0]).suffix.lower() in ZIPPED_SUFFIXES:
        return names[0]
    return None


def _compression(path: Path) -> str | None:
    with path.open("rb") as f:
        magic = f.read(6)
    if magic.startswith(b"PK\x03\x04") and zipped_table(path) is not None:
        return "zip"
    return next((kind for m, kind in COMPRESSIONS.items() if magic.startswith(m)), None)


def _unzipped(path: Path, mode: str) -> IO[bytes]:
    """The one text file of a zip archive (zipped_table), as a stream of its bytes."""
    member = zipped_table(path)
    assert member is not None
    return zipfile.ZipFile(path).open(member)  # the archive closes with its member's stream


def _open_bytes(path: Path, found: list[str] | None = None) -> IO[bytes]:
    """The file's bytes, decompressed where it is compressed (COMPRESSIONS), up to where the
    compressed stream was cut if it was (_Salvaged: what was left out said in `found`)."""
    import bz2
    import gzip
    import lzma

    kind = _compression(path)
    opener = {"gzip": gzip.open, "bz2": bz2.open, "xz": lzma.open,
              "zip": _unzipped}.get(kind or "")
    if opener is None:
        return path.open("rb")
    return io.BufferedReader(_Salvaged(opener(path, "rb"), path, kind or "", found),
                             buffer_size=SALVAGE_CHUNK)


SALVAGE_CHUNK = 1 << 20
"""Decompressed bytes read at a time."""


def _cut_stream(kind: str) -> str:
    return (f"its {kind} stream ends before its end (the file was cut: a copy or download "
            "interrupted, or a logger stopped)")


class _Lines(io.RawIOBase):
    """A file's bytes handed on whole lines at a time, the bytes after the last line end held
    until more follow (or the file ends): what the streams that read a file's lines as
    something else share. `_chunk` gives the next bytes (None: the file was cut, and the line
    the cut fell in is left out), `_lines` what whole lines are read as."""

    def __init__(self, inner: Any) -> None:
        self._inner = inner
        self._out = memoryview(b"")  # ready to be read
        self._held = b""  # after the last line end so far
        self._done = False

    def readable(self) -> bool:
        return True

    def _chunk(self) -> bytes | None:
        return bytes(self._inner.read(SALVAGE_CHUNK))

    def _lines(self, whole: bytes) -> bytes:
        return whole

    def _cut(self, data: bytes) -> int:
        """Where the whole lines of `data` end."""
        return data.rfind(b"\n") + 1

    def readinto(self, buffer: Any) -> int:
        while not self._out and not self._done:
            chunk = self._chunk()
            if chunk is None:
                self._done = True
                break
            data = self._held + chunk
            cut = len(data) if not chunk else self._cut(data)
            self._done = not chunk
            whole, self._held = data[:cut], data[cut:]
            self._out = memoryview(self._lines(whole))
        n = min(len(buffer), len(self._out))
        memoryview(buffer).cast("B")[:n] = self._out[:n]
        self._out = self._out[n:]
        return n

    def close(self) -> None:
        self._inner.close()
        super().close()


class _Salvaged(_Lines):
    """A decompressing file's bytes up to where its compressed stream ends before its end marker
    (the file cut: a download or a copy interrupted, a logger that compressed as it wrote
    stopped), the line the cut fell in left out and said in `found` (None: not said). A
    damaged stream is refused (TableError), not read past."""

    def __init__(self, inner: Any, path: Path, kind: str, found: list[str] | None) -> None:
        super().__init__(inner)
        self._path, self._kind, self._found = path, kind, found

    def _cut(self, data: bytes) -> int:
        """Where the whole lines of `data` end, by either line end: a file whose lines end with
        a carriage return alone (_CrLines reads them after) is not held whole."""
        return max(data.rfind(b"\n"), data.rfind(b"\r")) + 1

    def _chunk(self) -> bytes | None:
        import lzma
        import zlib

        try:
            return bytes(self._inner.read1(SALVAGE_CHUNK))  # one read: data before a cut kept
        except EOFError:  # the stream ends before its end marker: the file was cut
            if self._found is not None:
                self._found.append(f"{_cut_stream(self._kind)}: read up to the cut" + (
                    ", the line it fell in left out" if self._held.strip() else ""))
            return None
        except (OSError, zlib.error, lzma.LZMAError, zipfile.BadZipFile) as err:
            raise TableError(f"{self._path}: its {self._kind} stream cannot be decompressed "
                             f"({err}): the file is damaged") from None


LONE_CR = re.compile(rb"\r(?!\n)")
"""A carriage return without a line feed after it: a line end of its own, as Python's csv module
and pyarrow's reader take it (classic Mac OS text ends every line so, a serial log some; a
sketch that prints "\\n\\r" ends each line with an empty one)."""


class _CrLines(_Lines):
    """A stream's bytes with each lone carriage return (LONE_CR) a line feed, as many bytes: a
    file's lines as every reader here counts them, by their line feeds, at the same byte
    offsets (_TextLayout.lone_cr). A carriage return that ends a read is held until the next
    byte shows whether a line feed follows it."""

    def _cut(self, data: bytes) -> int:
        return len(data) - 1 if data.endswith(b"\r") else len(data)

    def _lines(self, whole: bytes) -> bytes:
        return LONE_CR.sub(b"\n", whole)


# ----- delimited text --------------------------------------------------------------------------

@dataclass
class _TextLayout:
    encoding: str
    delimiter: str
    header_line: int  # the header's line in the file, from 1
    header: list[str]
    decimal_comma: bool
    padded: bool  # cells with spaces around the number (", " between cells)
    datetimes: dict[int, bool] = field(default_factory=dict)
    """Columns of ISO 8601 date-times (read as seconds since 1970): index -> with a zone."""
    times_of_day: set[int] = field(default_factory=set)
    """Columns of times of day (read as seconds since midnight)."""
    skipped: str = ""
    """The lines before the header that are not the table ("lines 1-3"; "" for none)."""
    data_after: int = 0
    """The line after which the data start (the header's, or a units row's under it)."""
    units_row: list[str | None] = field(default_factory=list)
    """Each column's unit from a row of units above or below the names (None: none)."""
    stacked: str = ""
    """The lines a header written on several rows spans ("lines 3-7"; "" for one row)."""
    rate: float | None = None
    """The sample rate [Hz] a line before the header states (STATED_RATE)."""
    durations: dict[int, str] = field(default_factory=dict)
    """Columns of durations written with their unit ("0.01 sec", as MATLAB's writetimetable
    writes a timetable's row times): index -> the unit (DURATION_UNITS), read as seconds."""
    data_end: int | None = None
    """The byte where the table ends before a tail a logger stopped mid-write leaves (None:
    the file's end; _tail)."""
    tail: str = ""
    """What was left out at the end and why ("" for nothing)."""
    found: list[str] = field(default_factory=list)
    """What a read found left out that the file's start and end did not show (a compressed
    stream cut short: _Salvaged)."""
    spaced: bool = False
    """Cells split by runs of spaces or tabs (numpy.savetxt's default, a C printf, TUM's
    trajectories): every line is read with each run as WHITESPACE_AS (_Spaced)."""
    not_iso: set[int] = field(default_factory=set)
    """Columns of dates and times, or of times of day, in one of _DATETIME's or
    _TIME_OF_DAY's forms other than ISO 8601's."""
    day_month: dict[int, str] = field(default_factory=dict)
    """Columns of dates with the day and month before the year (_DAY_MONTH) -> a cell: refused
    where read."""
    lone_cr: bool = False
    """The file holds a carriage return without a line feed after it (LONE_CR: classic Mac OS
    text and Excel for Mac's "CSV (Macintosh)" end every line so), or may (compressed): its
    bytes are read through _CrLines, so that each reader counts its lines alike."""


_DATETIME = re.compile(
    r"^(?:(?P<y>\d{4})(?P<sep>[-/])(?P<m>\d{2})(?P=sep)(?P<d>\d{2})"
    r"|(?P<d2>\d{2})\.(?P<m2>\d{2})\.(?P<y2>\d{4}))"
    r"[T ](?P<H>\d{2}):(?P<M>\d{2}):(?P<S>\d{2})(?:[.,](?P<f>\d{1,9})|:(?P<f2>\d{3}))?"
    r"\s*(?P<zone>Z|[+-]\d{2}(?::?\d{2})?)?$")
"""A date and time as loggers write it: ISO 8601's "2024-05-01T12:00:00.010" (a space for the
T, a decimal comma, a zone: Z, +02:00, +0200, or none), the year first with slashes
("2024/05/01 12:00:00.010", as East Asian locales write it) or the day first with dots
("01.05.2024 12:00:00,010", as German and other European locales do); the milliseconds after
a colon ("2019-09-07 09:13:29:506", as AndroSensor writes them). A day and month with
slashes ("05/01/2024") is refused: it reads as May 1 or January 5 alike."""
_DAY_MONTH = re.compile(r"^\d{1,2}/\d{1,2}/\d{2,4}[T ]\d{1,2}:\d{2}")
"""A date with slashes, the day and month before the year (US and UK locales alike)."""
_TO_ISO = ((r"^(\d{2})\.(\d{2})\.(\d{4})", r"\3-\2-\1"), (r"^(\d{4})/(\d{2})/(\d{2})", r"\1-\2-\3"),
           (r"(\d{2}:\d{2}:\d{2})[,:](\d)", r"\1.\2"))
"""_DATETIME's other forms rewritten as ISO 8601 (regular expression, replacement), for
pyarrow's reader, which parses only that."""


STATED_RATE = re.compile(r"\b(?:update|sample|sampling|output|data)[ _-]?(?:rate|frequency)"
                         r"\W{0,3}?([0-9]+(?:[.,][0-9]+)?)\s*hz\b", re.IGNORECASE)
"""A sample rate stated in a logger's preamble, with its unit: Xsens MT Manager's "// Update
Rate: 100.0Hz", "# Sample rate = 200 Hz", "Sampling frequency,50,Hz" does not (the unit in a
cell of its own). A file's time column governs where it has one; two statements are none."""


_TIME_OF_DAY = re.compile(r"^(\d{1,2}):(\d{2}):(\d{2})(?:[.,](\d{1,9})|:(\d{3}))?$")
"""A time of day without a date: "12:00:00.010", a decimal comma, "9:05:00", and the
milliseconds after a colon, "12:00:00:010", as Physics Toolbox Sensor Suite writes them
(exactly three digits: a video timecode's "01:00:00:12" counts frames, and is none)."""
_ISO_TIME_OF_DAY = re.compile(r"^\d{2}:\d{2}:\d{2}(?:\.\d{1,9})?$")
"""The times of day pyarrow's reader parses; the other forms of _TIME_OF_DAY it reads as
text, rewritten as these (_TIME_TO_ISO)."""
_TIME_TO_ISO = ((r"^(\d):", r"0\1:"), (r"^(\d{2}:\d{2}:\d{2})[,:](\d)", r"\1.\2"))
"""_TIME_OF_DAY's other forms rewritten as _ISO_TIME_OF_DAY's (regular expression,
replacement)."""


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_DURATION = re.compile(rf"^({_NUMBER})\s*([a-z]+)$")
DURATION_UNITS = {"sec": 1.0, "secs": 1.0, "s": 1.0, "ms": 1e-3, "min": 60.0, "mins": 60.0,
                  "hr": 3600.0, "hrs": 3600.0}
"""A duration's number and unit as MATLAB writes a duration ("0.01 sec", "1.5 min", "2 hr")."""


def duration_unit(text: str) -> str | None:
    """The unit of a duration written with one (DURATION_UNITS), None where the text is none."""
    m = _DURATION.match(text.strip())
    return m.group(2) if m and m.group(2) in DURATION_UNITS else None


def seconds_of_day(text: str) -> float | None:
    """Seconds since midnight of a time of day (_TIME_OF_DAY), None where the text is none."""
    m = _TIME_OF_DAY.match(text.strip())
    if m is None:
        return None
    hour, minute, second = (int(g) for g in m.groups()[:3])
    if hour > 23 or minute > 59 or second > 60:
        return None
    fraction = m.group(4) or m.group(5)
    return (3600.0 * hour + 60.0 * minute + second
            + (int(fraction) / 10 ** len(fraction) if fraction else 0.0))


def seconds_of(text: str) -> float | None:
    """Seconds since 1970-01-01 UTC of a date and time (_DATETIME; without a zone
    taken as UTC, as both a recording and its reference are read), None where the text is
    none."""
    m = _DATETIME.match(text.strip())
    if m is None:
        return None
    year, month, day = (int(m.group(k) or m.group(k + "2")) for k in "ymd")
    hour, minute, second = (int(m.group(k)) for k in "HMS")
    fraction, zone = m.group("f") or m.group("f2"), m.group("zone")
    try:
        t = dt.datetime(year, month, day, hour, minute, second, tzinfo=dt.timezone.utc)
    except ValueError:
        return None
    offset = 0
    if zone and zone != "Z":
        digits = zone[1:].replace(":", "")
        offset = (int(digits[:2]) * 60 + int(digits[2:4] or 0)) * (1 if zone[0] == "+" else -1)
    whole = t.timestamp() - 60.0 * offset
    return whole + (int(fraction) / 10 ** len(fraction) if fraction else 0.0)


def _utf16(raw: bytes) -> str | None:
    """The UTF-16 codec a text's start is written in (Windows' "Unicode": Excel's Unicode Text,
    PowerShell's redirection), by its byte-order mark or, without one, by the zero byte beside
    every ASCII character; None for any other text."""
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        return "utf-16"
    pairs = len(raw) // 2
    if pairs < 8:
        return None
    if raw[1:2 * pairs:2].count(0) > 0.9 * pairs and raw[0:2 * pairs:2].count(0) == 0:
        return "utf-16-le"
    if raw[0:2 * pairs:2].count(0) > 0.9 * pairs and raw[1:2 * pairs:2].count(0) == 0:
        return "utf-16-be"
    return None


def _decoded(raw: bytes, encoding: str, cut: bool) -> str:
    """The text of a file's start in a UTF-16 codec, a character cut at its end left out."""
    raw = raw[:len(raw) // 2 * 2]
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError:
        if not cut:
            raise
        return raw[:-2].decode(encoding)  # half a surrogate pair


def _sniff(path: Path) -> _TextLayout:
    cut: list[str] = []
    with _open_bytes(path, cut) as f:
        raw = f.read(SNIFF_BYTES)
    # a line end of a carriage return alone (not in UTF-16, whose bytes pair): a compressed
    # stream is not read twice to look
    lone_cr = _utf16(raw) is None and (_compression(path) is not None or _has_lone_cr(path))
    if lone_cr:
        raw = LONE_CR.sub(b"\n", raw)
    encoding = "utf-8"
    try:
        if (wide := _utf16(raw)) is not None:
            encoding, text = wide, _decoded(raw, wide, len(raw) == SNIFF_BYTES)
        else:
            text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        if encoding == "utf-8" and err.start >= len(raw) - 4 and len(raw) == SNIFF_BYTES:
            text = raw[:err.start].decode("utf-8-sig")  # a character cut at the end
        else:
            encoding, text = "latin-1", raw.decode("latin-1")
    if len(raw) == SNIFF_BYTES:  # the last line may be cut
        text = text[:text.rfind("\n") + 1] or text
    lines = text.splitlines()
    numbered = [(i + 1, line) for i, line in enumerate(lines) if line.strip()]
    if not numbered:
        raise TableError(f"{path}: " + (f"{_cut_stream(_compression(path) or '')}, before "
                                        "any whole line" if cut else "empty file"))
    ends = [k for k, (_, line) in enumerate(numbered) if _END_OF_HEADER.match(line)]
    found = _find_header(numbered, ends[-1] + 1 if ends else 0)
    spaced = False
    if found is None:  # cells split by runs of spaces: each run read as WHITESPACE_AS
        spaced_lines = [(no, _spaced_line(line)) for no, line in numbered]
        found = _find_header(spaced_lines, ends[-1] + 1 if ends else 0, WHITESPACE_AS)
        if found is None:
            raise _no_table(path, numbered[0])
        numbered, spaced = spaced_lines, True
    delimiter, start = found
    header_line, header_text = numbered[start]
    preamble = numbered[:start]
    commented = False
    if _all_numbers(header_text, delimiter):  # no header row, or one written as a comment
        commented = [(no, _comment(line)) for no, line in preamble if _comment(line)]
        named = commented[-1] if commented else None
        if named is not None and _cells(named[1], delimiter) == _cells(header_text, delimiter):
            header_line, header_text = named
            preamble = [(no, line) for no, line in preamble if no < header_line]
            commented = True
        elif len(commented) < len(preamble):  # rows before these that split otherwise
            raise _no_table(path, numbered[0])
        else:
            raise TableError(f"{path}, line {header_line}: numbers where a header row naming "
                             "the columns belongs (time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z "
                             "or the like): add one")
    header = [c.strip() for c in next(csv.reader([header_text], delimiter=delimiter,
                                                  skipinitialspace=True))]  # ", \"name\""
    data_after, units_row, stacked = header_line, [None] * len(header), ""
    if not commented:
        header, header_line, data_after, units_row, stacked = _stacked(numbered, start, header,
                                                                       delimiter)
    rows = [next(csv.reader([line], delimiter=delimiter))
            for no, line in numbered if no > data_after][:49]
    header, units_row = _trailing_delimiter(header, units_row, rows)
    datetimes, times_of_day, durations, rewritten = {}, set(), {}, set()
    day_month: dict[int, str] = {}
    for j in range(len(header)):
        column = [row[j].strip() for row in rows if len(row) == len(header) and row[j].strip()]
        matches = [_DATETIME.match(c) for c in column]
        if column and all(matches):
            datetimes[j] = all(m.group("zone") for m in matches if m)  # with a zone
            if any(m.group("sep") != "-" or "," in c or m.group("f2") for m, c
                   in zip(matches, column, strict=True) if m) or any(
                       row[j] != row[j].strip() for row in rows
                       if len(row) == len(header) and row[j].strip()):  # padded
                rewritten.add(j)
        elif column and all(_DAY_MONTH.match(c) for c in column):
            day_month[j] = column[0]
        elif column and all(seconds_of_day(c) is not None for c in column):
            times_of_day.add(j)
            if not all(_ISO_TIME_OF_DAY.match(row[j]) for row in rows
                       if len(row) == len(header) and row[j].strip()):  # padded too
                rewritten.add(j)
        elif column and all(duration_unit(c) for c in column):  # in the first cell's unit
            durations[j] = duration_unit(column[0]) or ""
    cells = [c for row in rows for j, c in enumerate(row)
             if c.strip() and j not in datetimes and j not in times_of_day]
    decimal_comma = (any("," in c for c in cells)  # a cell's comma: ';' or tab between cells,
                     and not any("." in c for c in cells))  # or ',' and the cell quoted
    padded = any(c != c.strip() for row in rows for c in row if c.strip())
    skipped = (f"lines {preamble[0][0]}-{preamble[-1][0]}" if len(preamble) > 1
               else f"line {preamble[0][0]}") if preamble else ""
    rates = [float(m.group(1).replace(",", ".")) for _, line in preamble
             if (m := STATED_RATE.search(line))]
    layout = _TextLayout(encoding, delimiter, header_line, header, decimal_comma, padded,
                         datetimes, times_of_day, skipped, data_after, units_row, stacked,
                         rates[0] if len(rates) == 1 and rates[0] > 0.0 else None, durations,
                         spaced=spaced, not_iso=rewritten, day_month=day_month,
                         lone_cr=lone_cr)
    if _compression(path) is None and encoding in ASCII_LINES:
        layout.data_end, layout.tail = _tail(path, layout)
    return layout


TAIL_BYTES = 1 << 16
"""How much of a text file's end is looked at for what a logger stopped mid-write leaves."""


def _tail(path: Path, layout: _TextLayout) -> tuple[int | None, str]:
    """Where the table ends before what a logger leaves when it stops mid-write, and what that
    was (_tail_of), from the file's last bytes: back over windows of NULs to the last byte
    written."""
    size = stop = path.stat().st_size
    with path.open("rb") as f:
        while True:  # back over windows of NULs to the last byte written
            start = max(0, stop - TAIL_BYTES)
            f.seek(start)
            kept = f.read(stop - start).rstrip(b"\x00")
            if kept or start == 0:
                break
            stop = start
    if layout.lone_cr:
        kept = LONE_CR.sub(b"\n", kept)
    return _tail_of(kept, start, size - start - len(kept), layout,
                    lambda at: _lines_before(path, at, layout.lone_cr))


def _tail_of(kept: bytes, start: int, nul: int, layout: _TextLayout,
             lines_before: Callable[[int], int]) -> tuple[int | None, str]:
    """Where the table ends before what a logger leaves when it stops mid-write, and what that
    was: NUL bytes after the last line (a file preallocated on an SD card, its unwritten rest)
    and a last line cut short (fewer cells than the header, no line end after it: power lost
    while it was written, its last cell's digits perhaps cut too; _cut_value), and a last line
    of text, with a line end or without (a footer a logger appends: "END OF LOG"). (None, "")
    where the file ends with its table. A short line of numbers that ends with a line end is
    no cut: a line that is no row (_python_parts). kept: the file's last bytes but its `nul`
    NULs, from byte `start`; lines_before(end): the line ends before byte `end`."""
    said = []
    terminated = kept.endswith(b"\n")
    body = kept.rstrip(b"\r\n") if terminated else kept
    last = body.rfind(b"\n") + 1
    line = body[last:]
    end = start + len(kept)
    if line.strip() and start + last > 0:
        text = line.decode(layout.encoding, errors="replace")
        values = _line_cells(text, layout)
        cells = len(values)
        short = not terminated and cells < len(layout.header) and _row_start(values)
        cut = (not terminated and cells == len(layout.header) and _row_start(values)
               and _cut_value(values[-1], kept[:last], layout))
        footer = not (short or cut) and cells != len(layout.header) and _footer(values)
        if short or cut or footer:
            end = start + last
            number = lines_before(end) + 1
            said.append(f"line {number}, the last, cut short ({cells} of "
                        f"{len(layout.header)} values: a logger stopped mid-write): left out"
                        if short else
                        f"line {number}, the last, cut mid-write (no line end after it, and its "
                        f"last value {values[-1]!r} {cut}): left out" if cut else
                        f"line {number}, the last, is text after the table ({text.strip()[:40]!r}"
                        "): left out as a footer")
    if nul:
        said.append(f"{nul} NUL bytes after the last line (the unwritten rest of a "
                    "preallocated file): ignored")
    return (end, "; ".join(said)) if said else (None, "")


class _Tailed(io.RawIOBase):
    """A stream's bytes (a compressed file's, decompressed), its last TAIL_BYTES held until it
    ends and its trailing NULs counted, then passed on up to where the table ends before what
    a logger stopped mid-write leaves (_tail_of), which `found` is told: what _tail finds from
    a file's end, for a file read through to its end once."""

    def __init__(self, inner: IO[bytes], layout: _TextLayout, found: list[str]) -> None:
        self._inner, self._layout, self._found = inner, layout, found
        self._out = memoryview(b"")
        self._held, self._nul, self._passed, self._line_ends = b"", 0, 0, 0
        self._done = False

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        while not self._out and not self._done:
            chunk = self._inner.read(SALVAGE_CHUNK)
            if not chunk:
                self._done = True
                self._out = memoryview(self._ending())
                break
            written = chunk.rstrip(b"\x00")
            if not written:  # NULs alone so far: counted, not held
                self._nul += len(chunk)
                continue
            data = self._held + b"\x00" * self._nul + written  # NULs before more: data
            self._nul = len(chunk) - len(written)
            keep = max(0, len(data) - TAIL_BYTES)
            self._out, self._held = memoryview(data[:keep]), data[keep:]
            self._passed += keep
            self._line_ends += data.count(b"\n", 0, keep)
        n = min(len(buffer), len(self._out))
        memoryview(buffer).cast("B")[:n] = self._out[:n]
        self._out = self._out[n:]
        return n

    def _ending(self) -> bytes:
        held, start = self._held, self._passed
        end, said = _tail_of(held, start, self._nul, self._layout,
                             lambda at: self._line_ends + held.count(b"\n", 0, at - start))
        if said:
            self._found.append(said)
        return held if end is None else held[:end - start]

    def close(self) -> None:
        self._inner.close()
        super().close()


_SHAPE = re.compile(r"[-+]?([0-9]*)(?:[.,]([0-9]*))?(?:[eE][-+]?([0-9]*))?")
SHAPE_LINES = 10
"""The whole lines before an unterminated last line that must all show its last column's
width for a shorter last value to be taken for a cut."""


def _shape(cell: str) -> tuple[int, int, int] | None:
    """A number's (digits of an integer, digits after its decimal point, digits of its
    exponent): what a logger writing a column with one format keeps, and a cut shortens."""
    m = _SHAPE.fullmatch(cell)
    if m is None:
        return None
    whole, fraction, exponent = m.groups()
    plain = fraction is None and exponent is None
    return (len(whole) if plain else 0, len(fraction or ""), len(exponent or ""))


def _cut_value(cell: str, before: bytes, layout: _TextLayout) -> str:
    """Why a whole-width last line without a line end has its last value cut ("" where
    nothing shows it): it is no number yet ("1.5e-"), or has fewer digits after its point, in
    its exponent or (an integer column) in all than that column's value on each of the up to
    100 whole lines before it (at least SHAPE_LINES of them)."""
    if not _number_like(cell):
        return "is no number"
    shape = _shape(cell)
    shapes = []
    for raw in before.splitlines()[-100:]:
        values = _line_cells(raw.decode(layout.encoding, errors="replace"), layout)
        if len(values) == len(layout.header) and (seen := _shape(values[-1])) is not None:
            shapes.append(seen)
    if shape is None or len(shapes) < SHAPE_LINES:
        return ""
    fewest = np.min(shapes, axis=0)
    if any(have < want for have, want in zip(shape, fewest, strict=True)):
        return (f"has fewer digits than that column's value on each of the {len(shapes)} "
                "lines before it")
    return ""


def _footer(cells: list[str]) -> bool:
    """Whether a line's cells are text, no row (a summary a logger appends: "END OF LOG"; its
    caller asks that they be not as many as the header's, as a row's with a text column are)."""
    return (any(ch.isalpha() for c in cells for ch in c)
            and not all(_value_like(c) for c in cells))


_NUMBER_START = re.compile(r"^[-+]?[0-9]*[.,]?[0-9]*(?:[eE][-+]?[0-9]*)?$")
"""What a number cut after any of its characters can be ("1.59", "-", "2e", "")."""


def _row_start(cells: list[str]) -> bool:
    """Whether cells can be a data row's start cut mid-write: every cell a number or missing,
    the last perhaps cut (a footer's text is no row: _footer)."""
    *whole, cut = cells
    return (all(_value_like(c) for c in whole)
            and (_number_like(cut) or bool(_NUMBER_START.match(cut))))


def _value_like(cell: str) -> bool:
    """Whether a cell is a number or marks a missing one."""
    return _number_like(cell) or cell.lower() in MISSING_VALUES


def _line_cells(text: str, layout: _TextLayout) -> list[str]:
    """A line's cells as the layout splits them (runs of spaces as one delimiter where the
    file is so written)."""
    return _cells_of(_spaced_line(text) if layout.spaced else text, layout.delimiter)


def _has_lone_cr(path: Path) -> bool:
    """Whether the file holds a carriage return without a line feed after it (LONE_CR), read a
    few megabytes at a time (a pass at the pace of the disk's cache)."""
    held = b""
    with path.open("rb") as f:
        while chunk := f.read(1 << 22):
            data = held + chunk
            held = b"\r" if data.endswith(b"\r") else b""
            if b"\r" in data and LONE_CR.search(data, 0, len(data) - len(held)):
                return True
    return bool(held)


def _lines_before(path: Path, end: int, lone_cr: bool = False) -> int:
    """The line ends in the file's first `end` bytes (lone carriage returns too: _CrLines)."""
    count = 0
    with (_CrLines(path.open("rb")) if lone_cr else path.open("rb")) as f:
        while end > 0 and (chunk := f.read(min(end, 1 << 22))):
            count += chunk.count(b"\n")
            end -= len(chunk)
    return count


class _Head(io.RawIOBase):
    """A binary file's first `size` bytes, as a file."""

    def __init__(self, path: Path, size: int) -> None:
        self._f, self._left = path.open("rb"), size

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        n = self._f.readinto(memoryview(buffer)[:max(0, min(len(buffer), self._left))])
        self._left -= n or 0
        return n or 0

    def close(self) -> None:
        self._f.close()
        super().close()


class _AfterLines(io.RawIOBase):
    """A binary stream without its first `lines` lines (counted by their line ends, as
    pyarrow's reader skips them), found a megabyte at a time without decoding them."""

    def __init__(self, inner: IO[bytes], lines: int) -> None:
        self._inner, self._left, self._pending = inner, lines, b""

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        while self._left:
            chunk = self._inner.read(1 << 20)
            if not chunk:
                self._left = 0
                break
            if (ends := chunk.count(b"\n")) < self._left:
                self._left -= ends
                continue
            at = -1
            for _ in range(self._left):
                at = chunk.index(b"\n", at + 1)
            self._pending, self._left = chunk[at + 1:], 0
        if self._pending:
            n = min(len(buffer), len(self._pending))
            buffer[:n] = self._pending[:n]
            self._pending = self._pending[n:]
            return n
        return self._inner.readinto(buffer)

    def close(self) -> None:
        self._inner.close()
        super().close()


def _table_bytes(path: Path, layout: _TextLayout) -> IO[bytes]:
    """The file's bytes up to the table's end (decompressed where it is compressed, what the
    read finds said in layout.found)."""
    raw = (_open_bytes(path, layout.found) if layout.data_end is None
           else io.BufferedReader(_Head(path, layout.data_end)))
    if layout.lone_cr:
        raw = io.BufferedReader(_CrLines(raw), buffer_size=SALVAGE_CHUNK)
    if _compression(path) is not None and layout.encoding in ASCII_LINES:
        raw = io.BufferedReader(_Tailed(raw, layout, layout.found), buffer_size=SALVAGE_CHUNK)
    return io.BufferedReader(_Spaced(raw), buffer_size=SALVAGE_CHUNK) if layout.spaced else raw


def _trailing_delimiter(header: list[str], units: list[str | None], rows: list[list[str]]
                        ) -> tuple[list[str], list[str | None]]:
    """The header as wide as the rows where one of them ends with a delimiter the other lacks:
    rows of one cell more, empty in every row, get an unnamed column (read, and taken by no
    quantity); a header that ends with an empty name the rows lack loses it."""
    widths = {len(row) for row in rows}
    if widths == {len(header) + 1} and not any(row[-1].strip() for row in rows):
        return [*header, ""], [*units, None]
    if widths == {len(header) - 1} and not header[-1]:
        return header[:-1], units[:-1]
    return header, units


def _cells_of(line: str, delimiter: str) -> list[str]:
    return [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]


def _units_of(cells: list[str]) -> list[str | None] | None:
    """A row of units (every cell empty, in brackets or not, a unit UNIT_ALIASES knows or one
    of OTHER_UNITS, one at least of UNIT_ALIASES') as each column's unit; None for any other
    row."""
    bare = [c[1:-1] if c[:1] in "([" and c[-1:] in ")]" else c for c in cells]
    units = [unit_named(c) if c else None for c in bare]
    other = [bool(c) and u is None and c.replace(" ", "").lower() in OTHER_UNITS
             for c, u in zip(bare, units, strict=True)]
    if not any(units) or any(c and u is None and not o
                             for c, u, o in zip(bare, units, other, strict=True)):
        return None
    return units


def _text_row(line: str, delimiter: str) -> bool:
    """Whether a line is a row of names (a header's): cells of text and empty ones, none a
    number, a date and time or a time of day. A row of data with a bad cell is no such row:
    the reader refuses it by its line."""
    cells = [c for c in _cells_of(line, delimiter) if c]
    if all(c.lower() in MISSING_VALUES for c in cells):  # a row of missing values: data
        return False
    return bool(cells) and not any(_number_like(c) for c in cells)


_RULE = re.compile(r"^[-=_:+ ]+$")
"""A cell of a rule drawn under a header (----, a Markdown table's |:---:|)."""


def _stacked(numbered: list[tuple[int, str]], at: int, header: list[str], delimiter: str
             ) -> tuple[list[str], int, int, list[str | None], str]:
    """A header written on several rows, as motion capture exports it (OptiTrack Motive: the
    rigid body's name, then "Rotation" or "Position" over "X, Y, Z, W"; a row of units above
    or below the names): (header, its line, the line after which the data start, each column's
    unit from a units row (None: none), the lines the header spans as said). The header is the
    last row of text before the data, each name after the group the row above it names; a row
    of units is units, not names."""
    width = len(header)
    k, run = at, 0  # the last row of text before HEADER_CHECK rows of data in a row
    for j in range(at + 1, min(len(numbered), at + PREAMBLE_LINES)):
        if _cells(numbered[j][1], delimiter) != width:
            break
        if _text_row(numbered[j][1], delimiter):
            k, run = j, 0
        else:
            run += 1
            if run >= HEADER_CHECK:
                break
    units: list[str | None] = [None] * width
    rows = [j for j in range(at, k + 1)  # a rule under the names (----, |---|) is no row
            if not all(_RULE.match(c) for c in _cells_of(numbered[j][1], delimiter) if c)]
    if not rows:
        return header, numbered[at][0], numbered[at][0], units, ""
    names_at = rows[-1]
    if len(rows) > 1 and (below := _units_of(_cells_of(numbered[names_at][1], delimiter))):
        units, names_at = below, rows[-2]  # units under the names (Vicon's mm)
    names = _cells_of(numbered[names_at][1], delimiter)
    group: list[str] = [""] * width
    for no in reversed([j for j in rows if j < names_at]):  # the nearest row of text above
        cells = _cells_of(numbered[no][1], delimiter)
        above = _units_of(cells)
        if above is not None:  # no units row
            units = [u or a for u, a in zip(units, above, strict=True)]
        elif _text_row(numbered[no][1], delimiter):  # not an id row (Motive's 1, 1, ...)
            group = cells
            break
    if k == at:
        return header, numbered[at][0], numbered[at][0], units, ""
    first, last = numbered[at][0], numbered[k][0]
    return _grouped(group, names), numbered[names_at][0], last, units, f"lines {first}-{last}"


def _grouped(group: list[str], names: list[str]) -> list[str]:
    """Each name after the group the row above it names, where the names need one: a group
    tells apart the columns whose names repeat (OptiTrack Motive's X, Y, Z under Rotation and
    under Position; a spreadsheet's x, y, z under merged cells "Accelerometer" and "Gyroscope",
    whose heading is written in the first cell alone and spans the empty cells after it, over
    names that repeat). Where no name repeats (their units aside), the row above names no
    groups but the table (a title, a device's name, as a spreadsheet pads it to the table's
    width): the names as they are, not the first one run into it."""
    bare = [split_unit(n)[0].lower() for n in names]
    repeated = {b for b in bare if b and bare.count(b) > 1}
    if not repeated:
        return names
    joined, spanning = [], ""
    for g, n, b in zip(group, names, bare, strict=True):
        spanning = g or (spanning if b in repeated else "")  # a name of its own ends a span
        joined.append(f"{spanning} {n}".strip() if spanning and spanning != n else n)
    return joined


def _no_table(path: Path, first: tuple[int, str]) -> TableError:
    line, text = first
    return TableError(f"{path}: no delimiter splits a header and the rows after it alike (tried "
                      f"comma, semicolon, tab, bar and runs of spaces); line {line} reads "
                      f"{text[:80]!r}")


WHITESPACE_AS = ";"
"""What a run of spaces or tabs between cells is read as: a delimiter no number holds, so that
a decimal comma stays one ("0,01 9,81")."""


def _spaced_line(line: str) -> str:
    """A line whose cells runs of spaces split, with WHITESPACE_AS between them (a comment's
    mark kept apart: numpy.savetxt's "# time acc_x ...")."""
    text = line.strip()
    mark = next((c for c in COMMENTS if text.startswith(c)), "")
    cells = text[len(mark):].split()
    return (f"{mark} " if mark else "") + WHITESPACE_AS.join(cells)


class _Spaced(_Lines):
    """A file's bytes with the runs of spaces or tabs between cells read as WHITESPACE_AS, line
    by line (as many lines, so that line numbers stay the file's): _spaced_line on bytes,
    without its comment mark, as the rows that are read come after the header."""

    def _lines(self, whole: bytes) -> bytes:
        between = WHITESPACE_AS.encode()  # bytes.split: ten times re.sub's pace
        return b"\n".join(between.join(line.split()) for line in whole.split(b"\n"))


def _comment(line: str) -> str:
    """A comment line's text after its mark ("" for a line that is no comment)."""
    text = line.lstrip()
    mark = next((c for c in COMMENTS if text.startswith(c)), None)
    if mark is None:
        return ""
    return text[len(mark):] or " "


def _cells(line: str, delimiter: str) -> int:
    return len(next(csv.reader([line], delimiter=delimiter)))


def _number_like(cell: str) -> bool:
    """Whether a cell is a number (a decimal comma too), a date and time, a time of day or a
    duration with its unit."""
    try:
        float(cell.strip().replace(",", "."))
    except ValueError:
        return bool(_DATETIME.match(cell.strip()) or _TIME_OF_DAY.match(cell.strip())
                    or duration_unit(cell))
    return True


def _all_numbers(line: str, delimiter: str) -> bool:
    return all(_number_like(c) for c in next(csv.reader([line], delimiter=delimiter)))


_END_OF_HEADER = re.compile(r"^\s*\*\*\*End_of_Header\*\*\*[\s,;|]*$", re.IGNORECASE)
"""LabVIEW's measurement file (.lvm) closes its file header and each segment's header with this
line; the table's header row follows the last."""


def _find_header(numbered: list[tuple[int, str]], first: int = 0,
                 delimiters: str = DELIMITERS) -> tuple[str, int] | None:
    """(delimiter, index into numbered) of the header: the first line from numbered[first] on
    (after LabVIEW's file and segment headers) that, with the HEADER_CHECK lines after it, one
    delimiter splits into as many cells (but for HEADER_CHECK_ODD of them), more than one (the
    most cells where several do), or as many but for a delimiter that ends the header or the
    rows alone (a sketch that prints a comma after every value, its header without one). Lines
    before it are a logger's preamble (a comment, a device name, the settings) and are
    skipped."""
    content = [k for k, (_, line) in enumerate(numbered) if k >= first and not _comment(line)]
    for i, start in enumerate(content[:PREAMBLE_LINES]):
        window = [numbered[k][1] for k in content[i:i + HEADER_CHECK + 1]]
        best: tuple[str, int] | None = None
        cells = 1
        for d in delimiters:
            for cut in ("", d):  # as written; without a delimiter that ends a line
                counts = [_cells(line.rstrip().removesuffix(cut) if cut else line, d)
                          for line in window]
                if sum(c != counts[0] for c in counts[1:]) <= HEADER_CHECK_ODD:
                    break
            else:
                continue
            if (n := counts[0]) > cells and not _spaced_numbers(window, d):
                best, cells = (d, start), n
        if best is not None:
            return best
    return None


def _spaced_numbers(lines: list[str], delimiter: str) -> bool:
    """Whether a cell of the lines holds numbers with spaces between: the delimiter is a
    decimal comma of cells that runs of spaces split ("0,01 9,81"), not the cells' own."""
    return any(len(words := cell.split()) > 1 and all(_number_like(w) for w in words)
               for line in lines for cell in next(csv.reader([line], delimiter=delimiter)))


def _text(path: Path) -> TableSource:
    layout = _sniff(path)
    names, stated = zip(*(split_unit(h) for h in layout.header), strict=True)
    units = [_clock_of(layout, j) or (DURATION if j in layout.durations else None) or u
             or layout.units_row[j] for j, u in enumerate(stated)]

    def read(columns: list[int], rows: int) -> Iterator[np.ndarray]:
        for j in columns:
            if j in layout.day_month:
                raise TableError(f"{path}, column {layout.header[j]!r}: dates with the day and "
                                 f"the month before the year ({layout.day_month[j][:30]!r}), "
                                 "which read as the month first or the day first alike: export "
                                 "the time as ISO 8601 (2024-05-01 12:00:00.010) or as seconds")
        tally = _Tally(path, layout)
        parts = (_python_parts(path, layout, columns, 0, tally) if not _has_pyarrow()
                 else _text_parts(path, layout, columns, tally))
        yield from _reblocked(parts, rows, len(columns), tally.finish)

    def where(row: int) -> str:
        return f"line {_line_of_row(path, layout, row)}"

    spans = layout.stacked or f"line {layout.header_line}"
    note = (f"the header on {spans}" + (f", {layout.skipped} before it skipped"
                                        if layout.skipped else "")
            if layout.skipped or layout.stacked else "")
    note = "; ".join(n for n in (note, layout.tail) if n)
    attrs = {} if layout.rate is None else {"rate": layout.rate}
    return TableSource(path, list(layout.header), list(names), list(units), "text", None, read,
                       where, attrs, note=note, found=layout.found)


class _ArrowFailed(Exception):
    pass


def _has_pyarrow() -> bool:
    """pyarrow parses text fast; without it Python's csv module reads the same file."""
    try:
        import pyarrow.csv  # noqa: F401
    except ImportError:
        return False
    return True


def _float64(column: Any) -> np.ndarray:
    """A pyarrow float64 array as numpy, its nulls NaN. Read from its buffers: pyarrow's
    to_numpy imports pandas on its first call, a quarter of a second on every command."""
    validity, data = column.buffers()
    n, offset = len(column), column.offset
    x = np.frombuffer(data, dtype=np.float64, count=offset + n)[offset:]
    if column.null_count:
        valid = np.unpackbits(np.frombuffer(validity, dtype=np.uint8),
                              bitorder="little")[offset:offset + n].astype(bool)
        x = np.where(valid, x, np.nan)
    return x


def _as_iso(column: Any, kind: Any) -> Any:
    """A pyarrow string array of dates and times in _DATETIME's other forms, or of times of
    day in _TIME_OF_DAY's, as `kind` (a timestamp or time64 type; rewritten as ISO 8601, which
    pyarrow parses; a time of day as that time on 1970-01-01, whose seconds since 1970 are its
    seconds since midnight: pyarrow casts no text to a time of day); ArrowInvalid where one is
    none."""
    import pyarrow as pa
    import pyarrow.compute as pc

    column = pc.utf8_trim_whitespace(column)  # a padded cell's
    if pa.types.is_time(kind):
        for pattern, replacement in (*_TIME_TO_ISO, (r"^", "1970-01-01T")):
            column = pc.replace_substring_regex(column, pattern, replacement)
        return column.cast(pa.timestamp("ns"))
    for pattern, replacement in _TO_ISO:
        column = pc.replace_substring_regex(column, pattern, replacement)
    return column.cast(kind)


def _seconds(column: Any, per_second: int = 10**9) -> np.ndarray:
    """A pyarrow timestamp, duration or time of day array (per_second ticks a second: [ns] by
    default) as seconds since 1970 or midnight, its nulls NaN: the whole seconds and their
    fraction added, as seconds_of and seconds_of_day add them, so that both readers give the
    same seconds to the bit (one rounding; the nanoseconds times 1e-9 round twice)."""
    import pyarrow as pa

    ticks = column.cast(pa.int64()).fill_null(0).to_numpy(zero_copy_only=False)
    seconds = ticks_seconds(ticks, per_second)
    if column.null_count:
        seconds[np.asarray(column.is_null().to_numpy(zero_copy_only=False))] = np.nan
    return seconds


def _duration_seconds(column: Any, unit: str) -> np.ndarray:
    """A pyarrow string array of durations in `unit` ("0.01 sec") as seconds, its nulls NaN;
    _ArrowFailed where a cell is no such duration (Python's reader then names its line)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    number = pc.extract_regex(column, rf"^\s*(?P<n>{_NUMBER})\s*{unit}\s*$")
    if number.null_count != column.null_count:
        raise _ArrowFailed(f"a cell is no duration in {unit}")
    values = pc.cast(pc.struct_field(number, "n"), pa.float64())
    return _float64(values) * DURATION_UNITS[unit]


def _read_as_number(layout: _TextLayout, j: int) -> bool:
    """Whether pyarrow's reader reads a column as numbers (float64): not as text it converts
    after (a date Python's ISO parser would not take, a duration with its unit) or a time."""
    return not (j in layout.not_iso or j in layout.durations or j in layout.datetimes
                or j in layout.times_of_day)


def _arrow_parts(path: Path, layout: _TextLayout, columns: list[int], skip: int,
                 mended: _Mended | None = None) -> Iterator[np.ndarray]:
    """The chosen columns of the rows after the file's first `skip` lines (the lines read
    through `mended` where given), a batch of pyarrow's reader at a time; _ArrowFailed where a
    line is no row it can read."""
    import pyarrow as pa
    import pyarrow.csv as pc

    keys = [f"c{i}" for i in range(len(layout.header))]
    wanted = [keys[i] for i in columns]
    types = {keys[i]: pa.float64() if _read_as_number(layout, i)
             else pa.string() if i in layout.not_iso or i in layout.durations
             else pa.timestamp("ns", tz="UTC" if layout.datetimes[i] else None)
             if i in layout.datetimes else pa.time64("ns") for i in columns}
    durations = {keys[i]: layout.durations[i] for i in columns if i in layout.durations}
    not_iso = {keys[i]: pa.timestamp("ns", tz="UTC" if layout.datetimes[i] else None)
               if i in layout.datetimes else pa.time64("ns")
               for i in columns if i in layout.not_iso}
    compression = _compression(path)
    # lines pyarrow cannot skip itself (past its first block), or lines read mended
    after = skip > layout.data_after or mended is not None
    stream: IO[bytes] | None = _AfterLines(_table_bytes(path, layout), skip) if after else None
    if mended is not None:
        stream = mended.reading(stream)
    try:
        reader = pc.open_csv(
            path if (compression is None and layout.data_end is None and not layout.spaced
                     and not after and not layout.lone_cr)
            else pa.PythonFile(io.BufferedReader(stream) if stream is not None
                               else _table_bytes(path, layout), mode="r"),
            read_options=pc.ReadOptions(column_names=keys, skip_rows=0 if after else skip,
                                        encoding="utf8" if layout.encoding == "utf-8"
                                        else layout.encoding, block_size=ARROW_BLOCK),
            parse_options=pc.ParseOptions(delimiter=layout.delimiter, ignore_empty_lines=True),
            convert_options=pc.ConvertOptions(
                column_types=types, include_columns=wanted, strings_can_be_null=True,
                decimal_point="," if layout.decimal_comma else "."))
        for batch in reader:
            yield np.column_stack([_float64(batch.column(k)) if types[k] == pa.float64()
                                   else _duration_seconds(batch.column(k), durations[k])
                                   if k in durations else
                                   _seconds(_as_iso(batch.column(k), not_iso[k]))
                                   if k in not_iso else _seconds(batch.column(k))
                                   for k in wanted]) \
                if wanted else np.empty((batch.num_rows, 0))
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError) as err:
        raise _ArrowFailed(str(err)) from None


class _Mended(_Lines):
    """A table's bytes from where a read starts, its first `drop` rows (read before) left out,
    with each line that is no row of the table (another count of cells than the header's, a
    cell read as a number that is none, the header again: a serial link's lost or garbled
    bytes, two rows run together) made a row of empty cells, which pyarrow's reader takes as a
    sample without numbers, as Python's reader takes such a line; each such line's refusal
    kept for the tally. numpy finds the lines, counts their delimiters and finds the bytes no
    number holds in the columns read as numbers; only those lines are parsed (_row_numbers, as
    Python's reader does), so that a log with such lines every few rows is read at pyarrow's
    pace. A line of spaces and delimiters alone is blank, as Python's reader takes it; one that
    quotes is left as it is, as is a cell of a number's bytes that is still none (pyarrow's
    reader then stops there)."""

    def __init__(self, path: Path, layout: _TextLayout, columns: list[int], line: int, row: int,
                 drop: int) -> None:
        self.path, self.layout, self.columns = path, layout, columns
        self.line, self.row, self.drop = line, row, drop  # lines and rows before the next
        self.found: collections.deque[tuple[int, str]] = collections.deque()
        """(rows through a line made a row, its refusal), until the tally is told."""
        super().__init__(None)  # the stream it reads is given by `reading`
        self._delimiter = layout.delimiter.encode(layout.encoding)
        self._width = width = len(layout.header)
        self._empty = self._delimiter * (width - 1)
        marks = "".join(MISSING_VALUES) + "infinity"  # letters a cell of a number may hold
        numbers = (b"0123456789.+-eE \t\r\n" + self._delimiter
                   + (marks.lower() + marks.upper()).encode() + (b"," if layout.decimal_comma
                                                                else b""))
        self._number_byte = np.zeros(256, dtype=bool)
        self._number_byte[list(numbers)] = True
        self._number_column = np.zeros(width, dtype=bool)  # read by pyarrow as float64
        self._number_column[[j for j in columns if _read_as_number(layout, j)]] = True

    def reading(self, inner: IO[bytes] | None) -> _Mended:
        self._inner = inner
        return self

    def tally(self, tally: _Tally, rows: int) -> None:
        """The lines made rows among the first `rows` rows, added to the tally (those after
        are read again where the read stops before them)."""
        while self.found and self.found[0][0] <= rows:
            through, said = self.found.popleft()
            tally.add(TableError(said), through)

    def _lines(self, whole: bytes) -> bytes:
        """Whole lines (the last without its line end at the stream's end), mended."""
        if not whole:
            return whole
        a = np.frombuffer(whole, dtype=np.uint8)
        ends = np.flatnonzero(a == ord("\n"))
        if not whole.endswith(b"\n"):
            ends = np.append(ends, len(a))
        starts = np.concatenate(([0], ends[:-1] + 1)).astype(np.int64)
        stops = ends - ((ends > starts) & (a[np.maximum(ends - 1, 0)] == ord("\r")))
        rows = stops > starts  # pyarrow's reader passes empty lines over
        if self.drop:  # rows read before, every one a row of the table
            k = np.flatnonzero(rows)
            if len(k) <= self.drop:
                self.drop -= len(k)
                self.line, self.row = self.line + len(ends), self.row + len(k)
                return b""
            first = int(k[self.drop])
            self.line, self.row, self.drop = self.line + first, self.row + self.drop, 0
            return self._lines(whole[starts[first]:])
        at_delimiter = np.flatnonzero(a == self._delimiter[0])
        cells = (np.searchsorted(at_delimiter, stops) - np.searchsorted(at_delimiter, starts)
                 + 1)
        odd = rows & (cells != self._width)
        odd_byte = np.flatnonzero(~self._number_byte[a])  # in a column read as a number?
        line = np.searchsorted(ends, odd_byte)
        cell = np.searchsorted(at_delimiter, odd_byte) - np.searchsorted(at_delimiter,
                                                                         starts[line])
        odd[line[self._number_column[np.minimum(cell, self._width - 1)]]] = True
        pieces, at = [], 0
        for i in np.flatnonzero(odd & rows):
            text = whole[starts[i]:stops[i]]
            if b'"' in text:
                continue
            said = text.decode(self.layout.encoding, "replace")
            cells_of = next(csv.reader([said], delimiter=self.layout.delimiter))
            rows[i] = not _blank(cells_of, self._width)
            try:
                if rows[i]:
                    _row_numbers(self.path, self.layout, self.columns, self.line + i + 1,
                                 cells_of)
                    continue  # a row after all, which pyarrow's reader reads or stops at
            except TableError as err:
                self.found.append((self.row + int(rows[:i + 1].sum()), str(err)))
            pieces += [whole[at:starts[i]], self._empty if rows[i] else b""]
            at = int(stops[i])
        self.line, self.row = self.line + len(ends), self.row + int(rows.sum())
        return b"".join([*pieces, whole[at:]]) if pieces else whole


def _reblocked(parts: Iterator[np.ndarray], rows: int, width: int,
               before_last: Callable[[], None]) -> Iterator[np.ndarray]:
    """The rows of parts of any length in blocks of `rows` (the last shorter), before_last
    called once the parts are read and before the last block (which a refusal of the whole
    read then precedes)."""
    pending: list[np.ndarray] = []
    held = 0
    for part in parts:
        pending.append(part)
        held += len(part)
        while held > rows:
            merged = np.concatenate(pending)
            yield merged[:rows]
            rest = merged[rows:]
            pending, held = [rest], len(rest)
    before_last()
    if held:
        yield np.concatenate(pending).reshape(held, width)


ARROW_BLOCK = 1 << 18
"""Bytes per batch of pyarrow's reader (about 4500 rows of an IMU's text): the rows Python's
reader parses again where a batch holds a line that is no row (as fast as larger batches)."""
RESUME_ROWS = 2_000
"""Where pyarrow's reader meets a line that is no row, Python's reads from its batch through
that line and on to at least this many rows (about what it costs pyarrow's to start again
there), then pyarrow's goes on: a few such lines in a long log cost a few stretches read by
Python. Where pyarrow's meets the next within fewer rows, it reads on with such lines mended
(_Mended), and where it still meets one (a cell of a number's bytes that is none), Python's
stretch doubles."""
ASCII_LINES = ("utf-8", "latin-1")
"""The encodings whose line ends are the byte b"\\n" (_AfterLines counts them so)."""


def _text_parts(path: Path, layout: _TextLayout, columns: list[int], tally: _Tally
                ) -> Iterator[np.ndarray]:
    """The chosen columns of every row: pyarrow's reader, and where it meets a line it cannot
    read, Python's from the start of that batch through that line (naming it, or taking it as
    a sample without numbers), pyarrow's again after it. Where it meets one again within the
    rows Python's read last (RESUME_ROWS: such lines come often), pyarrow's reads that batch
    again with each such line made a row without numbers, and so on to the end (_Mended,
    whose passes of numpy over the bytes a line or two in a long file would not repay)."""
    done, skip, base, least = 0, layout.data_after, 0, RESUME_ROWS
    lines_by_bytes = layout.encoding in ASCII_LINES  # else lines are not counted in bytes
    mend = False
    while True:
        started = (skip, base) if lines_by_bytes else (0, 0)  # lines skipped, rows before
        mended = _Mended(path, layout, columns, skip, base, done - base) if mend else None
        try:
            for part in _arrow_parts(path, layout, columns, skip, mended=mended):
                yield part
                done += len(part)
                tally.rows = max(tally.rows, done)
                if mended is not None:
                    mended.tally(tally, done)
            return
        except _ArrowFailed:
            soon = done - started[1] < least  # after the start or the last stretch
            if lines_by_bytes and soon and started[1] and not mend:
                mend = True  # such lines come often: that batch again, mended from there on
                continue
            least = least * 2 if soon else RESUME_ROWS
            tally.stopped = None
            for part in _python_parts(path, layout, columns, done, tally,
                                      stop=least if lines_by_bytes else 0, after=started):
                yield part
                done += len(part)
            if tally.stopped is None:  # it read to the end
                return
            skip, base = tally.stopped, done


def _blank(cells: list[str], width: int) -> bool:
    """Whether a line's cells are no row: none, or spaces alone and not the header's count of
    them (which is a row of empty cells, a sample without numbers, as pyarrow's reader reads
    it)."""
    return not cells or (len(cells) != width and not any(c.strip() for c in cells))


def _rows(path: Path, layout: _TextLayout, after: int = 0, skip: int = 0
          ) -> Iterator[tuple[int, list[str]]]:
    """(line, cells) of every data row after the file's first `after` lines and its first
    `skip` data rows (passed over as lines, not parsed), blank lines skipped: a line of
    spaces and delimiters alone, but for one of the header's count of cells, which is a row of
    empty cells (a sample without numbers) as pyarrow's reader reads it. Bytes that are no
    character of the encoding (a serial link's garbled byte, past where the encoding was
    found) are read as U+FFFD, which makes their cell no number and the line no row."""
    raw = _table_bytes(path, layout)
    width = len(layout.header)
    with io.TextIOWrapper(io.BufferedReader(_AfterLines(raw, after)) if after else raw,
                          newline="", encoding="utf-8-sig" if layout.encoding == "utf-8"
                          else layout.encoding, errors="replace") as f:
        blank, passed = " \t\r\n" + layout.delimiter, after
        for text in f if skip else ():
            passed += 1
            if passed > layout.data_after and (text.strip(blank) or (
                    text.strip("\r\n") and text.count(layout.delimiter) == width - 1)):
                skip -= 1
                if not skip:
                    break
        reader = csv.reader(f, delimiter=layout.delimiter)
        for row in reader:
            if reader.line_num + passed <= layout.data_after or _blank(row, width):
                continue
            yield reader.line_num + passed, row


def _line_of_row(path: Path, layout: _TextLayout, row: int) -> int:
    for k, (line, _) in enumerate(_rows(path, layout)):
        if k == row:
            return line
    return -1


GARBLED_SHARE = 0.01
"""Lines that are no row of the table (a serial link's lost or garbled bytes, two rows run
together, the header written again by a logger restarted) are taken as samples without a
number where they are at most this share of the rows: more say the file is not the table its
header and first rows describe, and it is refused naming the line (as soon as they pass one
more than the share of the rows read, else at the end)."""


class _Tally:
    """A read's lines that are no row of the table (GARBLED_SHARE): how many, the first's
    refusal, and where Python's reader stopped after one for pyarrow's to go on."""

    def __init__(self, path: Path, layout: _TextLayout) -> None:
        self.path, self.layout = path, layout
        self.garbled, self.first, self.rows = 0, "", 0
        self.stopped: int | None = None
        """The line after which pyarrow's reader goes on (None: Python's read to the end)."""

    def add(self, err: TableError, rows: int) -> None:
        """A line that is no row, the rows-th: refused where they are more than one beyond
        GARBLED_SHARE of the rows read (the first is weighed at the end)."""
        self.garbled += 1
        self.first = self.first or str(err)
        if self.garbled > 1 + GARBLED_SHARE * rows:
            raise self._refusal(str(err), rows)

    def finish(self) -> None:
        """At the end of the read: refused where such lines are more than GARBLED_SHARE of
        the rows, else said (layout.found)."""
        if self.garbled > GARBLED_SHARE * max(self.rows, 1):
            raise self._refusal(self.first, self.rows)
        if self.garbled:
            first = self.first.removeprefix(f"{self.path}, ")
            self.layout.found.append(
                f"{self.garbled} line(s) no row of the table, taken as samples without a "
                f"number (a logger's garbled or lost bytes; the first: {first})")

    def _refusal(self, said: str, rows: int) -> TableError:
        return TableError(f"{said}; {self.garbled} of {rows} rows are no row of the table "
                          f"(more than {GARBLED_SHARE:.0%} of them, which would be taken as "
                          "samples without a number)" if self.garbled > 1 else said)


def _python_parts(path: Path, layout: _TextLayout, columns: list[int], skip: int,
                  tally: _Tally, stop: int = 0, after: tuple[int, int] = (0, 0)
                  ) -> Iterator[np.ndarray]:
    """The rows from row `skip` on, cell by cell, in parts: an empty cell as NaN; a line that
    is no row of the table (the header's count of numbers) as a row of NaN, counted in tally.
    Where `stop`, the read ends once it has passed such a line and read `stop` rows, with
    tally.stopped its last line. after: (lines, rows) the file holds before where the read
    may start (where pyarrow's reader started)."""
    part: list[list[float]] = []
    nan_row = [float("nan")] * len(columns)
    met = False
    for k, (line, row) in enumerate(_rows(path, layout, after[0], skip - after[1]),
                                    start=skip):
        tally.rows = max(tally.rows, k + 1)
        try:
            part.append(_row_numbers(path, layout, columns, line, row))
        except TableError as err:
            tally.add(err, k + 1)
            part.append(nan_row)
            met = True
        if stop and met and k + 1 - skip >= stop:
            tally.stopped = line
            break
        if len(part) == BLOCK_ROWS:
            yield np.array(part, dtype=float).reshape(len(part), len(columns))
            part = []
    if part:
        yield np.array(part, dtype=float).reshape(len(part), len(columns))


def _row_numbers(path: Path, layout: _TextLayout, columns: list[int], line: int,
                 row: list[str]) -> list[float]:
    """The chosen columns' numbers of a row's cells; TableError naming the line where it is no
    row of the table (another count of cells, the header again, a cell that is no number)."""
    width = len(layout.header)
    if len(row) != width:
        text = layout.delimiter.join(row)
        raise TableError(f"{path}, line {line}: {len(row)} value(s) where the header has "
                         f"{width} columns ({text[:60]!r})")
    if [c.strip() for c in row] == layout.header:
        raise TableError(f"{path}, line {line}: the header again (a logger restarted and "
                         "wrote on)")
    return [_number(row[j], path, line, layout.header[j], layout.decimal_comma,
                    _clock_of(layout, j), layout.durations.get(j, "")) for j in columns]


def _clock_of(layout: _TextLayout, j: int) -> str:
    """What a column's cells are as time: DATETIME, TIME_OF_DAY or "" (numbers)."""
    return (DATETIME if j in layout.datetimes else TIME_OF_DAY if j in layout.times_of_day
            else "")


def _number(cell: str, path: Path, line: int, column: str, decimal_comma: bool,
            clock: str = "", duration: str = "") -> float:
    text = cell.strip()
    if text.lower() in MISSING_VALUES:
        return float("nan")  # a missing value: that sample is rejected and counted
    if duration:  # a number and the column's unit
        m = _DURATION.match(text)
        if m is None or m.group(2) != duration:
            raise TableError(f"{path}, line {line}, column {column!r}: {text[:40]!r} is not "
                             f"a duration in {duration} as the column's others are (0.01 "
                             f"{duration}; an empty cell marks a missing value)")
        return float(m.group(1)) * DURATION_UNITS[duration]
    if clock:  # seconds since 1970, or since midnight
        seconds = (seconds_of if clock == DATETIME else seconds_of_day)(text)
        if seconds is None:
            like = ("a date and time as the column's others are (2024-05-01T12:00:00.010, a "
                    "zone or none" if clock == DATETIME else
                    "a time of day as the column's others are (12:00:00.010")
            raise TableError(f"{path}, line {line}, column {column!r}: {text[:40]!r} is not "
                             f"{like}; an empty cell marks a missing value)")
        return seconds
    if decimal_comma:
        text = text.replace(",", ".")
    try:
        return float(text)
    except ValueError:
        raise TableError(f"{path}, line {line}, column {column!r}: {text[:40]!r} is not "
                         "a number (a number serves; an empty cell or NaN marks a missing "
                         "value, whose sample is rejected and counted)") from None


# ----- Parquet ---------------------------------------------------------------------------------

def _parquet(path: Path) -> TableSource:
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(path)
    except (pa.ArrowInvalid, OSError) as err:
        raise TableError(f"{path}: not a readable Parquet file ({err})") from None

    def batches(names: list[str], rows: int) -> Iterator[Any]:
        return iter(pf.iter_batches(batch_size=rows, columns=names))

    def first(name: str) -> Any:
        return pf.read_row_group(0, columns=[name]).column(0) if pf.num_row_groups else None

    return _arrow_source(path, "parquet", pf.schema_arrow, pf.metadata.num_rows, batches, first)


ARROW_MAGIC = (b"ARROW1", b"FEA1")
"""The first bytes of an Arrow IPC file (Feather v2, `.arrow`) and of a Feather v1 file."""


def _arrow_ipc(path: Path) -> TableSource:
    """An Arrow IPC file (pandas' to_feather, Polars' write_ipc), memory-mapped and read a
    written batch at a time (each decompressed as it is read); Feather v1, which has no
    batches, read whole."""
    import pyarrow as pa
    import pyarrow.feather as feather

    try:
        ipc = pa.ipc.open_file(pa.memory_map(str(path)))
    except (pa.ArrowInvalid, OSError):
        ipc = None
    if ipc is not None:
        def batches(names: list[str], rows: int) -> Iterator[Any]:
            return (ipc.get_batch(i).select(names) for i in range(ipc.num_record_batches))

        def first(name: str) -> Any:
            return ipc.get_batch(0).column(name) if ipc.num_record_batches else None

        rows = sum(ipc.get_batch(i).num_rows for i in range(ipc.num_record_batches))
        return _arrow_source(path, "arrow", ipc.schema, rows, batches, first)
    try:
        with warnings.catch_warnings():  # pyarrow's: v1 is deprecated (it reads it still)
            warnings.simplefilter("ignore", DeprecationWarning)
            table = feather.read_table(str(path))
    except (pa.ArrowInvalid, OSError) as err:
        raise TableError(f"{path}: not a readable Arrow IPC (Feather) file ({err})") from None
    return _arrow_source(path, "arrow", table.schema, table.num_rows,
                         lambda names, rows: iter(table.select(names).to_batches(rows)),
                         lambda name: table.column(name).chunk(0)
                         if table.column(name).num_chunks else None)


def _arrow_columns(field: Any, first: Callable[[str], Any]
                   ) -> list[tuple[str, tuple[Any, ...], Any]]:
    """A top-level Arrow field's columns as (name, the parts to its numbers, its metadata): a
    number's own; each number of a struct ("acc.x", "header.stamp.sec"); each of a list's k
    numbers, k the length of most lists of the first row group (a fixed-size list's own):
    "acc_x", "acc_y", "acc_z" for three, "q_1" ... "q_k" otherwise, as array_files names a
    matrix's columns."""
    import pyarrow as pa

    def numeric(kind: Any) -> bool:
        return (pa.types.is_floating(kind) or pa.types.is_integer(kind)
                or pa.types.is_timestamp(kind) or pa.types.is_duration(kind))

    def walk(f: Any, name: str, parts: tuple[Any, ...]) -> list[tuple[str, tuple[Any, ...], Any]]:
        kind = f.type
        if pa.types.is_struct(kind):
            return [c for child in kind for c in walk(child, f"{name}.{child.name}",
                                                      (*parts, child.name))]
        if (pa.types.is_list(kind) or pa.types.is_large_list(kind)
                or pa.types.is_fixed_size_list(kind)) and numeric(kind.value_type) and not parts:
            k = kind.list_size if pa.types.is_fixed_size_list(kind) else _list_width(first(name))
            if k:
                names = ([f"{name}_{axis}" for axis in "xyz"] if k == 3
                         else [f"{name}_{i + 1}" for i in range(k)])
                return [(n, (*parts, (i, k)), f.metadata) for i, n in enumerate(names)]
        return [(name, parts, f.metadata)]

    return walk(field, field.name, ())


def _list_width(column: Any) -> int | None:
    """The length most lists of a column's first chunk have (a list of another length is a
    sample without numbers), None for none."""
    import pyarrow.compute as pc

    if column is None or len(column) == 0:
        return None
    counts = pc.value_counts(pc.drop_null(pc.list_value_length(column))).to_pylist()
    width = max(counts, key=lambda c: c["counts"])["values"] if counts else 0
    return width if width > 0 else None


def _arrow_part(column: Any, parts: tuple[Any, ...], path: Path, name: str) -> np.ndarray:
    """The numbers at `parts` of a top-level column (a struct's fields by name, then a list's
    (element, length)), as float64: a null struct or list, or a list of another length, a
    sample without numbers."""
    import pyarrow.compute as pc

    missing = np.zeros(len(column), dtype=bool)
    for part in parts:
        missing |= ~np.asarray(column.is_valid().to_numpy(zero_copy_only=False))
        if isinstance(part, str):
            column = column.field(part)
            continue
        element, width = part
        lengths = pc.list_value_length(column).fill_null(0).to_numpy(zero_copy_only=False)
        missing |= lengths != width
        values = np.full(len(missing), np.nan)
        values[~missing] = _arrow_float(pc.list_element(column.filter(~missing), element), path,
                                        name)
        return values
    values = _arrow_float(column, path, name)
    return np.where(missing, np.nan, values) if missing.any() else values


def _arrow_source(path: Path, kind: str, schema: Any, rows: int, batches: Callable[..., Any],
                  first: Callable[[str], Any]) -> TableSource:
    """A Parquet or Arrow file's columns (_arrow_columns), read in blocks through `batches(names,
    rows)`; a unit from a field's `unit` or `units` metadata, timestamps as DATETIME."""
    import pyarrow as pa

    columns = [(field.name, *c) for field in schema for c in _arrow_columns(field, first)]
    header = [name for _, name, _, _ in columns]
    named = []
    for top, name, parts, meta in columns:
        kind = schema.field(top).type
        for part in parts:
            kind = kind.field(part).type if isinstance(part, str) else kind.value_type
        bare, unit = unit_of(name, (meta or {}).get(b"unit", (meta or {}).get(b"units")))
        named.append((bare, DATETIME if pa.types.is_timestamp(kind) else unit))

    def parts(chosen: list[int], size: int) -> Iterator[np.ndarray]:
        tops = list(dict.fromkeys(columns[i][0] for i in chosen))
        for batch in batches(tops, size):
            yield np.column_stack([
                _arrow_part(batch.column(columns[i][0]), columns[i][2], path, header[i])
                for i in chosen]) if chosen else np.empty((batch.num_rows, 0))

    def read(chosen: list[int], size: int) -> Iterator[np.ndarray]:
        return _reblocked(parts(chosen, size), size, len(chosen), lambda: None)

    return TableSource(path, header, [n for n, _ in named], [u for _, u in named], kind, rows,
                       read, lambda row: f"row {row + 1}")


def _arrow_float(column: Any, path: Path, name: str) -> np.ndarray:
    """An Arrow column as float64: numbers as they are, a timestamp or duration as seconds."""
    import pyarrow as pa

    kind = column.type
    if pa.types.is_timestamp(kind) or pa.types.is_duration(kind):
        return _seconds(column, round(1.0 / TIME_SCALE[kind.unit]))
    if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
        raise TableError(f"{path}, column {name!r}: holds {kind}, not numbers")
    return np.asarray(column.cast(pa.float64()).to_numpy(zero_copy_only=False), dtype=float)


__all__ = [
    "open_table",
    "zipped_table",
]
