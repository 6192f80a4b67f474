"""One sign convention for mode shapes: the largest station value of every mode is positive.

An eigensolver returns each mode with an arbitrary sign (LAPACK's and ARPACK's differ, and so do
CPUs' round-off); flexshaft fixes it once, in the modal result, so tables, JSON, plots, 3D views
and exports agree. References: the convention itself (checked on the raw shapes) and two
eigensolver paths, which must then give the same shapes.
"""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import mode_signs
from flexshaft.sections import table_from_segments
from tests.conftest import EXAMPLES


@pytest.mark.parametrize("name", ["customer1", "without_dut", "customer2", "customer1_flex"])
def test_the_largest_station_rotation_is_positive(name):
    r = fs.modal_analysis(fs.load_model(EXAMPLES / f"{name}.toml"))
    rows = r.model.node_dof(r.model.station_nodes, "θx")
    v = r.node_shapes[rows]
    top = np.max(np.abs(v), axis=0)
    for k in range(r.count):
        first = np.flatnonzero(np.abs(v[:, k]) >= (1 - 1e-6) * top[k])[0]
        assert v[first, k] > 0, (name, k)
    assert np.all(mode_signs(r) == 1.0)  # already in the convention: nothing left to flip


def test_two_eigensolvers_give_the_same_shapes():
    # The dense (LAPACK) and Lanczos (ARPACK) paths return their own signs; after the convention the
    # shapes agree to the solvers' accuracy. Customer 1's modes are distinct (no degenerate pair whose
    # basis could rotate), so each mode is unique up to its sign: 1e-8 of the largest entry is far
    # outside round-off (~1e-12) and far inside a flipped sign (2).
    d = fs.load_model(EXAMPLES / "customer1.toml")
    big = fs.Drivetrain(d.name, [c for c in d.components], inertia_model=d.inertia_model)
    from flexshaft.analysis.convergence import mesh_for_range

    model = mesh_for_range(big, 2000.0).drivetrain
    a = fs.modal_analysis(model, 8, method="dense")
    b = fs.modal_analysis(model, 8, method="lanczos")
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-9, atol=1e-9)
    e = ~a.rigid
    scale = np.max(np.abs(a.shapes[:, e]))
    np.testing.assert_allclose(a.shapes[:, e], b.shapes[:, e], atol=1e-8 * scale)


def test_a_six_dof_models_modes_follow_their_family():
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "ptss_full.toml"))
    m = r.model
    for k, kind in enumerate(r.kinds):
        names = {"torsion": ("θx",), "axial": ("ux",), "lateral": ("uy", "uz")}[kind]
        rows = np.sort(np.concatenate([m.node_dof(m.station_nodes, n) for n in names]))
        v = r.node_shapes[rows, k]
        top = np.max(np.abs(v))
        if top > 0:
            assert v[np.flatnonzero(np.abs(v) >= (1 - 1e-6) * top)[0]] > 0, (k, kind)


def test_the_views_draw_the_convention():
    from flexshaft.views.deformed import mode_surface

    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    for k in range(1, r.count):
        s = mode_surface(r, k)
        # the surface's twist is the mode normalised by its largest station rotation: +1 at that station
        assert np.max(s.phi) == pytest.approx(s.scale, rel=1e-12)


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_an_exported_bodys_fixed_interface_modes_follow_the_convention(dofs):
    from flexshaft.parts.model import DOF_NAMES
    from flexshaft.reduction.craig_bampton import craig_bampton

    t = table_from_segments([{"length": 1.2, "od": 0.1}, {"length": 0.4, "od": 0.07}], name="s")
    part = fs.part_model(t, fs.STEEL, dofs=dofs, max_element_length=0.05)
    body = craig_bampton(part, modes=6, residual=False)
    nb = body.K.shape[0] - 6
    names = np.asarray(DOF_NAMES[dofs])[np.arange(body.T.shape[0]) % len(DOF_NAMES[dofs])]
    for k in range(6):
        col = body.T[:, nb + k]
        v = col[names == "θx"]
        if np.max(np.abs(v)) <= 1e-9 * np.max(np.abs(col)):
            v = col[np.isin(names, ("ux", "uy", "uz"))]
        top = np.max(np.abs(v))
        assert v[np.flatnonzero(np.abs(v) >= (1 - 1e-6) * top)[0]] > 0, (dofs, k)
