"""TDMS files (NI LabVIEW, DIAdem, VeriStand) through npTDMS, streamed: only the channels asked for
are read, each by itself.

- Channels: ``GROUP/CHANNEL`` or the channel's name alone where no other group has one of that name.
- Units: the channel property ``unit_string`` (LabVIEW's), else ``NI_UnitDescription``; an empty
  one states nothing. Values are npTDMS's scaled values (a channel's NI scaling applied).
- Time: the waveform properties ``wf_start_offset`` + k ``wf_increment`` (s; what npTDMS's
  ``time_track()`` gives), or a time channel of the same group (``time_column``, or one named
  ``time``; numbers in s or ms, or TDMS timestamps, counted from the first).
- Damage: npTDMS reads what it can of a truncated file and logs a warning; that warning refuses the
  file. A channel whose segments claim more values than the file's bytes can hold is refused before
  it is read. A ``.tdms_index`` file beside it is never used (the file is handed over open).
  ``wf_increment`` must be a number (a boolean or text is none) whose rate lies within
  :data:`~.common.RATE_RANGE_HZ`, ``wf_start_offset`` a finite number.
- Reading: a channel of unscaled numbers (not DAQmx raw data) is planned (:mod:`.plan`): npTDMS
  finds where its values lie in each segment, the caller reads them.
"""

from __future__ import annotations

import contextlib

import numpy as np

from .base import Entry, Raw, check_claim, uniform_timing
from .layout import PROBE, Planned, Run

__all__ = ["LIBRARY", "MAGIC", "WHAT", "source"]

WHAT = "TDMS file"
LIBRARY = ("nptdms", "npTDMS")
MAGIC = b"TDSm"  # every segment's lead-in tag ('TDSh' starts an index file, which holds no data)
_PROBE_BYTES = 1 << 20  # the most npTDMS may read to give the plan's check its first or last values


def _unit(props):
    for key in ("unit_string", "NI_UnitDescription"):
        value = props.get(key)
        if isinstance(value, str) and value.strip():
            return value
    return None


class _Source:
    def __init__(self, tdms, path, size: int):
        self.tdms, self.path, self.size = tdms, path, size

    def entries(self) -> list[Entry]:
        out = []
        for g in self.tdms.groups():
            for c in g.channels():
                kind = c.dtype.kind if c.dtype is not None else "O"
                out.append(
                    Entry(
                        g.name, c.name, c, numeric=kind in "iuf", time=c.name.lower() == "time" or kind == "M"
                    )
                )
        return out

    def claim(self, entry: Entry) -> int:
        """The values the channel's segments claim, checked against the file's size."""
        c = entry.handle
        n = len(c)
        itemsize = getattr(c.data_type, "size", None) or 1  # a string's or raw DAQmx value: at least a byte
        check_claim(self.path, entry.label, n, itemsize, self.size)
        return n

    def read(self, entry: Entry, plan: bool = False) -> Raw:
        c = entry.handle
        n = self.claim(entry)
        values = (_plan(c, n) if plan else None) or c[:]
        props = c.properties
        timing = None
        if "wf_increment" in props:
            timing = uniform_timing(
                self.path,
                entry.label,
                "wf_increment",
                props["wf_increment"],
                rate=False,
                start=props.get("wf_start_offset", 0.0),
                what="property",
            )
        return Raw(values, _unit(props), timing)


def _plan(c, n: int) -> Planned | None:
    """Where a channel's raw values lie, segment by segment, or None: npTDMS reads it (scaled values,
    DAQmx raw data, strings, a truncated segment). npTDMS's parsed segments are read as its own
    reader reads them (contiguous: each chunk holds every channel's values in turn; interleaved: one
    value of each channel per row). The library's values at either end check the plan where npTDMS
    reads them cheaply: it reads a whole chunk for one value (all of a segment where interleaved), so
    a chunk above :data:`_PROBE_BYTES` (one segment of a whole record, as npTDMS's own writer makes
    it) is not read twice; the plan is then npTDMS's layout alone, its counts equal to npTDMS's."""
    from nptdms.common import toc_properties as toc

    try:
        if n == 0 or c._scaling is not None:
            return None
        nptype = c.data_type.nptype
        if nptype is None or np.dtype(nptype).kind not in "iuf":
            return None
        itemsize, pieces, dtype, costs = np.dtype(nptype).itemsize, [], None, []
        for seg in c._reader._segments:
            if not seg.toc_mask & toc["kTocRawData"]:
                continue
            obj = seg.get_segment_object(c.path)
            if obj is None or not obj.has_data or obj.number_values == 0:
                continue
            if seg.final_chunk_lengths_override is not None or seg._have_daqmx_objects():
                return None
            order = ">" if seg.toc_mask & toc["kTocBigEndian"] else "<"
            this = np.dtype(nptype).newbyteorder(order).str
            if dtype not in (None, this):
                return None
            dtype = this
            objects = [o for o in seg.ordered_objects if o.has_data]
            before = objects[: next(i for i, o in enumerate(objects) if o is obj)]
            count = obj.number_values * seg.num_chunks
            if seg._have_interleaved_data():
                width = sum(o.data_type.size for o in objects)
                run = Run(((seg.data_position, count * width),), width)
                pieces.append((run, sum(o.data_type.size for o in before), count))
                costs.append(count * width)  # npTDMS reads the segment's every row for one value
            else:
                at = seg.data_position + sum(o.data_size for o in before)
                size, chunk = obj.number_values * itemsize, seg._get_chunk_size()
                extents = tuple((at + k * chunk, size) for k in range(seg.num_chunks))
                costs.append(size)  # npTDMS reads the chunk holding a value
                last = pieces[-1] if pieces else None
                if last is not None and last[0].record == itemsize:  # one run over contiguous segments
                    pieces[-1] = (Run(last[0].extents + extents, itemsize), 0, last[2] + count)
                else:
                    pieces.append((Run(extents, itemsize), 0, count))
        if sum(count for _, _, count in pieces) != n:
            return None
    except (AttributeError, TypeError, ValueError, KeyError, StopIteration):
        return None  # another npTDMS: its own reading
    k = min(PROBE, n)
    none = np.empty(0)
    head = np.asarray(c[0:k], dtype=np.float64) if costs[0] <= _PROBE_BYTES else none
    tail = np.asarray(c[n - k : n], dtype=np.float64) if costs[-1] <= _PROBE_BYTES else none
    return Planned(tuple(pieces), dtype, head, tail)


@contextlib.contextmanager
def source(fh, path, size: int, lib):
    """The open TDMS file ``fh`` as a source of channels (metadata read now, data when asked)."""
    with lib.TdmsFile.open(fh) as tdms:
        yield _Source(tdms, path, size)
