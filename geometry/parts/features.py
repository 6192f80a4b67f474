"""Cuts into a finished shaft: keyways and flats, prismatic with a floor parallel to x.

Each takes the shaft (one solid in build123d's millimetres, e.g. from
:mod:`geometry.parts.primitives`) and SI metres (keyword-only), and returns a
:class:`build123d.Part` of one valid solid without the cut's material. Angles
about the shaft axis are in radians, right-handed about +x from the +z axis:
angle 0 is the +z side, angle pi/2 the -y side.
"""

from __future__ import annotations

import math

import build123d as bd

from flexshaft.errors import ModelError
from flexshaft.validation import check_int, check_real

from ..units import to_cad
from .primitives import as_part, only_solid

__all__ = ["keyway", "flats"]


def _rotated(tool: bd.Solid, angle: float) -> bd.Solid:
    """``tool`` built on the +z side, turned to ``angle`` (rad) about +x."""
    return tool.rotate(bd.Axis.X, math.degrees(angle)) if angle else tool


def _cut(solid: bd.Solid, tools: list[bd.Solid], x_start: float, missed: str, doing: str) -> bd.Part:
    """``solid`` less ``tools``; refused with ``missed`` if that removes nothing, or if not one solid."""
    result = solid.cut(*tools)
    if sum(s.volume for s in result.solids()) >= solid.volume * (1.0 - 1e-12):
        raise ModelError(
            missed,
            field="x_start",
            value=x_start,
            unit="m",
            valid="a position and diameter where the shaft has material",
        )
    return as_part(result, doing)


def keyway(
    part: bd.Part,
    *,
    width: float,
    depth: float,
    length: float,
    x_start: float,
    diameter: float,
    angle: float = 0.0,
    rounded_ends: bool = False,
) -> bd.Part:
    """Cut a keyway (key seat) into the outer surface of a shaft.

    Parameters
    ----------
    part : build123d.Part
        The shaft, one solid (mm).
    width : float
        Keyway width, m (0 < width < diameter).
    depth : float
        Depth below the outer diameter on the keyway centre line, m
        (0 < depth < diameter/2). The floor is flat and parallel to x.
    length : float
        Overall axial length, m (> 0; > width with rounded ends).
    x_start : float
        Axial position of the keyway's start, m.
    diameter : float
        Outer diameter of the shaft where the keyway is, m (> 0).
    angle : float, optional
        Angular position, rad, right-handed about +x from +z. Default 0 (+z side).
    rounded_ends : bool, optional
        Round ends of radius width/2 (end-milled, form A) instead of square
        ends. Default False.

    Returns
    -------
    build123d.Part
        One solid (mm) without the keyway's material.

    Raises
    ------
    ModelError
        If a dimension is out of range or the keyway misses the part.
    """
    solid = only_solid(part, "part")
    diameter = check_real(diameter, "diameter", "m", lo=0.0, lo_open=True)
    width = check_real(width, "width", "m", lo=0.0, lo_open=True, hi=diameter, hi_open=True)
    depth = check_real(depth, "depth", "m", lo=0.0, lo_open=True, hi=diameter / 2.0, hi_open=True)
    length = check_real(length, "length", "m", lo=0.0, lo_open=True)
    x_start = check_real(x_start, "x_start", "m")
    angle = check_real(angle, "angle", "rad")
    if not isinstance(rounded_ends, bool):
        raise ModelError("not a boolean", field="rounded_ends", value=rounded_ends, valid="true or false")
    if rounded_ends and length <= width:
        raise ModelError(
            "a round-ended keyway must be longer than wide",
            field="length",
            value=length,
            unit="m",
            valid=f"> width {width:g} m",
        )
    w, r = to_cad(width), to_cad(diameter) / 2.0
    z_floor = r - to_cad(depth)
    height = 2.0 * to_cad(depth)  # reaches a depth past the OD, so the top never grazes the surface
    x0, x1 = to_cad(x_start), to_cad(x_start + length)
    if rounded_ends:
        tools = [
            bd.Solid.make_box(x1 - x0 - w, w, height, bd.Plane(origin=(x0 + w / 2.0, -w / 2.0, z_floor))),
            bd.Solid.make_cylinder(w / 2.0, height, bd.Plane(origin=(x0 + w / 2.0, 0.0, z_floor))),
            bd.Solid.make_cylinder(w / 2.0, height, bd.Plane(origin=(x1 - w / 2.0, 0.0, z_floor))),
        ]
    else:
        tools = [bd.Solid.make_box(x1 - x0, w, height, bd.Plane(origin=(x0, -w / 2.0, z_floor)))]
    tools = [_rotated(t, angle) for t in tools]
    return _cut(solid, tools, x_start, "keyway misses the part", "cutting the keyway")


def flats(
    part: bd.Part,
    *,
    depth: float,
    length: float,
    x_start: float,
    diameter: float,
    count: int = 1,
    angle: float = 0.0,
) -> bd.Part:
    """Mill one flat, or two opposite flats (a spanner seat), parallel to x.

    Parameters
    ----------
    part : build123d.Part
        The shaft, one solid (mm).
    depth : float
        Depth of each flat below the diameter, m (0 < depth < diameter/2).
    length : float
        Axial length, m (> 0).
    x_start : float
        Axial position of the flats' start, m.
    diameter : float
        Outer diameter of the shaft there, m (> 0).
    count : int, optional
        1 or 2 (the second opposite the first). Default 1.
    angle : float, optional
        Position of the first flat's normal, rad, right-handed about +x from
        +z. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm) without the flats' material.

    Raises
    ------
    ModelError
        If a dimension is out of range or the flats miss the part.
    """
    solid = only_solid(part, "part")
    diameter = check_real(diameter, "diameter", "m", lo=0.0, lo_open=True)
    depth = check_real(depth, "depth", "m", lo=0.0, lo_open=True, hi=diameter / 2.0, hi_open=True)
    length = check_real(length, "length", "m", lo=0.0, lo_open=True)
    x_start = check_real(x_start, "x_start", "m")
    count = check_int(count, "count", lo=1, hi=2)
    angle = check_real(angle, "angle", "rad")
    r, dd = to_cad(diameter) / 2.0, to_cad(depth)
    half = r + dd  # wider than the chord and taller than the cap, so no cutter face grazes the OD
    box = bd.Solid.make_box(
        to_cad(length), 2.0 * half, 2.0 * dd, bd.Plane(origin=(to_cad(x_start), -half, r - dd))
    )
    tools = [_rotated(box, angle + k * math.pi) for k in range(count)]
    return _cut(solid, tools, x_start, "flats miss the part", "milling the flats")
