"""Slicing CAD solids and meshes into section tables, against closed forms and the solid itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

bd = pytest.importorskip("build123d")

import flexshaft as fs  # noqa: E402
from geometry.cadio import read_cad, read_mesh, write_step, write_stl  # noqa: E402
from geometry.slicing import sections  # noqa: E402

G = fs.STEEL.G


def revolved(profile_m):
    """A solid of revolution about x from a closed (x, r) half-profile in metres (build123d is mm)."""
    with bd.BuildPart() as p:
        with bd.BuildSketch(bd.Plane.XY):
            with bd.BuildLine():
                bd.Polyline(*[(1e3 * x, 1e3 * r) for x, r in profile_m], close=True)
            bd.make_face()
        bd.revolve(axis=bd.Axis.X)
    return p.part


# A stepped, partly hollow shaft: (length, od, id) in m.
STEPS = [(0.3, 0.10, 0.04), (0.4, 0.16, 0.04), (0.3, 0.08, 0.04)]


def stepped():
    pts, x = [], 0.0
    for L, D, _ in STEPS:
        pts += [(x, D / 2), (x + L, D / 2)]
        x += L
    return revolved([(0.0, 0.02), *pts, (x, 0.02)])


def test_annulus_exact_and_stepped_stiffness_is_series_sum():
    t = sections(stepped(), axis=((0, 0, 0), (1, 0, 0)))
    assert t.x.tolist() == pytest.approx([0.0, 0.3, 0.7, 1.0], abs=1e-12)  # mm to m: a rounding
    # Circles and annuli are recognised, so closed forms to round-off (a few eps; 1e-9 is loose); the
    # solid's volume and ∫r²dV are integrated exactly on its planes and cylinders (2e-16 seen).
    for i, (_, D, d) in enumerate(STEPS):
        # Closed forms of a tube: A = π (D² − d²)/4, Ip = J = π (D⁴ − d⁴)/32.
        assert t.area[i] == pytest.approx(math.pi * (D**2 - d**2) / 4, rel=1e-9)
        assert t.ip[i] == pytest.approx(math.pi * (D**4 - d**4) / 32, rel=1e-9)
        assert t.j[i] == pytest.approx(math.pi * (D**4 - d**4) / 32, rel=1e-9)
    k = 1.0 / sum(L / (G * math.pi * (D**4 - d**4) / 32) for L, D, d in STEPS)
    assert t.torsional_stiffness(G) == pytest.approx(k, rel=1e-9)
    c = t.meta["mass_check"]
    assert abs(c.volume_error) < 1e-9 and abs(c.axial_moment_error) < 1e-9


def test_axis_found_from_principal_axes_of_a_moved_part():
    part = stepped().rotate(bd.Axis.Z, 37.0).rotate(bd.Axis.X, 21.0).translate((120.0, -40.0, 75.0))
    t = sections(part)
    assert t.meta["axis"].found
    # The axis from a 3 × 3 eigen-solve (transverse and axial moments well apart: eps-accurate), the
    # stations projected onto it: round-off of the 0.15 m offsets, ~1e-16 m; 1e-9 is loose.
    assert t.x.tolist() == pytest.approx([0.0, 0.3, 0.7, 1.0], abs=1e-9)
    k = 1.0 / sum(L / (G * math.pi * (D**4 - d**4) / 32) for L, D, d in STEPS)
    assert t.torsional_stiffness(G) == pytest.approx(k, rel=1e-9)


def test_cone_converges_at_rate_two():
    # A truncated cone r(x) = r1 + (r2 − r1) x / L. Exact compliance:
    # ∫ dx / (G π r⁴ / 2) = 2 L / (3 π G (r2 − r1)) (1/r1³ − 1/r2³).
    r1, r2, L = 0.05, 0.1, 0.4
    cone = revolved([(0, 0), (0, r1), (L, r2), (L, 0)])
    exact = 1.0 / (2 * L / (3 * math.pi * G * (r2 - r1)) * (1 / r1**3 - 1 / r2**3))
    errs = []
    for n in (4, 8, 16):
        t = sections(cone, axis=((0, 0, 0), (1, 0, 0)), taper_divisions=n)
        assert t.n_intervals == n
        errs.append(abs(t.torsional_stiffness(G) / exact - 1))
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert rates == pytest.approx([2.0, 2.0], abs=0.1)
    # The volume of the frustum, π L (r1² + r1 r2 + r2²)/3, to 0.1 % already at 6 pieces.
    t = sections(cone, axis=((0, 0, 0), (1, 0, 0)))
    assert t.volume == pytest.approx(math.pi * L * (r1**2 + r1 * r2 + r2**2) / 3, rel=1e-3)


def test_step_and_stl_round_trip(tmp_path):
    part = stepped()
    write_step(part, tmp_path / "s.step")
    with pytest.raises(fs.ModelError, match="file exists"):
        write_step(part, tmp_path / "s.step")
    from_step = sections(read_cad(tmp_path / "s.step"))
    direct = sections(part)
    # STEP keeps 15+ significant digits: coordinates to ~1e-15, J (∝ r⁴) to 4x that.
    np.testing.assert_allclose(from_step.x, direct.x, atol=1e-12)
    np.testing.assert_allclose(from_step.j, direct.j, rtol=1e-12)
    # STL at 20 µm chord / 0.05 rad: a circle of N facets has Ip short by about
    # (2π/N)²/3 ≈ 1e-3 for N = 2π/0.05; the chord tolerance makes it finer here.
    write_stl(part, tmp_path / "s.stl", tolerance=2e-5, angular_tolerance=0.05)
    mesh = read_mesh(tmp_path / "s.stl")  # the unit comes from flexshaft's STL header
    from_stl = sections(mesh)
    assert from_stl.method == direct.method
    np.testing.assert_allclose(from_stl.x, direct.x, atol=1e-6)
    np.testing.assert_allclose(from_stl.area, direct.area, rtol=5e-4)
    np.testing.assert_allclose(from_stl.j, direct.j, rtol=1e-3)
    # the mesh is sliced exactly: its volume against the table's, sums over 4e3 facets: round-off (2e-16)
    assert abs(from_stl.meta["mass_check"].volume_error) < 1e-9


def test_mesh_unit_is_required_and_checked(tmp_path):
    import trimesh

    trimesh.creation.cylinder(radius=50.0, height=400.0).export(tmp_path / "c.stl")
    with pytest.raises(fs.ModelError, match="a mesh file carries no length unit"):
        read_mesh(tmp_path / "c.stl")
    t = sections(tmp_path / "c.stl", unit="mm")
    assert t.length == pytest.approx(0.4, rel=1e-9)  # ±200 mm are exact in float32: one rounding


# ---- bad geometry -----------------------------------------------------------------------------


def test_not_a_solid():
    face = bd.Rectangle(10, 20).face()
    with pytest.raises(fs.ModelError, match="holds no solid"):
        sections(face)
    with pytest.raises(fs.ModelError, match="is not a CAD shape"):
        sections(42)


def test_two_solids():
    two = bd.Compound([bd.Cylinder(10, 100).solid(), bd.Cylinder(10, 100).translate((100, 0, 0)).solid()])
    with pytest.raises(fs.ModelError, match="holds 2 solids"):
        sections(two)


def test_bent_shaft_is_refused():
    leg1 = bd.Cylinder(20, 600, align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN))
    leg2 = bd.Cylinder(20, 300, align=(bd.Align.CENTER, bd.Align.CENTER, bd.Align.MIN)).rotate(bd.Axis.Y, 90)
    bent = leg1.rotate(bd.Axis.Y, 90) + leg2.rotate(bd.Axis.Z, 30).translate((600, 0, 0))
    with pytest.raises(fs.ModelError, match="not a straight shaft"):
        sections(bent)


def test_eccentric_or_flat_body_is_refused():
    plate = bd.Box(1000, 200, 50)
    with pytest.raises(fs.ModelError, match="not a straight shaft about its axis"):
        sections(plate, axis=((0, 0, 0), (1, 0, 0)))
    offset = bd.Cylinder(50, 500).rotate(bd.Axis.Y, 90).translate((0, 0, 30))
    with pytest.raises(fs.ModelError, match="off the axis"):
        sections(offset, axis=((0, 0, 0), (1, 0, 0)))


def test_no_axis_of_symmetry():
    # A block of three different side lengths has three different principal moments.
    with pytest.raises(fs.ModelError, match="no axis of near-rotational symmetry"):
        sections(bd.Box(100, 300, 700))
    with pytest.raises(fs.ModelError, match="no preferred axis"):
        sections(bd.Sphere(50))


def test_keyed_shaft_against_roark_and_sectionproperties():
    # Two opposite keyways, half-width a, depth b (flat floor at r − b), on a shaft of radius r:
    # Roark's Formulas for Stress and Strain, 7th ed. (Young & Budynas 2002), Table 10.1, "shaft
    # with two keyways": K = 2 C r⁴, C = C1 + C2 (b/r) + C3 (b/r)² + C4 (b/r)³ with the coefficients
    # below, valid for 0.2 <= b/r <= 0.5, 0.5 <= a/b <= 1.5 (a curve fit good to ~1.5 %; see
    # tests/geometry/slicing/test_warping.py for how the dimensions were identified).
    from shapely.geometry import Polygon

    from geometry import parts
    from geometry.slicing import brep
    from geometry.slicing.warping import corrected, warping_properties
    from geometry.units import from_cad

    r, b, a = 0.05, 0.0125, 0.0125  # b/r = 0.25, a/b = 1: a standard parallel key (width D/4, depth D/8)
    shaft = parts.stepped_shaft([{"length": 0.4, "od": 2 * r}])
    for angle in (0.0, math.pi):
        shaft = parts.keyway(
            shaft, width=2 * a, depth=b, length=0.2, x_start=0.1, diameter=2 * r, angle=angle
        )
    t = sections(shaft, axis=((0, 0, 0), (1, 0, 0)))
    assert t.x.tolist() == pytest.approx([0.0, 0.1, 0.3, 0.4], abs=1e-12)  # keyway ends from the B-rep
    assert t.method == ("circle", "warping", "circle")
    ab, br = a / b, b / r
    c = (
        0.7854
        + (-0.0795 + 0.1286 * ab - 0.1169 * ab**2) * br
        + (-1.4126 - 3.8589 * ab + 1.3292 * ab**2) * br**2
        + (0.7098 + 4.1936 * ab - 1.1053 * ab**2) * br**3
    )
    assert t.j[1] == pytest.approx(2 * c * r**4, rel=0.02)
    # The same number as sectionproperties' own on the same polygon (then scaled by exact/polygon Ip).
    face = brep.section_faces(brep.as_solid(shaft), 200.0)[0]
    ext, holes = brep.face_rings(face, 128)
    exact = brep.face_props(face)
    direct = corrected(
        warping_properties(Polygon(from_cad(ext), [from_cad(h) for h in holes]), nu=t.nu, cache=False),
        exact.area * 1e-6,
        exact.ip_axis * 1e-12,
    )
    assert t.j[1] == pytest.approx(direct.j, rel=1e-12)  # the same polygon, mesh and solve
    # Stiffness: the three pieces in series (a few roundings).
    k = 1.0 / (0.2 / (G * math.pi * r**4 / 2) + 0.2 / (G * t.j[1]))
    assert t.torsional_stiffness(G) == pytest.approx(k, rel=1e-12)


def test_step_length_unit_is_honoured(tmp_path):
    # The same coordinates declared in metres instead of millimetres must read 1000 times longer:
    # the reader takes the unit from the file (OCCT converts it), not from an assumption.
    write_step(stepped(), tmp_path / "mm.step")
    text = (tmp_path / "mm.step").read_text()
    assert text.count("SI_UNIT(.MILLI.,.METRE.)") == 1
    (tmp_path / "m.step").write_text(text.replace("SI_UNIT(.MILLI.,.METRE.)", "SI_UNIT($,.METRE.)"))
    t_mm = sections(read_cad(tmp_path / "mm.step"))
    t_m = sections(read_cad(tmp_path / "m.step"))
    assert t_mm.length == pytest.approx(1.0, rel=1e-12)  # a unit factor: a rounding
    assert t_m.length == pytest.approx(1000.0, rel=1e-12)


@pytest.mark.parametrize("kind", ["polygon", "spline", "flats", "hub"])
def test_other_sections_slice_and_conserve_volume(kind):
    from geometry import parts

    part = {
        "polygon": lambda: parts.polygon_shaft(length=0.5, sides=6, across_flats=0.1),
        "spline": lambda: parts.spline_shaft(length=0.3, root_d=0.08, tip_d=0.09, teeth=12),
        "flats": lambda: parts.flats(
            parts.stepped_shaft([{"length": 0.5, "od": 0.1}]),
            depth=0.01,
            length=0.2,
            x_start=0.1,
            diameter=0.1,
            count=2,
        ),
        "hub": lambda: parts.coupling_hub(
            hub_od=0.2,
            hub_length=0.15,
            bore=0.1,
            flange_od=0.35,
            flange_thickness=0.04,
            bolt_count=8,
            bolt_hole_d=0.02,
            pitch_d=0.29,
            keyway_width=0.028,
            keyway_depth=0.0064,
        ),
    }[kind]()
    t = sections(part)
    assert "warping" in t.method
    # Prismatic intervals are exact, and OCCT integrates these planes, cylinders and extrusions exactly:
    # round-off, 3e-14 at most (the hub); 1e-9 is the integrator's own target on curved B-spline faces.
    assert abs(t.meta["mass_check"].volume_error) < 1e-9
    # Saint-Venant: J <= Ip, with equality only for a circle or concentric annulus (the section
    # does not warp); every other section twists more easily than its polar moment says.
    w = np.array([m == "warping" for m in t.method])
    assert np.all(t.j[w] < t.ip[w])
