"""A text recording reads the same through pyarrow's reader as through Python's: the same
samples to the bit, the same words, the same refusals.

The two readers share a file's reading: pyarrow's reads it in batches, Python's takes over a
stretch where pyarrow's meets a line that is no row, and pyarrow's goes on after it, mended
where such lines come often (testbenches.reader._text_parts); Python's reads a whole file
whose cells are padded or where pyarrow is missing. Each seeded file below is the repository's
example written as a logger might have written it (a delimiter, line ends, a byte-order mark,
a preamble, a footer, a time column in seconds, as dates or as times of day) with faults put
in where a serial link or a logger leaves them (blank lines, too few or too many values, rows
run together, a cell that is no number, a missing value, the header again, a cut line, a
quoted line), or a few of its bytes changed, dropped or put in: any way the two part is a
sample lost, moved or changed by which reader read it.
"""

from __future__ import annotations

import datetime as dt
import random
from pathlib import Path

import numpy as np
import pytest

from testbenches.fit.recording import RecordingError, open_recording

pytestmark = pytest.mark.heavy

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "tilt_motion.csv"
SEEDS = range(24)


def _fault(rng: random.Random, header: str, row: str) -> str:
    cells = row.split(",")
    j = rng.randrange(len(cells))
    kinds = [
        "", "   ", ",,,", "," * (len(cells) - 1),  # blank; a row of empty cells
        ",".join(cells[:rng.randrange(1, len(cells))]),  # cut short
        row + "," + row,  # two rows run together
        row.replace(",", ",,", 1),  # a delimiter twice
        ",".join(c[:1] + "$" + c[2:] if k == j else c for k, c in enumerate(cells)),
        ",".join("x" if k == j else c for k, c in enumerate(cells)),
        ",".join("" if k == j else c for k, c in enumerate(cells)),  # a missing value
        ",".join("NaN" if k == j else c for k, c in enumerate(cells)),
        header, row[:rng.randrange(len(row))], '"' + row + '"',
    ]
    return rng.choice(kinds)


def _time_cell(form: str, cell: str) -> str:
    """A time in seconds written in another form: as it is, a date and time, or a time of
    day."""
    try:
        seconds = float(cell)
    except ValueError:
        return cell
    if form == "s" or seconds != seconds:
        return cell
    when = dt.datetime(2024, 5, 1, 23, 59, 57) + dt.timedelta(seconds=seconds)
    return when.strftime({"iso": "%Y-%m-%dT%H:%M:%S.%f", "slashes": "%Y/%m/%d %H:%M:%S.%f",
                          "day": "%H:%M:%S.%f"}[form])[:-3]


def _logged(rng: random.Random, path: Path) -> Path:
    """The example as a logger might have written it, with faults (_fault) among its rows: a
    few, or many (those refused where more than 1 % are no row)."""
    header, *rows = EXAMPLE.read_text().splitlines()
    faults = set(rng.sample(range(20, len(rows) - 5), rng.choice([rng.randrange(10),
                                                                  rng.randrange(5, 25)])))
    lines = []
    for k, row in enumerate(rows):
        if k in faults:
            lines.append(_fault(rng, header, row))
            if rng.random() < 0.5:
                continue  # in the row's place, else before it
        lines.append(row)
    form = rng.choice(["s", "s", "iso", "slashes", "day"])
    lines = [header] + [",".join([_time_cell(form, line.split(",")[0]),
                                  *line.split(",")[1:]]) if line else line for line in lines]
    delimiter = rng.choice([",", ";", "\t", " "])
    if delimiter == " ":  # aligned columns
        lines = [" ".join(f"{c:>16}" for c in line.split(",")) for line in lines]
    elif delimiter != ",":
        lines = [line.replace(",", delimiter) for line in lines]
    end = rng.choice(["\n", "\r\n"])
    text = end.join(lines) + (end if rng.random() < 0.9 else "")
    if rng.random() < 0.2:
        text = f"# logger v1.2{end}# rate: 100 Hz{end}" + text
    if rng.random() < 0.1:
        text += f"END OF LOG{end}"
    path.write_bytes((("\ufeff" if rng.random() < 0.2 else "") + text).encode())
    return path


def _read(path: Path) -> tuple[str, object]:
    try:
        rec, t = open_recording(path, gyro_unit="rad/s").load()
    except RecordingError as err:
        return "refused", str(err)
    return "read", (rec, t)


def _garbled(rng: random.Random, path: Path) -> Path:
    """The example with a few of its bytes changed, dropped or put in, as a noisy serial link
    leaves it (a carriage return too, a line end of its own to both readers)."""
    data = bytearray(EXAMPLE.read_bytes())
    first = data.index(b"\n") + 1  # the header as written
    for _ in range(rng.randrange(1, 12)):
        at, byte = rng.randrange(first, len(data)), rng.choice([*range(256), 13, 13])
        kind = rng.random()
        if kind < 0.6:
            data[at] = byte
        elif kind < 0.8:
            del data[at]
        else:
            data.insert(at, byte)
    path.write_bytes(bytes(data))
    return path


def _lone_crs(rng: random.Random, path: Path) -> Path:
    """The example with carriage returns put inside a few of its lines (or its lines ended
    "\\n\\r", as a sketch may print them) and a few lines garbled: a line end of its own to
    either reader, which each once counted otherwise (pyarrow's reader went on from another
    line than Python's stopped at: a sample lost or read twice)."""
    lines = EXAMPLE.read_bytes().split(b"\n")
    for _ in range(rng.randrange(1, 4)):
        k = rng.randrange(2, len(lines) - 10)
        at = rng.randrange(len(lines[k]) + 1)
        lines[k] = lines[k][:at] + b"\r" + lines[k][at:]
    for _ in range(rng.randrange(4)):
        k = rng.randrange(2, len(lines) - 10)
        lines[k] = lines[k].replace(b",", b";", 1)
    path.write_bytes((b"\n\r" if rng.random() < 0.2 else b"\n").join(lines))
    return path


@pytest.mark.parametrize(("seed", "write"), [*((s, _logged) for s in SEEDS),
                                             *((s, _garbled) for s in SEEDS[:12]),
                                             *((s, _lone_crs) for s in SEEDS[:12])])
def test_a_logger_file_reads_the_same_through_either_reader(tmp_path, monkeypatch, seed, write):
    import testbenches.reader as reader

    path = write(random.Random(seed), tmp_path / "logged.csv")
    monkeypatch.setattr(reader, "ARROW_BLOCK", 1 << 12)  # batches of some 40 rows
    monkeypatch.setattr(reader, "RESUME_ROWS", 30)  # Python's stretches short: both kinds
    arrow = _read(path)
    monkeypatch.setattr(reader, "_has_pyarrow", lambda: False)
    python = _read(path)
    assert arrow[0] == python[0], (arrow, python)
    if arrow[0] == "refused":
        assert arrow[1] == python[1]
        return
    (a, a_t), (p, p_t) = arrow[1], python[1]
    for name in ("acc", "gyro", "dt", "valid"):
        np.testing.assert_array_equal(getattr(a, name), getattr(p, name), err_msg=name)
    np.testing.assert_array_equal(a_t, p_t)
    assert a.described == p.described


@pytest.mark.parametrize("seed", SEEDS[::3])
def test_a_logger_file_reads_the_same_compressed(tmp_path, seed):
    """A gzip copy of the file reads as the file: what its end holds (a cut line, a footer)
    is found in the decompressed stream as at the file's end."""
    import gzip

    path = _logged(random.Random(seed), tmp_path / "logged.csv")
    packed = tmp_path / "logged.csv.gz"
    packed.write_bytes(gzip.compress(path.read_bytes()))
    plain, compressed = _read(path), _read(packed)
    assert plain[0] == compressed[0]
    if plain[0] == "refused":
        assert str(compressed[1]).replace(packed.name, path.name) == plain[1]
        return
    (a, a_t), (p, p_t) = plain[1], compressed[1]
    for name in ("acc", "gyro", "dt", "valid"):
        np.testing.assert_array_equal(getattr(a, name), getattr(p, name), err_msg=name)
    np.testing.assert_array_equal(a_t, p_t)
    said = sorted(a.described.split("; "))  # a footer's said where the stream ends
    assert sorted(p.described.replace(packed.name, path.name).split("; ")) == said


def _same_reads(want: tuple[str, object], got: tuple[str, object], path: Path, as_path: Path
                ) -> None:
    """got (a read of `path`) as want (of `as_path`): the same samples to the bit, words and
    refusals, the file's name aside."""
    assert got[0] == want[0], (want, got)
    if want[0] == "refused":
        assert str(got[1]).replace(str(path), str(as_path)) == want[1]
        return
    (a, a_t), (p, p_t) = want[1], got[1]
    for name in ("acc", "gyro", "dt", "valid"):
        np.testing.assert_array_equal(getattr(a, name), getattr(p, name), err_msg=name)
    np.testing.assert_array_equal(a_t, p_t)
    assert (sorted(p.described.replace(str(path), str(as_path)).split("; "))
            == sorted(a.described.split("; ")))


@pytest.mark.parametrize("seed", SEEDS[::2])
def test_a_logger_file_whose_lines_end_with_a_carriage_return_alone(tmp_path, monkeypatch,
                                                                   seed):
    """Classic Mac OS text and Excel for Mac's "CSV (Macintosh)" end each line with a carriage
    return alone: such a file was a traceback (csv's "new-line character seen in unquoted
    field", from the look at its end). It reads as the same file with line feeds, plain and
    gzipped, with NULs after its last line too: the same samples, words (line numbers) and
    refusals."""
    import gzip

    import testbenches.reader as reader

    monkeypatch.setattr(reader, "ARROW_BLOCK", 1 << 12)  # both readers in turn (as above)
    monkeypatch.setattr(reader, "RESUME_ROWS", 30)
    text = _logged(random.Random(seed), tmp_path / "any.csv").read_bytes().replace(b"\r\n",
                                                                                  b"\n")
    lf, cr, packed = (tmp_path / "lf.csv", tmp_path / "cr.csv", tmp_path / "cr.csv.gz")
    lf.write_bytes(text)
    cr.write_bytes(text.replace(b"\n", b"\r"))
    packed.write_bytes(gzip.compress(cr.read_bytes()))
    want = _read(lf)
    _same_reads(want, _read(cr), cr, lf)
    _same_reads(want, _read(packed), packed, lf)
    lf.write_bytes(text + b"\x00" * 5000)  # a preallocated file's unwritten rest
    cr.write_bytes(text.replace(b"\n", b"\r") + b"\x00" * 5000)
    _same_reads(_read(lf), _read(cr), cr, lf)
