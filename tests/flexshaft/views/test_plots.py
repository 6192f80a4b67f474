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
    np.testing.assert_array_equal(x, np.arange(c1.model.n_nodes))
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
