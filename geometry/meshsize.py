"""The element size field of a solid mesh, and how many elements and DOFs it will give.

The size a user asks for (``size``) is the size of the elements in the bulk of the part. Smaller
elements are wanted at two kinds of feature, each the source of a size that grows back to ``size``
at a fixed rate away from it:

- a curved face of smallest curvature radius ρ (a bolt hole, a fillet, a small bore) gets
  h = 2πρ / ``curvature_elements`` on it, growing by :data:`GROWTH` per unit distance (h + 0.7·d):
  a fillet of 10 mm meets the 120 mm elements of a coarse mesh over some 0.16 m instead of within
  one element;
- a re-entrant circular edge (a diameter step's inner corner) gets ``refine · size``, growing back
  to ``size`` over 2·``size`` (:mod:`geometry.meshing`).

The size at a point is the smallest of these and ``size``, and gmsh follows this field (on a curved
face itself also its own curvature size, ``Mesh.MeshSizeFromCurvature``: the same 2πρ/N): sizes are
not also carried in from the faces' meshes into the volume (``Mesh.MeshSizeExtendFromBoundary`` 0),
so the field is the whole story. That is what makes a coarse mesh coarse and quick: with gmsh's
default the sizes of the small faces spread into the bulk (PTSS part 4 meshed into 724 000 DOFs at
0.1 m and 1 130 000 at 0.03 m), and a 10 mm fillet next to 120 mm elements made flat elements
that the curved mid-side nodes turned inside out - 50 to 80 of them on PTSS part 1, which gmsh's
high-order optimiser then took 30 to 220 s to mend.

And it makes the count predictable before gmsh meshes anything (:func:`estimate`): a
tetrahedron's volume is a fixed share of the cube of its size, so the element count is ∫ dV / h³
over the solid, integrated here per feature along the distance from it (:class:`Feature`), plus a
share of the surface triangles where the part is thinner than its elements. The constants are
fitted to gmsh's meshes of the bench's parts over sizes (tests/geometry/test_meshsize.py checks the
estimate against meshes within :data:`ESTIMATE_FACTOR`).

This module's gmsh part runs in the mesher's child (:mod:`geometry.meshing`); :func:`estimate` is
plain arithmetic. Lengths in any one unit (the mesher's are mm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = [
    "GROWTH",
    "ESTIMATE_FACTOR",
    "Feature",
    "MeshEstimate",
    "estimate",
    "smallest_size",
    "curved_faces",
    "install_size_field",
]

#: How fast the element size grows away from a curved face, per unit distance: h(d) = h_c + 0.7·d.
#: PTSS part 1 at 0.16 m: at 1.0, 64 curved elements came out inverted and the meshing took 8 s
#: (108 000 DOFs); at 0.7, 10 and 2.1 s (131 000); at 0.5, 2 and 2.1 s, but 28 % more DOFs.
GROWTH = 0.7
#: The estimate's stated accuracy: the DOFs gmsh makes are within this factor of :func:`estimate`'s
#: (either way) on the parts the tests mesh.
ESTIMATE_FACTOR = 2.0

# Nodes (corners and mid-side nodes) and 10-node tetrahedra per unit of ∫ dV / h³ in the bulk
# (a regular tetrahedron of edge h holds h³/(6√2) = 0.118 h³; gmsh's are larger, their edges 1.1 to
# 1.6 h inside the volume), per unit of it near the features (about twice: the graded elements there
# come out smaller than the field asks) and per surface triangle (the layer a wall thinner than its
# elements is made of). Fitted in log scale to gmsh 4.15's meshes of 12 parts (a tube, a rod, a box,
# stepped and flanged shafts, the bench's seven parts) at 5 to 8 sizes each: the meshes of more than
# 1000 nodes have 0.62 to 1.42 times the nodes estimated, 0.61 to 1.43 times the elements.
_NODES = (4.32, 9.0, 2.31)
_ELEMENTS = (3.41, 5.26, 0.82)
# A surface triangle of size h covers about (√3/4)·h² of the face.
_TRIANGLE_AREA = math.sqrt(3.0) / 4.0


@dataclass(frozen=True)
class Feature:
    """One source of small elements: a curved face, or a diameter step's inner corner.

    The element size at distance ``d`` from it is ``min(size, h + slope·max(0, d - flat))`` (the
    global size ``size`` given to :func:`estimate`), and the solid within distance ``d`` of it
    has the measure ``d_volume(d)·dd``.

    Attributes
    ----------
    kind : str
        ``"face"`` or ``"corner"``.
    h : float
        The element size at the feature (length).
    extent : float
        A face's area (length²), a corner circle's length 2πr (length).
    radius : float
        A face's smallest curvature radius ρ; a corner circle's radius (length).
    side : int
        A face: +1 where the solid lies away from the centre of curvature (a hole, a bore, a
        fillet: the solid around it grows with the distance), -1 toward it (an outer cylinder).
    slope : float
        The growth of the size per unit distance.
    flat : float
        The distance up to which the size stays ``h`` (a corner's refined core), length.
    refine : float
        A corner's refinement as a share of the global size (0 for a face, whose size is its
        curvature's whatever the global size): at another global size its ``h``, ``flat`` and
        ``slope`` are that size's (:meth:`at`).
    spread : float
        A corner's grading back to the global size, over this many global sizes.
    """

    kind: str
    h: float
    extent: float
    radius: float
    side: int = 1
    slope: float = GROWTH
    flat: float = 0.0
    refine: float = 0.0
    spread: float = 1.0

    def at(self, size: float) -> Feature:
        """The feature as a mesh of global size ``size`` has it: a face's unchanged, a corner's
        refined core ``refine·size`` wide, graded back to ``size`` over ``spread·size``."""
        if self.refine <= 0.0:
            return self
        fine = self.refine * size
        return replace(self, h=fine, flat=fine, slope=(1.0 - self.refine) / self.spread)

    def reach(self, size: float) -> float:
        """The distance at which the size is back to ``size``."""
        return self.flat + max(size - self.h, 0.0) / self.slope

    def d_volume(self, d: np.ndarray) -> np.ndarray:
        """The solid's measure at distance ``d`` from the feature, per unit distance (length²)."""
        if self.kind == "corner":
            # an inner corner: the solid fills three of the four quadrants about the circle
            return 0.75 * self.extent * 2.0 * math.pi * d
        grow = 1.0 + self.side * d / self.radius
        return self.extent * np.clip(grow, 0.0, None)

    def elements_integral(self, size: float) -> float:
        """∫ (h(x)⁻³ − size⁻³) dV over the solid near the feature: what it adds to the bulk's V/size³."""
        if self.h >= size:
            return 0.0
        far = self.reach(size)
        if self.kind == "face" and self.side < 0:
            far = min(far, self.radius)  # an outer cylinder's inside ends at its axis
        # geometric spacing: the integrand falls as (h + slope·d)⁻³
        d = np.concatenate([[0.0], np.geomspace(1e-3 * self.h, max(far, 2e-3 * self.h), 400)])
        h = np.minimum(self.h + self.slope * np.clip(d - self.flat, 0.0, None), size)
        f = (h**-3 - size**-3) * self.d_volume(d)
        return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(d)))

    def surface_triangles(self, size: float) -> float:
        """The triangles of a face beyond those of its area at ``size`` (0 for a corner's circle,
        whose refined faces are small)."""
        if self.kind != "face" or self.h >= size:
            return 0.0
        return self.extent / _TRIANGLE_AREA * (self.h**-2 - size**-2)


@dataclass(frozen=True)
class MeshEstimate:
    """What a size field will mesh into, estimated before meshing.

    Attributes
    ----------
    size : float
        The global element size it is for (length).
    elements : float
        10-node tetrahedra.
    surface_triangles : float
        Triangles of the surface mesh.
    nodes : float
        Nodes (corners and mid-side nodes).
    """

    size: float
    elements: float
    surface_triangles: float
    nodes: float

    @property
    def dofs(self) -> float:
        """Degrees of freedom: three displacements per node."""
        return 3.0 * self.nodes


def estimate(volume: float, area: float, size: float, features: tuple[Feature, ...] | list) -> MeshEstimate:
    """The element, node and DOF counts of a solid's mesh, before meshing it.

    Parameters
    ----------
    volume, area : float
        The solid's volume (length³) and surface area (length²).
    size : float
        The global element size (length).
    features : sequence of Feature
        The curved faces and inner corners the mesh is refined at.

    Returns
    -------
    MeshEstimate
        Within :data:`ESTIMATE_FACTOR` of gmsh's mesh on the parts the tests mesh.
    """
    features = [f.at(size) for f in features]
    terms = (
        volume / size**3,
        sum(f.elements_integral(size) for f in features),
        area / (_TRIANGLE_AREA * size**2) + sum(f.surface_triangles(size) for f in features),
    )
    elements = sum(c * t for c, t in zip(_ELEMENTS, terms))
    nodes = sum(c * t for c, t in zip(_NODES, terms))
    triangles = terms[2]
    return MeshEstimate(size=size, elements=elements, surface_triangles=triangles, nodes=nodes)


def smallest_size(volume: float, area: float, features, dofs: float, *, largest: float) -> float | None:
    """The smallest global size whose estimate is within ``dofs``, or None if no size up to ``largest`` is.

    The count falls as the size grows until the curved faces' sizes, which do not change with it
    (the steps' refinement does, :meth:`Feature.at`), take over (beyond, it levels off, and rises a
    little as their gradings reach further): a part whose features alone need more than ``dofs``
    fits at no size. The sizes are scanned from
    ``largest`` / 10⁶ up by factors of 1.25, then the first that fits is narrowed down by bisection.
    """
    grid = largest * 1.25 ** np.arange(-62, 1)  # 1.25⁻⁶² ≈ 1e-6
    fits = [estimate(volume, area, float(s), features).dofs <= dofs for s in grid]
    if not any(fits):
        return None
    k = fits.index(True)
    if k == 0:
        return float(grid[0])
    lo, hi = float(grid[k - 1]), float(grid[k])
    for _ in range(40):  # bisection in log size: the bracket's 1.25 to 1e-12
        mid = math.sqrt(lo * hi)
        if estimate(volume, area, mid, features).dofs <= dofs:
            hi = mid
        else:
            lo = mid
    return hi


# --- in the mesher's child: gmsh ---------------------------------------------------------------------

# Curvature is sampled on a 5 x 5 grid of each face's parameters (cell centres: away from a
# cone's apex or a sphere's poles, where gmsh reports none).
_SAMPLES = 5
# Faces whose sizes differ by less than this factor share one distance field (each field costs a
# kd-tree query wherever gmsh asks for a size).
_GROUP = 1.15
# The distance to a face is the distance to points sampled on it this many of its sizes apart.
_SPACING = 0.5


def curved_faces(gmsh, volume: int, curvature_elements: int, tol: float):
    """The curved faces of the solid and the sizes their curvature asks for: (surface tag, Feature) pairs.

    A face's size is 2πρ/``curvature_elements`` for its smallest curvature radius ρ over the
    sampled points, as gmsh's ``Mesh.MeshSizeFromCurvature`` makes it on the face itself. Every
    curved face is listed (those whose size is above the global one count for nothing): the
    estimate at other global sizes needs them.
    """
    if curvature_elements <= 0:
        return []
    found = []
    t = (np.arange(_SAMPLES) + 0.5) / _SAMPLES
    for _, tag in gmsh.model.getEntities(2):
        lo, hi = gmsh.model.getParametrizationBounds(2, tag)
        uv = np.array([(lo[0] + a * (hi[0] - lo[0]), lo[1] + b * (hi[1] - lo[1])) for a in t for b in t])
        kappa, normal = _curvatures(gmsh, tag, uv)
        i = int(np.argmax(np.abs(kappa)))
        if not np.isfinite(kappa[i]) or abs(kappa[i]) * tol >= 1.0 or abs(kappa[i]) * 1e9 * tol <= 1.0:
            continue  # a degenerate point, or flat: a radius beyond 1e9 tolerances (100 x the part's size)
        rho = 1.0 / abs(float(kappa[i]))
        p = np.asarray(gmsh.model.getValue(2, tag, uv[i].tolist()))
        # The centre of curvature is on the side of sign(κ)·n: the solid is there (an outer
        # cylinder) or not (a hole, a bore, a fillet).
        probe = p + np.sign(kappa[i]) * normal[i] * max(1e-3 * rho, 10.0 * tol)
        side = -1 if gmsh.model.isInside(3, volume, probe.tolist()) else 1
        area = gmsh.model.occ.getMass(2, tag)
        found.append((tag, Feature("face", 2.0 * math.pi * rho / curvature_elements, area, rho, side)))
    return found


def _curvatures(gmsh, tag: int, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The principal curvature of largest magnitude at each point (1/length, signed: positive when
    the centre of curvature is on the side of the normal returned) and the unit normals.

    From the face's first and second fundamental forms (gmsh's derivatives of its parametrisation),
    so that the sign goes with a normal we know, whichever way the face is oriented in the solid.
    """
    d1 = np.reshape(gmsh.model.getDerivative(2, tag, uv.ravel().tolist()), (-1, 2, 3))
    d2 = np.reshape(gmsh.model.getSecondDerivative(2, tag, uv.ravel().tolist()), (-1, 3, 3))
    xu, xv = d1[:, 0], d1[:, 1]
    n = np.cross(xu, xv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    first = np.stack([np.stack([(xu * xu).sum(1), (xu * xv).sum(1)], -1),
                      np.stack([(xu * xv).sum(1), (xv * xv).sum(1)], -1)], -2)  # fmt: skip
    uu, vv, uv_ = np.einsum("pkj,pj->kp", d2, n)  # gmsh lists x_uu, x_vv, x_uv
    second = np.stack([np.stack([uu, uv_], -1), np.stack([uv_, vv], -1)], -2)
    # the shape operator's eigenvalues: the principal curvatures along n
    k = np.linalg.eigvals(np.linalg.solve(first, second)).real
    return k[np.arange(len(k)), np.argmax(np.abs(k), axis=1)], n


def install_size_field(gmsh, size: float, faces, corner_fields=()) -> None:
    """Set gmsh's size field: the curved faces' growing sizes, the given corner fields, ``size``.

    Parameters
    ----------
    gmsh : module
    size : float
        The global size (mm).
    faces : list of (int, Feature)
        From :func:`curved_faces`.
    corner_fields : sequence of int
        Fields already added (the inner corners' thresholds), joined in.
    """
    field = gmsh.model.mesh.field
    fields = list(corner_fields)
    groups: list[list] = []
    for tag, feature in sorted(faces, key=lambda tf: tf[1].h):
        if feature.h >= size:
            break  # gentle enough for the global size (and so are the rest: they are sorted)
        if groups and feature.h <= _GROUP * groups[-1][0][1].h:
            groups[-1].append((tag, feature))
        else:
            groups.append([(tag, feature)])
    for group in groups:
        h = group[0][1].h
        tags = [tag for tag, _ in group]
        # Sample each face a half-size apart (the distance is to the samples: a size within a
        # fifth of the field's), along its largest extent.
        extent = max(math.dist(*np.reshape(gmsh.model.getBoundingBox(2, t), (2, 3))) for t in tags)
        distance = field.add("Distance")
        field.setNumbers(distance, "SurfacesList", tags)
        field.setNumber(distance, "Sampling", int(min(200, max(8, math.ceil(extent / (_SPACING * h)) + 1))))
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", h)
        field.setNumber(threshold, "SizeMax", size)
        field.setNumber(threshold, "DistMin", 0.0)
        field.setNumber(threshold, "DistMax", group[0][1].reach(size))  # the estimate's own grading
        fields.append(threshold)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    # The field is the whole story (with gmsh's curvature size on the curved faces themselves, the
    # field's own value there): no sizes carried in from the faces' meshes into the volume or
    # from the curves into the faces, and none from gmsh's default of a tenth of the part's
    # bounding-box diagonal at its corner points (which made a 0.1 m mesh of a 0.5 m tube 0.057 m).
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    # A curve's nodes follow the integral of 1/h along it, which gmsh takes to 1e-9 by default:
    # 1.3 s of field evaluations on PTSS part 1 at 0.16 m, 0.25 s at 1e-3 (the same nodes: their
    # count is rounded to a whole number anyway).
    gmsh.option.setNumber("Mesh.LcIntegrationPrecision", 1e-3)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    if fields:
        smallest = field.add("Min")
        field.setNumbers(smallest, "FieldsList", fields)
        field.setAsBackgroundMesh(smallest)
