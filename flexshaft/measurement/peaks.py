"""Peaks of a spectrum and the damping of a mode: half-power bandwidth (:mod:`.decay`: of a free decay).

Three routes to a damping ratio ξ, for three kinds of record (the last two in :mod:`.decay`):

- :func:`find_peaks` on a :class:`~flexshaft.measurement.spectrum.Spectrum` (or a frequency response):
  the half-power bandwidth of each peak, ``ξ = (f2 − f1) / (2·f_peak)``. Right for a response
  spectrum or FRF whose peak spans many bins; a tone's peak is only as wide as the window's main
  lobe, which a note says.
- :func:`log_decrement` on a free decay in time: the slope of ln(amplitude) over the cycles.
- :func:`decay_damping` on a free decay in frequency: the half-power bandwidth with a window made
  for a transient (rectangular or exponential, never Hann: see there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ModelError
from ..system.threads import follows_policy
from ..validation import check_int, check_real
from .checks import as_signal
from .halfpower import (
    FLOOR_REACH,
    LOBE_HALF_WIDTH,
    MAX_CANDIDATES,
    MAX_RELATIVE_SPREAD,
    MIN_BANDWIDTH_BINS,
    MIN_PROMINENCE_DB,
    above_floor,
    fit_half_power,
    floor_factor,
    select_peaks,
    tone,
    widths,
)

__all__ = [
    "Peak",
    "describe_peak",
    "find_peaks",
    "half_power_damping",
    "response_peaks",
    "log_parabola",
    "peak_threshold",
    "MIN_RELATIVE",
]

#: A peak counts only at or above this fraction of the largest amplitude above DC (60 dB down).
MIN_RELATIVE = 1e-3

#: Walking down a peak's flank, a rise by this factor over the lowest amplitude passed is another peak.
VALLEY_RISE = 1.1


@dataclass(frozen=True)
class Peak:
    """A peak of a spectrum with its half-power bandwidth.

    Attributes
    ----------
    frequency_hz : float
        Peak frequency, interpolated between bins (parabola through the log-amplitudes), Hz.
    amplitude : float
        Peak amplitude, interpolated the same way (for ``window="flattop"`` the largest bin's,
        which that window makes right to 0.1 %), in the spectrum's unit.
    damping_ratio : float
        ``(f_high − f_low) / (2·frequency)``, > 0; NaN when a half-power point is missing or the
        peak is one bin wide (``damping_missing`` says which).
    f_low_hz, f_high_hz : float
        The half-power (−3 dB, amplitude/√2) points, linearly interpolated between bins, Hz; NaN
        when the spectrum ends or another peak rises before the amplitude falls that far.
    bins_in_bandwidth : float
        ``(f_high − f_low) / resolution``: how many bins the half-power bandwidth spans (NaN with it).
    notes : tuple of str
        What limits the result (coarse resolution, a missing half-power point), for a person to read.
    damping_missing : str or None
        Why ``damping_ratio`` is NaN (the half-power points that could not be found, and why);
        None when it is a number. The frequency and amplitude are the peak's all the same.
    damping_spread : float
        One standard deviation of ``damping_ratio`` from the scatter of the bins about the fitted
        1-DOF shape (:mod:`flexshaft.measurement.halfpower`); NaN where there is no fit (a free
        decay's walked band, or no damping).
    """

    frequency_hz: float
    amplitude: float
    damping_ratio: float
    f_low_hz: float
    f_high_hz: float
    bins_in_bandwidth: float
    notes: tuple[str, ...] = ()
    damping_missing: str | None = None
    damping_spread: float = math.nan

    def to_dict(self) -> dict:
        """A JSON-ready document (NaN becomes None; ``damping_missing`` says why when it is)."""
        return {
            "frequency_hz": _json(self.frequency_hz),
            "amplitude": _json(self.amplitude),
            "damping_ratio": _json(self.damping_ratio),
            "damping_missing": self.damping_missing,
            "damping_spread": _json(self.damping_spread),
            "f_low_hz": _json(self.f_low_hz),
            "f_high_hz": _json(self.f_high_hz),
            "bins_in_bandwidth": _json(self.bins_in_bandwidth),
            "notes": list(self.notes),
        }


def _json(value: float) -> float | None:
    return None if math.isnan(value) else float(value)


def log_parabola(left, mid, right) -> tuple[np.ndarray, np.ndarray]:
    """Vertex of the parabola through the log-amplitudes of three neighbouring bins.

    Parameters
    ----------
    left, mid, right : array_like
        Amplitudes of bins ``k − 1``, ``k``, ``k + 1`` (``mid`` the largest for a peak).

    Returns
    -------
    offset : ndarray
        The vertex's position relative to bin ``k``, in bins, clipped to [−0.5, 0.5] (where it lies
        whenever ``mid`` is the largest of the three).
    amplitude : ndarray
        ``exp`` of the vertex's value. Where an amplitude is not > 0 (no logarithm) the offset is 0
        and the amplitude ``mid``.

    Notes
    -----
    A peak is close to a Gaussian in log-amplitude near its top, so the parabola on the logarithm
    fits it better than one on the amplitude: for a Hann-windowed tone the frequency comes within
    0.02 bin and the amplitude within +3.8 % (the worst case, half a bin off), where the largest bin
    alone can be 15 % low.
    """
    left, mid, right = (np.asarray(a, dtype=float) for a in (left, mid, right))
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b, c = np.log(left), np.log(mid), np.log(right)
        curvature = a - 2.0 * b + c
        offset = 0.5 * (a - c) / curvature
    ok = (left > 0) & (mid > 0) & (right > 0) & (curvature < 0) & np.isfinite(offset)
    offset = np.where(ok, np.clip(offset, -0.5, 0.5), 0.0)
    with np.errstate(invalid="ignore"):
        amplitude = np.where(ok, np.exp(b - 0.25 * (a - c) * offset), mid)
    return offset, amplitude


def _half_power_point(freqs: np.ndarray, amp: np.ndarray, k: int, level: float, direction: int):
    """Where the amplitude first falls below ``level`` walking from bin ``k`` by ``direction``.

    Returns ``(frequency or NaN, note or None)``. The walk stops (NaN) at the end of the spectrum,
    or where the amplitude rises by :data:`VALLEY_RISE` over the lowest passed: another peak shares
    the band, and a bandwidth across both would overstate the damping.
    """
    j, lowest = k, amp[k]
    side = "below" if direction < 0 else "above"
    while True:
        nxt = j + direction
        if nxt < 0 or nxt >= amp.size:
            return math.nan, f"no half-power point {side} the peak: the spectrum ends first"
        if amp[nxt] < level:
            # linear interpolation between the last bin above the level and the first below it
            frac = (amp[j] - level) / (amp[j] - amp[nxt])
            return float(freqs[j] + frac * (freqs[nxt] - freqs[j])), None
        if amp[nxt] > VALLEY_RISE * lowest:
            return math.nan, (
                f"no half-power point {side} the peak: another peak at {freqs[nxt]:.6g} Hz rises"
                " before the amplitude falls to 1/√2"
            )
        lowest = min(lowest, amp[nxt])
        j = nxt


def describe_peak(
    freqs: np.ndarray, amp: np.ndarray, k: int, resolution: float, window: str, advice: str
) -> Peak:
    """The :class:`Peak` at local maximum ``k`` (0 < k < len − 1) of a spectrum."""
    offset, top = log_parabola(amp[k - 1], amp[k], amp[k + 1])
    offset, top = float(offset), float(top)
    if top >= math.sqrt(2.0) * amp[k]:
        # The parabola through the log-amplitudes overshoots its largest bin by 3 dB or more (a
        # neighbour far below the other, as at the first bin of a steep slope): no peak shape to
        # interpolate, and its half-power level would lie above the bin itself. The bin it is.
        return _unresolved(freqs, amp, k)
    frequency = float(freqs[k] + offset * (freqs[k + 1] - freqs[k]))
    # flattop is flat within 0.1 % over a bin: its largest bin is the amplitude, a parabola only adds error
    amplitude = float(amp[k]) if window == "flattop" else top
    level = top / math.sqrt(2.0)
    f_low, low_note = _half_power_point(freqs, amp, k, level, -1)
    f_high, high_note = _half_power_point(freqs, amp, k, level, +1)
    notes = [n for n in (low_note, high_note) if n]
    missing = "; ".join(notes) or None
    width = f_high - f_low
    bins = width / resolution
    damping = width / (2.0 * frequency) if frequency > 0 and missing is None else math.nan
    if missing is None and not damping > 0:  # cannot happen with both points found; never a number < 0
        missing, damping = f"the half-power band {width:.4g} Hz is not positive", math.nan
    if bins < MIN_BANDWIDTH_BINS:  # False for NaN
        notes.append(_too_coarse(resolution, width, bins, f"{MIN_BANDWIDTH_BINS:g} or more wanted", advice))
    return Peak(frequency, amplitude, damping, f_low, f_high, bins, tuple(notes), missing)


def _too_coarse(resolution: float, width: float, bins: float, what: str, advice: str) -> str:
    """The note of a half-power band spanning too few bins, with what would do."""
    return (
        f"resolution {resolution:.4g} Hz too coarse for a half-power bandwidth of {width:.4g} Hz"
        f" ({bins:.2g} bins, {what}): {advice}"
    )


def _unresolved(freqs: np.ndarray, amp: np.ndarray, k: int) -> Peak:
    """A peak of one bin: its frequency and amplitude are the bin's; its damping is missing."""
    why = (
        "no half-power points: the peak is one bin wide (its neighbours fall more than 3 dB at"
        " once, as at the edge of a steep slope)"
    )
    nan = math.nan
    return Peak(float(freqs[k]), float(amp[k]), nan, nan, nan, nan, (why,), why)


def _spectrum_parts(spec) -> tuple[np.ndarray, np.ndarray, float, str]:
    valid = "a Spectrum (flexshaft.measurement.spectrum) or an object with its fields"
    try:
        freqs = np.asarray(spec.frequencies_hz, dtype=float)
        amp = np.asarray(spec.amplitude, dtype=float)
        resolution = float(spec.resolution_hz)
        window = str(getattr(spec, "window", ""))
    except (AttributeError, TypeError, ValueError):
        raise ModelError(
            f"is a {type(spec).__name__}, not a spectrum", field="spectrum", valid=valid
        ) from None
    if freqs.ndim != 1 or amp.shape != freqs.shape or freqs.size < 3:
        raise ModelError(
            f"has {freqs.shape} frequencies and {amp.shape} amplitudes",
            field="spectrum",
            valid=valid + ": equal 1-D arrays of at least 3 bins",
        )
    if not (np.all(np.isfinite(amp)) and np.all(np.isfinite(freqs))):
        raise ModelError("holds non-finite values", field="spectrum", valid=valid)
    return freqs, amp, resolution, window


@follows_policy
def find_peaks(
    spec,
    *,
    count: int | None = None,
    min_relative: float = MIN_RELATIVE,
    prominence_db: float = MIN_PROMINENCE_DB,
) -> list[Peak]:
    """The peaks of a spectrum, largest first, each with its half-power damping.

    Parameters
    ----------
    spec : Spectrum
        A :class:`~flexshaft.measurement.spectrum.Spectrum`, or any object with ``frequencies_hz``,
        ``amplitude`` (equal 1-D arrays, ascending uniform frequencies) and ``resolution_hz`` (e.g. a
        frequency response magnitude to read damping from).
    count : int, optional
        Return at most this many (the largest). ``None``: all.
    min_relative : float
        Only local maxima at or above ``min_relative`` times the largest amplitude above DC count
        (default 1e-3, i.e. 60 dB down); in [0, 1].
    prominence_db : float
        A peak rises at least this far above the higher of its two bases, dB (default 6); >= 0.

    Returns
    -------
    list of Peak
        Sorted by amplitude, largest first (the first is the dominant one; sort by
        ``frequency_hz`` for a table). DC and the last bin are never peaks; one resonance or tone
        gives one peak (see :mod:`flexshaft.measurement.halfpower`: prominence, and the window's
        main-lobe half-width between peaks).

    Notes
    -----
    A tone's amplitude and frequency come from the window's response (Hann, rectangular: within
    0.5 % wherever it lies between bins; flat-top: its largest bin, within 0.1 %). A resonance's
    damping comes from a weighted fit of the 1-DOF shape to the bins around it, with the
    window's widening divided out and its spread from the fit's residuals (``damping_spread``).
    The damping is refused - None in the document, NaN here, ``damping_missing`` saying why and
    what would do - where a half-power point is missing, where the band spans fewer than
    :data:`~flexshaft.measurement.halfpower.MIN_BANDWIDTH_BINS` bins of a windowed spectrum, or where
    the spread is more than half the value. Problems are notes on the peak, never warnings.
    """
    freqs, amp, resolution, window = _spectrum_parts(spec)
    if count is not None:
        count = check_int(count, "count", lo=1)
    min_relative = check_real(min_relative, "min_relative", "", lo=0.0, hi=1.0)
    prominence_db = check_real(prominence_db, "prominence_db", "dB", lo=0.0)
    averages = getattr(spec, "averages", 1)
    segment = getattr(spec, "segment_s", None)
    advice = _Advice(averages if isinstance(averages, int) else 1, segment, resolution, window)
    return _peaks(freqs, amp, resolution, window, count, min_relative, advice, prominence_db)


@dataclass(frozen=True)
class _Advice:
    """What the spectrum was made of, to say what would read a damping it cannot."""

    averages: int
    segment_s: float | None
    resolution_hz: float
    window: str

    def coarse(self, zeta: float, frequency: float) -> str:
        """The band spans too few bins: the segment (or record) that gives it enough."""
        if self.window not in LOBE_HALF_WIDTH:
            return "a finer frequency grid"
        # bins across the band = 2ξf·T: T >= MIN_BANDWIDTH_BINS / (2ξf), where ξ is a resonance's
        # (a tone read as one has no width: its ξ says nothing of the length needed)
        need = MIN_BANDWIDTH_BINS / (2.0 * zeta * frequency) if zeta > 0 and frequency > 0 else math.inf
        if math.isfinite(need) and need * self.resolution_hz < 20.0:
            band = 2.0 * zeta * frequency
            length = f"at least {need:.3g} s ({MIN_BANDWIDTH_BINS:g} bins across 2ξf = {band:.3g} Hz)"
        else:
            length = f"longer than {1.0 / self.resolution_hz:.3g} s"
        if self.averages > 1:
            return f"a segment longer: {length}, with the record long enough for 10 or more of them"
        return f"a record longer: {length}"

    def noisy(self, spread: float) -> str:
        """The band is resolved but noisy: more averages."""
        what = f"the spectrum is too noisy across the peak (spread of ξ ±{spread:.0%}"
        if self.window not in LOBE_HALF_WIDTH:
            return what + ")"
        return (
            what + f" from {self.averages} average{'s' if self.averages != 1 else ''}): more averages -"
            " a longer record, or shorter segments while the band still spans"
            f" {MIN_BANDWIDTH_BINS:g} bins"
        )


def peak_threshold(spec, min_relative: float = MIN_RELATIVE) -> tuple[float, float]:
    """The amplitude a peak of ``spec`` must reach to count, and the frequency (Hz) of the largest
    amplitude above DC it is relative to: :func:`find_peaks`' first test, for a plot or a report
    that says why a peak it shows is not listed."""
    freqs, amp, _, _ = _spectrum_parts(spec)
    k = _largest(amp)
    return min_relative * float(amp[k]), float(freqs[k])


def _largest(amp: np.ndarray) -> int:
    """The bin of the largest amplitude above DC, which the peak threshold is relative to."""
    return 1 + int(np.argmax(amp[1:]))


def _peaks(freqs, amp, resolution, window, count, min_relative, advice, prominence_db) -> list[Peak]:
    threshold = min_relative * amp[_largest(amp)]
    spacing = LOBE_HALF_WIDTH.get(window, 1)
    ks = select_peaks(amp, threshold, prominence_db, spacing)
    ks = ks[np.argsort(-amp[ks], kind="stable")]
    if window in LOBE_HALF_WIDTH:  # a signal's spectrum: peaks stand above its noise floor
        ks = ks[:MAX_CANDIDATES]
        factor, scale, kept, reaches = floor_factor(advice.averages), widths(amp, ks), [], []
        for k, w in zip(ks, scale):
            if count is not None and len(kept) == count:
                break
            reach = above_floor(amp, int(k), w, factor)
            # a peak that clears its floor only beyond a larger peak is a spike on that one's flank
            if reach is not None and not any(abs(int(k) - j) < reach for j in kept):
                kept.append(int(k))
                reaches.append(reach)
        ks = np.asarray(kept, dtype=int)
    else:
        ks = ks if count is None else ks[:count]
        reaches = [0] * ks.size
    return [
        _spectral_peak(freqs, amp, int(k), resolution, window, advice, ks, reach)
        for k, reach in zip(ks, reaches)
    ]


def _spectral_peak(
    freqs, amp, k: int, resolution: float, window: str, advice: _Advice, ks, reach: int
) -> Peak:
    """The :class:`Peak` of a spectrum at ``k`` (``ks``: all the peaks kept; ``reach``: how far, bins,
    its noise floor lies): the walk finds the band, the fit reads it. In a windowed spectrum (a
    signal's, with noise) the walk is only a first guess and the other peaks kept bound the fit; in
    a computed response (no window) a neighbour the walk meets inside the band is another mode, and
    the damping is missing."""
    walked = describe_peak(freqs, amp, k, resolution, window, "")
    step = freqs[k + 1] - freqs[k]
    found = tone(amp, k, window)
    frequency, amplitude = walked.frequency_hz, walked.amplitude
    if found is not None:
        frequency, amplitude = float(freqs[k] + found[0] * step), found[1]
    windowed = window in LOBE_HALF_WIDTH
    if walked.damping_missing is not None and not windowed:
        notes = tuple(n for n in walked.notes if "too coarse" not in n)
        return replace(walked, frequency_hz=frequency, amplitude=amplitude, notes=notes)
    if found is not None:  # the window's own shape: a tone, or a resonance narrower than a bin
        width = walked.f_high_hz - walked.f_low_hz
        why = _too_coarse(
            resolution,
            width,
            walked.bins_in_bandwidth,
            "the window's own main lobe: a tone, or a resonance narrower than a bin",
            advice.coarse(math.nan, frequency),
        )
        nan = math.nan
        return Peak(
            frequency,
            amplitude,
            nan,
            walked.f_low_hz,
            walked.f_high_hz,
            walked.bins_in_bandwidth,
            (why,),
            why,
        )
    lo, hi = _bases(amp, k, ks if windowed else None)
    guess = walked.f_high_hz - walked.f_low_hz
    # a resonance of a single FFT is a crowd of spikes: the walk sees one; its floor lies ~2.5 bands off
    guess = max(guess if math.isfinite(guess) else 0.0, reach / FLOOR_REACH * resolution)
    fit = fit_half_power(freqs, amp, k, lo, hi, guess, resolution, window)
    if fit is None:
        if walked.damping_missing is not None:
            return replace(walked, frequency_hz=frequency, amplitude=amplitude)
        zeta, spread, f1, f2 = walked.damping_ratio, math.nan, walked.f_low_hz, walked.f_high_hz
        bins = walked.bins_in_bandwidth
    else:
        zeta, spread, f1, f2, bins = fit.damping_ratio, fit.spread, fit.f_low_hz, fit.f_high_hz, fit.bins
    notes, missing = [], None
    if fit is not None and windowed and not (freqs[lo] <= f1 and f2 <= freqs[hi]):
        side = "below" if f1 < freqs[lo] else "above"
        ends = lo == 0 if side == "below" else hi == amp.size - 1
        missing = f"no half-power point {side} the peak: " + (
            "the spectrum ends first" if ends else "another peak rises before the amplitude falls to 1/√2"
        )
        notes.append(missing)
    if missing is None and bins < MIN_BANDWIDTH_BINS:
        wanted = f"{MIN_BANDWIDTH_BINS:g} or more wanted"
        text = _too_coarse(resolution, f2 - f1, bins, wanted, advice.coarse(zeta, frequency))
        notes.append(text)
        if windowed:  # the window's own width, not the resonance's: no damping to read
            missing = text
    if missing is None and fit is not None and not spread <= MAX_RELATIVE_SPREAD * zeta:
        missing = advice.noisy(spread / zeta)
        notes.append(missing)
    if missing is not None:
        zeta, spread = math.nan, math.nan
    return Peak(frequency, amplitude, zeta, f1, f2, bins, tuple(notes), missing, spread)


def _bases(amp: np.ndarray, k: int, ks=None) -> tuple[int, int]:
    """The bins where peak ``k``'s flanks end: the lowest point on the way to a higher bin (or the
    end); with ``ks``, to the next peak of those (or the end): noise between them is no peak."""
    if ks is None:
        left = np.flatnonzero(amp[:k][::-1] > amp[k])
        right = np.flatnonzero(amp[k + 1 :] > amp[k])
        a = k - 1 - left[0] if left.size else 0
        b = k + 1 + right[0] if right.size else amp.size - 1
    else:
        others = np.asarray(ks)
        below, above = others[others < k], others[others > k]
        a = int(below.max()) if below.size else 0
        b = int(above.min()) if above.size else amp.size - 1
    lo = a + int(np.argmin(amp[a : k + 1]))
    hi = k + int(np.argmin(amp[k : b + 1]))
    return lo, hi


@follows_policy
def response_peaks(frequencies_hz, amplitude, count: int | None = None) -> list[Peak]:
    """The peaks of a frequency response's magnitude (a measured FRF, say), largest first, each with
    its half-power damping.

    A response has no window and no noise floor: every local maximum is a peak, and its band is read
    by the same 1-DOF fit as a spectrum's. A neighbour rising inside a peak's band is another mode, and
    that peak's damping is missing (``damping_missing`` says so).

    Parameters
    ----------
    frequencies_hz : array_like, shape (f,)
        Uniformly spaced, ascending, Hz.
    amplitude : array_like, shape (f,)
        Magnitudes (>= 0) at those frequencies.
    count : int, optional
        The largest this many (default: all).

    Returns
    -------
    list of Peak
    """
    f = as_signal(frequencies_hz, "frequencies_hz", "Hz", min_samples=3)
    a = as_signal(amplitude, "amplitude", min_samples=3)
    if a.size != f.size:
        raise ModelError(
            f"has {a.size} values for {f.size} frequencies", field="amplitude", valid="one per frequency"
        )
    if np.any(a < 0):
        raise ModelError("has negative values", field="amplitude", valid="magnitudes >= 0")
    if count is not None:
        count = check_int(count, "count", lo=1)
    step = np.diff(f)
    if not (np.all(step > 0) and np.ptp(step) <= 1e-6 * step.mean()):
        raise ModelError(
            "are not ascending with a uniform step", field="frequencies_hz", valid="a uniform ascending grid"
        )
    advice = _Advice(1, None, float(step.mean()), "")
    # every local maximum, however little it rises (a grid may end inside a band)
    return _peaks(f, a, float(step.mean()), "", count, 0.0, advice, 0.0)


@follows_policy
def half_power_damping(frequencies_hz, amplitude) -> Peak:
    """The largest peak of ``amplitude`` over ``frequencies_hz`` with its half-power damping.

    A convenience for a magnitude that is no :class:`Spectrum` (a measured FRF, say): the
    frequencies must be uniformly spaced and ascending (:func:`response_peaks`, its first).

    Parameters
    ----------
    frequencies_hz : array_like, shape (f,)
        Uniformly spaced, ascending, Hz.
    amplitude : array_like, shape (f,)
        Magnitudes (>= 0) at those frequencies.

    Returns
    -------
    Peak
        As :func:`find_peaks` gives its first.
    """
    peaks = response_peaks(frequencies_hz, amplitude, 1)
    if not peaks:
        raise ModelError("has no peak inside the range", field="amplitude", valid="a magnitude with a peak")
    return peaks[0]


# --- free decays -------------------------------------------------------------------------------------
