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
"""

from __future__ import annotations

import contextlib
import math

from .common import Entry, Raw, Uniform, check_claim, error

__all__ = ["LIBRARY", "MAGIC", "WHAT", "source"]

WHAT = "TDMS file"
LIBRARY = ("nptdms", "npTDMS")
MAGIC = b"TDSm"  # every segment's lead-in tag ('TDSh' starts an index file, which holds no data)


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

    def read(self, entry: Entry) -> Raw:
        c = entry.handle
        n = len(c)
        itemsize = getattr(c.data_type, "size", None) or 1  # a string's or raw DAQmx value: at least a byte
        check_claim(self.path, entry.label, n, itemsize, self.size)
        values = c[:]
        props = c.properties
        timing = None
        if "wf_increment" in props:
            try:
                step = float(props["wf_increment"])
                start = float(props.get("wf_start_offset", 0.0))
            except (TypeError, ValueError):
                step = start = math.nan
            if not (math.isfinite(step) and step > 0 and math.isfinite(start)):
                raise error(
                    self.path,
                    f"has the waveform timing wf_increment = {props['wf_increment']!r}, "
                    f"wf_start_offset = {props.get('wf_start_offset', 0.0)!r}",
                    field=entry.label,
                    valid="wf_increment a finite number > 0 (s), wf_start_offset finite (s)",
                )
            timing = Uniform(start, step)
        return Raw(values, _unit(props), timing)


@contextlib.contextmanager
def source(fh, path, size: int, lib):
    """The open TDMS file ``fh`` as a source of channels (metadata read now, data when asked)."""
    with lib.TdmsFile.open(fh) as tdms:
        yield _Source(tdms, path, size)
