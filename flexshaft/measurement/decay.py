"""The damping of a free decay: the logarithmic decrement in time, the half-power bandwidth in frequency.

- :func:`log_decrement`: the slope of ln(amplitude) over the cycles of a (band-passed) free decay;
- :func:`decay_damping`: the half-power bandwidth of the spectrum of the whole transient, with a
  window made for a transient (rectangular or exponential, never Hann: see there).

The peaks of a spectrum and their half-power damping are :mod:`.peaks`'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.fft
import scipy.signal

from ..errors import ModelError
from ..system.threads import follows_policy
from ..validation import check_choice, check_real
from .checks import as_signal, check_band, rate_from_times
from .peaks import Peak, describe_peak

__all__ = ["Decay", "DecayPeak", "decay_damping", "log_decrement"]

#: Cycles of a free decay smaller than this fraction of the largest are noise floor, not decay.
DECAY_FLOOR = 0.02
#: Zero-crossing hysteresis, as a fraction of the largest amplitude: noise on a slow crossing near
#: the floor is not counted as extra cycles.
CROSSING_HYSTERESIS = 0.01
#: The fewest cycles a log-decrement fit accepts.
MIN_CYCLES = 3
#: Scatter of ln(amplitude) about the fitted line above which a note says the decay is not one mode.
MAX_LOG_SCATTER = 0.05
#: Butterworth order of the band-pass of :func:`log_decrement` (doubled by the forward-backward pass).
BAND_ORDER = 4
#: A free decay's record is zero-padded to this many times its length in :func:`decay_damping`...
DECAY_PADDING = 8
#: ... but to no more samples than this (the FFT's memory: 2^23 samples, ~200 MB with its output).
MAX_PADDED = 1 << 23
#: The last fraction of a record checked for a decay that has not died out (rectangular window).
TAIL_FRACTION = 0.1
#: Envelope left in that tail, relative to the largest, above which a note warns of leakage.
TAIL_LIMIT = 0.01
#: The exponential window's default time constant, as a fraction of the record: its end is e^-6 (0.25 %).
DEFAULT_TAU_FRACTION = 1.0 / 6.0
DECAY_WINDOWS = ("rect", "exponential")


@dataclass(frozen=True)
class Decay:
    """The damping of a free decay from its envelope (logarithmic decrement).

    Attributes
    ----------
    damping_ratio : float
        ``σ / √(σ² + ω_d²)``.
    frequency_hz : float
        The damped frequency ``ω_d / 2π`` used: from the cycles' zero crossings, or as given, Hz.
    decay_rate : float
        σ, the envelope's exponential decay rate ``e^(−σt)``, 1/s (``ξ·ω_n``).
    cycles : int
        How many cycles the fit used.
    start_s, end_s : float
        The time span of those cycles, s.
    method : str
        How the amplitudes were found and fitted (and the band-pass, if any).
    notes : tuple of str
        What limits the result, for a person to read.
    """

    damping_ratio: float
    frequency_hz: float
    decay_rate: float
    cycles: int
    start_s: float
    end_s: float
    method: str
    notes: tuple[str, ...] = ()


def _band_pass(y: np.ndarray, rate: float, band) -> tuple[np.ndarray, int, float, str]:
    """Zero-phase Butterworth band-pass; returns the output, the samples to skip at each end, the
    filter's slowest decay rate (1/s) and a description."""
    f1, f2 = check_band(band, rate)
    sos = scipy.signal.butter(BAND_ORDER, [f1, f2], btype="bandpass", fs=rate, output="sos")
    # The filter's own ringing decays as its slowest pole: exp(-r t). Its start (forward pass) and end
    # (backward pass) transients have fallen to 1e-4 after ln(1e4)/r seconds, which are skipped.
    # the poles are the roots of each section's denominator (sos2zpk also factors the numerators,
    # whose narrow-band coefficients it calls "badly conditioned" in a warning the user would see)
    poles = np.concatenate([np.roots(section[3:]) for section in sos])
    slowest = float(-np.log(np.abs(poles)).max() * rate)
    skip = int(math.ceil(math.log(1e4) / slowest * rate))
    padlen = 3 * (2 * len(sos) + 1)  # sosfiltfilt's default edge padding
    if y.size <= max(padlen, 2 * skip + 4 * int(math.ceil(rate / f1))):
        raise ModelError(
            f"needs a longer record: the filter rings for {skip / rate:.3g} s at each end",
            field="band",
            value=(f1, f2),
            unit="Hz",
            valid=f"a record longer than {2 * skip / rate + 4 / f1:.3g} s, or a wider band",
        )
    out = scipy.signal.sosfiltfilt(sos, y)
    what = (
        f"after a zero-phase Butterworth band-pass {f1:g}-{f2:g} Hz (order {BAND_ORDER}, forward and"
        f" backward: sosfiltfilt), its first and last {skip / rate:.3g} s skipped"
    )
    return out, skip, slowest, what


def _upward_crossings(y: np.ndarray, hysteresis: float) -> np.ndarray:
    """Indices i where y crosses zero upwards between i and i + 1, counting a crossing only after y
    has been below −hysteresis and then rises above +hysteresis."""
    state = np.zeros(y.size, dtype=np.int8)
    state[y > hysteresis] = 1
    state[y < -hysteresis] = -1
    marked = np.flatnonzero(state)
    if marked.size == 0:
        return marked
    # carry the last definite state forward over the samples inside the hysteresis band
    filled = state[marked][np.searchsorted(marked, np.arange(y.size), side="right") - 1]
    filled[: marked[0]] = state[marked[0]]
    rises = np.flatnonzero((filled[1:] == 1) & (filled[:-1] == -1)) + 1  # first sample above +h
    negatives = np.flatnonzero(y < 0)
    # the crossing lies after the last negative sample before each rise
    return negatives[np.searchsorted(negatives, rises) - 1]


def _extremum(y: np.ndarray, k: int) -> tuple[float, float]:
    """Value and sub-sample position of the extremum at sample k (parabola through 3 samples)."""
    if k == 0 or k == y.size - 1:
        return float(y[k]), float(k)
    a, b, c = y[k - 1], y[k], y[k + 1]
    curvature = a - 2.0 * b + c
    if curvature == 0:
        return float(b), float(k)
    p = 0.5 * (a - c) / curvature
    return float(b - 0.25 * (a - c) * p), k + p


@follows_policy
def log_decrement(t, x, *, frequency_hz=None, band=None) -> Decay:
    """Damping of a free decay from the logarithmic decrement of its cycles.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times, uniformly spaced, s.
    x : array_like, shape (n,)
        The decay, any unit, around any static value (torque on a mean load, say); from the start of
        the free decay or earlier (the fit starts at the largest cycle).
    frequency_hz : float, optional
        The damped frequency to use, Hz; default: measured from the zero crossings.
    band : (float, float), optional
        ``(f1, f2)`` in Hz: first isolate one mode with a band-pass, for a decay of several modes.

    Returns
    -------
    Decay

    Notes
    -----
    Each cycle (between two upward zero crossings of ``x`` minus its mean, with a hysteresis of 1 %
    of the largest amplitude) gives an amplitude ``(max − min) / 2``, each extremum refined by a
    parabola through three samples, at the time midway between them. Half the peak-to-peak value
    does not depend on the static offset and is, for ``C + A·e^(−σt)·sin(ω_d t)``, exactly
    proportional to ``e^(−σt)``. The fit starts at the largest cycle and ends before the first below
    2 % of it (the noise floor of a measurement); ``ln(amplitude)`` is fitted by least squares
    against time: slope ``−σ``. Then ``ξ = σ / √(σ² + ω_d²)``, exact for a 1-DOF decay.

    The band-pass is a 4th-order Butterworth run forward and backward (``scipy.signal.sosfiltfilt``):
    no phase shift, and a decay passed through a linear filter keeps its rate once the filter's own
    transients have died. They decay with the filter's slowest pole, so the first and last
    ln(1e4)/r seconds are skipped (r its decay rate, about 0.9 × the bandwidth in Hz). The band must
    be much wider than the mode's half-power bandwidth; a note says when the decay is as fast as
    the filter's ringing.

    Raises
    ------
    ModelError
        Bad samples or times, a band outside (0, Nyquist), or fewer than 3 cycles of decay.
    """
    x = as_signal(x, "x", min_samples=3)
    t, rate = rate_from_times(t, x.size)
    if frequency_hz is not None:
        frequency_hz = check_real(frequency_hz, "frequency_hz", "Hz", lo=0.0, lo_open=True, hi=rate / 2)
    notes: list[str] = []
    method = "half peak-to-peak per cycle, least-squares line through ln(amplitude) against time"
    y = x - x.mean()
    skip, ring = 0, math.inf
    if band is not None:
        y, skip, ring, what = _band_pass(y, rate, band)
        method += "; " + what
    y = y[skip : y.size - skip] if skip else y
    ts = t[skip : t.size - skip] if skip else t
    crossings = _upward_crossings(y, CROSSING_HYSTERESIS * np.abs(y).max())
    amps, times = [], []
    for c0, c1 in zip(crossings[:-1], crossings[1:]):
        seg = y[c0 + 1 : c1 + 1]
        hi, khi = _extremum(y, c0 + 1 + int(np.argmax(seg)))
        lo, klo = _extremum(y, c0 + 1 + int(np.argmin(seg)))
        amps.append(0.5 * (hi - lo))
        times.append(ts[0] + 0.5 * (khi + klo) / rate)
    amps, times = np.asarray(amps), np.asarray(times)
    start = int(np.argmax(amps)) if amps.size else 0
    stop = start
    while stop < amps.size and amps[stop] >= DECAY_FLOOR * amps[start]:
        stop += 1
    used = stop - start
    if used < MIN_CYCLES:
        raise ModelError(
            f"holds {used} cycles of decay from its largest down to {DECAY_FLOOR:.0%} of it",
            field="x",
            valid=f"a free decay of at least {MIN_CYCLES} cycles"
            + (" in the band" if band is not None else "")
            + f" above {DECAY_FLOOR:.0%} of its largest amplitude",
        )
    a, tt = amps[start:stop], times[start:stop]
    slope, intercept = np.polyfit(tt, np.log(a), 1)
    sigma = -float(slope)
    scatter = float(np.sqrt(np.mean((np.log(a) - (slope * tt + intercept)) ** 2)))
    if frequency_hz is None:
        # crossings bracketing the used cycles: c[start] .. c[stop], linearly interpolated
        idx = crossings[start : stop + 1]
        tc = ts[0] + (idx + y[idx] / (y[idx] - y[idx + 1])) / rate
        frequency_hz = used / float(tc[-1] - tc[0])
    omega = 2.0 * math.pi * frequency_hz
    damping = sigma / math.hypot(sigma, omega)
    if sigma <= 0:
        notes.append("the envelope does not decay: no free decay, or an excitation still on")
    if scatter > MAX_LOG_SCATTER:
        notes.append(
            f"the envelope is not one exponential (rms deviation {scatter:.3g} of ln(amplitude)):"
            " beating of close modes, noise or non-linear damping; isolate one mode with band="
        )
    if sigma > ring / 3:
        notes.append(
            f"the decay rate {sigma:.3g} 1/s is not well below the band-pass's own decay rate"
            f" {ring:.3g} 1/s: the filter's ringing lengthens the decay; widen the band"
        )
    return Decay(damping, float(frequency_hz), sigma, used, float(tt[0]), float(tt[-1]), method, tuple(notes))


@dataclass(frozen=True)
class DecayPeak:
    """The half-power damping of a free decay from its spectrum (see :func:`decay_damping`).

    Attributes
    ----------
    damping_ratio : float
        ξ of the decay, with the exponential window's added damping removed; NaN when it cannot be
        read (``damping_missing`` says why).
    frequency_hz : float
        The damped frequency ω_d/2π, Hz; the peak's own frequency when its half-power points are
        missing.
    decay_rate : float
        σ = ξ·ω_n, 1/s (NaN with the damping).
    window : str
        ``"rect"`` or ``"exponential"``.
    tau_s : float or None
        The exponential window's time constant, s (None for rect).
    resolution_hz : float
        The record's resolution 1/T, Hz (the spectrum is sampled finer: zero padding).
    peak : Peak
        The peak of the windowed, zero-padded spectrum as measured (its damping includes the window's).
    method : str
        The window and the formulas used.
    notes : tuple of str
        Leakage, coarse resolution, missing half-power points.
    damping_missing : str or None
        Why ``damping_ratio`` is NaN: a half-power point not found, or a decay slower than the
        exponential window's own (σ <= 0 after subtracting 1/τ: nothing left to measure). None when
        it is a number.
    """

    damping_ratio: float
    frequency_hz: float
    decay_rate: float
    window: str
    tau_s: float | None
    resolution_hz: float
    peak: Peak
    method: str
    notes: tuple[str, ...] = ()
    damping_missing: str | None = None


def _decay_window(t: np.ndarray, record: float, window: str, tau):
    """The window of :func:`decay_damping` over the times t and its time constant (None: rectangular)."""
    if window == "rect":
        if tau is not None:
            raise ModelError(
                "is for the exponential window only", field="tau", value=tau, unit="s", valid="None"
            )
        w = np.ones(t.size)
    else:
        tau = (
            record * DEFAULT_TAU_FRACTION if tau is None else check_real(tau, "tau", "s", lo=0, lo_open=True)
        )
        w = np.exp(-(t - t[0]) / tau)
    return w, tau


def _tail_note(y: np.ndarray, window: str) -> str | None:
    """A note where the (windowed) decay y has not died out by the record's end, which leaks."""
    tail = int(math.ceil(TAIL_FRACTION * y.size))
    largest = float(np.abs(y).max())
    left = float(np.abs(y[-tail:]).max()) / largest if largest > 0 else 0.0
    if left > TAIL_LIMIT:
        fix = "a longer record, or window='exponential'" if window == "rect" else "a shorter tau"
        return (
            f"the decay has not died out: the last {TAIL_FRACTION:.0%} of the record holds"
            f" {left:.1%} of the largest amplitude (leakage widens the peak): {fix}"
        )
    return None


def _largest_peak(amp: np.ndarray, freqs: np.ndarray, band, rate: float) -> int:
    """The index of the largest local maximum of the amplitude spectrum above DC (in ``band``, Hz)."""
    lo, hi = 1, amp.size - 1
    if band is not None:
        f1, f2 = check_band(band, rate)
        lo, hi = max(1, int(np.searchsorted(freqs, f1))), min(amp.size - 1, int(np.searchsorted(freqs, f2)))
    inner = amp[lo:hi]
    ks = np.flatnonzero((inner > amp[lo - 1 : hi - 1]) & (inner >= amp[lo + 1 : hi + 1])) + lo
    if ks.size == 0:
        raise ModelError(
            "holds no peak" + (" in the band" if band is not None else ""),
            field="x" if band is None else "band",
            value=band,
            has_value=band is not None,
            valid="a free decay with a peak" + (" between f1 and f2" if band is not None else ""),
        )
    return int(ks[np.argmax(amp[ks])])


@follows_policy
def decay_damping(t, x, *, band=None, window: str = "rect", tau=None) -> DecayPeak:
    """The half-power damping of a free decay, from the spectrum of the whole transient.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times, uniformly spaced, s.
    x : array_like, shape (n,)
        The free decay, starting at (or just before) its start; its mean is removed.
    band : (float, float), optional
        Look for the peak only in ``(f1, f2)`` Hz (the largest peak above DC otherwise). The spectrum
        separates modes by itself: no filter is applied.
    window : str
        ``"rect"`` (default): no window, for a record in which the decay has died out (a note warns
        when the last 10 % of the record still holds more than 1 % of the largest amplitude: the
        cut end leaks and widens the peak; on an analytic decay a 2.7 % tail overstates ξ by 6 %, a
        1.5 % tail by 2 %). ``"exponential"``: ``w = e^(−(t − t0)/τ)``, which makes
        any decay die out in the record and whose added damping is removed exactly.
    tau : float, optional
        The exponential window's time constant, s (default: a sixth of the record, so it ends at
        e^−6 ≈ 0.25 %). Only with ``window="exponential"``. The same leakage check applies to the
        windowed record. The shorter τ, the more of the measured decay rate is the window's and the
        larger the relative error of the difference.

    Returns
    -------
    DecayPeak

    Notes
    -----
    Why not Hann: a window multiplies the decay, and a spectrum reads the damping of the product.
    Hann is zero at the start where a free decay is largest; on a record much longer than the decay
    the windowed decay is ≈ (πt/T)²·e^(−σt), whose spectrum ∝ ``|σ + iΔω|^(−3)`` falls to 1/√2 at
    Δω = σ·√(2^(1/3) − 1) ≈ 0.51·σ: Hann roughly halves the damping. The rectangular window leaves
    the decay untouched; the exponential one turns ``e^(−σt)`` into ``e^(−(σ + 1/τ)t)``, adding
    exactly ``1/τ`` to the decay rate, so ``σ = σ_measured − 1/τ``.

    The spectrum of ``e^(−σt)·sin(ω_d t)`` is ∝ ``1/|ω_d² + σ² − ω² + 2iσω|`` (a 1-DOF frequency
    response), whose half-power points ω1 < ω2 satisfy exactly ``ω2² − ω1² = 4σω_d`` and
    ``(ω1² + ω2²)/2 = ω_d² − σ²``; both are solved for σ and ω_d (no small-damping approximation).
    The record (times the window) is zero-padded to 8 times its length (at most 2^23 samples)
    before the FFT: for a transient that has died out in the record this samples the same spectrum
    8 times finer, so the half-power points are interpolated between close samples. It adds no
    resolution to a record cut short: that is what the leakage note is for.

    Raises
    ------
    ModelError
        Bad samples or times, an unknown window, a tau without the exponential window, a band
        outside (0, Nyquist), no peak in the band.
    """
    x = as_signal(x, "x", min_samples=3)
    t, rate = rate_from_times(t, x.size)
    check_choice(window, "window", DECAY_WINDOWS)
    n = x.size
    record = n / rate
    w, tau = _decay_window(t, record, window, tau)
    y = (x - x.mean()) * w
    note = _tail_note(y, window)
    notes: list[str] = [] if note is None else [note]
    npad = scipy.fft.next_fast_len(max(n, min(DECAY_PADDING * n, MAX_PADDED)), real=True)
    amp = np.abs(scipy.fft.rfft(y, npad)) * (2.0 / w.sum())
    freqs = scipy.fft.rfftfreq(npad, 1.0 / rate)
    resolution = rate / npad
    k = _largest_peak(amp, freqs, band, rate)
    peak = describe_peak(freqs, amp, k, resolution, window, "record longer")
    notes.extend(peak.notes)
    extra = 0.0 if window == "rect" else 1.0 / tau
    missing = peak.damping_missing
    if missing is None:
        w1, w2 = 2 * math.pi * peak.f_low_hz, 2 * math.pi * peak.f_high_hz
        wp2, d = 0.5 * (w1 * w1 + w2 * w2), w2 * w2 - w1 * w1
        wd = math.sqrt(0.5 * (wp2 + math.sqrt(wp2 * wp2 + 0.25 * d * d)))
        sigma = d / (4.0 * wd) - extra
        if sigma <= 0:
            missing = (
                f"the window's added decay rate 1/tau = {extra:.4g} 1/s is more than the measured"
                f" {d / (4.0 * wd):.4g} 1/s: no decay, or one too slow for this record (a longer"
                " record, or a longer tau)"
            )
            notes.append(missing)
    if missing is not None:
        # the peak stays: its frequency and amplitude are read; only the damping is not
        wd, sigma = 2 * math.pi * peak.frequency_hz, math.nan
    damping = sigma / math.hypot(sigma, wd)
    method = (
        "half-power points of the |FFT| of the whole record"
        + (
            f" times exp(-t/{tau:.4g} s), whose added decay rate 1/tau = {extra:.4g} 1/s is subtracted"
            if window == "exponential"
            else " (rectangular window)"
        )
        + f", zero-padded {npad / n:.3g}x; windowed rate s' = (w2^2 - w1^2)/(4 w_d),"
        " w_d^2 = (w1^2 + w2^2)/2 + s'^2"
        + (", sigma = s' - 1/tau" if window == "exponential" else ", sigma = s'")
    )
    return DecayPeak(
        damping,
        peak.frequency_hz if missing is not None else wd / (2 * math.pi),
        sigma,
        window,
        None if window == "rect" else float(tau),
        1.0 / record,
        peak,
        method,
        tuple(notes),
        missing,
    )
