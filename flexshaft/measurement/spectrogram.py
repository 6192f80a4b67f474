"""Spectrograms of run-ups and coast-downs: amplitude against time and frequency, with order lines.

Each column is the amplitude-correct spectrum (see :mod:`flexshaft.measurement.spectrum`) of one
segment. On a run-up the eigenfrequencies stay as horizontal lines while the orders of the speed
(``k·n/60`` Hz) fan out; where an order line crosses an eigenfrequency the drivetrain resonates.
:func:`ridge` follows the largest amplitude in a frequency band from column to column.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft

from ..errors import ModelError
from ..system.threads import follows_policy
from ..validation import check_choice, check_real, check_type
from .checks import MAX_SIGNAL, as_signal, check_orders, check_overlap, check_rate, segment_samples
from .peaks import log_parabola
from .spectrum import DETRENDS, WINDOWS, frame_amplitudes
from .spectrum import window as window_samples

__all__ = ["Spectrogram", "order_lines", "ridge", "spectrogram"]


@dataclass(frozen=True)
class Spectrogram:
    """Amplitude spectra of successive segments.

    Attributes
    ----------
    times_s : ndarray, shape (t,)
        The centre of each segment, s from the first sample (``(start + nper/2) / rate``, as
        ``scipy.signal.spectrogram`` gives).
    frequencies_hz : ndarray, shape (f,)
        Bin frequencies, 0 to Nyquist, Hz.
    amplitude : ndarray, shape (f, t)
        Single-sided peak amplitude per bin and segment, in the signal's unit.
    speed_rpm : ndarray, shape (t,), or None
        The mean speed over each segment's samples, rpm, when a speed was given.
    window : str
        The window used.
    segment_s : float
        The segment length, s.
    resolution_hz : float
        The bin spacing, Hz.
    """

    times_s: np.ndarray
    frequencies_hz: np.ndarray
    amplitude: np.ndarray
    speed_rpm: np.ndarray | None
    window: str
    segment_s: float
    resolution_hz: float

    def to_dict(self) -> dict:
        """A JSON-ready document with its units (``amplitude`` as rows per frequency)."""
        return {
            "units": {
                "time": "s",
                "frequency": "Hz",
                "amplitude": "signal unit (single-sided peak)",
                "speed": "rpm",
            },
            "window": self.window,
            "segment_s": self.segment_s,
            "resolution_hz": self.resolution_hz,
            "times_s": self.times_s.tolist(),
            "frequencies_hz": self.frequencies_hz.tolist(),
            "speed_rpm": None if self.speed_rpm is None else self.speed_rpm.tolist(),
            "amplitude": self.amplitude.tolist(),
        }


@follows_policy
def spectrogram(
    x,
    rate,
    *,
    segment,
    overlap=0.5,
    window: str = "hann",
    speed=None,
    detrend: str = "mean",
) -> Spectrogram:
    """The amplitude spectrogram of ``x`` sampled at ``rate``.

    Parameters
    ----------
    x : array_like, shape (n,)
        The samples, any unit; finite, n >= 2.
    rate : float
        Sampling rate, Hz (> 0).
    segment : float
        Segment length, s (rounded to whole samples; 8 samples to the whole record). The
        resolution is ``1 / segment``: a run-up wants it short enough that the speed changes
        little within one.
    overlap : float
        Overlap of successive segments, a fraction in [0, 1) (default 0.5).
    window : str
        ``"hann"`` (default), ``"flattop"`` or ``"rect"``.
    speed : array_like, shape (n,), optional
        The shaft speed at each sample, rpm; its mean over each segment is stored.
    detrend : str
        ``"mean"`` (default), ``"linear"`` or ``"none"``, per segment.

    Returns
    -------
    Spectrogram
        Segments that fit entirely in the record, as ``scipy.signal.spectrogram`` takes them.

    Notes
    -----
    The segments are a strided view of ``x`` transformed a block of about 2^18 samples at a
    time, so the memory beyond the result is a few MB whatever the record's length (a 10-minute
    record at 1.6 kHz takes ~0.1 s).

    Raises
    ------
    ModelError
        As :func:`~flexshaft.measurement.spectrum.spectrum`; a speed of another length or not finite.
    """
    rate = check_rate(rate)
    x = as_signal(x, "x")
    check_choice(window, "window", WINDOWS)
    check_choice(detrend, "detrend", DETRENDS)
    overlap = check_overlap(overlap)
    if segment is None:
        raise ModelError("is required", field="segment", valid="a segment length in seconds", has_value=True)
    n = x.size
    nper = segment_samples(segment, rate, n)
    step = max(1, nper - int(round(overlap * nper)))
    count = (n - nper) // step + 1
    starts = np.arange(count) * step
    if speed is not None:
        speed = as_signal(speed, "speed", "rpm")
        if speed.size != n:
            raise ModelError(
                f"has {speed.size} samples but x has {n}",
                field="speed",
                valid="one speed (rpm) per sample of x",
            )
        total = np.concatenate(([0.0], np.cumsum(speed)))
        speed = (total[starts + nper] - total[starts]) / nper
    win = window_samples(window, nper)
    # filled column block by column block; rows of the (t, f) buffer are contiguous for each block
    out = np.empty((count, nper // 2 + 1))
    for first, amp in frame_amplitudes(x, nper, step, win, detrend):
        out[first : first + amp.shape[0]] = amp
    return Spectrogram(
        times_s=(starts + nper / 2) / rate,
        frequencies_hz=scipy.fft.rfftfreq(nper, 1.0 / rate),
        amplitude=out.T,
        speed_rpm=speed,
        window=window,
        segment_s=nper / rate,
        resolution_hz=rate / nper,
    )


def order_lines(speed_rpm, orders) -> dict[float, np.ndarray]:
    """The frequencies of engine/shaft orders at the given speeds.

    Parameters
    ----------
    speed_rpm : float or array_like
        Shaft speed(s), rpm (a negative speed, the other direction, gives the same frequencies).
    orders : iterable of float
        The orders k (> 0): 1 per revolution, 2 twice per revolution, 0.5 every second one.

    Returns
    -------
    dict
        ``{k: |k·n| / 60}`` in Hz, one array (shape of ``speed_rpm``) per order, keyed by
        ``float(k)`` (so ``lines[2]`` and ``lines[2.0]`` are the same entry).
    """
    try:
        speed = np.asarray(speed_rpm, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(
            "is not numbers", field="speed_rpm", valid="finite speeds in rpm", has_value=False
        ) from None
    with np.errstate(invalid="ignore"):
        inside = np.abs(speed) <= MAX_SIGNAL  # False for NaN and ±inf as well
    if speed.size == 0 or not np.all(inside):
        raise ModelError(
            f"is empty, not finite or beyond ±{MAX_SIGNAL:g} rpm",
            field="speed_rpm",
            valid=f"finite speeds within ±{MAX_SIGNAL:g} rpm",
        )
    # orders up to MAX_ORDER, speeds up to MAX_SIGNAL: every line stays finite
    return {k: np.abs(k * speed) / 60.0 for k in check_orders(orders)}


@follows_policy
def ridge(spec: Spectrogram, f_lo, f_hi) -> np.ndarray:
    """The frequency of the largest amplitude in ``[f_lo, f_hi]``, column by column.

    Parameters
    ----------
    spec : Spectrogram
        The spectrogram.
    f_lo, f_hi : float
        The band, Hz, ``0 <= f_lo < f_hi``; it must hold at least one bin.

    Returns
    -------
    ndarray, shape (t,)
        Per segment, the frequency of the band's largest bin, refined by the parabola through the
        log-amplitudes of it and its neighbours (also outside the band; none at DC and Nyquist);
        NaN in a column of zeros.
        At the band's edge, where the largest bin is not a local maximum, the refinement is capped
        at half a bin.
    """
    check_type(spec, Spectrogram, "spectrogram", "a Spectrogram")
    f_lo = check_real(f_lo, "f_lo", "Hz", lo=0.0)
    f_hi = check_real(f_hi, "f_hi", "Hz", lo=0.0)
    freqs, amp = spec.frequencies_hz, spec.amplitude
    inside = np.flatnonzero((freqs >= f_lo) & (freqs <= f_hi))
    if not f_lo < f_hi or inside.size == 0:
        raise ModelError(
            f"[{f_lo:g}, {f_hi:g}] Hz holds no bin",
            field="f_hi",
            value=f_hi,
            unit="Hz",
            valid=f"f_lo < f_hi, a band holding at least one of the bins from 0 to {freqs[-1]:g} Hz"
            f" spaced {spec.resolution_hz:g} Hz",
        )
    cols = np.arange(amp.shape[1])
    k = inside[0] + np.argmax(amp[inside], axis=0)
    # neighbours, also outside the band; at the spectrum's ends the bin itself (offset 0 then)
    left = amp[np.maximum(k - 1, 0), cols]
    right = amp[np.minimum(k + 1, freqs.size - 1), cols]
    mid = amp[k, cols]
    offset, _ = log_parabola(left, mid, right)
    offset = np.where((k == 0) | (k == freqs.size - 1), 0.0, offset)
    out = freqs[k] + offset * spec.resolution_hz
    return np.where(mid > 0, out, np.nan)
