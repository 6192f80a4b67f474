"""HDF5 files (``.h5``, ``.hdf5``) and MATLAB v7.3 files (HDF5 after a 512-byte header) through h5py.

- Channels: 1-D numeric datasets, named by their path (``bench/run1/torque``) or, where no other
  dataset has it, by their last name; ``group`` names the parent group (``bench/run1``). Only the
  file's own hard-linked datasets are channels: no external or soft link is followed, and datasets
  whose data live in other files (external storage, virtual datasets) or hold references are
  refused.
- Units: the attribute ``units`` or ``unit`` of the dataset (text).
- Time: a dataset ``time_column`` (default: one named ``time`` in the same group), else the
  attribute ``rate_hz`` or ``sampling_rate`` (Hz) or ``wf_increment`` (s) with ``wf_start_offset``
  (s), on the dataset or its group, else the ``rate`` given. Each must be a number (a boolean or
  text is none), its rate within :data:`~.common.RATE_RANGE_HZ`.
- Claims: a dataset's shape is checked against the storage the file has ALLOCATED for it, before
  anything is read (a header's shape costs nothing: a 109 kB file claimed 60 M samples in chunks
  never written, and reading it would have filled 4 GB with the fill value). Contiguous: its
  allocated bytes must hold the shape's. Chunked: every chunk the shape needs must be stored
  (``get_num_chunks``), and their stored bytes hold the shape's - unfiltered 1:1, deflate at most
  1032:1 (the format's bound); other filters state no bound, and the signal file's ceiling alone
  bounds them. The refusal names the dataset, its claim and what is stored.
- Reading: a dataset stored plainly (contiguous, or unfiltered chunks; a standard integer or IEEE
  float type) is planned (:mod:`.plan`): h5py finds where its samples lie, the caller reads them.

A MATLAB v7.3 file is read the same way with MATLAB's conventions: its variables are the root's
datasets (``MATLAB_class`` double, single or an integer class; a 1xN or Nx1 vector), never the
``#refs#`` group's cell contents; it states no units (``units=`` states them).
"""

from __future__ import annotations

import contextlib

import numpy as np

from .base import Entry, Raw, check_claim, error, uniform_timing
from .layout import DTYPES, PROBE, Planned, Run

__all__ = ["LIBRARY", "SIGNATURE", "WHAT", "superblock_offset", "source"]

WHAT = "HDF5 file"
LIBRARY = ("h5py", "h5py")
SIGNATURE = b"\x89HDF\r\n\x1a\n"
_MAX_ATTRIBUTE = 1 << 16  # bytes: a unit or a rate is a few; a larger attribute is not read
_MAX_DATASETS = 100_000  # a channel list longer than this is no bench record
_DEFLATE_RATIO = 1032  # the most a deflate stream inflates, bytes per byte (see _Storage)
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
        self.claimed: dict[Entry, tuple] = {}  # entry -> (dataset, its shape, samples, storage), checked

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
        shape = d.shape
        numeric = kind in "iuf" and (_vector(shape) if self.matlab else len(shape) == 1)
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

    def _timing(self, d, label: str):
        """The dataset's :class:`~.common.Uniform` timing from its attributes or its group's, or None."""
        for obj in (d, d.parent):
            where = label if obj is d else (obj.name.strip("/") or "/")  # the group's path: the attribute's
            for key in ("rate_hz", "sampling_rate", "wf_increment"):
                value = self._attribute(obj, key, label)
                if value is not None:
                    start = self._attribute(obj, "wf_start_offset", label)
                    return uniform_timing(
                        self.path,
                        where,
                        key,
                        value,
                        rate=key != "wf_increment",
                        start=0.0 if start is None else start,
                    )
        return None

    def _dataset(self, entry: Entry):
        """The dataset of ``entry``, checked to be a vector of numbers stored in this file."""
        d = self.h5[entry.handle]
        label = entry.label
        if d.is_virtual or d.external:
            raise error(
                self.path,
                "keeps its data in other files (a virtual or external dataset)",
                field=label,
                valid="a dataset stored in the file itself",
            )
        dtype, shape = d.dtype, d.shape
        if dtype.kind not in "iuf" or not (_vector(shape) if self.matlab else len(shape) == 1):
            what = f"{dtype} values" if dtype.kind not in "iuf" else f"shape {shape}"
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
        return d

    def claim(self, entry: Entry) -> int:
        """The samples the dataset's shape claims, checked against the storage the file has ALLOCATED
        for it (module docstring), before anything is read."""
        return self._claimed(entry)[2]

    def _claimed(self, entry: Entry) -> tuple:
        if entry in self.claimed:  # each dataset checked once: the channel list, then its reading
            return self.claimed[entry]
        d = self._dataset(entry)
        shape = d.shape
        n = int(np.prod(shape, dtype=np.int64))
        check_claim(self.path, entry.label, n, d.dtype.itemsize, None)  # the ceiling
        stored = _Storage(d, shape, self.lib)
        claimed = n * d.dtype.itemsize
        complaint = stored.shortfall(claimed)
        if complaint is not None:
            raise error(
                self.path,
                f"is damaged: its shape claims {n:,} samples ({claimed:,} bytes), the file stores "
                f"{stored.nbytes:,} bytes of them" + (f" ({complaint})" if complaint else ""),
                field=entry.label,
                valid="a dataset written in full",
            )
        if not stored.filters:  # allocated, but within the file? (a truncated file)
            check_claim(self.path, entry.label, n, d.dtype.itemsize, self.size)
        self.claimed[entry] = d, shape, n, stored
        return self.claimed[entry]

    def read(self, entry: Entry, plan: bool = False) -> Raw:
        d, shape, n, stored = self._claimed(entry)
        values = (_plan(d, shape, n, stored, self.lib) if plan else None) or d[()].reshape(-1)
        if self.matlab:
            return Raw(values, None, None)  # MATLAB states no units and no rate
        label = entry.label
        unit = self._text(d, "units", label) or self._text(d, "unit", label)
        return Raw(values, unit, self._timing(d, label))


class _Storage:
    """What the file stores of a dataset: its layout, the bytes allocated, its chunks and filters."""

    def __init__(self, d, shape, lib):
        h5d, h5z = lib.h5d, lib.h5z
        dcpl = d.id.get_create_plist()
        self.layout = dcpl.get_layout()
        self.filters = [dcpl.get_filter(i)[0] for i in range(dcpl.get_nfilters())]
        self.nbytes = d.id.get_storage_size()  # allocated; compressed chunks at their stored size
        self.chunks_needed = self.chunks_stored = 0
        if self.layout == h5d.CHUNKED:
            per = [-(-s // c) for s, c in zip(shape, d.chunks)]
            self.chunks_needed = int(np.prod(per, dtype=np.int64))
            self.chunks_stored = d.id.get_num_chunks()
        # deflate's format bounds what a byte inflates to (a 258-byte match in 2 bits: 1032:1); shuffle
        # and fletcher32 only reorder or add a checksum. Other filters (szip, LZF, scale-offset,
        # n-bit, plugins) state no bound (scale-offset stores a constant chunk in a few bytes): for
        # them the signal file's ceiling alone bounds a claim, beside every chunk stored.
        known = {h5z.FILTER_DEFLATE, h5z.FILTER_SHUFFLE, h5z.FILTER_FLETCHER32}
        self.ratio = 1 if not self.filters else _DEFLATE_RATIO if set(self.filters) <= known else None

    def shortfall(self, claimed: int) -> str | None:
        """Why the storage cannot hold ``claimed`` bytes of samples (``""``: it is smaller), or None
        where it can."""
        if self.chunks_stored < self.chunks_needed:
            return (
                f"{self.chunks_stored:,} of its {self.chunks_needed:,} chunks; the rest would read as "
                "its fill value, never written"
            )
        if self.ratio is not None and claimed > self.nbytes * self.ratio:
            return "" if self.ratio == 1 else f"deflated, which inflates at most {self.ratio}:1"
        return None


def _standard(d, lib) -> str | None:
    """The dataset's numpy type (``'<f8'``) where its HDF5 type is that standard one, else None (an
    HDF5 float of another layout, which h5py converts)."""
    dtype = d.dtype.str
    if dtype not in DTYPES:
        return None
    kind, size, order = dtype[1], int(dtype[2:]), "LE" if dtype[0] == "<" else "BE"
    name = f"IEEE_F{8 * size}{order}" if kind == "f" else f"STD_{kind.upper()}{8 * size}{order}"
    std = getattr(lib.h5t, name, None)
    return dtype if std is not None and d.id.get_type().equal(std) else None


def _plan(d, shape: tuple, n: int, storage: _Storage, lib) -> Planned | None:
    """Where an unfiltered dataset's samples lie (contiguous, or in chunks along its one long axis), or
    None: the library reads it."""
    if storage.filters or n == 0:
        return None
    dtype = _standard(d, lib)
    if dtype is None:
        return None
    itemsize = d.dtype.itemsize
    axis = int(np.argmax(shape)) if len(shape) > 1 else 0
    if storage.layout == lib.h5d.CONTIGUOUS:
        offset = d.id.get_offset()
        if offset is None:
            return None
        extents = ((int(offset), n * itemsize),)
    elif storage.layout == lib.h5d.CHUNKED:
        step = d.chunks[axis]
        if any(c != 1 for i, c in enumerate(d.chunks) if i != axis):
            return None  # a chunk spanning a short axis holds its rows interleaved
        found = {}

        def take(info):
            found[info.chunk_offset[axis]] = (int(info.byte_offset), int(info.size))

        if hasattr(d.id, "chunk_iter"):
            d.id.chunk_iter(take)
        else:
            for i in range(storage.chunks_stored):
                take(d.id.get_chunk_info(i))
        starts = range(0, n, step)
        if len(found) != len(starts) or any(found.get(s, (0, -1))[1] != step * itemsize for s in starts):
            return None
        extents = tuple(found[s] for s in starts)
    else:
        return None  # compact: a few kB in the object header, read by the library
    k = min(PROBE, n)
    ends = [slice(None)] * len(shape)
    ends[axis] = slice(0, k)
    head = d[tuple(ends)].reshape(-1).astype(np.float64)
    ends[axis] = slice(n - k, n)
    tail = d[tuple(ends)].reshape(-1).astype(np.float64)
    return Planned(((Run(extents, itemsize), 0, n),), dtype, head, tail)


def _vector(shape) -> bool:
    return len(shape) == 2 and min(shape) == 1


@contextlib.contextmanager
def source(fh, path, size: int, lib, *, matlab: bool = False):
    """The open HDF5 (or MATLAB v7.3) file ``fh`` as a source of channels."""
    with lib.File(fh, "r") as h5:
        yield _Source(h5, lib, path, size, matlab)
