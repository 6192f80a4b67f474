"""Where a channel's samples lie in its file, and their reading by plain file reads in the caller.

A format module that finds a channel stored plainly - numbers of a standard type at known offsets: an
HDF5 dataset contiguous or in unfiltered chunks, a TDMS channel's raw data, an MDF 4 channel group's
records - gives a :class:`Planned` instead of the samples: the extents of the file that hold them, the
records' layout, the type. The library parses the file's structure (in the child process, where its
crash or hang on a damaged file is one error); the caller then reads the bytes itself
(:func:`read_planned`), straight into its float64 arrays. No sample crosses between the processes,
which on a fork-and-pipe or a shared-memory transfer costs 3-10 times the library's own reading of a
record of a few hundred MB.

Trust: the plan comes from the library's reading of an untrusted file, so it is checked as any
header is: its type is one of :data:`DTYPES`, every extent lies within the file, the records hold the
samples claimed. And the library's own first and last samples travel with it: the samples read must
agree with them bit for bit (:func:`read_planned` raises :class:`Disagrees` otherwise, and the caller
reads that file through the library after all), so a layout the plan mistook cannot give other numbers
than the library's. Except for a TDMS channel whose first or last chunk is over 1 MB: npTDMS would
read the whole chunk for those samples (a 40 MB chunk twice), so there the layout is npTDMS's own
segment index, unprobed (:mod:`.tdms`).
"""

from __future__ import annotations

import bisect
import os
from dataclasses import dataclass

import numpy as np

from .base import error

__all__ = ["DTYPES", "PROBE", "Disagrees", "Planned", "Run", "read_planned"]

#: The types a plan may read, each in either byte order: what test benches store.
DTYPES = frozenset(
    np.dtype(c).newbyteorder(o).str
    for c in ("f4", "f8", "i1", "i2", "i4", "i8", "u1", "u2", "u4", "u8")
    for o in "<>"
)
#: Samples the library reads at each end of a planned channel, to check the plan against.
PROBE = 8
#: Bytes read at a time where records interleave channels (a window in the processor's cache).
_WINDOW = 1 << 22
#: Float64 values read at a time into a contiguous channel's array (1 MB: tested while in the cache).
_BLOCK = 1 << 17
_F8 = np.dtype(np.float64)


@dataclass(frozen=True)
class Run:
    """Records of ``record`` bytes, one after another in the ``extents`` of the file.

    Attributes
    ----------
    extents : tuple of (int, int)
        (offset, bytes) in the file, in the order the records follow each other (a record may
        continue from one extent into the next, as in MDF data lists).
    record : int
        Bytes per record: a value's item size where a channel's values are contiguous.
    """

    extents: tuple
    record: int


@dataclass(frozen=True, eq=False)
class Planned:
    """One channel's samples: where they lie, their type, and the library's own at either end.

    Attributes
    ----------
    pieces : tuple of (Run, int, int)
        (run, the value's byte offset within a record, count): the samples in order, ``count`` from
        the first records of each run.
    dtype : str
        Their numpy type with its byte order (``'<f8'``, ``'>i2'``), one of :data:`DTYPES`.
    head, tail : ndarray
        The library's first and last (up to :data:`PROBE`) samples, as float64.
    scale : tuple of (float, float), optional
        (a, b): the sample is ``x * a + b`` (an MDF linear conversion of integers), in float64.
    """

    pieces: tuple
    dtype: str
    head: np.ndarray
    tail: np.ndarray
    scale: tuple | None = None

    @property
    def n(self) -> int:
        """The samples, in all."""
        return sum(count for _, _, count in self.pieces)


class Disagrees(Exception):
    """The samples a plan read differ from the library's own: read the file through the library."""


def _read_into(fh, offset: int, dst: memoryview, path) -> None:
    """``len(dst)`` bytes of the file at ``offset`` into ``dst``; the file ending sooner is an error.

    By the descriptor, at the offset given: never through ``fh``'s buffer, whose idea of the file's
    offset a forked reading (sharing the open file) may have made stale."""
    fd, done = fh.fileno(), 0
    while done < len(dst):
        if hasattr(os, "preadv"):  # Linux, BSD
            got = os.preadv(fd, [dst[done:]], offset + done)
        elif hasattr(os, "readv"):  # macOS
            os.lseek(fd, offset + done, os.SEEK_SET)
            got = os.readv(fd, [dst[done:]])
        else:  # Windows: no fork, so no other reader; the file object is this process's alone
            fh.seek(offset + done)
            got = fh.readinto(dst[done:])
        if not got:
            raise error(
                path,
                f"is truncated: {len(dst) - done:,} bytes at byte {offset + done:,} are beyond its end",
                valid="a complete file",
            )
        done += got


class _Stream:
    """A run's extents as one stream of bytes: ``read(start, dst)`` fills ``dst`` from byte ``start``."""

    def __init__(self, fh, run: Run, path):
        self.fh, self.path, self.extents = fh, path, run.extents
        self.starts, at = [], 0
        for _, nbytes in run.extents:
            self.starts.append(at)
            at += nbytes
        self.size = at

    def read(self, start: int, dst: memoryview) -> None:
        i = bisect.bisect_right(self.starts, start) - 1
        done = 0
        while done < len(dst):
            offset, nbytes = self.extents[i]
            skip = start + done - self.starts[i]
            take = min(nbytes - skip, len(dst) - done)
            _read_into(self.fh, offset + skip, dst[done : done + take], self.path)
            done += take
            i += 1


def _check(path, label: str, plan: Planned, size: int) -> np.dtype:
    """The plan within the file and its type one that is read: else one error (a damaged file)."""
    if plan.dtype not in DTYPES:
        raise error(path, f"has samples of type {plan.dtype!r}", field=label, valid="numbers")
    dtype = np.dtype(plan.dtype)
    for run, field, count in plan.pieces:
        held = 0
        for offset, nbytes in run.extents:
            if offset < 0 or nbytes < 0 or offset + nbytes > size:
                raise error(
                    path,
                    f"is damaged: {nbytes:,} bytes of it at byte {offset:,}, beyond the file's {size:,}",
                    field=label,
                    valid="an undamaged, complete file",
                )
            held += nbytes
        if count < 0 or not 0 <= field <= run.record - dtype.itemsize or count * run.record > held:
            raise error(
                path,
                f"is damaged: {count:,} records of {run.record} bytes where the file holds {held:,}",
                field=label,
                valid="an undamaged, complete file",
            )
    return dtype


def read_planned(fh, size: int, path, plans: dict) -> tuple[dict, set]:
    """Read planned channels from the open file ``fh`` (``size`` bytes): their samples as float64.

    Parameters
    ----------
    plans : dict of object to (str, Planned)
        Each channel's key -> (its label for messages, its plan).

    Returns
    -------
    arrays : dict of object to ndarray
        Each key's samples, float64 (converted as the library converts them).
    finite : set
        The keys whose every sample is finite (tested a block at a time as it is read, while in the
        processor's cache): the caller need not test them again.

    Raises
    ------
    ModelError
        A plan reaching beyond the file (a damaged file, or one cut meanwhile).
    Disagrees
        The samples read differ from the library's own at either end.

    Channels whose values interleave in one run's records (an MDF channel group, a TDMS segment of
    interleaved data) are read in one pass over the records, a window at a time; a channel of
    contiguous float64 values is read straight into its array.
    """
    out, jobs = {}, {}
    finite = set(plans)
    for key, (label, plan) in plans.items():
        dtype = _check(path, label, plan, size)
        out[key] = np.empty(plan.n, dtype=_F8)
        at = 0
        for run, field, count in plan.pieces:
            jobs.setdefault(run, []).append((key, at, field, count, dtype, plan.scale))
            at += count

    def settle(key, x: np.ndarray, scale) -> None:
        """A block just read: converted, and tested finite while it is in the cache."""
        if scale is not None:
            a, b = scale
            with np.errstate(over="ignore", invalid="ignore"):  # an overflow is a non-finite sample
                x *= a  # as asammdf converts: x * a, then + b where b is not 0
                if b:
                    x += b
        if key in finite and not np.isfinite(x).all():
            finite.discard(key)

    for run, users in jobs.items():
        stream = _Stream(fh, run, path)
        rest = []
        for key, at, field, count, dtype, scale in users:
            if dtype == _F8 and run.record == _F8.itemsize and scale is None:
                # contiguous float64: the bytes are the array's, read straight into it
                dst = out[key][at : at + count]
                for first in range(0, count, _BLOCK):
                    block = dst[first : first + _BLOCK]
                    stream.read(first * 8, memoryview(block).cast("B"))
                    settle(key, block, None)
            else:
                rest.append((key, at, field, count, dtype, scale))
        if not rest:
            continue
        records = max(u[3] for u in rest)
        per = max(1, _WINDOW // run.record)
        window = np.empty(min(per, records) * run.record, dtype=np.uint8)
        for first in range(0, records, per):
            m = min(per, records - first)
            stream.read(first * run.record, memoryview(window[: m * run.record]))
            for key, at, field, count, dtype, scale in rest:
                k = min(m, count - first)
                if k > 0:
                    block = out[key][at + first : at + first + k]
                    block[:] = np.ndarray(
                        (k,), dtype=dtype, buffer=window, offset=field, strides=(run.record,)
                    )
                    settle(key, block, scale)
    for key, (_, plan) in plans.items():
        x = out[key]
        k = min(len(plan.head), x.size)
        if not (
            np.array_equal(x[:k], plan.head, equal_nan=True)
            and np.array_equal(x[x.size - len(plan.tail) :], plan.tail, equal_nan=True)
        ):
            raise Disagrees(key)
    return out, finite
