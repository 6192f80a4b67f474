"""One :class:`~flexshaft.measurement.signaltable.SignalTable` of a measured file's channels, from their
:class:`~.survey.Survey`: planned samples read (:mod:`.plan`), every sample checked finite and made SI,
the times brought to one uniform time base.

The time base: where every channel asked for has the same sample times (one TDMS group's waveforms,
one MDF channel group), they are the table's, and every value is the file's. Otherwise the fastest
channel asked for (the highest mean rate; the first asked among equals) gives the time stamps, over
the span every channel covers, and the others are interpolated linearly onto them (up-sampling a
slower channel aliases nothing; its error is at most h^2/8 max|x''| for its own step h). The
table's ``notes`` say so. The fastest channel must be uniformly sampled (as a CSV signal file's
time); the others need only increase. Its rate must lie in
:data:`~flexshaft.measurement.files.base.RATE_RANGE_HZ`.

This runs in the caller (no library is involved): plain numpy on the arrays, each pass once.
"""

from __future__ import annotations

import numpy as np

from ...errors import ModelError
from ..checks import UNIFORM_TOLERANCE, non_finite_text, uniform_rate
from ..signaltable import SignalTable
from .base import RATE_RANGE_HZ, Uniform, error
from .layout import Planned, read_planned

__all__ = ["assemble"]

# Relative slack on the rate range for a rate measured from time stamps (a stated rate of exactly
# 1 GHz measures 1 GHz within a few rounding errors).
_RATE_SLACK = 1e-9
_BLOCK = 1 << 16  # samples tested at a time for finiteness


def _all_finite(arr: np.ndarray) -> bool:
    # a block at a time: each block's test array stays in the processor's cache (numpy's isfinite over
    # the whole array writes and reads back a bool array of n bytes); no BLAS (x·x would be one pass,
    # but OpenBLAS's threads on busy cores made it 3x slower than this)
    return all(np.isfinite(arr[i : i + _BLOCK]).all() for i in range(0, arr.size, _BLOCK))


def _finite(path, label: str, arr: np.ndarray, factor: float = 1.0, tested: bool = False) -> np.ndarray:
    """``arr`` as float64 (its own array where it is one) times ``factor``, every sample finite
    (``tested``: known to be, by the reading)."""
    arr = arr.astype(np.float64, copy=False)
    if not tested and not _all_finite(arr):
        raise error(path, non_finite_text(arr), field=label, valid="finite numbers")
    if factor != 1.0:
        with np.errstate(over="ignore"):
            arr *= factor
        if not _all_finite(arr):
            i = int(np.argmax(~np.isfinite(arr)))
            raise error(
                path,
                f"sample {i} times {factor:g} (its unit to SI) is beyond floating point",
                field=label,
                valid=f"finite numbers in SI (below {np.finfo(np.float64).max:.3g})",
            )
    return arr


def _values(path, samples, arrays: dict, finite: set, taken: set) -> np.ndarray:
    """A channel's samples in SI: float64, finite, times its factor (in place where the array is ours
    alone: ``taken`` holds the arrays given out already, which one sent twice would be)."""
    data = arrays[id(samples)] if isinstance(samples.data, Planned) else samples.data
    if data.dtype.kind == "M":  # TDMS date-times: seconds from the first
        return (data - data[0]) / np.timedelta64(1, "s")
    if samples.factor != 1.0 and data.dtype == np.float64 and (id(data) in taken or not data.flags.writeable):
        data = data.copy()
    taken.add(id(data))
    return _finite(path, samples.label, data, samples.factor, tested=id(samples) in finite)


def _time_array(timing: Uniform, n: int) -> np.ndarray:
    """start + k step, k = 0..n-1: the same floats as ``start + np.arange(n) * step`` (npTDMS's
    ``time_track()``), made a block at a time in the processor's cache."""
    t = np.empty(n, dtype=np.float64)
    with np.errstate(over="ignore"):  # a start near the float range's end: _uniform refuses its inf
        for i in range(0, n, _BLOCK):
            block = t[i : i + _BLOCK]
            np.multiply(np.arange(i, i + block.size, dtype=np.float64), timing.step, out=block)
            if timing.start:
                block += timing.start
    return t


def _in_range(path, rate: float, label: str) -> float:
    lo, hi = RATE_RANGE_HZ
    if not (lo * (1 - _RATE_SLACK) <= rate <= hi * (1 + _RATE_SLACK)):  # False for inf and NaN
        raise error(
            path,
            f"is sampled at {rate:g} Hz",
            field=label,
            valid=f"a sampling rate from {lo:g} to {hi:g} Hz",
        )
    return rate


def _uniform(path, t: np.ndarray, label: str, timing=None) -> float:
    """The rate (Hz) of the time stamps ``t``, checked uniform (as
    :func:`~flexshaft.measurement.checks.uniform_rate`) and within the rate range.

    For ``t`` made from a :class:`Uniform` timing the check is a bound, not a pass over the samples:
    each t_k = fl(start + fl(k step)) lies within 2u (|start| + k step) of start + k step (u = 2^-53,
    one rounding per operation), so every step lies within 8u M of ``step`` (M = |start| + (n-1) step)
    and the mean step within 8u M / (n-1); where 32u M is below the tolerance's share of a step no
    step can fail it (a 5 M-sample record from 0 s: 32u·5e6·step = 1.8e-8 of a step, 2 % of the
    1e-6 tolerance). Above it (a start of 1e9 s in ms steps), every step is checked.
    """
    if t.size < 2:
        raise error(
            path, f"has {t.size} samples", field=label, valid="at least 2 samples (the rate needs two)"
        )
    if not np.isfinite(t[-1]):
        raise error(path, f"ends at {float(t[-1])!r} s", field=label, valid="finite times (s)")
    if isinstance(timing, Uniform):
        bound = 32 * (np.finfo(np.float64).eps / 2) * (abs(timing.start) + (t.size - 1) * timing.step)
        if bound <= UNIFORM_TOLERANCE * timing.step:
            step = (float(t[-1]) - float(t[0])) / (t.size - 1)  # as uniform_rate finds it
            return _in_range(path, 1.0 / step, label)
    try:
        with np.errstate(over="ignore", divide="ignore"):  # a rate of inf is refused below, not warned
            rate = uniform_rate(t, label)
    except ModelError as err:
        raise err.located(file=str(path)) from None
    return _in_range(path, float(rate), label)


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


def _same(a, na: int, b, nb: int, times: dict) -> bool:
    if na != nb:
        return False
    if isinstance(a, Uniform) or isinstance(b, Uniform):
        return a == b
    return a == b or np.array_equal(times[a], times[b])


def _one_time_base(path, series, times: dict):
    """``series`` [(key, values, timing, time label)] on one uniform time base: (time, columns, notes,
    rate in Hz). A timing is a :class:`Uniform` or the label of its array in ``times``."""

    def as_array(tm, n):
        return _time_array(tm, n) if isinstance(tm, Uniform) else times[tm]

    key0, v0, tm0, label0 = series[0]
    if all(_same(tm, v.size, tm0, v0.size, times) for _, v, tm, _ in series[1:]):
        t = as_array(tm0, v0.size)
        return t, {k: v for k, v, _, _ in series}, [], _uniform(path, t, label0, tm0)
    arrays = []
    for _, v, tm, label in series:
        t = as_array(tm, v.size)
        _increasing(path, t, label)
        arrays.append(t)
    with np.errstate(over="ignore"):  # a rate beyond floating point is refused by _uniform, not warned
        rates = [(t.size - 1) / (t[-1] - t[0]) for t in arrays]
    r = int(np.argmax(rates))  # the first of the fastest
    ref_key, _, ref_timing, ref_label = series[r]
    tr = arrays[r]
    rate = _uniform(
        path, tr, ref_label, ref_timing
    )  # the fastest must be uniform: its samples are the table's
    lo, hi = max(t[0] for t in arrays), min(t[-1] for t in arrays)
    i0, i1 = int(np.searchsorted(tr, lo, "left")), int(np.searchsorted(tr, hi, "right"))
    if i1 - i0 < 2:
        spans = ", ".join(f"{k!r} {t[0]:g}..{t[-1]:g} s" for (k, *_), t in zip(series, arrays))
        raise error(
            path,
            f"the channels have no common time span ({spans})",
            field="channels",
            valid="channels recorded over the same time",
        )
    grid = tr[i0:i1]
    columns, notes = {}, []
    for (key, v, tm, _), t, rate_i in zip(series, arrays, rates):
        if _same(tm, v.size, ref_timing, tr.size, times):
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
    return grid, columns, notes, _uniform(path, grid, ref_label)


def assemble(path, fh, size: int, found) -> SignalTable:
    """The table of a :class:`~.survey.Survey`: its planned samples read from the open file ``fh``
    (``size`` bytes), then checked, made SI and put on one time base (module docstring).

    Raises
    ------
    ModelError
        A non-finite sample, times that do not increase or are not uniform, no common span, a plan
        reaching beyond the file.
    plan.Disagrees
        A plan's samples differ from the library's: the caller reads the file through it instead.
    """
    everything = [c.samples for c in found.columns] + list(found.times.values())
    plans = {id(s): (s.label, s.data) for s in everything if isinstance(s.data, Planned)}
    arrays, finite = read_planned(fh, size, path, plans) if plans else ({}, set())
    taken: set = set()
    times = {label: _values(path, s, arrays, finite, taken) for label, s in found.times.items()}
    series, units = [], {}
    for c in found.columns:
        series.append((c.key, _values(path, c.samples, arrays, finite, taken), c.timing, c.time_label))
        units[c.key] = c.unit
    arrays.clear()
    time, columns, notes, rate_hz = _one_time_base(path, series, times)
    return SignalTable(
        time=time,
        columns=columns,
        units=units,
        rate_hz=rate_hz,
        source=str(path),
        notes=tuple(notes),
    )
