"""Slice a shaft solid along its axis into a :class:`~flexshaft.sections.SectionTable`.

The breakpoints come from the B-rep (vertices and face extents), so diameter
steps, flange faces and keyway ends are exact. Between two breakpoints a
section is either constant (every face crossing the interval is parallel to
the axis: one mid-slice is exact) or varies (chamfers, fillets: the interval
is cut into ``taper_divisions`` pieces, each taken at its mid-section).
A circle or annulus on the axis gets the closed forms; any other section
gets exact area moments from the B-rep and the St-Venant torsion constant and
shear areas from sectionproperties' warping analysis of its polygon, once per
distinct shape.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from flexshaft.errors import ModelError
from flexshaft.sections import SectionTable, annulus_properties, shear_definition_ratio

from ..units import area_from_cad, from_cad, moment_from_cad, to_cad, volume_from_cad, volume_moment_from_cad
from . import brep
from .polygons import polygon_moments, roundness

__all__ = ["AxisSpec", "MassCheck", "sections", "find_axis", "SYMMETRY_TOL", "MAX_OFFSET", "MIN_FILL"]

#: Two principal moments within this relative difference count as equal (an axis of symmetry).
SYMMETRY_TOL = 0.05
#: A section's centroid may sit at most this fraction of its outer radius off the axis.
MAX_OFFSET = 0.10
#: A section must fill at least this fraction of its circumscribed circle about the axis.
MIN_FILL = 0.60


@dataclass(frozen=True)
class AxisSpec:
    """The shaft axis: a point on it and its direction (SI, m)."""

    origin: tuple[float, float, float]
    direction: tuple[float, float, float]
    found: bool = False

    @staticmethod
    def of(value: object, *, name: str = "part") -> AxisSpec:
        """Read an axis from ``AxisSpec``, ``(origin, direction)`` or a mapping with those keys."""
        if isinstance(value, AxisSpec):
            return value
        try:
            if isinstance(value, dict):
                unknown = set(value) - {"origin", "direction"}
                if unknown:
                    raise ModelError(
                        "unknown key",
                        component=name,
                        field=f"axis.{sorted(unknown)[0]}",
                        valid="origin (m), direction",
                    )
                origin, direction = value.get("origin", (0.0, 0.0, 0.0)), value["direction"]
            else:
                origin, direction = value
            o = np.asarray(origin, float).reshape(3)
            d = np.asarray(direction, float).reshape(3)
        except (KeyError, ValueError, TypeError):
            raise ModelError(
                "is not an axis",
                component=name,
                field="axis",
                value=value,
                has_value=True,
                valid="{origin = [x, y, z] (m), direction = [dx, dy, dz]}",
            ) from None
        if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))) or np.linalg.norm(d) == 0.0:
            raise ModelError(
                "needs a finite origin and a non-zero direction",
                component=name,
                field="axis",
                value=value,
                has_value=True,
                valid="finite numbers, direction not all zero",
            )
        d = d / np.linalg.norm(d)
        return AxisSpec(tuple(o.tolist()), tuple(d.tolist()))


@dataclass(frozen=True)
class MassCheck:
    """The section table's integrals against the solid's own mass properties (SI).

    ``volume`` in m³ and ``axial_moment`` = ∫ r² dV about the shaft axis in m⁵
    (times the density it is the axial mass moment of inertia).
    """

    volume_table: float
    volume_solid: float
    axial_moment_table: float
    axial_moment_solid: float

    @property
    def volume_error(self) -> float:
        """Relative error of the table's volume (and mass)."""
        return self.volume_table / self.volume_solid - 1.0

    @property
    def axial_moment_error(self) -> float:
        """Relative error of the table's axial inertia."""
        return self.axial_moment_table / self.axial_moment_solid - 1.0


def find_axis(solid, *, name: str = "part") -> AxisSpec:
    """The axis of near-rotational symmetry of a solid.

    A shaft has two equal principal moments of inertia (within
    :data:`SYMMETRY_TOL`); the third principal direction is roughly its axis.
    The exact axis is then that of the largest cylinder, cone or torus face
    along it (a keyway tilts the principal axes, not the turned faces).
    Raises :class:`ModelError` when no two moments agree (not a shaft) or all
    three do (no preferred axis: give it explicitly).
    """
    props = brep.volume_props(solid)
    ax = axis_from_inertia(volume_moment_from_cad(props.inertia), from_cad(props.centre), name=name)
    exact = brep.revolution_axis(solid, np.asarray(ax.direction))
    if exact is None:  # no turned faces (a polygon shaft): its principal axis is its axis
        return ax
    point, d = exact
    d = d / np.linalg.norm(d)
    d = d if d[int(np.argmax(np.abs(d)))] > 0 else -d
    # The point on that line nearest the centroid, so stations start near the part.
    c = props.centre
    origin = point + np.dot(c - point, d) * d
    return AxisSpec(tuple(from_cad(origin).tolist()), tuple(d.tolist()), found=True)


def axis_from_inertia(inertia: np.ndarray, centre: np.ndarray, *, name: str = "part") -> AxisSpec:
    """The symmetry axis from a centroidal ∫(r²·1 − r rᵀ) dV matrix (m⁵) and the centroid (m)."""
    w, v = np.linalg.eigh(inertia)
    rel = lambda a, b: abs(a - b) / max(a, b)  # noqa: E731
    d01, d12 = rel(w[0], w[1]), rel(w[1], w[2])
    moments = ", ".join(f"{m:.4g}" for m in w)
    if d01 <= SYMMETRY_TOL and d12 <= SYMMETRY_TOL:
        raise ModelError(
            f"has no preferred axis (principal moments {moments} m⁵ all about equal)",
            component=name,
            field="axis",
            valid="give the axis explicitly: {origin = [x, y, z] (m), direction = [dx, dy, dz]}",
        )
    if min(d01, d12) > SYMMETRY_TOL:
        raise ModelError(
            f"is not a shaft: no axis of near-rotational symmetry (principal moments {moments} m⁵)",
            component=name,
            field="geometry",
            valid=f"a straight shaft: two principal moments within {SYMMETRY_TOL:.0%}",
        )
    d = v[:, 2] if d01 < d12 else v[:, 0]
    # Keep a part drawn along +x (or +y, +z) pointing the way it was drawn.
    d = d if d[int(np.argmax(np.abs(d)))] > 0 else -d
    return AxisSpec(tuple(np.asarray(centre, float).tolist()), tuple(d.tolist()), found=True)


def check_section(exterior: np.ndarray, offset: float, where: str, name: str) -> None:
    """Refuse a section that is not near-round about the axis (a bent, eccentric or flat body).

    ``exterior`` is the outer ring in (y, z), m; ``offset`` the centroid's
    distance from the axis, m.
    """
    enclosed = abs(polygon_moments(exterior).area)
    r_max, fill = roundness(exterior, enclosed)
    if offset > MAX_OFFSET * r_max or fill < MIN_FILL:
        raise ModelError(
            f"is not a straight shaft about its axis: {where} has its centroid {offset:.4g} m "
            f"({offset / r_max:.0%} of its outer radius {r_max:.4g} m) off the axis and fills "
            f"{fill:.0%} of its circle",
            component=name,
            field="geometry",
            valid=f"a straight, near-axisymmetric shaft (centroid within {MAX_OFFSET:.0%} of the "
            f"radius, fill >= {MIN_FILL:.0%}); give `axis` if the found one is wrong",
        )


def _interval_plan(stations: np.ndarray, prismatic: np.ndarray, divisions: int) -> np.ndarray:
    """Slice stations: breakpoints, with each varying interval cut into ``divisions`` pieces."""
    xs = [stations[0]]
    for a, b, flat in zip(stations[:-1], stations[1:], prismatic):
        pieces = 1 if flat else divisions
        xs.extend(np.linspace(a, b, pieces + 1)[1:])
    return np.asarray(xs)


def sections(
    shape,
    *,
    axis=None,
    nu: float = 0.29,
    name: str = "part",
    taper_divisions: int = 6,
    points_per_circle: int = 128,
    progress: Callable[[int, int], None] | None = None,
    unit: str | None = None,
) -> SectionTable:
    """The section table of a straight shaft solid.

    Parameters
    ----------
    shape : build123d Shape, trimesh.Trimesh, str or Path
        One closed solid (build123d's millimetres, as build123d makes them),
        a watertight mesh in metres (see :func:`geometry.io.read_mesh`), or
        a part file to read with :func:`geometry.io.read_cad`.
    axis : AxisSpec, (origin, direction) or mapping, optional
        The shaft axis in SI metres. If omitted it is found (:func:`find_axis`:
        the principal axes of inertia, made exact by the turned faces) and the
        stations start at 0 at the part's lower end.
    nu : float
        Poisson's ratio for the shear areas.
    name : str
        The part's name for the table and for messages.
    taper_divisions : int
        Sub-intervals for an interval whose section varies (chamfer, fillet).
    points_per_circle : int
        Polygon resolution of the largest circle in a section given to the
        warping analysis.
    progress : callable, optional
        Called as ``progress(done, total)`` after each slice.
    unit : str, optional
        Length unit of a mesh file given as a path.

    Returns
    -------
    SectionTable
        With ``meta["mass_check"]`` a :class:`MassCheck` and ``meta["axis"]``
        the axis used.

    Raises
    ------
    ModelError
        Not one closed solid; no axis of symmetry; a section that is split,
        empty or too far from round about the axis (a bent or eccentric body).
    """
    if isinstance(shape, (str, os.PathLike)):
        from ..io import read_cad

        shape = read_cad(shape, unit=unit)
    if type(shape).__module__.split(".")[0] == "trimesh":
        from .mesh import mesh_sections

        return mesh_sections(
            shape, axis=axis, nu=nu, name=name, taper_divisions=taper_divisions, progress=progress
        )
    solid = brep.as_solid(shape, name=name)
    ax = find_axis(solid, name=name) if axis is None else AxisSpec.of(axis, name=name)
    local = brep.aligned(solid, to_cad(np.asarray(ax.origin)), np.asarray(ax.direction))
    bb = local.bounding_box()
    tol = 1e-7 * max(bb.size.X, bb.size.Y, bb.size.Z)
    stations = brep.breakpoints(local, tol)
    flat = brep.prismatic_intervals(local, stations, tol)
    if taper_divisions < 1:
        raise ModelError(
            "must be at least 1",
            component=name,
            field="taper_divisions",
            value=taper_divisions,
            valid="an integer >= 1",
        )
    xs = _interval_plan(stations, flat, taper_divisions)
    n = xs.size - 1
    cols = {
        c: np.empty(n)
        for c in ("area", "ip", "iy", "iz", "iyz", "j", "shear_area_y", "shear_area_z", "yc", "zc")
    }
    method = []
    for i in range(n):
        xm = 0.5 * (xs[i] + xs[i + 1])
        faces = brep.section_faces(local, xm)
        where = f"the section at x = {from_cad(xm - (bb.min.X if ax.found else 0.0)):.6g} m"
        if len(faces) != 1:
            what = "is empty" if not faces else f"has {len(faces)} separate pieces"
            raise ModelError(
                f"is not a straight shaft: {where} {what}",
                component=name,
                field="geometry",
                valid="one connected section at every station along the axis",
            )
        face = faces[0]
        radii = brep.round_radii(face, tol)
        if radii is not None:
            ro, ri = from_cad(radii[0]), from_cad(radii[1])
            p = annulus_properties(2 * ro, 2 * ri, nu=nu)
            vals = dict(
                area=p.area,
                ip=p.ip,
                iy=p.i,
                iz=p.i,
                iyz=0.0,
                j=p.j,
                shear_area_y=p.shear_area,
                shear_area_z=p.shear_area,
                yc=0.0,
                zc=0.0,
            )
            method.append("annulus" if ri > 0 else "circle")
        else:
            exact = brep.face_props(face)
            exterior, holes = brep.face_rings(face, points_per_circle)
            ext_m = from_cad(exterior)
            holes_m = [from_cad(h) for h in holes]
            check_section(ext_m, math.hypot(from_cad(exact.yc), from_cad(exact.zc)), where, name)
            from .warping import corrected, warping_properties  # sectionproperties only when needed

            area = area_from_cad(exact.area)
            ip_axis = moment_from_cad(exact.ip_axis)
            # Chords cut the arcs short; for a circle J = Ip, so scaling by exact/polygon Ip removes
            # that first-order faceting error (geometry.warping.corrected).
            w = corrected(warping_properties(_shapely(ext_m, holes_m), nu=nu), area, ip_axis)
            to_cowper = shear_definition_ratio(nu)
            vals = dict(
                area=area,
                ip=ip_axis,
                iy=moment_from_cad(exact.iy),
                iz=moment_from_cad(exact.iz),
                iyz=moment_from_cad(exact.iyz),
                j=w.j,
                shear_area_y=w.shear_area_y * to_cowper,
                shear_area_z=w.shear_area_z * to_cowper,
                yc=from_cad(exact.yc),
                zc=from_cad(exact.zc),
            )
            method.append("warping")
        for c, v in vals.items():
            cols[c][i] = v
        if progress is not None:
            progress(i + 1, n)
    x0 = bb.min.X if ax.found else 0.0
    table = SectionTable(x=from_cad(xs - x0), method=tuple(method), nu=nu, name=name, **cols)
    vp = brep.volume_props(local)
    # ∫ r² dV about the x axis: the centroidal matrix's xx term plus the parallel-axis shift.
    moment_solid = vp.inertia[0, 0] + vp.volume * (vp.centre[1] ** 2 + vp.centre[2] ** 2)
    check = MassCheck(
        volume_table=table.volume,
        volume_solid=volume_from_cad(vp.volume),
        axial_moment_table=float(np.dot(table.ip, table.lengths)),
        axial_moment_solid=volume_moment_from_cad(moment_solid),
    )
    return replace(table, meta={"mass_check": check, "axis": ax, "source": "brep"})


def _shapely(exterior: np.ndarray, holes: list[np.ndarray]):
    from shapely.geometry import Polygon

    return Polygon(exterior, holes)
