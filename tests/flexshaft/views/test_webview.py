"""The browser viewer: its data against the surface it is drawn from, offline, and alive in Chromium.

References: the surface module's arrays (themselves checked against closed forms in test_surface),
the int16 quantisation bound (1/32767 of an array's largest magnitude, half of it by rounding),
and headless Chromium with software WebGL (the canvas is drawn, the animation moves, nothing
errs, nothing is fetched).
"""

from __future__ import annotations

import base64
import json
import re

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.views.deformed import mode_surface
from flexshaft.views.webview import VIEWER_CSP, viewer_data, viewer_html, viewer_scripts
from tests.browser import NO_BROWSER, page_errors, screenshot
from tests.conftest import EXAMPLES


@pytest.fixture(scope="module")
def customer1():
    return fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))


def _array(b64: str, dtype) -> np.ndarray:
    return np.frombuffer(base64.b64decode(b64), dtype=dtype)


def _field(q: dict) -> np.ndarray:
    return _array(q["data"], "<i2") * (q["max"] / 32767)


@pytest.fixture(scope="module")
def tube_line():
    # A steel tube from sections between two discs: stress and energy colours are not zero (a shaft
    # given by numbers has no radius, so no stress, and would check nothing).
    from flexshaft.sections import table_from_segments

    t = table_from_segments([{"length": 2.0, "od": 0.2, "id": 0.1}], name="tube")
    shaft = fs.Shaft.from_sections("tube", t, fs.STEEL, max_element_length=0.1)
    return fs.modal_analysis(
        fs.Drivetrain("line", [fs.Rigid("motor", 50.0), shaft, fs.Rigid("generator", 20.0)])
    )


def test_the_data_is_the_surface_it_draws(tube_line, customer1):
    data = viewer_data(tube_line, [1, 2])
    s = mode_surface(tube_line, 2, colour="stress")
    assert np.max(np.abs(s.scalars)) > 0
    g = data["points"]
    lo, hi = np.array(g["lo"]), np.array(g["hi"])
    P = lo + (_array(g["data"], "<i2").reshape(-1, 3).astype(float) + 32767) / 65534 * (hi - lo)
    assert P.shape == s.points.shape == (data["n_points"], 3)
    # int16 steps of the bounding box: within half a step, (hi - lo)/65534/2 per axis
    assert np.all(np.abs(P - s.points) <= (hi - lo) / 65534 / 2 * (1 + 1e-9))
    m = data["modes"][1]
    assert m["index"] == 2 and m["frequency_hz"] == tube_line.frequencies_hz[2]
    # int16 fractions of the largest magnitude: within half a step (0.5/32767 of it) after rounding
    for got, want in ((_field(m["phi"]), s.phi / s.scale), (_field(m["stress"]), s.scalars)):
        assert np.max(np.abs(got - want)) <= 0.5 / 32767 * np.max(np.abs(want)) * (1 + 1e-9)
    # every triangle index names a point; the quads are split into two triangles each
    tri = _array(data["triangles"], "<u2" if data["index_type"] == "u16" else "<u4").reshape(-1, 3)
    assert tri.max() < data["n_points"]
    assert tri.shape[0] == s.triangles.shape[0] + 2 * s.faces.shape[0]
    assert [d["name"] for d in data["discs"]] == ["motor", "generator"]
    # each disc turns with its node: the mode normalised by its largest station rotation (the first and
    # last stations here), the same arithmetic, so to round-off
    st = tube_line.station_shapes()[:, 2]
    assert [d["phi"][1] for d in data["discs"]] == pytest.approx([st[0], st[-1]], abs=1e-12)
    # the energy colour is the stress colour's τ²/(2G) (one steel): the same field, squared
    g = fs.STEEL.G
    energy = (1e6 * s.scalars) ** 2 / (2 * g)
    assert np.max(np.abs(_field(m["energy"]) - energy)) <= 0.5 / 32767 * np.max(energy) * (1 + 1e-9)
    assert {lab["text"] for lab in data["labels"]} >= {"tube", "motor", "generator"}
    # a numbers-only chain has every part labelled too
    labels = {lab["text"] for lab in viewer_data(customer1, [1])["labels"]}
    assert labels >= {"part 1", "part 2", "part 3", "part 4", "motor"}


def test_default_modes_are_the_elastic_ones_up_to_max_hz(customer1):
    from flexshaft.analysis.modal import DEFAULT_LISTED
    from flexshaft.views import webview

    assert webview._LISTED == DEFAULT_LISTED  # the viewer lists what `flexshaft modes` lists
    data = viewer_data(customer1)
    shown = [m["index"] for m in data["modes"]]
    assert shown == [k for k in range(customer1.count) if not customer1.rigid[k]][:20]
    with pytest.raises(fs.ModelError, match="mode"):
        viewer_data(customer1, [99])
    with pytest.raises(fs.ModelError, match="rigid-body"):
        viewer_data(customer1, [0])


def test_the_page_needs_nothing_from_the_network(customer1):
    page = viewer_html(customer1, [1])
    assert f'content="{VIEWER_CSP}"' in page and "default-src 'none'" in VIEWER_CSP
    # No URL but XML namespace names (three.js and the viewer create SVG/XHTML elements by them).
    urls = set(re.findall(r"https?://[^\s\"'<>)]+", page))
    assert urls <= {"http://www.w3.org/2000/svg", "http://www.w3.org/1999/xhtml"}, urls
    assert not re.search(r"<(link|iframe|img)\b", page)
    # an inline script ends at the first "</script": the vendored code must not hold one
    scripts = viewer_scripts()
    assert scripts.count("</script>") == scripts.count("<script>") == 2
    blob = re.search(r'<script type="application/json" id="fs-view-1-data">(.*?)</script>', page, re.S)
    assert json.loads(blob.group(1))["modes"][0]["index"] == 1
    # three.js's licence travels with it, and the page names it
    from flexshaft.views import webview

    assert "MIT License" in (webview._VENDOR / "THREE-LICENSE").read_text()
    assert "three.js r187, MIT licence" in page


@pytest.fixture(scope="module")
def cad_page(tmp_path_factory):
    from flexshaft.analysis.convergence import mesh_for_range

    d = fs.load_model(EXAMPLES / "customer1_cad.toml")
    r = fs.modal_analysis(mesh_for_range(d, d.max_hz).drivetrain)
    page = tmp_path_factory.mktemp("view") / "m2.html"
    page.write_text(viewer_html(r, [2]))
    return page


@pytest.mark.slow
def test_a_cad_page_stays_small(cad_page):
    # the CAD surface (23k points, 28k triangles) and one mode: a couple of MB, three.js included
    assert cad_page.stat().st_size < 4e6


def _draws_and_moves(page):
    # 0.4 s and 1.5 s into the animation (the page's clock starts there: a loaded machine's slower
    # page load does not shift the moments), 100 ms of virtual time to draw
    a, b = screenshot(page, 100, fragment="#t=0.4"), screenshot(page, 100, fragment="#t=1.5")
    if a is None:
        pytest.skip(NO_BROWSER)
    # not blank: the drivetrain covers a good part of the drawing area (white elsewhere)
    drawn = np.any(a < 0.9, axis=2)
    assert drawn.mean() > 0.03
    # 0.4 s and 1.5 s into a 2 s period: sin = 0.95 and -1, the twist and its colours reversed
    changed = np.any(np.abs(a - b) > 2 / 255, axis=2)
    assert changed.mean() >= 0.005
    told = page_errors(page, 1500)
    assert told.startswith("errors:0 "), told
    frames = int(re.search(r"frames:(-?\d+)", told).group(1))
    assert frames > 0  # the animation clock ran
    assert " overlaps:0 " in told  # the part and station labels, placed apart on screen


@pytest.mark.slow
def test_a_cad_models_report_carries_the_viewer_and_stays_small(tmp_path):
    from flexshaft.cli import main

    out = tmp_path / "rep"
    assert main(["report", str(EXAMPLES / "customer1_cad.toml"), "-o", str(out)]) == 0
    page = (out / "index.html").read_text()
    assert len(page.encode()) < 10e6  # issue 22: a CAD model's report under ~10 MB (3.7 MB today)
    blob = re.search(r'<script type="application/json" id="fs-viewer-\d+-data">(.*?)</script>', page, re.S)
    modes = [m["index"] for m in json.loads(blob.group(1))["modes"]]
    assert modes and 0 not in modes  # the elastic modes the tables show
    told = page_errors(out / "index.html", 1500)
    if told is not None:
        assert told.startswith("errors:0 "), told


@pytest.mark.slow  # Chromium drawing and turning the viewer: 6-7 s
def test_the_viewer_draws_and_moves_in_a_browser(customer1, tmp_path):
    page = tmp_path / "c1.html"
    page.write_text(viewer_html(customer1, first=2))
    _draws_and_moves(page)


@pytest.mark.slow
def test_the_cad_benchs_viewer_draws_and_moves_in_a_browser(cad_page):
    # the demonstration: flexshaft view examples/customer1_cad.toml --mode 2 -o m2.html
    _draws_and_moves(cad_page)


def _drawing_length(data) -> float:
    lo, hi = np.array(data["bounds"][0]), np.array(data["bounds"][1])
    return float(hi[0] - lo[0])


@pytest.mark.parametrize("which", ["customer1", "tube_line"])
def test_every_mode_moves_a_hand_far_enough_to_see(which, request):
    # A slender shaft turned by the drawn twist moves its surface by a few pixels (r/L ~ 1/50): each
    # mode's motion must show elsewhere - a hand or a disc's radius mark whose tip travels at least
    # 2 % of the drawing's length between rest and the largest deflection (20 pixels across a
    # 1000-pixel drawing). The tip of a mark of length R turned by a travels 2·R·sin(a/2).
    result = request.getfixturevalue(which)
    data = viewer_data(result)
    length = _drawing_length(data)
    for k, mode in enumerate(data["modes"]):
        marks = [(h["length"], h["phi"][k]) for h in data["hands"]]
        marks += [(d["radius"], d["phi"][k]) for d in data["discs"]]
        travel = max(2 * r * np.sin(abs(data["scale"] * phi) / 2) for r, phi in marks)
        assert travel >= 0.02 * length, (mode["index"], travel / length)
    # a hand turns with its station: the mode normalised by its largest station rotation
    st = result.station_shapes()
    peak = np.max(np.abs(st[:, data["modes"][0]["index"]]))
    names = [s.name for s in result.model.stations]
    for h in data["hands"]:
        want = st[names.index(h["name"]), data["modes"][0]["index"]] / peak
        assert h["phi"][0] == pytest.approx(want, abs=1e-12)


def test_a_chain_given_by_numbers_has_no_length_to_show(customer1, tube_line):
    assert viewer_data(customer1)["lengths"] is False  # drawn one unit per node: no length scale
    assert viewer_data(tube_line)["lengths"] is True
