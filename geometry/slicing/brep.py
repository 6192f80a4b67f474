"""Low-level reads of an OCCT B-rep: mass properties, faces, planar sections.

Everything here works in build123d's millimetres; :mod:`geometry.slicing.solid`
converts to SI once, through :mod:`geometry.units`. Only this module and
:func:`geometry.cadio.write_stl` (clearing a cached triangulation) touch OCP directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import build123d as bd
import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.GCPnts import GCPnts_TangentialDeflection
from OCP.GeomAbs import (
    GeomAbs_Circle,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_Line,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_Torus,
)
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopoDS import TopoDS

from flexshaft.errors import ModelError

from .common import merge_stations
from .frames import axis_frame
from .polygons import PolygonMoments

__all__ = [
    "VolumeProps",
    "as_solid",
    "volume_props",
    "aligned",
    "revolution_axis",
    "breakpoints",
    "prismatic_intervals",
    "section_faces",
    "face_props",
    "round_radii",
    "face_rings",
]


@dataclass(frozen=True)
class VolumeProps:
    """Volume (mm³), centre of volume (mm) and the second-moment matrix about it (mm⁵)."""

    volume: float
    centre: np.ndarray
    inertia: np.ndarray


def as_solid(shape: object, *, name: str = "part") -> bd.Solid:
    """The one valid, closed solid in ``shape``, or a :class:`ModelError` saying why not."""
    if isinstance(shape, bd.Solid):
        solids = [shape]
    elif isinstance(shape, bd.Shape):
        solids = list(shape.solids())
    else:
        raise ModelError(
            "is not a CAD shape",
            component=name,
            field="geometry",
            value=type(shape).__name__,
            has_value=True,
            valid="a build123d Part/Solid, a STEP/BREP file or a watertight STL",
        )
    if len(solids) != 1:
        kinds = "no solid (a surface, wire or empty shape)" if not solids else f"{len(solids)} solids"
        raise ModelError(
            f"holds {kinds}",
            component=name,
            field="geometry",
            valid="exactly one closed solid (fuse the pieces of a part first)",
        )
    solid = solids[0]
    if not BRepCheck_Analyzer(solid.wrapped).IsValid():
        raise ModelError(
            "is not a valid solid (BRepCheck failed: self-intersecting or broken faces)",
            component=name,
            field="geometry",
            valid="a valid closed solid",
        )
    shells = solid.shells()
    if not shells or not all(BRep_Tool.IsClosed_s(s.wrapped) for s in shells):
        raise ModelError(
            "is not closed (open shell)", component=name, field="geometry", valid="a closed solid"
        )
    if not solid.volume > 0.0:
        raise ModelError(
            "has no volume", component=name, field="geometry", value=solid.volume, unit="mm³", valid="> 0"
        )
    return solid


def volume_props(solid: bd.Shape) -> VolumeProps:
    """Volume, centre and centroidal second-moment matrix (∫ r² dV form) of a solid, mm units."""
    props = GProp_GProps()
    # Adaptive integration: the default fixed rule is ~4e-6 off on faces bounded by B-spline edges.
    BRepGProp.VolumeProperties_s(solid.wrapped, props, 1e-9, False)
    c = props.CentreOfMass()
    m = props.MatrixOfInertia()
    inertia = np.array([[m.Value(i, j) for j in (1, 2, 3)] for i in (1, 2, 3)])
    return VolumeProps(volume=props.Mass(), centre=np.array([c.X(), c.Y(), c.Z()]), inertia=inertia)


def aligned(solid: bd.Solid, origin: np.ndarray, direction: np.ndarray) -> bd.Solid:
    """The solid in coordinates whose x axis is the line (origin, direction), mm."""
    d, _, z = axis_frame(direction)
    plane = bd.Plane(origin=tuple(origin), x_dir=tuple(d), z_dir=tuple(z))
    out = plane.to_local_coords(solid)
    return out if isinstance(out, bd.Solid) else out.solids()[0]


def _surface_axis(adaptor: BRepAdaptor_Surface) -> tuple[int, np.ndarray | None, np.ndarray | None]:
    kind = adaptor.GetType()
    getter = {
        GeomAbs_Plane: "Plane",
        GeomAbs_Cylinder: "Cylinder",
        GeomAbs_Cone: "Cone",
        GeomAbs_Torus: "Torus",
        GeomAbs_Sphere: "Sphere",
    }.get(kind)
    if getter is None:
        return kind, None, None
    ax = getattr(adaptor, getter)().Position()
    d, p = ax.Direction(), ax.Location()
    return kind, np.array([d.X(), d.Y(), d.Z()]), np.array([p.X(), p.Y(), p.Z()])


def revolution_axis(solid: bd.Solid, approx: np.ndarray, max_angle: float = 0.1):
    """The axis of the largest surface of revolution roughly along ``approx``: (point, direction), mm.

    A turned part's cylinders, cones and tori share one axis exactly, while
    its principal axes of inertia tilt as soon as a keyway or a flat breaks
    the symmetry; so the axis is read off the B-rep where it can be. Returns
    None when no such face lies within ``max_angle`` rad of ``approx``.
    """
    best, best_area = None, 0.0
    a = np.asarray(approx, float) / np.linalg.norm(approx)
    for f in solid.faces():
        kind, d, p = _surface_axis(BRepAdaptor_Surface(f.wrapped))
        if kind not in (GeomAbs_Cylinder, GeomAbs_Cone, GeomAbs_Torus) or d is None:
            continue
        if abs(float(d @ a)) < math.cos(max_angle):
            continue
        area = f.area
        if area > best_area:
            best, best_area = (p, d if d @ a > 0 else -d), area
    return best


def _x_range(face: bd.Face) -> tuple[float, float]:
    bb = face.bounding_box(optimal=True)
    return bb.min.X, bb.max.X


def breakpoints(solid: bd.Solid, tol: float) -> np.ndarray:
    """Axial stations where the section can change: every vertex and every face's x-extent, mm.

    Steps, flange faces, keyway ends and hole ends are vertices or planar faces
    of the B-rep, so they are found exactly rather than by sampling. Stations
    closer than ``tol`` are merged.
    """
    xs = [v.X for v in solid.vertices()]
    for f in solid.faces():
        xs.extend(_x_range(f))
    return merge_stations(np.sort(np.asarray(xs)), tol)


def prismatic_intervals(solid: bd.Solid, stations: np.ndarray, tol: float) -> np.ndarray:
    """For each interval between ``stations``: True where the section is the same all along it.

    An interval is prismatic when every face crossing it is a plane containing
    the x direction or a cylinder parallel to x (shaft bodies, bores, bolt
    holes, keyway sides and floors). Cones (chamfers), tori (fillets), spheres,
    radial holes and free-form faces make the section vary.
    """
    ok = np.ones(stations.size - 1, dtype=bool)
    ex = np.array([1.0, 0.0, 0.0])
    for f in solid.faces():
        lo, hi = _x_range(f)
        inside = (stations[1:] > lo + tol) & (stations[:-1] < hi - tol)
        if not inside.any():
            continue
        kind, d, _ = _surface_axis(BRepAdaptor_Surface(f.wrapped))
        if kind == GeomAbs_Plane and abs(float(d @ ex)) < 1e-9:
            continue
        if kind == GeomAbs_Cylinder and abs(abs(float(d @ ex)) - 1.0) < 1e-12:
            continue
        ok &= ~inside
    return ok


def section_faces(solid: bd.Solid, x: float) -> list[bd.Face]:
    """The planar section of the solid at x (mm): its faces in the plane x = const."""
    plane = bd.Plane(origin=(x, 0.0, 0.0), x_dir=(0.0, 1.0, 0.0), z_dir=(1.0, 0.0, 0.0))
    result = solid.intersect(plane)
    if result is None:
        return []
    return [f for f in (result.faces() if hasattr(result, "faces") else []) if f.area > 0.0]


def face_props(face: bd.Face) -> PolygonMoments:
    """Exact area, centroid and centroidal second moments of a section face (OCCT GProp, mm units)."""
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face.wrapped, props)
    c = props.CentreOfMass()
    m = props.MatrixOfInertia()
    # OCCT's matrix is ∫(r² δ - r rᵀ): in a plane x = const, M22 = ∫z², M33 = ∫y², M23 = -∫yz.
    return PolygonMoments(
        area=props.Mass(), yc=c.Y(), zc=c.Z(), iy=m.Value(2, 2), iz=m.Value(3, 3), iyz=-m.Value(2, 3)
    )


def _ordered_edges(wire: bd.Wire, face: bd.Face):
    explorer = BRepTools_WireExplorer(TopoDS.Wire(wire.wrapped), TopoDS.Face(face.wrapped))
    while explorer.More():
        yield explorer.Current()
        explorer.Next()


def round_radii(face: bd.Face, tol: float) -> tuple[float, float] | None:
    """(outer, inner) radii if the face is a circle or annulus centred on the axis, else None (mm).

    Every edge of the outer wire (and of the single inner wire, if any) must be
    a circular arc of one radius about a centre within ``tol`` of the axis.
    """
    wires = [face.outer_wire(), *face.inner_wires()]
    if len(wires) > 2:
        return None
    radii = []
    for w in wires:
        r = None
        for e in w.edges():
            c = BRepAdaptor_Curve(e.wrapped)
            if c.GetType() != GeomAbs_Circle:
                return None
            circ = c.Circle()
            p = circ.Location()
            if math.hypot(p.Y(), p.Z()) > tol:
                return None
            if r is not None and abs(circ.Radius() - r) > tol:
                return None
            r = circ.Radius()
        radii.append(r)
    return radii[0], (radii[1] if len(radii) == 2 else 0.0)


def _arc_points(c: BRepAdaptor_Curve, reverse: bool, step: float) -> list[tuple[float, float]]:
    """Points of a circular arc in the plane x = const, on a grid of absolute angles about its centre.

    Sampling at angles k·Δφ measured from +y (not from the edge's own
    parameter origin, which OCCT puts wherever the seam happens to be) makes
    two equal sections give the same polygon point for point, so the warping
    cache recognises them. The arc's end points are kept exactly.
    """
    circ = c.Circle()
    centre = circ.Location()
    cy, cz, r = centre.Y(), centre.Z(), circ.Radius()
    t0, t1 = c.FirstParameter(), c.LastParameter()
    if reverse:
        t0, t1 = t1, t0
    p0, p1, pm = c.Value(t0), c.Value(t1), c.Value(0.5 * (t0 + t1))
    phi0 = math.atan2(p0.Z() - cz, p0.Y() - cy)
    phim = math.atan2(pm.Z() - cz, pm.Y() - cy)
    sense = 1.0 if math.sin(phim - phi0) > 0 else -1.0  # walking direction in the y-z plane
    span = abs(t1 - t0)
    # At least 16 points on a full circle so that small holes stay round.
    n_full = max(16, math.ceil(2 * math.pi * r / step))
    dphi = 2 * math.pi / n_full
    if span > 2 * math.pi - 1e-9:
        # A whole circle: its seam is no corner of the section, so only grid points.
        return [(cy + r * math.cos(k * dphi), cz + r * math.sin(k * sense * dphi)) for k in range(n_full)]
    pts = [(p0.Y(), p0.Z())]
    k = math.floor(phi0 / dphi) if sense > 0 else math.ceil(phi0 / dphi)
    while True:
        k += int(sense)
        phi = k * dphi
        travelled = (phi - phi0) * sense
        if travelled >= span - 1e-9 * dphi:
            break
        if travelled > 1e-9 * dphi:
            pts.append((cy + r * math.cos(phi), cz + r * math.sin(phi)))
    del p1  # the next edge starts there
    return pts


def _wire_points(wire: bd.Wire, face: bd.Face, step: float) -> np.ndarray:
    """Ordered (y, z) points around a wire, arcs at about ``step`` mm, straight edges exact."""
    pts: list[tuple[float, float]] = []
    for edge in _ordered_edges(wire, face):
        c = BRepAdaptor_Curve(edge)
        reverse = edge.Orientation() == TopAbs_REVERSED
        kind = c.GetType()
        if kind == GeomAbs_Circle:
            pts.extend(_arc_points(c, reverse, step))
            continue
        t0, t1 = c.FirstParameter(), c.LastParameter()
        if kind == GeomAbs_Line:
            ts = np.array([t0, t1])
        else:
            sampler = GCPnts_TangentialDeflection(c, 2 * math.pi / 96, step / 50.0)
            ts = np.array([sampler.Parameter(i) for i in range(1, sampler.NbPoints() + 1)])
        if reverse:
            ts = ts[::-1]
        for t in ts[:-1]:
            p = c.Value(float(t))
            pts.append((p.Y(), p.Z()))
    return np.asarray(pts)


def face_rings(face: bd.Face, points_per_circle: int = 128) -> tuple[np.ndarray, list[np.ndarray]]:
    """The face as polygon rings in (y, z), mm: (exterior, [holes]).

    Arcs are cut into chords of about 2π R / ``points_per_circle`` where R is
    the face's outer radius, so the largest circle gets ``points_per_circle``
    points and small holes proportionally fewer (never below 16).
    """
    bb = face.bounding_box()
    radius = max(abs(bb.min.Y), abs(bb.max.Y), abs(bb.min.Z), abs(bb.max.Z))
    step = 2 * math.pi * radius / points_per_circle
    outer = _wire_points(face.outer_wire(), face, step)
    holes = [_wire_points(w, face, step) for w in face.inner_wires()]
    return outer, holes
