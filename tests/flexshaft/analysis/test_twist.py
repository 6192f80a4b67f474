"""The applied-torque twist test and the torsion mesh of parts made from sections."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.twist import twist_test
from flexshaft.cli import main
from flexshaft.sections import table_from_segments
from tests.conftest import EXAMPLES

G, RHO = fs.STEEL.G, fs.STEEL.rho
STEPS = [(0.3, 0.16, 0.0), (0.5, 0.12, 0.04), (0.2, 0.10, 0.04)]  # length, od, id (m)


def ip(od, id_):
    return math.pi * (od**4 - id_**4) / 32  # polar moment of a tube, = J for a tube


def chain(steps=STEPS, max_element_length=None, motor=58.1):
    table = table_from_segments([{"length": L, "od": D, "id": d} for L, D, d in steps])
    shaft = fs.Shaft.from_sections("shaft", table, fs.STEEL, max_element_length=max_element_length)
    return fs.Drivetrain("t", [fs.Rigid("motor", motor), shaft])


def test_tube_stiffness_is_G_J_over_L_exactly():
    r = twist_test(chain([(1.3, 0.2, 0.12)], max_element_length=0.01), torque=86e3)
    (part,) = r.parts
    # Round-off of the clamped 130-element chain's solve: condition number 2.8e4, eps·κ ≈ 6e-12.
    assert part.stiffness == pytest.approx(G * ip(0.2, 0.12) / 1.3, rel=1e-10)
    assert r.theta.size == 131  # 130 elements of 1 cm: nodes at every station and every cut


def test_stepped_shaft_twist_line_is_the_series_sum():
    r = twist_test(chain(max_element_length=0.05), torque=1e4)
    (part,) = r.parts
    # Round-off of the clamped 20-element chain's solve: condition number 1.4e3, eps·κ ≈ 3e-13.
    assert part.stiffness == pytest.approx(1 / sum(L / (G * ip(D, d)) for L, D, d in STEPS), rel=1e-11)
    # The twist at x is T·∫₀ˣ dx/(G J): piecewise linear, one slope per segment.
    edges = np.cumsum([0.0] + [L for L, _, _ in STEPS])
    slopes = [1e4 / (G * ip(D, d)) for _, D, d in STEPS]
    expected = np.array(
        [sum(s * np.clip(x - a, 0.0, b - a) for s, a, b in zip(slopes, edges[:-1], edges[1:])) for x in r.x]
    )
    # The same solve (eps·κ ≈ 3e-13) against sums of clipped segment lengths (a few eps); atol for the
    # clamp's 0 against twists of ~1e-5 rad.
    np.testing.assert_allclose(r.theta, expected, rtol=1e-11, atol=1e-18)


def test_load_independent_and_sign():
    r = twist_test(chain(), torque=-500.0)
    # The ramp's multiples are powers of two (and 1): one solve scales exactly, the spread is 0 up to
    # the rounding of the ratios.
    assert r.load_spread < 1e-12
    assert r.parts[0].twist < 0 and r.parts[0].stiffness > 0


def test_given_chain_returns_every_stiffness_and_interior_stations():
    d = fs.load_model("examples/customer1.toml")
    r = twist_test(d, torque=1.0)
    # One element per part, the clamped 4-DOF solve's condition number 38: a few eps; 1e-12 here and below.
    for p in r.parts:
        assert p.stiffness == pytest.approx(d.component(p.name).stiffness, rel=1e-12)
    # Clamp and load between two interior stations: only the parts in between carry the torque.
    r2 = twist_test(d, torque=1.0, clamp="part 1/part 2", load="part 3/part 4")
    assert [p.name for p in r2.parts] == ["part 2", "part 3"]
    k_series = 1 / (1 / d.component("part 2").stiffness + 1 / d.component("part 3").stiffness)
    assert r2.total_stiffness == pytest.approx(k_series, rel=1e-12)


def test_bad_twist_input():
    d = chain()
    with pytest.raises(fs.ModelError, match="clamp = 'x': no such station"):
        twist_test(d, clamp="x")
    with pytest.raises(fs.ModelError, match="torque = 0.0 N·m: must be a finite, non-zero torque"):
        twist_test(d, torque=0.0)
    with pytest.raises(fs.ModelError, match="clamp and load are the same station"):
        twist_test(d, clamp="motor", load="motor")


def test_stiffnesses_near_the_end_of_floating_point(recwarn):
    # One part of 1e308 N·m/rad twists 1e-305 rad under 1000 N·m: resolved, and the load-spread
    # check (a mean of stiffnesses) must not overflow. Two of them sum past 1e308 at their shared
    # node: the assembled matrix is refused, as modal analysis refuses it (before: inf and a spread
    # of nan printed with warnings, exit 0).
    c1 = (EXAMPLES / "customer1.toml").read_text()
    one = fs.loads_model(c1.replace("stiffness = 307933.18", "stiffness = 1e308"), source="m.toml")
    t = twist_test(one)
    # A chain's LU is a substitution: the part's twist is T/k after a few roundings (eps each), and
    # the ramp's torques give it again, so 1e-9 holds with orders to spare.
    assert t.parts[0].stiffness == pytest.approx(1e308, rel=1e-9) and t.load_spread < 1e-9
    two = c1.replace("stiffness = 307933.18", "stiffness = 1e308")
    two = two.replace("stiffness = 156591.02", "stiffness = 1e308")
    with pytest.raises(fs.ModelError, match="the assembled stiffness matrix overflows double precision"):
        twist_test(fs.loads_model(two, source="m.toml"))
    assert not [str(w.message) for w in recwarn]


def test_section_mesh_frequencies_converge_at_rate_two():
    # Free-free uniform tube: f_k = k/(2L)·√(G/ρ); consistent inertia converges from above at h².
    L, D, d = 2.0, 0.2, 0.1
    exact = 1 / (2 * L) * math.sqrt(G / RHO)
    errs = []
    for n in (10, 20, 40):
        table = table_from_segments([{"length": L, "od": D, "id": d}])
        shaft = fs.Shaft.from_sections("tube", table, fs.STEEL, max_element_length=L / n)
        f1 = fs.modal_analysis(fs.Drivetrain("t", [shaft]), count=2, damped=False).frequencies_hz[1]
        errs.append(f1 / exact - 1)
    assert all(e > 0 for e in errs)
    assert np.log2(errs[0] / errs[1]) == pytest.approx(2.0, abs=0.05)
    assert np.log2(errs[1] / errs[2]) == pytest.approx(2.0, abs=0.05)


def test_section_mesh_puts_inertia_where_the_mass_is():
    # A heavy flange-like segment at one end: the shaft's inertia is not spread uniformly any more,
    # but its total is ρ·Σ Ip·L and its end-to-end stiffness the series sum, whatever the mesh.
    steps = [(0.05, 0.5, 0.1), (1.0, 0.1, 0.0)]
    a = chain(steps).component("shaft")
    b = chain(steps, max_element_length=0.01).component("shaft")
    for s in (a, b):
        k, j, _ = s.element_properties()
        # Sums of up to 105 positive terms against the segments' closed forms: ~100 eps at most.
        assert 1 / np.sum(1 / k) == pytest.approx(s.stiffness, rel=1e-12)
        assert np.sum(j) == pytest.approx(RHO * sum(ip(D, d) * L for L, D, d in steps), rel=1e-12)
    assert a.torsion_mesh().n_elements == 2 and b.torsion_mesh().n_elements == 5 + 100


def test_cli_twist(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n[[chain]]\nname = "tube"\n'
        'type = "shaft"\nmaterial = "steel"\nsegments = [{length = 1.3, od = 0.2, id = 0.12}]\n'
        "max_element_length = 0.1\n"
    )
    assert main(["twist", str(model), "--torque", "86000", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    # 13 elements: condition number 290, eps·κ ≈ 6e-14 (JSON keeps every digit).
    assert doc["parts"][0]["stiffness"] == pytest.approx(G * ip(0.2, 0.12) / 1.3, rel=1e-12)
    assert doc["units"]["stiffness"] == "N·m/rad" and len(doc["nodes"]["x"]) == 14
    assert main(["twist", str(model)]) == 0
    assert "load independence" in capsys.readouterr().out
    assert main(["twist", str(model), "--at", "nowhere"]) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith(f"flexshaft: error: {model}: --at = 'nowhere': no such station")
        and err.count("\n") == 1
    )


def test_stiffness_target_is_exact():
    from flexshaft.analysis.twist import stiffness_target

    shaft = chain().component("shaft")
    target = 0.8 * shaft.stiffness
    t = stiffness_target(shaft, target)
    # Rebuild with the new E (ν fixed) and with scaled dimensions: both hit the target (k ∝ E, s³, s⁴ - a
    # root and a few roundings, ~10 eps).
    e_mat = fs.Material(E=t.youngs_modulus, nu=fs.STEEL.nu, rho=fs.STEEL.rho)
    assert fs.Shaft.from_sections("s", shaft.sections, e_mat).stiffness == pytest.approx(target, rel=1e-12)
    s = t.scale_all
    scaled = table_from_segments([{"length": s * L, "od": s * D, "id": s * d} for L, D, d in STEPS])
    assert scaled.torsional_stiffness(G) == pytest.approx(target, rel=1e-12)
    s = t.scale_diameters
    scaled = table_from_segments([{"length": L, "od": s * D, "id": s * d} for L, D, d in STEPS])
    assert scaled.torsional_stiffness(G) == pytest.approx(target, rel=1e-12)
    with pytest.raises(fs.ModelError, match="needs a shaft made from sections"):
        stiffness_target(fs.Shaft("p", stiffness=1e5, inertia=1.0), 1e5)


def test_cli_twist_target_and_plot(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n[[chain]]\nname = "tube"\n'
        'type = "shaft"\nmaterial = "steel"\nsegments = [{length = 1.3, od = 0.2, id = 0.12}]\n'
    )
    png = tmp_path / "twist.png"
    k = G * ip(0.2, 0.12) / 1.3
    assert main(["twist", str(model), "--json", "--target", f"tube={k / 2}", "--plot", str(png)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["targets"][0]["E"] == pytest.approx(fs.STEEL.E / 2, rel=1e-12)  # k ∝ E: a few roundings
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["twist", str(model), "--plot", str(png)]) == 2  # never overwritten without --force
    assert "file exists" in capsys.readouterr().err
    assert main(["twist", str(model), "--target", "tube"]) == 2
    assert "--target = 'tube': is not PART=STIFFNESS" in capsys.readouterr().err


def test_named_nodes_inside_a_part(tmp_path):
    # A station inside a part: the twist from the clamp to it is T·x/(G·J) on a uniform first segment.
    model = tmp_path / "m.toml"
    model.write_text(
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n[[chain]]\nname = "a"\n'
        'type = "shaft"\nmaterial = "steel"\nsegments = [{length = 1.0, od = 0.2}, '
        "{length = 0.5, od = 0.1}]\nstations = {journal = 0.37, sensor = 1.2}\n"
    )
    d = fs.load_model(model)
    names = [s.name for s in fs.assemble(d).stations]
    assert names == ["motor", "a: journal", "a: sensor", "a end"]
    r = twist_test(d, 1e4, load="a: journal")
    assert r.parts == ()  # no whole part between the clamp and the load
    node = dict(r.stations)["a: journal"]
    assert r.x[node] == pytest.approx(0.37, abs=1e-15)  # the station's own x, or an ulp off it (5.6e-17)
    # A few elements in series from the clamp (κ ~ 10): a few eps
    assert r.theta[node] == pytest.approx(1e4 * 0.37 / (G * ip(0.2, 0.0)), rel=1e-12)
    model.write_text(model.read_text().replace("sensor = 1.2", "sensor = 1.5"))
    with pytest.raises(fs.ModelError, match=r"stations = 1.5 m: lies outside the part"):
        fs.load_model(model)


@pytest.mark.parametrize("torque", [1e-320, 1e308, -1e308, 0.0])
def test_torques_double_precision_cannot_carry_are_refused(torque):
    # 1e-320 N·m is subnormal (the twist would be 0: T/Δθ a division by zero) and 1e308 overflows the
    # ramp to 2 T; either was a traceback or NaN stiffnesses. 1e±30 N·m is the accepted range.
    with pytest.raises(fs.ModelError, match=r"torque = .* N·m: must be a finite, non-zero torque"):
        twist_test(fs.load_model(EXAMPLES / "customer1.toml"), torque)
    r = twist_test(fs.load_model(EXAMPLES / "customer1.toml"), 1e30)
    # the ramp scales by powers of two: the spread is round-off of the ratios at most
    assert np.all(np.isfinite([p.stiffness for p in r.parts])) and r.load_spread < 1e-12


def test_a_1d_parts_end_stiffness_is_the_cantilevers_closed_forms():
    # The one twist test of a part (part_stiffness) on a 6-DOF beam model, clamped at its start:
    # Saint-Venant's G·J/L, the bar's E·A/L and Timoshenko's cantilever 1/(L³/(3EI) + L/(G·κA)) - exact
    # for Timoshenko elements at any length (statics), so to round-off.
    from flexshaft.analysis.twist import part_stiffness
    from flexshaft.parts.model import part_model

    L, D = 1.0, 0.1
    table = table_from_segments([{"length": L, "od": D}])
    got = part_stiffness(part_model(table, fs.STEEL, dofs="full", max_element_length=0.1))
    A, I = math.pi * D**2 / 4, math.pi * D**4 / 64
    E, G = fs.STEEL.E, fs.STEEL.G
    assert got.torsion == pytest.approx(G * 2 * I / L, rel=1e-9)
    assert got.axial == pytest.approx(E * A / L, rel=1e-9)
    tip = 1.0 / (L**3 / (3 * E * I) + L / (G * float(table.shear_area_y[0])))
    assert got.bending == pytest.approx((tip, tip), rel=1e-9)
    np.testing.assert_allclose(got.stiffness @ got.compliance, np.eye(6), atol=1e-8)


def test_a_1d_body_by_multigrid_condenses_to_the_series_stiffness():
    # the solver strategy of the one Craig-Bampton front end: multigrid CG (to 1e-8) on a 1D part
    # gives the static condensation of the chain, the intervals' springs in series 1/Σ L/(G·J)
    from flexshaft.errors import ModelError
    from flexshaft.parts.model import part_model
    from flexshaft.reduction import craig_bampton

    table = table_from_segments([{"length": 0.6, "od": 0.2, "id": 0.1}, {"length": 0.4, "od": 0.12}])
    part = part_model(table, fs.STEEL, dofs="torsion", max_element_length=0.01)
    series = 1.0 / (
        0.6 / (fs.STEEL.G * math.pi * (0.2**4 - 0.1**4) / 32) + 0.4 / (fs.STEEL.G * math.pi * 0.12**4 / 32)
    )
    body = craig_bampton(part, modes=0, residual=False, solver="amg")
    assert body.K[0, 0] == pytest.approx(series, rel=1e-6)
    with pytest.raises(ModelError, match="unknown solver"):
        craig_bampton(part, modes=0, solver="cholesky")
