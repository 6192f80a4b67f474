"""The drivetrain with six DOFs per node: Timoshenko shafts, couplings as links, bearings."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.cli import main
from flexshaft.fullchain import assemble_full, full_modes
from flexshaft.partmodel import part_model
from flexshaft.partmodes import part_modes
from flexshaft.sections import cowper_shear_factor, table_from_segments

E, G, RHO, NU = fs.STEEL.E, fs.STEEL.G, fs.STEEL.rho, fs.STEEL.nu


def shaft(name, segs, n=40):
    t = table_from_segments(segs, name=name)
    return fs.Shaft.from_sections(name, t, fs.STEEL, max_element_length=t.length / n)


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
    m = full_modes(assemble_full(d), 30)
    torsion = m.frequencies_hz[np.array(m.kind) == "torsion"]
    chain = fs.modal_analysis(d, count=5, damped=False).frequencies_hz
    np.testing.assert_allclose(torsion[:5], chain, rtol=1e-8, atol=1e-9)
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
    m = full_modes(assemble_full(d), 16)
    one = part_modes(
        part_model(
            table_from_segments([{"length": 2.0, "od": 0.1}]), fs.STEEL, dofs="full", max_element_length=0.02
        ),
        16,
    )
    np.testing.assert_allclose(m.frequencies_hz[6:], one.frequencies_hz[6:], rtol=1e-9)


def test_bearings_from_the_model_file_give_pinned_pinned_timoshenko(tmp_path):
    model = tmp_path / "m.toml"
    model.write_text(
        '[model]\ndofs = "full"\n\n[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\n'
        "segments = [{length = 1.0, od = 0.1}]\nmax_element_length = 0.02\n\n"
        '[[bearings]]\nstation = "s start"\nstiffness = 1e14\n\n'
        '[[bearings]]\nstation = "s end"\nstiffness = 1e14\n'
    )
    d = fs.load_model(model)
    m = full_modes(assemble_full(d, dict(d.bearings)), 6)
    # Timoshenko pinned-pinned (Han, Benaroya & Wei, J. Sound Vib. 225, 1999), k = π/L, lower root of
    # EI k⁴ − ρA ω² − ρI ω² k² (1 + E/(κG)) + ρ² I ω⁴/(κG) = 0.
    L, D = 1.0, 0.1
    I, A = math.pi * D**4 / 64, math.pi * D**2 / 4
    kap = cowper_shear_factor(0.0, NU)
    k = math.pi / L
    a, b, c = RHO**2 * I / (kap * G), -(RHO * A + RHO * I * k**2 * (1 + E / (kap * G))), E * I * k**4
    f = math.sqrt((-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)) / (2 * math.pi)
    lateral = m.frequencies_hz[~m.rigid][:2]
    np.testing.assert_allclose(lateral, [f, f], rtol=2e-4)
    assert m.kind[2] == "lateral"


def test_full_model_errors():
    d = fs.Drivetrain("x", [fs.Rigid("m", 1.0), fs.Shaft("p", stiffness=1e5, inertia=1.0)], dofs="full")
    with pytest.raises(fs.ModelError, match="has no cross-sections, so no bending stiffness or mass"):
        assemble_full(d)
    with pytest.raises(fs.ModelError, match="bearings.station = 'nowhere': no such station"):
        assemble_full(bench_chain(dofs="full"), {"nowhere": 1e9})
    with pytest.raises(fs.ModelError, match="bearings act on lateral DOFs"):
        bench_chain(bearings=(("motor", 1e9),))


def test_cli_modes_of_a_full_model(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(
        '[model]\ndofs = "full"\n\n[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 5.0\n\n'
        '[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\n'
        "segments = [{length = 1.0, od = 0.1}]\nmax_element_length = 0.05\n\n"
        '[[bearings]]\nstation = "motor"\nstiffness = 1e9\n\n'
        '[[bearings]]\nstation = "s end"\nstiffness = 1e9\n'
    )
    assert main(["modes", str(model), "--json", "--count", "8"]) == 0
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

    assert main(["modes", str(EXAMPLES / "ptss_full.toml"), "--json", "--count", "6"]) == 0
    doc = json.loads(capsys.readouterr().out)
    torsion = [m["frequency_hz"] for m in doc["modes"] if m["kind"] == "torsion" and not m["rigid"]]
    chain = fs.modal_analysis(fs.load_model(EXAMPLES / "ptss_full.toml"), count=3, damped=False)
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
    m = full_modes(assemble_full(d, dict(d.bearings)), 10)
    pm = part_model(t, fs.STEEL, dofs="full", max_element_length=0.05, nodes_at=(0.5, 1.5))
    nodes = [int(np.argmin(np.abs(pm.x - p))) for p in (0.5, 1.5)]
    ref = part_modes(pm, 10, bearings={nodes[0]: 1e9, nodes[1]: 1e9})
    np.testing.assert_allclose(m.frequencies_hz[2:], ref.frequencies_hz[2:], rtol=1e-9)
    assert m.kind[2] == "lateral"
