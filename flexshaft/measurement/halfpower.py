"""Which local maxima of a spectrum are peaks, and what each one's bins say: a tone's amplitude and
frequency from the window's own response, a resonance's damping from a fit of the 1-DOF shape with
the window's widening removed.

Three things a spectrum gets wrong when read bin by bin, and what is done about each:

- **Ripple is not a peak.** Noise on the flank of a resonance, or leakage, makes local maxima that
  are no resonance of their own. A peak must rise :data:`MIN_PROMINENCE_DB` above the higher of its
  two bases (the prominence of ``scipy.signal.find_peaks``: the lowest point on the way to a higher
  maximum, or to the end) and lie at least the window's main-lobe half-width
  (:data:`LOBE_HALF_WIDTH`) from a larger one. 6 dB: a resonance whose half-power points can be read
  falls by 3 dB on both sides before anything rises again; twice that leaves room for the noise of
  an averaged spectrum (a bin's amplitude scatters by ~4.3/√N dB over N averages: 1.3 dB at 11).
- **Noise is not a peak either.** A spectrum of a noisy record (a windowed one: a measurement, a
  simulation with noise) has a local maximum every few bins, and a single FFT's bins scatter so
  widely (exponentially distributed power) that many rise 6 dB above their neighbours. A peak must
  also stand above the noise floor on both sides - the median amplitude between
  :data:`FLOOR_NEAR` and :data:`FLOOR_FAR` of its own widths away on both sides - by the factor a
  bin of Gaussian noise exceeds its median with probability :data:`FALSE_PEAK` (power over N
  averages ∝ χ² with 2N degrees of freedom: 15 dB for one FFT, 6 dB over 11 averages). A
  computed frequency response (no window) has no noise and no such test.
- **A tone between two bins reads low.** Its amplitude is the window's response ``|W(δ)|`` at its
  offset δ from the bin: Hann ``sinc(δ)/(1 − δ²)`` (−15 % at half a bin), rectangular ``sinc(δ)``
  (−36 %). The ratio α of the larger neighbour to the largest bin gives δ exactly for a tone
  (Hann: ``δ = (2α − 1)/(α + 1)``, rectangular: ``δ = α/(1 + α)``; Grandke 1983, "Interpolation
  algorithms for discrete Fourier transforms of weighted signals", IEEE Trans. Instrum. Meas. 32(2)),
  and the amplitude is the bin's over ``|W(δ)|``. What is left is the other tones' and the negative
  frequency's leakage into the two bins: ~1e-4 for Hann a few bins from DC.
- **A resonance reads wider than it is, and a noisy one narrower.** Walking down from the largest
  bin to the first one below 1/√2 of it reads noise: over 11 Welch averages each bin scatters by
  ~15 %, and the first bin that dips below the level ends the band, often within a few bins of a
  53-bin-wide peak (ξ read 22 times too low). Here the squared amplitude of the bins within
  :data:`FIT_SPAN` half-power bandwidths of the peak is fitted by the 1-DOF shape - the reciprocal
  ``1/|H|²`` is a quadratic in f², exactly so for a displacement response (within 0.1 % of ξ at
  ξ = 10 % for a velocity) - by weighted least squares (every bin the same relative error), which
  averages the noise of all those bins; the fit's residuals give the spread of ξ (an estimate:
  0.6-0.8 of the scatter across records). Every window also
  smears the spectrum by its own response: the expected spectrum is the true one convolved with
  ``|W|²``, which widens a resonance of b bins (half-power) by the factor
  ``1 + 1.25·m₂/b²`` for a smooth window whose ``|W|²`` has second moment m₂ (Hann: m₂ = 1/3 bin²;
  see :data:`WIDENING`) and
  ``1 + 1/(π·b)`` for the rectangular one (its ``|W|²`` has no second moment: the triangle it
  puts on the correlation ``e^(−σ|τ|)`` of the response lowers the peak by 1/(σT) = 1/(πb)). The
  factor is divided out. Where the band spans fewer than :data:`MIN_BANDWIDTH_BINS` bins the
  damping is refused, saying which segment length would do (the factor is 1.7 % at 5 bins under
  Hann, 6.5 % rectangular, 7.6 % flat-top, and grows fast below).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.signal
import scipy.special

__all__ = [
    "FIT_SPAN",
    "FLOOR_REACH",
    "LOBE_HALF_WIDTH",
    "MIN_BANDWIDTH_BINS",
    "MIN_PROMINENCE_DB",
    "HalfPowerFit",
    "above_floor",
    "fit_half_power",
    "floor_factor",
    "select_peaks",
    "tone",
    "widening",
    "widths",
]

#: A peak rises at least this far above the higher of its two bases, dB.
MIN_PROMINENCE_DB = 6.0
#: Each window's main-lobe half-width, bins (its first null): two maxima closer than this are one.
LOBE_HALF_WIDTH = {"rect": 1, "hann": 2, "flattop": 5}
#: The fit of a resonance takes the bins within this many half-power bandwidths of its peak (at
#: 2.5 the 1-DOF power has fallen to 1/26: the flanks that fix the width, not yet the floor; at 1.5
#: the scatter of ξ over 11 averages was 1.3x as large).
FIT_SPAN = 2.5
#: A half-power band narrower than this many bins is the window's as much as the resonance's: the
#: damping is refused (a coarser advice than the walk gave, and the reason).
MIN_BANDWIDTH_BINS = 5.0
#: A damping whose spread (one standard deviation from the fit's residuals) is more than this
#: fraction of it is refused: the spectrum is too noisy across the peak.
MAX_RELATIVE_SPREAD = 0.5
#: Iterations of the fit's span (it starts from the walked bandwidth and follows the fitted one).
FIT_ITERATIONS = 6
#: The fit needs at least this many bins (three coefficients and some to spare for the spread).
MIN_FIT_BINS = 7
#: A tone's smaller neighbour must be within this fraction of the largest bin of what the window's
#: response predicts for the offset found, or the peak is not one tone (a resonance, two tones).
TONE_CONSISTENCY = 0.05

#: The noise floor of a peak is the median amplitude from this many of its widths away ...
FLOOR_NEAR = 5.0
#: ... to this many (and at least :data:`FLOOR_BINS` bins further), on both sides.
FLOOR_FAR = 10.0
FLOOR_BINS = 32
#: The probability that one bin of noise passes the floor test.
FALSE_PEAK = 1e-9
#: The floor test examines at most this many local maxima, the largest first (a single FFT of a long
#: noisy record has a maximum every few bins): a peak smaller than the largest 2000 maxima is not found.
MAX_CANDIDATES = 2000
#: A ring's median is taken over at most this many of its bins per side (evenly strided): a floor,
#: not a statistic, and the test's cost bounded however far the ring reaches.
RING_SAMPLES = 256
#: A resonance's floor (at the peak's amplitude over ~5.6, one FFT's factor) lies about this many
#: half-power bands from its top (a 1-DOF amplitude 1/√(1 + (2d/b)²) is down 5.6x at d = 2.7b):
#: how far the floor test reached, over this, is a first guess of a spiky resonance's band.
FLOOR_REACH = 2.5

# Samples of the window whose moments are taken (its shape's, not its length's: converged to 1e-6).
_MOMENT_SAMPLES = 4096


@functools.cache
def _moments(window: str) -> tuple[float, float | None]:
    """The window's equivalent noise bandwidth n·Σw²/(Σw)², bins - neighbouring bins share this much
    of the noise, so the residuals' scatter counts that many too many independent bins - and the
    second moment m₂ = n²·Σ(Δw)²/(4π²·Σw²) of its |W|², bins² (Hann: 1/3; None for no window and for
    the rectangular one, whose |W|² = sinc² has none)."""
    if window not in LOBE_HALF_WIDTH or window == "rect":
        return 1.0, None
    w = scipy.signal.get_window(window, _MOMENT_SAMPLES, fftbins=True)
    step = np.diff(w, append=w[:1])  # periodic: the last sample steps to the first
    n, energy = w.size, float(w @ w)
    return n * energy / float(w.sum()) ** 2, n * n * float(step @ step) / (4.0 * math.pi**2 * energy)


#: The widening of a resonance of b bins by a smooth window, as the fit over ±FIT_SPAN bands reads
#: it: 1 + WIDENING·m₂/b². A small window convolved into the 1-DOF shape adds m₂/2 times its second
#: derivative, which lowers the top and lifts the flanks; how much of that the fitted width takes up
#: depends on the bins fitted (4 over the top's −6 dB, the curvature alone). Over ±2.5 bands the
#: fit of the exact expected spectrum gave 1.17-1.4 for Hann and flat-top at 3-20 bins.
WIDENING = 1.25


def select_peaks(amp: np.ndarray, threshold: float, prominence_db: float, spacing: int) -> np.ndarray:
    """Indices of the peaks of ``amp`` (not DC, not the last bin), in no particular order.

    A peak is a local maximum at or above ``threshold``, rising ``prominence_db`` above the higher
    of its two bases, and at least ``spacing`` bins from any larger peak.
    """
    floor = max(float(amp.max()) * 1e-30, np.finfo(float).tiny)
    level = 20.0 * np.log10(np.maximum(amp, floor))
    height = 20.0 * math.log10(max(threshold, floor))
    ks, _ = scipy.signal.find_peaks(
        level, height=height, prominence=prominence_db, distance=max(1, int(spacing))
    )
    return ks[amp[ks] > 0]


def floor_factor(averages: int) -> float:
    """The amplitude ratio to the median by which one bin of Gaussian noise, its power averaged over
    ``averages`` segments (χ² with 2N degrees of freedom), is exceeded with probability
    :data:`FALSE_PEAK`."""
    half_dof = max(1, int(averages))  # χ²(2N)/2 is a gamma variate of shape N
    ratio = scipy.special.gammainccinv(half_dof, FALSE_PEAK) / scipy.special.gammainccinv(half_dof, 0.5)
    return math.sqrt(float(ratio))  # power ratio -> amplitude ratio


def above_floor(amp: np.ndarray, k: int, width_bins: float, factor: float) -> int | None:
    """How far (bins) the floor lies that peak ``k`` (about ``width_bins`` wide) stands ``factor``
    above, or None when it stands above none.

    The floor is the median amplitude in a ring of bins around the peak, from :data:`FLOOR_NEAR` to
    :data:`FLOOR_FAR` of its widths away (plus :data:`FLOOR_BINS`), the ring doubled until the peak
    clears it or the ring leaves the spectrum: a spike on a broad resonance (a single FFT of a
    random response is all spikes) clears only the ring beyond the resonance, and that distance is
    what :func:`_peaks` uses to keep one peak per resonance.
    """
    w = max(1.0, float(width_bins))
    scale = 1.0
    while True:
        near = int(math.ceil(FLOOR_NEAR * w * scale))
        far = int(math.ceil(FLOOR_FAR * w * scale)) + FLOOR_BINS
        if k - near <= 1 and k + near >= amp.size:
            return None
        # each side's median, and the higher of them: a spike on a slope (a response falling as
        # 1/f² away from its resonance) clears the lower side only
        sides = [amp[max(1, k - far) : max(1, k - near)], amp[k + near : k + far]]
        sides = [side[:: max(1, side.size // RING_SAMPLES)] for side in sides]
        floors = [float(np.median(side)) for side in sides if side.size >= 4]
        if not floors:
            if scale == 1.0:  # no floor to speak of (a short spectrum): it stands
                return 0
        elif amp[k] >= factor * max(floors):
            return near
        scale *= 2.0


def widths(amp: np.ndarray, ks: np.ndarray) -> np.ndarray:
    """Each peak's width, bins, half-way down its prominence (``scipy.signal.peak_widths``): the
    scale of its floor test (no more than that)."""
    if ks.size == 0:
        return np.zeros(0)
    return scipy.signal.peak_widths(amp, ks, rel_height=0.5)[0]


def tone(amp: np.ndarray, k: int, window: str) -> tuple[float, float] | None:
    """Offset (bins; within ±0.5: the largest bin is the nearest) and amplitude of a tone whose
    largest bin is ``k``, from the window's response; None when the bins are not one tone's (or the
    window has no formula)."""
    if window not in ("hann", "rect") or not (0 < k < amp.size - 1) or amp[k] <= 0:
        return None
    side = 1 if amp[k + 1] >= amp[k - 1] else -1
    alpha = amp[k + side] / amp[k]
    delta = (2.0 * alpha - 1.0) / (alpha + 1.0) if window == "hann" else alpha / (1.0 + alpha)
    if not 0.0 <= delta <= 1.0:
        return None
    response, other = _response(window, delta), _response(window, 1.0 + delta)
    # the other neighbour lies 1 + δ bins from the tone: the window predicts its amplitude too
    if abs(amp[k - side] - amp[k] * other / response) > TONE_CONSISTENCY * amp[k]:
        return None
    return side * delta, float(amp[k] / response)


def _response(window: str, delta: float) -> float:
    """|W(δ)| / W(0) of a long window at δ bins (Hann's, rectangular's)."""
    s = float(np.sinc(delta))
    if window == "rect":
        return abs(s)
    d2 = delta * delta
    return abs(s / (1.0 - d2)) if d2 != 1.0 else 0.5  # Hann's limit at δ = 1


def widening(window: str, bins: float) -> float:
    """The factor by which ``window`` widens a resonance whose true half-power band spans ``bins``
    bins (see the module docstring); 1 for no window (a computed frequency response)."""
    if window == "rect":
        return 1.0 + 1.0 / (math.pi * bins)
    m2 = _moments(window)[1]
    return 1.0 if m2 is None else 1.0 + WIDENING * m2 / (bins * bins)


def _unwidened(window: str, measured_bins: float) -> float:
    """The true band (bins) that ``window`` widens to ``measured_bins``: b·widening(b) = measured."""
    b = measured_bins
    for _ in range(50):  # a contraction for b >= 1 (the factor's slope is small): converges fast
        nb = measured_bins / widening(window, b)
        if abs(nb - b) <= 1e-12 * measured_bins:
            break
        b = nb
    return b


@dataclass(frozen=True)
class HalfPowerFit:
    """A resonance's half-power band from the 1-DOF fit (see the module docstring).

    Attributes
    ----------
    damping_ratio : float
        ξ with the window's widening divided out.
    spread : float
        One standard deviation of ξ from the fit's residuals, their count divided by the window's
        equivalent noise bandwidth in bins (neighbouring bins share noise); 0 for an exact 1-DOF
        shape. An estimate: over 11 and 59 Welch averages it was 0.85 of the scatter of ξ across
        40 records, over one FFT 0.65.
    f_low_hz, f_high_hz : float
        Half-power points of the fitted shape (as measured: window included), Hz.
    natural_hz : float
        The fitted shape's natural frequency, Hz.
    bins : float
        Bins across the fitted half-power band (window included).
    used : int
        Bins fitted.
    widening : float
        The window's factor divided out of ξ.
    """

    damping_ratio: float
    spread: float
    f_low_hz: float
    f_high_hz: float
    natural_hz: float
    bins: float
    used: int
    widening: float


def fit_half_power(
    freqs: np.ndarray,
    amp: np.ndarray,
    k: int,
    lo: int,
    hi: int,
    width_hz: float,
    resolution: float,
    window: str,
) -> HalfPowerFit | None:
    """Fit the 1-DOF power shape to the bins around peak ``k`` (within its bases ``lo``..``hi``).

    ``width_hz`` is a first guess of the half-power band (the walked one); None when no fit holds
    (too few bins, a shape that is no resonance).
    """
    width = width_hz if np.isfinite(width_hz) and width_hz > 0 else 2.0 * resolution
    fp = float(freqs[k])
    if fp <= 0:
        return None
    result = None
    for _ in range(FIT_ITERATIONS):
        half = max(3, int(math.ceil(FIT_SPAN * width / resolution)))
        a, b = max(lo, k - half, 1), min(hi, k + half)
        idx = np.arange(a, b + 1)
        idx = idx[amp[idx] > 0]
        if idx.size < MIN_FIT_BINS:
            break
        got = _fit(freqs[idx], amp[idx] ** 2, fp)
        if got is None:
            break
        result = got
        new = got[3] - got[2]  # f_high - f_low
        if abs(new - width) <= 0.5 * resolution:
            break
        width = new
    if result is None:
        return None
    zeta, spread, f1, f2, fn, used = result
    spread *= math.sqrt(_moments(window)[0])
    bins = (f2 - f1) / resolution
    factor = widening(window, _unwidened(window, bins))
    return HalfPowerFit(zeta / factor, spread / factor, f1, f2, fn, bins, used, factor)


def _fit(f: np.ndarray, power: np.ndarray, fp: float):
    """Weighted least squares of ``1/P = c0 + c1·x + c2·x²``, ``x = (f/fp)² − 1``: ξ, its spread,
    the half-power points, the natural frequency and the bins used; None for no resonance shape."""
    x = (f / fp) ** 2 - 1.0
    h = float(np.abs(x).max())
    if h == 0:
        return None
    t = x / h
    # 1/P scatters by (relative error)/P: each row weighted by P gives every bin the same relative
    # error. (Weights from the fitted P instead, reweighted, were no better over 11 averages and
    # failed on a single FFT's exponentially scattered bins.)
    rows = np.column_stack([np.ones_like(t), t, t * t]) * power[:, None]
    rhs = np.ones_like(t)  # (1/P)·P
    coef, *_ = np.linalg.lstsq(rows, rhs, rcond=None)
    natural = _natural(coef, h)
    if natural is None:
        return None
    xn, zeta = natural
    c0, c1, c2 = coef[0], coef[1] / h, coef[2] / (h * h)
    # the fitted 1/P's minimum m at x* = −c1/(2c2); half power where 1/P = 2m: x = x* ± √(m/c2)
    xs = -c1 / (2.0 * c2)
    m = c0 - c1 * c1 / (4.0 * c2)
    if not m > 0:
        return None
    d = math.sqrt(m / c2)
    if not xs - d > -1.0:
        return None
    f1, f2 = fp * math.sqrt(1.0 + xs - d), fp * math.sqrt(1.0 + xs + d)
    spread = _spread(rows, rhs, coef, h)
    return zeta, spread, f1, f2, fp * math.sqrt(1.0 + xn), int(f.size)


def _spread(rows, rhs, coef, h) -> float:
    """One standard deviation of ξ from the residuals of the weighted fit (linearised)."""
    n = rows.shape[0]
    resid = rows @ coef - rhs
    s2 = float(resid @ resid) / max(n - 3, 1)
    try:
        cov = s2 * np.linalg.inv(rows.T @ rows)
    except np.linalg.LinAlgError:
        return math.inf
    # the gradient of ξ(coef) by central differences (ξ is smooth where it exists)
    grad = np.zeros(3)
    for i in range(3):
        step = 1e-6 * max(abs(coef[i]), 1e-12)
        up, dn = coef.copy(), coef.copy()
        up[i] += step
        dn[i] -= step
        zu, zd = _natural(up, h), _natural(dn, h)
        if zu is None or zd is None:
            return math.inf
        grad[i] = (zu[1] - zd[1]) / (2 * step)
    var = float(grad @ cov @ grad)
    return math.sqrt(var) if var >= 0 else math.inf


def _natural(coef, h) -> tuple[float, float] | None:
    """``(xn, ξ)`` of the fitted ``1/P = c0 + c1·t + c2·t²`` (t = x/h), or None for no resonance.

    1/|H|² ∝ (x − xn)² + 4ξ²(1 + xn)(1 + x) with xn = (fn/fp)² − 1: c1/c2 = −2xn + 4ξ²(1 + xn) and
    c0/c2 = xn² + 4ξ²(1 + xn); their difference gives xn, then ξ.
    """
    c0, c1, c2 = coef[0], coef[1] / h, coef[2] / (h * h)
    if not c2 > 0 or not 1.0 + (c0 - c1) / c2 > 0:
        return None
    xn = math.sqrt(1.0 + (c0 - c1) / c2) - 1.0
    z2 = (c0 / c2 - xn * xn) / (4.0 * (1.0 + xn))
    return (xn, math.sqrt(z2)) if z2 > 0 else None
