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
