"""Spectra you can trust: one peak per resonance, a tone's amplitude wherever it lies between bins,
and a resonance's half-power damping from a noisy averaged spectrum - against signals whose answers
are known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal

from flexshaft.measurement.analyse import analyse_signal
from flexshaft.measurement.halfpower import widening
from flexshaft.measurement.peaks import find_peaks
from flexshaft.measurement.spectrum import spectrum

RATE = 1000.0


def _response(fn: float, xi: float, rate: float, duration: float, seed: int) -> np.ndarray:
    """A 1-DOF oscillator's displacement under white noise, exactly sampled: the continuous system
    discretised with the input held over each sample (zero-order hold keeps its poles exactly)."""
    wn = 2 * math.pi * fn
    num, den, _ = scipy.signal.cont2discrete(([1.0], [1.0, 2 * xi * wn, wn * wn]), 1 / rate, method="zoh")
    u = np.random.default_rng(seed).standard_normal(int(round(rate * duration)))
    return scipy.signal.lfilter(num.ravel(), den, u)


@pytest.mark.parametrize("window, tol", [("hann", 1e-3), ("rect", 5e-3), ("flattop", 1.5e-3)])
def test_a_tone_between_bins_reads_its_amplitude(window, tol):
    # Hann and rectangular: the offset δ from the ratio of the two largest bins is exact for a tone
    # of a long window (Grandke 1983); what is left is the leakage of the tone's negative-frequency
    # image into the bins, |W(2k)| at k = 100 bins: Hann ~1/(π·(2k)³) < 1e-6, rectangular
    # 1/(π·2k) = 0.16 % - and the DFT's kernel differs from the long window's by O(1/n²). Flat-top:
    # scipy's window is flat within 0.1 % over a bin (its largest bin is read).
    n = 4096
    worst = 0.0
    for delta in np.linspace(0.0, 0.5, 11):
        f = (100 + delta) * RATE / n
        x = 2.5 * np.sin(2 * np.pi * f * np.arange(n) / RATE + 0.7)
        (p,) = spectrum(x, RATE, window=window).peaks(count=1)
        worst = max(worst, abs(p.amplitude / 2.5 - 1))
        # the frequency to a hundredth of a bin (flat-top, made for amplitudes: a parabola through
        # its flat top, within 0.15 bin)
        assert abs(p.frequency_hz - f) <= (0.15 if window == "flattop" else 0.01) * RATE / n
    assert worst <= tol


def test_a_noisy_free_decay_gives_one_peak_per_resonance():
    # Regression: a noisy decay listed the resonance three times (two within 0.002 Hz of each other)
    # and noise ripple around it, with a band so narrow that the log decrement read 10x too low.
    rate, xi, fn = 2000.0, 0.0053, 91.11
    t = np.arange(int(10 * rate)) / rate
    wn = 2 * math.pi * fn
    rng = np.random.default_rng(1)
    x = np.exp(-xi * wn * t) * np.sin(wn * math.sqrt(1 - xi**2) * t) + 0.02 * rng.standard_normal(t.size)
    for window in ("rect", "exponential"):
        a = analyse_signal(t, x, name="torque", unit="N·m", decay=True, window=window, peaks=20)
        assert len(a.peaks) == 1, [p["frequency_hz"] for p in a.peaks]
        (p,) = a.peaks
        assert all(math.isfinite(p[k]) for k in ("frequency_hz", "amplitude"))
        # the damped frequency within the record's resolution 0.1 Hz; the damping within 10 %: the
        # noise (2 % of the first amplitude) is 1/20 of the decay's when it is e^-3 down, the end of
        # what either method reads
        assert abs(p["frequency_hz"] - fn) < 0.1
        assert p["damping_ratio"] == pytest.approx(xi, rel=0.1)
        assert p["log_decrement_damping_ratio"] == pytest.approx(xi, rel=0.1)


def test_welch_of_a_random_response_reads_its_damping():
    # Regression: 100 s segments over a 600 s random response read ξ = 0.024 % for 0.53 % (a walk
    # down from the largest bin stopped at the first bin noise pushed below 1/√2) and advised a
    # longer record or segment. The band 2ξf = 0.32 Hz spans 32 bins of 0.01 Hz; the fit over
    # ±2.5 bands uses ~160 bins, ~107 independent (Hann shares noise over 1.5 bins), each power
    # scattering by 1/√11 = 30 % (11 averages): ξ's scatter about 2·0.3/√107 ≈ 6 % (0.059 measured
    # over 40 records). 25 % is four of those.
    xi, fn = 0.0053, 30.0
    x = _response(fn, xi, 500.0, 600.0, seed=3)
    s = spectrum(x, 500.0, segment=100.0)
    assert s.averages == 11
    peaks = s.peaks(count=3)
    assert len(peaks) == 1  # one resonance: no noise peak clears the floor, none on its flanks
    (p,) = peaks
    assert p.damping_ratio == pytest.approx(xi, rel=0.25)
    assert 0 < p.damping_spread < 0.25 * xi and p.damping_missing is None
    # segments of 10 s: the band spans 3 bins, the window's smearing as wide as the resonance -
    # the damping is refused, and the advice is a segment long enough (5 bins: 5/(2ξf) = 15.7 s),
    # with enough of them
    (p,) = spectrum(x, 500.0, segment=10.0).peaks(count=1)
    assert math.isnan(p.damping_ratio) and "segment longer: at least" in p.damping_missing
    need = float(p.damping_missing.split("at least ")[1].split(" s")[0])
    assert 10.0 < need < 5 / (2 * xi * fn) * 1.5


@pytest.mark.parametrize("window", ["hann", "rect"])
@pytest.mark.parametrize("bins", [5.0, 8.0, 20.0, 40.0])
def test_the_windows_widening_is_divided_out(window, bins):
    # The expected spectrum of a random response is its true spectrum convolved with the window's
    # |W|² (Welch's expectation): built here by brute force - the 1-DOF |H|² on a grid 20x finer
    # than the bins, weighted by |DFT of the window|² at each offset - with no noise. The fit reads
    # its width, the widening 1 + 1/(πb) (rectangular: first order in 1/b) or 1 + 1.25·m₂/b² (Hann,
    # its coefficient read from such fits) is divided out: what is left is the next order, ~0.2 % at
    # 5-40 bins.
    n, fine = 256, 20
    w = scipy.signal.get_window("hann" if window == "hann" else "boxcar", n)
    d = np.arange(-80 * fine, 80 * fine + 1) / fine  # offsets, bins
    kernel = np.abs(np.exp(-2j * np.pi * np.outer(d, np.arange(n)) / n) @ w) ** 2
    kernel /= kernel.sum()
    fn = 4000.0  # bins of 1 Hz: ξ <= 0.5 %, so the half-power ratio is ξ to O(ξ²) < 3e-5
    xi = bins / (2 * fn)
    k = np.arange(int(fn - 8 * bins - 20), int(fn + 8 * bins + 21))
    f = k[:, None] + d[None, :]
    power = (1.0 / ((fn**2 - f**2) ** 2 + (2 * xi * fn * f) ** 2)) @ kernel

    class Expected:  # a spectrum's fields: 1 Hz bins, one average, the window named
        frequencies_hz = k.astype(float)
        amplitude = np.sqrt(power)
        resolution_hz = 1.0
        averages = 100

    Expected.window = window
    (p,) = find_peaks(Expected(), count=1)
    assert p.damping_ratio == pytest.approx(xi, rel=5e-3)
    raw = (p.f_high_hz - p.f_low_hz) / (2 * fn)  # as fitted, window included: wider by the factor
    assert abs(raw / xi - widening(window, bins)) <= 2.5e-3


def test_white_noise_has_no_peaks_but_a_tone_in_it_does():
    # One FFT of 2^20 samples: 524 288 bins of exponentially scattered power. The floor test lets a
    # bin of noise through with probability 1e-9: no noise peak; a tone 30 dB over the floor stands.
    rng = np.random.default_rng(7)
    n = 1 << 20
    x = rng.standard_normal(n)
    assert spectrum(x, RATE).peaks() == []
    t = np.arange(n) / RATE
    # a bin's noise amplitude (rms) is 2σ·√(ENBW/n) = 2·√(1.5/2^20) = 2.4e-3 under Hann: 0.1 is 32 dB over
    tone = 0.1 * np.sin(2 * np.pi * 123.4 * t)
    peaks = spectrum(x + tone, RATE).peaks()
    assert len(peaks) == 1 and abs(peaks[0].frequency_hz - 123.4) < RATE / n
    # that noise on the tone's two bins moves its amplitude by ~2.4 % rms: 10 % is four of those
    assert peaks[0].amplitude == pytest.approx(0.1, rel=0.1)
