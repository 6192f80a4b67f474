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
"""

from __future__ import annotations

import contextlib

from .common import Entry, Raw, Stamps, check_claim, error

__all__ = ["LIBRARY", "MAGICS", "WHAT", "source"]

WHAT = "MDF file"
LIBRARY = ("asammdf", "asammdf")
MAGICS = (b"MDF     ", b"UnFinMF ")  # a finalised file's identification; an MDF 4 file not finalised

# Data types whose raw values are numbers (asammdf's v4_constants / v2_v3_constants).
_NUMERIC_V4 = frozenset(range(6))  # unsigned, signed, real; Intel and Motorola
_NUMERIC_V3 = frozenset((0, 1, 2, 3, *range(9, 17)))
_SYNC = {2: "angle", 3: "distance", 4: "index"}  # MDF 4 master sync types that are not time


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

    def read(self, entry: Entry) -> Raw:
        gi, ci = entry.handle
        n = self._check_group(gi, entry.label)
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
        master = self.mdf.masters_db.get(gi)
        timing = None
        if master is not None:
            m = self.mdf.groups[gi].channels[master]
            sync = getattr(m, "sync_type", 1)
            if sync in _SYNC:
                raise error(
                    self.path,
                    f"has a master channel of {_SYNC[sync]}, not of time",
                    field=entry.label,
                    valid="a channel group whose master channel is a time",
                )
            self.entries()  # listed once: the master's entry, for a unit stated for it
            timing = Stamps(sig.timestamps, getattr(m, "unit", None), self.listed[gi, master])
        return Raw(sig.samples, sig.unit, timing)


@contextlib.contextmanager
def source(fh, path, size: int, lib):
    """The open MDF file ``fh`` as a source of channels (metadata read now, data when asked)."""
    mdf = lib.MDF(fh)
    try:
        yield _Source(mdf, path, size)
    finally:
        mdf.close()
