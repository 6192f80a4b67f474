"""ASAM MDF files, version 3 and 4 (``.mf4``, ``.mdf``, ``.dat``: dSPACE, Vector CANape/CANoe, ETAS,
HBM, CAN loggers) through asammdf, lazily: its metadata at opening, then one channel at a time
(``MDF.get(group=, index=)``), its group's records read in pieces.

- Channels: ``GROUP/NAME`` where GROUP is the channel group's index as asammdf counts them (``0``,
  ``1``, ...) or its acquisition name; the name alone where only one group has it.
- Units: the channel's unit (its conversion's, else its own), after its conversion to physical
  values. A channel with invalid samples (MDF 4 invalidation bits) is refused.
- Time: each channel's own time stamps, its group's master channel (unit s unless it says ms; a
  master of angle or distance is refused). Groups sampled at different rates are brought to one
  time base as :mod:`.assemble` says.
- Damage and claims: a group's records must fit in its data blocks, and uncompressed blocks in the
  file, before a channel is read; compressed (DZ) data count against the signal file's ceiling.
- Reading: in an MDF 4 group of sorted, uncompressed records without invalidation bits, a channel of
  a whole-byte integer or float at a fixed place in each record (with at most a linear conversion of
  integers) and its time-master alike are planned (:mod:`.plan`): asammdf finds where its values lie,
  the caller reads the records once for every channel of the group. Others asammdf reads.
"""

from __future__ import annotations

import contextlib

import numpy as np

from .base import Entry, Raw, Stamps, check_claim, error
from .layout import PROBE, Planned, Run

__all__ = ["LIBRARY", "MAGICS", "WHAT", "source"]

WHAT = "MDF file"
LIBRARY = ("asammdf", "asammdf")
MAGICS = (b"MDF     ", b"UnFinMF ")  # a finalised file's identification; an MDF 4 file not finalised

# Data types whose raw values are numbers (asammdf's v4_constants / v2_v3_constants).
_NUMERIC_V4 = frozenset(range(6))  # unsigned, signed, real; Intel and Motorola
_NUMERIC_V3 = frozenset((0, 1, 2, 3, *range(9, 17)))
_SYNC = {2: "angle", 3: "distance", 4: "index"}  # MDF 4 master sync types that are not time
# MDF 4 data types of whole-byte numbers -> numpy type without the size: Intel little-endian, Motorola big
_DTYPES_V4 = {0: "<u", 1: ">u", 2: "<i", 3: ">i", 4: "<f", 5: ">f"}


class _Source:
    def __init__(self, mdf, path, size: int):
        self.mdf, self.path, self.size = mdf, path, size
        self.v4 = str(mdf.version).startswith("4")
        self.listed: dict[tuple, Entry] = {}

    def entries(self) -> list[Entry]:
        if not self.listed:
            self.listed = {e.handle: e for e in self._entries()}
        return list(self.listed.values())

    def _entries(self) -> list[Entry]:
        numeric = _NUMERIC_V4 if self.v4 else _NUMERIC_V3
        out = []
        for gi, g in enumerate(self.mdf.groups):
            master = self.mdf.masters_db.get(gi)
            acq = getattr(g.channel_group, "acq_name", "") or ""
            aliases = (acq,) if acq.strip() else ()
            for ci, ch in enumerate(g.channels):
                out.append(
                    Entry(
                        str(gi),
                        ch.name,
                        (gi, ci),
                        aliases=aliases,
                        numeric=ch.data_type in numeric,
                        time=ci == master,
                    )
                )
        return out

    def _check_group(self, gi: int, label: str) -> int:
        """The records group ``gi`` claims; refused where its data blocks cannot hold them."""
        g = self.mdf.groups[gi]
        cg = g.channel_group
        record = cg.samples_byte_nr + getattr(cg, "invalidation_bytes_nr", 0)
        n = int(cg.cycles_nr)
        get_blocks = getattr(g, "get_data_blocks", None)
        if get_blocks is None:  # another asammdf: the file's size and the ceiling still bound it
            check_claim(self.path, label, n, record, self.size)
            return n
        held, compressed = 0, False
        for b in get_blocks():
            stored = b.original_size if b.block_type == 0 else b.compressed_size
            if b.address < 0 or stored is None or b.address + stored > self.size:
                raise error(
                    self.path,
                    f"is damaged: a data block of channel group {gi} lies beyond the file's end",
                    field=label,
                    valid="an undamaged, complete MDF file",
                )
            compressed |= b.block_type != 0
            held += b.original_size or 0
        # compressed blocks state their own inflated size: it counts against the ceiling
        check_claim(self.path, label, held // 8, 8, None)
        check_claim(self.path, label, n, record, held)
        return n

    def claim(self, entry: Entry) -> int:
        """The records the channel's group claims, checked against its data blocks."""
        return self._check_group(entry.handle[0], entry.label)

    def read(self, entry: Entry, plan: bool = False) -> Raw:
        gi, ci = entry.handle
        n = self._check_group(gi, entry.label)
        master = self.mdf.masters_db.get(gi)
        m = self.mdf.groups[gi].channels[master] if master is not None else None
        sync = getattr(m, "sync_type", 1)
        if sync in _SYNC:
            raise error(
                self.path,
                f"has a master channel of {_SYNC[sync]}, not of time",
                field=entry.label,
                valid="a channel group whose master channel is a time",
            )
        planned = self._plan(gi, ci, master, n) if plan else None
        if planned is not None:
            samples, stamps, unit = planned
        else:
            sig = self.mdf.get(group=gi, index=ci)
            bits = sig.invalidation_bits
            if bits is not None and len(bits) and bits.any():
                raise error(
                    self.path,
                    f"has {int(bits.sum())} invalid samples (MDF invalidation bits)",
                    field=entry.label,
                    valid="a channel whose every sample is valid",
                )
            if len(sig.samples) > n:  # asammdf reads what the blocks hold: never above the claim checked
                raise error(self.path, "is damaged: more samples than its group claims", field=entry.label)
            samples, stamps, unit = sig.samples, sig.timestamps, sig.unit
        timing = None
        if m is not None:
            self.entries()  # listed once: the master's entry, for a unit stated for it
            timing = Stamps(stamps, getattr(m, "unit", None), self.listed[gi, master])
        return Raw(samples, unit, timing)

    def _plan(self, gi: int, ci: int, master, n: int):
        """(samples, time stamps, unit) of a channel whose values (and its master's) lie plainly in its
        group's records, as :class:`~.plan.Planned`; None where asammdf reads it (module docstring)."""
        g = self.mdf.groups[gi]
        cg = g.channel_group
        if not self.v4 or n == 0 or master is None:
            return None
        try:
            if (
                not g.sorted
                or g.uses_ld
                or g.data_location != 0  # asammdf's LOCATION_ORIGINAL_FILE
                or g.data_group.record_id_len
                or cg.invalidation_bytes_nr
            ):
                return None
            extents = []
            for b in g.get_data_blocks():
                if b.block_type != 0 or b.invalidation_block is not None:
                    return None  # compressed (DZ) or with invalidation blocks: asammdf inflates them
                size = b.original_size if b.block_limit is None else min(b.original_size, b.block_limit)
                extents.append((int(b.address), int(size)))
            run = Run(tuple(extents), int(cg.samples_byte_nr))
            fields = [_field(g, i, run.record) for i in (ci, master)]
        except (AttributeError, TypeError, ValueError):
            return None  # another asammdf: its own reading
        if None in fields:
            return None
        k = min(PROBE, n)
        head = self.mdf.get(group=gi, index=ci, record_offset=0, record_count=k)
        tail = self.mdf.get(group=gi, index=ci, record_offset=n - k, record_count=k)
        if len(head.samples) != k or len(tail.samples) != k:
            return None
        out = []
        for (offset, dtype, scale), attr in zip(fields, ("samples", "timestamps")):
            first = np.asarray(getattr(head, attr), dtype=np.float64)
            last = np.asarray(getattr(tail, attr), dtype=np.float64)
            out.append(Planned(((run, offset, n),), dtype, first, last, scale))
        return out[0], out[1], head.unit


def _field(g, ci: int, record: int):
    """(byte offset, numpy type, linear scale or None) of channel ``ci`` of group ``g`` where it is a
    whole-byte number of a standard type at a fixed place in each record with at most a linear
    conversion of integers; else None."""
    ch = g.channels[ci]
    if ch.channel_type not in (0, 2) or g.channel_dependencies[ci] or ch.bit_offset:
        return None  # value or master channels only; no arrays, no bit fields
    kind = _DTYPES_V4.get(ch.data_type)
    bits = ch.bit_count
    if kind is None or bits not in ((32, 64) if kind[1] == "f" else (8, 16, 32, 64)):
        return None
    dtype = kind + str(bits // 8)
    if ch.byte_offset + bits // 8 > record:
        return None
    conv, scale = ch.conversion, None
    if conv is not None and conv.conversion_type != 0:
        if conv.conversion_type != 1 or kind[1] == "f":
            return None  # asammdf computes a float's conversion in its own type: it reads those
        if (conv.a, conv.b) != (1, 0):
            scale = (float(conv.a), float(conv.b))
    return int(ch.byte_offset), np.dtype(dtype).str, scale


@contextlib.contextmanager
def source(fh, path, size: int, lib):
    """The open MDF file ``fh`` as a source of channels (metadata read now, data when asked)."""
    mdf = lib.MDF(fh)
    try:
        yield _Source(mdf, path, size)
    finally:
        mdf.close()
