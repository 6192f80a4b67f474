"""Frequency-domain decomposition (FDD, Brincker, Zhang & Andersen 2001): the cross-check of SSI's modes.

The output spectral density matrix G(f) (l × l, Hermitian) of a lightly damped structure driven by
broadband noise is, near a mode, dominated by that mode: G(f) ≈ s₁(f)·u₁u₁ᴴ with u₁ the mode's shape. So
the first singular value s₁ of G peaks at each natural frequency and its singular vector u₁ there is
the shape. :func:`spectral_matrix` estimates G by Welch averaging (Hann, half overlap, a block of
segments at a time); :func:`fdd_peak` reads s₁'s peak and u₁ near a frequency. The peak's frequency
is the damped one, f·√(1 − ζ²) (within 3·10⁻⁵ of f for ζ < 0.8 %), read to a fraction of a bin.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.fft
import scipy.signal

from .peaks import log_parabola

__all__ = ["fdd_peak", "segment_samples", "spectral_matrix"]

# Segments transformed at a time (bounded memory whatever the record's length).
_BLOCK_VALUES = 1 << 20


def spectral_matrix(y: np.ndarray, rate_hz: float, nper: int) -> tuple[np.ndarray, np.ndarray]:
    """The Welch estimate of the output spectral density matrix, up to a constant factor.

    Parameters
    ----------
    y : ndarray, shape (l, N)
        The channels (rows).
    rate_hz : float
        Their sampling rate, Hz.
    nper : int
        Samples per segment (<= N); segments overlap by half, each Hann-windowed.

    Returns
    -------
    frequencies : ndarray, shape (nper // 2 + 1,)
        Hz.
    g : ndarray, shape (nper // 2 + 1, l, l), complex
        Σ over segments of X(f)·X(f)ᴴ: Hermitian, positive semi-definite per frequency.
    """
    l, n = y.shape
    step = max(1, nper // 2)
    win = scipy.signal.get_window("hann", nper, fftbins=True)
    frames = np.lib.stride_tricks.sliding_window_view(y, nper, axis=1)[:, ::step]  # (l, segments, nper)
    g = np.zeros((nper // 2 + 1, l, l), dtype=complex)
    rows = max(1, _BLOCK_VALUES // (l * nper))
    for first in range(0, frames.shape[1], rows):
        block = frames[:, first : first + rows]
        spec = scipy.fft.rfft((block - block.mean(axis=2, keepdims=True)) * win, axis=2)  # (l, s, f)
        g += np.matmul(spec.transpose(2, 0, 1), spec.conj().transpose(2, 1, 0))  # Σ_s X Xᴴ per f
    return scipy.fft.rfftfreq(nper, 1.0 / rate_hz), g


def fdd_peak(frequencies: np.ndarray, g: np.ndarray, near_hz: float, tolerance: float):
    """The first singular value's peak within ``tolerance`` (relative) of ``near_hz``.

    Parameters
    ----------
    frequencies, g
        :func:`spectral_matrix`'s.
    near_hz : float
        Where to look, Hz.
    tolerance : float
        The window's half-width, relative to ``near_hz`` (at least a bin is searched either side).

    Returns
    -------
    (float, ndarray) or None
        The peak's frequency (Hz, interpolated on the log of s₁ between bins) and the first singular
        vector at its bin (complex, unit norm); None where s₁ has no maximum inside the window (it
        rises to an edge: no peak of its own there).
    """
    df = frequencies[1] - frequencies[0]
    half = max(tolerance * near_hz, 2 * df)
    inside = np.flatnonzero(np.abs(frequencies - near_hz) <= half)
    if inside.size < 3:
        return None
    lo, hi = max(0, inside[0] - 1), min(frequencies.size - 1, inside[-1] + 1)
    u, s, _ = np.linalg.svd(g[lo : hi + 1], hermitian=True)  # per bin, s sorted from the largest
    s1 = s[:, 0]
    inner = inside - lo
    k = int(inner[np.argmax(s1[inner])])
    if k in (inner[0], inner[-1]):
        return None  # the largest value sits at the window's edge: s₁ rises beyond it
    shift, _ = log_parabola(s1[k - 1], s1[k], s1[k + 1])
    return float(frequencies[lo + k] + float(shift) * df), u[k, :, 0]


def segment_samples(rate_hz: float, modes: list[tuple[float, float]], n: int) -> int:
    """Samples per Welch segment at ``rate_hz``: a resolution of a quarter of the narrowest half-power
    band (2·ζ·f of each (f Hz, ζ) in ``modes``), so each peak spans several bins, but at most an eighth
    of the record's ``n`` samples (15 averages or more with half overlap)."""
    width = min(2 * max(z, 1e-4) * f for f, z in modes)  # Hz
    nper = int(math.ceil(4 * rate_hz / width))
    return int(max(16, min(nper, n // 8)))
