"""The test-bench library (geometry.parts.testbench): its parts as solids, and against their own solids
once sliced.

Every expected number is a closed form written out here from the dimensions given, not read off our
own output; volumes go mm³ → m³ through geometry.units, positions through to_cad / from_cad.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

bd = pytest.importorskip("build123d")

import flexshaft as fs  # noqa: E402
from geometry.cadio import read_mesh, write_stl  # noqa: E402
from geometry.parts import testbench  # noqa: E402
from geometry.slicing import sections  # noqa: E402
from geometry.units import from_cad, to_cad  # noqa: E402
from tests.geometry.conftest import BENCH, EXACT, one_valid_solid, vol_m3  # noqa: E402

G, RHO = fs.STEEL.G, fs.STEEL.rho


# --------------------------------------------------------------------------- the parts


@pytest.mark.parametrize("name", BENCH)
def test_bench_part_is_one_valid_solid_from_zero_symmetric_about_the_axis(bench_parts, name):
    part = bench_parts[name]
    assert one_valid_solid(part)
    box = part.bounding_box()
    assert box.min.X == pytest.approx(0.0, abs=1e-6)
    assert box.min.Y == pytest.approx(-box.max.Y, abs=1e-6)
    assert box.min.Z == pytest.approx(-box.max.Z, abs=1e-6)
    assert box.max.Y == pytest.approx(box.max.Z, abs=1e-6)  # turned: the same radius both ways


def test_ptss_parts_and_overrides():
    pieces = testbench.ptss(part2={"length": 6.0})
    assert list(pieces) == ["part 1", "part 2", "part 4"]
    lengths = {name: from_cad(p.bounding_box().max.X) for name, p in pieces.items()}
    # the end faces' x, mm to m: a rounding (1e-16 seen); 1 nm is loose
    assert lengths == pytest.approx({"part 1": 3.0, "part 2": 6.0, "part 4": 1.0}, abs=1e-9)


# Closed forms of the parts' volumes from their documented default dimensions (m): the turned profile
# (cylinders and annuli; each shoulder fillet adds the spandrel between its arc and the corner, area
# (1 - π/4)·f², centroid (10 - 3π)/(12 - 3π)·f off the smaller radius - Pappus; each 45° end chamfer
# takes a triangle c²/2 at c/3 inside the rim), less the bolt holes and keyways.
SPANDREL = (10.0 - 3.0 * math.pi) / (12.0 - 3.0 * math.pi)


def turned_volume(segments, fillet=0.0, chamfer=0.0) -> float:
    """Volume of a turned profile of (length, od, id) segments with shoulder fillets and end chamfers."""
    v = sum(math.pi / 4.0 * (od**2 - bore**2) * length for length, od, bore in segments)
    for (_, od_a, _), (_, od_b, _) in zip(segments, segments[1:]):
        if od_a != od_b:
            r = min(od_a, od_b) / 2.0
            v += 2.0 * math.pi * (1.0 - math.pi / 4.0) * fillet**2 * (r + SPANDREL * fillet)
    for _, od, _ in (segments[0], segments[-1]):
        v -= 2.0 * math.pi * chamfer**2 / 2.0 * (od / 2.0 - chamfer / 3.0)
    return v


def holes(count, hole_d, drilled) -> float:
    """Bolt holes: count cylinders of hole_d through ``drilled`` m of material in all."""
    return count * math.pi / 4.0 * hole_d**2 * drilled


def chord_area(a: float, r: float) -> float:
    """∫ √(r² − y²) dy over |y| <= a: the part of a disc of radius r above a chord's line, between ±a."""
    return a * math.sqrt(r * r - a * a) + r * r * math.asin(a / r)


def shaft_keyway(width, depth, length, diameter) -> float:
    """A round-ended keyway in a shaft: the material above the flat floor (depth below the OD on the
    centre line) under its slot - the straight part in closed form, the two half-disc ends (one disc
    of radius width/2) by quadrature of the cap's height over the disc."""
    from scipy.integrate import quad

    a, r = width / 2.0, diameter / 2.0
    floor = r - depth
    straight = (length - width) * (chord_area(a, r) - 2.0 * a * floor)
    # y = a·sin φ over the disc: chord 2a·cos φ, height √(r² − y²) − floor
    ends, _ = quad(
        lambda p: 2.0 * a * a * math.cos(p) ** 2 * (math.sqrt(r * r - (a * math.sin(p)) ** 2) - floor),
        -math.pi / 2.0,
        math.pi / 2.0,
        epsabs=0.0,
        epsrel=1e-13,
    )
    return straight + ends


def hub_keyway(width, depth, bore, length) -> float:
    """A keyway through a hub's bore: width × (bore/2 + depth) from the axis, less the bore already empty."""
    a = width / 2.0
    return length * (2.0 * a * (bore / 2.0 + depth) - chord_area(a, bore / 2.0))


FLANGE, HUB = (0.06, 0.52, 0.18), (0.12, 0.34, 0.18)  # the PTSS flange and hub (length, od, id)
RING, WEB = (0.03, 0.52, 0.18), (0.04, 0.30, 0.18)  # the torque flange's rings and web
CLOSED_FORM = {
    # body 0.26 x 0.30 | seat 0.22 x 0.35, fillet 5 mm, chamfer 3 mm; keyway 50 x 17 x 280 mm
    "motor_shaft_end": (
        turned_volume([(0.30, 0.26, 0.0), (0.35, 0.22, 0.0)], 0.005, 0.003)
        - shaft_keyway(0.050, 0.017, 0.28, 0.22),
        0.65,
        0.26,
    ),
    # hub 0.34 | flange 0.52 x 0.06, bore 0.22, 0.35 long; 12 x 26 mm holes; hub keyway 50 x 11.4 mm
    "coupling_hub": (
        turned_volume([(0.29, 0.34, 0.22), (0.06, 0.52, 0.22)])
        - holes(12, 0.026, 0.06)
        - hub_keyway(0.050, 0.0114, 0.22, 0.35),
        0.35,
        0.52,
    ),
    "ptss_part1": (
        turned_volume([FLANGE, HUB, (3.0 - 0.36, 0.28, 0.18), HUB, FLANGE], 0.01) - holes(12, 0.026, 0.12),
        3.0,
        0.52,
    ),
    "torque_flange": (turned_volume([RING, WEB, RING], 0.01) - holes(12, 0.026, 0.06), 0.10, 0.52),
    # tube A to the torque flange at 1.2 m, the torque flange (0.10 m), tube B to 5.8 m; each bolted
    # stack drilled through: 0.06 + (0.06 + 0.03) + (0.03 + 0.06) + 0.06 m
    "ptss_part2": (
        turned_volume(
            [FLANGE, HUB, (1.2 - 0.36, 0.28, 0.18), HUB, FLANGE, RING, WEB, RING]
            + [FLANGE, HUB, (5.8 - 1.3 - 0.36, 0.28, 0.18), HUB, FLANGE],
            0.01,
        )
        - holes(12, 0.026, 0.30),
        5.8,
        0.52,
    ),
    # flange | hub 0.10 | solid body 0.26 | hub | generator flange 0.60 x 0.07 (16 x 30 mm holes)
    "ptss_part4": (
        turned_volume(
            [
                (0.06, 0.52, 0.0),
                (0.10, 0.34, 0.0),
                (1.0 - 0.33, 0.26, 0.0),
                (0.10, 0.34, 0.0),
                (0.07, 0.60, 0.0),
            ],
            0.01,
        )
        - holes(12, 0.026, 0.06)
        - holes(16, 0.030, 0.07),
        1.0,
        0.60,
    ),
    "generator_shaft_end": (
        turned_volume([(0.07, 0.60, 0.0), (0.30, 0.34, 0.0), (0.40, 0.30, 0.0)], 0.008)
        - holes(16, 0.030, 0.07),
        0.77,
        0.60,
    ),
}


@pytest.mark.parametrize("name", BENCH)
def test_bench_part_volume_and_extent_are_the_closed_forms_of_its_dimensions(bench_parts, name):
    # OCCT integrates planes, cylinders, cones and tori to round-off (EXACT); the keyways' faces are
    # trimmed by B-spline edges, which vol_m3 integrates adaptively to 1e-12.
    volume, length, od = CLOSED_FORM[name]
    part = bench_parts[name]
    assert vol_m3(part) == pytest.approx(volume, rel=EXACT)
    box = part.bounding_box()
    # the box's faces are the end faces and the largest rim: mm to m is a rounding; 1 nm is loose
    assert from_cad(box.max.X - box.min.X) == pytest.approx(length, abs=1e-9)
    assert from_cad(box.max.Z - box.min.Z) == pytest.approx(od, abs=1e-9)


def slab(part, x0: float, x1: float) -> bd.Compound:
    """The part's material between x0 and x1 (m)."""
    box = bd.Solid.make_box(
        to_cad(x1 - x0), to_cad(2.0), to_cad(2.0), bd.Plane(origin=(to_cad(x0), to_cad(-1.0), to_cad(-1.0)))
    )
    return bd.Compound(part.solids()[0].intersect(box))


def test_mating_flanges_of_parts_1_and_2_are_one_section_shape(bench_parts):
    # Default PTSS flange: 0.52 m OD, 0.18 m bore, 12 holes of 0.026 m on 0.44 m, 0.06 m thick.
    part1, part2 = bench_parts["ptss_part1"], bench_parts["ptss_part2"]
    end1 = slab(part1, 3.0 - 0.045, 3.0 - 0.015)  # middle of part 1's far flange
    start2 = slab(part2, 0.015, 0.045)  # middle of part 2's near flange
    ring = math.pi / 4.0 * (0.52**2 - 0.18**2 - 12 * 0.026**2) * 0.03  # annulus less 12 holes, 30 mm thick
    assert vol_m3(end1) == pytest.approx(ring, rel=EXACT)
    assert vol_m3(start2) == pytest.approx(ring, rel=EXACT)
    # Same holes at the same angles: shifted onto each other the two slabs coincide.
    overlap = bd.Compound(start2.solids()[0].intersect(end1.moved(bd.Location((to_cad(-2.94), 0, 0)))))
    assert vol_m3(overlap) == pytest.approx(ring, rel=EXACT)


def test_torque_flange_in_part2_is_drilled_with_the_ptss_bolt_circle(bench_parts):
    solid = bench_parts["ptss_part2"].solids()[0]
    r, gap = to_cad(0.44 / 2.0), math.pi / 12.0  # pitch radius; half the angle between two of 12 holes
    # Flange A (1.14–1.20 m) and ring 1 (1.20–1.23 m) are drilled through on +z; between holes is metal.
    for x in (1.17, 1.215):
        assert not solid.is_inside((to_cad(x), 0.0, r))
        assert solid.is_inside((to_cad(x), -r * math.sin(gap), r * math.cos(gap)))
    assert not solid.is_inside((to_cad(1.25), 0.0, to_cad(0.16)))  # beside the 0.30 m measuring web: air
    assert solid.is_inside((to_cad(1.25), 0.0, to_cad(0.12)))  # the web itself (bore 0.18 m)


# --------------------------------------------------------------------------- sliced


@pytest.mark.parametrize("name", BENCH)
def test_testbench_table_matches_the_solid(testbench_tables, name):
    # Volume (mass) and ∫r² dV (axial inertia) of the table against OCCT's own volume integrals.
    check = testbench_tables[name].meta["mass_check"]
    assert abs(check.volume_error) < 1e-3
    assert abs(check.axial_moment_error) < 1e-3


# Slow (CI's `pytest -m slow` step): a long CAD round trip - part 4 tessellated at 20 µm chords, the STL
# read back and sliced through its facet rings: 7-9 s on the 2-core machine.
@pytest.mark.slow
def test_testbench_flanged_part_stl_round_trip(tmp_path, testbench_tables):
    # Mesh tolerance: 20 µm chords and 0.05 rad facets on 0.5 m flanges: faceting moves areas
    # by ~1e-4 and polar moments by ~2e-4; bolt holes (24+ facets) and the warping mesh add
    # ~1e-3 on J of the drilled sections. Interval ends move by float32 rounding only.
    part = testbench.ptss_part4()
    write_stl(part, tmp_path / "p4.stl", tolerance=2e-5, angular_tolerance=0.05)
    mesh = sections(read_mesh(tmp_path / "p4.stl"), name="p4")
    brep = testbench_tables["ptss_part4"]
    # Fillets are sliced differently (B-rep: 6 pieces each; mesh: its facet rings), so compare the
    # sections in the middle of every B-rep interval longer than 2 cm, and the part's totals.
    long = np.flatnonzero(brep.lengths > 0.02)
    mid = 0.5 * (brep.x[long] + brep.x[long + 1])
    k = np.searchsorted(mesh.x, mid) - 1
    assert [mesh.method[i] for i in k] == [brep.method[i] for i in long]
    np.testing.assert_allclose(mesh.area[k], brep.area[long], rtol=2e-3)
    np.testing.assert_allclose(mesh.ip[k], brep.ip[long], rtol=2e-3)
    np.testing.assert_allclose(mesh.j[k], brep.j[long], rtol=5e-3)
    assert mesh.length == pytest.approx(brep.length, abs=1e-6)
    assert mesh.volume == pytest.approx(brep.volume, rel=1e-3)
    assert mesh.torsional_stiffness(G) == pytest.approx(brep.torsional_stiffness(G), rel=2e-3)
    assert mesh.axial_inertia(RHO) == pytest.approx(brep.axial_inertia(RHO), rel=2e-3)
