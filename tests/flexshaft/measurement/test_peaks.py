"""find_peaks / half_power_damping: a damped oscillator's |H| with known ξ, the order and selection of
peaks, and the notes when the bandwidth cannot be read."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.measurement.peaks import Peak, find_peaks, half_power_damping
from flexshaft.measurement.spectrum import spectrum

XI, FN = 0.0053, 25.0


def _frf(f, fn=FN, xi=XI):
    """Receptance of a 1-DOF oscillator normalised to its static value: 1 / (1 - r² + 2iξr)."""
    r = f / fn
    return 1.0 / (1.0 - r**2 + 2j * xi * r)


def _exact_half_power_ratio(xi):
    """(f2 - f1) / (2 f_peak) of |H| in closed form: r1,2² = 1 - 2ξ² ∓ 2ξ√(1-ξ²), r_peak² = 1 - 2ξ²."""
    root = 2 * xi * math.sqrt(1 - xi**2)
    return (math.sqrt(1 - 2 * xi**2 + root) - math.sqrt(1 - 2 * xi**2 - root)) / (
        2 * math.sqrt(1 - 2 * xi**2)
    )


def test_half_power_damping_of_a_damped_oscillator():
    step = 0.005  # the bandwidth 2ξ·fn = 0.265 Hz spans 53 steps
    f = np.arange(0.0, 50.0 + step / 2, step)
    peak = half_power_damping(f, np.abs(_frf(f)))
    # Linear interpolation of a half-power crossing errs by at most h²·|a''|/(8|a'|); at the
    # half-power point of this peak a''/a' = 1/(2·half-bandwidth), so per side ≤ 1/(8·B²) of the
    # bandwidth with B = 53 bins: 4.4e-5. Both sides: < 1e-4; 1e-3 leaves a 10x margin.
    assert peak.damping_ratio == pytest.approx(_exact_half_power_ratio(XI), rel=1e-3)
    assert 0.0050 <= peak.damping_ratio <= 0.0056
    # the closed form differs from ξ itself only by O(ξ²) = 3e-5 relative
    assert _exact_half_power_ratio(XI) == pytest.approx(XI, rel=1e-4)
    # the peak of |H| lies at fn·√(1 - 2ξ²), between grid points: within 0.05 bin
    assert abs(peak.frequency_hz - FN * math.sqrt(1 - 2 * XI**2)) <= 0.05 * step
    # its height is 1/(2ξ√(1-ξ²)); the log-parabola over a peak 53 bins wide is exact to O((1/53)²)
    assert peak.amplitude == pytest.approx(1 / (2 * XI * math.sqrt(1 - XI**2)), rel=1e-3)
    assert peak.bins_in_bandwidth == pytest.approx(2 * XI * FN / step, rel=1e-3)
    assert peak.notes == ()


def test_a_coarse_grid_gets_a_note_not_an_exception():
    step = 0.1  # 2.65 bins in the bandwidth
    f = np.arange(0.0, 50.0 + step / 2, step)
    peak = half_power_damping(f, np.abs(_frf(f)))
    assert len(peak.notes) == 1 and "too coarse" in peak.notes[0] and "finer frequency grid" in peak.notes[0]
    assert peak.bins_in_bandwidth < 5


def test_a_half_power_point_past_the_end_is_nan_with_a_note():
    f = np.arange(24.9, 30.0, 0.005)  # starts 0.09 Hz below the peak, inside its half-bandwidth 0.13 Hz
    peak = half_power_damping(f, np.abs(_frf(f)))
    assert math.isnan(peak.f_low_hz) and math.isnan(peak.damping_ratio) and math.isnan(peak.bins_in_bandwidth)
    assert peak.f_high_hz > peak.frequency_hz
    assert any("spectrum ends" in n for n in peak.notes)
    assert json.loads(json.dumps(peak.to_dict()))["damping_ratio"] is None


def test_a_neighbouring_mode_inside_the_half_power_band_is_nan_with_a_note():
    # two modes 0.3 Hz apart, each 0.265 Hz wide: the amplitude rises again before falling to 1/√2
    f = np.arange(20.0, 30.0, 0.005)
    peak = half_power_damping(f, np.abs(_frf(f) + _frf(f, fn=FN + 0.3)))
    assert math.isnan(peak.damping_ratio)
    assert any("another peak" in n for n in peak.notes)


def test_peaks_largest_first_count_and_threshold():
    rate, n = 1000.0, 2000
    t = np.arange(n) / rate
    x = (
        1.0 * np.sin(2 * np.pi * 40 * t)
        + 5.0 * np.sin(2 * np.pi * 100 * t)
        + 0.002 * np.sin(2 * np.pi * 230 * t)
    )
    s = spectrum(x, rate)

    # All three on bins: Hann leaves nothing elsewhere but rounding (~1e-16 of the largest), and each
    # peak's neighbours hold A/2 both, so the parabola's vertex is the bin up to rounding: for the 0.002
    # tone beside one of 5, ~eps·5 on its A/2 = 1e-3, a vertex ~1e-12 bin (5e-13 Hz) off; abs 1e-9 Hz.
    def freqs(peaks):
        return pytest.approx([p.frequency_hz for p in peaks], abs=1e-9)

    assert freqs(find_peaks(s)) == [100.0, 40.0]  # 0.002/5 is below 1e-3
    assert freqs(find_peaks(s, min_relative=1e-4)) == [100.0, 40.0, 230.0]
    assert freqs(s.peaks(count=1)) == [100.0]
    (p,) = s.peaks(1)
    # On a bin: A·Σw/2 up to the FFT's rounding, ~eps·log2(2000) ≈ 3e-15 relative
    assert isinstance(p, Peak) and p.amplitude == pytest.approx(5.0, rel=1e-12)
    # a tone's peak is the window's main lobe, 1.2 bins at half power: the note says so
    assert "too coarse" in p.notes[0] and "record longer" in p.notes[0]
    welch = spectrum(x, rate, segment=0.5)
    assert "segment longer" in welch.peaks(1)[0].notes[0]


@pytest.mark.parametrize(
    "spec_or_kwargs, field",
    [
        ("not a spectrum", "spectrum"),
        ({"count": 0}, "count"),
        ({"count": 1.5}, "count"),
        ({"min_relative": 2.0}, "min_relative"),
    ],
)
def test_find_peaks_refuses_bad_input(spec_or_kwargs, field):
    s = spectrum(np.sin(np.arange(100.0)), 10.0)
    with pytest.raises(ModelError) as err:
        if isinstance(spec_or_kwargs, str):
            find_peaks(spec_or_kwargs)
        else:
            find_peaks(s, **spec_or_kwargs)
    assert err.value.field == field


@pytest.mark.parametrize(
    "f, a, field",
    [
        ([1.0, 2.0, 4.0], [0.0, 1.0, 0.0], "frequencies_hz"),
        ([1.0, 2.0, 3.0], [0.0, 1.0], "amplitude"),
        ([1.0, 2.0, 3.0], [0.0, -1.0, 0.0], "amplitude"),
        ([1.0, 2.0, 3.0], [0.0, np.nan, 0.0], "amplitude"),
        ([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], "amplitude"),  # rising: no peak inside
    ],
)
def test_half_power_damping_refuses_bad_input(f, a, field):
    with pytest.raises(ModelError) as err:
        half_power_damping(f, a)
    assert err.value.field == field
