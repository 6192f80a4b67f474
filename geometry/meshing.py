"""A part's solid meshed into curved 10-node tetrahedra with gmsh: a
:class:`~flexshaft.elements.tetmesh.TetMesh`.

The solid (a build123d part, or a STEP/BREP file read by :mod:`geometry.cadio`) is first put in the
part's own frame by the slicer's :func:`~geometry.slicing.solid.part_frame`, so the mesh and the
part's section table share coordinates: x along the axis from 0 at the part's lower end (from the
axis' origin when the axis is given), y and z across. It is written as an OCCT BREP file and meshed
by gmsh (GPL; the optional extra ``flexshaft[solid]``, imported only here, when a part is meshed):

1. element size (:mod:`geometry.meshsize`): ``size`` in the bulk; on a curved face
   2πρ / ``curvature_elements`` for its smallest curvature radius ρ, so fillets, bolt holes and
   small bores get round, growing back to ``size`` at 0.7 per unit distance; ``refine · size`` at
   the re-entrant circular edges about the axis that are not at the part's ends - a diameter step's
   inner corner, where the stress concentrates and a coarse mesh is too stiff - growing back to
   ``size`` over 2·``size``. gmsh follows this field (and its own curvature size, the same, on the
   curved faces themselves; no sizes carried in from the faces' meshes), so the count is known
   before meshing: a size whose estimate is surely above the solid
   DOF ceiling (``FLEXSHAFT_MAX_SOLID_DOFS``) is refused in one line that names the smallest size
   that fits, before gmsh meshes anything;
2. surfaces, then the volume: gmsh's HXT on one thread (five times as fast as its Delaunay on the
   bench's parts, with fewer curved elements to mend), Delaunay where HXT fails;
3. second order with every mid-side node placed ON the geometry (``Mesh.SecondOrderLinear`` 0: a
   boundary edge's mid-side node is its midpoint in the face's or curve's parameters), so a
   cylinder's mid-side nodes lie on the cylinder rather than a sagitta inside it;
4. the check: gmsh's bound on each element's Jacobian determinant (``minDetJac``, from the
   determinant's Bezier coefficients); where a curved element came out inverted, gmsh's high-order
   optimiser moves its nodes, and an element still inverted is an error. With the graded sizes of
   step 1 that is a few elements of the bench's parts at any size, mended in a fraction of a
   second; where a small curved face met elements 15 times its size (a coarse mesh without the
   grading) it was 50 to 80, in patches of large elements that took the optimiser 30 to 220 s.

gmsh runs in a forked child (:func:`flexshaft.system.isolate.run_isolated`): it can crash or loop on a
damaged shape, and its terminal output is silenced. Its node order is converted to VTK's (verified
on straight-sided meshes by the tests: each mid-side node is the midpoint of its corner pair): a
10-node tetrahedron (gmsh type 11) lists the edges 0-1, 1-2, 0-2, 0-3, 2-3, 1-3, VTK 0-1, 1-2, 0-2,
0-3, 1-3, 2-3; a 6-node triangle (type 9) has VTK's order already.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from flexshaft.elements.tetmesh import TET10_EDGES, TetMesh
from flexshaft.errors import ModelError
from flexshaft.system.limits import CEILINGS, ceiling
from flexshaft.validation import check_int, check_real

from .meshsize import (
    ESTIMATE_FACTOR,
    Feature,
    MeshEstimate,
    curved_faces,
    estimate,
    install_size_field,
    smallest_size,
)
from .units import from_cad, to_cad

__all__ = [
    "EXTRA",
    "SYSTEM_LIBRARIES",
    "TIMEOUT_S",
    "MEMORY_BYTES",
    "GMSH_TET10_TO_VTK",
    "GMSH_TRI6_TO_VTK",
    "default_size",
    "estimate_mesh",
    "jacobian_dets",
    "mesh_solid",
]

#: What to install for solid meshing (pyproject's optional dependencies).
EXTRA = "pip install 'flexshaft[solid]'"
#: The system libraries the gmsh wheel's libgmsh links (OpenGL, X11 client and fonts; present on a
#: desktop, missing from a minimal server or container image).
SYSTEM_LIBRARIES = "apt-get install libglu1-mesa libxcursor1 libxft2 libxinerama1 libgomp1"
#: Seconds the meshing may take by default before it counts as hung: the bench's longest part (PTSS
#: part 2, 5.8 m) meshes at its default size into 420 000 nodes in 9 s on one core, so this allows
#: some millions of nodes.
TIMEOUT_S = 300.0
#: Bytes of address space the mesher may add to what it inherits: PTSS part 2's 420 000 nodes take
#: ~150 MB beyond the ~450 MB the caller's libraries hold, so this leaves room for ~10 million.
MEMORY_BYTES = 4 << 30
#: Column ``k`` of a VTK 10-node tetrahedron is gmsh's column ``GMSH_TET10_TO_VTK[k]`` (gmsh lists
#: the mid-side nodes of the edges 2-3 and 1-3 the other way round).
GMSH_TET10_TO_VTK = (0, 1, 2, 3, 4, 5, 6, 7, 9, 8)
#: The same for a 6-node triangle (the orders agree).
GMSH_TRI6_TO_VTK = (0, 1, 2, 3, 4, 5)
# Swapping corners 1 and 2 turns a tetrahedron inside out; its mid-side nodes follow their edges
# (0-1 <-> 0-2, 1-3 <-> 2-3; 1-2 and 0-3 stay).
_TET10_FLIP = (0, 2, 1, 3, 6, 5, 4, 7, 9, 8)
# The same for a triangle: corners 1 <-> 2, edges 0-1 <-> 2-0.
_TRI6_FLIP = (0, 2, 1, 5, 4, 3)
# gmsh's element types: the 10-node tetrahedron and the 6-node triangle.
_GMSH_TET10, _GMSH_TRI6 = 11, 9
# The growth of the element size from the refined edges back to the global size: over 2 sizes.
_REFINE_GROWTH = 2.0
# The size a refusal suggests is estimated at the ceiling divided by this: gmsh's meshes came out at
# up to 1.42 times the estimate (geometry.meshsize).
_SUGGEST_MARGIN = 1.5


def _gmsh(name: str):
    """The gmsh module, or a ModelError naming the extra that brings it."""
    try:
        import gmsh
    except ImportError:
        raise ModelError(
            "a solid (3D) mesh needs gmsh, which is not installed",
            component=name,
            field="fe",
            value="solid",
            valid=f"{EXTRA} (gmsh is GPL, so it is an optional extra), or the 1D elements",
        ) from None
    except OSError as err:  # the wheel's libgmsh links the system's OpenGL and X11 client libraries
        raise ModelError(
            f"gmsh is installed but its library does not load ({str(err).splitlines()[0]})",
            component=name,
            field="fe",
            value="solid",
            valid=f"the system libraries gmsh needs: {SYSTEM_LIBRARIES} on Debian/Ubuntu, or the 1D elements",
        ) from None
    return gmsh


def default_size(volume: float, area: float) -> float:
    """The default global element size: V / S, half the solid's mean thickness 2V / S.

    2V/S is a tube's wall thickness (R − r), a solid shaft's radius R, a disc's thickness: the
    default puts about two 10-node tetrahedra across the wall of a part, which with their quadratic
    fields carries torsion's linear shear profile exactly and its bending to a few per mille. Any
    consistent unit (m³ and m² give m).
    """
    return volume / area


# --- the Jacobian of a 10-node tetrahedron (VTK order) ------------------------------------------------

# Barycentric sample points: the corners, the edge midpoints, the centroid and the 4-point Gauss
# rule (a = (5 − √5)/20); gmsh's minDetJac is the rigorous bound, these a check of the arrays returned.
_A = (5.0 - math.sqrt(5.0)) / 20.0
_SAMPLES = np.vstack(
    [
        np.eye(4),
        [[0.5 * (i == a or i == b) for i in range(4)] for a, b in TET10_EDGES],
        [[0.25] * 4],
        [[1.0 - 3.0 * _A if i == k else _A for i in range(4)] for k in range(4)],
    ]
)
# The gradients of the barycentric coordinates L0..L3 in the reference coordinates (ξ, η, ζ).
_DL = np.array([[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def _shape_gradients(lam: np.ndarray) -> np.ndarray:
    """(10, 3): the reference gradients of the 10 quadratic shape functions at barycentrics ``lam``."""
    g = np.empty((10, 3))
    for i in range(4):
        g[i] = (4.0 * lam[i] - 1.0) * _DL[i]  # corner: L_i (2 L_i − 1)
    for k, (a, b) in enumerate(TET10_EDGES):
        g[4 + k] = 4.0 * (lam[a] * _DL[b] + lam[b] * _DL[a])  # mid-side: 4 L_a L_b
    return g


def jacobian_dets(nodes: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Jacobian determinants of curved 10-node tetrahedra (VTK order) at 15 points each.

    The points: the 4 corners, the 6 edge midpoints, the centroid and the 4-point Gauss rule. The
    determinant is the element's local volume scale, 6·(corner volume) for a straight-sided one; a
    value <= 0 anywhere means the element is inverted there.

    Parameters
    ----------
    nodes : ndarray, shape (n, 3)
        Node coordinates (any length unit).
    tets : ndarray of int, shape (m, 10)
        The elements.

    Returns
    -------
    ndarray, shape (m, 15)
        det J at each point (length unit cubed).
    """
    x = np.asarray(nodes, float)[np.asarray(tets)].transpose(0, 2, 1)  # (m, 3, 10)
    m = x.shape[0]
    flat = x.reshape(3 * m, 10)
    out = np.empty((m, len(_SAMPLES)))
    for p, lam in enumerate(_SAMPLES):
        j = (flat @ _shape_gradients(lam)).reshape(m, 3, 3)  # j[e, i, k] = dx_i / dξ_k
        out[:, p] = (
            j[:, 0, 0] * (j[:, 1, 1] * j[:, 2, 2] - j[:, 1, 2] * j[:, 2, 1])
            - j[:, 0, 1] * (j[:, 1, 0] * j[:, 2, 2] - j[:, 1, 2] * j[:, 2, 0])
            + j[:, 0, 2] * (j[:, 1, 0] * j[:, 2, 1] - j[:, 1, 1] * j[:, 2, 0])
        )
    return out


# --- the part and its frame ---------------------------------------------------------------------------


def _source_shape(shape, name: str):
    """(build123d shape, description): a part as given, or read from a STEP/BREP file."""
    if not isinstance(shape, (str, os.PathLike)):
        return shape, f"build123d {type(shape).__name__}"
    from .cadio import CAD_SUFFIXES, read_brep, read_step

    suffix = Path(shape).suffix.lower()
    if suffix not in CAD_SUFFIXES:
        raise ModelError(
            "cannot be meshed into a solid: its mid-side nodes must lie on the exact geometry, which "
            "a triangulated surface (STL/OBJ/PLY) does not carry",
            component=name,
            field="geometry",
            value=str(shape),
            valid=f"a STEP or BREP file ({', '.join(CAD_SUFFIXES)}) or a build123d part",
        )
    reader = read_step if suffix in (".step", ".stp") else read_brep
    try:
        return reader(shape), f"{'STEP' if reader is read_step else 'BREP'} file {str(shape)!r}"
    except ModelError as err:
        raise err.located(component=name) from None


@dataclass(frozen=True)
class _Job:
    """What the child meshes: a BREP file in the part's frame and the sizes, all in mm."""

    path: str
    name: str
    size: float
    curvature_elements: int
    refine: float
    x_lo: float  # the part's two ends (the frame's x, mm)
    x_hi: float
    tol: float  # lengths closer than this are equal, mm
    x0: float  # where the part's x starts (mm), for messages in m
    extent: float = 0.0  # the diagonal of the part's bounding box, mm: no element is larger
    max_dofs: int = 0  # the solid DOF ceiling in force
    field: str = "size"  # what the size is called where it was given (a model file's mesh_size)
    estimate_only: bool = False  # stop after the estimate and return it


# --- in the child: gmsh -------------------------------------------------------------------------------


def _end_surfaces(gmsh, job: _Job) -> tuple[list[int], list[int]]:
    """The surfaces at the part's two ends: planes normal to the axis at its extreme x (each a list)."""
    ends: tuple[list[int], list[int]] = ([], [])
    for _, tag in gmsh.model.getEntities(2):
        x_min, _, _, x_max, _, _ = gmsh.model.getBoundingBox(2, tag)
        if x_max - x_min > 2.0 * job.tol or gmsh.model.getType(2, tag) != "Plane":
            continue
        x = 0.5 * (x_min + x_max)
        for k, end in enumerate((job.x_lo, job.x_hi)):
            if abs(x - end) <= 2.0 * job.tol:
                ends[k].append(tag)
    for k, (which, end) in enumerate((("start", job.x_lo), ("end", job.x_hi))):
        if not ends[k]:
            raise ModelError(
                f"its {which} (x = {from_cad(end - job.x0):.6g} m) is not a plane face normal to its axis, "
                "where a solid part is joined to its neighbours",
                component=job.name,
                field="geometry",
                valid="a part whose two axial ends are plane faces normal to its axis (a turned "
                "shaft's end faces; not a point, a dome or a cone)",
            )
    return ends


def _reentrant_circles(gmsh, job: _Job, volume: int) -> tuple[list[int], float]:
    """The curves to refine at, and the largest radius among them (mm).

    A curve qualifies when it is a circle (or arc) about the axis in a plane x = const that is not
    one of the ends, and the solid lies on three of the four sides of it in its (x, r) plane: an
    inner corner. A convex corner (one side) carries no stress concentration, a smooth seam (two
    sides: a fillet's tangent edge) has its own refinement from the curvature.
    """
    eps = 1e-3 * job.size  # the corner's four sides are probed this far off the edge
    found, r_max = [], 0.0
    ex = np.array([1.0, 0.0, 0.0])
    for _, tag in gmsh.model.getEntities(1):
        lo, hi = gmsh.model.getParametrizationBounds(1, tag)
        pts = np.reshape(gmsh.model.getValue(1, tag, np.linspace(lo[0], hi[0], 5).tolist()), (-1, 3))
        r = np.hypot(pts[:, 1], pts[:, 2])
        if np.ptp(pts[:, 0]) > job.tol or np.ptp(r) > job.tol or r.min() <= job.tol:
            continue  # not a circle about the axis in a plane normal to it
        x = float(pts[2, 0])
        if min(abs(x - job.x_lo), abs(x - job.x_hi)) <= 2.0 * job.tol:
            continue  # the ends are tied to the neighbours: no refinement there
        p = pts[2]
        er = np.array([0.0, p[1], p[2]]) / r[2]
        probes = [p + eps * (sx * ex + sr * er) for sx in (-1.0, 1.0) for sr in (-1.0, 1.0)]
        if gmsh.model.isInside(3, volume, np.ravel(probes).tolist()) >= 3:
            found.append(tag)
            r_max = max(r_max, float(r.max()))
    return found, r_max


def _corner_refinement(gmsh, job: _Job, curves: list[int], r_max: float) -> tuple[list[int], list[Feature]]:
    """The inner corners' size field (``refine · size`` growing back to ``size`` over 2·``size``):
    its gmsh field tags, and the corners as :class:`~geometry.meshsize.Feature` for the estimate."""
    if not curves or job.refine >= 1.0:
        return [], []
    fine = job.refine * job.size
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "CurvesList", curves)
    # Sample points a quarter of the fine size apart on the largest circle: the distance to
    # them is the distance to the curve within an eighth of the fine size.
    field.setNumber(distance, "Sampling", min(20_000, math.ceil(8.0 * math.pi * r_max / fine) + 1))
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", fine)
    field.setNumber(threshold, "SizeMax", job.size)
    field.setNumber(threshold, "DistMin", fine)
    field.setNumber(threshold, "DistMax", fine + _REFINE_GROWTH * job.size)
    slope = (job.size - fine) / (_REFINE_GROWTH * job.size)
    corners = []
    for tag in curves:
        lo, hi = gmsh.model.getParametrizationBounds(1, tag)
        p = np.asarray(gmsh.model.getValue(1, tag, [0.5 * (lo[0] + hi[0])]))
        length = gmsh.model.occ.getMass(1, tag)
        r = float(np.hypot(p[1], p[2]))
        grading = {"slope": slope, "flat": fine, "refine": job.refine, "spread": _REFINE_GROWTH}
        corners.append(Feature("corner", fine, length, r, **grading))
    return [threshold], corners


def _check_estimate(job: _Job, guess: MeshEstimate, solid: float, area: float, features: list) -> None:
    """Refuse, before meshing, a size whose mesh would surely be above the solid DOF ceiling.

    Surely: the estimate is within :data:`~geometry.meshsize.ESTIMATE_FACTOR` of the mesh, so a
    size is refused here only when even the estimate divided by that factor is above the ceiling;
    a mesh between is made and refused by its count (:func:`flexshaft.elements.tet10.solid_matrices`).
    """
    if guess.dofs <= ESTIMATE_FACTOR * job.max_dofs:
        return
    c = CEILINGS["solid_dofs"]
    # The size suggested fits with the estimate's margin: meshes came out up to 1.42 times it.
    fits = smallest_size(solid, area, features, job.max_dofs / _SUGGEST_MARGIN, largest=job.extent)
    if fits is None:
        floor = estimate(solid, area, job.extent, features)
        valid = (
            f"no mesh size fits: the refinement at its curved faces and steps alone makes about "
            f"{floor.dofs:.2g} DOFs (fewer curvature_elements, or {c.variable}=N sets another ceiling)"
        )
    else:
        valid = (
            f"a {job.field} of at least {_round_up(from_cad(fits)):g} m (estimated at "
            f"{_format_count(round(job.max_dofs / _SUGGEST_MARGIN))} DOFs, the estimate's margin below "
            f"the ceiling), or {c.variable}=N sets another ceiling"
        )
    raise ModelError(
        f"would mesh into about {_format_count(guess.dofs)} DOFs ({guess.elements:.2g} 10-node tetrahedra; "
        f"estimated before meshing from its volume, its curved faces and steps, within a factor "
        f"{ESTIMATE_FACTOR:g}), above the ceiling of {_format_count(job.max_dofs)} {c.unit} ({c.why})",
        component=job.name,
        field=job.field,
        value=float(f"{from_cad(job.size):.12g}"),  # as given: no round-off of the mm <-> m trip
        unit="m",
        valid=valid,
    )


def _format_count(n: float) -> str:
    """A count for a message: a whole number below ten million as its digits (the ceiling's 2000000),
    anything else to two digits (1.1e+08)."""
    return str(int(n)) if float(n).is_integer() and n < 1e7 else f"{n:.2g}"


def _round_up(x: float) -> float:
    """``x`` rounded up to two significant digits (a size to suggest: at least this)."""
    scale = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.ceil(x / scale - 1e-9) * scale


def _run_gmsh(job: _Job, send) -> dict:
    """Mesh ``job`` with gmsh (in the child): plain arrays of gmsh's node tags and elements."""
    import gmsh

    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        option = gmsh.option.setNumber
        option("General.Terminal", 0)
        option("General.NumThreads", 1)  # flexshaft's thread policy: one thread unless asked
        send("reading the solid", 0.0)
        gmsh.model.occ.importShapes(job.path)
        gmsh.model.occ.synchronize()
        volumes = gmsh.model.getEntities(3)
        if len(volumes) != 1:
            raise ModelError(
                f"holds {len(volumes)} volumes after its import into gmsh",
                component=job.name,
                field="geometry",
                valid="exactly one closed solid",
            )
        start, end = _end_surfaces(gmsh, job)
        curves, r_max = _reentrant_circles(gmsh, job, volumes[0][1])
        corner_fields, corners = _corner_refinement(gmsh, job, curves, r_max)
        curved = curved_faces(gmsh, volumes[0][1], job.curvature_elements, job.tol)
        install_size_field(gmsh, job.size, curved, corner_fields)
        option("Mesh.MeshSizeFromCurvature", job.curvature_elements)
        send("estimating the mesh", 0.05)
        features = [f for _, f in curved] + corners
        solid = gmsh.model.occ.getMass(3, volumes[0][1])
        area = sum(gmsh.model.occ.getMass(2, tag) for _, tag in gmsh.model.getEntities(2))
        guess = estimate(solid, area, job.size, features)
        if job.estimate_only:
            return {"estimate": guess}
        _check_estimate(job, guess, solid, area, features)
        option("Mesh.ElementOrder", 1)
        send("meshing the surfaces", 0.1)
        gmsh.model.mesh.generate(2)
        send("meshing the volume", 0.25)
        try:
            option("Mesh.Algorithm3D", 10)  # HXT: 5x faster than Delaunay, fewer elements to mend
            gmsh.model.mesh.generate(3)
        except Exception:  # noqa: BLE001 - gmsh reports any failure so; Delaunay is the robust one
            gmsh.model.mesh.clear()
            option("Mesh.Algorithm3D", 1)
            gmsh.model.mesh.generate(3)
        if not len(gmsh.model.mesh.getElementsByType(4)[0]):
            # gmsh logs some failures (a std::bad_alloc at the memory cap among them) and returns
            raise RuntimeError("gmsh made no tetrahedra (out of memory, or a volume it could not fill)")
        send("placing the mid-side nodes on the geometry", 0.7)
        option("Mesh.SecondOrderLinear", 0)
        gmsh.model.mesh.setOrder(2)
        send("checking the elements", 0.85)
        tet_tags, tet_nodes = gmsh.model.mesh.getElementsByType(_GMSH_TET10)
        det = gmsh.model.mesh.getElementQualities(tet_tags, "minDetJac")
        optimised = 0
        if det.size and det.min() <= 0.0:
            optimised = int(np.count_nonzero(det <= 0.0))
            send("moving the nodes of curved elements that came out inverted", 0.9)
            gmsh.model.mesh.optimize("HighOrder")
            tet_tags, tet_nodes = gmsh.model.mesh.getElementsByType(_GMSH_TET10)
            det = gmsh.model.mesh.getElementQualities(tet_tags, "minDetJac")
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        faces = {}
        for key, surfaces in (("start", start), ("end", end)):
            tris = [gmsh.model.mesh.getElementsByType(_GMSH_TRI6, s)[1] for s in surfaces]
            faces[key] = np.concatenate(tris).astype(np.int64).reshape(-1, 6)
        return {
            "node_tags": node_tags.astype(np.int64),
            "coords": np.reshape(coords, (-1, 3)),
            "tets": tet_nodes.astype(np.int64).reshape(-1, 10),
            "min_det": det.astype(float),
            "faces": faces,
            "optimised": optimised,
            "refined_curves": len(curves),
        }
    finally:
        gmsh.finalize()


# --- in the caller --------------------------------------------------------------------------------------


def _to_mesh(raw: dict, job: _Job, source: str) -> TetMesh:
    """gmsh's arrays as a :class:`TetMesh`: nodes in m in the part's frame, VTK order, oriented."""
    where = dict(component=job.name, field="geometry")
    bad = raw["min_det"] <= 0.0
    if bad.any():
        raise ModelError(
            f"meshes into {int(bad.sum())} inverted curved elements (of {bad.size}) that gmsh's high-order "
            "optimiser could not mend",
            **where,
            valid="a solid whose thin walls and small radii allow a smaller size or more curvature_elements",
        )
    tags, tets = raw["node_tags"], raw["tets"]
    if not len(tets):  # the child refuses an empty mesh as gmsh's failure: here it is a defect of ours
        raise AssertionError("an empty mesh came past the mesher's own check")
    used = np.unique(tets)  # sorted gmsh tags of the nodes the tetrahedra use
    index = np.full(int(max(tags.max(), used.max())) + 1, -1, dtype=np.int64)
    index[used] = np.arange(used.size)
    position = np.full(index.size, -1, dtype=np.int64)
    position[tags] = np.arange(tags.size)
    xyz = raw["coords"][position[used]]
    nodes = from_cad(np.column_stack([xyz[:, 0] - job.x0, xyz[:, 1], xyz[:, 2]]))
    tets = index[tets][:, list(GMSH_TET10_TO_VTK)]
    dets = jacobian_dets(nodes, tets)
    # An element's orientation is that of its curved volume (the Gauss points' det J, equal
    # weights), not of its corners: a valid curved element can have its four corners inside out
    # (gmsh's optimiser made some; turned by their corners they came out inverted - a mesh gmsh
    # called valid refused as "inverted").
    inside_out = dets[:, -4:].sum(axis=1) < 0.0
    tets[inside_out] = tets[inside_out][:, list(_TET10_FLIP)]
    dets[inside_out] *= -1.0  # the same points, each det J of the turned element's
    if not np.all(dets > 0.0):
        k = int(np.argmin(dets.min(axis=1)))
        raise ModelError(
            f"meshes into an inverted curved element (element {k}: det J {dets[k].min():.3g} m³ at one "
            "of its sample points)",
            **where,
            valid="a solid whose thin walls and small radii allow a smaller size or more curvature_elements",
        )
    c = nodes[tets[:, :4]]
    corners6 = np.einsum("ij,ij->i", c[:, 1] - c[:, 0], np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]))
    if not np.all(corners6 > 0.0):
        # A valid curved element, but a TetMesh's elements are oriented by their corners (a
        # straight-sided reading of it, a VTK view, would see it inside out): not seen with the
        # graded sizes; gmsh's optimiser made 13 on PTSS part 1 at 0.16 m without them.
        raise ModelError(
            f"meshes into {int(np.sum(corners6 <= 0.0))} curved elements whose four corners are inside out "
            "(the curved element is valid, its straight-sided reading is not)",
            **where,
            valid="a slightly different size or more curvature_elements",
        )
    faces = {}
    for key, tri in raw["faces"].items():
        if np.any(index[tri] < 0):
            raise ModelError(
                f"its {key} face has nodes no tetrahedron uses (gmsh's mesh is not conforming)",
                **where,
                valid="a valid closed solid",
            )
        tri = index[tri][:, list(GMSH_TRI6_TO_VTK)]
        # Outward normals: -x at the start, +x at the end.
        p = nodes[tri[:, :3]]
        nx = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 0]
        flip = nx > 0.0 if key == "start" else nx < 0.0
        tri[flip] = tri[flip][:, list(_TRI6_FLIP)]
        faces[key] = tri
    return TetMesh(name=job.name, nodes=nodes, tets=tets, faces=faces, size=from_cad(job.size), source=source)


def mesh_solid(
    shape,
    *,
    name: str = "part",
    axis=None,
    size: float | None = None,
    curvature_elements: int = 8,
    refine: float = 0.25,
    timeout: float | None = None,
    progress: Callable[[str, float | None], None] | None = None,
    field: str = "size",
) -> TetMesh:
    """Mesh a shaft part's solid into curved 10-node tetrahedra (module docstring: the steps).

    Parameters
    ----------
    shape : build123d Shape, str or Path
        One closed solid (build123d's millimetres, as :mod:`geometry.parts` builds them), or a STEP or
        BREP file (read by :mod:`geometry.cadio`).
    name : str
        The part's name, for the mesh and for messages.
    axis : AxisSpec, (origin, direction) or mapping, optional
        The shaft axis in m, as for :func:`geometry.slicing.sections`; found when omitted (then x
        starts at 0 at the part's lower end, as its section table's stations do).
    size : float, optional
        The global (largest) element size, m: the size of the elements in the bulk (at most the
        diagonal of the part's bounding box: a larger one meshes as that). Default
        :func:`default_size`: V / S, half the part's mean thickness 2V/S (two elements across a
        tube's wall).
    curvature_elements : int
        Elements per 2π of a curved face or edge (a bolt hole's circle gets at least this many),
        the size growing back to ``size`` away from the face (:mod:`geometry.meshsize`); 0 leaves
        curvature out.
    refine : float
        The element size at a diameter step's inner corner, as a fraction of ``size`` (growing back
        to ``size`` over 2·``size``); 1 leaves it out.
    timeout : float, optional
        Seconds the meshing may take, default :data:`TIMEOUT_S`.
    progress : callable, optional
        ``progress(stage, fraction)`` at each stage: ``stage`` a phrase (``"meshing the volume"``),
        ``fraction`` the rough share of the work done by then (0 to 1; the volume mesh and the
        second order take most), or None before the meshing starts (reading, finding the axis).
    field : str
        What ``size`` is called in messages: a model file's ``mesh_size``.

    Returns
    -------
    TetMesh
        Nodes in m in the part's frame, tetrahedra in VTK order (positively oriented), faces
        ``"start"`` and ``"end"`` (6-node triangles on the end planes, normals outward).

    Raises
    ------
    ModelError
        gmsh is missing (names the extra); the shape is not one closed solid, or a file cannot be
        read; an end of the part is not a plane normal to its axis; the mesh's estimated DOFs are
        surely above the solid DOF ceiling (refused before meshing, naming the smallest size that
        fits); gmsh fails, crashes or runs out of time; an element is inverted.
    """
    report = progress if progress is not None else (lambda stage, fraction: None)
    job, source, raw = _in_child(
        shape, name, axis, size, curvature_elements, refine, timeout, report, field=field, estimate_only=False
    )
    report("converting the mesh", 0.95)
    mesh = _to_mesh(raw, job, source)
    report("done", 1.0)
    return mesh


def estimate_mesh(
    shape,
    *,
    name: str = "part",
    axis=None,
    size: float | None = None,
    curvature_elements: int = 8,
    refine: float = 0.25,
    timeout: float | None = None,
) -> MeshEstimate:
    """What :func:`mesh_solid` would make of a part, estimated before meshing (in about a second).

    The parameters are :func:`mesh_solid`'s. The solid DOF ceiling is not applied.

    Returns
    -------
    MeshEstimate
        Elements, surface triangles, nodes and DOFs (within
        :data:`~geometry.meshsize.ESTIMATE_FACTOR` of the mesh's on the parts the tests mesh), and
        the global size in m.

    Raises
    ------
    ModelError
        As :func:`mesh_solid` before it meshes.
    """
    job, _, raw = _in_child(
        shape, name, axis, size, curvature_elements, refine, timeout, lambda *a: None, estimate_only=True
    )
    return replace(raw["estimate"], size=from_cad(job.size))


def _in_child(
    shape, name, axis, size, curvature_elements, refine, timeout, report, *, estimate_only, field="size"
):
    """Check the options, put the part in its frame, and run :func:`_run_gmsh` in a forked child:
    (the job, the source's description, what the child returned)."""
    gmsh = _gmsh(name)
    try:
        if size is not None:
            size = check_real(size, "size", "m", lo=0.0, lo_open=True)
        curvature_elements = check_int(curvature_elements, "curvature_elements", lo=0, hi=1000)
        refine = check_real(refine, "refine", "", lo=0.0, lo_open=True, hi=1.0)
        limit = TIMEOUT_S if timeout is None else check_real(timeout, "timeout", "s", lo=0.0, lo_open=True)
    except ModelError as err:
        raise err.located(component=name) from None
    max_dofs = ceiling("solid_dofs")  # read here: a bad FLEXSHAFT_MAX_SOLID_DOFS is refused before meshing
    report("reading the part", None)
    shape, source = _source_shape(shape, name)
    report("finding the axis", None)
    import build123d as bd

    from flexshaft.system.isolate import Failure, run_isolated

    from .slicing import brep
    from .slicing.solid import part_frame

    frame = part_frame(shape, axis=axis, name=name)
    solid = frame.solid
    bb = solid.bounding_box()
    largest_side = max(bb.size.X, bb.size.Y, bb.size.Z)
    diagonal = math.dist((bb.min.X, bb.min.Y, bb.min.Z), (bb.max.X, bb.max.Y, bb.max.Z))
    size_mm = to_cad(size) if size is not None else default_size(brep.volume_props(solid).volume, solid.area)
    # An element larger than the part is the part: a size beyond its bounding box's diagonal meshes as
    # that (gmsh and the estimate then see finite numbers, whatever was asked).
    size_mm = min(size_mm, diagonal)
    job = _Job(
        path="",
        name=name,
        size=size_mm,
        curvature_elements=curvature_elements,
        refine=refine,
        x_lo=bb.min.X,
        x_hi=bb.max.X,
        # the slicer's 1e-7 of the extent, and at least ten times OCCT's 1e-7 mm (gmsh widens its
        # bounding boxes by that): far below any feature
        tol=max(1e-7 * largest_side, 1e-6),
        x0=frame.x0,
        extent=diagonal,
        max_dofs=max_dofs,
        field=field,
        estimate_only=estimate_only,
    )

    def failed(failure: Failure) -> ModelError:
        return ModelError(
            f"gmsh {gmsh.__version__} could not mesh it into tetrahedra: {failure.reason}",
            component=name,
            field="geometry",
            value=source,
            valid="a valid closed solid (a larger size or fewer curvature_elements mesh faster; "
            "timeout sets the time allowed)",
        )

    with tempfile.TemporaryDirectory(prefix="flexshaft-mesh-") as tmp:
        path = os.path.join(tmp, "part.brep")
        bd.export_brep(solid, path)
        job = replace(job, path=path)
        raw = run_isolated(
            lambda send: _run_gmsh(job, send),
            timeout=limit,
            error=failed,
            on_message=report,
            memory=MEMORY_BYTES,
        )
    return job, source, raw
