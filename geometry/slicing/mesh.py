"""Slice a triangle mesh (STL/OBJ/PLY, already in metres) into a section table.

A mesh has no B-rep, but its breakpoints are still exact: the section of a
triangle mesh changes shape only at the axial positions of its vertices, so
those are the stations. Between two stations a section is a polygon whose
corners move linearly with x; where any facet is inclined to the axis the
interval is cut into ``taper_divisions`` pieces, each taken at its middle.
Polygon properties are exact for the polygon: the difference from the CAD
solid is the mesh's faceting (its chord tolerance), nothing else.
"""

from __future__ import annotations

import numpy as np

from flexshaft.errors import ModelError
from flexshaft.sections import SectionTable, cowper_shear_factor

from .common import (
    AxisSpec,
    Columns,
    SliceOptions,
    axial_moment,
    axis_from_inertia,
    check_one_piece,
    check_section,
    merge_stations,
    subdivide,
    warped,
    with_mass_check,
)
from .frames import axis_frame
from .polygons import polygon_moments

__all__ = ["mesh_sections", "ROUND_TOL"]

#: A mesh section counts as a circle/annulus when all its ring radii agree to this (relative).
ROUND_TOL = 0.02


def _refined_axis(mesh, ax: AxisSpec) -> AxisSpec:
    """Correct a principal axis for the tilt and offset a keyway or flat gives it.

    A mesh keeps no surfaces of revolution to read the axis from. Parts are
    nearly always drawn along a coordinate axis: a principal direction within
    0.02 rad of one is taken to be it. The axis then passes through the
    centre of the outer envelope's y–z bounding box, which a keyway or flat
    along part of the length does not move.
    """
    d = np.asarray(ax.direction)
    k = int(np.argmax(np.abs(d)))
    if abs(d[k]) > np.cos(0.02):
        d = np.eye(3)[k] * np.sign(d[k])
    rot = axis_frame(d)
    v = (np.asarray(mesh.vertices) - np.asarray(ax.origin)) @ rot.T
    centre_yz = 0.5 * (v[:, 1:].min(axis=0) + v[:, 1:].max(axis=0))
    origin = np.asarray(ax.origin) + centre_yz @ rot[1:]
    return AxisSpec(tuple(origin.tolist()), tuple(d.tolist()), found=True)


def _round(exterior: np.ndarray, holes: list[np.ndarray], tol: float) -> bool:
    rings = [exterior, *holes]
    if len(rings) > 2:
        return False
    for ring in rings:
        r = np.hypot(ring[:, 0], ring[:, 1])
        if r.max() - r.min() > ROUND_TOL * r.max():
            return False
    return True


def mesh_sections(mesh, options: SliceOptions) -> SectionTable:
    """The section table of a watertight triangle mesh in metres.

    ``options`` are :func:`geometry.slicing.sections`' arguments (its polygon
    resolution aside); ``mesh`` is a :class:`trimesh.Trimesh` (as
    :func:`geometry.cadio.read_mesh` returns it). Sections whose rings are all
    round about the axis (within :data:`ROUND_TOL`) are ``"annulus"``/``"circle"``
    with J = Ip of the faceted polygon; others go to the warping analysis of the
    polygon.
    """
    axis, nu, name = options.axis, options.nu, options.name
    taper_divisions, progress = options.taper_divisions, options.progress
    import trimesh

    if not isinstance(mesh, trimesh.Trimesh) or not mesh.is_watertight:
        raise ModelError(
            "is not a watertight triangle mesh",
            component=name,
            field="geometry",
            valid="a closed mesh (read it with geometry.cadio.read_mesh)",
        )
    if axis is None:
        ax = _refined_axis(
            mesh, axis_from_inertia(np.asarray(mesh.moment_inertia), np.asarray(mesh.center_mass), name=name)
        )
    else:
        ax = AxisSpec.of(axis, name=name)
    rot = axis_frame(np.asarray(ax.direction))
    v = (np.asarray(mesh.vertices) - np.asarray(ax.origin)) @ rot.T
    local = trimesh.Trimesh(vertices=v, faces=mesh.faces, process=False)
    x_all = v[:, 0]
    extent = float(np.ptp(v, axis=0).max())
    # Float32 STL coordinates carry ~1e-7 relative noise: merge stations closer than that.
    tol = 1e-6 * extent
    # The section changes only where a facet not parallel to the axis begins or ends; the extra
    # vertices a mesher puts inside a cylinder wall only add collinear points, so they are no station.
    tri_x = x_all[mesh.faces]
    crossing = np.abs(local.face_normals[:, 0]) > 1e-6
    xs_sorted = np.sort(np.concatenate([tri_x[crossing].ravel(), [x_all.min(), x_all.max()]]))
    stations = merge_stations(xs_sorted, tol)
    # An interval varies where a facet inclined to the axis spans it (difference-array marking).
    lo = np.searchsorted(stations, tri_x.min(axis=1)[crossing] - tol)
    hi = np.searchsorted(stations, tri_x.max(axis=1)[crossing] + tol, side="right") - 1
    marks = np.zeros(stations.size + 1)
    np.add.at(marks, lo, 1)
    np.add.at(marks, np.maximum(hi, lo), -1)
    varying = np.cumsum(marks)[: stations.size - 1] > 0
    # Between two close rings of a curved face the corners move linearly and the mid-section
    # is already second-order accurate; only long tapered intervals (cones) need pieces.
    xs = subdivide(stations, np.where(varying & (np.diff(stations) > 0.01 * extent), taper_divisions, 1))
    mids = 0.5 * (xs[:-1] + xs[1:])
    paths = local.section_multiplane(plane_origin=[0.0, 0.0, 0.0], plane_normal=[1.0, 0.0, 0.0], heights=mids)
    n = mids.size
    cols = Columns(n)
    x0 = stations[0] if ax.found else 0.0
    for i, path in enumerate(paths):
        where = f"the section at x = {mids[i] - x0:.6g} m"
        polys = [] if path is None else list(path.polygons_full)
        check_one_piece(len(polys), where, name)
        # Back from the path's own 2-D frame to the global (y, z) of the plane x = mid.
        t = np.asarray(path.metadata["to_3D"])

        def to_yz(coords, t=t):
            c = np.asarray(coords)[:-1, :2]
            return c @ t[1:3, :2].T + t[1:3, 3]

        poly = polys[0]
        exterior = to_yz(poly.exterior.coords)
        holes = [to_yz(h.coords) for h in poly.interiors]
        m = polygon_moments(exterior, holes)
        offset = float(np.hypot(m.yc, m.zc))
        check_section(exterior, offset, where, name)
        ip = m.ip_axis
        if _round(exterior, holes, tol) and offset <= 1e-3 * np.hypot(exterior[:, 0], exterior[:, 1]).max():
            ratio = 0.0
            if holes:
                ratio = np.hypot(holes[0][:, 0], holes[0][:, 1]).mean() / np.hypot(*exterior.T).mean()
            kappa = float(cowper_shear_factor(ratio, nu))
            vals = dict(j=ip, shear_area_y=kappa * m.area, shear_area_z=kappa * m.area)
            method = "annulus" if holes else "circle"
        else:
            from shapely.geometry import Polygon

            # A fine STL puts hundreds of facets on each circle and collinear points on every chord;
            # the warping mesh grows with the boundary points, not with accuracy. Simplify to about
            # 128 chords on the outer circle, then scale back to the mesh polygon's own A and Ip.
            r_max = float(np.hypot(exterior[:, 0], exterior[:, 1]).max())
            coarse = Polygon(exterior, holes).simplify(3e-4 * r_max, preserve_topology=True)
            vals = warped(coarse, nu=nu, area=m.area, ip_axis=m.ip_axis)
            method = "warping"
        vals.update(area=m.area, ip=ip, iy=m.iy, iz=m.iz, iyz=m.iyz, yc=m.yc, zc=m.zc)
        cols.set(i, method, vals)
        if progress is not None:
            progress(i + 1, n)
    return with_mass_check(
        cols.table(xs - x0, nu=nu, name=name),
        volume_solid=float(local.volume),
        axial_moment_solid=float(
            axial_moment(local.volume, np.asarray(local.center_mass), np.asarray(local.moment_inertia))
        ),
        axis=ax,
        source="mesh",
    )
