"""Signal files: the piecewise reader (pandas' C parser for plain pieces, the line-by-line text path
for the rest) and the orjson writer against independent references.

The reference reader below is the format's rules written plainly, on the whole text at once: lines as
``str.splitlines`` cuts them, cells as ``csv`` reads them, numbers as Python's ``float()`` takes the
cells :data:`~flexshaft.measurement.signalfile._NUMBER` admits. Every file is read three ways - small files'
numpy path, pandas forced, and pandas on pieces of a few lines (so that pieces end in every place) -
and each must give the reference's numbers, bit for bit, or its error, word for word.
"""

from __future__ import annotations

import csv
import os
import threading

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.measurement import signalfile
from flexshaft.measurement.signalfile import read_signals, write_signals

HEADER = "time [s],a [N·m],b [rad]"


@pytest.fixture(params=["numpy", "pandas", "pieces"])
def way(request, monkeypatch):
    """How the reader parses: numpy alone (a small file), pandas for every piece, pandas on pieces of
    a few lines each."""
    if request.param != "numpy":
        monkeypatch.setattr(signalfile, "_PANDAS_MIN_BYTES", 0)
    if request.param == "pieces":
        monkeypatch.setattr(signalfile, "_PIECE_BYTES", 24)
    return request.param


def _reference(path):
    """The file's numbers as the format's rules read them: (header, matrix), or the ModelError."""
    err = signalfile._error
    data = path.read_bytes()
    if b"\0" in data:
        nul = data.index(b"\0")
        return err(path, f"holds a NUL byte at offset {nul}: not a text file", valid="a UTF-8 CSV file")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        return err(path, f"is not UTF-8 text (byte {e.start})", valid="a UTF-8 CSV file")
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        return err(path, "is empty", valid="a header row 'time [s],name [unit],...' and rows of numbers")
    try:
        header = signalfile._parse_header(path, lines[0])
    except ModelError as e:
        return e
    rows = [(k + 1, line) for k, line in enumerate(lines) if k and line.strip()]
    if len(rows) < 2:
        return err(
            path,
            f"has {len(rows)} data rows",
            valid="at least 2 rows of numbers under the header (the rate needs two)",
        )
    names = [h[0] for h in header]
    matrix = []
    for lineno, line in rows:
        try:
            cells = next(csv.reader([line]))
        except csv.Error as e:
            return err(path, f"line {lineno} is not CSV ({e})", valid="comma-separated numbers")
        if len(cells) != len(names):
            return err(
                path,
                f"line {lineno} has {len(cells)} cells, the header {len(names)}",
                valid="as many cells in every row as in the header",
            )
        row = []
        for c, cell in enumerate(cells):
            s = cell.strip()
            if not signalfile._NUMBER.fullmatch(s):
                return err(
                    path,
                    f"line {lineno}: not a number",
                    field=names[c],
                    value=s if len(s) <= 40 else s[:40] + "...",
                    valid="a decimal number such as 1.5 or -2e-3",
                )
            row.append(float(s))
        matrix.append(row)
    matrix = np.array(matrix).reshape(len(rows), len(names))
    bad = ~np.isfinite(matrix)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        return err(
            path,
            f"line {rows[r][0]}: {matrix[r, c]!r} ({int(bad.sum())} non-finite cells in all)",
            field=names[c],
            valid="finite numbers",
        )
    return header, matrix


def _same_bits(a, b) -> bool:
    """Equal to the last bit, the sign of zero included."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def _check_against_reference(path):
    """read_signals(path) gives the reference's numbers or its error (units here are all SI)."""
    ref = _reference(path)
    try:
        table = read_signals(path)
    except ModelError as err:
        if isinstance(ref, ModelError):
            assert str(err) == str(ref)
            return "error"
        # the numbers were fine: what is left is about the time base or the columns
        assert err.field in {"time", "time_column", "columns", *(h[0] for h in ref[0])}, str(err)
        return "later error"
    assert not isinstance(ref, ModelError), f"read, but the reference says: {ref}"
    header, matrix = ref
    names = [h[0] for h in header]
    ti = names.index("time")
    assert _same_bits(table.time, matrix[:, ti])
    for i, name in enumerate(names):
        if i != ti:
            assert _same_bits(table.columns[name], matrix[:, i]), name
    return "read"


def _file(tmp_path, content: str | bytes, name="s.csv"):
    path = tmp_path / name
    path.write_bytes(content.encode("utf-8") if isinstance(content, str) else content)
    return path


# Edge cases of the parsers, each a whole file, each read the three ways and compared with the reference.
ROWS = ["0,1.5,-2e-3", "0.001,+.5,1.", "0.002,1E+05,-0", "0.003, 7 ,\t8\t", "0.004,2.5e-320,1e22"]
EDGE = {
    "scientific notation and signs": HEADER + "\n" + "\n".join(ROWS) + "\n",
    "no newline at the end": HEADER + "\n" + "\n".join(ROWS),
    "CRLF line ends": HEADER + "\r\n" + "\r\n".join(ROWS) + "\r\n",
    "CR line ends": HEADER + "\r" + "\r".join(ROWS) + "\r",
    "a byte-order mark": "\ufeff" + HEADER + "\n" + "\n".join(ROWS) + "\n",
    "quoted header and numbers": '"time [s]","a [N·m]",b [rad]\n' + "\n".join(ROWS).replace("1.5", '"1.5"'),
    "blank lines between and after": HEADER + "\n\n" + "\n \t\n".join(ROWS) + "\n\n  \n\r\n",
    "blank lines, CRLF": HEADER + "\r\n\r\n" + "\r\n\r\n".join(ROWS) + "\r\n\r\n",
    "form feed and vertical tab in cells": HEADER + "\n" + "\n".join(ROWS).replace(" 7 ", "\f7\v") + "\n",
    "a line break inside a cell": HEADER + "\n" + "\n".join(ROWS).replace("1E+05", "1\x1c5") + "\n",
    "nan": HEADER + "\n" + "\n".join(ROWS).replace("1E+05", "nan") + "\n",
    "inf and -Infinity": HEADER
    + "\n"
    + "\n".join(ROWS).replace("+.5,1.", "+.5,inf").replace("1E+05", "-Infinity"),
    "overflow to inf": HEADER + "\n" + "\n".join(ROWS).replace("1e22", "1e400") + "\n",
    "a short row": HEADER + "\n" + "\n".join(ROWS).replace(",1E+05,-0", ",1E+05") + "\n",
    "a long row": HEADER + "\n" + "\n".join(ROWS).replace(",1E+05,-0", ",1E+05,-0,1") + "\n",
    "an empty cell": HEADER + "\n" + "\n".join(ROWS).replace("1E+05", "") + "\n",
    "a letter": HEADER + "\n" + "\n".join(ROWS).replace("1E+05", "1d5") + "\n",
    "a quote left open": HEADER + "\n" + "\n".join(ROWS).replace("1E+05", '"1E+05') + "\n",
    "a number and a comment": HEADER + "\n" + "\n".join(ROWS).replace("-0", "-0 # zero") + "\n",
    "a non-ASCII blank": HEADER + "\n" + "\n".join(ROWS).replace(" 7 ", "\u00a07\u2003") + "\n",
    "a non-ASCII line break": HEADER + "\n" + "\n".join(ROWS).replace(",1E+05,-0", ",1E+05,-0\u2028") + "\n",
    "nan then a ragged row later": HEADER + "\n" + "\n".join(ROWS).replace("1.5", "nan") + "\n0.005,1\n",
    "one data row and a bad one": HEADER + "\n\n0,x,1\n\n",
    "a bad first row, more rows after": HEADER + "\n0,x" + " " * 30 + ",1\n" + "\n".join(ROWS[1:]) + "\n",
    "a NUL byte after a ragged row": HEADER + "\n" + "\n".join(ROWS) + "\n0.005\n0.006,1,2\x00\n",
}
# Files that are not UTF-8 text, each with something else wrong before the damage (the order of errors
# stands, whatever comes first in the file; the offsets count from the first byte, NUL ones, or from
# after a byte-order mark, UTF-8 ones, as before).
GOOD = (HEADER + "\n" + "\n".join(ROWS) + "\n").encode("utf-8")
EDGE |= {
    "not UTF-8 after a bad number": GOOD.replace(b"\n0.001,", b"\n0,x,1\n0.001,") + b"0.005,\xff,1\n",
    "a byte-order mark and not UTF-8": b"\xef\xbb\xbf" + GOOD.replace(b"1e22", b"1e\xfe22"),
    "a byte-order mark, not UTF-8 then NUL": b"\xef\xbb\xbf"
    + GOOD.replace(b"1e22", b"1e\xfe22")
    + b"0,\x00\n",
}


@pytest.mark.parametrize("case", list(EDGE))
def test_edge_cases_read_as_the_reference_reads_them(tmp_path, way, case):
    assert _check_against_reference(_file(tmp_path, EDGE[case])) in {"read", "error"}


def test_the_edge_cases_that_should_read_do(tmp_path, way):
    """The reference itself is no tautology: the good cases read, with the numbers float() gives."""
    for case in ("scientific notation and signs", "CRLF line ends", "blank lines between and after"):
        table = read_signals(_file(tmp_path, EDGE[case]))
        assert _same_bits(table.columns["a"], [1.5, 0.5, 1e5, 7.0, 2.5e-320])
        assert _same_bits(table.columns["b"], [-2e-3, 1.0, -0.0, 8.0, 1e22])


@pytest.mark.parametrize("piece", [16, 23, 31, 40, 57])
def test_errors_name_the_line_across_pieces(tmp_path, way, piece, monkeypatch):
    if way == "pieces":  # pieces that end in other places: after a row, after a blank line, ...
        monkeypatch.setattr(signalfile, "_PIECE_BYTES", piece)
    rows = [f"{k / 1000!r},{k},{-k}" for k in range(40)]
    rows[31] = "0.031,1,2,3"
    path = _file(tmp_path, HEADER + "\n" + "\n\n".join(rows) + "\n")  # blank lines between: line 64
    with pytest.raises(ModelError, match="line 64 has 4 cells, the header 3"):
        read_signals(path)
    rows[31], rows[35] = "0.031,inf,2", "0.035,1,nan"
    # a blank line after every third row: some pieces end in one (cut off before pandas), some not
    text = "".join(r + ("\r\n \r\n" if k % 3 == 2 else "\r\n") for k, r in enumerate(rows))
    path = _file(tmp_path, HEADER + "\r\n" + text)
    with pytest.raises(ModelError, match=r"line 43: .*inf.* \(2 non-finite cells in all\)") as err:
        read_signals(path)
    assert err.value.field == "a"
    assert _check_against_reference(path) == "error"


def test_random_files_read_as_the_reference_reads_them(tmp_path, way):
    """Files of random cells, separators, line ends and damage: the reader and the reference agree."""
    rng = np.random.default_rng(20261124)
    good = ["0", "-0", "1.5", "+.5", "1.", "-2e-3", "1E+05", " 7 ", "\t8", "1e-320", "123456789.123456789e-3"]
    bad = ["", "x", "nan", "inf", "-Infinity", "1e400", "1d5", '"3"', '"3', "1_0", "0x2", "1 2", "\f4", "\v5"]
    ends = ["\n", "\r\n", "\r", "\n\n", "\n \n", "\x0c", "\u2028"]
    outcomes = set()
    for _ in range(150):
        lines = []
        for k in range(int(rng.integers(1, 12))):
            cells = [repr(k / 64.0)] + [str(rng.choice(good)) for _ in range(2)]
            if rng.random() < 0.1:
                cells[int(rng.integers(3))] = str(rng.choice(bad))
            if rng.random() < 0.03:
                cells = cells[: int(rng.integers(1, 5))] if rng.random() < 0.5 else [*cells, "1"]
            lines.append(",".join(cells))
        text = HEADER + "".join(
            str(rng.choice(ends, p=[0.7, 0.1, 0.05, 0.05, 0.04, 0.03, 0.03])) + r for r in lines
        )
        data = bytearray(text.encode("utf-8"))
        if rng.random() < 0.05:  # a byte anywhere (a NUL or not UTF-8)
            data[int(rng.integers(len(data)))] = int(rng.choice([0, 0xFF, 0xC3]))
        outcomes.add(_check_against_reference(_file(tmp_path, bytes(data))))
    assert outcomes == {"read", "error", "later error"}  # each kind was met


def test_decimal_strings_round_correctly(tmp_path, way):
    """Long and awkward decimals, as other tools write them, are read as float() reads them."""
    rng = np.random.default_rng(7)
    n = 3000
    mant = rng.integers(1, 10**18, n, dtype=np.int64)
    exp = rng.integers(-345, 290, n)  # from below the subnormals (0) to 1e307: all finite
    cells = [f"{m}e{e}" for m, e in zip(mant, exp)]
    cells[:4] = [
        "2.4703282292062328e-324",
        "9007199254740993",
        "0.1000000000000000055511151231257827",
        "1e23",
    ]
    t = [repr(k / 1000.0) for k in range(n)]
    path = _file(tmp_path, HEADER + "\n" + "\n".join(f"{a},{b},{b}" for a, b in zip(t, cells)) + "\n")
    expected = np.array([float(c) for c in cells])
    table = read_signals(path)
    assert _same_bits(table.columns["a"], expected) and _same_bits(table.columns["b"], expected)


def test_only_the_columns_asked_for_are_returned_and_none_share_memory(tmp_path, way):
    rows = "\n".join(f"{k / 100!r},{k},{2 * k}" for k in range(50))
    path = _file(tmp_path, HEADER + "\n" + rows + "\n")
    table = read_signals(path, columns=["b", "time"])
    assert list(table.columns) == ["b", "time"]
    assert _same_bits(table.columns["time"], table.time)
    assert not np.shares_memory(table.columns["time"], table.time)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_pipe_is_refused_by_name_without_waiting_for_a_writer(tmp_path):
    """A named pipe may never end (or never start: no writer, and an open waits forever), so it is
    refused by name before it is opened, whether a writer is there or not (issue 20)."""
    path = tmp_path / "pipe.csv"
    os.mkfifo(path)
    done = {}

    def read():
        try:
            read_signals(path)
        except ModelError as err:
            done["error"] = str(err)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(10)
    if reader.is_alive():  # blocked in open: release it before failing
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        pytest.fail("read_signals waited for a writer to the pipe")
    assert "pipe.csv: is a FIFO (a named pipe), not a signal file" in done["error"]


def _significant_digits(cell: str) -> int:
    mantissa = cell.lstrip("+-").lower().split("e")[0].replace(".", "")
    return max(len(mantissa.strip("0")), 1)


def test_writing_is_exact_and_shortest(tmp_path, monkeypatch):
    """Any finite double, subnormals and -0 included, is written so that float() gives it back, with
    no more digits than Python's repr (the shortest that round-trips), and reads back the same."""
    rng = np.random.default_rng(3)
    n = 20000
    bits = rng.integers(0, 2**63, n, dtype=np.uint64) | (
        rng.integers(0, 2, n, dtype=np.uint64) << np.uint64(63)
    )
    x = bits.view(np.float64)
    x = np.where(np.isfinite(x), x, 1.0)
    x[:8] = [0.0, -0.0, 5e-324, -2.2250738585072014e-308, 1.7976931348623157e308, 0.1, 1 / 3, 1e23]
    t = np.arange(n) / 1600.0
    path = write_signals(tmp_path / "w.csv", t, {"x": (x, "rad"), "y": (-x[::-1], "N·m")})
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0] == "time [s],x [rad],y [N·m]" and len(lines) == n + 1
    cells = [line.split(",") for line in lines[1:]]
    for k, column in enumerate((t, x, -x[::-1])):
        written = [row[k] for row in cells]
        assert _same_bits([float(c) for c in written], column)
        assert all(
            _significant_digits(c) <= _significant_digits(repr(float(v))) for c, v in zip(written, column)
        )
    for pandas_from in (signalfile._PANDAS_MIN_BYTES, 0):  # read by numpy (a small file), by pandas
        monkeypatch.setattr(signalfile, "_PANDAS_MIN_BYTES", pandas_from)
        table = read_signals(path)
        assert _same_bits(table.time, t) and _same_bits(table.columns["x"], x)
        assert _same_bits(table.columns["y"], -x[::-1])


def test_writing_a_single_column_and_a_long_record(tmp_path):
    """One signal (a single value per row besides time) and more rows than one formatting block."""
    n = 3 * signalfile._WRITE_ROWS + 17
    t = np.arange(n) / 1000.0
    v = np.sin(t) * 1e3
    path = write_signals(tmp_path / "w.csv", t, {"v": (v, "rpm")})
    text = path.read_text(encoding="utf-8")
    assert text.endswith("\n") and text.count("\n") == n + 1 and "[" not in text.split("\n", 1)[1]
    table = read_signals(path)
    assert _same_bits(table.time, t)
    # the reader multiplies by pi/30 once, (v * pi) / 30 here rounds twice: a few ulp apart at most
    assert table.columns["v"] == pytest.approx(v * np.pi / 30.0, rel=1e-15)
