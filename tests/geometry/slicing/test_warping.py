"""geometry.warping: St-Venant J and shear areas of non-circular shaft sections.

Every expected number below comes from a published or closed-form result, or
from sectionproperties itself (plumbing), with the source next to it.
"""

import math

import numpy as np
import pytest

pytest.importorskip("sectionproperties")
shapely = pytest.importorskip("shapely")
from shapely import affinity  # noqa: E402
from shapely.geometry import LineString, MultiPolygon, Polygon, box  # noqa: E402

from flexshaft.errors import ModelError  # noqa: E402
from geometry.slicing import warping as wp  # noqa: E402


def circle(radius, n, center=(0.0, 0.0)):
    """Regular n-gon inscribed in a circle (vertices on the circle), m."""
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return Polygon(np.c_[center[0] + radius * np.cos(a), center[1] + radius * np.sin(a)])


def two_keyways(r, a, b, n=256):
    """Shaft of radius r with two opposite keyways: half-width a, radial depth b, flat bottom."""
    return circle(r, n).difference(box(r - b, -a, 2 * r, a)).difference(box(-2 * r, -a, -r + b, a))


@pytest.fixture(autouse=True)
def _fresh_cache():
    wp.clear_cache()
    yield
    wp.clear_cache()


# --- 1. published keyed-shaft torsion constants -------------------------------------------------


def roark_two_keyways_c(b_over_r, a_over_b):
    # W. C. Young, R. G. Budynas, "Roark's Formulas for Stress and Strain", 7th ed., McGraw-Hill 2002,
    # Table 10.1 "Formulas for torsional deformation and stress", case "Shaft with two keyways"
    # (edition and table as the transcriptions at eng-calculations.com and engineersedge.com name them):
    #   K = 2 C r^4,  C = C1 + C2 (b/r) + C3 (b/r)^2 + C4 (b/r)^3,  for 0.2 <= b/r <= 0.5, 0.5 <= a/b <= 1.5,
    #   C1 = 0.7854, C2 = -0.0795 + 0.1286 (a/b) - 0.1169 (a/b)^2,
    #   C3 = -1.4126 - 3.8589 (a/b) + 1.3292 (a/b)^2, C4 = 0.7098 + 4.1936 (a/b) - 1.1053 (a/b)^2.
    # Read from the transcription at eng-calculations.com ("Roark's formulas ... TABLE 10.1 / shaft with
    # two keyways"); the book's figure was not available, so the dimensions were identified by trying
    # the readings: a = keyway HALF-width, b = radial depth at the keyway centre line (flat bottom at
    # r - b). This reading agrees with the formula to -0.6 ... +1.5 % over the whole stated range; the
    # others tried (width a, depth b; width b, depth a; width 2b, depth a) miss by up to 22 %, 79 % and
    # 47 % somewhere in it (the last coincides with ours at a/b = 1 only).
    # Accuracy of the reference: C is Roark's polynomial curve fit; the transcription states no error
    # bound. Our converged J sits +0.1 ... +1.5 % above it (-0.6 % at b/r = 0.5, a/b = 1.5), so the
    # fit is good to ~1.5 %; 2 % is the tolerance.
    ab = a_over_b
    c2 = -0.0795 + 0.1286 * ab - 0.1169 * ab**2
    c3 = -1.4126 - 3.8589 * ab + 1.3292 * ab**2
    c4 = 0.7098 + 4.1936 * ab - 1.1053 * ab**2
    return 0.7854 + c2 * b_over_r + c3 * b_over_r**2 + c4 * b_over_r**3


@pytest.mark.parametrize("b_over_r, a_over_b", [(0.25, 1.0), (0.4, 0.5), (0.2, 1.5)])
def test_two_keyways_against_roark(b_over_r, a_over_b):
    # (0.25, 1.0) is a standard parallel key (width D/4, depth D/8); 256-gon: faceting error ~2e-4.
    r = 0.05
    b = b_over_r * r
    res = wp.warping_properties(two_keyways(r, a_over_b * b, b), nu=0.3)
    k_roark = 2.0 * roark_two_keyways_c(b_over_r, a_over_b) * r**4
    assert res.j == pytest.approx(k_roark, rel=0.02)


@pytest.mark.parametrize("h_over_r", [0.1, 0.3])
def test_opposite_flats_against_roark(h_over_r):
    # Same table, case "Circular shaft with opposite sides flattened" (transcribed at engineersedge.com):
    #   K = 2 C r^4, C = 0.7854 - 0.4053 (h/r) - 3.5810 (h/r)^2 + 5.2708 (h/r)^3 - 2.0772 (h/r)^4,
    #   h = r - w, w = half the distance between the flats, 0 <= h/r <= 0.8.
    # Again a curve fit without a stated bound: our J is +0.6 ... +0.8 % above it for h/r <= 0.3,
    # +1.7 % at 0.5 and +2.9 % at 0.7, so only the lower part of the range is asserted at 2 %.
    r = 0.05
    h = h_over_r * r
    flats = circle(r, 256).intersection(box(-2 * r, -(r - h), 2 * r, r - h))
    c = 0.7854 - 0.4053 * h_over_r - 3.5810 * h_over_r**2 + 5.2708 * h_over_r**3 - 2.0772 * h_over_r**4
    assert wp.warping_properties(flats, nu=0.3).j == pytest.approx(2 * c * r**4, rel=0.02)


# --- 2. plumbing: the wrapper returns what sectionproperties computes -----------------------------


def test_same_as_a_direct_sectionproperties_call():
    from sectionproperties.analysis.section import Section
    from sectionproperties.pre.geometry import Geometry
    from sectionproperties.pre.pre import Material

    shaft = circle(0.05, 128).difference(box(0.04, -0.014, 0.1, 0.014))  # D 100, keyway 28 x 10
    res = wp.warping_properties(shaft, nu=0.3)
    mi = wp.mesh_input(shaft, mesh_elements=wp.DEFAULT_MESH_ELEMENTS)

    def direct(material):
        geom = Geometry(mi.polygon) if material is None else Geometry(mi.polygon, material=material)
        geom.create_mesh(mesh_sizes=mi.max_area, min_angle=mi.min_angle)
        sec = Section(geom)
        sec.calculate_geometric_properties()
        sec.calculate_warping_properties()
        return sec

    steel_like = direct(Material("direct", 1.0, 0.3, 1.0, 1.0, "k"))
    assert res.elements == len(steel_like.elements)
    # The same mesh and solve as ours (equal to the bit here); 1e-12 leaves room for a summation order.
    assert res.j == pytest.approx(steel_like.get_ej(), rel=1e-12)
    assert (res.shear_area_y, res.shear_area_z) == pytest.approx(steel_like.get_eas(), rel=1e-12)
    assert res.shear_centre == pytest.approx(steel_like.get_sc(), rel=1e-12, abs=1e-15)
    # Geometric-only call (no material): J is the same; its shear areas are those for nu = 0
    # (sectionproperties uses nu = 0 unless a material is given), which is what we return for nu = 0.
    plain = direct(None)
    assert res.j == pytest.approx(plain.get_j(), rel=1e-12)
    res0 = wp.warping_properties(shaft, nu=0.0)
    assert (res0.shear_area_y, res0.shear_area_z) == pytest.approx(plain.get_as(), rel=1e-12)
    assert res0.j == pytest.approx(res.j, rel=1e-14)  # same mesh and solve, J does not depend on nu
    assert res.shear_area_z != pytest.approx(res0.shear_area_z, rel=1e-3)


def test_axes_and_second_moments_of_an_i_section():
    # Web along z, flanges along y, centroid moved to (0.1, -0.05) m. Second moments of a polygon are
    # integrated exactly by the quadratic elements; the shear force along z is carried by the web.
    yc, zc = 0.1, -0.05
    flange_w, flange_t, web_t, h = 0.3, 0.01, 0.005, 0.4
    parts = [
        box(-flange_w / 2, h / 2 - flange_t, flange_w / 2, h / 2),
        box(-flange_w / 2, -h / 2, flange_w / 2, -h / 2 + flange_t),
        box(-web_t / 2, -h / 2 + flange_t, web_t / 2, h / 2 - flange_t),
    ]
    section = affinity.translate(shapely.union_all(parts), yc, zc)
    res = wp.warping_properties(section, nu=0.3)
    web_h = h - 2 * flange_t
    arm = (h - flange_t) / 2
    area = 2 * flange_w * flange_t + web_t * web_h
    iy = 2 * (flange_w * flange_t**3 / 12 + flange_w * flange_t * arm**2) + web_t * web_h**3 / 12
    iz = 2 * flange_t * flange_w**3 / 12 + web_h * web_t**3 / 12
    # Exact integration up to round-off: sums over the mesh's elements (~1e3) of one sign, the moments
    # about the centroid losing ~10x to the parallel-axis shift: ~1e-13; 1e-12 / 1e-10 leave room.
    assert res.area == pytest.approx(area, rel=1e-12)
    assert res.centroid == pytest.approx((yc, zc), abs=1e-12)
    assert (res.iy, res.iz) == pytest.approx((iy, iz), rel=1e-10)
    assert res.iyz == pytest.approx(0.0, abs=1e-12 * iy)
    assert res.ip_axis == pytest.approx(iy + iz + area * (yc**2 + zc**2), rel=1e-10)
    assert res.shear_centre == pytest.approx((yc, zc), abs=1e-6)  # doubly symmetric
    assert 0.85 < res.shear_area_z / (web_t * web_h) < 1.15
    assert res.shear_area_y > 2 * res.shear_area_z


# --- 3. polygonised annulus and the faceting correction -------------------------------------------


def test_polygonised_annulus_converges_and_correction_removes_faceting():
    D, d = 0.2, 0.1
    j_exact = np.pi / 32 * (D**4 - d**4)
    a_exact = np.pi / 4 * (D**2 - d**2)
    ns = [32, 64, 128]
    errors = []
    for n in ns:
        res = wp.warping_properties(circle(D / 2, n).difference(circle(d / 2, n)), nu=0.3)
        errors.append(res.j / j_exact - 1)
        # A chord of an n-gon cuts off a sag ~ r (pi/n)^2 / 2 all round, so J and Ip of the polygon
        # are both low by ~ (pi/n)^2 (1e-2 at n = 32). For a circle or annulus J = Ip, and the
        # polygon's warping (its departure from J = Ip) is of higher order in 1/n, so the faceting
        # error of J is that of Ip to first order: scaling J by exact Ip / polygon Ip removes it.
        # (At this mesh the discrete warping of a fine n-gon is nil and J = Ip to 1e-15; with a
        # 1000-element mesh J/Ip - 1 = -2.7e-4 at n = 32 and -8e-6 at n = 64.)
        fixed = wp.corrected(res, a_exact, j_exact)
        if n >= 64:
            assert fixed.j == pytest.approx(j_exact, rel=1e-4)
        assert fixed.ip_axis == j_exact and fixed.area == a_exact
        # the same product and quotient: a rounding
        assert fixed.shear_area_y == pytest.approx(res.shear_area_y * a_exact / res.area, rel=1e-15)
    assert all(e < 0 for e in errors)
    rates = np.diff(np.log(np.abs(errors))) / np.diff(np.log(ns))
    assert rates == pytest.approx([-2.0, -2.0], abs=0.05)  # error ~ n^-2 as the polygon is refined
    assert abs(errors[-1]) < 1e-3


# --- 4. closed forms: rectangle J, circle shear area ----------------------------------------------


def rectangle_j(long_side, short_side, terms=50):
    # Exact series, S. P. Timoshenko & J. N. Goodier, "Theory of Elasticity", 3rd ed. (1970), chapter
    # "Torsion", torsion of rectangular bars (the torque series), with sides 2a = short, 2b = long:
    #   J = (1/3) (2a)^3 (2b) [1 - (192/pi^5) (a/b) sum_{n=1,3,5..} tanh(n pi b / 2a) / n^5].
    a, b = short_side / 2, long_side / 2
    s = sum(math.tanh(n * math.pi * b / (2 * a)) / n**5 for n in range(1, 2 * terms, 2))
    return (2 * a) ** 3 * (2 * b) / 3 * (1 - 192 / math.pi**5 * (a / b) * s)


@pytest.mark.parametrize("aspect", [1.0, 2.0, 10.0])
def test_rectangle_torsion_constant(aspect):
    # Square: J = 0.1406 a^4 (T&G's table of k1 for rectangles: 0.141). Mesh error at the default
    # target: +1e-4 (square) ... +2.2e-4 (aspect 10).
    short = 0.02
    res = wp.warping_properties(box(0.0, -short / 2, aspect * short, short / 2), nu=0.3)
    assert res.j == pytest.approx(rectangle_j(aspect * short, short), rel=5e-4)
    if aspect == 1.0:
        assert res.j / short**4 == pytest.approx(0.1406, abs=1e-4)


@pytest.mark.parametrize("nu", [0.0, 0.3])
def test_solid_circle_shear_area(nu):
    # sectionproperties' shear area is energy-equivalent: A_s = V^2 / ∫ tau^2 dA (Pilkey 2002).
    # With the exact flexure stresses of a circular cantilever (Timoshenko & Goodier, 3rd ed., chapter
    # "Bending of prismatical bars", circular cross section:
    #   tau_xz = (3+2nu)/(8(1+nu)) V/I [a^2 - x^2 - (1-2nu)/(3+2nu) y^2],
    #   tau_yz = -(1+2nu)/(4(1+nu)) V x y / I)
    # that integral gives kappa = A_s/A = 6 (1+nu)^2 / (7 + 14 nu + 8 nu^2) (integrated symbolically;
    # the stresses resolve to V) - which sectionproperties reproduces to ~6e-6 on a 128-gon.
    # Cowper (1966), J. Appl. Mech. 33:335, eq. for the solid circle, kappa = 6 (1+nu) / (7 + 6 nu),
    # is a different (displacement-averaged) definition: equal at nu = 0 (6/7), 4 % higher at nu = 0.3.
    disk = circle(0.05, 128)
    res = wp.warping_properties(disk, nu=nu)
    kappa_energy = 6 * (1 + nu) ** 2 / (7 + 14 * nu + 8 * nu**2)
    kappa_cowper = 6 * (1 + nu) / (7 + 6 * nu)
    for shear_area in (res.shear_area_y, res.shear_area_z):
        assert shear_area / res.area == pytest.approx(kappa_energy, rel=1e-4)
        if nu == 0.0:
            assert shear_area / res.area == pytest.approx(kappa_cowper, rel=1e-4)
        else:
            assert shear_area / res.area < 0.97 * kappa_cowper
    assert res.j == pytest.approx(res.ip_axis, rel=1e-6)  # circle: J = Ip


# --- 5. cache ----------------------------------------------------------------------------------


def keyed_slice_at(x):
    """The (y, z) section of a keyed shaft cut at axial position x, as a CAD slicer would give it."""
    shaft = circle(0.05, 96).difference(box(0.04, -0.014, 0.1, 0.014))
    xyz = [(x, y, z) for y, z in shaft.exterior.coords]
    return Polygon([(y, z) for _, y, z in xyz])


def test_cache_hits_the_same_shape_and_misses_a_different_one():
    first = wp.warping_properties(keyed_slice_at(0.3), nu=0.3)
    assert wp.analysis_count() == 1 and not first.cached
    again = wp.warping_properties(keyed_slice_at(1.7), nu=0.3)  # same shape further along the shaft
    assert wp.analysis_count() == 1 and again.cached and again.j == first.j
    # Reversed orientation, another start vertex, floating-point noise: still the same entry. (A
    # coordinate within the noise of a half-nanometre rounds either way: probability 2 noise / 1 nm.)
    ring = np.asarray(keyed_slice_at(0.0).exterior.coords)[:-1][::-1]
    noisy = Polygon(np.roll(ring, 17, axis=0) * (1 + 1e-15))
    assert wp.warping_properties(noisy, nu=0.3).cached
    assert wp.analysis_count() == 1
    # A rotated copy is a different polygon: a new analysis, with J equal to mesh accuracy.
    turned = wp.warping_properties(affinity.rotate(keyed_slice_at(0.0), 15.0, origin=(0, 0)), nu=0.3)
    assert wp.analysis_count() == 2 and not turned.cached
    assert turned.j == pytest.approx(first.j, rel=1e-3)
    # Both polygons are snapped to the 1 nm grid: each vertex moves up to 0.7 nm, so each area by at most
    # perimeter (0.33 m) × 0.7 nm = 2.3e-10 m², 6e-8 of the 7.6e-3 m² section for the two (9.6e-10 seen:
    # the roundings' random walk). A vertex or facet lost in the rotation would cost 1e-4 or more.
    assert turned.area == pytest.approx(first.area, rel=1e-7)
    # Another nu or mesh target is another entry; cache=False neither reads nor writes.
    wp.warping_properties(keyed_slice_at(0.0), nu=0.25)
    assert wp.analysis_count() == 3
    wp.warping_properties(keyed_slice_at(0.0), nu=0.3, cache=False)
    assert wp.analysis_count() == 4
    wp.clear_cache()
    assert wp.analysis_count() == 0
    assert not wp.warping_properties(keyed_slice_at(0.0), nu=0.3).cached


def test_sliver_of_a_multipolygon_is_dropped_and_hits_the_cache():
    disk = circle(0.05, 64)
    sliver = Polygon([(0.2, 0.2), (0.2 + 1e-10, 0.2), (0.2, 0.2 + 1e-10)])
    wp.warping_properties(disk, nu=0.3)
    assert wp.warping_properties(MultiPolygon([disk, sliver]), nu=0.3).cached


def test_near_duplicate_vertices_do_not_crash_the_mesher():
    # Without snapping, two vertices 1e-13 m apart become one after sectionproperties' own rounding,
    # leaving a zero-length facet that made Triangle segfault (found with a keyway edge through a
    # circle vertex).
    ring = list(circle(0.05, 64).exterior.coords)[:-1]
    ring.insert(5, (ring[5][0] + 1e-13, ring[5][1]))
    res = wp.warping_properties(Polygon(ring), nu=0.3)
    assert res.j == pytest.approx(res.ip_axis, rel=1e-6)


def test_no_output(capfd):
    wp.preload()
    wp.warping_properties(circle(0.05, 48), nu=0.3)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


# --- 6. bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: Polygon(), "empty"),
        (lambda: Polygon([(0, 0), (0.1, 0.1), (0.1, 0), (0, 0.1)]), "Self-intersection"),
        (lambda: Polygon([(0, 0), (0.1, 0), (0.2, 0)]), "invalid polygon"),
        (lambda: Polygon([(0, 0), (1e-6, 0), (0, 1e-6)]), "area"),
        (lambda: circle(50.0, 32), "millimetres"),
        (lambda: MultiPolygon([circle(0.05, 32), circle(0.01, 32, (0.2, 0))]), "2 disjoint regions"),
        (lambda: Polygon([(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)]), "third coordinate"),
        (lambda: Polygon([(0, 0), (0.1, float("nan")), (0, 0.1)]), "non-finite"),
        (lambda: LineString([(0, 0), (0.1, 0)]), "got LineString"),
        (lambda: [(0, 0), (0.1, 0), (0, 0.1)], "got list"),
    ],
)
@pytest.mark.filterwarnings("ignore:invalid value encountered")
def test_bad_polygons_raise_model_error(make, words):
    with pytest.raises(ModelError, match=words) as info:
        wp.warping_properties(make(), nu=0.3)
    assert info.value.field == "polygon"
    assert "\n" not in str(info.value) and str(info.value).startswith("polygon")
    assert wp.analysis_count() == 0


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"nu": 0.5}, "nu"),
        ({"nu": float("nan")}, "nu"),
        ({"nu": "0.3"}, "nu"),
        ({"nu": 0.3, "mesh_elements": 0}, "mesh_elements"),
        ({"nu": 0.3, "mesh_elements": 200.0}, "mesh_elements"),
        ({"nu": 0.3, "mesh_elements": True}, "mesh_elements"),
    ],
)
def test_bad_options_raise_model_error(kwargs, field):
    with pytest.raises(ModelError) as info:
        wp.warping_properties(circle(0.05, 32), **kwargs)
    assert info.value.field == field


def test_corrected_rejects_values_of_another_section():
    res = wp.warping_properties(circle(0.05, 64), nu=0.3)
    with pytest.raises(ModelError, match="exact_ip_axis"):
        wp.corrected(res, res.area, 2 * res.ip_axis)
    with pytest.raises(ModelError, match="exact_area"):
        wp.corrected(res, res.area * 1e6, res.ip_axis)  # mm² passed for m²
