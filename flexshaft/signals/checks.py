"""Checks shared by the signal modules: a signal, its sampling, a segment, a band.

Each returns the cleaned value or raises :class:`~flexshaft.errors.ModelError` naming the field,
the value, its unit and what is valid, so that no numpy or scipy exception reaches the user.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..validation import check_real

__all__ = [
    "MIN_SEGMENT_SAMPLES",
    "UNIFORM_TOLERANCE",
    "uniform_rate",
    "as_signal",
    "check_band",
    "check_overlap",
    "check_rate",
    "rate_from_times",
    "segment_samples",
]

#: The fewest samples a segment may have: below this a spectrum has too few bins to mean anything.
MIN_SEGMENT_SAMPLES = 8
#: Largest relative deviation of a time step from the mean step for a record to count as uniform.
UNIFORM_TOLERANCE = 1e-6


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
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise ModelError(
            f"sample {i} is {arr[i]!r} ({int(bad.sum())} non-finite samples in all)", field=field, valid=valid
        )
    return arr


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
            f"does not increase at sample {i + 1} ({t[i]!r} s then {t[i + 1]!r} s)",
            field=field,
            valid="strictly increasing times (s)",
        )
    step = (t[-1] - t[0]) / (t.size - 1)
    dev = np.abs(dt - step)
    if dev.max() > UNIFORM_TOLERANCE * step:
        i = int(np.argmax(dev))
        raise ModelError(
            f"is not uniformly sampled: step {dt[i]!r} s at sample {i + 1}, mean step {step!r} s",
            field=field,
            valid=f"equal time steps (within {UNIFORM_TOLERANCE:g} relative); resample the record first",
        )
    return 1.0 / step
