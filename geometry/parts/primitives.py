"""Generic parametric shaft bodies as build123d solids with exact analytic surfaces.

The segment and bolt-circle data and their checks; turned bodies (stepped and
flanged shafts, flanges, coupling hubs) with the bolt holes they are drilled
with; fusing parts. Prismatic shafts (polygon, spline) are in
:mod:`geometry.parts.prismatic`, the cuts made into a finished shaft (keyways,
flats) in :mod:`geometry.parts.features`.

Every public builder takes SI metres (keyword-only) and returns a
:class:`build123d.Part` holding exactly one valid solid in build123d's
millimetres, with the shaft axis along +x and the driving end at x = 0 unless
an ``x`` argument places it elsewhere. Turned bodies are one revolve of a 2D
half-profile about the x axis (planes, cylinders, cones for chamfers, tori for
fillets); bolt holes are cylinders parallel to x; keyways and flats are
prismatic cuts with a floor parallel to x. No splines or lofts, so a slicer can
read every face of the B-rep exactly.

Angles about the shaft axis are in radians, measured right-handed about +x from
the +z axis: angle 0 is the +z side, angle pi/2 the -y side.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import build123d as bd

from flexshaft.errors import ModelError
from flexshaft.sections import SectionSegment
from flexshaft.system.limits import check_ceiling
from flexshaft.validation import check_choice, check_int, check_real

from ..units import to_cad, volume_from_cad

__all__ = [
    "Segment",
    "BoltCircle",
    "stepped_shaft",
    "flanged_shaft",
    "flange",
    "bolt_holes",
    "check_bolt_pattern",
    "fuse",
    "coupling_hub",
]

# cos 45°: where a 90° fillet arc passes half-way between its two tangent points.
_SIN45 = math.sqrt(0.5)


# --------------------------------------------------------------------------- data


#: One cylindrical (or tubular) stretch of a stepped shaft: length, od, id (m). The same
#: class a model file's ``segments`` use, so a part and its closed-form twin share one check.
Segment = SectionSegment


@dataclass(frozen=True)
class BoltCircle:
    """A pattern of equal axial through holes on a pitch circle.

    Parameters
    ----------
    count : int
        Number of holes (>= 1), equally spaced.
    hole_d : float
        Hole diameter, m (> 0).
    pitch_d : float
        Pitch-circle diameter, m (> hole_d; adjacent holes must not touch:
        ``pitch_d * sin(pi / count) > hole_d``).
    x_start : float
        Axial position where the holes start, m.
    length : float
        Axial length of the drilled material, m (> 0); the holes go through
        it and must lie wholly in material.
    angle : float, optional
        Angular position of the first hole, rad, right-handed about +x from
        +z. Default 0 (first hole on +z).
    """

    count: int
    hole_d: float
    pitch_d: float
    x_start: float
    length: float
    angle: float = 0.0

    def __post_init__(self) -> None:
        count = check_ceiling("bolt_holes", check_int(self.count, "count", lo=1), field="count")
        hole_d = check_real(self.hole_d, "hole_d", "m", lo=0.0, lo_open=True)
        pitch_d = check_real(self.pitch_d, "pitch_d", "m", lo=0.0, lo_open=True)
        _check_hole_spacing(count, hole_d, pitch_d, "pitch_d")
        object.__setattr__(self, "count", count)
        object.__setattr__(self, "hole_d", hole_d)
        object.__setattr__(self, "pitch_d", pitch_d)
        object.__setattr__(self, "x_start", check_real(self.x_start, "x_start", "m"))
        object.__setattr__(self, "length", check_real(self.length, "length", "m", lo=0.0, lo_open=True))
        object.__setattr__(self, "angle", check_real(self.angle, "angle", "rad"))

    @property
    def volume(self) -> float:
        """Material the holes remove, m³ (count · π/4 · hole_d² · length)."""
        return self.count * math.pi / 4.0 * self.hole_d**2 * self.length


# --------------------------------------------------------------------------- checks


def _check_hole_spacing(count: int, hole_d: float, pitch_d: float, field: str) -> None:
    """Refuse holes that reach the axis or touch their neighbours."""
    if pitch_d <= hole_d:
        raise ModelError(
            "bolt holes would overlap at the axis",
            field=field,
            value=pitch_d,
            unit="m",
            valid=f"> hole diameter {hole_d:g} m",
        )
    # The chord between adjacent hole centres is pitch_d·sin(pi/n); it must exceed one diameter.
    if count >= 2 and pitch_d * math.sin(math.pi / count) <= hole_d:
        need = hole_d / math.sin(math.pi / count)
        raise ModelError(
            f"{count} holes of {hole_d:g} m overlap their neighbours",
            field=field,
            value=pitch_d,
            unit="m",
            valid=f"> {need:g} m (pitch_d·sin(pi/{count}) > hole diameter)",
        )


def _check_circle(circle: object, i: int) -> None:
    """Refuse ``circles[i]`` unless it is a :class:`BoltCircle`."""
    if not isinstance(circle, BoltCircle):
        raise ModelError(
            "not a BoltCircle", field=f"circles[{i}]", value=circle, valid="a BoltCircle", has_value=True
        )


def _both_or_neither(feature: str, first: tuple[str, float, str], second: tuple[str, float, str]) -> None:
    """Refuse a feature given by one of its two dimensions only: each ``(field, value in m, what)``."""
    (name1, value1, what1), (name2, value2, what2) = first, second
    if (value1 > 0.0) != (value2 > 0.0):
        field, value = (name2, value2) if value1 > 0.0 else (name1, value1)
        raise ModelError(
            f"a {feature} needs both {what1} and {what2}",
            field=field,
            value=value,
            unit="m",
            valid=f"> 0 together with the other {feature} dimension, or both 0",
        )


def check_bolt_pattern(
    count: int,
    hole_d: float,
    pitch_d: float,
    *,
    inner_d: float,
    inner_name: str,
    outer_d: float,
    outer_name: str,
    prefix: str = "",
) -> None:
    """Check that a flange's bolt holes lie in the annulus between inner_d and outer_d.

    Parameters
    ----------
    count : int
        Number of holes (0 = none; then hole_d and pitch_d must be 0).
    hole_d, pitch_d : float
        Hole and pitch-circle diameters, m.
    inner_d : float
        Diameter the holes must clear on the inside (bore, spigot, hub), m.
    inner_name, outer_name : str
        What inner_d and outer_d are, for the message.
    outer_d : float
        Diameter the holes must stay inside (flange outer diameter), m.
    prefix : str, optional
        Prefix of the argument names in messages (``bolt_count``,
        ``bolt_hole_d``, ``pitch_d``), e.g. ``"generator_"``.

    Raises
    ------
    ModelError
        Naming the offending argument, its value in m and the valid range.
    """
    names = {k: f"{prefix}{k}" for k in ("bolt_count", "bolt_hole_d", "pitch_d")}
    check_ceiling("bolt_holes", count, field=names["bolt_count"])
    if count == 0:
        # No holes asked for: a hole size given anyway is a mistake, not a default to ignore.
        for name, val in ((names["bolt_hole_d"], hole_d), (names["pitch_d"], pitch_d)):
            if val != 0.0:
                raise ModelError(
                    "given without bolt holes",
                    field=name,
                    value=val,
                    unit="m",
                    valid=f"0 when {names['bolt_count']} = 0",
                )
        return
    if hole_d <= 0.0:
        raise ModelError(
            "bolt holes need a diameter",
            field=names["bolt_hole_d"],
            value=hole_d,
            unit="m",
            valid=f"> 0 when {names['bolt_count']} = {count}",
        )
    if pitch_d - hole_d <= inner_d:
        raise ModelError(
            f"bolt holes cut into the {inner_name}",
            field=names["pitch_d"],
            value=pitch_d,
            unit="m",
            valid=f"{names['pitch_d']} - {names['bolt_hole_d']} > {inner_d:g} m (the {inner_name} diameter)",
        )
    if pitch_d + hole_d >= outer_d:
        raise ModelError(
            f"bolt holes break through the {outer_name}",
            field=names["pitch_d"],
            value=pitch_d,
            unit="m",
            valid=f"{names['pitch_d']} + {names['bolt_hole_d']} < {outer_d:g} m (the {outer_name} diameter)",
        )
    _check_hole_spacing(count, hole_d, pitch_d, names["pitch_d"])


# --------------------------------------------------------------------------- helpers (also for features.py)


def only_solid(part: object, field: str) -> bd.Solid:
    """The single solid of a Part/Solid/Compound, or a ModelError naming ``field``."""
    if not isinstance(part, bd.Shape):
        raise ModelError(
            "not a build123d shape", field=field, value=type(part).__name__, valid="a Part with one solid"
        )
    solids = part.solids()
    if len(solids) != 1:
        raise ModelError(
            "needs exactly one solid", field=field, value=len(solids), valid="a Part with one solid"
        )
    return solids[0]


def as_part(shape: bd.Shape, what: str) -> bd.Part:
    """Wrap a boolean result as a Part after checking it is one valid solid."""
    solids = shape.solids()
    if len(solids) != 1:
        raise ModelError(
            f"{what} does not leave exactly one solid",
            field="solids",
            value=len(solids),
            valid="exactly 1 (parts must touch or overlap; cuts must not split the part)",
        )
    solid = solids[0]
    if not solid.is_valid:
        raise ModelError(f"{what} gives an invalid solid", field="solids", value=1, valid="a valid B-rep")
    return bd.Part([solid])


def _xr(x: float, r: float) -> bd.Vector:
    """A point of the half-profile: axial x and radius r (mm) in the xy plane (y = radius)."""
    return bd.Vector(x, r, 0.0)


def _revolve(loop: Sequence[tuple]) -> bd.Solid:
    """Revolve a closed half-profile 360° about the x axis.

    ``loop`` holds ``("L", (x, r))`` for a straight edge to the point and
    ``("A", (xm, rm), (x, r))`` for a circular arc through a mid point; the
    first entry is the start point ``("P", (x, r))``. Lengths in mm.
    """
    edges = []
    start = _xr(*loop[0][1])
    here = start
    for item in loop[1:] + [("L", loop[0][1])]:
        end = _xr(*item[-1])
        if (end - here).length < 1e-9:
            continue  # a chamfer or fillet of 0 leaves a repeated point; skip the empty edge
        if item[0] == "A":
            edges.append(bd.Edge.make_three_point_arc(here, _xr(*item[1]), end))
        else:
            edges.append(bd.Edge.make_line(here, end))
        here = end
    face = bd.Face(bd.Wire(edges))
    return bd.Solid.revolve(face, 360.0, bd.Axis.X)


def polar_yz(radius: float, angle: float) -> tuple[float, float]:
    """(y, z) of a point at ``radius`` and ``angle`` (rad, right-handed about +x from +z)."""
    return -radius * math.sin(angle), radius * math.cos(angle)


def _hole_tools(circle: BoltCircle, margin: float) -> list[bd.Solid]:
    """Cylinders (mm) for the holes of one bolt circle, ``margin`` mm longer at both ends."""
    r_hole = to_cad(circle.hole_d) / 2.0
    r_pitch = to_cad(circle.pitch_d) / 2.0
    x0 = to_cad(circle.x_start) - margin
    height = to_cad(circle.length) + 2.0 * margin
    tools = []
    for k in range(circle.count):
        y, z = polar_yz(r_pitch, circle.angle + 2.0 * math.pi * k / circle.count)
        plane = bd.Plane(origin=(x0, y, z), x_dir=(0, 1, 0), z_dir=(1, 0, 0))
        tools.append(bd.Solid.make_cylinder(r_hole, height, plane))
    return tools


# --------------------------------------------------------------------------- turned bodies


def _as_segment(item: object, i: int) -> Segment:
    """A Segment from a Segment or a mapping with keys length/od/id."""
    where = f"segments[{i}]"
    try:
        if isinstance(item, Segment):
            return item
        if isinstance(item, Mapping):
            unknown = sorted(set(item) - {"length", "od", "id"})
            if unknown:
                raise ModelError(
                    "unknown key", field=str(unknown[0]), valid="keys length, od, id (m)", has_value=False
                )
            for key in ("length", "od"):
                if key not in item:
                    raise ModelError("missing key", field=key, valid="keys length, od and optional id (m)")
            return Segment(item["length"], item["od"], item.get("id", 0.0))
    except ModelError as err:
        raise err.located(component=where) from None
    raise ModelError(
        "not a segment",
        field=where,
        value=item,
        valid="a Segment or a mapping {length, od, id} in m",
        has_value=True,
    )


def _segment_list(segments: object) -> list[Segment]:
    """Validated segments from a non-empty sequence of Segment or mappings."""
    if isinstance(segments, (str, bytes, Mapping)) or not isinstance(segments, Iterable):
        raise ModelError(
            "not a sequence of segments",
            field="segments",
            value=segments,
            valid="a non-empty list of Segment or {length, od, id} (m)",
            has_value=True,
        )
    if hasattr(segments, "__len__"):  # counted before each one is checked
        check_ceiling("cad_segments", len(segments), field="segments")
    segs = [_as_segment(item, i) for i, item in enumerate(segments)]
    check_ceiling("cad_segments", len(segs), field="segments")
    if not segs:
        raise ModelError(
            "no segments",
            field="segments",
            value=[],
            valid="a non-empty list of Segment or {length, od, id} (m)",
        )
    return segs


def _check_profile(segs: list[Segment], f_m: float, c_m: float) -> None:
    """Refuse segments that do not join, and fillets/chamfers that do not fit (all in m)."""
    n = len(segs)
    for i in range(n - 1):
        a, b = segs[i], segs[i + 1]
        if max(a.id, b.id) >= min(a.od, b.od):
            raise ModelError(
                f"segments {i} and {i + 1} do not overlap radially (the bore of one is not inside the other)",
                field=f"segments[{i + 1}].id" if b.id >= a.od else f"segments[{i}].id",
                value=max(a.id, b.id),
                unit="m",
                valid=f"< the smaller outer diameter {min(a.od, b.od):g} m",
            )
    for i, end in ((0, "start"), (n - 1, "end")):
        wall = (segs[i].od - segs[i].id) / 2.0
        if c_m >= wall:
            raise ModelError(
                f"chamfer does not fit the wall at the shaft {end}",
                field="chamfer",
                value=c_m,
                unit="m",
                valid=f"0 <= chamfer < {wall:g} m",
            )
    # Length used up on each segment by chamfers and shoulder fillets.
    used = [0.0] * n
    used[0] += c_m
    used[-1] += c_m
    for i in range(n - 1):
        a, b = segs[i], segs[i + 1]
        if a.od == b.od or f_m == 0.0:
            continue
        height = abs(b.od - a.od) / 2.0
        if f_m >= height:
            raise ModelError(
                f"fillet does not fit the shoulder between segments {i} and {i + 1}",
                field="fillet",
                value=f_m,
                unit="m",
                valid=f"0 <= fillet < step height {height:g} m",
            )
        used[i if a.od < b.od else i + 1] += f_m
    for i, seg in enumerate(segs):
        if used[i] >= seg.length:
            field = "fillet" if f_m > 0.0 else "chamfer"
            raise ModelError(
                f"fillets/chamfers use {used[i]:g} m of segments[{i}], which is only {seg.length:g} m long",
                field=field,
                value=f_m if field == "fillet" else c_m,
                unit="m",
                valid=f"a radius leaving length on segments[{i}]",
            )


def _shaft_loop(segs: Sequence[Segment], fillet: float, chamfer: float) -> list[tuple]:
    """Half-profile (mm) of a stepped shaft from x = 0: outer contour left to right, bore back.

    A shoulder fillet sits in the concave corner, on the smaller segment's side.
    """
    n = len(segs)
    xs = [0.0]
    for seg in segs:
        xs.append(xs[-1] + to_cad(seg.length))
    big = [to_cad(s.od) / 2.0 for s in segs]
    small = [to_cad(s.id) / 2.0 for s in segs]
    f, c = to_cad(fillet), to_cad(chamfer)
    d = f * (1.0 - _SIN45)  # offset of a 90° fillet's mid point from its corner, both axes

    loop: list[tuple] = [("P", (0.0, small[0])), ("L", (0.0, big[0] - c)), ("L", (c, big[0]))]
    for i in range(n - 1):
        x, ra, rb = xs[i + 1], big[i], big[i + 1]
        if ra == rb:
            continue
        if f == 0.0:
            loop += [("L", (x, ra)), ("L", (x, rb))]
        elif rb > ra:  # step up: the concave corner is on the left, at (x, ra)
            loop += [("L", (x - f, ra)), ("A", (x - d, ra + d), (x, ra + f)), ("L", (x, rb))]
        else:  # step down: the concave corner is on the right, at (x, rb)
            loop += [("L", (x, ra)), ("L", (x, rb + f)), ("A", (x + d, rb + d), (x + f, rb))]
    loop += [("L", (xs[-1] - c, big[-1])), ("L", (xs[-1], big[-1] - c)), ("L", (xs[-1], small[-1]))]
    for i in range(n - 1, 0, -1):
        if small[i] != small[i - 1]:
            loop += [("L", (xs[i], small[i])), ("L", (xs[i], small[i - 1]))]
    return loop


def _profile(segments: object, fillet: object, chamfer: object) -> tuple[list[Segment], float, float]:
    """Checked segments, fillet and chamfer (m) of a turned shaft that fit together."""
    segs = _segment_list(segments)
    f_m = check_real(fillet, "fillet", "m", lo=0.0)
    c_m = check_real(chamfer, "chamfer", "m", lo=0.0)
    _check_profile(segs, f_m, c_m)
    return segs, f_m, c_m


def _turned(segs: Sequence[Segment], fillet: float, chamfer: float) -> bd.Part:
    """The turned shaft of checked segments, fillet and chamfer (m): one revolve."""
    return bd.Part([_revolve(_shaft_loop(segs, fillet, chamfer))])


def stepped_shaft(
    segments: Iterable[Segment | Mapping], *, fillet: float = 0.0, chamfer: float = 0.0
) -> bd.Part:
    """A turned shaft of cylindrical segments, solid or hollow, as one revolve.

    Parameters
    ----------
    segments : sequence of Segment or mapping
        From the driving end (x = 0) on; each a :class:`Segment` or a mapping
        with keys ``length``, ``od`` and optional ``id`` (m). Where ``id > 0``
        the segment is bored; the bore may step between segments. Adjacent
        segments must overlap radially (the larger bore smaller than the
        smaller outer diameter).
    fillet : float, optional
        Radius of the shoulder fillets at every outer-diameter step, m
        (0 = sharp). Must be smaller than every step height and leave length
        on the (smaller) segment that carries it. Default 0.
    chamfer : float, optional
        Leg of the 45° chamfer on the outer edge at both shaft ends, m
        (0 = none). Must be smaller than the wall at the ends. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm) from x = 0 to x = Σ length; cylinders, planes, cones
        (chamfers) and tori (fillets) only.

    Raises
    ------
    ModelError
        If a segment or the fillet/chamfer does not fit.
    """
    return _turned(*_profile(segments, fillet, chamfer))


def flanged_shaft(
    segments: Iterable[Segment | Mapping],
    circles: Iterable[BoltCircle] = (),
    *,
    fillet: float = 0.0,
    chamfer: float = 0.0,
) -> bd.Part:
    """A stepped shaft with bolt circles drilled through some of its segments (its flanges).

    :func:`stepped_shaft` then :func:`bolt_holes` (one revolve, one boolean),
    with the holes checked against the segments first so a misfit names the
    circle and the segment. Keep ``chamfer`` 0 on drilled end flanges where
    speed matters: OCCT intersects every hole with the chamfer's cone, which
    makes the boolean about five times slower.

    Parameters
    ----------
    segments : sequence of Segment or mapping
        As for :func:`stepped_shaft` (m).
    circles : sequence of BoltCircle
        Hole patterns (m). Each must start and end on segment boundaries (a
        flange, or a bolted stack of flanges), lie inside every segment it
        crosses, and leave into free space at both ends: the neighbouring
        segments (with their fillets) must stay inside the holes' inner
        edge.
    fillet : float, optional
        Shoulder fillet radius, m, as for :func:`stepped_shaft`. Default 0.
    chamfer : float, optional
        45° end chamfer, m, as for :func:`stepped_shaft`. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm) from x = 0 to x = Σ length.

    Raises
    ------
    ModelError
        If a segment, fillet or chamfer does not fit, or a bolt circle does
        not start and end on segment boundaries or does not fit its segments.
    """
    segs, f_m, c_m = _profile(segments, fillet, chamfer)
    circles = list(circles)
    n = len(segs)
    bounds = [0.0]
    for seg in segs:
        bounds.append(bounds[-1] + seg.length)
    tol = 1e-9 * bounds[-1]

    def boundary(x: float, field: str, value: float) -> int:
        hits = [k for k, b in enumerate(bounds) if abs(b - x) <= tol]
        if not hits:
            raise ModelError(
                "bolt circle must start and end on a segment boundary",
                field=field,
                value=value,
                unit="m",
                valid="ends at one of " + ", ".join(f"{b:g}" for b in bounds) + " m",
            )
        return hits[0]

    for i, circle in enumerate(circles):
        _check_circle(circle, i)
        k0 = boundary(circle.x_start, f"circles[{i}].x_start", circle.x_start)
        k1 = boundary(circle.x_start + circle.length, f"circles[{i}].length", circle.length)
        inner = circle.pitch_d - circle.hole_d  # diameter of the holes' inner edge
        outer = circle.pitch_d + circle.hole_d
        for k in range(k0, k1):
            rim = segs[k].od - 2.0 * c_m * (k in (0, n - 1))  # the end chamfer eats the rim
            if outer >= rim or inner <= segs[k].id:
                raise ModelError(
                    f"bolt holes do not fit inside segments[{k}] (od {segs[k].od:g} m, id {segs[k].id:g} m)",
                    field=f"circles[{i}].pitch_d",
                    value=circle.pitch_d,
                    unit="m",
                    valid=f"id {segs[k].id:g} < pitch_d ± hole_d < {rim:g} m",
                )
        for k in (k0 - 1, k1):
            if 0 <= k < n:
                # A smaller neighbour carries the shoulder fillet, which reaches f beyond its radius.
                reach = segs[k].od + 2.0 * f_m * (segs[k].od < segs[k0 if k < k0 else k1 - 1].od)
                if reach >= inner:
                    raise ModelError(
                        f"bolt holes run into segments[{k}] (reaching diameter {reach:g} m with its fillet)",
                        field=f"circles[{i}].pitch_d",
                        value=circle.pitch_d,
                        unit="m",
                        valid=f"pitch_d - hole_d > {reach:g} m, or a neighbour that clears the holes",
                    )
    shaft = _turned(segs, f_m, c_m)
    return bolt_holes(shaft, *circles) if circles else shaft


def bolt_holes(part: bd.Part, *circles: BoltCircle) -> bd.Part:
    """Drill one or more bolt circles of axial through holes into a part, in one boolean.

    Parameters
    ----------
    part : build123d.Part
        A part holding one solid (mm).
    *circles : BoltCircle
        The hole patterns (dimensions in m). Every hole must lie wholly in
        material over its ``length`` (checked by the volume removed).

    Returns
    -------
    build123d.Part
        One solid (mm) with the holes.

    Raises
    ------
    ModelError
        If a hole leaves the material, holes overlap, or the part splits.
    """
    solid = only_solid(part, "part")
    if not circles:
        raise ModelError("no bolt circles given", field="circles", value=0, valid="at least one BoltCircle")
    for i, circle in enumerate(circles):
        _check_circle(circle, i)
    # Cutters stick out a little past both ends so no hole face is coplanar with a part face.
    tools = [t for circle in circles for t in _hole_tools(circle, margin=0.5 * to_cad(circle.hole_d))]
    result = solid.cut(*tools)
    expected = sum(circle.volume for circle in circles)
    removed = volume_from_cad(solid.volume) - volume_from_cad(sum(s.volume for s in result.solids()))
    if abs(removed - expected) > 1e-6 * expected + 1e-9 * volume_from_cad(solid.volume):
        raise ModelError(
            f"bolt holes remove {removed:.6g} m³ instead of {expected:.6g} m³: they leave the material "
            "or overlap (check x_start, length, pitch_d)",
            field="circles",
            value=len(circles),
            valid="holes wholly inside solid material between x_start and x_start + length",
        )
    return as_part(result, "drilling bolt holes")


def flange(
    *,
    od: float,
    thickness: float,
    bore: float = 0.0,
    bolt_count: int = 0,
    bolt_hole_d: float = 0.0,
    pitch_d: float = 0.0,
    spigot_d: float = 0.0,
    spigot_length: float = 0.0,
    x: float = 0.0,
) -> bd.Part:
    """A flange disc with an optional bolt circle and centring spigot.

    Parameters
    ----------
    od : float
        Outer diameter, m (> 0).
    thickness : float
        Axial thickness of the disc, m (> 0); it spans x .. x + thickness.
    bore : float, optional
        Bore diameter, m (0 = solid). Default 0.
    bolt_count : int, optional
        Number of axial through holes (0 = none). The first hole is on +z
        (angle 0), the others follow right-handed about +x. Default 0.
    bolt_hole_d : float, optional
        Hole diameter, m (> 0 when bolt_count > 0, else 0). Default 0.
    pitch_d : float, optional
        Pitch-circle diameter, m; holes must lie between the bore (or spigot)
        and the outer diameter and not touch each other. Default 0.
    spigot_d : float, optional
        Diameter of the centring spigot, m (bore < spigot_d < od; 0 = none).
        Default 0.
    spigot_length : float, optional
        How far the spigot protrudes beyond the face at x + thickness, m
        (> 0 exactly when spigot_d > 0). Default 0.
    x : float, optional
        Axial position of the back face, m. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm) from x to x + thickness + spigot_length.

    Raises
    ------
    ModelError
        If a dimension is out of range or the holes do not fit.
    """
    od = check_real(od, "od", "m", lo=0.0, lo_open=True)
    thickness = check_real(thickness, "thickness", "m", lo=0.0, lo_open=True)
    bore = check_real(bore, "bore", "m", lo=0.0, hi=od, hi_open=True)
    bolt_count = check_int(bolt_count, "bolt_count", lo=0)
    bolt_hole_d = check_real(bolt_hole_d, "bolt_hole_d", "m", lo=0.0)
    pitch_d = check_real(pitch_d, "pitch_d", "m", lo=0.0)
    spigot_d = check_real(spigot_d, "spigot_d", "m", lo=0.0)
    spigot_length = check_real(spigot_length, "spigot_length", "m", lo=0.0)
    x = check_real(x, "x", "m")
    _both_or_neither(
        "spigot", ("spigot_d", spigot_d, "a diameter"), ("spigot_length", spigot_length, "a length")
    )
    if spigot_d > 0.0 and not bore < spigot_d < od:
        raise ModelError(
            "spigot not between bore and outer diameter",
            field="spigot_d",
            value=spigot_d,
            unit="m",
            valid=f"bore {bore:g} m < spigot_d < od {od:g} m",
        )
    inner_d, inner_name = (spigot_d, "spigot") if spigot_d > 0.0 else (bore, "bore")
    check_bolt_pattern(
        bolt_count,
        bolt_hole_d,
        pitch_d,
        inner_d=inner_d,
        inner_name=inner_name,
        outer_d=od,
        outer_name="flange rim",
    )
    x0, x1 = to_cad(x), to_cad(x + thickness)
    r_out, r_in = to_cad(od) / 2.0, to_cad(bore) / 2.0
    loop: list[tuple] = [("P", (x0, r_in)), ("L", (x0, r_out)), ("L", (x1, r_out))]
    if spigot_d > 0.0:
        r_sp, x2 = to_cad(spigot_d) / 2.0, to_cad(x + thickness + spigot_length)
        loop += [("L", (x1, r_sp)), ("L", (x2, r_sp)), ("L", (x2, r_in))]
    else:
        loop += [("L", (x1, r_in))]
    part = bd.Part([_revolve(loop)])
    if bolt_count:
        part = bolt_holes(part, BoltCircle(bolt_count, bolt_hole_d, pitch_d, x, thickness))
    return part


def coupling_hub(
    *,
    hub_od: float,
    hub_length: float,
    bore: float,
    flange_od: float,
    flange_thickness: float,
    bolt_count: int,
    bolt_hole_d: float,
    pitch_d: float,
    keyway_width: float = 0.0,
    keyway_depth: float = 0.0,
    flange_at: str = "end",
    x: float = 0.0,
) -> bd.Part:
    """A coupling half: a bored hub tube with a bolted flange at one end.

    Parameters
    ----------
    hub_od : float
        Hub outer diameter, m (> bore).
    hub_length : float
        Overall axial length, flange included, m (> flange_thickness).
    bore : float
        Bore diameter, m (> 0).
    flange_od : float
        Flange outer diameter, m (> hub_od).
    flange_thickness : float
        Axial flange thickness, m (> 0).
    bolt_count : int
        Number of axial through holes in the flange (>= 1); first on +z.
    bolt_hole_d : float
        Hole diameter, m (> 0).
    pitch_d : float
        Pitch-circle diameter, m; holes clear the hub
        (pitch_d - bolt_hole_d > hub_od) and the rim
        (pitch_d + bolt_hole_d < flange_od).
    keyway_width : float, optional
        Width of a keyway in the bore on the +z side, m (0 = plain bore,
        else < bore). Default 0.
    keyway_depth : float, optional
        Depth of the bore keyway measured from the bore on the keyway centre
        line, outward, m (> 0 with a width; bore/2 + depth < hub_od/2).
        Default 0.
    flange_at : {"end", "start"}, optional
        Whether the flange is at x + hub_length (facing +x) or at x. Default "end".
    x : float, optional
        Axial position of the hub's first face, m. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm) from x to x + hub_length.

    Raises
    ------
    ModelError
        If a dimension is out of range or parts do not fit together.
    """
    hub_od = check_real(hub_od, "hub_od", "m", lo=0.0, lo_open=True)
    hub_length = check_real(hub_length, "hub_length", "m", lo=0.0, lo_open=True)
    bore = check_real(bore, "bore", "m", lo=0.0, lo_open=True, hi=hub_od, hi_open=True)
    flange_od = check_real(flange_od, "flange_od", "m", lo=hub_od, lo_open=True)
    flange_thickness = check_real(
        flange_thickness, "flange_thickness", "m", lo=0.0, lo_open=True, hi=hub_length, hi_open=True
    )
    bolt_count = check_int(bolt_count, "bolt_count", lo=1)
    bolt_hole_d = check_real(bolt_hole_d, "bolt_hole_d", "m", lo=0.0, lo_open=True)
    pitch_d = check_real(pitch_d, "pitch_d", "m", lo=0.0, lo_open=True)
    keyway_width = check_real(keyway_width, "keyway_width", "m", lo=0.0, hi=bore, hi_open=True)
    keyway_depth = check_real(keyway_depth, "keyway_depth", "m", lo=0.0)
    flange_at = check_choice(flange_at, "flange_at", ("end", "start"))
    x = check_real(x, "x", "m")
    check_bolt_pattern(
        bolt_count,
        bolt_hole_d,
        pitch_d,
        inner_d=hub_od,
        inner_name="hub",
        outer_d=flange_od,
        outer_name="flange rim",
    )
    _both_or_neither(
        "keyway", ("keyway_width", keyway_width, "a width"), ("keyway_depth", keyway_depth, "a depth")
    )
    if keyway_depth > 0.0 and bore / 2.0 + keyway_depth >= hub_od / 2.0:
        raise ModelError(
            "keyway breaks through the hub wall",
            field="keyway_depth",
            value=keyway_depth,
            unit="m",
            valid=f"< hub wall {(hub_od - bore) / 2.0:g} m",
        )
    hub = Segment(hub_length - flange_thickness, hub_od, bore)
    disc = Segment(flange_thickness, flange_od, bore)
    shaft = stepped_shaft([hub, disc] if flange_at == "end" else [disc, hub])
    x_flange = x + hub_length - flange_thickness if flange_at == "end" else x
    # Shift the profile-built part (which starts at 0) to x before cutting, so all tools use absolute x.
    solid = only_solid(shaft, "hub").moved(bd.Location((to_cad(x), 0.0, 0.0)))
    part = bolt_holes(
        bd.Part([solid]), BoltCircle(bolt_count, bolt_hole_d, pitch_d, x_flange, flange_thickness)
    )
    if keyway_width > 0.0:
        w, r_b = to_cad(keyway_width), to_cad(bore) / 2.0
        margin = to_cad(keyway_depth)
        # A box from the axis to the keyway floor; the part inside the bore is empty already.
        box = bd.Solid.make_box(
            to_cad(hub_length) + 2.0 * margin,
            w,
            r_b + to_cad(keyway_depth),
            bd.Plane(origin=(to_cad(x) - margin, -w / 2.0, 0.0)),
        )
        part = as_part(only_solid(part, "hub").cut(box), "cutting the hub keyway")
    return part


def fuse(*parts: bd.Part) -> bd.Part:
    """Union of parts that touch or overlap, as one solid.

    Parameters
    ----------
    *parts : build123d.Part
        At least two parts, each one solid (mm).

    Returns
    -------
    build123d.Part
        One solid (mm); coplanar/coaxial faces are merged.

    Raises
    ------
    ModelError
        If fewer than two parts are given or the union is not exactly one solid.
    """
    if len(parts) < 2:
        raise ModelError("fuse needs at least two parts", field="parts", value=len(parts), valid=">= 2 parts")
    solids = [only_solid(p, f"parts[{i}]") for i, p in enumerate(parts)]
    # build123d's boolean already unifies faces of the same surface (ShapeUpgrade_UnifySameDomain).
    result = solids[0].fuse(*solids[1:])
    return as_part(result, "fusing the parts")
