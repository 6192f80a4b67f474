"""What a measured file holds of the channels asked for, found through its library: the channels picked by
name, their units, their time, and their samples or where these lie - everything but the reading of
planned samples (:mod:`.plan`) and the table (:mod:`.assemble`), which the caller does.

This runs where the library runs (the forked child of :func:`~flexshaft.measurement.files.read_measured`):
its result, a :class:`Survey`, holds only metadata, plans and the samples of channels that are not
stored plainly (compressed, scaled, MATLAB v5), so little crosses back to the caller.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ModelError
from ..signaltable import UNITS, VALID_UNITS, stated_units
from .base import Entry, Raw, Stamps, Uniform, check_total, error, label_list, resolve
from .layout import Planned

__all__ = ["Column", "Samples", "Survey", "survey"]


@dataclass(frozen=True, eq=False)
class Samples:
    """One channel's samples: read (an array, in the file's type), or planned (:class:`~.plan.Planned`).

    Attributes
    ----------
    label : str
        The channel, ``GROUP/NAME``, for messages.
    data : ndarray or Planned
        The samples, or where they lie.
    factor : float
        What they are multiplied by to be SI (1 for SI; for date-times, unused).
    """

    label: str
    data: object
    factor: float = 1.0

    @property
    def n(self) -> int:
        return self.data.n if isinstance(self.data, Planned) else int(self.data.size)


@dataclass(frozen=True, eq=False)
class Column:
    """One column of the table: its key and SI unit, its samples, and its time.

    Attributes
    ----------
    timing : Uniform or str
        A start and step, or the label of its time channel in :attr:`Survey.times`.
    time_label : str
        What to call its time in messages.
    """

    key: str
    unit: str
    samples: Samples
    timing: object
    time_label: str


@dataclass(frozen=True, eq=False)
class Survey:
    """The channels asked for, in order, and the time channels they refer to (by label; values in s
    after their factor, or TDMS date-times)."""

    columns: tuple
    times: dict


def _numeric(path, label: str, values) -> np.ndarray:
    """Samples the library read: a 1-D array of numbers (their finiteness is the caller's to check)."""
    arr = np.asarray(values)
    if arr.dtype.kind not in "iuf":
        raise error(path, f"holds {arr.dtype} values, not numbers", field=label, valid="a numeric channel")
    if arr.ndim != 1:
        raise error(path, f"has shape {arr.shape}", field=label, valid="a channel of one dimension")
    return arr


def _data(path, label: str, values):
    return values if isinstance(values, Planned) else _numeric(path, label, values)


class _Reading:
    """The state of one file's survey: its channels, the units stated, the time channels found."""

    def __init__(self, path, source, units, time_column, rate, plan: bool):
        self.path = path
        self.source = source
        self.plan = plan
        self.entries = source.entries()
        self.time_column = time_column
        self.rate = rate
        self.stated: dict[Entry, str] = {
            resolve(path, self.entries, key, None, "units"): unit
            for key, unit in stated_units(units, "channel").items()
        }
        self.times: dict[str, Samples] = {}

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

    def seconds(self, entry: Entry, values, file_unit, label: str) -> str:
        """Time stamps (numbers in a time unit, or date-times) kept under ``label``; the label."""
        if label in self.times:
            return label
        if not isinstance(values, Planned) and np.asarray(values).dtype.kind == "M":
            arr = np.asarray(values)  # a TDMS timestamp channel: absolute times
            if arr.ndim != 1 or arr.size < 2:
                raise error(self.path, f"has shape {arr.shape}", field=entry.label, valid="at least 2 times")
            self.times[label] = Samples(entry.label, arr)
            return label
        unit, factor = self.si(entry, file_unit, default="s")
        if unit != "s":
            raise error(
                self.path, "is not a time", field=entry.label, value=file_unit, valid="a unit s or ms"
            )
        self.times[label] = Samples(entry.label, _data(self.path, entry.label, values), factor)
        return label

    def time_channel(self, entry: Entry) -> str:
        if entry.label not in self.times:
            raw = self.source.read(entry, self.plan)
            self.seconds(entry, raw.values, raw.unit, entry.label)
        return entry.label

    def _refuse_rate(self, entry: Entry, how: str) -> None:
        if self.rate is not None:
            raise ModelError(
                f"is given, but the file gives the time of {entry.label!r} ({how})",
                field="rate",
                value=self.rate,
                unit="Hz",
                valid="no rate where the file has the time",
            )

    def timing(self, entry: Entry, raw: Raw, n: int) -> tuple[object, str]:
        """The sample times of ``entry``: :class:`Uniform`, or the label of a time channel; and what to
        call them."""
        if self.time_column is not None:
            same = [e for e in self.entries if e.group == entry.group and e.name == self.time_column]
            t_entry = (
                same[0]
                if len(same) == 1
                else resolve(self.path, self.entries, self.time_column, None, "time_column")
            )
            self._refuse_rate(entry, f"the channel {t_entry.label!r}")
            label = self.time_channel(t_entry)
        elif isinstance(raw.timing, Uniform):
            self._refuse_rate(entry, "its waveform start and increment")
            return raw.timing, f"{entry.label} (time)"
        elif isinstance(raw.timing, Stamps):
            st = raw.timing
            how = f"the master channel {st.entry.label!r}" if st.entry is not None else "its time stamps"
            self._refuse_rate(entry, how)
            label = st.entry.label if st.entry is not None else f"{entry.label} (time)"
            label = self.seconds(st.entry or entry, st.values, st.unit, label)
        else:
            beside = [
                e for e in self.entries if e.group == entry.group and e.name.lower() == "time" and e != entry
            ]
            if len(beside) == 1:
                self._refuse_rate(entry, f"the channel {beside[0].label!r}")
                label = self.time_channel(beside[0])
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
        t = self.times[label]
        if t.n != n:
            raise error(
                self.path,
                f"has {n} samples, its time {label!r} {t.n}",
                field=entry.label,
                valid="one time per sample",
            )
        return label, label


def survey(path, source, *, channels, units, time_column, group, rate, plan: bool = True) -> Survey:
    """The channels asked for of an open ``source``, with their units and time (module docstring).

    Parameters
    ----------
    plan : bool
        Channels stored plainly are planned (the caller reads them); False: the library reads every
        channel (when a plan's samples disagreed with the library's).
    """
    reading = _Reading(path, source, units, time_column, rate, plan)
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
    # what every channel claims, checked (each alone, and all together) before any is read
    check_total(path, [source.claim(e) for e in picked])
    names = [e.name for e in picked]
    columns = []
    for entry in picked:
        key = entry.name if names.count(entry.name) == 1 else entry.label
        raw = source.read(entry, plan)
        unit, factor = reading.si(entry, raw.unit)
        samples = Samples(entry.label, _data(path, entry.label, raw.values), factor)
        raw.values = None  # the file's own array goes before the next is read
        timing, label = reading.timing(entry, raw, samples.n)
        columns.append(Column(key, unit, samples, timing, label))
    return Survey(tuple(columns), reading.times)
