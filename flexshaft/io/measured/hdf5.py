"""HDF5 files (``.h5``, ``.hdf5``) and MATLAB v7.3 files (HDF5 after a 512-byte header) through h5py.

- Channels: 1-D numeric datasets, named by their path (``bench/run1/torque``) or, where no other
  dataset has it, by their last name; ``group`` names the parent group (``bench/run1``). Only the
  file's own hard-linked datasets are channels: no external or soft link is followed, and datasets
  whose data live in other files (external storage, virtual datasets) or hold references are
  refused.
- Units: the attribute ``units`` or ``unit`` of the dataset (text).
- Time: a dataset ``time_column`` (default: one named ``time`` in the same group), else the
  attribute ``rate_hz`` or ``sampling_rate`` (Hz) or ``wf_increment`` (s) with ``wf_start_offset``
  (s), on the dataset or its group, else the ``rate`` given.
- Claims: a dataset's shape times its item size is checked before it is read: against the file's
  size when stored unfiltered (and its stored bytes must be all of it), against the ceiling when
  compressed.

A MATLAB v7.3 file is read the same way with MATLAB's conventions: its variables are the root's
datasets (``MATLAB_class`` double, single or an integer class; a 1xN or Nx1 vector), never the
``#refs#`` group's cell contents; it states no units (``units=`` states them).
"""

from __future__ import annotations

import contextlib
import math

import numpy as np

from .common import Entry, Raw, Uniform, check_claim, error

__all__ = ["LIBRARY", "SIGNATURE", "WHAT", "superblock_offset", "source"]

WHAT = "HDF5 file"
LIBRARY = ("h5py", "h5py")
SIGNATURE = b"\x89HDF\r\n\x1a\n"
_MAX_ATTRIBUTE = 1 << 16  # bytes: a unit or a rate is a few; a larger attribute is not read
_MAX_DATASETS = 100_000  # a channel list longer than this is no bench record
_MATLAB_NUMERIC = frozenset(
    ("double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64")
)


def superblock_offset(fh, size: int) -> int | None:
    """Where the HDF5 signature is: at 0, 512, 1024, 2048... (after a user block), or None."""
    offset = 0
    while offset + len(SIGNATURE) <= size:
        fh.seek(offset)
        if fh.read(len(SIGNATURE)) == SIGNATURE:
            return offset
        offset = 512 if offset == 0 else 2 * offset
    return None


class _Source:
    def __init__(self, h5, lib, path, size: int, matlab: bool):
        self.h5, self.lib, self.path, self.size, self.matlab = h5, lib, path, size, matlab
        self.listed: list[Entry] | None = None

    def entries(self) -> list[Entry]:
        if self.listed is None:
            found = []

            def visit(name, obj):
                # visititems walks hard links only: soft and external links are never followed
                if isinstance(obj, self.lib.Dataset):
                    found.append(self._entry(name, obj))
                    if len(found) > _MAX_DATASETS:
                        raise error(
                            self.path,
                            f"holds more than {_MAX_DATASETS} datasets",
                            valid=f"a record of at most {_MAX_DATASETS} datasets",
                        )
                return None

            self.h5.visititems(visit)
            self.listed = found
        return self.listed

    def _entry(self, name: str, d) -> Entry:
        group, _, last = name.rpartition("/")
        kind = d.dtype.kind
        numeric = kind in "iuf" and (_vector(d.shape) if self.matlab else len(d.shape) == 1)
        if self.matlab:
            numeric = numeric and not group and self._text(d, "MATLAB_class") in _MATLAB_NUMERIC
        return Entry(group, last, name, numeric=numeric, time=last.lower() == "time")

    def _attribute(self, obj, key: str, label: str):
        if key not in obj.attrs:
            return None
        if obj.attrs.get_id(key).get_storage_size() > _MAX_ATTRIBUTE:
            raise error(self.path, f"has an attribute {key!r} of over 64 kB", field=label)
        value = obj.attrs[key]
        if isinstance(value, np.ndarray):
            if value.size != 1:
                raise error(self.path, f"has an attribute {key!r} of {value.size} values", field=label)
            value = value.reshape(-1)[0]
        return value

    def _text(self, obj, key: str, label: str = "") -> str | None:
        value = self._attribute(obj, key, label)
        if isinstance(value, bytes | np.bytes_):
            try:
                value = bytes(value).decode("utf-8")
            except UnicodeDecodeError:
                raise error(self.path, f"has an attribute {key!r} that is not UTF-8", field=label) from None
        if value is not None and not isinstance(value, str):
            raise error(self.path, f"has an attribute {key!r} that is not text", field=label, value=value)
        return value

    def _number(self, obj, key: str, label: str) -> float | None:
        value = self._attribute(obj, key, label)
        if value is None:
            return None
        try:
            x = float(value)
        except (TypeError, ValueError):
            x = math.nan
        if not math.isfinite(x):
            raise error(
                self.path, f"has the attribute {key} = {value!r}", field=label, valid="a finite number"
            )
        return x

    def _timing(self, d, label: str) -> Uniform | None:
        for obj in (d, d.parent):
            start = self._number(obj, "wf_start_offset", label) or 0.0
            for key, step_of in (
                ("rate_hz", lambda r: 1 / r),
                ("sampling_rate", lambda r: 1 / r),
                ("wf_increment", float),
            ):
                value = self._number(obj, key, label)
                if value is not None:
                    if not value > 0:
                        raise error(
                            self.path, f"has the attribute {key} = {value!r}", field=label, valid="> 0"
                        )
                    return Uniform(start, step_of(value))
        return None

    def read(self, entry: Entry) -> Raw:
        d = self.h5[entry.handle]
        label = entry.label
        if d.is_virtual or d.external:
            raise error(
                self.path,
                "keeps its data in other files (a virtual or external dataset)",
                field=label,
                valid="a dataset stored in the file itself",
            )
        if d.dtype.kind not in "iuf" or not (_vector(d.shape) if self.matlab else len(d.shape) == 1):
            what = f"{d.dtype} values" if d.dtype.kind not in "iuf" else f"shape {d.shape}"
            raise error(self.path, f"holds {what}", field=label, valid="a 1-D dataset of numbers")
        if self.matlab:
            cls = self._text(d, "MATLAB_class", label)
            if cls not in _MATLAB_NUMERIC or "MATLAB_sparse" in d.attrs or "MATLAB_empty" in d.attrs:
                raise error(
                    self.path,
                    f"is a MATLAB {cls or 'unknown'} variable",
                    field=label,
                    valid="a vector of double, single or an integer class",
                )
        n = int(np.prod(d.shape, dtype=np.int64))
        filtered = d.id.get_create_plist().get_nfilters() > 0
        check_claim(self.path, label, n, d.dtype.itemsize, None if filtered else self.size)
        if not filtered and d.id.get_storage_size() < n * d.dtype.itemsize:
            raise error(
                self.path,
                f"stores {d.id.get_storage_size():,} bytes of the {n * d.dtype.itemsize:,} its shape claims",
                field=label,
                valid="a dataset written in full",
            )
        values = d[()].reshape(-1)
        if self.matlab:
            return Raw(values, None, None)  # MATLAB states no units and no rate
        unit = self._text(d, "units", label) or self._text(d, "unit", label)
        return Raw(values, unit, self._timing(d, label))


def _vector(shape) -> bool:
    return len(shape) == 2 and min(shape) == 1


@contextlib.contextmanager
def source(fh, path, size: int, lib, *, matlab: bool = False):
    """The open HDF5 (or MATLAB v7.3) file ``fh`` as a source of channels."""
    with lib.File(fh, "r") as h5:
        yield _Source(h5, lib, path, size, matlab)
