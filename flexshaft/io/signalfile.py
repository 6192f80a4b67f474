"""Signal files: sampled time signals (simulated or measured) as CSV with units in the header.

The format: UTF-8 text, comma-separated, one header row, then one row per sample. A header cell is
``name [unit]`` (``time [s]``, ``torque:part 3 [N·m]``, ``speed:generator [rad/s]``); a cell
without ``[unit]`` needs its unit stated by the reader (``units=``). The time column is ``time``
unless told. Reading converts to SI:

=========  ===========================  =========
quantity   accepted units               SI
=========  ===========================  =========
time       s, ms                        s
angle      rad, deg, °                  rad
speed      rad/s, rpm                   rad/s
torque     N·m (N*m, Nm, N⋅m), kN·m     N·m
           (kN*m, kNm, kN⋅m)
=========  ===========================  =========

Files are untrusted: anything that is not such a table - ragged rows, a cell that is no number,
NaN or infinity, duplicate or empty headers, times that do not increase uniformly, an unknown unit,
bytes that are not UTF-8, a file above :data:`MAX_BYTES` - is one :class:`~flexshaft.errors.ModelError`
naming the file, the row or column, and what is valid. Nothing is allocated from what a file claims:
the rows are what is there. Writing (:func:`write_signals`) is atomic and exact: values carry 17
significant digits, so a file read back gives the same floats.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import atomic_write_text
from ..errors import ModelError
from ..signals.checks import uniform_rate
from ..threads import follows_policy
from ..validation import check_name

__all__ = ["MAX_BYTES", "UNITS", "SignalTable", "read_signals", "write_signals"]

#: The largest file read, bytes (2 GiB: some 50 million samples of a few channels).
MAX_BYTES = 2 << 30

#: Every unit spelling read: spelling -> (SI unit, factor to SI).
UNITS: dict[str, tuple[str, float]] = {
    "s": ("s", 1.0),
    "ms": ("s", 1e-3),
    "rad": ("rad", 1.0),
    "deg": ("rad", math.pi / 180.0),
    "°": ("rad", math.pi / 180.0),
    "rad/s": ("rad/s", 1.0),
    "rpm": ("rad/s", math.pi / 30.0),
    "N·m": ("N·m", 1.0),
    "N⋅m": ("N·m", 1.0),
    "N*m": ("N·m", 1.0),
    "Nm": ("N·m", 1.0),
    "kN·m": ("N·m", 1e3),
    "kN⋅m": ("N·m", 1e3),
    "kN*m": ("N·m", 1e3),
    "kNm": ("N·m", 1e3),
}
_VALID_UNITS = ", ".join(UNITS)
# A header cell: a name, then optionally a unit in square brackets at the end.
_HEADER = re.compile(r"^(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?$")
# What a number cell may be (ASCII digits only; float() alone would take '1_000' or Arabic digits).
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:nan|inf|infinity)", re.I | re.A)


@dataclass(frozen=True)
class SignalTable:
    """Sampled signals on one uniform time base, in SI.

    Attributes
    ----------
    time : ndarray, shape (n,)
        Sample times, s (uniformly spaced, increasing).
    columns : dict of str to ndarray
        Each signal by its name (the header without its unit), in SI.
    units : dict of str to str
        Each signal's SI unit: ``s``, ``rad``, ``rad/s`` or ``N·m``.
    rate_hz : float
        The sampling rate, Hz.
    source : str
        The file read.
    """

    time: np.ndarray
    columns: dict
    units: dict
    rate_hz: float
    source: str


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


def _read_text(path: Path) -> str:
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_BYTES:
                raise _error(
                    path,
                    f"is {size:,} bytes",
                    field="size",
                    valid=f"a file of at most {MAX_BYTES:,} bytes (split the record)",
                )
            data = fh.read(MAX_BYTES + 1)  # a pipe or a growing file may hold more than it said
    except OSError as err:
        raise _error(
            path, f"cannot be read ({err.strerror or type(err).__name__})", valid="a readable CSV file"
        ) from None
    if len(data) > MAX_BYTES:
        raise _error(path, f"holds more than {MAX_BYTES:,} bytes", field="size", valid="a smaller file")
    nul = data.find(b"\0")
    if nul >= 0:
        raise _error(path, f"holds a NUL byte at offset {nul}: not a text file", valid="a UTF-8 CSV file")
    try:
        return data.decode("utf-8-sig")  # a byte-order mark, as spreadsheets write it, is dropped
    except UnicodeDecodeError as err:
        raise _error(path, f"is not UTF-8 text (byte {err.start})", valid="a UTF-8 CSV file") from None


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


@follows_policy
def read_signals(path, columns=None, units=None, *, time_column: str = "time") -> SignalTable:
    """Read a signal file (see the module docstring for the format).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    columns : sequence of str, optional
        The signals to read, each by its full header (``"torque [N·m]"``) or its name
        (``"torque"``). Default: every column but the time.
    units : dict of str to str, optional
        Units for header cells that have none, by name or full header: ``{"torque": "kNm"}``. A
        unit given for a column whose header states another one is an error.
    time_column : str
        The time column, by name or full header (default ``"time"``); its unit must be s or ms
        (seconds when the header has none and ``units`` does not say).

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
    text = _read_text(p)
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise _error(p, "is empty", valid="a header row 'time [s],name [unit],...' and rows of numbers")
    header = _parse_header(p, lines[0])
    names = [h[0] for h in header]
    # (line number, text) of the data rows; blank lines carry nothing and are passed over
    rows = [(i + 2, line) for i, line in enumerate(lines[1:]) if line.strip()]
    if len(rows) < 2:
        raise _error(
            p,
            f"has {len(rows)} data rows",
            valid="at least 2 rows of numbers under the header (the rate needs two)",
        )
    data = None
    try:
        # numpy's C parser: fast for a long record; anything it refuses is read again cell by cell below
        data = np.loadtxt([r[1] for r in rows], delimiter=",", comments=None, dtype=float, ndmin=2)
    except ValueError:
        pass
    if data is None or data.shape != (len(rows), len(names)):
        data = _parse_rows_slowly(p, rows, names)
    bad = ~np.isfinite(data)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise _error(
            p,
            f"line {rows[r][0]}: {data[r, c]!r} ({int(bad.sum())} non-finite cells in all)",
            field=names[c],
            valid="finite numbers",
        )

    stated = {}
    for key, unit in (units or {}).items():
        if not isinstance(key, str) or not isinstance(unit, str):
            raise ModelError(
                "must map column names to unit strings",
                field="units",
                value=units,
                valid="a dict such as {'torque': 'kNm'}",
            )
        stated[_resolve(p, key, header, "units")] = unit.strip()
    ti = _resolve(p, time_column, header, "time_column")
    if columns is None:
        picked = [i for i in range(len(header)) if i != ti]
    else:
        if isinstance(columns, str):
            columns = [columns]
        picked = [_resolve(p, c, header, "columns") for c in columns]
    if not picked:
        raise _error(p, "holds only the time column", field="columns", valid="at least one signal column")

    def si(i: int) -> tuple[str, float]:
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
                f"(command line: --unit {name}=UNIT); units: {_VALID_UNITS}",
            )
        if unit not in UNITS:
            raise _error(p, "unknown unit", field=name, value=unit, valid=f"one of {_VALID_UNITS}")
        return UNITS[unit]

    t_unit, t_factor = si(ti)
    if t_unit != "s":
        raise _error(p, "is not a time", field=header[ti][0], value=header[ti][1], valid="a unit s or ms")
    time = data[:, ti] * t_factor
    rate = _check_time(time, header[ti][0], p)
    out, out_units = {}, {}
    for i in picked:
        unit, factor = si(i)
        out[names[i]] = data[:, i] * factor if factor != 1.0 else data[:, i].copy()
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
        The file written: a header ``time [s],NAME [unit],...`` and the values with 17 significant
        digits (``%.17g``: read back, the same floats).
    """
    t = _column(time, "time", None)
    _check_time(t, "time")
    if not isinstance(columns, dict) or not columns:
        raise ModelError("is not a non-empty dict", field="columns", valid="{name: (values, unit)}")
    cells, arrays = ["time [s]"], [t]
    for key, entry in columns.items():
        name = check_name(key, "columns")
        if "[" in name or "]" in name or name == "time":
            raise ModelError(
                "is not a usable column name",
                field="columns",
                value=key,
                valid="a name without [ ], not 'time'",
            )
        try:
            values, unit = entry
        except (TypeError, ValueError):
            raise ModelError("is not a (values, unit) pair", field=name, valid="(array, unit)") from None
        if unit not in UNITS:
            raise ModelError("unknown unit", field=name, value=unit, valid=f"one of {_VALID_UNITS}")
        arrays.append(_column(values, name, t.size))
        cells.append(f"{name} [{unit}]")
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(cells)
    np.savetxt(buf, np.column_stack(arrays), fmt="%.17g", delimiter=",")
    return atomic_write_text(path, buf.getvalue(), overwrite=overwrite)
