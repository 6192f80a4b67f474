"""The report's figures fixed figure by figure (issue 35): what a reader checks by eye, checked on the
figures' own artists - axes that carry information, colour bars with their unit, titles that fit and
name what tells two figures apart, labels that hide nothing, no length where there is none - never
on pixels. References: the documented rules (a peak counts at or above 1e-3 of the largest amplitude
above DC; an order line k·n/60 moves k·Δn/60 Hz over a record), the figures' window extents, and
the arrays the figures are drawn from.
"""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.measurement.analyse import analyse_signal
from flexshaft.measurement.peaks import find_peaks, peak_threshold
from flexshaft.measurement.spectrogram import spectrogram
from flexshaft.measurement.spectrum import spectrum
from flexshaft.views.plots import (
    SPECTRUM_DECADES,
    campbell_figure,
    reduction_figure,
    signal_figure,
    spectrogram_figure,
    spectrum_figure,
    speed_varies,
)
from tests.conftest import EXAMPLES

RATE = 1000.0


@pytest.fixture(scope="module")
def c1():
    return fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))


def _renderer(fig):
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def _inside(inner, outer, slack: float = 0.5) -> bool:
    return (
        inner.x0 >= outer.x0 - slack
        and inner.x1 <= outer.x1 + slack
        and inner.y0 >= outer.y0 - slack
        and inner.y1 <= outer.y1 + slack
    )


def _texts(ax, gid):
    return [t for t in ax.texts if t.get_gid() == gid]


def _record(seconds: float):
    t = np.arange(0.0, seconds, 1 / RATE)
    return t, 1e4 * np.exp(-0.5 * t) * np.sin(2 * np.pi * 12.7 * t) + 50 * np.sin(2 * np.pi * 88 * t)


def test_a_steady_speed_spectrogram_is_drawn_against_time_with_its_colour_bar():
    # a coast stop that holds 1000 rpm within 0.16 rpm (the x axis -0.002 ... 0.0005 + 1e3):
    # the 6th order line moves 6·0.16/60 = 0.016 Hz over the record, far under the 1 Hz bin
    t, x = _record(5.0)
    speed = 1000.0 + 0.16 * t / t[-1]
    sg = spectrogram(x, RATE, segment=1.0, window="hann", speed=speed)
    assert not speed_varies(sg, [1, 2, 6])
    fig = spectrogram_figure(sg, orders=[1, 2, 6], title="torque [N·m]", unit="N·m")
    ax, bar = fig.axes
    assert ax.get_xlabel() == "time (s)"
    assert 0.0 <= ax.get_xlim()[0] and ax.get_xlim()[1] <= t[-1] + 1.0  # seconds, not rpm
    assert bar.get_ylabel() == "amplitude (dB re 1 N·m)"
    # each order a steady line at k·n̄/60, named inside the axes
    renderer = _renderer(fig)
    labels = _texts(ax, "order-label")
    assert [lb.get_text().split("×")[0] for lb in labels] == ["1", "2", "6"]
    assert all(_inside(lb.get_window_extent(renderer), ax.get_window_extent(renderer)) for lb in labels)


def test_a_ramp_spectrogram_is_drawn_against_speed_without_an_offset():
    # 1000 -> 1020 rpm: over the 1 s segments' mean speeds (1002 ... 1018 rpm) the 6th order moves
    # 1.6 Hz, more than the 1 Hz bin - the speed axis tells something; its ticks are plain rpm (no
    # "+1e3" offset)
    t, x = _record(5.0)
    speed = 1000.0 + 20.0 * t / t[-1]
    sg = spectrogram(x, RATE, segment=1.0, window="hann", speed=speed)
    assert speed_varies(sg, [1, 2, 6]) and not speed_varies(sg, [1])  # 1st order: 0.2 Hz < 1 bin
    fig = spectrogram_figure(sg, orders=[1, 2, 6], title="torque [N·m]", unit="N·m")
    ax, bar = fig.axes
    renderer = _renderer(fig)
    assert ax.get_xlabel() == "speed (rpm)"
    assert ax.xaxis.get_offset_text().get_text() == ""
    assert "dB re 1 N·m" in bar.get_ylabel()
    for lb in _texts(ax, "order-label"):
        assert _inside(lb.get_window_extent(renderer), ax.get_window_extent(renderer)), lb.get_text()


def test_a_decay_spectrum_scales_on_the_bins_above_dc_and_its_title_fits():
    t, x = _record(5.0)
    spec = spectrum(x - x.mean(), RATE, window="rect")  # the mean removed: the 0 Hz bin is round-off
    amp = spec.amplitude
    assert amp[0] < 1e-6 * amp[1:].max()
    title = "torque:part 2: torque flange [N·m]: free decay: exponential window on the whole record " * 2
    fig = spectrum_figure(spec, title=title, unit="N·m")
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    assert hi >= amp[1:].max() and lo > amp[0]  # DC does not set the axis
    assert np.log10(hi / lo) <= SPECTRUM_DECADES + 1e-9
    renderer = _renderer(fig)
    assert _inside(ax.title.get_window_extent(renderer), fig.bbox)  # not cut at either end


def test_the_spectrum_shows_the_listed_peaks_and_the_threshold_they_passed():
    # A speed ramp's torque: its quasi-static rise (50 N·m over the record) and a resonance 0.005 N·m
    # high. The documented rule - a peak counts at or above 1e-3 of the largest amplitude above DC -
    # puts the threshold over the resonance: it is not listed, and the plot draws the threshold above
    # the resonance it shows, so the two agree.
    t = np.arange(0.0, 11.0, 1 / RATE)
    x = 50.0 * t / t[-1] + 0.005 * np.sin(2 * np.pi * 77.0 * t)
    a = analyse_signal(t, x, name="torque", unit="N·m")
    rule = 1e-3 * a.spectrum.amplitude[1:].max()
    assert peak_threshold(a.spectrum)[0] == pytest.approx(rule, rel=1e-12)
    assert rule > 0.005 and not any(abs(p["frequency_hz"] - 77.0) < 1.0 for p in a.peaks)
    assert any(abs(p.frequency_hz - 77.0) < 0.5 for p in find_peaks(a.spectrum, min_relative=1e-6))
    ax = signal_figure(a).axes[0]
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "threshold"]
    assert line.get_ydata()[0] == pytest.approx(rule)
    (marks,) = [ln for ln in ax.lines if ln.get_gid() == "peaks"]
    assert sorted(marks.get_xdata()) == pytest.approx(sorted(p["frequency_hz"] for p in a.peaks))
    # a resonance above it is listed, and marked where it is
    b = analyse_signal(t, 50.0 * t / t[-1] + 2.0 * np.sin(2 * np.pi * 77.0 * t), name="torque", unit="N·m")
    assert any(abs(p["frequency_hz"] - 77.0) < 1.0 for p in b.peaks)
    (marks,) = [ln for ln in signal_figure(b).axes[0].lines if ln.get_gid() == "peaks"]
    assert sorted(marks.get_xdata()) == pytest.approx(sorted(p["frequency_hz"] for p in b.peaks))


def test_an_frf_title_names_its_damping(c1):
    ss = fs.state_space(c1, ["motor"], ["torque:part 3"])
    resp = fs.frequency_response(ss, np.linspace(1.0, 100.0, 200))
    titles = {v: resp.plot(damping=v).axes[0].get_title() for v in ("per-part damping", "system damping")}
    assert all(v in title for v, title in titles.items()) and len(set(titles.values())) == 2


def test_campbell_order_labels_sit_inside_the_axes(c1):
    diagram = fs.campbell(c1, (0.0, 1800.0), (1, 2, 6))
    fig = campbell_figure(diagram)
    ax = fig.axes[0]
    renderer = _renderer(fig)
    labels = _texts(ax, "order-label")
    assert len(labels) == 3
    for lb in labels:
        assert _inside(lb.get_window_extent(renderer), ax.get_window_extent(renderer)), lb.get_text()


def test_twist_labels_name_every_station_and_hide_no_part_of_the_line():
    from flexshaft.analysis.convergence import mesh_for_range

    d = fs.load_model(EXAMPLES / "customer1_cad.toml")
    result = fs.twist_test(mesh_for_range(d, 400.0).drivetrain, 1000.0)
    fig = result.plot()
    ax = fig.axes[0]
    renderer = _renderer(fig)
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "twist"]
    xy = ax.transData.transform(np.column_stack(line.get_data()))
    # the line sampled every pixel or so along its length
    dense = np.vstack([np.linspace(a, b, 2 + int(np.hypot(*(b - a)))) for a, b in zip(xy[:-1], xy[1:])])
    labels = _texts(ax, "station-label")
    assert sorted(lb.get_text() for lb in labels) == sorted(name for name, _ in result.stations)
    from matplotlib.text import Text

    for lb in labels:
        bb = Text.get_window_extent(lb, renderer)  # the name's box (its leader joins it to its point)
        hidden = (dense[:, 0] > bb.x0) & (dense[:, 0] < bb.x1) & (dense[:, 1] > bb.y0) & (dense[:, 1] < bb.y1)
        assert not hidden.any() or lb.get_bbox_patch().get_alpha() == 0.0, lb.get_text()


def test_the_reduction_figure_flags_the_modes_past_the_tolerance():
    full = np.array([100.0, 300.0, 600.0, 1000.0])
    reduced = full * np.array([1.0, 1.001, 1.02, 1.5])  # errors 0, 0.1 %, 2 %, 50 %
    ax = reduction_figure("part", reduced, full, tolerance=0.01).axes[1]
    (flagged,) = [ln for ln in ax.lines if ln.get_gid() == "flagged"]
    np.testing.assert_array_equal(flagged.get_xdata(), [3, 4])


def test_no_length_scale_on_a_drawing_without_lengths(c1):
    pytest.importorskip("pyvista")
    from flexshaft.sections import table_from_segments
    from flexshaft.views.deformed import mode_surface
    from flexshaft.views.render import mode_figure

    assert not mode_surface(c1, 1).has_length  # a chain given by numbers: drawn one unit per node
    t = table_from_segments([{"length": 2.0, "od": 0.2}], name="tube")
    shaft = fs.Shaft.from_sections("tube", t, fs.STEEL, max_element_length=0.1)
    line = fs.modal_analysis(fs.Drivetrain("line", [fs.Rigid("motor", 50.0), shaft, fs.Rigid("gen", 20.0)]))
    assert mode_surface(line, 1).has_length

    def scale_bars(result):
        return [ln for ln in mode_figure(result, 1).axes[0].lines if ln.get_gid() == "length-scale"]

    assert scale_bars(c1) == [] and len(scale_bars(line)) == 1
