"""The B-rep slicer: a shaft solid cut along its axis into a :class:`~flexshaft.sections.SectionTable`.

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
from dataclasses import dataclass

import numpy as np

from flexshaft.errors import ModelError
from flexshaft.sections import SectionTable, annulus_properties

from ..units import area_from_cad, from_cad, moment_from_cad, to_cad, volume_from_cad, volume_moment_from_cad
from . import brep
from .common import (
    AxisSpec,
    Columns,
    SliceOptions,
    axial_moment,
    axis_from_inertia,
    check_one_piece,
    check_section,
    subdivide,
    warped,
    with_mass_check,
)

__all__ = ["PartFrame", "find_axis", "part_frame", "solid_sections"]


def find_axis(solid, *, name: str = "part") -> AxisSpec:
    """The axis of near-rotational symmetry of a solid.

    A shaft has two equal principal moments of inertia (within
    :data:`~geometry.slicing.common.SYMMETRY_TOL`); the third principal direction is roughly its axis.
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


@dataclass(frozen=True)
class PartFrame:
    """A part's solid in its own frame, as the section table and the solid mesh both see it.

    Attributes
    ----------
    solid : build123d.Solid
        The solid with the shaft axis along x (coordinates in mm, build123d's unit): y and z across,
        from :func:`~geometry.slicing.frames.axis_frame`.
    axis : AxisSpec
        The axis used, SI (found, or as given).
    x0 : float
        The x of the solid (mm) where the part's stations start: its lower end when the axis was
        found, the axis' origin (0) when it was given.
    """

    solid: object
    axis: AxisSpec
    x0: float


def part_frame(shape, *, axis=None, name: str = "part") -> PartFrame:
    """The one closed solid of ``shape`` moved into the part's frame (see :class:`PartFrame`).

    The slicer and the tetrahedral mesher (:mod:`geometry.meshing`) both start here, so a part's
    section table and its solid mesh share coordinates. If ``axis`` is omitted it is found
    (:func:`find_axis`) and x starts at 0 at the part's lower end; a given axis keeps its origin
    at x = 0.
    """
    solid = brep.as_solid(shape, name=name)
    ax = find_axis(solid, name=name) if axis is None else AxisSpec.of(axis, name=name)
    local = brep.aligned(solid, to_cad(np.asarray(ax.origin)), np.asarray(ax.direction))
    x0 = local.bounding_box().min.X if ax.found else 0.0
    return PartFrame(solid=local, axis=ax, x0=x0)


def solid_sections(shape, options: SliceOptions) -> SectionTable:
    """The section table of a straight shaft solid (see :func:`geometry.slicing.sections`).

    ``shape`` is a build123d shape holding one closed solid (millimetres, as
    build123d makes them); ``options`` are :func:`~geometry.slicing.sections`'
    arguments. If the axis is not given it is found (:func:`find_axis`: the
    principal axes of inertia, made exact by the turned faces) and the stations
    start at 0 at the part's lower end.
    """
    axis, nu, name, taper_divisions = options.axis, options.nu, options.name, options.taper_divisions
    points_per_circle, progress = options.points_per_circle, options.progress
    frame = part_frame(shape, axis=axis, name=name)
    local, ax, x0 = frame.solid, frame.axis, frame.x0
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
    xs = subdivide(stations, np.where(flat, 1, taper_divisions))
    n = xs.size - 1
    cols = Columns(n)
    for i in range(n):
        xm = 0.5 * (xs[i] + xs[i + 1])
        faces = brep.section_faces(local, xm)
        where = f"the section at x = {from_cad(xm - x0):.6g} m"
        check_one_piece(len(faces), where, name)
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
            method = "annulus" if ri > 0 else "circle"
        else:
            exact = brep.face_props(face)
            exterior, holes = brep.face_rings(face, points_per_circle)
            ext_m = from_cad(exterior)
            holes_m = [from_cad(h) for h in holes]
            check_section(ext_m, math.hypot(from_cad(exact.yc), from_cad(exact.zc)), where, name)
            area = area_from_cad(exact.area)
            ip_axis = moment_from_cad(exact.ip_axis)
            # Chords cut the arcs short; for a circle J = Ip, so scaling by exact/polygon Ip removes
            # that first-order faceting error (geometry.slicing.warping.corrected).
            vals = dict(
                area=area,
                ip=ip_axis,
                iy=moment_from_cad(exact.iy),
                iz=moment_from_cad(exact.iz),
                iyz=moment_from_cad(exact.iyz),
                **warped(_shapely(ext_m, holes_m), nu=nu, area=area, ip_axis=ip_axis),
                yc=from_cad(exact.yc),
                zc=from_cad(exact.zc),
            )
            method = "warping"
        cols.set(i, method, vals)
        if progress is not None:
            progress(i + 1, n)
    vp = brep.volume_props(local)
    return with_mass_check(
        cols.table(from_cad(xs - x0), nu=nu, name=name),
        volume_solid=volume_from_cad(vp.volume),
        axial_moment_solid=volume_moment_from_cad(axial_moment(vp.volume, vp.centre, vp.inertia)),
        axis=ax,
        source="brep",
    )


def _shapely(exterior: np.ndarray, holes: list[np.ndarray]):
    from shapely.geometry import Polygon

    return Polygon(exterior, holes)
