"""The stabilisation diagram draws the identification's poles and writes a file."""

from __future__ import annotations

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.measurement.identify import identify_modes
from flexshaft.views.stabilisation import stabilisation_figure


@pytest.fixture(scope="module")
def found():
    # two decaying modes in two channels (noise-free: exact poles, stable from order 4 on)
    t = np.arange(20_000) / 1000.0
    a = np.exp(-0.02 * 2 * np.pi * 10 * t) * np.cos(2 * np.pi * 10 * t)
    b = np.exp(-0.01 * 2 * np.pi * 23 * t) * np.sin(2 * np.pi * 23 * t)
    return identify_modes([(t, {"x": a + b, "y": a - b}, {"x": "N·m", "y": "N·m"})], max_hz=50.0, segments=1)


def _line(ax, gid):
    (line,) = [ln for ln in ax.lines if ln.get_gid() == gid]
    return line


def test_each_modes_poles_are_drawn_where_the_diagram_has_them(found):
    fig = stabilisation_figure(found)
    (ax,) = fig.axes
    d = found.diagrams[0]
    assert len(found.modes) == 2
    for m in range(2):
        x, y = _line(ax, f"mode {m}").get_data()
        np.testing.assert_array_equal(x, d.frequency_hz[d.mode == m])
        np.testing.assert_array_equal(y, d.order[d.mode == m])
    x, _ = _line(ax, "loose").get_data()
    assert x.size == np.count_nonzero(~d.stable | ~d.physical)
    assert ax.get_xlim() == (0.0, 50.0)


def test_the_figure_is_written_once_unless_overwritten(found, tmp_path):
    path = tmp_path / "stab.png"
    stabilisation_figure(found, path=path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ModelError):
        stabilisation_figure(found, path=path)
    stabilisation_figure(found, path=path, overwrite=True)
    with pytest.raises(ModelError, match="valid: .png, .svg or .pdf"):
        stabilisation_figure(found, path=tmp_path / "stab.jpg")
    with pytest.raises(ModelError, match="run = 1"):
        stabilisation_figure(found, run=1)
