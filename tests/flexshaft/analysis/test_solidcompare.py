"""The 1D model against the solid: a diameter step's extra torsional flexibility against the published
correction, a uniform tube where the two agree, the write-back, the document.

The published correction. E. J. Nestorides (ed.), *A Handbook on Torsional Vibration*, British Internal
Combustion Engine Research Association (B.I.C.E.R.A.), Cambridge University Press, 1958: a change of
section from a shaft of diameter d to one of diameter D adds the flexibility of an extra length ΔL of
the smaller shaft, charted as ΔL/d against D/d for fillet radii r/(d/2). The values used here are
those of that chart's cubic fit in the RotorDin rotordynamics code (Fortran, ``tsecdl.f``, function
``tsecdlf``, "equivalent length of stepped shafts with abrupt change in cross section", citing
Nestorides; the fit is held at D/d = 3 beyond): for a sharp corner (r = 0)

    ΔL/d = 0.021020194·q³ − 0.183161384·q² + 0.534644181·q − 0.374011947,   q = D/d <= 3,

which is −0.0015 (nil) at q = 1. For the issue's steel shaft, 250 mm at D = 200 mm then 250 mm at
d = 120 mm, q = 5/3: ΔL/d = 0.1056, ΔL = 12.67 mm. (The handbook's page itself was not at hand: the
chart is known here through that fit only.)

Why the solid and the 1D model differ by the step's alone: a uniform circular shaft twisted by rigid end
faces is Saint-Venant's exact solution (sections turn rigidly), so neither end adds or removes anything;
a conforming finite-element model is stiffer than the solid it meshes, so the solid's ΔL converges to
the true one from below.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from flexshaft.analysis.solidcompare import APPORTION_RULE, KINDS, compare_solid, cone_compliance
from flexshaft.elements.materials import STEEL
from flexshaft.errors import ModelError
from flexshaft.sections import table_from_segments
from tests.conftest import gmsh_loads

pytestmark = pytest.mark.skipif(
    not gmsh_loads(), reason="gmsh does not import: pip install 'flexshaft[solid]' and its system libraries"
)

D, d, L1, L2 = 0.2, 0.12, 0.25, 0.25  # m: the stepped shaft
STEP = [{"length": L1, "od": D}, {"length": L2, "od": d}]
OD, ID, L = 0.2, 0.08, 0.5  # m: the tube
TUBE = [{"length": L, "od": OD, "id": ID}]
G = STEEL.G
J_SMALL = math.pi * d**4 / 32


def nestorides(q: float) -> float:
    """ΔL/d of a sharp-cornered step, D/d = q (module docstring: the handbook's chart as fitted)."""
    q = min(q, 3.0)
    return 0.021020194 * q**3 - 0.183161384 * q**2 + 0.534644181 * q - 0.374011947


PUBLISHED = nestorides(D / d) * d  # m: 12.67 mm


def _compare(segments, size, refine=0.25, **options):
    from geometry.meshing import mesh_solid
    from geometry.parts.primitives import stepped_shaft

    mesh = mesh_solid(stepped_shaft(segments), name="part", size=size, refine=refine)
    return compare_solid(table_from_segments(segments, name="part"), mesh, STEEL, **options)


@pytest.fixture(scope="module")
def step():
    # 2 elements across the larger shaft, 0.018 m at the step's corner: ~1 s
    return _compare(STEP, 0.12, refine=0.15, modes=0)


@pytest.fixture(scope="module")
def tube():
    # averaging (RBE3) end faces: free to contract and to warp, so axial and bending meet beam theory
    return _compare(TUBE, 0.04, interface="average", modes=4)


def test_the_published_fit_is_the_one_cited():
    # the fit's transcription: nothing without a step, and the value the docstring states
    assert abs(nestorides(1.0)) < 2e-3
    assert PUBLISHED == pytest.approx(0.012672, abs=1e-6)


def test_the_step_is_softer_by_about_the_published_correction(step):
    (s,) = step.steps
    assert s.x == pytest.approx(L1) and (s.d_small, s.d_large) == pytest.approx((d, D))
    assert step.torsion.ratio < 1.0 and step.compliance_excess > 0.0
    # the 1D number is the series formula, and the solid's extra compliance is the one step's
    series = L1 / (G * math.pi * D**4 / 32) + L2 / (G * J_SMALL)
    assert step.torsion.one_d == pytest.approx(1.0 / series, rel=1e-10)
    assert s.extra_length == pytest.approx(step.compliance_excess * G * J_SMALL, rel=1e-12)
    # A conforming mesh is stiffer than the solid: its ΔL lies below the true one, which the slow test
    # below bounds within 10 % of the handbook's. The shortfall is the corner's mesh error: 12 % of the
    # handbook's ΔL at this mesh's 0.018 m there (7 % at 0.01 m, 5 % at 0.006 m: the slow test's
    # meshes), so 20 % below holds it.
    assert 0.8 * PUBLISHED < s.extra_length <= 1.1 * PUBLISHED


@pytest.mark.slow
def test_the_converged_step_is_softer_by_the_published_correction():
    # two meshes, the second every size 0.6 of the first (the corner's 0.01 and 0.006 m); ~20 s
    coarse, fine = (_compare(STEP, h, refine=0.1, modes=0).steps[0].extra_length for h in (0.1, 0.06))
    # conforming meshes: each ΔL is below the true one, so the finer is a lower bound on it
    assert coarse < fine
    assert fine >= 0.9 * PUBLISHED
    # the rest of the way: the corner's singular field (r^(2/3)) converges the energy at least as
    # (size)^(4/3) on a mesh graded towards it; the remaining error after a refinement by 0.6 is then
    # at most 0.6^p / (1 − 0.6^p) <= 2 times the last change for any rate p >= 0.8
    assert fine + 2.0 * (fine - coarse) <= 1.1 * PUBLISHED


def test_the_write_back_has_the_solids_torsion_and_the_tables_inertia(step):
    corrected = step.corrected_table()
    table = step.table
    assert corrected.torsional_stiffness(G) == pytest.approx(step.torsion.solid, rel=1e-12)
    # only the smaller section's torsion constant moves; the geometry, so the inertia, stays
    np.testing.assert_array_equal(corrected.x, table.x)
    for name in ("area", "ip", "iy", "iz", "shear_area_y", "shear_area_z"):
        np.testing.assert_array_equal(getattr(corrected, name), getattr(table, name))
    assert corrected.j[0] == table.j[0] and corrected.j[1] < table.j[1]
    assert corrected.axial_inertia(STEEL.rho) == table.axial_inertia(STEEL.rho)
    # the smaller interval twists as if it were ΔL longer
    assert L2 / corrected.j[1] == pytest.approx((L2 + step.steps[0].extra_length) / table.j[1], rel=1e-12)
    assert "torsion_corrected" in corrected.meta
    # a table cut finer (a sliced part's): its stations stay, each piece of the smaller section alike
    split = replace(step, table=table.split_at([0.1, 0.3, 0.4])).corrected_table()
    np.testing.assert_array_equal(split.x, [0.0, 0.1, L1, 0.3, 0.4, L1 + L2])
    np.testing.assert_allclose(split.j, corrected.j[[0, 0, 1, 1, 1]], rtol=1e-12)


def test_several_steps_share_by_the_45_degree_rule():
    # a shaft stepping twice, 0.2 -> 0.16 -> 0.12 m (a coarse mesh: the sharing, not the size, is tested)
    segments = [{"length": 0.2, "od": 0.2}, {"length": 0.2, "od": 0.16}, {"length": 0.2, "od": 0.12}]
    c = _compare(segments, 0.15, modes=0)
    first, second = c.steps
    cones = [cone_compliance((r_s, 0.0), (r_l, 0.0), G) for r_s, r_l in ((0.08, 0.1), (0.06, 0.08))]
    assert first.weight == pytest.approx(cones[0] / sum(cones), rel=1e-9)
    assert first.compliance + second.compliance == pytest.approx(c.compliance_excess, rel=1e-12)
    assert (first.small, second.small) == (1, 2) and first.extra_length > 0 and second.extra_length > 0
    corrected = c.corrected_table()
    assert corrected.torsional_stiffness(G) == pytest.approx(c.torsion.solid, rel=1e-12)
    assert APPORTION_RULE in c.text()


def test_the_45_degree_cone_of_a_solid_shaft_is_its_closed_form():
    a, b = 0.06, 0.1
    closed = (2 / (math.pi * G)) * ((a**-3 - b**-3) / 3 - (b - a) / b**4)
    assert cone_compliance((a, 0.0), (b, 0.0), G) == pytest.approx(closed, rel=1e-12)
    assert cone_compliance((a, 0.02), (a, 0.02), G) == 0.0


def test_a_uniform_tube_compares_one_to_one(tube):
    assert tube.steps == ()
    # Stiffness, the mesh's error alone (a conforming mesh: from above, 1.3e-4 in torsion at this size,
    # test_part_stiffness): torsion is Saint-Venant's; axially the averaging faces contract freely
    # (uniform uniaxial stress, E·A/L); in bending Cowper's shear coefficient is the one that makes the
    # Timoshenko beam's tip deflection the elasticity solution's, whose end tractions the averaging
    # faces meet up to a self-equilibrated part (Saint-Venant: felt within about a diameter of the ends)
    for pair, tol in ((tube.torsion, 5e-4), (tube.axial, 5e-4), *((b, 2e-3) for b in tube.bending)):
        assert 1.0 - 1e-9 <= pair.ratio <= 1.0 + tol, pair
    assert abs(tube.compliance_excess) * tube.torsion.one_d < 5e-4


def test_a_uniform_tubes_modes_pair_by_kind(tube):
    kinds = [m.kind for m in tube.modes]
    assert kinds == ["lateral", "lateral", "torsion", "axial"] and set(kinds) <= set(KINDS)
    assert all(m.share > 0.9 for m in tube.modes)
    by = {m.kind: m for m in tube.modes}
    # torsion waves in a circular bar do not disperse: the 1D model is exact, the mesh's error alone
    assert by["torsion"].ratio == pytest.approx(1.0, abs=1e-3)
    # bending: Timoshenko's beam against the solid, the 1 % (as test_solid_part_modes)
    for m in tube.modes[:2]:
        assert m.ratio == pytest.approx(1.0, abs=0.01)
    # axially the rod has no lateral inertia; Rayleigh's (Love's) correction for it lowers the first
    # free-free mode by ½ν²(k·r_g)², k = π/L, r_g² = (OD² + ID²)/8 (Love, Theory of Elasticity, §278);
    # its next order is that times (k·r_outer)² ~ 0.4, so 4e-3
    love = 1 - 0.5 * STEEL.nu**2 * (math.pi / L) ** 2 * (OD**2 + ID**2) / 8
    assert by["axial"].ratio == pytest.approx(love, abs=4e-3)


def test_a_uniform_tubes_write_back_scales_j_alike(tube):
    corrected = tube.corrected_table()
    assert corrected.torsional_stiffness(G) == pytest.approx(tube.torsion.solid, rel=1e-12)
    assert corrected.ip[0] == tube.table.ip[0]


def test_the_document_states_its_units(step, tube):
    for c in (step, tube):
        doc = json.loads(json.dumps(c.to_dict(), allow_nan=False))
        assert set(doc["stiffness"]) == {"torsion", "axial", "bending_y", "bending_z"}
        assert doc["units"]["torsion"] == "N·m/rad" and doc["units"]["bending_y"] == "N/m"
        assert doc["units"]["frequency"] == "Hz" and doc["units"]["extra_length"] == "m"
        assert doc["units"]["compliance_excess"] == "rad/(N·m)"
        assert doc["stiffness"]["torsion"]["ratio"] == pytest.approx(c.torsion.ratio)
    (s,) = step.to_dict()["steps"]
    assert s["extra_length"] == pytest.approx(step.steps[0].extra_length) and s["x"] == pytest.approx(L1)
    assert [m["kind"] for m in tube.to_dict()["modes"]] == [m.kind for m in tube.modes]
    assert "torsion" in step.text() and "ΔL/d" in step.text()


def test_bad_input_is_refused():
    from geometry.meshing import mesh_solid
    from geometry.parts.primitives import stepped_shaft

    mesh = mesh_solid(stepped_shaft(TUBE), name="tube", size=0.1)
    table = table_from_segments(TUBE)
    with pytest.raises(ModelError, match="not as long"):
        compare_solid(table_from_segments([{"length": 0.4, "od": 0.2}]), mesh, STEEL)
    with pytest.raises(ModelError, match="out of range"):
        compare_solid(table, mesh, STEEL, modes=-1)
    with pytest.raises(ModelError, match="unknown interface"):
        compare_solid(table, mesh, STEEL, interface="glued")
    with pytest.raises(ModelError, match="not a solid mesh"):
        compare_solid(table, table, STEEL)
