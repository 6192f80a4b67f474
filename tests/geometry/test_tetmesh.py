"""A part's solid meshed into curved 10-node tetrahedra (geometry.meshing).

The references are geometry the tests compute themselves: a cylinder's radius, a chord's sagitta, the
area between a circular arc and the parabola through its ends and midpoint, the volume of an annulus,
the midpoint of a straight edge. The element node order is read off VTK's definition (each mid-side
node is the midpoint of its corner pair on a straight-sided mesh), not taken from the module.
"""

from __future__ import annotations

import math
import os
import signal
import sys

import numpy as np
import pytest

bd = pytest.importorskip("build123d")

from flexshaft.elements.tetmesh import TET10_EDGES, TRI6_EDGES  # noqa: E402
from flexshaft.errors import ModelError  # noqa: E402
from geometry import parts  # noqa: E402
from geometry.meshing import EXTRA, SYSTEM_LIBRARIES, jacobian_dets, mesh_solid  # noqa: E402
from tests.conftest import gmsh_loads  # noqa: E402

needs_gmsh = pytest.mark.skipif(
    not gmsh_loads(), reason=f"solid meshing needs gmsh: {EXTRA}; its system libraries: {SYSTEM_LIBRARIES}"
)

# The tube of the brief: OD 200 mm, ID 80 mm, 500 mm long (m).
R, RI, L = 0.1, 0.04, 0.5
# Coordinates come from OCCT evaluating a cylinder or plane (round-off ~1e-16 relative), a BREP file
# written with 17 digits and one mm -> m division: 1e-9 relative leaves six orders of headroom and
# is still seven below a sagitta at these sizes (~1e-2 relative).
ON_GEOMETRY = 1e-9
# The faces of a VTK tetrahedron (corners, then the mid-side nodes of its three edges in TRI6 order).
TET_FACES = ((0, 1, 2, 4, 5, 6), (0, 3, 1, 7, 8, 4), (1, 3, 2, 8, 9, 5), (0, 2, 3, 6, 9, 7))


def tube_part():
    return parts.stepped_shaft([parts.Segment(L, 2 * R, 2 * RI)])


@pytest.fixture(scope="module")
def tube():
    return mesh_solid(tube_part(), name="tube", size=0.03)


def boundary_triangles(tets: np.ndarray) -> np.ndarray:
    """(k, 6): the tetrahedra's faces that belong to one element only (corners, then mid-side nodes)."""
    faces = np.concatenate([tets[:, list(f)] for f in TET_FACES])
    key = np.sort(faces[:, :3], axis=1)
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[first[count == 1]]


def radius(p: np.ndarray) -> np.ndarray:
    return np.hypot(p[..., 1], p[..., 2])


def corner_volume(nodes, tets) -> np.ndarray:
    c = nodes[tets[:, :4]]
    return np.einsum("ij,ij->i", c[:, 1] - c[:, 0], np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0])) / 6.0


def edge_lengths(nodes, tets) -> np.ndarray:
    """Each element's mean corner-to-corner edge length, m."""
    c = nodes[tets[:, :4]]
    return np.mean([np.linalg.norm(c[:, a] - c[:, b], axis=1) for a, b in TET10_EDGES], axis=0)


# --- independent quadratic shape functions (the references of the curved volume and area) -----------

# The degree-3 rule on the tetrahedron (Keast; Zienkiewicz & Taylor, The Finite Element Method, vol. 1,
# table 5.4): the centroid with weight -4/5 and the points (1/2, 1/6, 1/6, 1/6) with 9/20, on the
# unit volume. A curved 10-node element's det J is a cubic, so it integrates the volume exactly.
KEAST = [(np.full(4, 0.25), -0.8)] + [(np.where(np.arange(4) == k, 0.5, 1.0 / 6.0), 0.45) for k in range(4)]


def p2_gradients(lam: np.ndarray, corners: int) -> np.ndarray:
    """Gradients of the quadratic Lagrange functions (VTK order) at barycentrics ``lam``, w.r.t. the
    reference coordinates (the last ``corners - 1`` barycentrics)."""
    d = np.vstack([-np.ones(corners - 1), np.eye(corners - 1)])
    edges = TET10_EDGES if corners == 4 else TRI6_EDGES
    g = [(4.0 * lam[i] - 1.0) * d[i] for i in range(corners)]
    g += [4.0 * (lam[a] * d[b] + lam[b] * d[a]) for a, b in edges]
    return np.array(g)


def curved_volume(nodes, tets) -> float:
    x = nodes[tets]
    total = 0.0
    for lam, w in KEAST:
        total += w * np.linalg.det(np.einsum("mki,kj->mij", x, p2_gradients(lam, 4))).sum()
    return total / 6.0


def curved_area_yz(nodes, tri) -> float:
    """The signed area in the (y, z) plane of 6-node triangles (normal +x positive): det J is
    quadratic, so the edge-midpoint rule (weights 1/3 of the unit triangle's 1/2) is exact."""
    y = nodes[tri][:, :, 1:]
    total = 0.0
    for lam in ([0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]):
        total += np.linalg.det(np.einsum("mki,kj->mij", y, p2_gradients(np.array(lam), 3))).sum() / 6.0
    return total


def arc_defect(rad, half_angle):
    """Area between a circular arc of half-angle a and the parabola through its ends and midpoint
    (the quadratic interpolant, parameter t from -1 to 1): the parabola (cos a + (1 - cos a)(1 - t²),
    t sin a)·R encloses R² sin a (1 + (1 - cos a)/3) with the centre against the sector's R² a, and
    lies inside the circle (|p|² - R² = -R²(1 - cos a)² t² (1 - t²) <= 0)."""
    a = half_angle
    return rad**2 * (a - np.sin(a) * (1.0 + (1.0 - np.cos(a)) / 3.0))


# --- the tube --------------------------------------------------------------------------------------------


@needs_gmsh
def test_tube_is_in_metres_in_the_section_tables_frame(tube):
    from geometry.slicing import sections

    x = tube.nodes
    assert x[:, 0].min() == pytest.approx(0.0, abs=ON_GEOMETRY * L)
    assert x[:, 0].max() == pytest.approx(L, rel=ON_GEOMETRY)
    assert radius(x).max() == pytest.approx(R, rel=ON_GEOMETRY)
    assert radius(x).min() == pytest.approx(RI, rel=ON_GEOMETRY)
    table = sections(tube_part(), name="tube")
    assert table.x[0] == pytest.approx(x[:, 0].min(), abs=ON_GEOMETRY * L)
    assert table.x[-1] == pytest.approx(x[:, 0].max(), rel=ON_GEOMETRY)
    assert tube.name == "tube" and tube.size == 0.03 and "build123d" in tube.source


@needs_gmsh
def test_a_part_placed_anywhere_is_meshed_in_its_own_frame():
    # The tube turned about two axes and moved: its mesh is the same tube along x from 0.
    turned = bd.Pos(40.0, -70.0, 15.0) * bd.Rot(0.0, -48.19, 63.43) * tube_part()
    mesh = mesh_solid(turned, name="turned", size=0.05)
    x = mesh.nodes
    assert x[:, 0].min() == pytest.approx(0.0, abs=1e-9 * L)
    assert x[:, 0].max() == pytest.approx(L, rel=1e-9)
    assert radius(x).max() == pytest.approx(R, rel=1e-9)
    assert radius(x).min() == pytest.approx(RI, rel=1e-9)


@needs_gmsh
def test_every_mid_side_node_on_the_cylinders_lies_on_them(tube):
    x = tube.nodes
    tri = boundary_triangles(tube.tets)
    checked = 0
    for rad in (R, RI):
        on = np.all(np.abs(radius(x[tri[:, :3]]) / rad - 1.0) < ON_GEOMETRY, axis=1)
        mids = tri[on][:, 3:]
        assert np.all(np.abs(radius(x[mids]) / rad - 1.0) < ON_GEOMETRY)
        # A straight-sided element would put them at the chord's midpoint, inside by the sagitta
        # R (1 - cos(Δφ/2)) of the angle Δφ between the corners: exactly that, and far from 1e-9.
        for a, b in TRI6_EDGES:
            pa, pb = x[tri[on][:, a]], x[tri[on][:, b]]
            dphi = np.angle(np.exp(1j * (np.arctan2(pb[:, 2], pb[:, 1]) - np.arctan2(pa[:, 2], pa[:, 1]))))
            chord_mid = radius(0.5 * (pa + pb))
            assert np.allclose(chord_mid, rad * np.cos(dphi / 2.0), rtol=ON_GEOMETRY, atol=0.0)
            assert np.max(1.0 - chord_mid / rad) > 1e-3  # what "curved" takes away: > 1e6 x the above
        checked += mids.size
    # every boundary triangle is on a cylinder or an end plane
    ends = np.all(np.isclose(x[tri[:, :3], 0], 0.0, atol=1e-12) | np.isclose(x[tri[:, :3], 0], L), axis=1)
    assert checked + 3 * ends.sum() == tri[:, 3:].size


@needs_gmsh
def test_end_faces_cover_the_annulus(tube):
    x = tube.nodes
    exact = math.pi * (R**2 - RI**2)
    for key, at, outward in (("start", 0.0, -1.0), ("end", L, 1.0)):
        tri = tube.faces[key]
        assert np.allclose(x[tri, 0], at, rtol=0.0, atol=ON_GEOMETRY * L)  # planar, at the end
        # outward normals
        p = x[tri[:, :3]]
        assert np.all(outward * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 0] > 0.0)
        # The boundary edges of the face set: on the two circles only, so it covers the annulus.
        edges = np.sort(np.concatenate([tri[:, [a, b]] for a, b in TRI6_EDGES]), axis=1)
        unique, count = np.unique(edges, axis=0, return_counts=True)
        rim = unique[count == 1]
        r_rim = radius(x[rim])
        outer = np.all(np.isclose(r_rim, R, rtol=ON_GEOMETRY), axis=1)
        inner = np.all(np.isclose(r_rim, RI, rtol=ON_GEOMETRY), axis=1)
        assert np.all(outer | inner) and outer.any() and inner.any()
        # The 6-node triangles' area is the annulus less the area between each outer arc and its
        # parabola, plus that of each inner one (the hole shrinks); the corner triangles' area the
        # same with the chords' segments R² (a - sin a cos a). Both exact up to round-off.
        phi = np.arctan2(x[rim][:, :, 2], x[rim][:, :, 1])
        half = 0.5 * np.abs(np.angle(np.exp(1j * (phi[:, 1] - phi[:, 0]))))
        curved = arc_defect(R, half[outer]).sum(), arc_defect(RI, half[inner]).sum()
        assert outward * curved_area_yz(x, tri) == pytest.approx(exact - curved[0] + curved[1], rel=1e-12)
        segment = [rad**2 * (a - np.sin(a) * np.cos(a)) for rad, a in ((R, half[outer]), (RI, half[inner]))]
        flat = outward * 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 0].sum()
        assert flat == pytest.approx(exact - segment[0].sum() + segment[1].sum(), rel=1e-12)
        # A segment is 2R²a³/3 to leading order, the arc's defect R²a⁵/30: curved elements leave
        # a²/20 of the flat ones' error, < 2 % with a < 0.6 (8 and more elements per circle).
        assert half.max() < 0.6
        assert curved[0] < 0.02 * segment[0].sum() and curved[1] < 0.02 * segment[1].sum()


@needs_gmsh
def test_corner_volume_converges_and_the_curved_volume_is_closer():
    exact = math.pi * (R**2 - RI**2) * L
    errors = []
    for size in (0.04, 0.02):
        # curvature left out: the angle per element then follows the size
        mesh = mesh_solid(tube_part(), name="tube", size=size, curvature_elements=0)
        x, tets = mesh.nodes, mesh.tets
        tri = boundary_triangles(tets)
        # A flat triangle with its corners on a cylinder lies between it and the circle through its
        # chord of largest angle Δφ: at most the sagitta s = ρ (1 - cos(Δφ/2)) inside it. So the
        # corner tetrahedra lose at most 2πRL·s_outer at the outer cylinder and gain at most
        # 2πrL·s_inner at the bore.
        bound = {}
        for rad in (R, RI):
            on = tri[np.all(np.isclose(radius(x[tri[:, :3]]), rad, rtol=ON_GEOMETRY), axis=1)][:, :3]
            phi = np.arctan2(x[on][:, :, 2], x[on][:, :, 1])
            dphi = np.max(
                [np.abs(np.angle(np.exp(1j * (phi[:, a] - phi[:, b])))) for a, b in TRI6_EDGES], axis=0
            )
            bound[rad] = 2 * math.pi * rad * L * rad * (1.0 - np.cos(dphi.max() / 2.0))
        linear = corner_volume(x, tets).sum()
        assert -bound[R] <= linear - exact <= bound[RI]
        # The curved elements follow the cylinders to O(angle⁴) where the corners do to O(angle²):
        # a factor (Δφ/2)²/8 < 1e-2 at these sizes.
        assert abs(curved_volume(x, tets) - exact) < 0.1 * max(bound.values())
        errors.append(max(bound.values()))
    # second order in the size: halving it quarters the sagitta (to within the mesh's irregularity)
    assert errors[1] < errors[0] / 2.5


@needs_gmsh
def test_a_convex_solids_corner_volume_is_below_its_volume():
    # Every tetrahedron is the convex hull of points of the convex solid: the sum is below its volume.
    mesh = mesh_solid(parts.stepped_shaft([parts.Segment(L, 2 * R)]), name="rod", size=0.04)
    exact = math.pi * R**2 * L
    assert corner_volume(mesh.nodes, mesh.tets).sum() < exact
    assert curved_volume(mesh.nodes, mesh.tets) == pytest.approx(exact, rel=1e-3)


# --- node order, on straight-sided elements ---------------------------------------------------------


@needs_gmsh
def test_mid_side_nodes_are_the_midpoints_of_their_vtk_edges_on_a_box():
    box = bd.Box(300.0, 100.0, 80.0, align=(bd.Align.MIN, bd.Align.CENTER, bd.Align.CENTER))
    mesh = mesh_solid(box, name="box", axis=((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)), size=0.03)
    x, tets = mesh.nodes, mesh.tets
    exact = 0.3  # the largest coordinate, m: midpoints are exact to its round-off
    for k, (a, b) in enumerate(TET10_EDGES):
        assert np.abs(x[tets[:, 4 + k]] - 0.5 * (x[tets[:, a]] + x[tets[:, b]])).max() < 1e-14 * exact
    for key, at in (("start", 0.0), ("end", 0.3)):
        tri = mesh.faces[key]
        assert np.allclose(x[tri, 0], at, atol=1e-14 * exact, rtol=0.0)
        for k, (a, b) in enumerate(TRI6_EDGES):
            assert np.abs(x[tri[:, 3 + k]] - 0.5 * (x[tri[:, a]] + x[tri[:, b]])).max() < 1e-14 * exact
        # the end face's area: the box's section, 100 mm x 80 mm
        assert abs(curved_area_yz(x, tri)) == pytest.approx(0.1 * 0.08, rel=1e-12)
    # straight-sided: det J is 6 x the corner volume everywhere, and every element is positive
    v6 = 6.0 * corner_volume(x, tets)
    assert np.all(v6 > 0.0)
    assert np.allclose(jacobian_dets(x, tets), v6[:, None], rtol=1e-9, atol=0.0)
    assert corner_volume(x, tets).sum() == pytest.approx(0.3 * 0.1 * 0.08, rel=1e-12)


@needs_gmsh
def test_elements_handed_over_inside_out_are_turned(monkeypatch):
    # gmsh's elements come positively oriented with outward triangles; should a version hand them over
    # otherwise, the conversion turns them: here every other one is given inside out (corners 1 and 2
    # swapped, their mid-side nodes with them: gmsh's edges 0-1 <-> 0-2 and 2-3 <-> 1-3).
    import gmsh

    by_type = gmsh.model.mesh.getElementsByType
    turned = {11: [0, 2, 1, 3, 6, 5, 4, 7, 9, 8], 9: [0, 2, 1, 5, 4, 3]}

    def inside_out(element_type, tag=-1, task=0, num_tasks=1):
        tags, nodes = by_type(element_type, tag, task, num_tasks)
        if element_type in turned:
            n = len(turned[element_type])
            nodes = nodes.reshape(-1, n).copy()
            nodes[::2] = nodes[::2][:, turned[element_type]]
            nodes = nodes.ravel()
        return tags, nodes

    monkeypatch.setattr(gmsh.model.mesh, "getElementsByType", inside_out)
    box = bd.Box(300.0, 100.0, 80.0, align=(bd.Align.MIN, bd.Align.CENTER, bd.Align.CENTER))
    mesh = mesh_solid(box, name="box", axis=((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)), size=0.05)
    x, tets = mesh.nodes, mesh.tets
    assert np.all(corner_volume(x, tets) > 0.0)
    for k, (a, b) in enumerate(TET10_EDGES):
        assert np.abs(x[tets[:, 4 + k]] - 0.5 * (x[tets[:, a]] + x[tets[:, b]])).max() < 1e-14 * 0.3
    for key, outward in (("start", -1.0), ("end", 1.0)):
        tri = mesh.faces[key]
        p = x[tri[:, :3]]
        assert np.all(outward * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 0] > 0.0)
        for k, (a, b) in enumerate(TRI6_EDGES):
            assert np.abs(x[tri[:, 3 + k]] - 0.5 * (x[tri[:, a]] + x[tri[:, b]])).max() < 1e-14 * 0.3


def test_jacobian_of_a_bent_element():
    # The unit corner tetrahedron with straight edges: det J = 1 everywhere. Pushing the mid-side node
    # of edge 0-1 by d along y adds d·4 L0 L1 e_y to x(ξ): J = I + 4d e_y ⊗ ∇(L0 L1), whose
    # determinant is 1 + 4d ∂(L0 L1)/∂η = 1 - 4d L1: 1 at corner 0, 1 - 4d at corner 1 (inverted
    # there once d > 1/4), 1 - 2d at the edge's midpoint.
    nodes = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0], [0, 0, 0.5],
         [0.5, 0, 0.5], [0, 0.5, 0.5]],
        float,
    )  # fmt: skip
    tets = np.arange(10)[None, :]
    assert np.allclose(jacobian_dets(nodes, tets), 1.0)
    for d in (0.1, 0.3):
        bent = nodes.copy()
        bent[4, 1] += d
        det = jacobian_dets(bent, tets)[0]
        # the sample points: corners 0-3, then the midpoints of the VTK edges (0-1 first)
        assert det[0] == pytest.approx(1.0) and det[1] == pytest.approx(1.0 - 4.0 * d)
        assert det[4] == pytest.approx(1.0 - 2.0 * d)
    assert det.min() < 0.0


# --- refinement where the section changes -----------------------------------------------------------


def _near(x_c, r_c, nodes, tets) -> np.ndarray:
    """Each element's centroid distance to the circle (x_c, r_c) about the axis, in the (x, r) plane."""
    c = nodes[tets[:, :4]].mean(axis=1)
    return np.hypot(c[:, 0] - x_c, radius(c) - r_c)


@needs_gmsh
def test_a_stepped_shaft_is_refined_at_its_inner_corner():
    shaft = parts.stepped_shaft([parts.Segment(0.2, 0.12), parts.Segment(0.3, 0.4)])
    size = 0.03
    mesh = mesh_solid(shaft, name="stepped", size=size, refine=0.25)
    plain = mesh_solid(shaft, name="stepped", size=size, refine=1.0)
    for m, near_ratio in ((mesh, (0.0, 0.5)), (plain, (0.6, 1.5))):
        h = edge_lengths(m.nodes, m.tets)
        to_corner = _near(0.2, 0.06, m.nodes, m.tets)
        inner = np.median(h[to_corner < 0.01])  # the re-entrant corner
        # the convex corner (its rim), beyond the inner corner's grading (2.25 sizes): not refined
        rim = np.median(h[_near(0.2, 0.2, m.nodes, m.tets) < 0.02])
        far = np.median(h[(to_corner > 4 * size) & (m.nodes[m.tets[:, 0], 0] > 0.3)])
        # gmsh meets the size on the surfaces; inside, its tetrahedra's edges are longer, 1.3 sizes
        # on average (1.1 to 1.6 for 90 % of them, with Delaunay and HXT alike). Elements near the
        # inner corner are asked for a quarter of that (half at most is asserted).
        assert 0.8 * size < far < 1.6 * size
        assert near_ratio[0] * far <= inner <= near_ratio[1] * far
        assert rim > 0.6 * far  # (elements at a surface run smaller than inside: 0.8 here)
    assert mesh.n_elements > plain.n_elements


@needs_gmsh
def test_a_flanged_part_is_refined_at_its_fillet_and_holes():
    hole_d, pitch_d, count = 0.02, 0.22, 6
    flanged = parts.flanged_shaft(
        [parts.Segment(0.04, 0.3), parts.Segment(0.36, 0.12)],
        [parts.BoltCircle(count, hole_d, pitch_d, 0.0, 0.04)],
        fillet=0.01,
    )
    mesh = mesh_solid(flanged, name="flanged")  # the default size and curvature (8 per circle)
    x, tets = mesh.nodes, mesh.tets
    h = edge_lengths(x, tets)
    size = mesh.size
    c = x[tets[:, :4]].mean(axis=1)
    # the bolt holes: their mid-side nodes on the holes' cylinders, and elements of about the
    # circle's 2π·10 mm / 8 = 7.9 mm round them
    angles = 2 * math.pi * np.arange(count) / count
    centres = np.column_stack([-0.5 * pitch_d * np.sin(angles), 0.5 * pitch_d * np.cos(angles)])
    tri = boundary_triangles(tets)
    d = np.linalg.norm(x[tri][:, :, None, 1:] - centres[None, None], axis=3)  # (k, 6, holes)
    on_hole = np.any(np.all(np.abs(d[:, :3] / (0.5 * hole_d) - 1.0) < ON_GEOMETRY, axis=1), axis=1)
    assert on_hole.sum() > count * 8
    mids = d[on_hole][:, 3:].min(axis=2)
    assert np.all(np.abs(mids / (0.5 * hole_d) - 1.0) < ON_GEOMETRY)
    dist = np.linalg.norm(c[:, None, 1:] - centres[None], axis=2).min(axis=1)
    by_hole = np.median(h[(dist < hole_d) & (c[:, 0] < 0.04)])
    far = np.median(h[(c[:, 0] > 0.2)])
    assert by_hole < 0.5 * far and 0.8 * size < far < 1.6 * size
    # the fillet (radius 10 mm, a quarter circle: two elements of 7.9 mm along it)
    d_fillet = _near(0.05, 0.07, x, tets)  # from the fillet's centre: the material is beyond 10 mm
    at_fillet = np.median(h[(d_fillet > 0.01) & (d_fillet < 0.016) & (c[:, 0] < 0.05) & (radius(c) < 0.07)])
    assert at_fillet < 0.6 * far
    # the start face is the flange's: its disc less the holes (the 6-node triangles follow the
    # circles to their arcs' defects, < 1e-3 of the area at 8 per circle)
    disc = math.pi * (0.15**2 - count * (0.5 * hole_d) ** 2)
    assert -curved_area_yz(x, mesh.faces["start"]) == pytest.approx(disc, rel=1e-3)
    assert curved_area_yz(x, mesh.faces["end"]) == pytest.approx(math.pi * 0.06**2, rel=1e-3)


# --- inputs ----------------------------------------------------------------------------------------------


@needs_gmsh
def test_a_step_file_is_meshed_in_the_same_frame(tmp_path):
    from geometry.cadio import write_step

    path = write_step(tube_part(), tmp_path / "tube.step")
    mesh = mesh_solid(path, name="tube", size=0.05)
    assert mesh.nodes[:, 0].min() == pytest.approx(0.0, abs=1e-9)
    assert mesh.nodes[:, 0].max() == pytest.approx(L, rel=1e-9)
    assert radius(mesh.nodes).max() == pytest.approx(R, rel=1e-9)
    assert "STEP file" in mesh.source and "tube.step" in mesh.source


@needs_gmsh
def test_progress_reports_each_stage_in_order(tube):
    seen = []
    mesh_solid(tube_part(), name="tube", size=0.05, progress=lambda stage, f: seen.append((stage, f)))
    stages = [s for s, _ in seen]
    assert stages[:2] == ["reading the part", "finding the axis"] and seen[-1] == ("done", 1.0)
    assert "meshing the volume" in stages and "placing the mid-side nodes on the geometry" in stages
    fractions = [f for _, f in seen if f is not None]
    assert fractions == sorted(fractions) and all(0.0 <= f <= 1.0 for f in fractions)


def test_without_gmsh_the_error_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "gmsh", None)  # import gmsh -> ImportError
    expected = r"^tube: fe = 'solid': .*needs gmsh.*pip install 'flexshaft\[solid\]'"
    with pytest.raises(ModelError, match=expected):
        mesh_solid(tube_part(), name="tube")


def test_a_gmsh_whose_library_does_not_load_names_the_system_libraries(monkeypatch):
    # the gmsh wheel's libgmsh links OpenGL and X11 client libraries; on a minimal image its import
    # fails with an OSError from ctypes (not an ImportError)
    class NoLibrary:
        def find_spec(self, fullname, path=None, target=None):
            if fullname == "gmsh":
                raise OSError("libGLU.so.1: cannot open shared object file: No such file or directory")
            return None

    monkeypatch.delitem(sys.modules, "gmsh", raising=False)
    monkeypatch.setattr(sys, "meta_path", [NoLibrary(), *sys.meta_path])
    with pytest.raises(
        ModelError, match=r"library does not load \(libGLU\.so\.1.*apt-get install libglu1-mesa"
    ):
        mesh_solid(tube_part(), name="tube")


@needs_gmsh
def test_a_broken_step_file_is_refused_naming_it(tmp_path):
    bad = tmp_path / "broken.step"
    bad.write_text("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('cut short'),'2;1');\n")
    with pytest.raises(ModelError, match=r"shaft: geometry = '.*broken\.step'") as err:
        mesh_solid(bad, name="shaft")
    assert err.value.component == "shaft"


@needs_gmsh
def test_a_mesh_file_is_refused(tmp_path):
    with pytest.raises(ModelError, match=r"triangulated surface .*valid: a STEP or BREP file"):
        mesh_solid(tmp_path / "part.stl", name="part")


@needs_gmsh
def test_two_solids_are_refused():
    two = bd.Compound([bd.Box(100, 40, 40), bd.Pos(300, 0, 0) * bd.Box(100, 40, 40)])
    with pytest.raises(ModelError, match="holds 2 solids.*exactly one closed solid"):
        mesh_solid(two, name="pair")


@needs_gmsh
def test_an_end_that_is_not_a_plane_normal_to_the_axis_is_refused():
    # a round bar with a hemispherical end at x = 0: no plane face there
    rod = bd.Rot(0, 90, 0) * bd.Cylinder(40.0, 300.0, align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN))
    domed = rod + bd.Sphere(40.0)
    expected = r"domed: geometry: its start \(x = 0 m\) is not a plane face normal"
    with pytest.raises(ModelError, match=expected):
        mesh_solid(domed, name="domed", size=0.03)


@needs_gmsh
def test_bad_options_are_refused():
    for kwargs, field in (
        ({"size": 0.0}, "size"),
        ({"refine": 1.5}, "refine"),
        ({"curvature_elements": 2.5}, "curvature_elements"),
        ({"timeout": -1.0}, "timeout"),
    ):
        with pytest.raises(ModelError, match=f"tube: {field} = ") as err:
            mesh_solid(tube_part(), name="tube", **kwargs)
        assert err.value.field == field


@needs_gmsh
def test_a_mesh_that_takes_too_long_is_stopped():
    expected = r"tube: geometry = 'build123d Part': gmsh .* took more than 0\.05 s"
    with pytest.raises(ModelError, match=expected):
        mesh_solid(tube_part(), name="tube", timeout=0.05)


@needs_gmsh
def test_a_failing_or_crashing_mesher_is_one_error(monkeypatch):
    import gmsh

    def fails(dim=3):
        raise Exception("Invalid boundary mesh (overlapping facets) on surface 7")

    monkeypatch.setattr(gmsh.model.mesh, "generate", fails)  # the forked child inherits it
    with pytest.raises(ModelError, match=r"could not mesh it .*failed: Exception: Invalid boundary mesh"):
        mesh_solid(tube_part(), name="tube", size=0.05)
    monkeypatch.setattr(gmsh.model.mesh, "generate", lambda dim=3: os.kill(os.getpid(), signal.SIGSEGV))
    with pytest.raises(ModelError, match=r"could not mesh it into tetrahedra: crashed \(signal SIGSEGV\)"):
        mesh_solid(tube_part(), name="tube", size=0.05)


@needs_gmsh
def test_a_mesher_that_makes_no_tetrahedra_is_its_failure(monkeypatch):
    # gmsh logs some failures and returns, a std::bad_alloc at the memory cap among them (the issue's
    # 1 mm mesh of a 1 m shaft): an empty volume mesh is gmsh's failure in one line, not a defect's
    # "unexpected ValueError" from the empty arrays
    import gmsh

    generate = gmsh.model.mesh.generate
    monkeypatch.setattr(gmsh.model.mesh, "generate", lambda dim=3: None if dim == 3 else generate(dim))
    expected = r"tube: geometry = 'build123d Part': gmsh .* could not mesh it .*: RuntimeError: gmsh made no"
    with pytest.raises(ModelError, match=expected):
        mesh_solid(tube_part(), name="tube", size=0.05)


@needs_gmsh
def test_when_hxt_fails_delaunay_meshes_the_volume(monkeypatch, tmp_path):
    import gmsh

    generate, set_number = gmsh.model.mesh.generate, gmsh.option.setNumber
    log = tmp_path / "calls"  # written by the forked child
    algorithm = [None]

    def hxt_fails(dim=3):
        with open(log, "a") as fh:
            fh.write(f"{dim} {algorithm[-1]}\n")
        if dim == 3 and algorithm[-1] == 10:
            raise Exception("HXT: could not recover the boundary")
        generate(dim)

    def noting(name, value):
        if name == "Mesh.Algorithm3D":
            algorithm.append(value)
        set_number(name, value)

    monkeypatch.setattr(gmsh.model.mesh, "generate", hxt_fails)
    monkeypatch.setattr(gmsh.option, "setNumber", noting)
    mesh = mesh_solid(tube_part(), name="tube", size=0.05)
    assert mesh.n_elements > 0 and mesh.nodes[:, 0].max() == pytest.approx(L, rel=ON_GEOMETRY)
    assert log.read_text().split("\n")[:3] == ["2 None", "3 10", "3 1"]  # HXT (10), then Delaunay (1)


@needs_gmsh
def test_an_inverted_element_is_refused(monkeypatch):
    import geometry.meshing as tetmesh

    def one_inverted(nodes, tets):
        det = jacobian_dets(nodes, tets)
        det[3, 5] = -1e-12
        return det

    monkeypatch.setattr(tetmesh, "jacobian_dets", one_inverted)
    expected = r"tube: geometry: meshes into an inverted curved element \(element 3"
    with pytest.raises(ModelError, match=expected):
        mesh_solid(tube_part(), name="tube", size=0.05)


@needs_gmsh
def test_a_valid_curved_element_with_its_corners_inside_out_is_refused_in_words(monkeypatch):
    # Orientation follows the curved volume (gmsh's optimiser once made valid curved elements whose
    # corners were inside out, and turning them by their corners inverted them); a TetMesh orients
    # by corners, so such an element is refused, saying what it is. Made here by handing over one
    # element inside out while its det J reads positive.
    import gmsh

    import geometry.meshing as tetmesh

    by_type = gmsh.model.mesh.getElementsByType

    def one_inside_out(element_type, tag=-1, task=0, num_tasks=1):
        tags, nodes = by_type(element_type, tag, task, num_tasks)
        if element_type == 11:
            nodes = nodes.reshape(-1, 10).copy()
            nodes[0] = nodes[0][[0, 2, 1, 3, 6, 5, 4, 7, 9, 8]]
            nodes = nodes.ravel()
        return tags, nodes

    monkeypatch.setattr(gmsh.model.mesh, "getElementsByType", one_inside_out)
    monkeypatch.setattr(tetmesh, "jacobian_dets", lambda nodes, tets: np.abs(jacobian_dets(nodes, tets)))
    with pytest.raises(ModelError, match=r"tube: geometry: meshes into 1 curved elements whose four corners"):
        mesh_solid(tube_part(), name="tube", size=0.05)
