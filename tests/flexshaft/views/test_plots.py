"""Engineering plots: what they draw is the result's data, and they never open a window."""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.sections import table_from_segments
from flexshaft.views.plots import png
from tests.conftest import EXAMPLES


def _line(ax, gid):
    (line,) = [ln for ln in ax.lines if ln.get_gid() == gid]
    return line


@pytest.fixture(scope="module")
def c1():
    return fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))


@pytest.fixture(scope="module")
def rod():
    # A uniform free shaft from sections, 40 elements: its first torsion mode is cos(πx/L).
    t = table_from_segments([{"length": 2.0, "od": 0.1}], name="rod")
    s = fs.Shaft.from_sections("rod", t, fs.STEEL, max_element_length=0.05)
    return fs.modal_analysis(fs.Drivetrain("rod", [s]), 4)


def test_mode_shape_panels_draw_the_modes_on_the_axial_positions(rod):
    fig = rod.plot("shapes", modes=[1, 2])
    assert len(fig.axes) == 2
    x, y = _line(fig.axes[0], "shape").get_data()
    np.testing.assert_array_equal(x, rod.model.x)
    # Max-normalised first mode of a free uniform rod: ±cos(πx/L), to the mesh's discretisation
    # (40 linear elements: 1e-3 on the shape).
    expected = np.cos(np.pi * rod.model.x / 2.0)
    assert np.max(np.abs(np.abs(y) - np.abs(expected))) < 1e-3
    assert "mode 1:" in fig.axes[0].get_title() and "Hz" in fig.axes[0].get_title()
    assert png(fig)[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_chain_given_by_numbers_is_drawn_against_its_nodes(c1):
    fig = c1.plot()  # the elastic modes among the first six
    assert len(fig.axes) == c1.count - 1
    x, _ = _line(fig.axes[0], "shape").get_data()
    np.testing.assert_array_equal(x, np.arange(c1.model.n_nodes))  # schematic: the chain's order
    with pytest.raises(fs.ModelError, match="mode = 9: no such mode"):
        c1.plot(modes=[9])


@pytest.mark.parametrize("kind", ["strain", "kinetic"])
def test_energy_bars_stack_to_the_shares(c1, kind):
    fig = c1.plot(kind)
    ax = fig.axes[0]
    heights = {}
    for bar in ax.patches:
        heights.setdefault(round(bar.get_x() + bar.get_width() / 2), 0.0)
        heights[round(bar.get_x() + bar.get_width() / 2)] += bar.get_height()
    # Every mode's bar adds up to 1 (the shares of all components): shares of one total, summed back,
    # ~n·eps.
    np.testing.assert_allclose(list(heights.values()), 1.0, rtol=1e-12)


def test_torque_bars_are_the_component_torques(c1):
    fig = c1.plot("torque")
    torques = c1.component_torques()
    elastic = np.flatnonzero(~c1.rigid)
    drawn = sorted(round(b.get_height(), 6) for b in fig.axes[0].patches)
    flexible = [ci for ci, c in enumerate(c1.model.drivetrain.components) if c.type != "rigid"]
    assert drawn == sorted(round(torques[i, ci], 6) for i in elastic for ci in flexible)


def test_twist_result_plots_itself():
    r = fs.twist_test(fs.load_model(EXAMPLES / "customer1.toml"), 1000.0)
    fig = r.plot()
    x, y = _line(fig.axes[0], "twist").get_data()
    np.testing.assert_allclose(y, 1e3 * r.theta, rtol=1e-15)  # mrad: the same product


def test_plotting_changes_no_global_state(c1):
    import matplotlib

    backend, params = matplotlib.get_backend(), dict(matplotlib.rcParams)
    c1.plot()
    assert matplotlib.get_backend() == backend and dict(matplotlib.rcParams) == params


def test_a_picture_is_the_type_its_suffix_names(c1):
    import matplotlib

    from flexshaft.views.plots import picture

    fig = c1.plot()
    params = dict(matplotlib.rcParams)
    magic = {".png": b"\x89PNG\r\n\x1a\n", ".PNG": b"\x89PNG\r\n\x1a\n", ".svg": b"<?xml", ".Pdf": b"%PDF"}
    for suffix, start in magic.items():
        data = picture(fig, suffix)
        assert data.startswith(start)
        assert picture(fig, suffix) == data  # no date, no random ids: the same figure, the same bytes
    assert dict(matplotlib.rcParams) == params  # SVG's fixed id salt was for that one save only
    for bad in (".txt", ".jpg", ""):
        with pytest.raises(fs.ModelError, match="unknown picture type"):
            picture(fig, bad)


# --- readable pictures (issue 22): units, unwrapped phase, labels clear of curves and of each other ---


def _overlaps(texts, fig):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(r) for t in texts if t.get_visible() and t.get_text()]
    return [(a, b) for i, a in enumerate(boxes) for b in boxes[:i] if a.overlaps(b)]


def test_a_numbers_only_chain_is_labelled_by_its_stations(c1):
    fig = c1.plot()
    bottom = fig.axes[-1]
    names = [t.get_text() for t in bottom.get_xticklabels()]
    assert names == [st.name for st in c1.model.stations]
    assert "schematic" in bottom.get_xlabel()
    assert not _overlaps(bottom.get_xticklabels(), fig)


def test_component_names_sit_above_the_curves(c1):
    fig = c1.plot()
    top = fig.axes[0]
    names = [t for t in top.texts if t.get_text() in c1.model.component_names]
    assert {t.get_text() for t in names} == set(c1.model.component_names)
    # placed in axes fraction above the panel (y > 1): no curve is drawn there
    assert all(t.xy[1] > 1.0 for t in names)
    assert all(not [t for t in ax.texts if t.get_text() in c1.model.component_names] for ax in fig.axes[1:])


def test_frf_phase_is_unwrapped(c1):
    from flexshaft.analysis.statespace import frequency_response, state_space
    from flexshaft.views.plots import bode_figure

    resp = frequency_response(state_space(c1, ["motor"], ["speed:generator"]), np.linspace(1, 700, 3000))
    fig = bode_figure(resp)
    _, phase = fig.axes[1].lines[0].get_data()
    # every step between neighbouring frequencies is less than half a turn: no ±360° jumps
    assert np.max(np.abs(np.diff(phase))) < 180
    # and it is the response's own phase, modulo whole turns
    wrapped = np.degrees(np.angle(resp.H[:, 0, 0]))
    np.testing.assert_allclose(np.mod(phase - wrapped + 180, 360) - 180, 0.0, atol=1e-9)


def test_speeds_are_drawn_in_rpm():
    from flexshaft.analysis.simulate import Scenario, simulate
    from flexshaft.views.plots import simulation_figure

    d = fs.load_model(EXAMPLES / "customer1.toml")
    run = simulate(fs.modal_analysis(d), Scenario("step", torque=1000.0), ["speed:motor"], duration=1.0)
    fig = simulation_figure(run)
    assert fig.axes[0].get_ylabel() == "rpm"
    _, y = fig.axes[0].lines[0].get_data()
    # the same samples, rad/s times 60/2π
    np.testing.assert_allclose(y, np.asarray(run.outputs["speed:motor"]) * 60 / (2 * np.pi), rtol=1e-15)
    assert simulation_figure(run, speed_unit="rad/s").axes[0].get_ylabel() == "rad/s"


def test_energy_labels_stay_apart_at_any_count(rod):
    many = fs.modal_analysis(rod.model, 30)
    fig = many.plot("strain")
    ticks = fig.axes[0].get_xticklabels()
    assert len(ticks) == 29
    assert not _overlaps(ticks, fig)
    assert all("e+" not in t.get_text() for t in ticks)  # plain digits (was "1.84e+03 Hz")


def test_the_twist_plot_shows_every_part():
    r = fs.twist_test(fs.load_model(EXAMPLES / "customer1.toml"), 1000.0)
    fig = r.plot()
    bars = fig.axes[1]
    assert [t.get_text() for t in bars.get_xticklabels()] == [p.name for p in r.parts]
    heights = sorted(b.get_height() for b in bars.patches)
    np.testing.assert_allclose(heights, sorted(1e3 * abs(p.twist) for p in r.parts), rtol=1e-15)
    assert bars.get_yscale() == "log"  # a soft coupling's twist does not flatten the shafts'
    stations = [t for t in fig.axes[0].texts if t.get_text() in {name for name, _ in r.stations}]
    assert len(stations) == len(r.stations) and not _overlaps(stations, fig)
