"""A spectrum's results are numbers or say why not: a peak whose half-power points cannot be found keeps
its frequency and amplitude and names the reason its damping is missing (never a NaN row, never a
negative damping); order lists are positive finite numbers; the time column is not a signal; samples
stay where a spectrum's sums are numbers."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.simulate import Scenario, simulate
from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.measurement.checks import (
    MAX_ORDER,
    MAX_SIGNAL,
    as_signal,
    check_not_time,
    check_orders,
    parse_orders,
)
from flexshaft.measurement.decay import decay_damping
from flexshaft.measurement.peaks import find_peaks
from flexshaft.measurement.spectrogram import order_lines
from flexshaft.measurement.spectrum import spectrum
from tests.conftest import EXAMPLES


def _peaks_are_numbers_or_say_why(peaks):
    for p in peaks:
        assert math.isfinite(p.frequency_hz) and p.frequency_hz > 0 and math.isfinite(p.amplitude)
        if math.isnan(p.damping_ratio):
            assert p.damping_missing, p
        else:
            assert p.damping_ratio > 0 and p.damping_missing is None, p


def test_the_first_bin_of_a_steep_slope_is_a_peak_without_damping():
    # A ramp (the time column's spectrum): after the mean, its Hann spectrum falls from bin 1 by ~1/k²
    # while bin 0 is ~0, so the log-parabola through bins 0-2 rises 2.3x above bin 1 - a "peak" whose
    # half-power level lies above its own bin. It was reported with -50 % damping; now its damping is
    # missing, and its frequency and amplitude are the bin's.
    t = np.arange(60001) / 1000.0
    s = spectrum(t, 1000.0)
    peaks = s.peaks(count=3)
    _peaks_are_numbers_or_say_why(peaks)
    first = peaks[0]
    assert math.isnan(first.damping_ratio) and "one bin wide" in first.damping_missing
    assert first.frequency_hz == s.frequencies_hz[1] and first.amplitude == s.amplitude[1]
    assert json.loads(json.dumps(first.to_dict()))["damping_ratio"] is None


@pytest.mark.parametrize("seed", range(5))
def test_no_peak_of_a_noisy_record_has_a_negative_or_nan_damping_without_a_reason(seed):
    rng = np.random.default_rng(seed)
    t = np.arange(4096) / 1000.0
    x = (
        np.sin(2 * np.pi * 37.3 * t)
        + 0.3 * np.cumsum(rng.standard_normal(t.size))
        + rng.standard_normal(t.size)
    )
    for window in ("hann", "rect", "flattop"):
        _peaks_are_numbers_or_say_why(find_peaks(spectrum(x, 1000.0, window=window)))


def test_a_missing_half_power_point_keeps_the_frequency():
    # a decay of two modes 0.3 Hz apart, each with a half-power band of σ/π = 0.32 Hz: the amplitude rises
    # to the second peak before it falls to 1/√2 above the first. Its frequency is its peak's, not NaN.
    t = np.arange(20000) / 1000.0
    x = np.exp(-1.0 * t) * (np.sin(2 * np.pi * 25.0 * t) + 0.9 * np.sin(2 * np.pi * 25.3 * t))
    d = decay_damping(t, x, window="rect")
    assert math.isnan(d.damping_ratio) and math.isnan(d.decay_rate)
    assert "another peak" in d.damping_missing
    assert d.frequency_hz == d.peak.frequency_hz and abs(d.frequency_hz - 25.0) < 0.3


def test_a_decay_slower_than_the_exponential_window_has_no_damping_and_says_why():
    # σ = 0.005 1/s over a 1 s record: the default window (τ = T/6) adds 6 1/s, and the record resolves
    # the peak's band only to ~1 Hz - the difference is noise. It was reported as -0.035 %.
    t = np.arange(1001) / 1000.0
    x = np.exp(-0.005 * t) * np.cos(2 * np.pi * 11.6 * t)
    d = decay_damping(t, x, window="exponential")
    assert math.isnan(d.damping_ratio) and "1/tau" in d.damping_missing
    assert d.damping_missing in d.notes and abs(d.frequency_hz - 11.6) < 1.0
    # a decay that does die out in its record gets its damping back, exactly as before (ξ = 1 %)
    t = np.arange(20000) / 1000.0
    wn, xi = 2 * np.pi * 11.6, 0.01
    x = np.exp(-xi * wn * t) * np.cos(wn * math.sqrt(1 - xi * xi) * t)
    d = decay_damping(t, x, window="exponential")
    assert d.damping_missing is None and d.damping_ratio == pytest.approx(xi, rel=0.05)


@pytest.fixture(scope="module")
def short_decay(tmp_path_factory):
    """The found case: Customer 1's coast stop, 1 s (the record is too short for most peaks' bands)."""
    result = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    run = simulate(result, Scenario.coast(1000.0), ["torque:part 1"], duration=1.0)
    path = tmp_path_factory.mktemp("decay") / "decay.csv"
    fs.write_signals(path, run.time, {"torque:part 1": (run.outputs["torque:part 1"], "N·m")})
    return str(path)


@pytest.mark.parametrize("window", ["exponential", "rect"])
def test_spectrum_decay_never_prints_a_nan_row(short_decay, capsys, window):
    assert main(["spectrum", short_decay, "--column", "torque:part 1", "--decay", "--window", window]) == 0
    out = capsys.readouterr()
    assert out.err == "" and not re.search(r"\bnan\b", out.out, re.IGNORECASE), out.out
    rows = [r for r in out.out.splitlines() if re.match(r"\s+\d+\.\d{4}\s", r)]
    assert rows  # every peak keeps its row: frequency and amplitude numbers, damping '-' where missing
    for row in rows:
        if row.split()[2] == "-":
            freq = row.split()[0]
            assert re.search(rf"{float(freq):.4g} Hz: damping missing: ", out.out), (row, out.out)
    assert (
        main(["spectrum", short_decay, "--column", "torque:part 1", "--decay", "--window", window, "--json"])
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    for p in doc["peaks"]:
        assert math.isfinite(p["frequency_hz"]) and math.isfinite(p["amplitude"])
        assert (p["damping_ratio"] is None) == bool(p["damping_missing"]), p
        assert p["damping_ratio"] is None or p["damping_ratio"] > 0


# --- orders, the time column, sample sizes -------------------------------------------------------------


@pytest.mark.parametrize("bad", ["nan", "-1", "0", "", "1,,2", "2,", "inf", "-inf", "1e308", "x", "1;2"])
def test_parse_orders_refuses_what_is_not_a_positive_finite_order(bad):
    with pytest.raises(ModelError) as info:
        parse_orders(bad, "--orders")
    assert info.value.field == "--orders" and "valid" in str(info.value)


def test_parse_orders_reads_orders():
    assert parse_orders("1, 2,6,0.5") == (1.0, 2.0, 6.0, 0.5)
    assert parse_orders(f"{MAX_ORDER:g}") == (MAX_ORDER,)
    assert check_orders(np.array([1, 2])) == (1.0, 2.0)
    for bad in ([], [True], ["1"], [0.0], [MAX_ORDER * 1.01]):
        with pytest.raises(ModelError):
            check_orders(bad)


def test_order_lines_stay_finite_at_the_ceilings():
    lines = order_lines([0.0, MAX_SIGNAL], [MAX_ORDER])
    assert np.all(np.isfinite(lines[MAX_ORDER]))
    with pytest.raises(ModelError):
        order_lines([1e308], [1.0])


def test_the_time_column_is_not_a_signal():
    for column, time in [("time", "time"), ("time [s]", "time"), ("t", "t [ms]"), (" time [s] ", "time")]:
        with pytest.raises(ModelError, match="time column"):
            check_not_time(column, time)
    assert check_not_time("torque [N·m]", "time") == "torque [N·m]"
    assert check_not_time("time2", "time") == "time2"


def test_samples_beyond_the_signal_ceiling_are_refused():
    with pytest.raises(ModelError, match="beyond") as info:
        as_signal([0.0, 1.0, 1e200], "x")
    assert "sample 2" in info.value.message
    with pytest.raises(ModelError, match="non-finite") as info:
        as_signal([0.0, np.nan], "x")
    assert "np.float64" not in str(info.value)
    # at the ceiling, a spectrum (Welch's squares included) is numbers
    t = np.arange(256)
    s = spectrum(MAX_SIGNAL * np.sin(2 * np.pi * t / 16), 1.0, segment=64)
    assert np.all(np.isfinite(s.amplitude)) and s.amplitude.max() == pytest.approx(MAX_SIGNAL, rel=1e-9)
