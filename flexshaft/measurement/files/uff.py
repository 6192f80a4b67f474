"""Universal files (UFF/UNV: Simcenter Testlab, ME'scope, pyuff) through pyuff: each dataset 58 of
function type 1 (a time response) is a channel.

- Channels: named by the record's first ID line (``id1``), else ``NODE:DIRECTION`` (its response node
  and direction); records of other function types (FRFs, spectra) and other datasets are not
  channels. Group: ``""``.
- Frequency responses (function type 4) are read apart, by :func:`frf_records`: named the same way
  (``RESPONSE/REFERENCE`` nodes and directions without an ID line), their abscissa in Hz, their
  ordinate complex, the units of response and reference from the two axis labels.
- Units: the ordinate's axis label (``ordinate_axis_units_lab``); an empty one states nothing.
- Time: ``abscissa_min + k·abscissa_inc`` (s) for an evenly spaced record; an uneven abscissa is
  refused (a test lab writes time records evenly).
- Damage: the points a record claims (``num_pts``) must fit in the bytes the file holds; a record
  pyuff cannot parse, or whose values are not the real ones its header claims, refuses the file.
  pyuff parses each dataset whole, so what it allocates is bounded by the dataset's own bytes (its
  text or its binary block), not by a claim.
- Reading: pyuff opens files by name, so the open file's bytes (within the signal file's ceiling)
  are copied to a private temporary file in the reading child first; pyuff parses the datasets.
"""

from __future__ import annotations

import contextlib
import tempfile
from pathlib import Path

import numpy as np

from .base import Entry, Raw, check_claim, error, uniform_timing

__all__ = [
    "LIBRARY",
    "MAGIC",
    "WHAT",
    "source",
    "is_uff",
    "frf_records",
    "TIME_FUNCTION",
    "FRF_FUNCTION",
    "FREQUENCY_DATA_TYPE",
]

WHAT = "universal file"
LIBRARY = ("pyuff", "pyuff")
#: A universal file's first line: a dataset delimiter, ``-1`` right-aligned in six columns.
MAGIC = b"    -1"
#: Dataset 58's function types: a time response, a frequency response function.
TIME_FUNCTION, FRF_FUNCTION = 1, 4
#: Dataset 58's abscissa data type of a frequency (its label should say Hz).
FREQUENCY_DATA_TYPE = 18


def is_uff(head: bytes) -> bool:
    """Whether a file's first bytes start a universal file (blank lines before the delimiter allowed)."""
    return head.lstrip(b"\r\n").startswith(MAGIC)


class _Source:
    def __init__(self, records: list, path, size: int):
        self.records, self.path, self.size = records, path, size

    def entries(self) -> list[Entry]:
        out = []
        for k, rec in enumerate(self.records):
            out.append(Entry("", _name(rec), k, numeric=True, time=False))
        return out

    def claim(self, entry: Entry) -> int:
        rec = self.records[entry.handle]
        n = int(rec.get("num_pts", 0))
        # a value takes 4 bytes at the least (binary single precision; text takes more)
        check_claim(self.path, entry.label, n, 4, self.size)
        return n

    def read(self, entry: Entry, plan: bool = False) -> Raw:
        rec = self.records[entry.handle]
        n = self.claim(entry)
        values = np.asarray(rec.get("data"))
        if values.ndim != 1 or values.size != n or np.iscomplexobj(values):
            raise error(
                self.path,
                f"holds a time record of {values.size} values where its header says {n} real ones",
                field=entry.label,
                valid="an undamaged dataset 58",
            )
        if int(rec.get("abscissa_spacing", 0)) != 1:
            raise error(
                self.path,
                "has an uneven abscissa",
                field=entry.label,
                valid="a time record evenly sampled (abscissa spacing 1)",
            )
        timing = uniform_timing(
            self.path,
            entry.label,
            "abscissa_inc",
            rec.get("abscissa_inc"),
            rate=False,
            start=rec.get("abscissa_min", 0.0),
            what="field",
        )
        unit = str(rec.get("ordinate_axis_units_lab", "")).strip() or None
        return Raw(values.astype(np.float64), unit, timing)


def _records(fh, size: int, lib, function: int) -> list[dict]:
    """The dataset 58 records of one function type in the open universal file ``fh`` (pyuff opens
    files by name: its bytes go to a private temporary copy first)."""
    with tempfile.TemporaryDirectory(prefix="flexshaft-uff-read-") as tmp:
        copy = Path(tmp) / "in.uff"
        copy.write_bytes(fh.read(size))
        uff = lib.UFF(str(copy))
        kinds = list(uff.get_set_types())
        records = (uff.read_sets(k) for k, kind in enumerate(kinds) if int(kind) == 58)
        return [rec for rec in records if int(rec.get("func_type", 0)) == function]


def _name(rec: dict) -> str:
    """A record's name: its first ID line, else its response node and direction (``NODE:DIRECTION``),
    an FRF's followed by its reference's (``/NODE:DIRECTION``)."""
    name = str(rec.get("id1", "")).strip()
    if name and name.upper() != "NONE":
        return name
    name = f"{rec.get('rsp_node', 0)}:{rec.get('rsp_dir', 0)}"
    if int(rec.get("func_type", 0)) == FRF_FUNCTION:
        name += f"/{rec.get('ref_node', 0)}:{rec.get('ref_dir', 0)}"
    return name


@contextlib.contextmanager
def source(fh, path, size: int, lib):
    """The open universal file ``fh`` as a source of channels: its time records (function type 1)."""
    yield _Source(_records(fh, size, lib, TIME_FUNCTION), path, size)


def frf_records(fh, path, size: int, lib) -> list[dict]:
    """The frequency responses (dataset 58, function type 4) of the open universal file ``fh``.

    Returns
    -------
    list of dict
        Per record: ``name``, ``frequencies_hz`` (ndarray), ``H`` (complex ndarray), ``response_unit``
        and ``reference_unit`` (the axis labels as written, ``""`` where none). Each record's claimed
        points are checked against the file's bytes before pyuff's values are taken, its values
        against its header; an abscissa other than Hz or not ascending refuses the file.
    """
    return [_frf(rec, path, size) for rec in _records(fh, size, lib, FRF_FUNCTION)]


def _frf(rec: dict, path, size: int) -> dict:
    """One FRF record checked: its claim against the file's bytes, its values against its header, its
    abscissa a frequency in Hz ascending from 0 or more."""
    name = _name(rec)
    n = int(rec.get("num_pts", 0))
    check_claim(path, name, n, 8, size)  # a complex value takes 8 bytes at the least (2 singles)
    H = np.asarray(rec.get("data"))
    if H.ndim != 1 or H.size != n:
        raise error(
            path,
            f"holds a frequency response of {H.size} values where its header says {n}",
            field=name,
            valid="an undamaged dataset 58",
        )
    unit = str(rec.get("abscissa_axis_units_lab", "")).strip()
    kind = int(rec.get("abscissa_spec_data_type", FREQUENCY_DATA_TYPE))
    if kind != FREQUENCY_DATA_TYPE or unit not in ("", "Hz"):
        raise error(
            path,
            "has an abscissa that is no frequency in Hz",
            field=name,
            value=unit or None,
            valid="a frequency response over frequency, Hz",
        )
    if int(rec.get("abscissa_spacing", 0)) == 1:
        f = float(rec.get("abscissa_min", 0.0)) + float(rec.get("abscissa_inc", 0.0)) * np.arange(n)
    else:
        f = np.asarray(rec.get("x"), dtype=float)
    if f.shape != (n,) or not np.all(np.isfinite(f)) or np.any(np.diff(f) <= 0) or (n and f[0] < 0):
        raise error(
            path,
            "has frequencies that are not ascending from 0 Hz or more",
            field=name,
            valid="an undamaged dataset 58",
        )
    if not np.all(np.isfinite(H)):
        raise error(path, "has a value that is no number", field=name, valid="finite values")
    return {
        "name": name,
        "frequencies_hz": f,
        "H": H.astype(np.complex128),
        "response_unit": str(rec.get("ordinate_axis_units_lab", "")).strip(),
        "reference_unit": str(rec.get("orddenom_axis_units_lab", "")).strip(),
    }
