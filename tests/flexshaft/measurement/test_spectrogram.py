"""spectrogram(): scipy.signal.spectrogram's power converted to amplitude, a run-up's order line and a
constant eigenfrequency found by ridge(), order lines in closed form, a 10-minute record in bounded
memory."""

from __future__ import annotations

import json
import tracemalloc

import numpy as np
import pytest
import scipy.signal

from flexshaft.errors import ModelError
from flexshaft.measurement.spectrogram import Spectrogram, order_lines, ridge, spectrogram


@pytest.mark.parametrize(
    "window, nper, overlap, detrend, scipy_window, scipy_detrend",
    [
        ("hann", 400, 0.5, "mean", "hann", "constant"),
        ("flattop", 401, 0.75, "linear", "flattop", "linear"),  # odd: no Nyquist bin
        ("rect", 256, 0.0, "none", "boxcar", False),
    ],
)
def test_matches_scipy_spectrogram(window, nper, overlap, detrend, scipy_window, scipy_detrend):
    rate, n = 1000.0, 12345
    rng = np.random.default_rng(5)
    t = np.arange(n) / rate
    x = 1.0 + np.sin(2 * np.pi * (30 * t + 4 * t**2)) + rng.normal(0.0, 0.3, n)
    s = spectrogram(x, rate, segment=nper / rate, overlap=overlap, window=window, detrend=detrend)
    noverlap = int(round(overlap * nper))
    f, times, sxx = scipy.signal.spectrogram(
        x,
        rate,
        window=scipy.signal.get_window(scipy_window, nper),
        nperseg=nper,
        noverlap=noverlap,
        detrend=scipy_detrend,
        scaling="spectrum",
        mode="psd",
    )
    # scipy's 'spectrum' power is |X|²/(Σw)², doubled except at DC and (even nper) Nyquist; our
    # amplitude is 2|X|/Σw inside and |X|/Σw at those ends.
    amp = np.sqrt(2.0 * sxx)
    amp[0] = np.sqrt(sxx[0])
    if nper % 2 == 0:
        amp[-1] = np.sqrt(sxx[-1])
    assert np.array_equal(s.frequencies_hz, f)
    assert np.allclose(s.times_s, times, rtol=1e-15, atol=0)  # (whole numbers)/rate both: <= 1 rounding each
    assert s.amplitude.shape == amp.shape == (nper // 2 + 1, (n - nper) // (nper - noverlap) + 1)
    # the same FFT of the same segments: rounding, ~eps·log2(401) ≈ 2e-15 relative to the largest
    # amplitude (detrending and windowing add a few eps); 1e-12 leaves 500x
    assert np.max(np.abs(s.amplitude - amp)) <= 1e-12 * amp.max()
    assert s.resolution_hz == rate / nper and s.segment_s == nper / rate and s.speed_rpm is None


RATE, RUN = 1600.0, 40.0  # a 40 s run-up sampled at 1.6 kHz


@pytest.fixture(scope="module")
def runup():
    """600 -> 3000 rpm linearly; order 2 (20 -> 100 Hz, amplitude 2) and a 73 Hz eigenfrequency (0.5)."""
    t = np.arange(int(RUN * RATE)) / RATE
    rpm = 600.0 + 2400.0 * t / RUN
    order2 = 2.0 * np.sin(2 * np.pi * 2 * (600.0 * t + 1200.0 * t**2 / RUN) / 60.0)  # phase: 2·∫n/60 dt
    x = order2 + 0.5 * np.sin(2 * np.pi * 73.0 * t)
    return spectrogram(x, RATE, segment=1.0, speed=rpm)


def test_the_speed_is_the_mean_over_each_segment(runup):
    nper, step = 1600, 800
    starts = np.arange(runup.times_s.size) * step
    # the mean of a linear ramp over samples k .. k+nper-1 is its value at sample k + (nper-1)/2
    expected = 600.0 + 2400.0 * ((starts + (nper - 1) / 2) / RATE) / RUN
    # Cumulative-sum rounding: a running sum to 1.2e8 over 64 000 samples errs by at most ~k·eps/2·sum/2 =
    # 4e-4, differenced and over 1600 samples 5e-7 rpm, 2e-10 of the speed (a random walk: ~1e-12).
    assert np.allclose(runup.speed_rpm, expected, rtol=1e-9, atol=0)
    assert np.allclose(runup.times_s, (starts + nper / 2) / RATE, rtol=1e-15, atol=0)  # one rounding


def test_ridge_follows_the_order_line_and_the_eigenfrequency(runup):
    line = order_lines(runup.speed_rpm, [2])[2]
    along = ridge(runup, 10.0, 120.0)  # the order (amplitude 2) dominates the 73 Hz line (0.5)
    apart = np.abs(line - 73.0) > 3 * runup.resolution_hz  # beyond Hann's main lobe (±2 bins)
    assert apart.sum() >= 70
    # A linear chirp's windowed spectrum is symmetric about its centre frequency, so the Hann
    # log-parabola's bias (≤ 0.016 bin, see test_spectrum) is all; the stored speed is centred half
    # a sample before the segment centre: 6e-4 Hz here. 0.02 bin.
    assert np.max(np.abs(along - line)[apart]) <= 0.02 * runup.resolution_hz
    far = np.abs(line - 73.0) > 6 * runup.resolution_hz  # the order outside the band [70, 76]
    eigen = ridge(runup, 70.0, 76.0)[far]
    # On a bin the log-parabola's vertex is the bin. The order's Hann sidelobes > 6 bins away,
    # |W| ≤ 1/(πν(ν²-1)) = 1.5e-3 of 2.0 = 6e-3 of 0.5, shift it by ~ that over the parabola's
    # curvature 2·ln 2: ≤ 5e-3 bin. 0.02 bin.
    assert np.max(np.abs(eigen - 73.0)) <= 0.02 * runup.resolution_hz


def test_order_lines_closed_form():
    lines = order_lines(1500.0, [0.5, 1, 2])
    assert lines[0.5] == 12.5 and lines[1] == 25.0 and lines[2.0] == 50.0  # k·n/60
    arr = order_lines(np.array([600.0, -3000.0]), 3)
    assert np.array_equal(arr[3.0], [30.0, 150.0])  # the other direction: the same frequencies
    for speed, orders, field in (
        (1500.0, [0.0], "orders"),
        (1500.0, [-1.0], "orders"),
        (1500.0, [], "orders"),
        ([np.nan], [1], "speed_rpm"),
        (["fast"], [1], "speed_rpm"),
    ):
        with pytest.raises(ModelError) as err:
            order_lines(speed, orders)
        assert err.value.field == field


def test_ten_minutes_at_1600_hz_in_bounded_memory():
    n = int(600 * RATE)  # 960 000 samples
    x = np.random.default_rng(0).normal(size=n)
    tracemalloc.start()
    try:
        s = spectrogram(x, RATE, segment=1.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert s.amplitude.shape == (801, 1199)  # (n - 1600) // 800 + 1 segments
    # Beyond the result (7.7 MB) one block of 2^18 samples is alive: detrended, windowed, its
    # complex FFT and magnitudes, ~8 MB. All segments at once would be 1199 x 1600 x 32 B = 61 MB.
    assert peak < s.amplitude.nbytes + 16e6


def test_to_dict_is_json(runup):
    doc = json.loads(json.dumps(runup.to_dict()))
    assert doc["units"]["speed"] == "rpm" and len(doc["amplitude"]) == runup.frequencies_hz.size
    assert doc["speed_rpm"] == runup.speed_rpm.tolist()


def test_ridge_of_silence_is_nan_and_bad_bands_are_refused():
    s = spectrogram(np.zeros(1000), 100.0, segment=1.0, detrend="none")
    assert isinstance(s, Spectrogram) and np.all(np.isnan(ridge(s, 10.0, 20.0)))
    for f_lo, f_hi, field in ((20.0, 10.0, "f_hi"), (10.2, 10.8, "f_hi"), (-1.0, 10.0, "f_lo")):
        with pytest.raises(ModelError) as err:
            ridge(s, f_lo, f_hi)
        assert err.value.field == field
    with pytest.raises(ModelError) as err:
        ridge("spectrogram", 1.0, 2.0)
    assert err.value.field == "spectrogram"


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"segment": None}, "segment"),
        ({"segment": 20.0}, "segment"),
        ({"segment": 0.01}, "segment"),
        ({"overlap": 1.5}, "overlap"),
        ({"window": "kaiser"}, "window"),
        ({"speed": np.ones(10)}, "speed"),
        ({"speed": np.full(1000, np.nan)}, "speed"),
        ({"rate": 0.0}, "rate"),
    ],
)
def test_bad_input_is_one_model_error(kwargs, field):
    args = {"segment": 1.0, "rate": 100.0} | kwargs
    rate = args.pop("rate")
    with pytest.raises(ModelError) as err:
        spectrogram(np.sin(np.arange(1000.0)), rate, **args)
    assert err.value.field == field
