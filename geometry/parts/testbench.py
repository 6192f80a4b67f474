"""Part library of the 9 MW drivetrain test bench, as parametric build123d solids.

The bench: a 9 MW, 1000 rpm induction motor (nominal torque
9e6 W / (1000 · 2π/60 rad/s) ≈ 86 kN·m) drives the generator under test through
a power-transmission shaft system (PTSS): motor – part 1 – part 2 – part 3
(composite coupling) – part 4 – generator. Parts 1 and 2 are steel shaft
pieces (part 2 carries an HBM T40-style torque-measuring flange), part 4 is the
short shaft to the generator flange.

No drawings of the bench are published. Every default below is a PLAUSIBLE
dimension chosen for a shaft line of this rating, NOT the bench's drawings:
tube bodies 0.28 m / 0.18 m (shear stress 16·T·D/(π(D⁴-d⁴)) ≈ 24 MPa at
86 kN·m), bolted flanges 0.52 m with 12 × M24 (0.026 m holes) on 0.44 m,
keys after DIN 6885-1 (50 × 28 mm for 200–230 mm shafts). Every PTSS flange
(both ends of parts 1 and 2, the torque-flange rings, part 4's coupling end)
has the same OD and bolt pattern with the first hole on +z; those of parts 1
and 2 and the torque-flange rings also share the 0.18 m bore, so their
sections are one shape and a slicer that caches section analyses by shape
sees few distinct shapes. Part 4 is solid.

Every function takes SI metres (keyword-only) and returns a
:class:`build123d.Part` of one solid in millimetres, axis along +x, driving end
at x = 0. Bolted joints are modelled as bonded (one solid); bolts and nuts are
not modelled, their holes are.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping
from dataclasses import dataclass

import build123d as bd

from flexshaft.errors import ModelError
from flexshaft.validation import check_int, check_real

from .. import parts
from ..units import to_cad
from .primitives import BoltCircle, Segment

__all__ = [
    "RATED_POWER",
    "RATED_SPEED_RPM",
    "NOMINAL_TORQUE",
    "motor_shaft_end",
    "coupling_hub",
    "ptss_part1",
    "torque_flange",
    "ptss_part2",
    "ptss_part4",
    "generator_shaft_end",
    "ptss",
]

#: Rated power of the bench motor, W.
RATED_POWER = 9.0e6
#: Rated speed of the bench motor, rpm.
RATED_SPEED_RPM = 1000.0
#: Nominal torque P / ω of the motor, N·m (≈ 85.9 kN·m).
NOMINAL_TORQUE = RATED_POWER / (RATED_SPEED_RPM * math.pi / 30.0)


def _pos(value: object, field: str) -> float:
    """A strictly positive length in m."""
    return check_real(value, field, "m", lo=0.0, lo_open=True)


def _nonneg(value: object, field: str) -> float:
    """A non-negative length in m (0 = feature absent)."""
    return check_real(value, field, "m", lo=0.0)


def _less(value: float, field: str, limit: float, what: str) -> None:
    """Refuse ``value >= limit`` (a bore not inside its body, a feature not fitting)."""
    if value >= limit:
        raise ModelError(
            f"must be smaller than {what}", field=field, value=value, unit="m", valid=f"< {limit:g} m"
        )


def _bolts(count: object, hole_d: object, pitch_d: object, *, hub_d: float, od: float, prefix: str = ""):
    """Validate a flange bolt pattern that must clear a hub (and its fillet) of diameter hub_d."""
    count = check_int(count, f"{prefix}bolt_count", lo=1)
    hole_d = _pos(hole_d, f"{prefix}bolt_hole_d")
    pitch_d = _pos(pitch_d, f"{prefix}pitch_d")
    parts.check_bolt_pattern(
        count,
        hole_d,
        pitch_d,
        inner_d=hub_d,
        inner_name="hub with its fillet",
        outer_d=od,
        outer_name="flange rim",
        prefix=prefix,
    )
    return count, hole_d, pitch_d


@dataclass(frozen=True)
class _FlangedTube:
    """The flanged tube of PTSS parts 1 and 2: flange | hub | tube | hub | flange, bored through (m)."""

    flange_thickness: float
    hub_length: float
    flange_od: float
    hub_od: float
    tube_od: float
    tube_id: float
    fillet: float

    @classmethod
    def checked(
        cls, flange_thickness, hub_length, flange_od, hub_od, tube_od, tube_id, fillet
    ) -> _FlangedTube:
        """The dimensions checked, each refused naming its argument."""
        flange_thickness = _pos(flange_thickness, "flange_thickness")
        hub_length = _pos(hub_length, "hub_length")
        flange_od, hub_od = _pos(flange_od, "flange_od"), _pos(hub_od, "hub_od")
        tube_od, tube_id = _pos(tube_od, "tube_od"), _nonneg(tube_id, "tube_id")
        fillet = _nonneg(fillet, "fillet")
        _less(tube_id, "tube_id", min(tube_od, hub_od), "the tube and hub diameters")
        return cls(flange_thickness, hub_length, flange_od, hub_od, tube_od, tube_id, fillet)

    @property
    def ends(self) -> float:
        """Axial length of the two flanges and hubs, m."""
        return 2.0 * (self.flange_thickness + self.hub_length)

    def segments(self, tube: float) -> list[Segment]:
        """The five segments from x = 0 with a tube ``tube`` m long."""
        return [
            Segment(self.flange_thickness, self.flange_od, self.tube_id),
            Segment(self.hub_length, self.hub_od, self.tube_id),
            Segment(tube, self.tube_od, self.tube_id),
            Segment(self.hub_length, self.hub_od, self.tube_id),
            Segment(self.flange_thickness, self.flange_od, self.tube_id),
        ]


def _tube_length(length: float, ends: float) -> float:
    """Length left for the tube once flanges and hubs (``ends``, m) are taken off."""
    if length <= ends:
        raise ModelError(
            "too short for its flanges and hubs",
            field="length",
            value=length,
            unit="m",
            valid=f"> {ends:g} m (flanges + hubs)",
        )
    return length - ends


def motor_shaft_end(
    *,
    body_d: float = 0.26,
    body_length: float = 0.30,
    seat_d: float = 0.22,
    seat_length: float = 0.35,
    keyway_width: float = 0.050,
    keyway_depth: float = 0.017,
    keyway_length: float = 0.28,
    fillet: float = 0.005,
    chamfer: float = 0.003,
) -> bd.Part:
    """The motor's output shaft end: a bearing-side body and a keyed coupling seat.

    Defaults are plausible dimensions, not the bench's drawings.

    Parameters
    ----------
    body_d : float, optional
        Diameter of the body towards the motor (x = 0), m. Default 0.26.
    body_length : float, optional
        Its length, m. Default 0.30.
    seat_d : float, optional
        Diameter of the coupling seat at the free end, m (< body_d). Default 0.22.
    seat_length : float, optional
        Its length, m. Default 0.35.
    keyway_width : float, optional
        Key width b, m (DIN 6885-1, 200–230 mm shafts: 50 mm). Default 0.050.
    keyway_depth : float, optional
        Shaft keyway depth t1, m (DIN 6885-1: 17 mm). Default 0.017.
    keyway_length : float, optional
        Keyway length, round-ended and centred on the seat, m
        (< seat_length - 2·fillet). Default 0.28.
    fillet : float, optional
        Shoulder fillet radius, m. Default 0.005.
    chamfer : float, optional
        45° end chamfer, m. Default 0.003.

    Returns
    -------
    build123d.Part
        One solid (mm), x from 0 to body_length + seat_length (0.65 m by default).
    """
    body_d, body_length = _pos(body_d, "body_d"), _pos(body_length, "body_length")
    seat_d, seat_length = _pos(seat_d, "seat_d"), _pos(seat_length, "seat_length")
    keyway_length = _pos(keyway_length, "keyway_length")
    fillet = _nonneg(fillet, "fillet")
    _less(seat_d, "seat_d", body_d, "body_d (a shoulder for the hub)")
    _less(keyway_length, "keyway_length", seat_length - 2.0 * fillet, "the seat length clear of its fillet")
    shaft = parts.stepped_shaft(
        [Segment(body_length, body_d), Segment(seat_length, seat_d)], fillet=fillet, chamfer=chamfer
    )
    return parts.keyway(
        shaft,
        width=keyway_width,
        depth=keyway_depth,
        length=keyway_length,
        x_start=body_length + (seat_length - keyway_length) / 2.0,
        diameter=seat_d,
        rounded_ends=True,
    )


def coupling_hub(
    *,
    bore: float = 0.22,
    hub_od: float = 0.34,
    hub_length: float = 0.35,
    flange_od: float = 0.52,
    flange_thickness: float = 0.06,
    bolt_count: int = 12,
    bolt_hole_d: float = 0.026,
    pitch_d: float = 0.44,
    keyway_width: float = 0.050,
    keyway_depth: float = 0.0114,
) -> bd.Part:
    """The coupling hub on the motor shaft end: keyed hub, bolted flange facing +x.

    Defaults are plausible dimensions, not the bench's drawings; they fit
    :func:`motor_shaft_end` (bore = seat_d, hub_length = seat_length) and the
    PTSS flange (:func:`ptss_part1`).

    Parameters
    ----------
    bore : float, optional
        Bore diameter, m. Default 0.22.
    hub_od : float, optional
        Hub outer diameter, m. Default 0.34.
    hub_length : float, optional
        Overall length with the flange, m. Default 0.35.
    flange_od : float, optional
        Flange outer diameter, m. Default 0.52.
    flange_thickness : float, optional
        Flange thickness, m. Default 0.06.
    bolt_count : int, optional
        Flange bolt holes. Default 12.
    bolt_hole_d : float, optional
        Hole diameter, m (M24 clearance). Default 0.026.
    pitch_d : float, optional
        Pitch-circle diameter, m. Default 0.44.
    keyway_width : float, optional
        Hub keyway width b, m (DIN 6885-1: 50 mm). Default 0.050.
    keyway_depth : float, optional
        Hub keyway depth t2 from the bore, m (DIN 6885-1: 11.4 mm). Default 0.0114.

    Returns
    -------
    build123d.Part
        One solid (mm), x from 0 to hub_length, flange at the +x end.
    """
    return parts.coupling_hub(
        hub_od=hub_od,
        hub_length=hub_length,
        bore=bore,
        flange_od=flange_od,
        flange_thickness=flange_thickness,
        bolt_count=bolt_count,
        bolt_hole_d=bolt_hole_d,
        pitch_d=pitch_d,
        keyway_width=keyway_width,
        keyway_depth=keyway_depth,
        flange_at="end",
    )


def ptss_part1(
    *,
    length: float = 3.0,
    tube_od: float = 0.28,
    tube_id: float = 0.18,
    hub_od: float = 0.34,
    hub_length: float = 0.12,
    flange_od: float = 0.52,
    flange_thickness: float = 0.06,
    bolt_count: int = 12,
    bolt_hole_d: float = 0.026,
    pitch_d: float = 0.44,
    fillet: float = 0.01,
    chamfer: float = 0.0,
) -> bd.Part:
    """PTSS part 1: a steel tube with a hub and a bolted flange at each end.

    Defaults are plausible dimensions, not the bench's drawings. The section
    from x = 0 is flange | hub | tube | hub | flange, bored through with
    ``tube_id``; both flanges carry the same bolt circle (first hole on +z) so
    they, and the mating flange of part 2, share one section shape.

    Parameters
    ----------
    length : float, optional
        Overall length, m. Default 3.0.
    tube_od, tube_id : float, optional
        Tube outer and bore diameters, m. Defaults 0.28, 0.18.
    hub_od : float, optional
        Diameter of the hubs behind the flanges, m. Default 0.34.
    hub_length : float, optional
        Length of each hub, m. Default 0.12.
    flange_od : float, optional
        Flange outer diameter, m. Default 0.52.
    flange_thickness : float, optional
        Thickness of each flange, m. Default 0.06.
    bolt_count : int, optional
        Bolt holes per flange. Default 12.
    bolt_hole_d : float, optional
        Hole diameter, m (M24 clearance). Default 0.026.
    pitch_d : float, optional
        Pitch-circle diameter, m. Default 0.44.
    fillet : float, optional
        Shoulder fillet radius (flange/hub, hub/tube), m. Default 0.01.
    chamfer : float, optional
        45° chamfer on the rims of the two end flanges, m. Default 0: a cone
        on a drilled flange makes OCCT's hole boolean about five times slower
        and does nothing for the dynamics.

    Returns
    -------
    build123d.Part
        One solid (mm), x from 0 to length.
    """
    length = _pos(length, "length")
    ft = _FlangedTube.checked(flange_thickness, hub_length, flange_od, hub_od, tube_od, tube_id, fillet)
    tube = _tube_length(length, ft.ends)
    count, hole_d, pitch = _bolts(
        bolt_count, bolt_hole_d, pitch_d, hub_d=ft.hub_od + 2.0 * ft.fillet, od=ft.flange_od
    )
    t = ft.flange_thickness
    return parts.flanged_shaft(
        ft.segments(tube),
        [BoltCircle(count, hole_d, pitch, 0.0, t), BoltCircle(count, hole_d, pitch, length - t, t)],
        fillet=ft.fillet,
        chamfer=chamfer,
    )


def _torque_flange_segments(od: float, ring: float, web_d: float, web_length: float, bore: float):
    """Ring | measuring web | ring of the torque flange, validated, as segments."""
    od, ring = _pos(od, "od"), _pos(ring, "ring_thickness")
    web_d, web_length = _pos(web_d, "web_d"), _pos(web_length, "web_length")
    bore = _nonneg(bore, "bore")
    _less(web_d, "web_d", od, "od")
    _less(bore, "bore", web_d, "web_d")
    return [Segment(ring, od, bore), Segment(web_length, web_d, bore), Segment(ring, od, bore)]


def torque_flange(
    *,
    od: float = 0.52,
    ring_thickness: float = 0.03,
    web_d: float = 0.30,
    web_length: float = 0.04,
    bore: float = 0.18,
    bolt_count: int = 12,
    bolt_hole_d: float = 0.026,
    pitch_d: float = 0.44,
    fillet: float = 0.01,
    x: float = 0.0,
) -> bd.Part:
    """A torque-measuring flange (HBM T40 style), idealised as a turned spool.

    Defaults are plausible dimensions, not the bench's (or HBM's) drawings.
    Two bolted rings, each drilled with the PTSS bolt circle, are joined by a
    short measuring web of diameter ``web_d`` that carries the torque (and
    the strain gauges); bolt heads sit in the gap beside the web. The real
    T40 measuring body (spokes, inner and outer bolt circles) is not modelled.

    Parameters
    ----------
    od : float, optional
        Outer diameter of both rings, m (= the PTSS flange). Default 0.52.
    ring_thickness : float, optional
        Axial thickness of each bolted ring, m. Default 0.03.
    web_d : float, optional
        Diameter of the measuring web, m (< pitch_d - bolt_hole_d - 2·fillet). Default 0.30.
    web_length : float, optional
        Axial length of the web, m (> 2·fillet). Default 0.04.
    bore : float, optional
        Bore diameter, m (= the PTSS tube bore). Default 0.18.
    bolt_count : int, optional
        Bolt holes per ring. Default 12.
    bolt_hole_d : float, optional
        Hole diameter, m. Default 0.026.
    pitch_d : float, optional
        Pitch-circle diameter, m. Default 0.44.
    fillet : float, optional
        Fillet radius where the web meets the rings, m. Default 0.01.
    x : float, optional
        Axial position of the driving-side face, m. Default 0.

    Returns
    -------
    build123d.Part
        One solid (mm), x .. x + 2·ring_thickness + web_length (0.10 m by default).
    """
    segs = _torque_flange_segments(od, ring_thickness, web_d, web_length, bore)
    x = check_real(x, "x", "m")
    fillet = _nonneg(fillet, "fillet")
    count, hole_d, pitch = _bolts(bolt_count, bolt_hole_d, pitch_d, hub_d=segs[1].od + 2.0 * fillet, od=od)
    ring, total = segs[0].length, sum(s.length for s in segs)
    body = parts.flanged_shaft(
        segs,
        [BoltCircle(count, hole_d, pitch, 0.0, ring), BoltCircle(count, hole_d, pitch, total - ring, ring)],
        fillet=fillet,
    )
    return bd.Part([body.solids()[0].moved(bd.Location((to_cad(x), 0.0, 0.0)))]) if x else body


def ptss_part2(
    *,
    length: float = 5.8,
    torque_flange_x: float = 1.2,
    tube_od: float = 0.28,
    tube_id: float = 0.18,
    hub_od: float = 0.34,
    hub_length: float = 0.12,
    flange_od: float = 0.52,
    flange_thickness: float = 0.06,
    bolt_count: int = 12,
    bolt_hole_d: float = 0.026,
    pitch_d: float = 0.44,
    ring_thickness: float = 0.03,
    web_d: float = 0.30,
    web_length: float = 0.04,
    fillet: float = 0.01,
    chamfer: float = 0.0,
) -> bd.Part:
    """PTSS part 2: two flanged steel tubes with the torque flange bolted between them.

    Defaults are plausible dimensions, not the bench's drawings. From x = 0:
    flanged tube A (flange | hub | tube | hub | flange), the torque flange
    (ring | web | ring, see :func:`torque_flange`), flanged tube B. Every
    flange and both torque-flange rings carry the same bolt circle as
    :func:`ptss_part1` (first hole on +z); each bolted pair is drilled through
    as one hole. Bolted joints are bonded, so the result is one solid.

    Parameters
    ----------
    length : float, optional
        Overall length, m. Default 5.8.
    torque_flange_x : float, optional
        Position of the torque flange's driving-side face (= length of tube
        A with its flanges), m. Default 1.2.
    tube_od, tube_id : float, optional
        Tube outer and bore diameters, m (the bore runs through, torque flange
        included). Defaults 0.28, 0.18.
    hub_od, hub_length : float, optional
        Hubs behind the flanges, m. Defaults 0.34, 0.12.
    flange_od, flange_thickness : float, optional
        Flanges (and torque-flange ring diameter), m. Defaults 0.52, 0.06.
    bolt_count : int, optional
        Bolt holes per flange. Default 12.
    bolt_hole_d, pitch_d : float, optional
        Hole and pitch-circle diameters, m. Defaults 0.026, 0.44.
    ring_thickness, web_d, web_length : float, optional
        Torque flange rings and measuring web, m. Defaults 0.03, 0.30, 0.04.
    fillet : float, optional
        Shoulder fillet radius, m. Default 0.01.
    chamfer : float, optional
        45° chamfer on the rims of the two end flanges, m. Default 0: a cone
        on a drilled flange makes OCCT's hole boolean about five times slower
        and does nothing for the dynamics.

    Returns
    -------
    build123d.Part
        One solid (mm), x from 0 to length.
    """
    length = _pos(length, "length")
    x_tf = _pos(torque_flange_x, "torque_flange_x")
    ft = _FlangedTube.checked(flange_thickness, hub_length, flange_od, hub_od, tube_od, tube_id, fillet)
    _less(ft.tube_id, "tube_id", _pos(web_d, "web_d"), "the torque flange's web_d")
    tf = _torque_flange_segments(ft.flange_od, ring_thickness, web_d, web_length, ft.tube_id)
    tf_length = sum(s.length for s in tf)
    if x_tf <= ft.ends:
        raise ModelError(
            "leaves no tube before the torque flange",
            field="torque_flange_x",
            value=x_tf,
            unit="m",
            valid=f"> {ft.ends:g} m (flanges + hubs of tube A)",
        )
    tube_a = x_tf - ft.ends
    tube_b = _tube_length(length, x_tf + tf_length + ft.ends)
    count, hole_d, pitch = _bolts(
        bolt_count, bolt_hole_d, pitch_d, hub_d=max(ft.hub_od, tf[1].od) + 2.0 * ft.fillet, od=ft.flange_od
    )
    t, ring = ft.flange_thickness, tf[0].length
    x_b = x_tf + tf_length  # driving-side face of tube B's first flange
    return parts.flanged_shaft(
        ft.segments(tube_a) + tf + ft.segments(tube_b),
        [
            BoltCircle(count, hole_d, pitch, 0.0, t),
            # flange A + ring 1 and ring 2 + flange B are each drilled through in one go
            BoltCircle(count, hole_d, pitch, x_tf - t, t + ring),
            BoltCircle(count, hole_d, pitch, x_b - ring, ring + t),
            BoltCircle(count, hole_d, pitch, length - t, t),
        ],
        fillet=ft.fillet,
        chamfer=chamfer,
    )


def ptss_part4(
    *,
    length: float = 1.0,
    body_d: float = 0.26,
    hub_od: float = 0.34,
    hub_length: float = 0.10,
    flange_od: float = 0.52,
    flange_thickness: float = 0.06,
    bolt_count: int = 12,
    bolt_hole_d: float = 0.026,
    pitch_d: float = 0.44,
    generator_flange_od: float = 0.60,
    generator_flange_thickness: float = 0.07,
    generator_bolt_count: int = 16,
    generator_bolt_hole_d: float = 0.030,
    generator_pitch_d: float = 0.52,
    fillet: float = 0.01,
    chamfer: float = 0.0,
) -> bd.Part:
    """PTSS part 4: the short solid shaft from the coupling (part 3) to the generator flange.

    Defaults are plausible dimensions, not the bench's drawings. From x = 0:
    coupling-side flange (the PTSS flange of :func:`ptss_part1`) | hub |
    solid body | hub | generator flange (mates :func:`generator_shaft_end`).

    Parameters
    ----------
    length : float, optional
        Overall length, m. Default 1.0.
    body_d : float, optional
        Diameter of the solid body, m (shear stress ≈ 25 MPa at 86 kN·m). Default 0.26.
    hub_od, hub_length : float, optional
        Hubs behind both flanges, m. Defaults 0.34, 0.10.
    flange_od, flange_thickness : float, optional
        Coupling-side flange, m. Defaults 0.52, 0.06.
    bolt_count : int, optional
        Coupling-side bolt holes. Default 12.
    bolt_hole_d, pitch_d : float, optional
        Coupling-side hole and pitch diameters, m. Defaults 0.026, 0.44.
    generator_flange_od, generator_flange_thickness : float, optional
        Generator-side flange, m. Defaults 0.60, 0.07.
    generator_bolt_count : int, optional
        Generator-side bolt holes (M27 clearance). Default 16.
    generator_bolt_hole_d, generator_pitch_d : float, optional
        Generator-side hole and pitch diameters, m. Defaults 0.030, 0.52.
    fillet : float, optional
        Shoulder fillet radius, m. Default 0.01.
    chamfer : float, optional
        45° chamfer on the rims of the two end flanges, m. Default 0: a cone
        on a drilled flange makes OCCT's hole boolean about five times slower
        and does nothing for the dynamics.

    Returns
    -------
    build123d.Part
        One solid (mm), x from 0 to length.
    """
    length, body_d = _pos(length, "length"), _pos(body_d, "body_d")
    hub_od, hub_length = _pos(hub_od, "hub_od"), _pos(hub_length, "hub_length")
    flange_od, flange_thickness = _pos(flange_od, "flange_od"), _pos(flange_thickness, "flange_thickness")
    gen_od = _pos(generator_flange_od, "generator_flange_od")
    gen_t = _pos(generator_flange_thickness, "generator_flange_thickness")
    fillet = _nonneg(fillet, "fillet")
    body = _tube_length(length, flange_thickness + 2.0 * hub_length + gen_t)
    hub_d = hub_od + 2.0 * fillet
    count, hole_d, pitch = _bolts(bolt_count, bolt_hole_d, pitch_d, hub_d=hub_d, od=flange_od)
    g_count, g_hole_d, g_pitch = _bolts(
        generator_bolt_count,
        generator_bolt_hole_d,
        generator_pitch_d,
        hub_d=hub_d,
        od=gen_od,
        prefix="generator_",
    )
    return parts.flanged_shaft(
        [
            Segment(flange_thickness, flange_od),
            Segment(hub_length, hub_od),
            Segment(body, body_d),
            Segment(hub_length, hub_od),
            Segment(gen_t, gen_od),
        ],
        [
            BoltCircle(count, hole_d, pitch, 0.0, flange_thickness),
            BoltCircle(g_count, g_hole_d, g_pitch, length - gen_t, gen_t),
        ],
        fillet=fillet,
        chamfer=chamfer,
    )


def generator_shaft_end(
    *,
    flange_od: float = 0.60,
    flange_thickness: float = 0.07,
    bolt_count: int = 16,
    bolt_hole_d: float = 0.030,
    pitch_d: float = 0.52,
    journal_d: float = 0.34,
    journal_length: float = 0.30,
    shaft_d: float = 0.30,
    shaft_length: float = 0.40,
    fillet: float = 0.008,
    chamfer: float = 0.0,
) -> bd.Part:
    """The generator's input shaft end: a forged flange facing part 4, a journal and the shaft.

    Defaults are plausible dimensions, not the bench's drawings; the flange
    matches the generator flange of :func:`ptss_part4`.

    Parameters
    ----------
    flange_od, flange_thickness : float, optional
        Flange at x = 0, m. Defaults 0.60, 0.07.
    bolt_count : int, optional
        Flange bolt holes. Default 16.
    bolt_hole_d, pitch_d : float, optional
        Hole and pitch-circle diameters, m. Defaults 0.030, 0.52.
    journal_d, journal_length : float, optional
        Bearing journal behind the flange, m. Defaults 0.34, 0.30.
    shaft_d, shaft_length : float, optional
        Shaft towards the rotor, m. Defaults 0.30, 0.40.
    fillet : float, optional
        Shoulder fillet radius, m. Default 0.008.
    chamfer : float, optional
        45° chamfer at both ends (the flange rim and the free end), m.
        Default 0, for build speed (see :func:`ptss_part1`).

    Returns
    -------
    build123d.Part
        One solid (mm), x from 0 to flange_thickness + journal_length + shaft_length (0.77 m).
    """
    flange_od, flange_thickness = _pos(flange_od, "flange_od"), _pos(flange_thickness, "flange_thickness")
    journal_d, fillet = _pos(journal_d, "journal_d"), _nonneg(fillet, "fillet")
    count, hole_d, pitch = _bolts(
        bolt_count, bolt_hole_d, pitch_d, hub_d=journal_d + 2.0 * fillet, od=flange_od
    )
    return parts.flanged_shaft(
        [
            Segment(flange_thickness, flange_od),
            Segment(journal_length, journal_d),
            Segment(shaft_length, shaft_d),
        ],
        [BoltCircle(count, hole_d, pitch, 0.0, flange_thickness)],
        fillet=fillet,
        chamfer=chamfer,
    )


_PTSS = {"part1": ("part 1", ptss_part1), "part2": ("part 2", ptss_part2), "part4": ("part 4", ptss_part4)}


def ptss(**overrides: Mapping[str, object]) -> dict[str, bd.Part]:
    """The PTSS shaft pieces 1, 2 and 4 with their default (plausible) dimensions.

    Parameters
    ----------
    **overrides : mapping
        Keyword arguments per part: ``part1``, ``part2``, ``part4``, each a
        mapping of that function's arguments (metres), e.g.
        ``ptss(part2={"length": 6.0})``. Keep the flanges of parts 1/2
        consistent when changing them.

    Returns
    -------
    dict of str to build123d.Part
        ``{"part 1": ..., "part 2": ..., "part 4": ...}``, each one solid in mm
        from x = 0 (every part in its own frame).

    Raises
    ------
    ModelError
        For an unknown part or argument, or a bad dimension.
    """
    for key, given in overrides.items():
        if key not in _PTSS:
            raise ModelError(
                "unknown part", field=key, value=given, valid="part1, part2 or part4", has_value=True
            )
        if not isinstance(given, Mapping):
            raise ModelError(
                "not a mapping of arguments", field=key, value=given, valid="a dict of keyword arguments (m)"
            )
        allowed = inspect.signature(_PTSS[key][1]).parameters
        for name in given:
            if name not in allowed:
                raise ModelError(
                    f"unknown argument of {_PTSS[key][1].__name__}",
                    field=f"{key}.{name}",
                    value=given[name],
                    valid=", ".join(allowed),
                    has_value=True,
                )
    result = {}
    for key, (name, build) in _PTSS.items():
        try:
            result[name] = build(**overrides.get(key, {}))
        except ModelError as err:
            raise err.located(component=key) from None
    return result
