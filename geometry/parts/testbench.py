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

The dimensions live in one table, :data:`DIMENSIONS` (per part its keyword
dimensions: default, meaning, check), built from the shared flanges, hubs and
keys below; each part function is its builder (a few lines taking the checked
dimensions) with the signature and the Parameters of its docstring read off the
table, so a dimension, its default and its check are written once.
"""

from __future__ import annotations

import inspect
import math
import textwrap
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, make_dataclass
from types import MappingProxyType

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


# --------------------------------------------------------------------------- the dimensions table


@dataclass(frozen=True)
class Dimension:
    """One keyword dimension of a bench part.

    Parameters
    ----------
    default : float or int
        Its default: a plausible value, not the bench's drawings (m; a count for bolt counts).
    meaning : str
        What it is, for the part function's docstring (without unit or default).
    check : {"length", "size", "count", "position"} or None, optional
        How the part function checks it before building: a length > 0 m, a size >= 0 m
        (0 = absent), a count >= 1, any position in m; None when the primitive it is handed to
        checks it (naming the same field). Default "length".
    """

    default: float | int
    meaning: str
    check: str | None = "length"


@dataclass(frozen=True)
class BoltedFlange:
    """A bolted flange: outer diameter and thickness, its bolt circle (m, first hole on +z) and bolt size."""

    od: float
    thickness: float
    bolt_count: int
    bolt_hole_d: float
    pitch_d: float
    bolt: str


#: The PTSS flange (both ends of parts 1 and 2, the torque-flange rings, part 4's coupling end and
#: the coupling hub).
PTSS_FLANGE = BoltedFlange(
    od=0.52, thickness=0.06, bolt_count=12, bolt_hole_d=0.026, pitch_d=0.44, bolt="M24"
)
#: The generator flange (part 4's far end and the generator's shaft end).
GENERATOR_FLANGE = BoltedFlange(
    od=0.60, thickness=0.07, bolt_count=16, bolt_hole_d=0.030, pitch_d=0.52, bolt="M27"
)
#: The keyed motor-coupling seat (DIN 6885-1 for 200–230 mm shafts): seat (= hub bore) diameter and
#: length, key width, keyway depth in the shaft (t1) and in the hub (t2), m.
SEAT_D, SEAT_LENGTH, KEY_WIDTH, KEY_SHAFT_DEPTH, KEY_HUB_DEPTH = 0.22, 0.35, 0.050, 0.017, 0.0114
#: The PTSS tube: outer and bore diameters, m; the hubs behind its flanges, m.
TUBE_OD, TUBE_ID, HUB_OD = 0.28, 0.18, 0.34

_NO_CHAMFER = (
    "45° chamfer on the rims of the two end flanges (keep it 0: a cone on a drilled flange makes OCCT's "
    "hole boolean about five times slower and does nothing for the dynamics)"
)


def _bolt_rows(flange: BoltedFlange, what: str, prefix: str = "", check: bool = True) -> dict:
    """The bolt circle of ``flange`` as rows ``{prefix}bolt_count`` ..., checked here or by the primitive."""
    kind = "length" if check else None
    return {
        f"{prefix}bolt_count": Dimension(
            flange.bolt_count, f"Bolt holes per {what}", "count" if check else None
        ),
        f"{prefix}bolt_hole_d": Dimension(
            flange.bolt_hole_d, f"Hole diameter ({flange.bolt} clearance)", kind
        ),
        f"{prefix}pitch_d": Dimension(flange.pitch_d, "Pitch-circle diameter", kind),
    }


def _flange_rows(flange: BoltedFlange, what: str, prefix: str = "", check: bool = True) -> dict:
    """Outer diameter, thickness and bolt circle of ``flange`` as rows ``{prefix}flange_od`` ..."""
    kind = "length" if check else None
    return {
        f"{prefix}flange_od": Dimension(flange.od, f"{what[0].upper()}{what[1:]} outer diameter", kind),
        f"{prefix}flange_thickness": Dimension(
            flange.thickness, f"{what[0].upper()}{what[1:]} thickness", kind
        ),
        **_bolt_rows(flange, what, prefix, check),
    }


_TUBE = {
    "tube_od": Dimension(TUBE_OD, "Tube outer diameter"),
    "tube_id": Dimension(TUBE_ID, "Tube bore diameter; the bore runs through the part", "size"),
    "hub_od": Dimension(HUB_OD, "Diameter of the hubs behind the flanges"),
    "hub_length": Dimension(0.12, "Length of each hub"),
}
_TORQUE_FLANGE_BODY = {
    "ring_thickness": Dimension(0.03, "Axial thickness of each bolted ring of the torque flange"),
    "web_d": Dimension(
        0.30, "Diameter of the torque flange's measuring web (< pitch_d - bolt_hole_d - 2·fillet)"
    ),
    "web_length": Dimension(0.04, "Axial length of the measuring web (> 2·fillet)"),
}
_FILLET = {"fillet": Dimension(0.01, "Shoulder fillet radius", "size")}
_FLANGE_CHAMFER = {"chamfer": Dimension(0.0, _NO_CHAMFER, None)}

#: Per part function, its keyword dimensions in signature order (SI; read-only).
DIMENSIONS: Mapping[str, Mapping[str, Dimension]] = MappingProxyType(
    {
        name: MappingProxyType(rows)
        for name, rows in {
            "motor_shaft_end": {
                "body_d": Dimension(0.26, "Diameter of the body towards the motor (x = 0)"),
                "body_length": Dimension(0.30, "Length of the body"),
                "seat_d": Dimension(SEAT_D, "Diameter of the coupling seat at the free end (< body_d)"),
                "seat_length": Dimension(SEAT_LENGTH, "Length of the coupling seat"),
                "keyway_width": Dimension(KEY_WIDTH, "Key width b (DIN 6885-1)", None),
                "keyway_depth": Dimension(KEY_SHAFT_DEPTH, "Shaft keyway depth t1 (DIN 6885-1)", None),
                "keyway_length": Dimension(
                    0.28, "Keyway length, round-ended and centred on the seat (< seat_length - 2·fillet)"
                ),
                "fillet": Dimension(0.005, "Shoulder fillet radius", "size"),
                "chamfer": Dimension(0.003, "45° end chamfer", None),
            },
            "coupling_hub": {
                "bore": Dimension(SEAT_D, "Bore diameter (= the motor shaft's seat_d)", None),
                "hub_od": Dimension(HUB_OD, "Hub outer diameter", None),
                "hub_length": Dimension(SEAT_LENGTH, "Overall length with the flange (= seat_length)", None),
                **_flange_rows(PTSS_FLANGE, "flange", check=False),
                "keyway_width": Dimension(KEY_WIDTH, "Hub keyway width b (DIN 6885-1)", None),
                "keyway_depth": Dimension(
                    KEY_HUB_DEPTH, "Hub keyway depth t2 from the bore (DIN 6885-1)", None
                ),
            },
            "ptss_part1": {
                "length": Dimension(3.0, "Overall length"),
                **_TUBE,
                **_flange_rows(PTSS_FLANGE, "flange"),
                **_FILLET,
                **_FLANGE_CHAMFER,
            },
            "torque_flange": {
                "od": Dimension(PTSS_FLANGE.od, "Outer diameter of both rings (= the PTSS flange)"),
                **_TORQUE_FLANGE_BODY,
                "bore": Dimension(TUBE_ID, "Bore diameter (= the PTSS tube bore)", "size"),
                **_bolt_rows(PTSS_FLANGE, "ring"),
                "fillet": Dimension(0.01, "Fillet radius where the web meets the rings", "size"),
                "x": Dimension(0.0, "Axial position of the driving-side face", "position"),
            },
            "ptss_part2": {
                "length": Dimension(5.8, "Overall length"),
                "torque_flange_x": Dimension(
                    1.2,
                    "Position of the torque flange's driving-side face (= length of tube A with its flanges)",
                ),
                **_TUBE,
                **_flange_rows(PTSS_FLANGE, "flange"),
                **_TORQUE_FLANGE_BODY,
                **_FILLET,
                **_FLANGE_CHAMFER,
            },
            "ptss_part4": {
                "length": Dimension(1.0, "Overall length"),
                "body_d": Dimension(0.26, "Diameter of the solid body (shear stress ≈ 25 MPa at 86 kN·m)"),
                "hub_od": _TUBE["hub_od"],
                "hub_length": Dimension(0.10, "Length of each hub"),
                **_flange_rows(PTSS_FLANGE, "coupling-side flange"),
                **_flange_rows(GENERATOR_FLANGE, "generator-side flange", "generator_"),
                **_FILLET,
                **_FLANGE_CHAMFER,
            },
            "generator_shaft_end": {
                **_flange_rows(GENERATOR_FLANGE, "flange (at x = 0, mating ptss_part4's generator flange)"),
                "journal_d": Dimension(0.34, "Diameter of the bearing journal behind the flange"),
                "journal_length": Dimension(0.30, "Length of the journal", None),
                "shaft_d": Dimension(0.30, "Diameter of the shaft towards the rotor", None),
                "shaft_length": Dimension(0.40, "Length of that shaft", None),
                "fillet": Dimension(0.008, "Shoulder fillet radius", "size"),
                "chamfer": Dimension(0.0, "45° chamfer at both ends (the flange rim and the free end)", None),
            },
        }.items()
    }
)


# --------------------------------------------------------------------------- checks


def _checked(field: str, value: object, check: str | None) -> object:
    """``value`` of dimension ``field`` as its check wants it (refused naming the field)."""
    if check == "length":
        return check_real(value, field, "m", lo=0.0, lo_open=True)
    if check == "size":
        return check_real(value, field, "m", lo=0.0)
    if check == "count":
        return check_int(value, field, lo=1)
    if check == "position":
        return check_real(value, field, "m")
    return value


def _less(value: float, field: str, limit: float, what: str) -> None:
    """Refuse ``value >= limit`` (a bore not inside its body, a feature not fitting)."""
    if value >= limit:
        raise ModelError(
            f"must be smaller than {what}", field=field, value=value, unit="m", valid=f"< {limit:g} m"
        )


def _bolts(d, *, hub_d: float, od: float, prefix: str = "") -> tuple[int, float, float]:
    """The checked bolt pattern ``{prefix}bolt_count, _hole_d, pitch_d`` of ``d``, clearing a hub of hub_d."""
    count, hole_d, pitch_d = (getattr(d, f"{prefix}{k}") for k in ("bolt_count", "bolt_hole_d", "pitch_d"))
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


# --------------------------------------------------------------------------- one builder each


def _motor_shaft_end(d) -> bd.Part:
    _less(d.seat_d, "seat_d", d.body_d, "body_d (a shoulder for the hub)")
    _less(
        d.keyway_length,
        "keyway_length",
        d.seat_length - 2.0 * d.fillet,
        "the seat length clear of its fillet",
    )
    shaft = parts.stepped_shaft(
        [Segment(d.body_length, d.body_d), Segment(d.seat_length, d.seat_d)],
        fillet=d.fillet,
        chamfer=d.chamfer,
    )
    return parts.keyway(
        shaft,
        width=d.keyway_width,
        depth=d.keyway_depth,
        length=d.keyway_length,
        x_start=d.body_length + (d.seat_length - d.keyway_length) / 2.0,
        diameter=d.seat_d,
        rounded_ends=True,
    )


def _coupling_hub(d) -> bd.Part:
    return parts.coupling_hub(**asdict(d), flange_at="end")


def _flanged_tube(d, tube: float) -> list[Segment]:
    """Flange | hub | tube | hub | flange from x = 0 with a tube ``tube`` m long (parts 1 and 2)."""
    flange, hub = (
        Segment(d.flange_thickness, d.flange_od, d.tube_id),
        Segment(d.hub_length, d.hub_od, d.tube_id),
    )
    return [flange, hub, Segment(tube, d.tube_od, d.tube_id), hub, flange]


def _tube_ends(d) -> float:
    """Axial length of a flanged tube's two flanges and hubs, m; its bore checked against them."""
    _less(d.tube_id, "tube_id", min(d.tube_od, d.hub_od), "the tube and hub diameters")
    return 2.0 * (d.flange_thickness + d.hub_length)


def _ptss_part1(d) -> bd.Part:
    tube = _tube_length(d.length, _tube_ends(d))
    count, hole_d, pitch = _bolts(d, hub_d=d.hub_od + 2.0 * d.fillet, od=d.flange_od)
    t = d.flange_thickness
    return parts.flanged_shaft(
        _flanged_tube(d, tube),
        [BoltCircle(count, hole_d, pitch, 0.0, t), BoltCircle(count, hole_d, pitch, d.length - t, t)],
        fillet=d.fillet,
        chamfer=d.chamfer,
    )


def _torque_flange_segments(od: float, ring: float, web_d: float, web_length: float, bore: float):
    """Ring | measuring web | ring of the torque flange, their diameters checked, as segments."""
    _less(web_d, "web_d", od, "od")
    _less(bore, "bore", web_d, "web_d")
    return [Segment(ring, od, bore), Segment(web_length, web_d, bore), Segment(ring, od, bore)]


def _torque_flange(d) -> bd.Part:
    segs = _torque_flange_segments(d.od, d.ring_thickness, d.web_d, d.web_length, d.bore)
    count, hole_d, pitch = _bolts(d, hub_d=d.web_d + 2.0 * d.fillet, od=d.od)
    ring, total = d.ring_thickness, sum(s.length for s in segs)
    body = parts.flanged_shaft(
        segs,
        [BoltCircle(count, hole_d, pitch, 0.0, ring), BoltCircle(count, hole_d, pitch, total - ring, ring)],
        fillet=d.fillet,
    )
    return bd.Part([body.solids()[0].moved(bd.Location((to_cad(d.x), 0.0, 0.0)))]) if d.x else body


def _ptss_part2(d) -> bd.Part:
    ends = _tube_ends(d)
    _less(d.tube_id, "tube_id", d.web_d, "the torque flange's web_d")
    tf = _torque_flange_segments(d.flange_od, d.ring_thickness, d.web_d, d.web_length, d.tube_id)
    x_tf, tf_length = d.torque_flange_x, sum(s.length for s in tf)
    if x_tf <= ends:
        raise ModelError(
            "leaves no tube before the torque flange",
            field="torque_flange_x",
            value=x_tf,
            unit="m",
            valid=f"> {ends:g} m (flanges + hubs of tube A)",
        )
    tube_b = _tube_length(d.length, x_tf + tf_length + ends)
    count, hole_d, pitch = _bolts(d, hub_d=max(d.hub_od, d.web_d) + 2.0 * d.fillet, od=d.flange_od)
    t, ring = d.flange_thickness, d.ring_thickness
    x_b = x_tf + tf_length  # driving-side face of tube B's first flange
    return parts.flanged_shaft(
        _flanged_tube(d, x_tf - ends) + tf + _flanged_tube(d, tube_b),
        [
            BoltCircle(count, hole_d, pitch, 0.0, t),
            # flange A + ring 1 and ring 2 + flange B are each drilled through in one go
            BoltCircle(count, hole_d, pitch, x_tf - t, t + ring),
            BoltCircle(count, hole_d, pitch, x_b - ring, ring + t),
            BoltCircle(count, hole_d, pitch, d.length - t, t),
        ],
        fillet=d.fillet,
        chamfer=d.chamfer,
    )


def _ptss_part4(d) -> bd.Part:
    gen_t = d.generator_flange_thickness
    body = _tube_length(d.length, d.flange_thickness + 2.0 * d.hub_length + gen_t)
    hub_d = d.hub_od + 2.0 * d.fillet
    count, hole_d, pitch = _bolts(d, hub_d=hub_d, od=d.flange_od)
    g_count, g_hole_d, g_pitch = _bolts(d, hub_d=hub_d, od=d.generator_flange_od, prefix="generator_")
    return parts.flanged_shaft(
        [
            Segment(d.flange_thickness, d.flange_od),
            Segment(d.hub_length, d.hub_od),
            Segment(body, d.body_d),
            Segment(d.hub_length, d.hub_od),
            Segment(gen_t, d.generator_flange_od),
        ],
        [
            BoltCircle(count, hole_d, pitch, 0.0, d.flange_thickness),
            BoltCircle(g_count, g_hole_d, g_pitch, d.length - gen_t, gen_t),
        ],
        fillet=d.fillet,
        chamfer=d.chamfer,
    )


def _generator_shaft_end(d) -> bd.Part:
    count, hole_d, pitch = _bolts(d, hub_d=d.journal_d + 2.0 * d.fillet, od=d.flange_od)
    return parts.flanged_shaft(
        [
            Segment(d.flange_thickness, d.flange_od),
            Segment(d.journal_length, d.journal_d),
            Segment(d.shaft_length, d.shaft_d),
        ],
        [BoltCircle(count, hole_d, pitch, 0.0, d.flange_thickness)],
        fillet=d.fillet,
        chamfer=d.chamfer,
    )


# --------------------------------------------------------------------------- the part functions


def _part_function(name: str, build: Callable, summary: str, returns: str) -> Callable[..., bd.Part]:
    """The public part function ``name``: keyword dimensions of :data:`DIMENSIONS`, checked, then built.

    Its signature (``inspect.signature``, which a model file's ``params`` are bound to) and the
    Parameters of its docstring are read off the table.
    """
    rows = DIMENSIONS[name]
    record = make_dataclass(f"{name}_dimensions", list(rows), frozen=True)
    signature = inspect.Signature(
        [
            inspect.Parameter(
                field,
                inspect.Parameter.KEYWORD_ONLY,
                default=row.default,
                annotation=type(row.default).__name__,
            )
            for field, row in rows.items()
        ],
        return_annotation="bd.Part",
    )

    def part(**given) -> bd.Part:
        values = signature.bind(**given)  # an unknown keyword is a TypeError, as for a def
        values.apply_defaults()
        return build(record(**{f: _checked(f, v, rows[f].check) for f, v in values.arguments.items()}))

    def described(field: str, row: Dimension) -> str:
        kind, unit = ("int", "") if row.check == "count" else ("float", ", m")
        text = textwrap.fill(f"{row.meaning}{unit}. Default {row.default!r}.", 96)
        return f"{field} : {kind}, optional\n" + textwrap.indent(text, "    ")

    part.__name__ = part.__qualname__ = name
    part.__module__ = __name__
    part.__signature__ = signature
    part.__doc__ = (
        textwrap.fill(summary, 100) + "\n\nDefaults are plausible dimensions, not the bench's drawings.\n\n"
        "Parameters\n----------\n"
        + "\n".join(described(f, row) for f, row in rows.items())
        + f"\n\nReturns\n-------\nbuild123d.Part\n    {returns}\n"
    )
    return part


motor_shaft_end = _part_function(
    "motor_shaft_end",
    _motor_shaft_end,
    "The motor's output shaft end: a bearing-side body and a keyed coupling seat.",
    "One solid (mm), x from 0 to body_length + seat_length (0.65 m by default).",
)
coupling_hub = _part_function(
    "coupling_hub",
    _coupling_hub,
    "The coupling hub on the motor shaft end: keyed hub, bolted flange facing +x. It fits "
    ":func:`motor_shaft_end` and the PTSS flange of :func:`ptss_part1`.",
    "One solid (mm), x from 0 to hub_length, flange at the +x end.",
)
ptss_part1 = _part_function(
    "ptss_part1",
    _ptss_part1,
    "PTSS part 1: a steel tube with a hub and a bolted flange at each end. The section from x = 0 is "
    "flange | hub | tube | hub | flange, bored through with ``tube_id``; both flanges carry the same "
    "bolt circle (first hole on +z) so they, and the mating flange of part 2, share one section shape.",
    "One solid (mm), x from 0 to length.",
)
torque_flange = _part_function(
    "torque_flange",
    _torque_flange,
    "A torque-measuring flange (HBM T40 style), idealised as a turned spool. Two bolted rings, each "
    "drilled with the PTSS bolt circle, are joined by a short measuring web of diameter ``web_d`` that "
    "carries the torque (and the strain gauges); bolt heads sit in the gap beside the web. The real "
    "T40 measuring body (spokes, inner and outer bolt circles) is not modelled.",
    "One solid (mm), x .. x + 2·ring_thickness + web_length (0.10 m by default).",
)
ptss_part2 = _part_function(
    "ptss_part2",
    _ptss_part2,
    "PTSS part 2: two flanged steel tubes with the torque flange bolted between them. From x = 0: "
    "flanged tube A (flange | hub | tube | hub | flange), the torque flange (ring | web | ring, see "
    ":func:`torque_flange`), flanged tube B. Every flange and both torque-flange rings carry the same "
    "bolt circle as :func:`ptss_part1` (first hole on +z); each bolted pair is drilled through as one "
    "hole. Bolted joints are bonded, so the result is one solid.",
    "One solid (mm), x from 0 to length.",
)
ptss_part4 = _part_function(
    "ptss_part4",
    _ptss_part4,
    "PTSS part 4: the short solid shaft from the coupling (part 3) to the generator flange. From x = 0: "
    "coupling-side flange (the PTSS flange of :func:`ptss_part1`) | hub | solid body | hub | generator "
    "flange (mates :func:`generator_shaft_end`).",
    "One solid (mm), x from 0 to length.",
)
generator_shaft_end = _part_function(
    "generator_shaft_end",
    _generator_shaft_end,
    "The generator's input shaft end: a forged flange facing part 4, a journal and the shaft.",
    "One solid (mm), x from 0 to flange_thickness + journal_length + shaft_length (0.77 m).",
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
        allowed = DIMENSIONS[_PTSS[key][1].__name__]
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
