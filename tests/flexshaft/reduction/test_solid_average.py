"""Solid bodies whose end faces are tied by averaging (RBE3), and one face of each kind.

References: Saint-Venant torsion of a circular tube (G·J/L: its sections turn rigidly, so an averaging
end imposes what a rigid one does, and the twist modes are the wave solution k·√(G/ρ)/(2L)); the twist
test of the solid part with averaging ends (:func:`~flexshaft.analysis.twist.part_stiffness`, which
solves the unreduced body for loads at the end's master with the start's held - the same RBE3
multipliers, but a direct solve rather than the reduction's constraint modes and their condensation);
the energy ordering of ties (a rigid face admits fewer motions than an averaging one, so the end
stiffness cannot be lower); the unreduced solid's free-free modes, which
an averaging tie does not stiffen, so the body's free-free modes converge to them as modes are added.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.sparse.linalg import eigsh

from flexshaft.analysis.twist import part_stiffness
from flexshaft.elements.materials import STEEL
from flexshaft.elements.tet10 import solid_matrices
from flexshaft.errors import ModelError
from flexshaft.parts.solidpart import solid_part_model
from flexshaft.parts.solidties import interface_kinds, interface_statement
from tests.flexshaft.reduction import test_solid_body as tube
from tests.flexshaft.reduction.test_solid_body import GJ_L, WAVE, solid_cb

pytestmark = tube.pytestmark  # gmsh must load
mesh = tube.mesh  # the tube at 40 mm (a module fixture: meshed once in this module too)


def test_an_averaging_torsion_body_is_the_averaging_twist_test(mesh):
    body = solid_cb(mesh, STEEL, dofs="torsion", modes=3, interface="average")
    k = body.K[1, 1]
    assert GJ_L <= k <= 1.005 * GJ_L  # conforming, from above; Saint-Venant's sections turn rigidly
    # both condense the same discrete solid with the same averaging ties, one by the constraint modes,
    # one by a direct solve of the end's loads: equal to the LU solves' round-off
    twist = part_stiffness(solid_part_model(mesh, STEEL, interface="average"))
    assert k == pytest.approx(twist.torsion, rel=1e-8)
    np.testing.assert_allclose(body.K[:2, 2:], 0.0, atol=1e-9 * k)  # boundary and modes uncoupled
    # the fixed-interface twist modes: the wave solution from above, within the mesh's 1e-3
    f = body.fixed_interface_hz[:3]
    exact = WAVE * np.arange(1, 4)
    assert np.all(exact <= f) and np.all(f < 1.001 * exact)
    assert body.solid.interface == "end faces averaged (RBE3)"


def test_a_six_dof_averaging_body_is_the_averaging_end_matrix(mesh):
    body = solid_cb(mesh, STEEL, dofs="full", modes=0, residual=False, interface="average")
    end = body.K[6:12, 6:12]  # the start master held: its rows and columns drop out
    ref = part_stiffness(solid_part_model(mesh, STEEL, interface="average")).stiffness
    np.testing.assert_allclose(end, ref, rtol=1e-7, atol=1e-7 * np.abs(ref).max())
    assert np.sum(body.free_hz == 0.0) == 6  # free: the six rigid-body motions


def test_a_rigid_face_is_never_softer_than_an_averaging_one(mesh):
    # The end stiffness is the least strain energy over the motions a tie admits; a rigid face admits
    # a subset of an averaging face's, so each diagonal term orders average <= mixed <= rigid (to the
    # solves' round-off; the tube's torsion terms nearly coincide: its sections turn rigidly anyway).
    def end(interface):
        body = solid_cb(mesh, STEEL, dofs="full", modes=0, residual=False, interface=interface)
        return np.diag(body.K[6:12, 6:12])

    average, mixed, rigid = end("average"), end({"start": "rigid", "end": "average"}), end("rigid")
    assert np.all(average <= mixed * (1 + 1e-9)) and np.all(mixed <= rigid * (1 + 1e-9))
    # the lateral and axial terms feel the face's freedom (its Poisson contraction, its warping)
    assert np.all(average[[0, 1, 2, 4, 5]] < 0.99 * rigid[[0, 1, 2, 4, 5]])


def test_averaging_free_modes_converge_to_the_unreduced_free_solid(mesh):
    mats = solid_matrices(mesh, STEEL)
    # scipy's shift-invert Lanczos below zero: the six rigid motions and six elastic modes (the first
    # bending pair, the first twist mode, the axial mode, the second bending pair)
    lam = np.sort(eigsh(mats.K.tocsc(), k=12, M=mats.M.tocsc(), sigma=-1e3, return_eigenvectors=False))
    solid = np.sqrt(lam[6:]) / (2 * np.pi)
    errors = []
    for modes in (4, 16):
        body = solid_cb(mesh, STEEL, dofs="full", modes=modes, interface="average")
        f = body.free_hz[6:9]  # the bending pair and the twist mode, far below the kept modes
        assert np.all(f >= solid[:3] * (1 - 1e-9))  # Rayleigh-Ritz: from above
        errors.append(np.max(f / solid[:3] - 1))
    # Craig-Bampton with residual vectors: the error falls like (f/f_c)⁴ or faster as f_c rises
    # (measured 2.8e-4 -> 1.5e-6 as f_c goes 4.3 -> 8.3 kHz; (4.3/8.3)⁴ alone would give 2e-5)
    assert errors[1] < 0.1 * errors[0] and errors[1] < 1e-5


def test_interfaces_are_read_and_refused_by_name():
    assert interface_kinds("average") == ("average", "average")
    assert interface_kinds({"end": "average"}) == ("rigid", "average")
    assert interface_kinds(["average", "rigid"]) == ("average", "rigid")
    assert interface_statement(("rigid", "average")) == "start face rigid (RBE2), end face averaged (RBE3)"
    with pytest.raises(ModelError, match="unknown tie") as e:
        interface_kinds({"end": "glued"})
    assert e.value.field == "interface.end"
    with pytest.raises(ModelError, match="names no end face"):
        interface_kinds({"middle": "rigid"})
    with pytest.raises(ModelError, match="one per end face"):
        interface_kinds(3)


def test_a_model_file_ties_each_face_and_the_twist_test_says_how(tmp_path, capsys):
    from flexshaft.cli import main

    model = tmp_path / "tube.toml"
    text = tube.TUBE.replace('fe = "solid"\n', 'fe = "solid"\ninterface = {end = "average"}\n')
    model.write_text(text)
    assert main(["twist", str(model), "--torque", "1000"]) == 0
    out = capsys.readouterr().out
    assert "start face rigid (RBE2), end face averaged (RBE3)" in out
    # a 1D part has no faces to tie: one line, exit 2, naming the key
    model.write_text(text.replace('fe = "solid"\n', "").replace('mesh_size = "40 mm"\n', ""))
    assert main(["twist", str(model)]) == 2
    err = capsys.readouterr().err
    assert "interface" in err and "solid" in err and len(err.strip().splitlines()) == 1


def test_compare_solid_ties_the_solid_as_the_part_says(tmp_path, capsys):
    from flexshaft.cli import main

    model = tmp_path / "tube.toml"
    model.write_text(tube.TUBE.replace('fe = "solid"\n', 'fe = "solid"\ninterface = "average"\n'))
    assert main(["sections", str(model), "--compare-solid", "--json"]) == 0
    (part,) = json.loads(capsys.readouterr().out)
    assert part["interface"].startswith("averaging (RBE3)")
    # the solid twist test ties both faces alike: a mixed part is refused in one line
    model.write_text(tube.TUBE.replace('fe = "solid"\n', 'fe = "solid"\ninterface = {end = "average"}\n'))
    assert main(["sections", str(model), "--compare-solid"]) == 2
    err = capsys.readouterr().err
    assert "interface" in err and "alike" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("interface", [{"end": "average"}, {"start": "average"}])
def test_a_mixed_tie_twist_test_is_the_bodys_end_matrix(mesh, interface):
    # one face of each kind: the end's stiffness solved directly (a rigid clamp leaves the unknowns,
    # an averaging one is held by its multipliers) against the body's condensation on the same mesh
    body = solid_cb(mesh, STEEL, dofs="full", modes=0, residual=False, interface=interface)
    end = body.K[6:12, 6:12]
    twist = part_stiffness(solid_part_model(mesh, STEEL, interface=interface))
    np.testing.assert_allclose(end, twist.stiffness, rtol=1e-7, atol=1e-7 * np.abs(twist.stiffness).max())
    assert twist.torsion == pytest.approx(GJ_L, rel=0.005)  # Saint-Venant's, the 0.5 %
