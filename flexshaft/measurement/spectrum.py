"""Amplitude-correct spectra of sampled signals: one FFT over the record, or Welch averaging.

The amplitude is the single-sided peak amplitude in the signal's own unit: a sinusoid
``A·sin(2πft)`` whose frequency lies on a bin reads ``A`` at that bin, whatever the window. To get
there the DFT is divided by the window's sum (its coherent gain times the length) and every bin but
DC and Nyquist is doubled (they have no negative-frequency twin). With Welch averaging the squared
amplitudes of the segments are averaged and the root taken, so a stationary tone keeps its amplitude
and noise averages down to its RMS level per bin.

Windows: ``"hann"`` (periodic, as ``scipy.signal.get_window("hann", n)``; the default: low leakage,
frequency of a tone to ~0.02 bin after interpolation), ``"flattop"`` (scipy's; amplitude of a tone
within 0.1 % at its largest bin, wide main lobe), ``"rect"`` (no taper; for transients that die out in
the record, and for exact Parseval checks).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import scipy.fft
import scipy.signal

from ..system.threads import follows_policy
from ..validation import check_choice, check_int
from .checks import as_signal, check_overlap, check_rate, segment_samples
from .peaks import find_peaks

__all__ = ["WINDOWS", "DETRENDS", "Spectrum", "frame_amplitudes", "spectrum", "window"]

#: The window names :func:`window` knows.
WINDOWS = ("hann", "rect", "flattop")
#: What may be removed from each segment before the FFT.
DETRENDS = ("mean", "linear", "none")

# Samples handled per block of segments: the segments of a long record are transformed a block at a
# time (a strided view, copied only block-wise), so memory stays bounded whatever the record length.
BLOCK_SAMPLES = 1 << 18


def window(name: str, n: int) -> np.ndarray:
    """The window ``name`` of ``n`` samples.

    Parameters
    ----------
    name : str
        ``"hann"`` (periodic, DFT-even: what ``scipy.signal.get_window("hann", n)`` gives),
        ``"flattop"`` (``scipy.signal.get_window("flattop", n)``) or ``"rect"`` (all ones).
    n : int
        Its length in samples, >= 1.

    Returns
    -------
    ndarray, shape (n,)
    """
    check_choice(name, "window", WINDOWS)
    return _window(name, check_int(n, "n", lo=1))


def _window(name: str, n: int) -> np.ndarray:
    if name == "rect":
        return np.ones(n)
    # periodic (fftbins=True): the window of a segment that repeats, the one spectral analysis wants
    return scipy.signal.get_window(name, n, fftbins=True)


@dataclass(frozen=True)
class Spectrum:
    """A single-sided amplitude spectrum.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (f,)
        Bin frequencies from 0 to the Nyquist frequency (included when the segment is even), Hz.
    amplitude : ndarray, shape (f,)
        Single-sided peak amplitude per bin, in the signal's unit (Welch: RMS over the segments of
        each bin's amplitude).
    window : str
        The window used.
    segment_s : float
        The segment length, s (the record's, without Welch averaging).
    averages : int
        How many segments were averaged (1: a single FFT).
    resolution_hz : float
        The bin spacing, Hz: ``rate / samples per segment``.
    enbw_hz : float
        The window's equivalent noise bandwidth, Hz: ``rate · Σw² / (Σw)²`` (1.5 bins for Hann).
    rate_hz : float
        The sampling rate, Hz.
    """

    frequencies_hz: np.ndarray
    amplitude: np.ndarray
    window: str
    segment_s: float
    averages: int
    resolution_hz: float
    enbw_hz: float
    rate_hz: float

    def peaks(self, count: int | None = None, **options) -> list:
        """The peaks of this spectrum: :func:`flexshaft.find_peaks` ``(self, count=count, ...)``."""
        return find_peaks(self, count=count, **options)

    def to_dict(self) -> dict:
        """A JSON-ready document with its units."""
        return {
            "units": {"frequency": "Hz", "amplitude": "signal unit (single-sided peak)", "segment": "s"},
            "window": self.window,
            "segment_s": self.segment_s,
            "averages": self.averages,
            "resolution_hz": self.resolution_hz,
            "enbw_hz": self.enbw_hz,
            "rate_hz": self.rate_hz,
            "frequencies_hz": self.frequencies_hz.tolist(),
            "amplitude": self.amplitude.tolist(),
        }


def frame_amplitudes(
    x: np.ndarray, nper: int, step: int, win: np.ndarray, detrend: str
) -> Iterator[tuple[int, np.ndarray]]:
    """Amplitude spectra of the segments of ``x``, a block of segments at a time.

    Segment ``j`` is ``x[j·step : j·step + nper]``; the segments that fit entirely are used (as in
    ``scipy.signal.welch``). Each block is ``(index of its first segment, amplitudes of shape
    (segments in the block, nper // 2 + 1))``, scaled as the module docstring says. ``x``, ``win``
    and the arguments are trusted (checked by the callers).
    """
    frames = np.lib.stride_tricks.sliding_window_view(x, nper)[::step]  # a view: nothing copied yet
    scale = np.full(nper // 2 + 1, 2.0 / win.sum())
    scale[0] /= 2.0  # DC has no negative-frequency twin
    if nper % 2 == 0:
        scale[-1] /= 2.0  # nor has the Nyquist bin of an even segment
    if detrend == "linear":
        ramp = np.arange(nper) - (nper - 1) / 2.0
        ramp_norm = ramp @ ramp
    rows = max(1, BLOCK_SAMPLES // nper)
    for first in range(0, frames.shape[0], rows):
        block = frames[first : first + rows]
        if detrend == "mean":
            block = block - block.mean(axis=1, keepdims=True)
        elif detrend == "linear":
            block = block - block.mean(axis=1, keepdims=True)
            block = block - np.outer(block @ ramp / ramp_norm, ramp)
        spec = scipy.fft.rfft(block * win, axis=1)
        amp = np.abs(spec)
        amp *= scale
        yield first, amp


@follows_policy
def spectrum(
    x,
    rate,
    *,
    window: str = "hann",
    segment=None,
    overlap=0.5,
    detrend: str = "mean",
) -> Spectrum:
    """The single-sided amplitude spectrum of ``x`` sampled at ``rate``.

    Parameters
    ----------
    x : array_like, shape (n,)
        The samples, in any unit (the amplitude comes out in it); finite, n >= 2.
    rate : float
        Sampling rate, Hz (> 0).
    window : str
        ``"hann"`` (default), ``"flattop"`` or ``"rect"``; see :func:`window`.
    segment : float, optional
        Segment length in seconds for Welch averaging (rounded to whole samples; at least
        8 samples, at most the record). ``None`` (default): one FFT over the whole record.
    overlap : float
        Overlap of successive segments, a fraction in [0, 1) (default 0.5); unused without a
        segment.
    detrend : str
        Removed from each segment before windowing: ``"mean"`` (default; a static torque would
        otherwise leak from DC into the low bins), ``"linear"`` or ``"none"``.

    Returns
    -------
    Spectrum
        A sinusoid ``A·sin(2πft)`` on a bin reads ``A`` there; see the module docstring.

    Raises
    ------
    ModelError
        A non-finite, empty or too short signal, a rate <= 0, a segment outside the record or
        shorter than 8 samples, an overlap outside [0, 1), an unknown window or detrend.
    """
    rate = check_rate(rate)
    x = as_signal(x, "x")
    check_choice(window, "window", WINDOWS)
    check_choice(detrend, "detrend", DETRENDS)
    overlap = check_overlap(overlap)
    n = x.size
    if segment is None:
        nper, step = n, n
    else:
        nper = segment_samples(segment, rate, n)
        # at least one sample forward, however close to 1 the overlap
        step = max(1, nper - int(round(overlap * nper)))
    win = _window(window, nper)
    averages = (n - nper) // step + 1
    power = np.zeros(nper // 2 + 1)
    for _, amp in frame_amplitudes(x, nper, step, win, detrend):
        power += np.einsum("ij,ij->j", amp, amp)
    return Spectrum(
        frequencies_hz=scipy.fft.rfftfreq(nper, 1.0 / rate),
        amplitude=np.sqrt(power / averages),
        window=window,
        segment_s=nper / rate,
        averages=averages,
        resolution_hz=rate / nper,
        enbw_hz=rate * float(win @ win) / float(win.sum()) ** 2,
        rate_hz=rate,
    )
