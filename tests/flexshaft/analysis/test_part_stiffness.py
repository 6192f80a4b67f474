"""The twist test of a solid part (its end stiffness) against closed forms: a tube's G·J/L, its axial
stiffness between the bounds energy gives, and the rate at which the curved 10-node tetrahedra converge.

References: Saint-Venant torsion of a circular tube - sections turn rigidly, without warping, so rigid
end faces (RBE2) impose nothing the exact solution does not do and the stiffness is G·J/L; a
conforming displacement model is stiffer than the solid, so it converges from above. Axially, the
rigid ends hold the faces' Poisson contraction: the tie only removes admissible motions, so the
stiffness lies above E·A/L (free contraction), and the uniform uniaxial strain (no contraction at all,
in the P2 space and admissible) bounds it by M·A/L, M = E(1 − ν)/((1 + ν)(1 − 2ν)) the constrained
modulus.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexshaft.analysis.twist import END_DOFS, part_stiffness
from flexshaft.elements.materials import STEEL
from flexshaft.errors import ModelError
from flexshaft.parts.solidpart import solid_part_model
from tests.conftest import gmsh_loads

pytestmark = pytest.mark.skipif(
    not gmsh_loads(), reason="gmsh does not import: pip install 'flexshaft[solid]' and its system libraries"
)

OD, ID, L = 0.2, 0.08, 0.5  # m: the tube
G = STEEL.E / (2 * (1 + STEEL.nu))
GJ_L = G * math.pi / 32 * (OD**4 - ID**4) / L
A = math.pi / 4 * (OD**2 - ID**2)


def _stiffness(mesh, material, *, interface="rigid", **how):
    """The one twist test of a part (:func:`part_stiffness`) on the solid part model of ``mesh``."""
    return part_stiffness(solid_part_model(mesh, material, interface=interface), **how)


def _tube(size):
    from build123d import Axis, Cylinder

    from geometry.meshing import mesh_solid

    solid = (Cylinder(1000 * OD / 2, 1000 * L) - Cylinder(1000 * ID / 2, 1000 * L)).rotate(Axis.Y, 90)
    return mesh_solid(solid, name="tube", size=size)


@pytest.fixture(scope="module")
def coarse():
    return _stiffness(_tube(0.04), STEEL)


def test_a_tube_twists_as_saint_venant_says(coarse):
    # from above (a conforming model is stiffer), within the 0.5 % at two elements across the
    # wall (1.3e-4 measured: curved quadratic elements, the energy error ~h⁴)
    assert GJ_L <= coarse.torsion <= 1.005 * GJ_L
    assert coarse.solver.method == "SuperLU" and coarse.interface.startswith("rigid (RBE2)")


def test_the_axial_stiffness_lies_between_its_energy_bounds(coarse):
    nu = STEEL.nu
    constrained = STEEL.E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    assert STEEL.E * A / L < coarse.axial < constrained * A / L
    # and the end matrix is the compliance's inverse, symmetric, in END_DOFS order
    np.testing.assert_allclose(coarse.stiffness @ coarse.compliance, np.eye(6), atol=1e-8)
    assert coarse.to_dict()["end_dofs"] == list(END_DOFS)


@pytest.fixture(scope="module")
def averaged():
    mesh = _tube(0.04)
    return mesh, _stiffness(mesh, STEEL, interface="average")


def test_averaging_ends_pull_the_tube_exactly_and_twist_it_softer_than_rigid_ends(averaged, coarse):
    from flexshaft.parts.solidties import averaging_interface

    mesh, avg = averaged
    assert avg.interface.startswith("averaging (RBE3)")
    # free to contract, the tube pulls as E·A/L up to its meshed section's departure from the circle
    # (8 curved elements a circle: ~1e-4 of the area; 2.5e-5 measured) and stays below rigid ends'
    area = averaging_interface(mesh, "end").area
    assert avg.axial == pytest.approx(STEEL.E * area / L, rel=5e-4) and avg.axial < coarse.axial
    # torsion: rigid faces are a constraint more than averaging ones, so at least as stiff (same mesh);
    # both within the 0.5 % of G·J/L
    assert avg.torsion <= coarse.torsion * (1 + 1e-9)
    assert avg.torsion == pytest.approx(GJ_L, rel=0.005)


def test_averaging_ends_pull_a_prism_exactly():
    # a box bar (flat faces: every section the same): a force on an averaging master reaches the end
    # face as a uniform traction and the clamp holds only the face's mean motion, so the solution is
    # uniform uniaxial stress - a linear displacement field, in the element's space: E·A/L to the
    # solver's round-off, and the lateral force's stiffness is the same in y and z (square section)
    from flexshaft.elements.tetmesh import TetMesh
    from tests.flexshaft.elements.test_tet10 import box_mesh, tri6_faces_on

    nodes, tets = box_mesh(np.array((6, 2, 2)), (0.6, 0.1, 0.1))
    faces = {"start": tri6_faces_on(nodes, tets, 0, 0.0), "end": tri6_faces_on(nodes, tets, 0, 0.6)}
    bar = _stiffness(TetMesh("bar", nodes, tets, faces=faces), STEEL, interface="average")
    assert bar.axial == pytest.approx(STEEL.E * 0.01 / 0.6, rel=1e-9)
    assert bar.bending[0] == pytest.approx(bar.bending[1], rel=1e-9)


def test_an_unknown_interface_is_refused():
    with pytest.raises(ModelError, match="unknown interface"):
        _stiffness(_tube(0.08), STEEL, interface="glued")


@pytest.mark.slow
def test_the_torsional_stiffness_converges_at_the_elements_rate():
    # halving the element size: the stiffness error (an energy error of quadratic elements, h⁴ for a
    # smooth solution) falls by ~16; a rate above 3 allows for the mesher's sizes not halving exactly
    errors = [_stiffness(_tube(h), STEEL).torsion / GJ_L - 1 for h in (0.04, 0.02)]
    assert all(e > 0 for e in errors)
    assert math.log2(errors[0] / errors[1]) > 3


def test_the_clamped_end_is_not_the_loaded_one():
    with pytest.raises(ModelError, match="loaded end"):
        _stiffness(_tube(0.08), STEEL, clamp="end", load="end")
