"""Signal files: sampled time signals (simulated or measured) as CSV with units in the header.

The format: UTF-8 text, comma-separated, one header row, then one row per sample. A header cell is
``name [unit]`` (``time [s]``, ``torque:part 3 [N·m]``, ``speed:generator [rad/s]``); a cell
without ``[unit]`` needs its unit stated by the reader (``units=``). The time column is ``time``
unless told. Reading converts to SI:

=========  ==============================  =========
quantity   accepted units                  SI
=========  ==============================  =========
time       s, ms                           s
angle      rad, deg, °                     rad
speed      rad/s, rpm (1/min, U/min,       rad/s
           rev/min)
torque     N·m (N*m, Nm, N m, N⋅m),        N·m
           kN·m (kN*m, kNm, kN m, kN⋅m)
=========  ==============================  =========

(:data:`~flexshaft.measurement.signaltable.UNITS`, shared with the measured files' reader.)

Other formats: a path ending in ``.tdms``, ``.mf4``, ``.mdf``, ``.dat``, ``.h5``, ``.hdf5`` or ``.mat``
is a measured test-bench file, read by :func:`flexshaft.measurement.files.read_measured` (same table,
same units); every other path is read as CSV, as described here.

Files are untrusted: anything that is not such a table - ragged rows, a cell that is no number,
NaN or infinity, duplicate or empty headers, times that do not increase uniformly, an unknown unit,
bytes that are not UTF-8, a file above its ceiling (:data:`MAX_BYTES` unless ``FLEXSHAFT_MAX_FILE_MB``
says), a line above :data:`MAX_LINE_BYTES`, a path that is no regular file (a FIFO, a device) - is
one :class:`~flexshaft.errors.ModelError` naming the file, the row or column, and what is valid.
Nothing is allocated from what a file claims: the rows are what is there. Writing
(:func:`write_signals`) is atomic and exact: each value is the shortest decimal that reads back as
the same float (as ``repr`` writes it), so a file read back gives the same floats.

Speed and memory: a file is read a piece (1 MiB) at a time, its text never held whole, and only the
columns asked for are kept. A piece of plain ASCII numbers (and of a file above 1 MiB) is parsed by
pandas' C parser (correctly rounded, as ``float()``), checked numeric and finite; a piece it refuses,
and every piece of a small file, is read line by line by the reference rules (numpy's ``loadtxt``,
then cell by cell), which find what is wrong and its line: the same numbers and the same errors
either way. ``benchmarks/bench_signalfile.py`` measured the choice (pandas over numpy's C parser,
orjson to format the values).
"""

from __future__ import annotations

import csv
import io
import os
import re
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..system.atomic import atomic_write_bytes
from ..system.inputs import MB, SIGNALS, open_input
from ..system.threads import follows_policy
from .checks import uniform_rate
from .signaltable import UNITS, VALID_UNITS, SignalTable, signal_entries, stated_units

__all__ = [
    "MAX_BYTES",
    "MAX_LINE_BYTES",
    "UNITS",
    "SignalTable",
    "read_signals",
    "read_torque_history",
    "write_signals",
]

#: The largest file read by default, bytes (2 GiB: some 50 million samples of a few channels);
#: ``FLEXSHAFT_MAX_FILE_MB`` sets another (:mod:`flexshaft.system.inputs`).
MAX_BYTES = int(SIGNALS.default_mb * MB)
#: The longest line read, bytes: a row of ~40 000 numbers. A file of one endless line (NUL bytes,
#: a binary file) is refused after this much, not read whole as one line.
MAX_LINE_BYTES = 1 << 20

# A header cell: a name, then optionally a unit in square brackets at the end.
_HEADER = re.compile(r"^(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?$")
# Rows formatted at a time when writing: a block's text (~0.8 MB) stays in the processor's cache for
# the bracket replacement (the whole record at once took 1.2x as long).
_WRITE_ROWS = 1 << 14
# What a number cell may be (ASCII digits only; float() alone would take '1_000' or Arabic digits).
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:nan|inf|infinity)", re.I | re.A)


def _error(path, message: str, **fields) -> ModelError:
    return ModelError(message, file=str(path), **fields)


def _check_time(time: np.ndarray, field: str, path=None) -> float:
    """The sampling rate of increasing, uniformly spaced ``time`` (s); raises naming ``field``."""
    loc = {"file": str(path)} if path is not None else {}
    if time.size < 2:
        raise ModelError(
            f"has {time.size} samples", field=field, valid="at least 2 samples (the rate needs two)", **loc
        )
    try:
        return uniform_rate(time, field)
    except ModelError as err:
        raise err.located(**loc) if loc else err from None


# Bytes read and parsed at a time. The file's text is never held whole: the peak is the columns kept,
# one piece and its parse. Pieces of 1 to 8 MiB read a long record equally fast (pandas' fixed cost per
# call, ~0.2 ms, is a few per cent of a 1 MiB parse); the smallest holds the least.
_PIECE_BYTES = 1 << 20
# Pieces of files smaller than this are parsed by numpy's loadtxt alone: importing pandas (~0.4 s) costs
# more than its faster parse saves on them (loadtxt ~20 ms per MB, pandas ~2 ms per MB on a 2-core machine).
_PANDAS_MIN_BYTES = 1 << 20
# The ASCII bytes str.strip() removes: a line of nothing else is blank.
_ASCII_SPACE = bytes(c for c in range(128) if chr(c).isspace())
_BOM = b"\xef\xbb\xbf"  # UTF-8's byte-order mark, as spreadsheets write it: dropped at the start


def _pieces(fh, path):
    """The file as pieces of whole lines, about :data:`_PIECE_BYTES` each.

    Every piece but the last ends at a line feed, so no line, no CR LF pair and no UTF-8 character
    is cut between two pieces. ``fh`` (:func:`flexshaft.system.inputs.open_input`) raises once more than the
    ceiling came (a growing file, or one that holds more than its size said); a line longer than
    :data:`MAX_LINE_BYTES` is refused as soon as it is seen, before the rest of it is read.
    """
    lines = 0  # line feeds before this piece
    while True:
        piece = fh.read(_PIECE_BYTES)
        if not piece:
            return
        tail = len(piece) - (piece.rfind(b"\n") + 1)  # bytes of the line the read cut
        if tail:
            if tail <= MAX_LINE_BYTES:
                piece += fh.readline(MAX_LINE_BYTES + 1 - tail)  # the rest of that line
                tail = len(piece) - (piece.rfind(b"\n") + 1)
            if tail > MAX_LINE_BYTES:
                line = lines + piece.count(b"\n") + 1
                raise _error(
                    path,
                    f"line {line} is longer than {MAX_LINE_BYTES // (1 << 20)} MB (no line feed in it)",
                    valid="a CSV file: one row of numbers per line",
                )
        lines += piece.count(b"\n")
        yield piece


def _pandas_values(data: bytes, ncols: int) -> np.ndarray | None:
    """The numbers of ``data`` by pandas' C parser, shape (rows, ``ncols``), or None where it refuses them.

    ``data`` is ASCII without NUL, vertical tab or form feed (the callers check), so that pandas' rules
    and the reference rules (:func:`_parse_rows`: lines as ``str.splitlines`` cuts them, cells as
    ``csv`` reads them, numbers as :data:`_NUMBER` takes them) read the same numbers: lines end at LF,
    CR LF or CR in both; a cell is a number with ASCII blanks around it or is refused; pandas parses
    every double correctly rounded (fast_float, pandas >= 3.1), as ``float()`` does.
    """
    import pandas as pd

    try:
        frame = pd.read_csv(
            io.BytesIO(data),
            header=None,
            dtype=np.float64,
            engine="c",
            na_filter=False,  # an empty cell or 'NA' is refused, not read as NaN
            quoting=csv.QUOTE_NONE,  # a quote is no number: refused (the text path unquotes, as csv does)
            skip_blank_lines=False,  # a blank line is refused: one skipped would go uncounted
            low_memory=False,  # one parse of the piece, not sub-pieces concatenated
        )
    except ValueError:  # what pandas refuses (its ParserError and EmptyDataError are ValueErrors)
        return None
    return frame.to_numpy() if frame.shape[1] == ncols else None


def _parse_rows(path, rows: list[tuple[int, str]], names: list[str]) -> np.ndarray:
    """The rows ``[(line number, text)]`` as numbers: numpy's C parser, or cell by cell where it refuses."""
    values = None
    try:
        values = np.loadtxt([r[1] for r in rows], delimiter=",", comments=None, dtype=float, ndmin=2)
    except ValueError:
        pass
    if values is None or values.shape != (len(rows), len(names)):
        values = _parse_rows_slowly(path, rows, names)
    return values


class _Reader:
    """One pass over a signal file, piece by piece: the columns kept, and the first damage of each kind.

    What is wrong with a file is reported in this order, whatever comes first in the file: more than
    the ceiling or a line above :data:`MAX_LINE_BYTES` (both end the reading at once); a NUL byte;
    bytes that are not UTF-8; no line that is not blank; the header; fewer than 2 data rows; a row
    that is not numbers; a non-finite number. So each kind's first occurrence is noted, and once a
    piece is damaged the rest of the file is only scanned for what outranks it. A piece that is ASCII
    (and big enough to be worth pandas' import) is parsed by pandas; one it refuses, and any other
    piece, is read line by line as text (numpy's ``loadtxt``, then cell by cell where it refuses):
    the reference rules, and the exact line of what is wrong.
    """

    def __init__(self, path, wanted, use_pandas: bool):
        self.path = path
        self.wanted = wanted  # header -> indices of the columns to keep
        self.use_pandas = use_pandas
        self.offset = 0  # of the next piece in the file, bytes
        self.bom = 0  # bytes of a byte-order mark at the start
        self.lines = 0  # lines so far, blank ones too (str.splitlines' count)
        self.rows = 0  # data rows so far (lines after the header that are not blank)
        self.nonblank = False
        self.header = None
        self.header_error = None
        self.nul = None  # offset of the first NUL byte
        self.utf8 = None  # offset (after a byte-order mark) of the first byte that is not UTF-8
        self.bad_row = None  # the error of the first row that is not numbers
        self.nonfinite = None  # (line, value, column index) of the first non-finite number
        self.nonfinite_count = 0
        self.parts: dict[int, list] = {}  # kept column -> its pieces

    def feed(self, piece: bytes) -> None:
        start = self.offset
        self.offset += len(piece)
        if start == 0 and piece.startswith(_BOM):
            piece, self.bom, start = piece[len(_BOM) :], len(_BOM), len(_BOM)
        if self.nul is not None:
            return  # nothing the rest may hold outranks it
        nul = piece.find(b"\0")
        if nul >= 0:
            self.nul = start + nul
            return
        if self.utf8 is not None:
            return  # only a NUL byte outranks it
        text = None
        if not piece.isascii():
            try:
                text = piece.decode("utf-8")
            except UnicodeDecodeError as err:
                self.utf8 = start - self.bom + err.start
                return
        if self.header is None:
            piece, text = self._take_header(piece, text)
            if text is not None and piece.isascii():
                text = None  # the header held the non-ASCII (a unit's '·'): the rows go the fast way
        if self.header_error is not None or self.bad_row is not None:
            self._count(piece, text)
        elif piece:
            fast = text is None and (self.use_pandas or len(piece) >= _PANDAS_MIN_BYTES)
            if not (fast and self._parse_fast(piece)):
                self._parse_text(piece.decode("ascii") if text is None else text, self.lines + 1)

    def _take_header(self, piece: bytes, text):
        """The header from the first line; the rest of the piece."""
        end = piece.find(b"\n") + 1 or len(piece)
        segment = piece[:end].decode("utf-8")  # decodes: the whole piece did
        if not segment:
            return piece, text
        line = segment.splitlines(keepends=True)[0]
        self.lines = 1
        header_line = line.splitlines()[0]
        self.nonblank = bool(header_line.strip())
        try:
            self.header = _parse_header(self.path, header_line)
        except ModelError as err:
            self.header, self.header_error = [], err
        else:
            self.parts = {i: [] for i in sorted(self.wanted(self.header))}
        size = len(line.encode("utf-8"))
        return piece[size:], None if text is None else text[len(line) :]

    def _count(self, piece: bytes, text) -> None:
        """Only count rows (as far as the order of errors needs them) in a file already damaged."""
        if self.nonblank and self.rows >= 2:
            return
        for line in (piece.decode("ascii") if text is None else text).splitlines():
            if line.strip():
                self.nonblank = True
                self.rows += self.header is not None
                if self.rows >= 2:
                    return

    def _parse_fast(self, piece: bytes) -> bool:
        """Parse an ASCII piece with pandas; False where the text path must read it."""
        end = len(piece)
        while end and piece[end - 1] in _ASCII_SPACE:
            end -= 1
        if not end:
            return False
        # The lines after the last row's end are blank: pandas refuses blank lines, so they are cut off
        # (a copy of the piece, hence only when there are some).
        blank = piece[end:].decode("ascii").splitlines()[1:]
        head = piece[:end] if blank else piece
        if b"\v" in head or b"\f" in head:  # pandas takes these two for blanks around a number
            return False
        values = _pandas_values(head, len(self.header))
        if values is None or not np.isfinite(values).all():
            return False  # the text path finds what is wrong, and its line
        n = values.shape[0]
        self._keep(values)
        self.lines += n + len(blank)
        self.rows += n
        self.nonblank = True
        return True

    def _parse_text(self, text: str, first: int) -> None:
        lines = text.splitlines()
        rows = [(first + k, line) for k, line in enumerate(lines) if line.strip()]
        self.lines += len(lines)
        if not rows:
            return
        self.nonblank = True
        self.rows += len(rows)  # all of them: the count outranks a bad row when it is below 2
        try:
            values = _parse_rows(self.path, rows, [h[0] for h in self.header])
        except ModelError as err:  # the first row that is not numbers (raised once the order allows)
            self.bad_row = err
            return
        bad = ~np.isfinite(values)
        if bad.any():
            if self.nonfinite is None:
                r, c = np.argwhere(bad)[0]
                self.nonfinite = (rows[r][0], values[r, c], c)
            self.nonfinite_count += int(bad.sum())
        self._keep(values)

    def _keep(self, values: np.ndarray) -> None:
        if self.nonfinite is None:  # after one, the data are never returned
            for i, parts in self.parts.items():
                parts.append(values[:, i].copy())  # a copy: the piece's other columns are let go

    def finish(self) -> tuple[list, dict]:
        """The header and the kept columns, or the first error in the order above."""
        p = self.path
        if self.nul is not None:
            raise _error(
                p, f"holds a NUL byte at offset {self.nul}: not a text file", valid="a UTF-8 CSV file"
            )
        if self.utf8 is not None:
            raise _error(p, f"is not UTF-8 text (byte {self.utf8})", valid="a UTF-8 CSV file")
        if not self.nonblank:
            raise _error(p, "is empty", valid="a header row 'time [s],name [unit],...' and rows of numbers")
        if self.header_error is not None:
            raise self.header_error
        if self.rows < 2:
            raise _error(
                p,
                f"has {self.rows} data rows",
                valid="at least 2 rows of numbers under the header (the rate needs two)",
            )
        if self.bad_row is not None:
            raise self.bad_row
        if self.nonfinite is not None:
            line, value, c = self.nonfinite
            raise _error(
                p,
                f"line {line}: {value!r} ({self.nonfinite_count} non-finite cells in all)",
                field=self.header[c][0],
                valid="finite numbers",
            )
        # one column at a time, each one's pieces let go after it: the peak is the columns and one more
        columns = {i: np.concatenate(self.parts.pop(i)) for i in list(self.parts)}
        return self.header, columns


def _read_table(path: Path, wanted) -> tuple[list, dict]:
    """Read and check a signal file: its header, and the columns ``wanted(header)`` picks, by index."""
    try:
        # a regular file within the signal file's ceiling, streamed (flexshaft.system.inputs)
        with open_input(path, SIGNALS) as fh:
            size = os.fstat(fh.fileno()).st_size
            reader = _Reader(path, wanted, use_pandas=size >= _PANDAS_MIN_BYTES)
            for piece in _pieces(fh, path):
                reader.feed(piece)
    except OSError as err:
        raise _error(
            path, f"cannot be read ({err.strerror or type(err).__name__})", valid="a readable CSV file"
        ) from None
    return reader.finish()


def _parse_header(path, line: str) -> list[tuple[str, str | None, str]]:
    """``[(name, unit or None, cell as written)]`` of the header row."""
    try:
        cells = next(csv.reader([line]))
    except csv.Error as err:
        raise _error(
            path, f"header row is not CSV ({err})", field="header", valid="name [unit],..."
        ) from None
    if len(cells) == 1:
        for sep, name in ((";", "semicolons"), ("\t", "tabs")):
            if sep in line:
                raise _error(
                    path,
                    f"the header is separated by {name}",
                    field="header",
                    valid="comma-separated columns (the decimal point a '.')",
                )
    out, seen = [], {}
    for i, cell in enumerate(cells):
        m = _HEADER.match(cell.strip())
        if m is None:
            raise _error(
                path,
                f"header cell {i + 1} is not 'name [unit]'",
                field="header",
                value=cell,
                valid="name [unit], or a bare name; no other square brackets",
            )
        name, unit = m["name"].strip(), m["unit"]
        if not name:
            raise _error(
                path,
                f"header cell {i + 1} has no name",
                field="header",
                value=cell,
                valid="a non-empty name in every header cell",
            )
        if name in seen:
            raise _error(
                path,
                f"header cells {seen[name] + 1} and {i + 1} both name {name!r}",
                field="header",
                valid="distinct column names",
            )
        seen[name] = i
        out.append((name, None if unit is None else unit.strip(), cell.strip()))
    return out


def _parse_rows_slowly(path, rows: list[tuple[int, str]], names: list[str]) -> np.ndarray:
    """The data rows cell by cell: the exact row and column of what is wrong."""
    out = np.empty((len(rows), len(names)))
    for r, (lineno, line) in enumerate(rows):
        try:
            cells = next(csv.reader([line]))
        except csv.Error as err:
            raise _error(path, f"line {lineno} is not CSV ({err})", valid="comma-separated numbers") from None
        if len(cells) != len(names):
            raise _error(
                path,
                f"line {lineno} has {len(cells)} cells, the header {len(names)}",
                valid="as many cells in every row as in the header",
            )
        for c, cell in enumerate(cells):
            text = cell.strip()
            if not _NUMBER.fullmatch(text):
                shown = text if len(text) <= 40 else text[:40] + "..."
                raise _error(
                    path,
                    f"line {lineno}: not a number",
                    field=names[c],
                    value=shown,
                    valid="a decimal number such as 1.5 or -2e-3",
                )
            out[r, c] = float(text)
    return out


def _resolve(path, wanted: str, header, what: str) -> int:
    for i, (name, _, cell) in enumerate(header):
        if wanted in (name, cell):
            return i
    raise _error(
        path,
        "no such column",
        field=what,
        value=wanted,
        valid="one of " + ", ".join(repr(h[0]) for h in header),
    )


def _wanted(p: Path, header, columns, time_column: str) -> set[int]:
    """The columns to keep: the time and the signals asked for, or all of them where that is unclear
    (the error it makes is raised by :func:`read_signals` after the file's own, as before)."""
    every = set(range(len(header)))
    if columns is None:
        return every
    try:
        asked = [columns] if isinstance(columns, str) else columns
        return {
            _resolve(p, time_column, header, "time_column"),
            *(_resolve(p, c, header, "columns") for c in asked),
        }
    except Exception:  # whatever it is, it is raised again by read_signals, in its turn
        return every


def _si_unit(p: Path, header, i: int, stated: dict, ti: int) -> tuple[str, float]:
    """Column ``i``'s SI unit and factor: its header's unit or the one ``stated`` (seconds for the time
    column ``ti`` when neither says), refused when the two differ, when there is none or it is unknown."""
    name, unit, _ = header[i]
    if unit is not None and i in stated and stated[i] != unit:
        raise _error(
            p,
            f"has the unit {unit!r} in the header and {stated[i]!r} in units=",
            field=name,
            valid="one unit: leave it out of units= when the header states it",
        )
    unit = unit if unit is not None else stated.get(i, "s" if i == ti else None)
    if unit is None:
        raise _error(
            p,
            "has no unit",
            field=name,
            valid=f"a header 'name [unit]', or the unit stated: units={{{name!r}: unit}} "
            f"(command line: --unit {name}=UNIT); units: {VALID_UNITS}",
        )
    if unit not in UNITS:
        raise _error(p, "unknown unit", field=name, value=unit, valid=f"one of {VALID_UNITS}")
    return UNITS[unit]


def _in_si(p: Path, name: str, raw: np.ndarray, unit: str, factor: float) -> np.ndarray:
    """A column's values times its unit's factor (the column itself for 1), refused where a value
    overflows when made SI."""
    if factor == 1.0:
        return raw
    with np.errstate(over="ignore"):  # a value that overflows when made SI: refused below
        values = raw * factor
    if not np.isfinite(values).all():
        row = int(np.flatnonzero(~np.isfinite(values))[0])
        raise _error(
            p,
            f"holds a value too large to convert to {unit} ({float(raw[row])!r} in data "
            f"row {row + 1}, times {factor:g})",
            field=name,
            valid=f"values whose {unit} value is a finite number (below 1.8e308)",
        )
    return values


def read_signals(
    path, columns=None, units=None, *, time_column: str | None = None, group: str | None = None, rate=None
) -> SignalTable:
    """Read a signal file (see the module docstring for the format), or a measured file.

    A path ending in ``.tdms``, ``.mf4``, ``.mdf``, ``.h5``, ``.hdf5``, ``.mat`` (or ``.dat`` holding
    MDF) is read by :func:`flexshaft.measurement.files.read_measured`, ``columns`` being its channels;
    every other path as CSV.

    Parameters
    ----------
    path : str or Path
        The CSV file (or measured file).
    columns : sequence of str, optional
        The signals to read, each by its full header (``"torque [N·m]"``) or its name
        (``"torque"``). Default: every column but the time.
    units : dict of str to str, optional
        Units for header cells that have none, by name or full header: ``{"torque": "kNm"}``. A
        unit given for a column whose header states another one is an error.
    time_column : str, optional
        The time column, by name or full header (default ``"time"``); its unit must be s or ms
        (seconds when the header has none and ``units`` does not say). A measured file: a time
        channel, default each channel's own timing.
    group, rate
        A measured file's channel group and sampling rate
        (:func:`~flexshaft.measurement.files.read_measured`); a CSV file has neither.

    Returns
    -------
    SignalTable
        Time in s, every signal converted to SI.

    Raises
    ------
    ModelError
        A damaged or hostile file, an unknown column, a unit missing or unknown.
    """
    try:
        p = Path(path)
    except TypeError:
        raise ModelError("is not a path", field="path", value=path, valid="a file path") from None
    from .files import is_measured

    if is_measured(p):
        from .files import read_measured

        try:
            return read_measured(p, columns, units, time_column=time_column, group=group, rate=rate)
        except ModelError as err:  # the channels are this function's columns
            raise (err.replaced(field="columns") if err.field == "channels" else err) from None
    for name, given in (("group", group), ("rate", rate)):
        if given is not None:
            raise ModelError(
                "applies to a measured file (TDMS, MDF, HDF5, MAT) only",
                field=name,
                value=given,
                valid="leave it out for a CSV signal file",
            )
    if time_column is None:
        time_column = "time"
    if columns is not None and not isinstance(columns, str):
        try:
            columns = list(columns)  # looked at twice: for what to keep, then for what to return
        except TypeError:
            pass  # refused below, in its turn, as before

    header, data = _read_table(p, lambda header: _wanted(p, header, columns, time_column))
    names = [h[0] for h in header]
    handed = set()

    def column(i: int) -> np.ndarray:
        """Column ``i``, as read; a copy when it was handed out already (no two results share memory)."""
        if i in handed:
            return data[i].copy()
        handed.add(i)
        return data[i]

    stated = {_resolve(p, key, header, "units"): unit for key, unit in stated_units(units, "column").items()}
    ti = _resolve(p, time_column, header, "time_column")
    if columns is None:
        picked = [i for i in range(len(header)) if i != ti]
    else:
        if isinstance(columns, str):
            columns = [columns]
        picked = [_resolve(p, c, header, "columns") for c in columns]
    if not picked:
        raise _error(p, "holds only the time column", field="columns", valid="at least one signal column")

    t_unit, t_factor = _si_unit(p, header, ti, stated, ti)
    if t_unit != "s":
        raise _error(p, "is not a time", field=header[ti][0], value=header[ti][1], valid="a unit s or ms")
    time = column(ti) * t_factor if t_factor != 1.0 else column(ti)
    rate = _check_time(time, header[ti][0], p)
    out, out_units = {}, {}
    for i in picked:
        unit, factor = _si_unit(p, header, i, stated, ti)
        values = _in_si(p, names[i], column(i), unit, factor)
        out[names[i]] = values
        out_units[names[i]] = unit
    return SignalTable(time=time, columns=out, units=out_units, rate_hz=rate, source=str(p))


def _column(values, field: str, n: int | None) -> np.ndarray:
    valid = "a 1-D sequence of finite numbers" + (f", one per time ({n})" if n is not None else "")
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ModelError("is not numbers", field=field, valid=valid) from None
    if arr.ndim != 1 or (n is not None and arr.size != n):
        raise ModelError(f"has shape {arr.shape}", field=field, valid=valid)
    if not np.all(np.isfinite(arr)):
        raise ModelError("holds non-finite values", field=field, valid=valid)
    return arr


def _csv_bytes(header: list[str], table: np.ndarray) -> bytearray:
    """The header cells and the rows of ``table`` (float64, finite) as a UTF-8 CSV file: each value the
    shortest decimal that reads back as the same float (what ``repr`` gives, but ``1e-7`` for ``1e-07``).

    orjson formats a block of rows as ``[[t,a,b],[t,a,b],...]`` in compiled code (a shortest
    round-trip algorithm): 0.3 s for a 900 s run at 1.6 kHz (3 columns), where Python's own ``%r``
    took 1.9 s and ``np.savetxt``'s ``%.17g`` 3.6 s, longer than the simulation. Its brackets become
    line ends.
    """
    import orjson

    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(header)  # quotes a name with a comma
    out = bytearray(buf.getvalue().encode("utf-8"))
    for first in range(0, table.shape[0], _WRITE_ROWS):
        block = np.ascontiguousarray(table[first : first + _WRITE_ROWS])  # orjson takes C order only
        text = orjson.dumps(block, option=orjson.OPT_SERIALIZE_NUMPY).replace(b"],[", b"\n")
        out += memoryview(text)[2:-2]  # appended without a copy of the slice: '[[' and ']]' left out
        out += b"\n"
    return out


@follows_policy
def write_signals(path, time, columns: dict, overwrite: bool = False) -> Path:
    """Write signals to a CSV signal file, atomically.

    Parameters
    ----------
    path : str or Path
        The file to write; an existing one only with ``overwrite``.
    time : array_like, shape (n,)
        Sample times, s: increasing, uniformly spaced (as :func:`read_signals` requires).
    columns : dict of str to (array_like, str)
        ``name -> (values, unit)``: values of shape (n,) in ``unit``, one of :data:`UNITS`
        (written as given, converted when read). Names must not contain square brackets or line
        breaks, nor be ``time``.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The file written: a header ``time [s],NAME [unit],...`` and the values, each the shortest
        decimal that reads back as the same float (``repr``'s digits: read back, the same floats).
    """
    t = _column(time, "time", None)
    _check_time(t, "time")
    cells, arrays = ["time [s]"], [t]
    for key, name, values, unit in signal_entries(columns):
        if "[" in name or "]" in name or name == "time":
            raise ModelError(
                "is not a usable column name",
                field="columns",
                value=key,
                valid="a name without [ ], not 'time'",
            )
        arrays.append(_column(values, name, t.size))
        cells.append(f"{name} [{unit}]")
    return atomic_write_bytes(path, _csv_bytes(cells, np.column_stack(arrays)), overwrite=overwrite)


def read_torque_history(
    path, column: str, *, units=None, time_column: str | None = None, group=None, field: str = "column"
):
    """A drive torque history (a simulation's csv scenario): one column of a signal file, in N·m.

    Parameters
    ----------
    path : str or Path
        The signal file, or a measured file (:func:`read_signals`).
    column : str
        The torque column (a measured file's channel).
    units, time_column, group
        As for :func:`read_signals`.
    field : str
        What an error calls the column (the CLI's ``--column``, a study's ``column``).

    Returns
    -------
    (ndarray, ndarray)
        Time (s) and torque (N·m).
    """
    table = read_signals(path, columns=[column], units=units, time_column=time_column, group=group)
    ((torque, unit),) = ((table.columns[n], table.units[n]) for n in table.columns)
    if unit != "N·m":
        raise ModelError(
            "the drive torque history must be a torque",
            field=field,
            value=column,
            unit=unit,
            valid="a column in N·m or kN·m",
        )
    return table.time, torque
