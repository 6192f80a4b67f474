"""Damping of a free decay: log decrement in time, half power in frequency with a window fit for a
transient, against an analytic 1-DOF decay x = C + A·e^(−ξωt)·sin(ω_d t) with ξ = 0.0053."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.measurement.decay import decay_damping, log_decrement
from flexshaft.measurement.spectrum import spectrum

XI, FN, RATE = 0.0053, 20.0, 1000.0  # 50 samples per period
WN = 2 * math.pi * FN
WD = WN * math.sqrt(1 - XI**2)
SIGMA = XI * WN  # 0.666 1/s


def decay(seconds, *, offset=500.0, amplitude=2.0, xi=XI, fn=FN, rate=RATE):
    """A free decay on a static torque, sampled from t = 0 (its start)."""
    t = np.arange(int(round(seconds * rate))) / rate
    wn = 2 * math.pi * fn
    return t, offset + amplitude * np.exp(-xi * wn * t) * np.sin(wn * math.sqrt(1 - xi**2) * t)


# --- log decrement -----------------------------------------------------------------------------------


def test_log_decrement_of_an_analytic_decay():
    t, x = decay(30.0)
    d = log_decrement(t, x)
    assert 0.0050 <= d.damping_ratio <= 0.0056
    # Each amplitude is a 3-sample parabola's extremum at 50 samples per period: off by at most
    # ~(2π/50)⁴/8 = 3e-5 of itself, scattered, over the ln(1/0.02) = 3.9 nepers fitted: the slope to
    # ~1e-5. 1e-3 leaves ample margin; half the peak-to-peak ignores the static 500 N·m.
    assert d.damping_ratio == pytest.approx(XI, rel=1e-3)
    assert d.decay_rate == pytest.approx(SIGMA, rel=1e-3)
    # The zero crossings are shifted by the record mean's small bias from the decay (5e-4 of the
    # static value: ∫decay/T), a few 1e-5 s over a 6 s span: 1e-4 relative.
    assert d.frequency_hz == pytest.approx(WD / (2 * math.pi), rel=1e-4)
    # the cycles from the largest down to 2 %: ln(50)/σ = 5.9 s of 20 Hz, ~117 cycles
    assert abs(d.cycles - math.log(50) / SIGMA * FN) <= 2
    assert d.notes == ()
    given = log_decrement(t, x, frequency_hz=WD / (2 * math.pi))
    assert given.damping_ratio == pytest.approx(XI, rel=1e-3) and given.frequency_hz == WD / (2 * math.pi)


def test_log_decrement_isolates_one_of_two_modes_with_a_band():
    t, x1 = decay(20.0)
    _, x2 = decay(20.0, offset=0.0, amplitude=1.5, xi=0.01, fn=55.0)
    x = x1 + x2
    mixed = log_decrement(t, x)
    assert any("not one exponential" in n for n in mixed.notes)  # the two modes beat
    # The band-pass skips its edges until its own transients are below 1e-4, and the other mode is
    # > 60 dB down (order 4 twice, two octaves out): ln(amplitude) moves by < 1e-3 over 3.9 nepers.
    first = log_decrement(t, x, band=(15.0, 27.0))
    assert first.damping_ratio == pytest.approx(XI, rel=5e-3)
    assert first.frequency_hz == pytest.approx(WD / (2 * math.pi), rel=1e-4)
    assert "sosfiltfilt" in first.method and first.notes == ()
    second = log_decrement(t, x, band=(45.0, 65.0))
    assert second.damping_ratio == pytest.approx(0.01, rel=5e-3)


def test_log_decrement_with_measurement_noise():
    t, x = decay(20.0)
    noisy = x + np.random.default_rng(11).normal(0.0, 0.002, t.size)  # 0.1 % of the amplitude
    d = log_decrement(t, noisy, band=(15.0, 27.0))
    # The 12 Hz band keeps 12/500 of the white noise's power: rms 3e-4, under 1 % of the amplitude
    # at the 2 % floor (0.04). ln errors of < 0.01 on the last cycles, none on the first, averaged by
    # the least squares over ~120 cycles: the slope moves by ~1e-3. 1e-2: margin.
    assert d.damping_ratio == pytest.approx(XI, rel=1e-2)


def test_log_decrement_refuses_too_few_cycles_and_bad_input():
    t, x = decay(0.1)  # two cycles
    with pytest.raises(ModelError, match="cycles") as err:
        log_decrement(t, x)
    assert err.value.field == "x"
    t, x = decay(2.0)
    for kwargs, field in (
        ({"band": (0.0, 30.0)}, "band"),
        ({"band": (30.0, 600.0)}, "band"),
        ({"band": (30.0, 20.0)}, "band"),
        ({"band": 20.0}, "band"),
        ({"frequency_hz": -1.0}, "frequency_hz"),
    ):
        with pytest.raises(ModelError) as err:
            log_decrement(t, x, **kwargs)
        assert err.value.field == field, kwargs
    with pytest.raises(ModelError) as err:
        log_decrement(t[::-1], x)
    assert err.value.field == "t"
    with pytest.raises(ModelError) as err:
        log_decrement(np.r_[t[:10], t[10:] + 1e-4], x)  # one step longer than the others
    assert err.value.field == "t" and "uniformly" in str(err.value)
    with pytest.raises(ModelError) as err:
        log_decrement(t[:-1], x)
    assert err.value.field == "t"


# --- half power of the whole transient ---------------------------------------------------------------


def test_rect_window_on_a_decay_that_has_died_out():
    t, x = decay(20.0)  # envelope at the end e^(-σT) = 2e-6
    d = decay_damping(t, x)
    assert 0.0050 <= d.damping_ratio <= 0.0056
    # The half-power relations are exact for the spectrum of e^(-σt)·sin(ω_d t). What remains: the
    # linear interpolation of the crossings, ≤ 1/(8B²) of the bandwidth per side with B = 34
    # zero-padded bins (1e-4), and the truncated tail (2e-6). 1e-3: a 5x margin.
    assert d.damping_ratio == pytest.approx(XI, rel=1e-3)
    assert d.frequency_hz == pytest.approx(WD / (2 * math.pi), rel=1e-5)  # 5e-4 bin of 1/T
    assert d.window == "rect" and d.tau_s is None and d.notes == ()
    assert d.resolution_hz == pytest.approx(1 / 20.0)


def test_exponential_window_on_a_decay_cut_short():
    t, x = decay(3.0)  # the envelope is still e^(-2) = 14 % at the end
    rect = decay_damping(t, x)
    assert any("not died out" in n for n in rect.notes)
    assert not 0.0050 <= rect.damping_ratio <= 0.0056  # leakage: the cut end widens the peak
    d = decay_damping(t, x, window="exponential")
    assert 0.0050 <= d.damping_ratio <= 0.0056
    # The window's 1/τ = 2 1/s is subtracted exactly. The windowed decay has died to e^(-8) = 3e-4
    # and spans 20 zero-padded bins (interpolation ≤ 1/(8·20²) = 3e-4 per side): its rate 2.67 1/s
    # is read to ~1e-3, and the difference σ = 2.67 - 2 carries 4x that relative error. 1e-2: margin.
    assert d.damping_ratio == pytest.approx(XI, rel=1e-2)
    assert d.tau_s == pytest.approx(0.5) and d.window == "exponential" and d.notes == ()
    # the peak as measured carries the window's damping: (σ + 1/τ)/ω
    assert d.peak.damping_ratio == pytest.approx((SIGMA + 1 / d.tau_s) / WN, rel=1e-2)
    assert decay_damping(t, x, window="exponential", tau=0.4).damping_ratio == pytest.approx(XI, rel=1e-2)


def test_hann_on_a_long_decay_reads_about_half_the_damping():
    # Why decay_damping offers no Hann: on a record much longer than the decay the Hann-windowed
    # decay is ≈ (πt/T)²·e^(-σt), whose spectrum ∝ |σ + iΔω|^-3 is down to 1/√2 at
    # Δω = σ·√(2^(1/3) - 1) = 0.51·σ, and falls faster than the 1-DOF shape beyond: any reading of
    # its width - the half-power points, or the 1-DOF fit find_peaks makes - is about half ξ or less
    # (the record-length correction is O(1/σT) = 1 %, the resolution 13 bins in the bandwidth).
    t, x = decay(120.0)
    hann = spectrum(x, RATE, window="hann").peaks(count=1)[0]
    assert 0 < hann.damping_ratio <= 1.05 * math.sqrt(2 ** (1 / 3) - 1) * XI  # clearly wrong
    for window in ("rect", "exponential"):
        assert 0.0050 <= decay_damping(t, x, window=window).damping_ratio <= 0.0056, window


def test_decay_damping_finds_the_mode_in_a_band():
    t, x1 = decay(20.0)
    _, x2 = decay(20.0, offset=0.0, amplitude=4.0, xi=0.01, fn=55.0)
    d = decay_damping(t, x1 + x2, band=(10.0, 30.0))
    # the 55 Hz mode's skirt at 20 Hz is ~1e-3 of the 20 Hz peak: tilts its half-power points by less
    # than that fraction of the bandwidth
    assert d.damping_ratio == pytest.approx(XI, rel=5e-3)
    # without a band, the largest peak: A/(2σ) = 1.5 at 20 Hz against 4/(2·3.46) = 0.58 at 55 Hz
    assert decay_damping(t, x1 + x2).frequency_hz == pytest.approx(WD / (2 * math.pi), rel=1e-4)


def test_decay_damping_refuses_bad_input():
    t, x = decay(2.0)
    for kwargs, field in (
        ({"window": "hann"}, "window"),
        ({"tau": 0.5}, "tau"),  # with the rectangular window
        ({"window": "exponential", "tau": 0.0}, "tau"),
        ({"band": (600.0, 700.0)}, "band"),
        ({"band": (100.0, 100.01)}, "band"),  # narrower than a zero-padded bin (1/16 Hz): no peak
    ):
        with pytest.raises(ModelError) as err:
            decay_damping(t, x, **kwargs)
        assert err.value.field == field, kwargs
    with pytest.raises(ModelError) as err:
        decay_damping(t, np.r_[x[:-1], np.inf])
    assert err.value.field == "x"


@pytest.mark.parametrize("analyse", [decay_damping, log_decrement])
def test_a_narrow_band_far_below_the_rate_raises_no_warning(analyse):
    # A 0.05-0.14 Hz band at 1 kHz (what `spectrum --decay` chose on a speed ramp): the Butterworth
    # numerators are tiny, and scipy's sos2zpk warned "badly conditioned" on stderr. The filter's
    # poles come from its denominators alone now. The band may still be refused (the record is short
    # for so slow a filter) - with one error, never a warning.
    from flexshaft.errors import ModelError

    rate = 1000.0
    t = np.arange(0, 11.0, 1 / rate)
    y = np.cos(2 * np.pi * 12.7 * t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            analyse(t, y, band=(0.045, 0.136))
        except ModelError:
            pass
