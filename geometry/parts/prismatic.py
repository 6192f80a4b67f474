"""Prismatic shafts as build123d solids: a regular polygon bar and a straight-sided spline shaft.

Each takes SI metres (keyword-only) and returns a :class:`build123d.Part` of one solid in
build123d's millimetres, extruded along +x from ``x``; the outline lies in a plane x = const, its
angles right-handed about +x from the +z axis (see :mod:`geometry.parts.primitives`).
"""

from __future__ import annotations

import math

import build123d as bd

from flexshaft.system.limits import check_ceiling
from flexshaft.validation import check_int, check_real

from ..units import to_cad
from .primitives import polar_yz

__all__ = ["polygon_shaft", "spline_shaft"]


def _extrude_x(wire: bd.Wire, length: float) -> bd.Part:
    """Extrude a closed outline lying in a plane x = const by ``length`` (mm) along +x: a prism."""
    return bd.Part([bd.Solid.extrude(bd.Face(wire), bd.Vector(length, 0.0, 0.0))])


def polygon_shaft(*, length: float, sides: int, across_flats: float, x: float = 0.0) -> bd.Part:
    """A prismatic shaft of regular polygon section (hexagon bar, square drive...).

    Parameters
    ----------
    length : float
        Axial length, m (> 0).
    sides : int
        Number of sides (>= 3).
    across_flats : float
        Distance between opposite flats (twice the apothem), m (> 0). For odd
        ``sides`` this is twice the inscribed radius.
    x : float, optional
        Axial start, m. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm) from x to x + length, one flat facing +z. Section area
        sides · a² · tan(pi/sides) with a = across_flats/2.

    Raises
    ------
    ModelError
        If a dimension is out of range.
    """
    length = check_real(length, "length", "m", lo=0.0, lo_open=True)
    sides = check_ceiling("sides", check_int(sides, "sides", lo=3))
    across_flats = check_real(across_flats, "across_flats", "m", lo=0.0, lo_open=True)
    x = check_real(x, "x", "m")
    rho = to_cad(across_flats) / 2.0 / math.cos(math.pi / sides)  # circumradius
    points = [polar_yz(rho, math.pi / sides + 2.0 * math.pi * k / sides) for k in range(sides)]
    x0 = to_cad(x)
    return _extrude_x(bd.Wire.make_polygon([(x0, y, z) for y, z in points]), to_cad(length))


def spline_shaft(
    *,
    length: float,
    root_d: float,
    tip_d: float,
    teeth: int,
    tooth_width: float | None = None,
    x: float = 0.0,
) -> bd.Part:
    """A straight-sided spline shaft (ISO 14 style), extruded along x.

    Parameters
    ----------
    length : float
        Axial length, m (> 0).
    root_d : float
        Minor (root) diameter, m (> 0).
    tip_d : float
        Major (tip) diameter, m (> root_d).
    teeth : int
        Number of teeth (>= 3); the first is centred on +z.
    tooth_width : float, optional
        Width between the parallel flanks of a tooth, m; must leave a gap at
        the root: tooth_width < root_d · sin(pi/teeth). Default
        root_d · sin(pi/(2·teeth)), i.e. teeth and gaps of equal angle at the root.
    x : float, optional
        Axial start, m. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm): planes, the root and tip cylinders only.

    Raises
    ------
    ModelError
        If a dimension is out of range.
    """
    length = check_real(length, "length", "m", lo=0.0, lo_open=True)
    root_d = check_real(root_d, "root_d", "m", lo=0.0, lo_open=True)
    tip_d = check_real(tip_d, "tip_d", "m", lo=root_d, lo_open=True)
    teeth = check_ceiling("teeth", check_int(teeth, "teeth", lo=3))
    x = check_real(x, "x", "m")
    if tooth_width is None:
        tooth_width = root_d * math.sin(math.pi / (2 * teeth))
    w_max = root_d * math.sin(math.pi / teeth)
    tooth_width = check_real(tooth_width, "tooth_width", "m", lo=0.0, lo_open=True, hi=w_max, hi_open=True)
    x0 = to_cad(x)
    rr, rt, hw = to_cad(root_d) / 2.0, to_cad(tip_d) / 2.0, to_cad(tooth_width) / 2.0
    a_root, a_tip = math.asin(hw / rr), math.asin(hw / rt)  # half-angles of a flank at root and tip
    pitch = 2.0 * math.pi / teeth

    def pt(radius: float, ang: float) -> bd.Vector:
        return bd.Vector(x0, *polar_yz(radius, ang))

    edges = []
    for k in range(teeth):
        phi = k * pitch
        edges += [
            bd.Edge.make_line(pt(rr, phi - a_root), pt(rt, phi - a_tip)),
            bd.Edge.make_three_point_arc(pt(rt, phi - a_tip), pt(rt, phi), pt(rt, phi + a_tip)),
            bd.Edge.make_line(pt(rt, phi + a_tip), pt(rr, phi + a_root)),
            bd.Edge.make_three_point_arc(
                pt(rr, phi + a_root), pt(rr, phi + pitch / 2.0), pt(rr, phi + pitch - a_root)
            ),
        ]
    return _extrude_x(bd.Wire(edges), to_cad(length))
