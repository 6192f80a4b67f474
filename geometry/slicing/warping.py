"""St-Venant torsion and shear properties of a non-circular shaft section.

A thin, cached wrapper around the warping analysis of ``sectionproperties``
(six-node triangles, Pilkey's formulation) for the sections that are *not* a
plain circle or annulus: keyways, flats, splines, bolt-hole flanges. The input
is a shapely polygon in the y–z plane, in metres, measured from the shaft axis,
as cut from the CAD solid with its arcs discretised. The output is a frozen
:class:`WarpingResult` in SI units.

What it does, in order:

1. :func:`canonical_polygon` checks the polygon (type, validity, size, one
   connected region), snaps it to a 1 nm grid and normalises its orientation.
   The snapped polygon is what is analysed *and* what keys the cache, so two
   identical flanges at different axial positions share one analysis.
2. :func:`mesh_input` turns the target element count into Triangle's maximum
   element *area* (``sectionproperties``' ``mesh_sizes`` is an area, not a
   length) and inserts collinear points along the edges next to re-entrant
   corners (keyway and spline roots), geometrically graded, so that Triangle
   grades the mesh into the stress singularity there. The points lie on the
   edges: the shape is unchanged.
3. ``Geometry`` → ``create_mesh`` → ``Section`` →
   ``calculate_geometric_properties`` → ``calculate_warping_properties``; no
   plastic or stress analysis, no plotting, no progress output.

Accuracy and cost (2-core development machine, shared, so times ±30 %; default settings:
``mesh_elements=200``, minimum angle 20°, corner grading down to 1/32 of the element size; J
error against the same polygon meshed with ~30 000 elements at 30°):

=============================================  ========  ========  =======  ======
section (polygon: segments per circle/hole)    vertices  elements  J error  time
=============================================  ========  ========  =======  ======
D 100 mm, keyway 28 × 10 (128)                 121       516       +1.3e-4  0.2 s
D 20 mm, keyway 6 × 3.5 (128)                  119       508       +1.9e-4  0.2 s
two keyways, b/r = 0.25, a/b = 1 (256)         222       836       +3.1e-4  0.3 s
flange OD 550/bore 200, 12 × Ø33 (256/24)      800       2 176     +4.9e-4  0.8 s
same flange (128/32)                           640       1 892     +3.3e-4  0.65 s
same flange (128/16)                           448       1 318     +8.0e-4  0.6 s
flange 16 × Ø28 (128/16)                       512       1 514     +7.7e-4  0.55 s
flange 8 × Ø40 (64/16)                         256       766       +9.9e-4  0.35 s
=============================================  ========  ========  =======  ======

The cost is ~0.3 ms per element, spent in ``sectionproperties``' per-element Python
loops (numba, its optional accelerator, saves only ~20 % and compiles for 10 s on first
use). Below a few hundred target elements the element count is set by the polygon, not
by ``mesh_elements``: about 2.7 triangles per boundary vertex at a 20° minimum angle
(~5 at 30°, for ~half the error on hole-dominated meshes). So discretise arcs no finer
than needed and remove the faceting error with :func:`corrected`: 64-128 segments per
full circle leave 3e-3 ... 8e-4 in J before and ~1e-5 after correction. Bolt holes need
more care: their faceting error in J is about twice that in Ip (the shear stress doubles
at a hole's flanks), so :func:`corrected` removes only about half of it; 16-gon holes
leave +2e-3 after correction, 32-gon holes +5e-4 (12 × Ø33 flange above).
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexshaft.errors import ModelError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from shapely.geometry import MultiPolygon, Polygon

__all__ = [
    "DEFAULT_MESH_ELEMENTS",
    "MeshInput",
    "WarpingResult",
    "analysis_count",
    "canonical_polygon",
    "clear_cache",
    "corrected",
    "mesh_input",
    "preload",
    "warping_properties",
]

#: Default target element count: the maximum triangle area is ``area / DEFAULT_MESH_ELEMENTS``.
DEFAULT_MESH_ELEMENTS = 200
#: Triangle's minimum angle (degrees). ≤ 20.7° is guaranteed to terminate on any input;
#: 30° (the sectionproperties default) costs ~1.9× the elements on boundary-dominated meshes.
MIN_ANGLE_DEG = 20.0
#: A vertex whose material-side angle is at least this (degrees) is a re-entrant corner to grade
#: into; the vertices of a discretised hole (180° + 360°/n) stay below it for n > 6.
CORNER_ANGLE_DEG = 240.0
#: Graded points at h/2, h/4, ..., h/2**CORNER_LEVELS from each re-entrant corner (h: element size).
CORNER_LEVELS = 5
#: Coordinates are snapped to this grid (m) before analysis and caching.
GRID_M = 1e-9
#: Largest coordinate accepted (m); a section this large is almost surely in millimetres.
MAX_EXTENT_M = 10.0
#: Smallest section area accepted (m²), a 10 µm square; below it the 1 nm grid is too coarse.
MIN_AREA_M2 = 1e-10
#: Parts of a multipolygon smaller than this fraction of the total area are slivers, dropped.
SLIVER_FRACTION = 1e-9

_CACHE: dict[tuple[bytes, float, int], WarpingResult] = {}
_ANALYSES = 0


@dataclass(frozen=True)
class WarpingResult:
    """Section properties of one cross-section, SI units.

    Axes: y and z span the section plane, x is the shaft axis; the polygon's
    first coordinate is y, its second z.

    Attributes
    ----------
    area : float
        Area of the polygon, m².
    iy, iz, iyz : float
        Second moments about axes through the centroid parallel to y and z,
        ``∫(z − z_c)² dA``, ``∫(y − y_c)² dA`` and ``∫(y − y_c)(z − z_c) dA``, m⁴.
    centroid : tuple of float
        (y, z) of the centroid, m.
    ip_axis : float
        Polar second moment about the shaft axis (the origin), ``∫(y² + z²) dA``, m⁴.
    j : float
        St-Venant torsion constant, m⁴ (torsional stiffness per length is G·j).
    shear_area_y, shear_area_z : float
        Timoshenko shear areas for a shear force along y and along z, m², as
        defined by sectionproperties (energy-equivalent, for Poisson's ratio
        ``nu``; a solid circle gives κ = 6(1+ν)²/(7+14ν+8ν²)).
    shear_centre : tuple of float
        (y, z) of the shear centre (elasticity approach), m.
    nu : float
        Poisson's ratio the shear properties were computed for.
    mesh_elements : int
        Target element count that set the maximum triangle area.
    elements : int
        Number of six-node triangles actually used.
    seconds : float
        Wall time of the call that returned this result, s (small for a cache hit).
    cached : bool
        True when the result came from the cache.
    """

    area: float
    iy: float
    iz: float
    iyz: float
    centroid: tuple[float, float]
    ip_axis: float
    j: float
    shear_area_y: float
    shear_area_z: float
    shear_centre: tuple[float, float]
    nu: float
    mesh_elements: int
    elements: int
    seconds: float
    cached: bool = False

    @property
    def ip_centroid(self) -> float:
        """Polar second moment about the centroid, ``iy + iz``, m⁴."""
        return self.iy + self.iz

    @property
    def j_ratio(self) -> float:
        """``j / ip_axis``: 1 for a circle or annulus about its centre, less for anything else."""
        return self.j / self.ip_axis


@dataclass(frozen=True)
class MeshInput:
    """What is handed to sectionproperties' mesher.

    Attributes
    ----------
    polygon : shapely.geometry.Polygon
        The canonical polygon (:func:`canonical_polygon`), exterior counter-clockwise, with
        graded collinear points inserted next to re-entrant corners, m.
    max_area : float
        Maximum triangle area (sectionproperties' ``mesh_sizes``), m².
    min_angle : float
        Triangle's minimum angle, degrees.
    """

    polygon: Polygon
    max_area: float
    min_angle: float


def _polygon_error(message: str, valid: str | None = None) -> ModelError:
    return ModelError(
        message,
        field="polygon",
        valid=valid or "a valid shapely Polygon in the y-z plane, in metres, one connected region",
    )


def canonical_polygon(polygon: Polygon | MultiPolygon) -> Polygon:
    """Check a section polygon and return its canonical form.

    Parameters
    ----------
    polygon : shapely.geometry.Polygon or shapely.geometry.MultiPolygon
        The section in the y–z plane, coordinates in m measured from the
        shaft axis. A multipolygon is accepted when all but one of its parts
        are slivers (less than ``SLIVER_FRACTION`` of the area).

    Returns
    -------
    shapely.geometry.Polygon
        The polygon snapped to a ``GRID_M`` (1 nm) grid, repeated vertices
        removed, orientation and start vertex normalised
        (``shapely.normalize``). Equal sections give equal polygons whatever
        their start vertex, orientation or floating-point noise (a coordinate
        within the noise δ of a half-nanometre can round either way: a chance
        of 2δ / 1 nm per coordinate, 2e-8 for δ = 1e-17 m).

    Raises
    ------
    flexshaft.errors.ModelError
        Not a polygon, empty, with a third coordinate, non-finite, invalid
        (self-intersecting...), too large (millimetres?), of zero or tiny
        area, or of several disjoint regions.
    """
    import shapely
    from shapely.geometry import MultiPolygon, Polygon

    if not isinstance(polygon, Polygon | MultiPolygon):
        raise _polygon_error(f"expected a shapely Polygon or MultiPolygon, got {type(polygon).__name__}")
    if polygon.is_empty:
        raise _polygon_error("the section polygon is empty")
    if shapely.has_z(polygon):
        raise _polygon_error("the polygon has a third coordinate; pass (y, z) pairs in the section plane")
    coords = shapely.get_coordinates(polygon)
    if not np.all(np.isfinite(coords)):
        raise _polygon_error("the polygon has non-finite coordinates")
    if not polygon.is_valid:
        raise _polygon_error(f"invalid polygon: {shapely.is_valid_reason(polygon)}")
    extent = float(np.max(np.abs(coords)))
    if extent > MAX_EXTENT_M:
        raise _polygon_error(
            f"coordinates reach {extent:g} m from the axis (millimetres passed as metres?)",
            valid=f"coordinates in metres, |y|, |z| <= {MAX_EXTENT_M:g} m",
        )
    if polygon.area < MIN_AREA_M2:
        raise _polygon_error(
            f"the section area is {polygon.area:.3g} m²", valid=f"an area >= {MIN_AREA_M2:g} m²"
        )
    snapped = shapely.set_precision(polygon, GRID_M)
    parts = [g for g in shapely.get_parts(snapped) if isinstance(g, Polygon) and not g.is_empty]
    total = sum(p.area for p in parts)
    parts = [p for p in parts if p.area >= SLIVER_FRACTION * total]
    if not parts:
        raise _polygon_error("the section collapses to nothing on a 1 nm grid")
    if len(parts) > 1:
        raise _polygon_error(
            f"the section has {len(parts)} disjoint regions; a warping analysis needs one connected region"
        )
    return shapely.normalize(parts[0])


def _graded_ring(ring: np.ndarray, spacing: float, levels: int) -> np.ndarray:
    """A closed ring (material on its left) with graded points next to its re-entrant corners."""
    pts = ring[:-1]
    n = len(pts)
    incoming = pts - np.roll(pts, 1, axis=0)
    outgoing = np.roll(pts, -1, axis=0) - pts
    turn = np.degrees(
        np.arctan2(
            incoming[:, 0] * outgoing[:, 1] - incoming[:, 1] * outgoing[:, 0],
            np.einsum("ij,ij->i", incoming, outgoing),
        )
    )
    corner = 180.0 - turn >= CORNER_ANGLE_DEG  # material angle: a right turn is re-entrant
    if levels <= 0 or not corner.any():
        return ring
    offsets = spacing * 0.5 ** np.arange(1, levels + 1)
    out = []
    for i in range(n):
        a, b = pts[i], pts[(i + 1) % n]
        length = float(np.hypot(*(b - a)))
        ts: list[float] = []
        if corner[i]:
            ts += [d / length for d in offsets if d < 0.5 * length]
        if corner[(i + 1) % n]:
            ts += [1.0 - d / length for d in offsets if d < 0.5 * length]
        out.append(a)
        out.extend(a + t * (b - a) for t in sorted(ts))
    out.append(out[0])
    return np.asarray(out)


def mesh_input(polygon: Polygon | MultiPolygon, *, mesh_elements: int = DEFAULT_MESH_ELEMENTS) -> MeshInput:
    """The polygon, maximum triangle area and minimum angle that the analysis meshes.

    Parameters
    ----------
    polygon : shapely.geometry.Polygon or shapely.geometry.MultiPolygon
        The section, m (see :func:`canonical_polygon`).
    mesh_elements : int, optional
        Target element count; the maximum triangle area is ``area / mesh_elements`` (m²).
        The mesh is finer where the polygon's edges are short.

    Returns
    -------
    MeshInput
        Polygon with graded points next to re-entrant corners, ``max_area`` in m²,
        ``min_angle`` in degrees.
    """
    from shapely.geometry import Polygon
    from shapely.geometry.polygon import orient

    _check_mesh_elements(mesh_elements)
    canon = orient(canonical_polygon(polygon), 1.0)
    max_area = canon.area / mesh_elements
    spacing = math.sqrt(2.0 * max_area)  # leg of a right isosceles triangle of that area
    shell = _graded_ring(np.asarray(canon.exterior.coords), spacing, CORNER_LEVELS)
    holes = [_graded_ring(np.asarray(r.coords), spacing, CORNER_LEVELS) for r in canon.interiors]
    return MeshInput(Polygon(shell, holes), max_area, MIN_ANGLE_DEG)


def _check_mesh_elements(mesh_elements: object) -> None:
    if (
        isinstance(mesh_elements, bool)
        or not isinstance(mesh_elements, int | np.integer)
        or not 1 <= mesh_elements <= 10**6
    ):
        raise ModelError(
            "", field="mesh_elements", value=mesh_elements, has_value=True, valid="an integer 1 ... 1000000"
        )


def _check_nu(nu: object) -> float:
    if isinstance(nu, bool) or not isinstance(nu, int | float | np.number) or not -1.0 < float(nu) < 0.5:
        raise ModelError(
            "Poisson's ratio", field="nu", value=nu, has_value=True, valid="a number, -1 < nu < 0.5"
        )
    return float(nu)


def _analyse(mi: MeshInput, nu: float) -> dict:
    """Run sectionproperties' geometric and warping analyses on a prepared mesh input."""
    global _ANALYSES
    from sectionproperties.analysis.section import Section
    from sectionproperties.pre.geometry import Geometry
    from sectionproperties.pre.pre import Material

    # E = 1 makes the modulus-weighted ("e") getters return plain geometric values; the
    # material must differ from sectionproperties' DEFAULT_MATERIAL, or the shear functions
    # are solved with nu = 0 whatever is asked.
    material = Material("flexshaft", 1.0, nu, 1.0, 1.0, "w")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        geom = Geometry(mi.polygon, material=material)
        geom.create_mesh(mesh_sizes=mi.max_area, min_angle=mi.min_angle)
        section = Section(geom, time_info=False)
        section.calculate_geometric_properties()
        section.calculate_warping_properties(solver_type="direct")
    _ANALYSES += 1
    ixx_g, iyy_g, _ = section.get_eig()
    ixx_c, iyy_c, ixy_c = section.get_eic()
    a_sx, a_sy = section.get_eas()
    out = {
        "area": section.get_area(),
        "iy": ixx_c,  # sectionproperties' (x, y) are our (y, z): its ixx = ∫z² dA
        "iz": iyy_c,
        "iyz": ixy_c,
        "centroid": tuple(float(c) for c in section.get_c()),
        "ip_axis": ixx_g + iyy_g,
        "j": section.get_ej(),
        "shear_area_y": a_sx,  # a_sx: shear force along sectionproperties' x, our y
        "shear_area_z": a_sy,
        "shear_centre": tuple(float(c) for c in section.get_sc()),
        "elements": len(section.elements),
    }
    values = [v for k, v in out.items() if k != "elements"]
    if not np.all(np.isfinite(np.hstack(values))) or out["j"] <= 0.0:
        why = "; ".join(sorted({str(w.message).split("\n")[0] for w in caught})) or "non-finite result"
        raise _polygon_error(f"the warping analysis failed ({why}); slivers or near-touching edges?")
    return {k: (v if k in ("centroid", "shear_centre", "elements") else float(v)) for k, v in out.items()}


def warping_properties(
    polygon: Polygon | MultiPolygon,
    *,
    nu: float,
    mesh_elements: int = DEFAULT_MESH_ELEMENTS,
    cache: bool = True,
) -> WarpingResult:
    """St-Venant torsion constant, shear areas and area properties of a section.

    Parameters
    ----------
    polygon : shapely.geometry.Polygon or shapely.geometry.MultiPolygon
        The section in the y–z plane, coordinates in m measured from the
        shaft axis (first coordinate y, second z); one connected region,
        holes allowed.
    nu : float
        Poisson's ratio (-); the shear areas and shear centre depend on it, J does not.
    mesh_elements : int, optional
        Target element count: the maximum triangle area is ``area / mesh_elements`` (m²).
        The default (200) gives J within ~5e-4 of the converged value of the polygon for
        keyed shafts and bolt-hole flanges; see the module docstring.
    cache : bool, optional
        Look up and store the result in the module cache. The key is the canonical
        polygon (1 nm grid, normalised orientation), ``nu`` and ``mesh_elements``.

    Returns
    -------
    WarpingResult
        Properties in SI units.

    Raises
    ------
    flexshaft.errors.ModelError
        Invalid polygon (see :func:`canonical_polygon`), ``nu`` or ``mesh_elements``.
    """
    t0 = time.perf_counter()
    nu = _check_nu(nu)
    _check_mesh_elements(mesh_elements)
    key = None
    if cache:
        key = (canonical_polygon(polygon).wkb, nu, int(mesh_elements))
        hit = _CACHE.get(key)
        if hit is not None:
            return dataclasses.replace(hit, seconds=time.perf_counter() - t0, cached=True)
    props = _analyse(mesh_input(polygon, mesh_elements=mesh_elements), nu)
    result = WarpingResult(**props, nu=nu, mesh_elements=int(mesh_elements), seconds=time.perf_counter() - t0)
    if key is not None:
        _CACHE[key] = result
    return result


def corrected(result: WarpingResult, exact_area: float, exact_ip_axis: float) -> WarpingResult:
    """Remove the faceting error of a polygonised section with its exact area and polar moment.

    Arcs cut into chords lose material at the rim, where it counts most. For a
    circle or annulus J equals the polar moment, so the polygon's J is wrong by
    the same factor as its polar moment, to first order in the chord sag; the
    same holds for any section whose faceted parts are arcs about the axis. So
    ``j`` and the second moments are scaled by ``exact_ip_axis / ip_axis`` and
    the shear areas by ``exact_area / area``. Faceted holes off the axis (bolt
    holes) change J about twice as much as Ip, so for them this removes only
    about half the faceting error (see the module notes).

    Parameters
    ----------
    result : WarpingResult
        Result for the polygon.
    exact_area : float
        Exact area of the section (e.g. from the B-rep), m².
    exact_ip_axis : float
        Exact polar second moment about the shaft axis, m⁴.

    Returns
    -------
    WarpingResult
        A copy with ``area``, ``ip_axis``, ``iy``, ``iz``, ``iyz``, ``j``,
        ``shear_area_y`` and ``shear_area_z`` scaled; centroid and shear centre unchanged.

    Raises
    ------
    flexshaft.errors.ModelError
        An exact value not positive and finite, or more than 10 % from the polygon's
        (not the same section, or other units).
    """
    checks = (
        ("exact_area", exact_area, result.area, "m²"),
        ("exact_ip_axis", exact_ip_axis, result.ip_axis, "m⁴"),
    )
    for name, exact, poly, unit in checks:
        ok = isinstance(exact, int | float | np.number) and math.isfinite(exact) and exact > 0
        if not ok or not 0.9 <= exact / poly <= 1.1:
            raise ModelError(
                f"the polygon's value is {poly:.6g} {unit}",
                field=name,
                value=exact,
                unit=unit,
                valid="the exact value of the same section, within 10 % of the polygon's",
            )
    s_ip = exact_ip_axis / result.ip_axis
    s_a = exact_area / result.area
    return dataclasses.replace(
        result,
        area=float(exact_area),
        ip_axis=float(exact_ip_axis),
        iy=result.iy * s_ip,
        iz=result.iz * s_ip,
        iyz=result.iyz * s_ip,
        j=result.j * s_ip,
        shear_area_y=result.shear_area_y * s_a,
        shear_area_z=result.shear_area_z * s_a,
    )


def preload() -> None:
    """Import sectionproperties' analysis modules now rather than in the first analysis.

    ``import sectionproperties`` alone loads nothing; its ``pre.geometry`` and
    ``analysis.section`` modules pull in matplotlib and take ~0.7 s, which
    otherwise lands in the first result's ``seconds``. Call this where imports
    are timed (a benchmark's import stage, a CLI start-up that will need it).
    """
    import sectionproperties.analysis.section  # noqa: F401
    import sectionproperties.pre.geometry  # noqa: F401


def clear_cache() -> None:
    """Empty the result cache and reset :func:`analysis_count` to zero."""
    global _ANALYSES
    _CACHE.clear()
    _ANALYSES = 0


def analysis_count() -> int:
    """Number of sectionproperties analyses run since import or the last :func:`clear_cache`."""
    return _ANALYSES
