"""spectrum(): amplitude-correct against closed forms (a sinusoid's amplitude, Parseval, the windows'
noise bandwidths) and against scipy.signal.welch; every bad input one ModelError."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.signal

from flexshaft.errors import ModelError
from flexshaft.measurement.spectrum import Spectrum, spectrum, window

RATE = 1000.0
N = 2000  # 2 s: bins every 0.5 Hz
T = np.arange(N) / RATE
# scipy's flattop coefficients, as its documentation of scipy.signal.windows.flattop gives them
FLATTOP = (0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368)


@pytest.mark.parametrize("name", ["hann", "rect", "flattop"])
def test_a_sinusoid_on_a_bin_reads_its_amplitude(name):
    x = 1.5 + 3.7 * np.sin(2 * np.pi * 50.0 * T + 0.3)  # 50 Hz = bin 100
    s = spectrum(x, RATE, window=name)
    # On a bin every one of these windows' kernels is zero at all other bins (Hann ±1, flattop ±4,
    # rect 0), the image at -50 Hz included: the bin holds A·Σw/2 exactly, so only rounding remains:
    # a 2000-point FFT's, ~eps·log2(2000) ≈ 3e-15 of the largest amplitude; 1e-12 leaves 300x.
    assert s.frequencies_hz[100] == 50.0
    assert s.amplitude[100] == pytest.approx(3.7, rel=1e-12)
    assert s.amplitude[0] < 1e-12  # the static 1.5 removed by detrend="mean": rounding, ~1e-15 of 3.7
    raw = spectrum(x, RATE, window=name, detrend="none")
    # DC is not doubled; a whole number of periods of sin has Σw·sin = 0 (DFT orthogonality)
    assert raw.amplitude[0] == pytest.approx(1.5, rel=1e-12)


@pytest.mark.parametrize("name", ["hann", "rect", "flattop"])
def test_the_nyquist_bin_is_not_doubled(name):
    x = 0.8 * (-1.0) ** np.arange(N)  # a cosine at the Nyquist frequency, 500 Hz
    s = spectrum(x, RATE, window=name)
    assert s.frequencies_hz[-1] == 500.0
    # Σ w·x·(-1)^k = 0.8·Σw: rounding only, ~eps·log2(N) ≈ 3e-15 relative
    assert s.amplitude[-1] == pytest.approx(0.8, rel=1e-12)


def _hann_kernel(nu):
    """The continuous Hann kernel, normalised to 1 at 0: sinc(ν)/(1 - ν²) (ν in bins; 1/2 at ν = ±1)."""
    at_one = np.isclose(np.abs(nu), 1.0)
    return np.where(at_one, 0.5, np.abs(np.sinc(nu) / np.where(at_one, 1.0, 1.0 - nu**2)))


def test_an_off_bin_tone_is_interpolated_within_the_hann_log_parabola_bias():
    # The bound, from the closed-form kernel: a tone δ bins above bin k leaves |W(δ+1)|, |W(δ)|,
    # |W(δ-1)| in bins k-1, k, k+1; the log-parabola's vertex through them is off by a bias that
    # depends on δ only. Its worst case over δ in [0, 0.5] is the tolerance (plus 1e-3 for the
    # finite-length kernel, O(1/n²), and the image's leakage, Hann sidelobes ∝ 1/ν³ at ν ≈ 200).
    d = np.linspace(0.0, 0.5, 501)
    a, b, c = (np.log(_hann_kernel(d + s)) for s in (1.0, 0.0, -1.0))
    p = 0.5 * (a - c) / (a - 2 * b + c)
    freq_bias = np.max(np.abs(p - d))
    amp_bias = np.max(np.abs(np.exp(b - 0.25 * (a - c) * p) - 1.0))
    assert freq_bias < 0.05 and amp_bias < 0.04  # what the docs promise: 0.02 bin, 3.8 %
    for delta in (0.0, 0.1, 0.25, 0.4, 0.5):
        f0 = (120 + delta) * 0.5
        s = spectrum(2.5 * np.sin(2 * np.pi * f0 * T + 1.0), RATE)
        (peak,) = s.peaks(count=1)
        assert abs(peak.frequency_hz - f0) / s.resolution_hz <= freq_bias + 1e-3
        assert peak.amplitude == pytest.approx(2.5, rel=amp_bias + 1e-3)


def test_flattop_reads_an_off_bin_tone_amplitude_at_its_largest_bin():
    # flattop's worst scalloping is its kernel half a bin off, computed here from scipy's window
    w = scipy.signal.get_window("flattop", N)
    half = abs(np.sum(w * np.exp(-1j * np.pi * np.arange(N) / N))) / w.sum()
    assert 1 - half < 2e-3
    for delta in (0.0, 0.3, 0.5):
        f0 = (120 + delta) * 0.5
        s = spectrum(2.5 * np.sin(2 * np.pi * f0 * T), RATE, window="flattop")
        assert s.amplitude.max() == pytest.approx(2.5, rel=(1 - half) + 1e-4)
        assert s.peaks(1)[0].amplitude == s.amplitude.max()  # flattop: the bin, not a parabola


@pytest.mark.parametrize(
    "name, detrend, scipy_detrend",
    [("hann", "mean", "constant"), ("flattop", "linear", "linear"), ("rect", "none", False)],
)
def test_welch_averaging_matches_scipy_welch(name, detrend, scipy_detrend):
    rate, n = 1600.0, 32000  # 20 s
    rng = np.random.default_rng(7)
    t = np.arange(n) / rate
    x = 3.0 + 0.1 * t + 2.0 * np.sin(2 * np.pi * 73.3 * t) + rng.normal(0.0, 0.5, n)
    s = spectrum(x, rate, window=name, segment=1.0, overlap=0.5, detrend=detrend)
    f, pxx = scipy.signal.welch(
        x,
        rate,
        window=scipy.signal.get_window("boxcar" if name == "rect" else name, 1600),
        nperseg=1600,
        noverlap=800,
        detrend=scipy_detrend,
        scaling="spectrum",
    )
    # welch's 'spectrum' scaling is the mean of |X|²/(Σw)², doubled except at DC and Nyquist;
    # the amplitude² is 4|X|²/(Σw)² inside, |X|²/(Σw)² at the two ends.
    amp2 = 2.0 * pxx
    amp2[[0, -1]] = pxx[[0, -1]]
    assert np.array_equal(s.frequencies_hz, f)
    assert s.averages == (n - 1600) // 800 + 1 == 39
    # the same sums in another order: rounding of 39 averaged 1600-point FFTs, ~eps·log2(1600) ≈ 2e-15
    # relative to the largest bin; 1e-12 leaves 500x
    assert np.max(np.abs(s.amplitude**2 - amp2)) <= 1e-12 * amp2.max()
    assert s.segment_s == 1.0 and s.resolution_hz == 1.0


@pytest.mark.parametrize("name", ["hann", "rect", "flattop"])
def test_parseval(name):
    # Σ_k |X_k|² = n Σ (w x)² over the full DFT; in single-sided amplitudes (A_k = 2|X_k|/Σw inside,
    # |X_k|/Σw at DC and Nyquist) that is (Σw)²·(A_0² + Σ A_k²/2 + A_Nyq²). Exact up to rounding: sums of
    # 2000 positive terms and an FFT, ~eps·log2(2000) ≈ 3e-15 relative; 1e-12 leaves 300x.
    rng = np.random.default_rng(3)
    x = rng.normal(size=N)
    s = spectrum(x, RATE, window=name, detrend="none")
    w = window(name, N)
    a = s.amplitude
    lhs = w.sum() ** 2 * (a[0] ** 2 + np.sum(a[1:-1] ** 2) / 2 + a[-1] ** 2)
    assert lhs == pytest.approx(N * np.sum((w * x) ** 2), rel=1e-12)


def test_noise_bandwidths_are_the_windows_closed_forms():
    # ENBW = n·Σw²/(Σw)² bins. Periodic Hann: Σw = n/2, Σw² = 3n/8 -> 1.5 bins. A periodic cosine
    # sum Σ (-1)^k a_k cos(2πkj/n): Σw = n·a0, Σw² = n·(a0² + Σ_{k>=1} a_k²/2) (orthogonality).
    a = np.array(FLATTOP)
    flattop_bins = (a[0] ** 2 + np.sum(a[1:] ** 2) / 2) / a[0] ** 2
    for name, bins in (("hann", 1.5), ("rect", 1.0), ("flattop", flattop_bins)):
        s = spectrum(np.sin(T), RATE, window=name)
        # rel 1e-8: the coefficients are printed with 9 digits in scipy's documentation
        assert s.enbw_hz == pytest.approx(bins * s.resolution_hz, rel=1e-8), name


def test_window_is_scipys_periodic_window():
    assert np.array_equal(window("hann", 16), scipy.signal.get_window("hann", 16))
    assert np.array_equal(window("flattop", 15), scipy.signal.get_window("flattop", 15))
    assert np.array_equal(window("rect", 4), np.ones(4))


def test_to_dict_is_json_with_units():
    s = spectrum(np.sin(2 * np.pi * 5.0 * T), RATE, segment=0.5)
    doc = json.loads(json.dumps(s.to_dict()))
    assert doc["units"]["frequency"] == "Hz" and doc["averages"] == s.averages == 7  # (2000-500)//250+1
    assert doc["amplitude"] == s.amplitude.tolist() and doc["frequencies_hz"][1] == 2.0
    assert isinstance(s, Spectrum)


BAD = [
    # (kwargs for spectrum, the field the error must name)
    ({"x": [1.0, np.nan, 2.0]}, "x"),
    ({"x": []}, "x"),
    ({"x": [1.0]}, "x"),
    ({"x": [[1.0, 2.0], [3.0, 4.0]]}, "x"),
    ({"x": ["a", "b"]}, "x"),
    ({"x": [1 + 1j, 2.0]}, "x"),
    ({"x": [[1.0], [2.0, 3.0]]}, "x"),
    ({"rate": 0.0}, "rate"),
    ({"rate": -1000.0}, "rate"),
    ({"rate": float("nan")}, "rate"),
    ({"rate": "1 kHz"}, "rate"),
    ({"segment": 3.0}, "segment"),  # the record is 2 s
    ({"segment": 0.005}, "segment"),  # 5 samples
    ({"segment": -1.0}, "segment"),
    ({"segment": 1.0, "overlap": 1.0}, "overlap"),
    ({"segment": 1.0, "overlap": -0.1}, "overlap"),
    ({"window": "hamming"}, "window"),
    ({"detrend": "quadratic"}, "detrend"),
]


@pytest.mark.parametrize("kwargs, field", BAD, ids=[f"{b[1]}-{i}" for i, b in enumerate(BAD)])
def test_bad_input_is_one_model_error_naming_the_field(kwargs, field):
    args = {"x": np.sin(T), "rate": RATE} | kwargs
    x, rate = args.pop("x"), args.pop("rate")
    with pytest.raises(ModelError) as err:
        spectrum(x, rate, **args)
    assert err.value.field == field and err.value.valid
    assert "\n" not in str(err.value)


def test_unknown_window_names_the_valid_ones():
    with pytest.raises(ModelError, match="'hann', 'rect', 'flattop'"):
        window("blackman", 8)
    with pytest.raises(ModelError) as err:
        window("hann", 0)
    assert err.value.field == "n"
