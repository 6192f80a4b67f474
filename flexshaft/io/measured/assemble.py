"""One :class:`~flexshaft.io.signaltable.SignalTable` of a measured file's channels: the channels
picked by name, their units to SI, their times brought to one uniform time base.

The time base: where every channel asked for has the same sample times (one TDMS group's waveforms,
one MDF channel group), they are the table's, and every value is the file's. Otherwise the fastest
channel asked for (the highest mean rate; the first asked among equals) gives the time stamps, over
the span every channel covers, and the others are interpolated linearly onto them (up-sampling a
slower channel aliases nothing; its error is at most h^2/8 max|x''| for its own step h). The
table's ``notes`` say so. The fastest channel must be uniformly sampled (as a CSV signal file's
time); the others need only increase.
"""

from __future__ import annotations

import numpy as np

from ...errors import ModelError
from ...signals.checks import uniform_rate
from ..signaltable import UNITS, VALID_UNITS, SignalTable, stated_units
from .common import Entry, Raw, Stamps, Uniform, error, label_list, resolve

__all__ = ["collect"]


def _numbers(path, label: str, values) -> np.ndarray:
    """A channel's samples as a 1-D float64 array of finite numbers."""
    arr = np.asarray(values)
    if arr.dtype.kind not in "iuf":
        raise error(path, f"holds {arr.dtype} values, not numbers", field=label, valid="a numeric channel")
    if arr.ndim != 1:
        raise error(path, f"has shape {arr.shape}", field=label, valid="a channel of one dimension")
    arr = arr.astype(np.float64, copy=False)
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise error(
            path,
            f"sample {i} is {float(arr[i])!r} ({int(bad.sum())} non-finite samples in all)",
            field=label,
            valid="finite numbers",
        )
    return arr


class _Reading:
    """The state of one file's reading: its channels, the units stated, the time channels read."""

    def __init__(self, path, source, units, time_column, rate):
        self.path = path
        self.source = source
        self.entries = source.entries()
        self.time_column = time_column
        self.rate = rate
        self.stated: dict[Entry, str] = {
            resolve(path, self.entries, key, None, "units"): unit
            for key, unit in stated_units(units, "channel").items()
        }
        self.times: dict[Entry, np.ndarray] = {}

    def si(self, entry: Entry, file_unit, default=None) -> tuple[str, float]:
        """(SI unit, factor) of ``entry``: the file's unit, else the one stated, else ``default``."""
        file_unit = file_unit.strip() if isinstance(file_unit, str) else None
        file_unit = file_unit or None  # an empty unit string (LabVIEW's default) states nothing
        stated = self.stated.get(entry)
        if file_unit is not None and stated is not None and stated != file_unit:
            raise error(
                self.path,
                f"has the unit {file_unit!r} in the file and {stated!r} in units=",
                field=entry.label,
                valid="one unit: leave it out of units= when the file states it",
            )
        unit = file_unit or stated or default
        if unit is None:
            raise error(
                self.path,
                "has no unit",
                field=entry.label,
                valid=f"the unit stated: units={{{entry.name!r}: unit}} (command line: --unit "
                f"{entry.name}=UNIT); units: {VALID_UNITS}",
            )
        if unit not in UNITS:
            raise error(
                self.path, "unknown unit", field=entry.label, value=unit, valid=f"one of {VALID_UNITS}"
            )
        return UNITS[unit]

    def seconds(self, entry: Entry, values, file_unit) -> np.ndarray:
        """Time stamps in s: numbers in a time unit, or date-times (seconds from the first)."""
        arr = np.asarray(values)
        if arr.dtype.kind == "M":  # a TDMS timestamp channel: absolute times
            if arr.ndim != 1 or arr.size < 2:
                raise error(self.path, f"has shape {arr.shape}", field=entry.label, valid="at least 2 times")
            return (arr - arr[0]) / np.timedelta64(1, "s")
        unit, factor = self.si(entry, file_unit, default="s")
        if unit != "s":
            raise error(
                self.path, "is not a time", field=entry.label, value=file_unit, valid="a unit s or ms"
            )
        t = _numbers(self.path, entry.label, arr)
        return t * factor if factor != 1.0 else t

    def time_channel(self, entry: Entry) -> np.ndarray:
        if entry not in self.times:
            raw = self.source.read(entry)
            self.times[entry] = self.seconds(entry, raw.values, raw.unit)
        return self.times[entry]

    def _refuse_rate(self, entry: Entry, how: str) -> None:
        if self.rate is not None:
            raise ModelError(
                f"is given, but the file gives the time of {entry.label!r} ({how})",
                field="rate",
                value=self.rate,
                unit="Hz",
                valid="no rate where the file has the time",
            )

    def timing(self, entry: Entry, raw: Raw, n: int):
        """The sample times of ``entry``: :class:`Uniform`, or an array (s); and what to call them."""
        if self.time_column is not None:
            same = [e for e in self.entries if e.group == entry.group and e.name == self.time_column]
            t_entry = (
                same[0]
                if len(same) == 1
                else resolve(self.path, self.entries, self.time_column, None, "time_column")
            )
            self._refuse_rate(entry, f"the channel {t_entry.label!r}")
            found = self.time_channel(t_entry), t_entry.label
        elif isinstance(raw.timing, Uniform):
            self._refuse_rate(entry, "its waveform start and increment")
            return raw.timing, f"{entry.label} (time)"
        elif isinstance(raw.timing, Stamps):
            st = raw.timing
            how = f"the master channel {st.entry.label!r}" if st.entry is not None else "its time stamps"
            self._refuse_rate(entry, how)
            label = st.entry.label if st.entry is not None else f"{entry.label} (time)"
            found = self.seconds(st.entry or entry, st.values, st.unit), label
        else:
            beside = [
                e for e in self.entries if e.group == entry.group and e.name.lower() == "time" and e != entry
            ]
            if len(beside) == 1:
                self._refuse_rate(entry, f"the channel {beside[0].label!r}")
                found = self.time_channel(beside[0]), beside[0].label
            elif self.rate is not None:
                return Uniform(0.0, 1.0 / self.rate), f"{entry.label} (time)"
            else:
                raise error(
                    self.path,
                    "has no time: no waveform timing, no time channel beside it",
                    field=entry.label,
                    valid="a time channel named: time_column='NAME' (--time-column NAME), "
                    "or the sampling rate given: rate=HZ",
                )
        t, label = found
        if t.size != n:
            raise error(
                self.path,
                f"has {n} samples, its time {label!r} {t.size}",
                field=entry.label,
                valid="one time per sample",
            )
        return t, label


def _as_array(timing, n: int) -> np.ndarray:
    if isinstance(timing, Uniform):
        return timing.start + np.arange(n) * timing.step  # as npTDMS's time_track() computes it
    return timing


def _same(a, na: int, b, nb: int) -> bool:
    if na != nb:
        return False
    if isinstance(a, Uniform) and isinstance(b, Uniform):
        return a == b
    return a is b or np.array_equal(_as_array(a, na), _as_array(b, nb))


def _uniform(path, t: np.ndarray, label: str) -> float:
    if t.size < 2:
        raise error(
            path, f"has {t.size} samples", field=label, valid="at least 2 samples (the rate needs two)"
        )
    try:
        return uniform_rate(t, label)
    except ModelError as err:
        raise err.located(file=str(path)) from None


def _increasing(path, t: np.ndarray, label: str) -> None:
    if t.size < 2:
        raise error(path, f"has {t.size} samples", field=label, valid="at least 2 samples")
    dt = np.diff(t)
    if not np.all(dt > 0):
        i = int(np.argmax(~(dt > 0)))
        raise error(
            path,
            f"does not increase at sample {i + 1} ({float(t[i])!r} s then {float(t[i + 1])!r} s)",
            field=label,
            valid="strictly increasing times (s)",
        )


def _one_time_base(path, series):
    """``series`` [(key, values, timing, time label)] on one uniform time base: (time, columns, notes,
    rate in Hz)."""
    key0, v0, tm0, label0 = series[0]
    if all(_same(tm, v.size, tm0, v0.size) for _, v, tm, _ in series[1:]):
        t = _as_array(tm0, v0.size)
        return t, {k: v for k, v, _, _ in series}, [], _uniform(path, t, label0)
    times = []
    for _, v, tm, label in series:
        t = _as_array(tm, v.size)
        _increasing(path, t, label)
        times.append(t)
    rates = [(t.size - 1) / (t[-1] - t[0]) for t in times]
    r = int(np.argmax(rates))  # the first of the fastest
    ref_key, _, ref_timing, ref_label = series[r]
    tr = times[r]
    rate = _uniform(path, tr, ref_label)  # the fastest must be uniform: its samples are the table's
    lo, hi = max(t[0] for t in times), min(t[-1] for t in times)
    i0, i1 = int(np.searchsorted(tr, lo, "left")), int(np.searchsorted(tr, hi, "right"))
    if i1 - i0 < 2:
        spans = ", ".join(f"{k!r} {t[0]:g}..{t[-1]:g} s" for (k, *_), t in zip(series, times))
        raise error(
            path,
            f"the channels have no common time span ({spans})",
            field="channels",
            valid="channels recorded over the same time",
        )
    grid = tr[i0:i1]
    columns, notes = {}, []
    for (key, v, tm, _), t, rate_i in zip(series, times, rates):
        if _same(tm, v.size, ref_timing, tr.size):
            columns[key] = v[i0:i1]
        else:
            columns[key] = np.interp(grid, t, v)
            notes.append(
                f"{key!r} (sampled at {rate_i:.6g} Hz) is interpolated linearly to the time stamps of "
                f"{ref_key!r} ({rate:.6g} Hz)"
            )
    if i0 > 0 or i1 < tr.size:
        notes.append(
            f"the record is cut to {grid[0]:.6g} s .. {grid[-1]:.6g} s, the span every channel covers"
        )
    return grid, columns, notes, uniform_rate(grid, ref_label)


def collect(path, source, *, channels, units, time_column, group, rate) -> SignalTable:
    """Read the channels asked for from an open ``source`` and make the table (module docstring)."""
    reading = _Reading(path, source, units, time_column, rate)
    entries = reading.entries
    if group is not None and not any(e.in_group(group) for e in entries):
        groups = sorted({e.group for e in entries})
        shown = ", ".join(repr(g) for g in groups[:20]) + (
            f", ... ({len(groups)} in all)" if len(groups) > 20 else ""
        )
        raise error(path, "no such group", field="group", value=group, valid=f"one of {shown or 'none'}")
    if channels is None:
        picked = [
            e
            for e in entries
            if e.numeric and not e.time and e.name != time_column and (group is None or e.in_group(group))
        ]
        if not picked:
            raise error(
                path,
                "holds no numeric channel but time channels",
                field="channels",
                valid="a file with signals; its channels: " + label_list(entries),
            )
    else:
        picked = [resolve(path, entries, c, group, "channels") for c in channels]
        picked = list(dict.fromkeys(picked))  # one channel asked for twice is read once
    names = [e.name for e in picked]
    series, out_units = [], {}
    for entry in picked:
        key = entry.name if names.count(entry.name) == 1 else entry.label
        raw = reading.source.read(entry)
        unit, factor = reading.si(entry, raw.unit)
        values = _numbers(path, entry.label, raw.values)
        raw.values = None  # the file's own array (another dtype) goes before the next is read
        values = values * factor if factor != 1.0 else values
        timing, label = reading.timing(entry, raw, values.size)
        series.append((key, values, timing, label))
        out_units[key] = unit
    reading.times.clear()
    time, columns, notes, rate_hz = _one_time_base(path, series)
    series.clear()
    return SignalTable(
        time=time,
        columns=columns,
        units=out_units,
        rate_hz=rate_hz,
        source=str(path),
        notes=tuple(notes),
    )
