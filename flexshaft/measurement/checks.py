"""Checks shared by the signal modules: a signal, its sampling, a segment, a band.

Each returns the cleaned value or raises :class:`~flexshaft.errors.ModelError` naming the field,
the value, its unit and what is valid, so that no numpy or scipy exception reaches the user.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import ModelError
from ..validation import check_real

__all__ = [
    "MAX_ORDER",
    "MAX_SIGNAL",
    "MIN_SEGMENT_SAMPLES",
    "UNIFORM_TOLERANCE",
    "uniform_rate",
    "as_signal",
    "bare_name",
    "check_band",
    "check_not_time",
    "check_orders",
    "check_overlap",
    "check_rate",
    "non_finite_text",
    "parse_orders",
    "rate_from_times",
    "segment_samples",
]

#: The fewest samples a segment may have: below this a spectrum has too few bins to mean anything.
MIN_SEGMENT_SAMPLES = 8
#: Largest relative deviation of a time step from the mean step for a record to count as uniform.
UNIFORM_TOLERANCE = 1e-6
#: The largest magnitude a sample may have, in its SI unit. Far beyond any measured or simulated
#: drivetrain signal (torques stay below 1e8 N·m), and low enough that a spectrum's sums over the
#: record and Welch's squared amplitudes (up to (2·n·1e100)² for n samples) stay in floating point,
#: which ends at 1.8e308.
MAX_SIGNAL = 1e100
#: The highest excitation order, per revolution: above every gear-mesh, blade-pass or inverter
#: order a drivetrain has, even counted on the slowest shaft of a multi-stage gearbox (a few
#: thousand); it keeps the order lines k·n/60 finite at any speed below 1e300 rpm.
MAX_ORDER = 1e6


def non_finite_text(arr: np.ndarray) -> str | None:
    """Where a signal first leaves the finite numbers, for a message; None when every sample is finite.

    Parameters
    ----------
    arr : numpy.ndarray
        Float samples (any unit).

    Returns
    -------
    str or None
        ``"sample i is x (n non-finite samples in all)"`` for the first NaN or ±inf sample.
    """
    bad = ~np.isfinite(arr)
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    return f"sample {i} is {float(arr[i])!r} ({int(bad.sum())} non-finite samples in all)"


def as_signal(x, field: str = "x", unit: str = "", *, min_samples: int = 2) -> np.ndarray:
    """``x`` as a 1-D float array of finite samples, at least ``min_samples`` long.

    Parameters
    ----------
    x : array_like
        The samples.
    field : str
        Its name, for the message.
    unit : str
        Its unit, for the message (``""`` for the signal's own unit).
    min_samples : int
        The fewest samples accepted.
    """
    valid = f"a 1-D sequence of at least {min_samples} finite real numbers" + (f" ({unit})" if unit else "")
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError):  # ragged nested sequences
        raise ModelError("not a sequence of numbers", field=field, valid=valid) from None
    if arr.dtype.kind not in "biuf":
        # complex, strings, objects: a signal here is real; bool counts as 0/1, which is harmless
        raise ModelError(f"not real numbers (dtype {arr.dtype})", field=field, valid=valid)
    if arr.ndim != 1:
        raise ModelError(f"has shape {arr.shape}, not one dimension", field=field, valid=valid)
    if arr.size < min_samples:
        raise ModelError(f"has {arr.size} samples", field=field, valid=valid)
    arr = arr.astype(float, copy=False)
    with np.errstate(invalid="ignore"):
        inside = np.abs(arr) <= MAX_SIGNAL  # one pass: False for NaN and ±inf too
    if not inside.all():
        text = non_finite_text(arr)
        if text is not None:
            raise ModelError(text, field=field, valid=valid)
        i = int(np.argmin(inside))
        raise ModelError(
            f"sample {i} is {float(arr[i])!r}, beyond ±{MAX_SIGNAL:g}",
            field=field,
            valid=f"samples within ±{MAX_SIGNAL:g}"
            + (f" {unit}" if unit else "")
            + " (larger ones leave floating point in a spectrum's sums)",
        )
    return arr


def check_orders(orders, field: str = "orders") -> tuple[float, ...]:
    """Excitation orders (per revolution) as a non-empty tuple of finite numbers in (0, MAX_ORDER].

    Parameters
    ----------
    orders : iterable of float
        The orders k: 1 per revolution, 2 twice per revolution, 0.5 every second one.
    field : str
        Its name, for the message (``"--orders"`` on the command line).
    """
    valid = f"one or more orders > 0 and <= {MAX_ORDER:g} per revolution, e.g. 1,2,6"
    if isinstance(orders, str) or not hasattr(orders, "__iter__"):
        orders = [orders]
    out = []
    for k in orders:
        if isinstance(k, bool) or not isinstance(k, (int, float, np.integer, np.floating)):
            raise ModelError("not a number", field=field, value=k, valid=valid, has_value=True)
        k = float(k)
        if not (np.isfinite(k) and 0.0 < k <= MAX_ORDER):
            why = "not finite" if not np.isfinite(k) else "not a positive order" if k <= 0 else "too high"
            raise ModelError(why, field=field, value=k, valid=valid)
        out.append(k)
    if not out:
        raise ModelError("is empty", field=field, valid=valid, has_value=False)
    from ..system.limits import check_ceiling

    check_ceiling("orders", len(out), field=field)  # the count: each order is a line to track and draw
    return tuple(out)


def parse_orders(text: str, field: str = "--orders") -> tuple[float, ...]:
    """Orders written as on the command line, ``"1,2,6"``: each a number > 0 (see :func:`check_orders`).

    An empty item (``"1,,2"``, a trailing comma) is refused too: it is a typing slip, never an order.
    """
    valid = f"comma-separated orders > 0 and <= {MAX_ORDER:g} per revolution, e.g. 1,2,6"
    items = [item.strip() for item in str(text).split(",")]
    values = []
    for item in items:
        try:
            values.append(float(item))
        except ValueError:
            what = "an empty item" if not item else f"{item!r} is not a number"
            raise ModelError(what, field=field, value=text, valid=valid) from None
    return check_orders(values, field)


def bare_name(column: str) -> str:
    """A signal file's column name without its unit: ``"torque [N·m]"`` -> ``"torque"``."""
    return re.sub(r"\s*\[[^\[\]]*\]\s*$", "", str(column)).strip()


def check_not_time(column: str, time_column: str, field: str = "--column") -> str:
    """``column``, unless it names the time column (by name or by its header): time is no signal.

    Column names are distinct in a signal file, so two names that agree without their units name
    the same column. Its spectrum would be that of a ramp, whose peaks and damping mean nothing.
    """
    if bare_name(column) == bare_name(time_column):
        raise ModelError(
            "is the time column, not a signal",
            field=field,
            value=column,
            valid="a signal column (torque, speed, angle); the time is --time-column",
        )
    return column


def check_rate(rate) -> float:
    """The sampling rate in Hz: a finite number > 0."""
    return check_real(rate, "rate", "Hz", lo=0.0, lo_open=True)


def rate_from_times(t, n: int) -> tuple[np.ndarray, float]:
    """The time stamps ``t`` (s) of ``n`` samples, checked uniform, and their sampling rate (Hz).

    A spectrum needs equal steps: every step must lie within :data:`UNIFORM_TOLERANCE` (relative)
    of the mean step, and the times must increase.
    """
    t = as_signal(t, "t", "s")
    if t.size != n:
        raise ModelError(
            f"has {t.size} samples but the signal x has {n}", field="t", valid="one time per sample of x"
        )
    return t, uniform_rate(t, "t")


def segment_samples(segment, rate: float, n: int) -> int:
    """The samples in a segment of ``segment`` seconds of a record of ``n`` samples at ``rate`` Hz."""
    seconds = check_real(segment, "segment", "s", lo=0.0, lo_open=True)
    record = n / rate
    valid = (
        f"a duration from {MIN_SEGMENT_SAMPLES / rate:g} s ({MIN_SEGMENT_SAMPLES} samples)"
        f" to {record:g} s (the record, {n} samples)"
    )
    nper = int(round(seconds * rate))
    if nper > n:
        raise ModelError("is longer than the record", field="segment", value=seconds, unit="s", valid=valid)
    if nper < MIN_SEGMENT_SAMPLES:
        raise ModelError(
            f"holds {nper} samples at {rate:g} Hz", field="segment", value=seconds, unit="s", valid=valid
        )
    return nper


def check_overlap(overlap) -> float:
    """The fraction by which segments overlap: in [0, 1)."""
    return check_real(overlap, "overlap", "", lo=0.0, hi=1.0, hi_open=True)


def check_band(band, rate: float) -> tuple[float, float]:
    """A frequency band ``(f1, f2)`` in Hz with 0 < f1 < f2 < the Nyquist frequency ``rate / 2``."""
    nyquist = rate / 2.0
    valid = f"two frequencies (f1, f2) with 0 < f1 < f2 < {nyquist:g} Hz (the Nyquist frequency)"
    try:
        f1, f2 = band
    except (TypeError, ValueError):
        raise ModelError("is not a pair of frequencies", field="band", value=band, valid=valid) from None
    f1 = check_real(f1, "band", "Hz", lo=0.0, lo_open=True, hi=nyquist, hi_open=True)
    f2 = check_real(f2, "band", "Hz", lo=0.0, lo_open=True, hi=nyquist, hi_open=True)
    if not f1 < f2:
        raise ModelError("is empty (f1 >= f2)", field="band", value=(f1, f2), unit="Hz", valid=valid)
    return f1, f2


def uniform_rate(t: np.ndarray, field: str = "t") -> float:
    """The sampling rate (Hz) of increasing times ``t`` (s) whose steps are all within
    :data:`UNIFORM_TOLERANCE` (relative) of the mean step; an error names ``field`` otherwise."""
    dt = np.diff(t)
    if not np.all(dt > 0):
        i = int(np.argmax(dt <= 0))
        raise ModelError(
            f"does not increase at sample {i + 1} ({float(t[i])!r} s then {float(t[i + 1])!r} s)",
            field=field,
            valid="strictly increasing times (s)",
        )
    step = (t[-1] - t[0]) / (t.size - 1)
    dev = np.abs(dt - step)
    if dev.max() > UNIFORM_TOLERANCE * step:
        i = int(np.argmax(dev))
        raise ModelError(
            f"is not uniformly sampled: step {float(dt[i])!r} s at sample {i + 1}, "
            f"mean step {float(step)!r} s",
            field=field,
            valid=f"equal time steps (within {UNIFORM_TOLERANCE:g} relative); resample the record first",
        )
    return 1.0 / step
