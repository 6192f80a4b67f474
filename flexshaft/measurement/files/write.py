"""Writing signals as a TDMS or MDF 4 file, as a test bench would (for examples, and the readers' tests):
what :func:`~flexshaft.measurement.files.read_measured` reads back as the same floats."""

from __future__ import annotations

import io
from pathlib import Path

from ...errors import ModelError
from ...system.atomic import atomic_write_bytes
from ...system.threads import follows_policy
from ...validation import check_name
from ..checks import as_signal, uniform_rate
from ..signaltable import signal_entries
from .base import need

__all__ = ["write_measured"]

_WRITERS = {".tdms": ("nptdms", "npTDMS"), ".mf4": ("asammdf", "asammdf")}


@follows_policy
def write_measured(path, time, columns: dict, *, group: str = "signals", overwrite: bool = False) -> Path:
    """Write signals to a TDMS (``.tdms``) or MDF 4 (``.mf4``) file, atomically.

    Parameters
    ----------
    path : str or Path
        The file; its suffix picks the format. An existing one only with ``overwrite``.
    time : array_like, shape (n,)
        Sample times, s: increasing, uniformly spaced.
    columns : dict of str to (array_like, str)
        ``name -> (values, unit)``, values of shape (n,) in ``unit`` (one of
        :data:`~flexshaft.measurement.signaltable.UNITS`, stored as the channel's unit).
    group : str
        The TDMS group, or the MDF channel group's acquisition name, holding every channel.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The file. TDMS: each channel a waveform (``wf_start_offset`` the first time,
        ``wf_increment`` the mean step; read back, the times are these within rounding) with its
        ``unit_string``. MDF 4: one channel group, its master channel the times as given.
    """
    p = Path(path)
    if p.suffix.lower() not in _WRITERS:
        raise ModelError("unknown file type", field="path", value=str(p), valid="FILE.tdms or FILE.mf4")
    group = check_name(group, "group")
    t = as_signal(time, "time", "s")
    uniform_rate(t, "time")  # increasing, equal steps: a waveform
    signals = []
    for _, name, values, unit in signal_entries(columns):
        x = as_signal(values, name, unit)
        if x.size != t.size:
            raise ModelError(f"has {x.size} samples, the time {t.size}", field=name, valid="one per time")
        signals.append((name, x, unit))
    lib = need(*_WRITERS[p.suffix.lower()], p.suffix.lower(), p)
    buf = io.BytesIO()
    if p.suffix.lower() == ".tdms":
        wf = {"wf_start_offset": float(t[0]), "wf_increment": float((t[-1] - t[0]) / (t.size - 1))}
        objects = [lib.ChannelObject(group, n, x, properties={"unit_string": u, **wf}) for n, x, u in signals]
        with lib.TdmsWriter(buf) as w:
            w.write_segment(objects)
    else:
        mdf = lib.MDF(version="4.10")
        try:
            mdf.append([lib.Signal(x, t, name=n, unit=u) for n, x, u in signals], acq_name=group)
            mdf.save(buf)
        finally:
            mdf.close()
    return atomic_write_bytes(p, buf.getvalue(), overwrite=overwrite)
