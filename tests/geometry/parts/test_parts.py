"""Parametric CAD parts (geometry.parts), and bad input to them and to the test-bench library.

Every expected number is a closed form written out here from the dimensions
given, not read off our own output: volumes of revolution by Pappus' theorem,
circular-segment areas, polygon areas. build123d works in mm, so volumes are
converted mm³ → m³ with geometry.units before comparing; positions go
through to_cad / from_cad.
"""

from __future__ import annotations

import math

import pytest
from scipy.integrate import quad

bd = pytest.importorskip("build123d")

from flexshaft.errors import ModelError, format_value  # noqa: E402
from geometry import parts  # noqa: E402
from geometry.parts import BoltCircle, Segment, testbench  # noqa: E402
from geometry.units import to_cad  # noqa: E402
from tests.geometry.conftest import EXACT, one_valid_solid, vol_m3  # noqa: E402


def cap_area(r: float, h: float) -> float:
    """Area of the circular segment of height h cut from a disc of radius r."""
    return r * r * math.acos((r - h) / r) - (r - h) * math.sqrt(2.0 * r * h - h * h)


# --------------------------------------------------------------------------- stepped shafts


def test_plain_stepped_shaft_volume_is_sum_of_cylinders():
    segs = [Segment(0.30, 0.16), Segment(0.40, 0.12), Segment(0.25, 0.20)]
    part = parts.stepped_shaft(segs)
    expected = sum(math.pi / 4.0 * s.od**2 * s.length for s in segs)
    assert one_valid_solid(part)
    assert vol_m3(part) == pytest.approx(expected, rel=EXACT)
    box = part.bounding_box()
    assert (box.min.X, box.max.X) == pytest.approx((0.0, to_cad(0.95)), abs=1e-6)
    r = to_cad(0.10)
    assert (box.min.Y, box.max.Y, box.min.Z, box.max.Z) == pytest.approx((-r, r, -r, r), abs=1e-6)


def test_hollow_stepped_shaft_with_stepping_bore_from_dicts():
    segs = [
        {"length": 0.30, "od": 0.16, "id": 0.04},
        {"length": 0.40, "od": 0.12},  # solid in the middle: the bore stops and restarts
        {"length": 0.25, "od": 0.20, "id": 0.10},
    ]
    part = parts.stepped_shaft(segs)
    expected = sum(math.pi / 4.0 * (s["od"] ** 2 - s.get("id", 0.0) ** 2) * s["length"] for s in segs)
    assert one_valid_solid(part)
    assert vol_m3(part) == pytest.approx(expected, rel=EXACT)


def test_fillets_and_chamfers_by_pappus():
    # Two segments, a step up from R1 to R2 at x = L1; fillet f in the concave corner, chamfer c at both ends.
    L1, R1, L2, R2, f, c = 0.20, 0.05, 0.15, 0.08, 0.01, 0.004
    part = parts.stepped_shaft([Segment(L1, 2 * R1), Segment(L2, 2 * R2)], fillet=f, chamfer=c)
    cylinders = math.pi * (R1**2 * L1 + R2**2 * L2)
    # A 45° chamfer removes a triangle of area c²/2 whose centroid is c/3 inside the rim (Pappus).
    chamfers = sum(2.0 * math.pi * (r - c / 3.0) * c * c / 2.0 for r in (R1, R2))
    # The fillet adds the spandrel f²(1 − π/4); its centroid lies f(10 − 3π)/(3(4 − π)) above R1.
    spandrel = f * f * (1.0 - math.pi / 4.0)
    r_bar = R1 + f * (10.0 - 3.0 * math.pi) / (3.0 * (4.0 - math.pi))
    expected = cylinders - chamfers + 2.0 * math.pi * r_bar * spandrel
    assert one_valid_solid(part)
    assert vol_m3(part) == pytest.approx(expected, rel=EXACT)
    kinds = {str(face.geom_type).split(".")[-1] for face in part.faces()}
    assert kinds == {"PLANE", "CYLINDER", "CONE", "TORUS"}  # exact analytic faces only


def test_step_down_fillet_sits_on_the_smaller_segment():
    L1, R1, L2, R2, f = 0.15, 0.08, 0.20, 0.05, 0.01
    part = parts.stepped_shaft([Segment(L1, 2 * R1), Segment(L2, 2 * R2)], fillet=f)
    spandrel = f * f * (1.0 - math.pi / 4.0)
    r_bar = R2 + f * (10.0 - 3.0 * math.pi) / (3.0 * (4.0 - math.pi))
    expected = math.pi * (R1**2 * L1 + R2**2 * L2) + 2.0 * math.pi * r_bar * spandrel
    assert vol_m3(part) == pytest.approx(expected, rel=EXACT)


# --------------------------------------------------------------------------- flanges, holes, fuse


def test_flange_volume_with_holes_and_spigot_and_first_hole_on_plus_z():
    od, t, bore, n, d, pitch, sd, sl, x = 0.50, 0.06, 0.10, 8, 0.03, 0.40, 0.20, 0.012, 0.3
    part = parts.flange(
        od=od,
        thickness=t,
        bore=bore,
        bolt_count=n,
        bolt_hole_d=d,
        pitch_d=pitch,
        spigot_d=sd,
        spigot_length=sl,
        x=x,
    )
    expected = math.pi / 4.0 * ((od**2 - bore**2) * t - n * d**2 * t + (sd**2 - bore**2) * sl)
    assert one_valid_solid(part)
    assert vol_m3(part) == pytest.approx(expected, rel=EXACT)
    box = part.bounding_box()
    assert (box.min.X, box.max.X) == pytest.approx((to_cad(x), to_cad(x + t + sl)), abs=1e-6)
    mid = to_cad(x + t / 2.0)
    r = to_cad(pitch / 2.0)
    solid = part.solids()[0]
    assert not solid.is_inside((mid, 0.0, r))  # the first hole is on +z
    assert solid.is_inside((mid, -r * math.sin(math.pi / n), r * math.cos(math.pi / n)))  # between holes


def test_fuse_touching_parts_is_one_solid_with_summed_volume():
    shaft = parts.stepped_shaft([Segment(0.5, 0.2)])
    disc = parts.flange(od=0.4, thickness=0.05, bore=0.0, x=0.5)
    both = parts.fuse(shaft, disc)
    assert one_valid_solid(both)
    assert vol_m3(both) == pytest.approx(math.pi / 4.0 * (0.2**2 * 0.5 + 0.4**2 * 0.05), rel=EXACT)


def test_flanged_shaft_matches_stepped_shaft_minus_holes():
    segs = [Segment(0.05, 0.40, 0.10), Segment(0.60, 0.20, 0.10), Segment(0.05, 0.40, 0.10)]
    circles = [BoltCircle(8, 0.02, 0.32, 0.0, 0.05), BoltCircle(8, 0.02, 0.32, 0.65, 0.05, angle=0.1)]
    part = parts.flanged_shaft(segs, circles)
    expected = (
        sum(math.pi / 4.0 * (s.od**2 - s.id**2) * s.length for s in segs)
        - 2 * 8 * math.pi / 4 * 0.02**2 * 0.05
    )
    assert one_valid_solid(part)
    assert vol_m3(part) == pytest.approx(expected, rel=EXACT)


# --------------------------------------------------------------------------- keyways and flats


def test_keyway_removes_the_exact_circular_strip():
    # Material removed = L · (area of the disc inside |y| <= w/2 above the flat floor z = R − t).
    # Against the naive w·t·L the exact cut is ~5 % smaller here: the OD curves away from the
    # flat floor at the keyway's edges (the two crescents between chord and arc are not cut).
    R, w, t, L = 0.10, 0.05, 0.02, 0.20
    shaft = parts.stepped_shaft([Segment(0.5, 2 * R)])
    cut = parts.keyway(shaft, width=w, depth=t, length=L, x_start=0.1, diameter=2 * R)
    strip = (w / 2.0) * math.sqrt(R * R - w * w / 4.0) + R * R * math.asin(w / (2.0 * R))  # ∫ sqrt(R²−y²)
    exact = L * (strip - w * (R - t))
    removed = vol_m3(shaft) - vol_m3(cut)
    assert one_valid_solid(cut)
    assert removed == pytest.approx(exact, rel=EXACT)
    assert removed == pytest.approx(w * t * L, rel=0.06)


def test_round_ended_keyway_volume_and_angle():
    R, w, t, L = 0.10, 0.05, 0.02, 0.20
    shaft = parts.stepped_shaft([Segment(0.5, 2 * R)])
    cut = parts.keyway(
        shaft, width=w, depth=t, length=L, x_start=0.1, diameter=2 * R, angle=math.pi / 2, rounded_ends=True
    )

    def depth_at(y):  # height of material above the floor at lateral offset y
        return math.sqrt(R * R - y * y) - (R - t)

    # Plan view is a stadium: straight part L − w plus two half-discs of radius w/2.
    straight = (L - w) * quad(depth_at, -w / 2, w / 2, epsabs=0, epsrel=1e-13)[0]
    ends = quad(
        lambda y: 2.0 * math.sqrt(w * w / 4 - y * y) * depth_at(y), -w / 2, w / 2, epsabs=0, epsrel=1e-13
    )[0]
    # Not EXACT: the round ends meet the shaft along B-spline edges, approximated by OCCT's (parallel)
    # boolean to its 1e-7 mm confusion tolerance - along ~160 mm of edge 20 mm deep, ~3e-4 mm³, 1.5e-9 of
    # the 2.2e5 mm³ removed (1.8e-10 and 9.8e-10 seen in different runs); vol_m3's adaptive integration
    # adds 1e-12 of each volume, 1/87 of the shaft's. 1e-8 leaves ~7x.
    assert vol_m3(shaft) - vol_m3(cut) == pytest.approx(straight + ends, rel=1e-8)
    solid = cut.solids()[0]
    probe = to_cad(R - t / 2.0)  # half-way down the keyway, at its mid-length x = 0.2 m
    assert not solid.is_inside((to_cad(0.2), -probe, 0.0))  # angle pi/2 (right-handed from +z) is -y
    assert solid.is_inside((to_cad(0.2), probe, 0.0))


@pytest.mark.parametrize("count", [1, 2])
def test_flats_remove_circular_segments(count):
    R, h, L = 0.10, 0.02, 0.15
    shaft = parts.stepped_shaft([Segment(0.4, 2 * R)])
    cut = parts.flats(shaft, depth=h, length=L, x_start=0.1, diameter=2 * R, count=count)
    assert one_valid_solid(cut)
    assert vol_m3(shaft) - vol_m3(cut) == pytest.approx(count * L * cap_area(R, h), rel=EXACT)


def test_coupling_hub_volume_with_bore_keyway():
    hub_od, lh, bore, fod, ft, n, d, pitch, w, t = 0.34, 0.35, 0.22, 0.52, 0.06, 12, 0.026, 0.44, 0.05, 0.0114
    part = parts.coupling_hub(
        hub_od=hub_od,
        hub_length=lh,
        bore=bore,
        flange_od=fod,
        flange_thickness=ft,
        bolt_count=n,
        bolt_hole_d=d,
        pitch_d=pitch,
        keyway_width=w,
        keyway_depth=t,
        x=0.5,
    )
    rb = bore / 2.0
    body = math.pi / 4.0 * ((hub_od**2 - bore**2) * (lh - ft) + (fod**2 - bore**2) * ft - n * d * d * ft)
    # Keyway in the bore: the strip |y| <= w/2 between the bore arc and the floor z = rb + t, full length.
    keyway = lh * (
        w * (rb + t) - ((w / 2.0) * math.sqrt(rb * rb - w * w / 4.0) + rb * rb * math.asin(w / (2 * rb)))
    )
    assert one_valid_solid(part)
    assert vol_m3(part) == pytest.approx(body - keyway, rel=EXACT)
    box = part.bounding_box()
    assert (box.min.X, box.max.X) == pytest.approx((to_cad(0.5), to_cad(0.5 + lh)), abs=1e-6)


# --------------------------------------------------------------------------- prismatic shafts


@pytest.mark.parametrize("sides", [3, 4, 6, 7])
def test_polygon_shaft_area(sides):
    a, L = 0.04, 0.5  # apothem (half across flats), length
    part = parts.polygon_shaft(length=L, sides=sides, across_flats=2 * a, x=0.2)
    assert one_valid_solid(part)
    # A regular n-gon of apothem a is n triangles of base 2a·tan(π/n) and height a.
    assert vol_m3(part) / L == pytest.approx(sides * a * a * math.tan(math.pi / sides), rel=EXACT)
    box = part.bounding_box()
    assert box.max.Z == pytest.approx(to_cad(a), abs=1e-6)  # a flat faces +z
    assert (box.min.X, box.max.X) == pytest.approx((to_cad(0.2), to_cad(0.2 + L)), abs=1e-6)


def test_spline_shaft_area():
    rr, rt, n, w, L = 0.05, 0.06, 8, 0.015, 0.3
    part = parts.spline_shaft(length=L, root_d=2 * rr, tip_d=2 * rt, teeth=n, tooth_width=w)

    def strip(r):  # area of the disc of radius r inside |y| <= w/2
        return w / 2.0 * math.sqrt(r * r - w * w / 4.0) + r * r * math.asin(w / (2.0 * r))

    area = math.pi * rr * rr + n * (strip(rt) - strip(rr))  # root disc + n teeth between the circles
    assert one_valid_solid(part)
    assert vol_m3(part) / L == pytest.approx(area, rel=EXACT)


# --------------------------------------------------------------------------- bad input


def shaft():
    return parts.stepped_shaft([Segment(0.5, 0.2)])


HUB = dict(
    hub_od=0.34,
    hub_length=0.35,
    bore=0.22,
    flange_od=0.52,
    flange_thickness=0.06,
    bolt_count=12,
    bolt_hole_d=0.026,
    pitch_d=0.44,
)

BAD = [
    # (label, call, field named in the message, value shown in the message)
    ("segment length <= 0", lambda: Segment(0.0, 0.2), "length", 0.0),
    ("segment od a string", lambda: Segment(0.1, "0.2"), "od", "0.2"),
    ("bore >= od", lambda: Segment(0.1, 0.2, 0.2), "id", 0.2),
    ("no segments", lambda: parts.stepped_shaft([]), "segments", []),
    ("unknown segment key", lambda: parts.stepped_shaft([{"length": 1, "od": 0.1, "di": 0.0}]), "di", None),
    ("negative od in dict", lambda: parts.stepped_shaft([{"length": 1, "od": -0.1}]), "od", -0.1),
    (
        "bores do not overlap",
        lambda: parts.stepped_shaft([Segment(0.1, 0.1), Segment(0.1, 0.3, 0.2)]),
        "segments[1].id",
        0.2,
    ),
    (
        "fillet >= step height",
        lambda: parts.stepped_shaft([Segment(0.1, 0.10), Segment(0.1, 0.12)], fillet=0.01),
        "fillet",
        0.01,
    ),
    (
        "fillet longer than segment",
        lambda: parts.stepped_shaft([Segment(0.005, 0.10), Segment(0.1, 0.2)], fillet=0.01),
        "fillet",
        0.01,
    ),
    (
        "chamfer >= wall",
        lambda: parts.stepped_shaft([Segment(0.1, 0.10, 0.08)], chamfer=0.012),
        "chamfer",
        0.012,
    ),
    ("flange bore >= od", lambda: parts.flange(od=0.2, thickness=0.02, bore=0.3), "bore", 0.3),
    (
        "holes break through rim",
        lambda: parts.flange(od=0.2, thickness=0.02, bolt_count=4, bolt_hole_d=0.03, pitch_d=0.18),
        "pitch_d",
        0.18,
    ),
    (
        "holes cut into bore",
        lambda: parts.flange(od=0.4, thickness=0.02, bore=0.2, bolt_count=4, bolt_hole_d=0.03, pitch_d=0.22),
        "pitch_d",
        0.22,
    ),
    (
        "holes cut into spigot",
        lambda: parts.flange(
            od=0.4,
            thickness=0.02,
            bolt_count=4,
            bolt_hole_d=0.03,
            pitch_d=0.3,
            spigot_d=0.28,
            spigot_length=0.01,
        ),
        "pitch_d",
        0.3,
    ),
    (
        "adjacent holes overlap",
        lambda: parts.flange(od=0.4, thickness=0.02, bolt_count=24, bolt_hole_d=0.04, pitch_d=0.3),
        "pitch_d",
        0.3,
    ),
    (
        "hole size without holes",
        lambda: parts.flange(od=0.4, thickness=0.02, bolt_hole_d=0.02),
        "bolt_hole_d",
        0.02,
    ),
    (
        "bolt_count not an int",
        lambda: parts.flange(od=0.4, thickness=0.02, bolt_count=2.5),
        "bolt_count",
        2.5,
    ),
    (
        "spigot without length",
        lambda: parts.flange(od=0.4, thickness=0.02, spigot_d=0.2),
        "spigot_length",
        0.0,
    ),
    (
        "spigot >= od",
        lambda: parts.flange(od=0.4, thickness=0.02, spigot_d=0.5, spigot_length=0.01),
        "spigot_d",
        0.5,
    ),
    (
        "keyway depth >= radius",
        lambda: parts.keyway(shaft(), width=0.05, depth=0.1, length=0.1, x_start=0.1, diameter=0.2),
        "depth",
        0.1,
    ),
    (
        "keyway wider than shaft",
        lambda: parts.keyway(shaft(), width=0.25, depth=0.02, length=0.1, x_start=0.1, diameter=0.2),
        "width",
        0.25,
    ),
    (
        "round keyway shorter than wide",
        lambda: parts.keyway(
            shaft(), width=0.05, depth=0.02, length=0.04, x_start=0.1, diameter=0.2, rounded_ends=True
        ),
        "length",
        0.04,
    ),
    (
        "keyway misses the part",
        lambda: parts.keyway(shaft(), width=0.05, depth=0.02, length=0.1, x_start=2.0, diameter=0.2),
        "x_start",
        2.0,
    ),
    (
        "three flats",
        lambda: parts.flats(shaft(), depth=0.02, length=0.1, x_start=0.1, diameter=0.2, count=3),
        "count",
        3,
    ),
    (
        "flat through the axis",
        lambda: parts.flats(shaft(), depth=0.15, length=0.1, x_start=0.1, diameter=0.2),
        "depth",
        0.15,
    ),
    (
        "hub keyway through the wall",
        lambda: parts.coupling_hub(**HUB, keyway_width=0.05, keyway_depth=0.07),
        "keyway_depth",
        0.07,
    ),
    (
        "hub keyway without depth",
        lambda: parts.coupling_hub(**HUB, keyway_width=0.05),
        "keyway_depth",
        0.0,
    ),
    ("hub holes hit the hub", lambda: parts.coupling_hub(**{**HUB, "pitch_d": 0.36}), "pitch_d", 0.36),
    ("hub flange too small", lambda: parts.coupling_hub(**{**HUB, "flange_od": 0.3}), "flange_od", 0.3),
    (
        "hub flange thicker than hub",
        lambda: parts.coupling_hub(**{**HUB, "flange_thickness": 0.4}),
        "flange_thickness",
        0.4,
    ),
    ("hub flange_at", lambda: parts.coupling_hub(**HUB, flange_at="middle"), "flange_at", "middle"),
    ("polygon with 2 sides", lambda: parts.polygon_shaft(length=1, sides=2, across_flats=0.1), "sides", 2),
    (
        "spline tip <= root",
        lambda: parts.spline_shaft(length=1, root_d=0.1, tip_d=0.1, teeth=6),
        "tip_d",
        0.1,
    ),
    (
        "spline teeth too wide",
        lambda: parts.spline_shaft(length=1, root_d=0.1, tip_d=0.12, teeth=6, tooth_width=0.06),
        "tooth_width",
        0.06,
    ),
    ("spline 2 teeth", lambda: parts.spline_shaft(length=1, root_d=0.1, tip_d=0.12, teeth=2), "teeth", 2),
    (
        "fuse parts that do not touch",
        lambda: parts.fuse(shaft(), parts.flange(od=0.4, thickness=0.05, x=0.6)),
        "solids",
        2,
    ),
    ("fuse one part", lambda: parts.fuse(shaft()), "parts", 1),
    ("bolt circle pitch <= hole", lambda: BoltCircle(4, 0.05, 0.04, 0.0, 0.02), "pitch_d", 0.04),
    (
        "bolt holes leave the material",
        lambda: parts.bolt_holes(shaft(), BoltCircle(4, 0.02, 0.19, 0.0, 0.1)),
        "circles",
        1,
    ),
    (
        "bolt circle off a segment boundary",
        lambda: parts.flanged_shaft(
            [Segment(0.05, 0.4), Segment(0.5, 0.2)], [BoltCircle(8, 0.02, 0.32, 0.0, 0.04)]
        ),
        "circles[0].length",
        0.04,
    ),
    (
        "bolt holes run into the neighbour",
        lambda: parts.flanged_shaft(
            [Segment(0.05, 0.4), Segment(0.5, 0.3)], [BoltCircle(8, 0.02, 0.32, 0.0, 0.05)]
        ),
        "circles[0].pitch_d",
        0.32,
    ),
    ("part 1 too short", lambda: testbench.ptss_part1(length=0.3), "length", 0.3),
    ("torque flange too early", lambda: testbench.ptss_part2(torque_flange_x=0.2), "torque_flange_x", 0.2),
    ("seat not below body", lambda: testbench.motor_shaft_end(seat_d=0.3), "seat_d", 0.3),
    (
        "generator holes hit hub",
        lambda: testbench.ptss_part4(generator_pitch_d=0.37),
        "generator_pitch_d",
        0.37,
    ),
    ("unknown ptss part", lambda: testbench.ptss(part3={"length": 1.0}), "part3", {"length": 1.0}),
    ("unknown ptss argument", lambda: testbench.ptss(part1={"lenght": 3.0}), "part1.lenght", 3.0),
]


@pytest.mark.parametrize("call, field, value", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_names_field_and_value(call, field, value):
    with pytest.raises(ModelError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message
    assert field in message
    if value is not None:
        assert format_value(value) in message
