"""The solid twist test against closed forms: a tube's G·J/L, its axial stiffness between the bounds
energy gives, and the rate at which the curved 10-node tetrahedra converge.

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

from flexshaft.analysis.solidstiffness import END_DOFS, solid_stiffness
from flexshaft.errors import ModelError
from flexshaft.materials import STEEL

pytest.importorskip("gmsh", reason="the solid extra (pip install 'flexshaft[solid]') meshes parts")

OD, ID, L = 0.2, 0.08, 0.5  # m: the tube
G = STEEL.E / (2 * (1 + STEEL.nu))
GJ_L = G * math.pi / 32 * (OD**4 - ID**4) / L
A = math.pi / 4 * (OD**2 - ID**2)


def _tube(size):
    from build123d import Axis, Cylinder

    from geometry.tetmesh import mesh_solid

    solid = (Cylinder(1000 * OD / 2, 1000 * L) - Cylinder(1000 * ID / 2, 1000 * L)).rotate(Axis.Y, 90)
    return mesh_solid(solid, name="tube", size=size)


@pytest.fixture(scope="module")
def coarse():
    return solid_stiffness(_tube(0.04), STEEL)


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


@pytest.mark.slow
def test_the_torsional_stiffness_converges_at_the_elements_rate():
    # halving the element size: the stiffness error (an energy error of quadratic elements, h⁴ for a
    # smooth solution) falls by ~16; a rate above 3 allows for the mesher's sizes not halving exactly
    errors = [solid_stiffness(_tube(h), STEEL).torsion / GJ_L - 1 for h in (0.04, 0.02)]
    assert all(e > 0 for e in errors)
    assert math.log2(errors[0] / errors[1]) > 3


def test_the_clamped_end_is_not_the_loaded_one():
    with pytest.raises(ModelError, match="loaded end"):
        solid_stiffness(_tube(0.08), STEEL, clamp="end", load="end")
