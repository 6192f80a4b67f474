"""The drivetrain with six DOFs per node: Timoshenko shafts, couplings as links, bearings.

Flexible bodies (shafts with ``reduce``) are checked against the same chain
unreduced (same mesh, same elements) and against the pinned-pinned Timoshenko
closed form.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import part_modes
from flexshaft.cli import main
from flexshaft.model.components import Reduce
from flexshaft.parts.model import part_model
from flexshaft.sections import cowper_shear_factor, table_from_segments
from tests.conftest import full_shaft_model

E, G, RHO, NU = fs.STEEL.E, fs.STEEL.G, fs.STEEL.rho, fs.STEEL.nu


def shaft(name, segs, n=40, **kw):
    t = table_from_segments(segs, name=name)
    return fs.Shaft.from_sections(name, t, fs.STEEL, max_element_length=t.length / n, **kw)


def bench_chain(**kw):
    return fs.Drivetrain(
        "c",
        [
            fs.Rigid("motor", 5.0),
            shaft("a", [{"length": 1.0, "od": 0.1}, {"length": 0.5, "od": 0.08, "id": 0.03}]),
            fs.Coupling("c", stiffness=2e4, inertia=0.02),
            shaft("b", [{"length": 0.8, "od": 0.09}]),
            fs.Rigid("gen", 2.0),
        ],
        **kw,
    )


def test_torsion_modes_equal_the_torsion_chain():
    # Torsion of a straight axisymmetric shaft does not couple to bending or axial motion, so the
    # full model's torsion modes are the torsion chain's (same mesh, same elements).
    d = bench_chain(dofs="full")
    m = fs.modal_analysis(fs.assemble(d), 30)
    torsion = m.frequencies_hz[np.array(m.kinds) == "torsion"]
    chain = fs.modal_analysis(fs.assemble(d, dofs="torsion"), count=5, damped=False).frequencies_hz
    # Equal in exact arithmetic; each dense solve errs by up to eps·λ_max/λ/2 on the 18 Hz mode: 7e-9 in
    # the 6-DOF model (f_max = 1.4e5 Hz: the 2 cm elements' axial modes), 3e-9 in the chain (2.8e-9
    # seen): 3e-8 leaves 3x on their sum. atol for the rigid mode's 0.
    np.testing.assert_allclose(torsion[:5], chain, rtol=3e-8, atol=1e-9)
    assert m.rigid.sum() == 6  # free chain: three translations, spin, two tilts


def test_a_rigid_coupling_joins_two_shafts_into_one():
    # A coupling links all but θx rigidly; with a huge torsional stiffness too, two 1 m shafts behave as
    # one 2 m shaft: the same frequencies as that shaft's own part model.
    d = fs.Drivetrain(
        "c2",
        [
            shaft("a", [{"length": 1.0, "od": 0.1}], 50),
            fs.Coupling("c", stiffness=1e15),
            shaft("b", [{"length": 1.0, "od": 0.1}], 50),
        ],
        dofs="full",
    )
    m = fs.modal_analysis(fs.assemble(d), 16)
    one = part_modes(
        part_model(
            table_from_segments([{"length": 2.0, "od": 0.1}]), fs.STEEL, dofs="full", max_element_length=0.02
        ),
        16,
    )
    # Not round-off (~1e-12 here) but the coupling's compliance: the 1e15 N·m/rad spring lowers the
    # torsion mode by (G·Ip/L)/1e15 = 4e-10 (scaling as 1/k); every other DOF is linked rigidly.
    np.testing.assert_allclose(m.frequencies_hz[6:], one.frequencies_hz[6:], rtol=1e-9)


def _pinned_pinned_timoshenko_hz(L: float, D: float) -> float:
    """First bending frequency of a pinned-pinned solid round Timoshenko shaft of steel, Hz.

    Han, Benaroya & Wei, J. Sound Vib. 225 (1999): k = π/L, lower root of
    EI k⁴ − ρA ω² − ρI ω² k² (1 + E/(κG)) + ρ² I ω⁴/(κG) = 0.
    """
    I, A = math.pi * D**4 / 64, math.pi * D**2 / 4
    kap = cowper_shear_factor(0.0, NU)
    k = math.pi / L
    a, b, c = RHO**2 * I / (kap * G), -(RHO * A + RHO * I * k**2 * (1 + E / (kap * G))), E * I * k**4
    return math.sqrt((-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)) / (2 * math.pi)


@pytest.mark.parametrize("reduce", ["", "reduce = {modes = 4}\n"])
def test_bearings_from_the_model_file_give_pinned_pinned_timoshenko(tmp_path, reduce):
    # Also as a flexible body: its boundary is the two end nodes, where the bearings sit, and four
    # fixed-interface modes (with the residual vectors) are plenty for the first bending pair.
    model = tmp_path / "m.toml"
    model.write_text(
        '[model]\ndofs = "full"\n\n[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\n'
        f"segments = [{{length = 1.0, od = 0.1}}]\nmax_element_length = 0.02\n{reduce}\n"
        '[[bearings]]\nstation = "s start"\nstiffness = 1e14\n\n'
        '[[bearings]]\nstation = "s end"\nstiffness = 1e14\n'
    )
    d = fs.load_model(model)
    fm = fs.assemble(d)
    assert len(fm.bodies) == (1 if reduce else 0)
    m = fs.modal_analysis(fm, 6)
    f = _pinned_pinned_timoshenko_hz(1.0, 0.1)
    lateral = m.frequencies_hz[~m.rigid][:2]
    # 2e-4: the 2 cm mesh (measured 2.7e-6; the reduction moves it by ~1e-8, round-off of 1e14 N/m).
    np.testing.assert_allclose(lateral, [f, f], rtol=2e-4)
    assert m.kinds[2] == "lateral"


def test_full_model_errors():
    d = fs.Drivetrain("x", [fs.Rigid("m", 1.0), fs.Shaft("p", stiffness=1e5, inertia=1.0)], dofs="full")
    with pytest.raises(fs.ModelError, match="has no cross-sections, so no bending stiffness or mass"):
        fs.assemble(d)
    with pytest.raises(fs.ModelError, match="bearings.station = 'nowhere': no such station"):
        fs.assemble(bench_chain(dofs="full", bearings=(("nowhere", 1e9),)))
    with pytest.raises(fs.ModelError, match="bearings act on lateral DOFs"):
        bench_chain(bearings=(("motor", 1e9),))
    # One check of a bearing's stiffness, wherever the drivetrain comes from.
    for bad in (float("nan"), -1e9, 0.0):
        with pytest.raises(fs.ModelError, match=r"bearings\['motor'\] = .* N/m"):
            bench_chain(dofs="full", bearings=(("motor", bad),))


def test_cli_modes_of_a_full_model(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(full_shaft_model())
    assert main(["modes", str(model), "--json", "--modes", "8"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["dofs"] == "full" and len(doc["modes"]) == 8
    assert [m["rigid"] for m in doc["modes"]][:2] == [True, True]
    # Two bearings hold the lateral motion: axial and spin stay rigid, the first elastic modes bend.
    assert [m["kind"] for m in doc["modes"]][:4] == ["axial", "torsion", "lateral", "lateral"]
    assert main(["modes", str(model)]) == 0
    assert "full: Timoshenko shafts" in capsys.readouterr().out


def test_example_full_model_torsion_matches_its_torsion_chain(capsys):
    pytest.importorskip("build123d")
    from tests.conftest import EXAMPLES

    assert main(["modes", str(EXAMPLES / "ptss_full.toml"), "--json", "--modes", "6"]) == 0
    doc = json.loads(capsys.readouterr().out)
    torsion = [m["frequency_hz"] for m in doc["modes"] if m["kind"] == "torsion" and not m["rigid"]]
    torsion_chain = fs.assemble(fs.load_model(EXAMPLES / "ptss_full.toml"), dofs="torsion")
    chain = fs.modal_analysis(torsion_chain, count=3, damped=False)
    # 1e-6, not round-off: the fillets are cut into 1.7 mm elements whose axial stiffness EA/L reaches
    # 1e13 N/m, so the 6-DOF problem's condition number (~1e10) leaves ~3e-7 of round-off on its lowest
    # eigenvalues (a dense solve of the same matrices differs by as much).
    assert torsion[0] == pytest.approx(chain.frequencies_hz[1], rel=1e-6)


def test_bearings_at_named_nodes_inside_a_part():
    # The same part, on the same mesh, through two code paths: the chain with bearings at named
    # stations and the part model with springs on those nodes.
    t = table_from_segments([{"length": 2.0, "od": 0.1}], name="s")
    s = fs.Shaft.from_sections(
        "s", t, fs.STEEL, max_element_length=0.05, named_nodes=(("b1", 0.5), ("b2", 1.5))
    )
    d = fs.Drivetrain("n", [s], dofs="full", bearings=(("s: b1", 1e9), ("s: b2", 1e9)))
    m = fs.modal_analysis(fs.assemble(d), 10)
    pm = part_model(t, fs.STEEL, dofs="full", max_element_length=0.05, nodes_at=(0.5, 1.5))
    nodes = [int(np.argmin(np.abs(pm.x - p))) for p in (0.5, 1.5)]
    ref = part_modes(pm, 10, bearings={nodes[0]: 1e9, nodes[1]: 1e9})
    # The same matrices (equal to the bit here) and dense solve; were they summed in another order, the
    # solves' round-off eps·λ_max/λ/2 <= 3e-11 (f_max = 5.7e4 Hz against 112 Hz) stays inside 1e-9.
    np.testing.assert_allclose(m.frequencies_hz[2:], ref.frequencies_hz[2:], rtol=1e-9)
    assert m.kinds[2] == "lateral"


def test_a_named_node_off_the_element_grid_keeps_the_meshes_aligned():
    # The named node at 0.33 m adds a node to the torsion mesh; the 6-DOF part model must have it too,
    # or every later node is shifted (shaft b would hang off the wrong nodes). Reference: torsion
    # does not couple to bending, so the torsion modes are the torsion chain's.
    d = fs.Drivetrain(
        "off grid",
        [
            shaft("a", [{"length": 1.0, "od": 0.1}], 10, named_nodes=(("j", 0.33),)),
            fs.Coupling("c", stiffness=1e4, inertia=0.01),
            shaft("b", [{"length": 1.0, "od": 0.1}], 10),
        ],
        dofs="full",
    )
    m = fs.modal_analysis(fs.assemble(d), 24)
    assert m.rigid.sum() == 6 and m.frequencies_hz[6] > 1.0
    torsion = m.frequencies_hz[np.array(m.kinds) == "torsion"]
    chain = fs.modal_analysis(fs.assemble(d, dofs="torsion"), count=3, damped=False).frequencies_hz
    # Round-off of the two dense solves, eps·λ_max/λ/2: 2e-11 + 8e-12 on the 80 Hz mode; 1e-8 is loose.
    np.testing.assert_allclose(torsion[:3], chain, rtol=1e-8, atol=1e-9)


# --- flexible bodies (shafts with reduce) -------------------------------------------------------


def flex_chain(reduce=None, bearings=(("motor", 2e8), ("a: journal", 2e8), ("gen", 2e8))):
    """The bench chain with a journal bearing at a named node inside shaft a; ``reduce`` on both shafts."""
    return fs.Drivetrain(
        "flex",
        [
            fs.Rigid("motor", 5.0),
            shaft(
                "a",
                [{"length": 1.0, "od": 0.1}, {"length": 0.5, "od": 0.08, "id": 0.03}],
                named_nodes=(("journal", 0.7),),
                reduce=reduce,
            ),
            fs.Coupling("c", stiffness=2e4, inertia=0.02),
            shaft("b", [{"length": 0.8, "od": 0.09}], reduce=reduce),
            fs.Rigid("gen", 2.0),
        ],
        dofs="full",
        bearings=bearings,
    )


def _full(d):
    return fs.assemble(d)


def _kept_cutoff(fm) -> float:
    """The lowest, over the bodies, of the highest kept fixed-interface frequency (residuals aside), Hz."""
    return min(
        float(b.body.fixed_interface_hz[: b.body.n_modes - b.body.n_residual].max()) for b in fm.bodies
    )


def _cluster_mac(a, b, M, f, rel=1e-6):
    """For each shape of ``a``, the share of its M-norm² in the span of ``b``'s shapes at its frequency.

    Isotropic shafts have degenerate bending pairs (any rotation of a pair is a mode), so a shape is
    compared with its cluster of equal frequencies (within ``rel``) rather than one vector. ``b`` is
    M-orthonormal (as eigenvectors are).
    """
    out = np.empty(a.shape[1])
    for i in range(a.shape[1]):
        same = np.abs(f - f[i]) <= rel * max(f[i], 1.0)
        c = b[:, same].T @ (M @ a[:, i])
        out[i] = (c @ c) / (a[:, i] @ (M @ a[:, i]))
    return out


def test_flexible_bodies_match_the_unreduced_full_model():
    # Reference: the same chain with every shaft on its full mesh. Both shafts reduced with every
    # fixed-interface mode below 3 kHz; compared: the 14 lowest modes (2 rigid, 12 elastic, up to
    # 750 Hz), all below half the lowest part cut-off (2.8 kHz kept). Measured: 2.5e-8 at most.
    ref = _full(flex_chain())
    red = _full(flex_chain(Reduce(cutoff_hz=3000.0)))
    assert len(red.bodies) == 2 and red.K.shape[0] < ref.K.shape[0] / 5
    a, b = fs.modal_analysis(red, 14), fs.modal_analysis(ref, 14)
    assert b.rigid.sum() == 2  # three bearings hold the lateral motion: axial and spin remain
    assert b.frequencies_hz[-1] < _kept_cutoff(red) / 2
    el = ~b.rigid
    np.testing.assert_allclose(a.frequencies_hz[el], b.frequencies_hz[el], rtol=1e-4)
    # A Ritz approximation of the unreduced model: never below it, beyond the unreduced dense solve's
    # round-off, eps·λ_max/λ/2 <= 7e-9 (its 18 Hz mode against f_max = 1.4e5 Hz; 1.1e-10 seen): 3e-8.
    assert np.all(a.frequencies_hz[el] >= b.frequencies_hz[el] * (1 - 3e-8))
    assert a.kinds == b.kinds
    assert set(a.kinds) == {"axial", "lateral", "torsion"}
    ea, eb = a.family_energy(), b.family_energy()
    for fam in ea:
        np.testing.assert_allclose(ea[fam], eb[fam], atol=1e-6)


def test_flexible_body_shapes_are_recovered_on_every_node():
    ref = _full(flex_chain())
    red = _full(flex_chain(Reduce(cutoff_hz=3000.0)))
    a, b = fs.modal_analysis(red, 14), fs.modal_analysis(ref, 14)
    assert a.node_shapes.shape == b.node_shapes.shape == (6 * ref.n_nodes, 14)
    # The same unreduced chain's mass on node DOFs in both, and M = Tᵀ M_nodes T (CB projects its
    # part's mass exactly), so recovered shapes are mass-normalised on the full mesh.
    assert abs(red.M_nodes - ref.M_nodes).max() == 0.0  # the same assembly of the same elements
    # TᵀMT against the bodies' own projections, summed in another order: ~n·eps (6e-16 seen)
    assert abs(red.T.T @ red.M_nodes @ red.T - red.M).max() < 1e-12 * abs(red.M).max()
    mac = _cluster_mac(a.node_shapes, b.node_shapes, ref.M_nodes, b.frequencies_hz)
    assert np.all(mac > 0.999), mac  # measured 1 − 4e-10
    # The interior nodes move too (not only the boundary nodes the bodies keep).
    body = red.bodies[0]
    inner = np.setdiff1d(np.arange(body.body.T.shape[0] // 6), body.body.boundary_nodes)
    rows = (6 * (body.first_node + inner))[:, None] + np.arange(6)
    assert np.all(np.abs(a.node_shapes[rows.ravel(), 2:]).max(axis=0) > 0)
    # Body.recover is T's rows of that shaft: boundary DOFs copied, interior from the body's T.
    V = np.random.default_rng(1).standard_normal((red.K.shape[0], 3))
    own = slice(6 * body.first_node, 6 * body.first_node + body.body.T.shape[0])
    np.testing.assert_allclose(body.recover(V), (red.T @ V)[own], rtol=1e-12, atol=1e-12)  # sums reordered


def test_every_interior_mode_kept_is_the_unreduced_full_model():
    # Keeping all fixed-interface modes makes T square and invertible: a change of coordinates, so
    # the eigenvalues are the unreduced ones. Both are dense 493-DOF solves, each good to
    # eps·λ_max/λ/2 = 7e-9 on the 18 Hz mode (f_max = 1.4e5 Hz): 1.4e-8 together at worst (4e-9 seen),
    # so 5e-8. atol for the rigid modes' 0.
    ref = _full(flex_chain())
    red = _full(flex_chain(Reduce(modes=10_000)))
    assert red.K.shape == ref.K.shape
    assert all(b.body.n_residual == 0 for b in red.bodies)
    a, b = fs.modal_analysis(red, 20), fs.modal_analysis(ref, 20)
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=5e-8, atol=1e-9)
    assert a.kinds == b.kinds


@pytest.mark.parametrize(("bearings", "n_rigid"), [((), 6), ((("a: journal", 2e8),), 4), (None, 2)])
def test_rigid_motions_of_a_chain_with_flexible_bodies_are_exact(bearings, n_rigid):
    # A rigid motion has K u = 0, which the constraint modes Ψ = −K_ii⁻¹ K_ib carry exactly: the
    # modal coordinates stay 0 and K R vanishes to round-off (not to the reduction's accuracy).
    kw = {} if bearings is None else {"bearings": bearings}
    fm = _full(flex_chain(Reduce(modes=3), **kw))
    R = fm.rigid_basis
    assert R.shape[1] == n_rigid
    assert np.all(R[fm.modal] == 0)
    # A few eps of max|K|·max|R| (R's entries reach 2.3, rotations times lever arms): ~1e-14 seen.
    assert np.max(np.abs(fm.K @ R)) < 1e-12 * abs(fm.K).max()
    # Recovered on every node it is the exact rigid motion of the unreduced chain, up to the constraint
    # modes' round-off: eps·κ(K_ii)·max|R| with the interiors' scaled condition ~4e4: ~2e-11 (2e-12 seen).
    ref = _full(flex_chain(**kw))
    np.testing.assert_allclose(fm.T @ R, ref.T @ ref.rigid_basis, rtol=0, atol=1e-10)
    m = fs.modal_analysis(fm, n_rigid + 2)
    assert m.rigid.sum() == n_rigid and np.all(m.frequencies_hz[n_rigid:] > 1.0)
    total = sum(m.family_energy().values())
    np.testing.assert_allclose(total, 1.0, rtol=1e-10)  # M-normalised shapes: n·eps (~2e-15 seen)
