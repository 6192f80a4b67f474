"""Flexible bodies (Craig–Bampton parts) assembled in the torsion chain.

References: the same chain unreduced (same mesh, same elements), closed forms
of a uniform free-free shaft and of series springs, and the damping ratio the
model sets (a free flexible body must carry it on every elastic mode).
"""

import dataclasses
import json
import re
import textwrap

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import modal_analysis
from flexshaft.analysis.twist import twist_test
from flexshaft.cli import main
from flexshaft.model.assembly import assemble
from flexshaft.model.components import Reduce, Shaft
from tests.conftest import EXAMPLES

FLEX = EXAMPLES / "customer1_flex.toml"


def _unreduced_text() -> str:
    """The example without its ``reduce`` lines: every part on its full mesh."""
    text = FLEX.read_text(encoding="utf-8")
    return re.sub(r"^reduce = .*$", "", text, flags=re.M)


def _load(text: str):
    return fs.loads_model(textwrap.dedent(text), source="m.toml")


def _part_cutoff(cb) -> float:
    """The highest fixed-interface frequency a body keeps (residual vectors aside), Hz."""
    body = cb.body
    return float(body.fixed_interface_hz[: body.n_modes - body.n_residual].max())


def test_customer1_flexible_parts_match_the_unreduced_chain():
    flex = fs.load_model(FLEX)
    full = fs.loads_model(_unreduced_text(), source=str(FLEX))
    red = modal_analysis(flex, 14)
    ref = modal_analysis(full, 14)
    assert len(red.model.bodies) == 3
    assert red.model.n_dof < ref.model.n_dof / 5
    cutoff = min(_part_cutoff(b) for b in red.model.bodies)
    below = ~ref.rigid & (ref.frequencies_hz < cutoff)
    assert below.sum() >= 8
    err = np.abs(red.frequencies_hz[below] / ref.frequencies_hz[below] - 1)
    assert np.all(err < 1e-3), err
    # The reduced model is a Ritz approximation of the full one: never below it, but for the unreduced
    # dense solve's round-off, eps·λ_max/λ/2 = 8e-9 at most on its 11 Hz mode (f_max = 9.3e4 Hz; 2.4e-10
    # seen): 3e-8.
    assert np.all(red.frequencies_hz[below] >= ref.frequencies_hz[below] * (1 - 3e-8))
    # Same stations, same dominant components, same shapes there.
    assert [s.name for s in red.model.stations] == [s.name for s in ref.model.stations]
    assert red.dominant_components()[:9] == ref.dominant_components()[:9]
    a, b = red.station_shapes()[:, below], ref.station_shapes()[:, below]
    assert np.max(np.abs(a - b)) < 2e-3  # measured 4.5e-4


def test_all_interior_modes_kept_is_exact():
    # Keeping every fixed-interface mode spans the whole interior: no reduction error at all.
    text = """
    [model]
    name = "one part"
    [[chain]]
    name = "motor"
    type = "rigid"
    inertia = 2.0
    [[chain]]
    name = "p"
    type = "shaft"
    material = "steel"
    segments = [{length = 0.3, od = 0.1}, {length = 0.2, od = 0.06, id = 0.02}]
    max_element_length = 0.05
    reduce = {modes = 9}
    """
    flex = _load(text)
    ref = _load(text.replace("reduce = {modes = 9}", ""))
    a, b = modal_analysis(flex), modal_analysis(ref)
    assert flex.component("p").reduce.modes == 9
    assert a.model.bodies[0].body.n_modes == 9  # 11 nodes, 2 interface: 9 interior
    # A change of coordinates: equal but for the two 11-DOF solves' round-off, eps·λ_max/λ₁ ~ 1e-13.
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-10, atol=1e-9)


def test_free_uniform_shaft_against_the_closed_form():
    # Free-free uniform shaft in torsion: f_n = n·c/(2L), c = √(G/ρ).
    L, d = 1.0, 0.1
    text = f"""
    [model]
    name = "rod"
    [[chain]]
    name = "rod"
    type = "shaft"
    material = "steel"
    segments = [{{length = {L}, od = {d}}}]
    max_element_length = 0.002
    reduce = {{modes = 12}}
    """
    dt = _load(text)
    mat = dt.component("rod").material
    c = np.sqrt(mat.G / mat.rho)
    res = modal_analysis(dt, 5)
    assert res.rigid[0] and res.frequencies_hz[0] == 0.0  # set, not solved for
    n = np.arange(1, 5)
    exact = n * c / (2 * L)
    # Linear elements with consistent inertia stiffen mode n by (kh)²/24, k = nπ/L
    # (the dispersion of the discrete rod); the reduction adds little on top.
    h = 0.002
    mesh = (n * np.pi * h / L) ** 2 / 24
    err = res.frequencies_hz[1:] / exact - 1
    assert np.all(err > 0)
    assert np.all(np.abs(err - mesh) < 2e-6 + 0.02 * mesh), (err, mesh)


def test_static_stiffness_between_interfaces_is_exact():
    # Craig–Bampton keeps the static condensation: clamping one end and twisting
    # the other gives the series stiffness 1/Σ(L/GJ) of the part, to round-off.
    dt = fs.load_model(FLEX)
    model = assemble(dt)
    for cb in model.bodies:
        comp = dt.components[cb.component]
        nb = cb.body.boundary_nodes.size
        Kb = cb.body.K[:nb, :nb]
        # end-to-end stiffness of the condensed boundary matrix (interior boundary nodes condensed too)
        if nb > 2:
            keep = [0, nb - 1]
            mid = list(range(1, nb - 1))
            Kb = Kb[np.ix_(keep, keep)] - Kb[np.ix_(keep, mid)] @ np.linalg.solve(
                Kb[np.ix_(mid, mid)], Kb[np.ix_(mid, keep)]
            )
        k_series = 1.0 / np.sum(comp.sections.lengths / (comp.material.G * comp.sections.j))
        # Round-off of the condensation (Ψ = −K_ii⁻¹K_ib, torsion K_ii of condition ~n² ≈ 8e3): ~eps·8e3
        # ≈ 2e-12 at most; 1e-10. The coupling K_bq cancels to a few eps of max|K|; 1e-9 is loose.
        assert Kb[0, 0] == pytest.approx(k_series, rel=1e-10)
        assert Kb[0, 1] == pytest.approx(-k_series, rel=1e-10)
        # No coupling of the boundary to the modal coordinates (the CB property).
        assert np.max(np.abs(cb.body.K[:nb, nb:])) <= 1e-9 * np.max(np.abs(cb.body.K))


def test_twist_test_of_a_flexible_model_equals_the_unreduced_one():
    flex, full = fs.load_model(FLEX), fs.loads_model(_unreduced_text(), source="x")
    a, b = twist_test(flex, 1e4), twist_test(full, 1e4)
    # The twist test assembles both unreduced: the same matrices and solve (identical); 1e-12 for the rest.
    np.testing.assert_allclose([p.stiffness for p in a.parts], [p.stiffness for p in b.parts], rtol=1e-12)


def test_flexible_damping_matches_per_shaft_modal_damping():
    # Unreduced shafts with damping_ratio get C from their own free-free modes;
    # a flexible body does the same on its reduced modes. The system's damped
    # ratios agree where the reduction is accurate.
    red = modal_analysis(fs.load_model(FLEX), 8)
    ref = modal_analysis(fs.loads_model(_unreduced_text(), source="x"), 8)
    el = ~ref.rigid
    # Measured 1.3e-4: the body's free modes are the unreduced shaft's to 1e-5 and carry the same ratios.
    np.testing.assert_allclose(red.damping_ratios[el], ref.damping_ratios[el], rtol=1e-3, atol=1e-7)


def test_energy_fractions_and_torques_include_bodies():
    res = modal_analysis(fs.load_model(FLEX), 8)
    ref = modal_analysis(fs.loads_model(_unreduced_text(), source="x"), 8)
    se, ke = res.strain_energy_fractions(), res.kinetic_energy_fractions()
    el = ~res.rigid
    # shares of one total summed back: ~n_owners·eps
    np.testing.assert_allclose(se[el].sum(axis=1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(ke.sum(axis=1), 1.0, rtol=1e-12)
    # Energies are quadratic in the shapes, so as accurate as the frequencies: measured 1e-6.
    np.testing.assert_allclose(se, ref.strain_energy_fractions(), atol=1e-5)
    np.testing.assert_allclose(ke, ref.kinetic_energy_fractions(), atol=1e-5)
    t, tr = res.component_torques(), ref.component_torques()
    # Peak element torque is a local strain, recovered through T: it converges more slowly than the
    # frequencies (measured 1.3e-2 on the highest of these modes).
    np.testing.assert_allclose(t, tr, rtol=3e-2, atol=1e-6 * np.max(tr))


def test_named_node_stays_a_physical_station():
    model = assemble(fs.load_model(FLEX))
    st = {s.name: s.node for s in model.stations}
    assert "part 2: torque_flange" in st
    part2 = next(b for b in model.bodies if model.drivetrain.components[b.component].name == "part 2")
    assert st["part 2: torque_flange"] in part2.interface_nodes
    # sums of segment lengths: an ulp or two of 2.2 m (4e-16)
    np.testing.assert_allclose(part2.body.boundary_x - part2.body.boundary_x[0], [0.0, 1.1, 2.2], atol=1e-12)
    # The rigid-body mode: every node turns, modal coordinates rest.
    R = model.rigid_basis
    # K·R cancels to round-off: a few eps of max|K|, the bodies' constraint modes adding eps·κ(K_ii) at
    # most (~1e-12); 1e-9 is loose.
    assert np.max(np.abs(model.K @ R)) < 1e-9 * abs(model.K).max()
    assert np.all(R[model.modal] == 0)


def test_cli_modes_on_flexible_bodies(capsys):
    assert main(["modes", str(FLEX)]) == 0
    out = capsys.readouterr().out
    # 4 modes as the file asks, one residual vector per interface DOF (θx at 2 nodes).
    assert re.search(
        r"part 1: flexible body, 2 interface nodes \+ 4 modes \(fixed-interface, up to \d+ Hz\) "
        r"\+ 2 residual vectors",
        out,
    )
    assert "part 2: flexible body, 3 interface nodes" in out
    assert main(["modes", str(FLEX), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    bodies = {b["component"]: b for b in doc["flexible_bodies"]}
    assert bodies["part 2"]["interface_stations"] == [
        "part 1/part 2",
        "part 2: torque_flange",
        "part 2/part 3",
    ]
    assert {c["name"]: c.get("reduce") for c in doc["components"]}["part 1"] == "4 modes"
    # part 1: 0.06 + 1.60 + 0.06 m in elements of at most 0.02 m: 3 + 80 + 3 elements, 87 nodes.
    assert bodies["part 1"]["mesh_nodes"] == 87


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        ("reduce = {}", "reduce"),
        ("reduce = {modes = 2, cutoff_hz = 100}", "reduce"),
        ("reduce = {modes = -1}", "reduce.modes"),
        ("reduce = {modes = 2.5}", "reduce.modes"),
        ("reduce = {cutoff_hz = -5}", "reduce.cutoff_hz"),
        ("reduce = {modes = 2, mode = 3}", "reduce.mode"),
        ("reduce = 4", "reduce"),
        ("damping_bands = [[0, 100, 0.01]]", "damping_bands"),
        ("rayleigh = {alpha = 1.0}", "rayleigh"),
        ("damping_ratio = [0.01, 0.02]", "damping_ratio"),
        ("reduce = {modes = 2}\ndamping_ratio = 0.01\nrayleigh = {alpha = 1.0}", "rayleigh"),
    ],
)
def test_bad_reduce_entries(extra, field):
    text = f"""
    [model]
    name = "bad"
    [[chain]]
    name = "p"
    type = "shaft"
    material = "steel"
    segments = [{{length = 0.5, od = 0.1}}]
    max_element_length = 0.05
    {extra}
    """
    with pytest.raises(fs.ModelError) as err:
        _load(text)
    assert err.value.field == field
    assert err.value.component is not None


def test_full_model_takes_flexible_bodies():
    # The 6-DOF PTSS line with every shaft a flexible body (boundary: its ends; two fixed-interface
    # modes plus residual vectors each) against itself unreduced: same modes, same DOF families.
    pytest.importorskip("build123d")
    dt = fs.load_model(EXAMPLES / "ptss_full.toml")
    comps = tuple(
        dataclasses.replace(c, reduce=Reduce(modes=2)) if isinstance(c, Shaft) else c for c in dt.components
    )
    red = assemble(dataclasses.replace(dt, components=comps))
    ref = assemble(dt)
    assert len(red.bodies) == 3 and red.K.shape[0] < ref.K.shape[0] / 10
    a, b = modal_analysis(red, 8), modal_analysis(ref, 8)
    el = ~b.rigid
    # 1e-4, though part 2 keeps only its 47 Hz pair and 56 and 93 Hz lie above it: the residual
    # vectors carry the truncated modes' static part (measured 2.1e-6 at most).
    np.testing.assert_allclose(a.frequencies_hz[el], b.frequencies_hz[el], rtol=1e-4)
    assert a.kinds == b.kinds
    # Each body reduces its part's whole mesh: T recovers the six DOFs of every node of it.
    for fb in red.bodies:
        start, stop = fb.first_node, fb.first_node + fb.body.n_mesh_nodes - 1
        assert fb.body.T.shape[0] == 6 * fb.body.n_mesh_nodes
        assert red.x[stop] - red.x[start] == pytest.approx(fb.body.boundary_x[-1] - fb.body.boundary_x[0])
