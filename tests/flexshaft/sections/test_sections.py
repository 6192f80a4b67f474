"""The section table and its closed forms (no CAD needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.sections import (
    SectionTable,
    annulus_properties,
    cowper_shear_factor,
    table_from_segments,
    tables_from_csv,
    tables_to_csv,
)

G = fs.STEEL.G
RHO = fs.STEEL.rho


def test_annulus_closed_forms():
    # Area, polar moment and torsion constant of a tube (any strength-of-materials text):
    # A = π (D² − d²)/4, Ip = J = π (D⁴ − d⁴)/32, I = Ip/2.
    D, d = 0.31, 0.12
    p = annulus_properties(D, d)
    # The same closed forms in another order: a few roundings (D² − d² cancels only 1.2×); 1e-14 ≈ 45 eps.
    assert p.area == pytest.approx(math.pi * (D * D - d * d) / 4, rel=1e-14)
    assert p.ip == pytest.approx(math.pi * (D**4 - d**4) / 32, rel=1e-14)
    assert p.j == p.ip and p.i == pytest.approx(p.ip / 2, rel=1e-15)  # a halving: exact


def test_cowper_thin_tube_limit():
    # Cowper (1966), J. Appl. Mech. 33, Table 1 lists the thin-walled round tube separately:
    # κ = 2 (1 + ν) / (4 + 3ν). The hollow-circle formula must tend to it as m → 1.
    for nu in (0.0, 0.29, 0.45):
        assert cowper_shear_factor(1.0 - 1e-7, nu) == pytest.approx(2 * (1 + nu) / (4 + 3 * nu), rel=1e-6)
    # and the solid circle entry, κ = 6 (1 + ν)/(7 + 6ν): 0.8864 at ν = 0.3 (Cowper's Table 1).
    assert cowper_shear_factor(0.0, 0.3) == pytest.approx(0.8864, abs=5e-5)


def test_stepped_shaft_stiffness_is_the_series_sum():
    segs = [(0.3, 0.10, 0.04), (0.4, 0.16, 0.0), (0.25, 0.08, 0.03)]
    t = table_from_segments([{"length": L, "od": D, "id": d} for L, D, d in segs])
    k_series = 1.0 / sum(L / (G * math.pi * (D**4 - d**4) / 32) for L, D, d in segs)
    # Three terms of a few operations each, summed in another order: ~10 roundings, 1e-14 ≈ 45 eps.
    assert t.torsional_stiffness(G) == pytest.approx(k_series, rel=1e-14)
    inertia = sum(RHO * math.pi * (D**4 - d**4) / 32 * L for L, D, d in segs)
    assert t.axial_inertia(RHO) == pytest.approx(inertia, rel=1e-14)
    assert t.length == pytest.approx(0.95, rel=1e-15)  # two additions of 0.3, 0.4, 0.25: <= 1 eps
    assert t.method == ("annulus", "circle", "annulus")


def test_merged_joins_equal_neighbours_only():
    t = table_from_segments([(0.1, 0.2), (0.2, 0.2), (0.3, 0.1), (0.1, 0.2)])
    m = t.merged()
    assert m.x.tolist() == pytest.approx([0.0, 0.3, 0.6, 0.7])
    # Σ L/(G·J) over 4 intervals or over 3 merged ones: a few roundings apart, 1e-14 ≈ 45 eps.
    assert m.torsional_stiffness(G) == pytest.approx(t.torsional_stiffness(G), rel=1e-14)


def test_csv_round_trip_and_unit_check():
    t1 = table_from_segments([(0.3, 0.1, 0.04), (0.4, 0.16)], name="part 1", nu=0.3)
    t2 = table_from_segments([(1.0, 0.2)], name="part 2")
    back = tables_from_csv(tables_to_csv([t1, t2]))
    assert [b.name for b in back] == ["part 1", "part 2"]
    for a, b in zip((t1, t2), back):
        np.testing.assert_array_equal(a.x, b.x)
        np.testing.assert_array_equal(a.j, b.j)
        assert a.method == b.method and a.nu == b.nu
    text = tables_to_csv([t1]).replace("x_start_m", "x_start_mm")
    with pytest.raises(fs.ModelError, match="columns or units do not match"):
        tables_from_csv(text, source="t.csv")
    with pytest.raises(fs.ModelError, match="not a flexshaft section table"):
        tables_from_csv("a,b\n1,2\n")


def test_csv_read_from_a_path(tmp_path):
    t = table_from_segments([(0.3, 0.1, 0.04)], name="p")
    path = tmp_path / "t.csv"
    path.write_text(tables_to_csv([t]))
    for given in (path, str(path)):  # a Path, or the path as a string: read, not parsed as CSV text
        np.testing.assert_array_equal(tables_from_csv(given)[0].j, t.j)
    with pytest.raises(fs.ModelError, match=r"missing.csv: file not found"):
        tables_from_csv(tmp_path / "missing.csv")


def test_table_refuses_bad_arrays():
    good = table_from_segments([(0.3, 0.1)])
    kw = {
        c: getattr(good, c)
        for c in ("area", "ip", "iy", "iz", "iyz", "j", "shear_area_y", "shear_area_z", "yc", "zc")
    }
    with pytest.raises(fs.ModelError, match="strictly increasing"):
        SectionTable(x=np.array([0.3, 0.0]), method=("circle",), **kw)
    with pytest.raises(fs.ModelError, match=r"j = -1.0 m⁴: must be positive"):
        SectionTable(x=good.x, method=("circle",), **(kw | {"j": np.array([-1.0])}))
    with pytest.raises(fs.ModelError, match=r"area = nan m²: must be finite"):
        SectionTable(x=good.x, method=("circle",), **(kw | {"area": np.array([np.nan])}))


@pytest.mark.parametrize(
    "seg, message",
    [
        ({"length": 0.0, "od": 0.1}, "segments[0].length = 0.0 m: out of range"),
        ({"length": 0.2, "od": 0.1, "id": 0.1}, "segments[0].id = 0.1 m: the bore must be smaller"),
        ({"length": 0.2, "od": -0.1}, "segments[0].od = -0.1 m: out of range"),
        ({"length": 0.2}, "segments[0].od: missing"),
        ({"length": 0.2, "od": 0.1, "dia": 3}, "segments[0].dia: unknown key"),
    ],
)
def test_bad_segments(seg, message):
    with pytest.raises(fs.ModelError, match=message.replace("[", r"\[").replace("]", r"\]")):
        table_from_segments([seg])


@pytest.mark.parametrize(
    "seg, message",
    [
        # d⁴ of 1e100 m overflowed (an OverflowError "defect"), 1e300 m the element matrices (warnings)
        ({"length": 0.2, "od": 1e100}, "segments[0].od = 1e+100 m: out of range; valid: a finite number"),
        (
            {"length": 1e300, "od": 0.1},
            "segments[0].length = 1e+300 m: out of range; valid: a finite number >= 1e-06 and <= 1000 (m)",
        ),
        ({"length": 0.2, "od": 1e-100}, "segments[0].od = 1e-100 m: out of range"),
    ],
)
def test_segments_past_any_drivetrain_are_range_errors(seg, message):
    with pytest.raises(fs.ModelError) as err:
        table_from_segments([seg])
    assert str(err.value).startswith(message)


def test_annulus_properties_past_floating_point_name_the_diameter():
    # (1e100)⁴ raises OverflowError in Python floats; (1e-100)⁴ is 0: both the od's range error.
    for od in (1e100, 1e-100):
        with pytest.raises(fs.ModelError) as err:
            annulus_properties(od)
        assert str(err.value).startswith(f"od = {od!r} m: gives section properties (π/32·d⁴) outside")
        assert "valid: 1e-06 m <= od <= 1000 m" in str(err.value)


def test_model_file_shaft_by_segments_and_material_table():
    text = """
[materials.s355]
E = 200e9
nu = 0.3
rho = 7800

[[chain]]
name = "motor"
type = "rigid"
inertia = 10.0

[[chain]]
name = "part 4"
type = "shaft"
material = "s355"
segments = [{length = 0.30, od = 0.16}, {length = 0.40, od = 0.12, id = 0.04}]
damping_ratio = 0.0053
"""
    d = fs.loads_model(text, source="m.toml")
    shaft = d.component("part 4")
    Gs = 200e9 / (2 * 1.3)
    k = 1.0 / (0.3 / (Gs * math.pi * 0.16**4 / 32) + 0.4 / (Gs * math.pi * (0.12**4 - 0.04**4) / 32))
    # Closed forms against the table's sums of the same terms: ~10 roundings, 1e-14 ≈ 45 eps.
    assert shaft.stiffness == pytest.approx(k, rel=1e-14)
    j = 7800 * (0.3 * math.pi * 0.16**4 / 32 + 0.4 * math.pi * (0.12**4 - 0.04**4) / 32)
    assert shaft.inertia == pytest.approx(j, rel=1e-14)
    assert shaft.source == "segments" and shaft.material.name == "s355"
    # The modes use it like any shaft: two inertias and a spring (consistent inertia per element).
    assert fs.modal_analysis(d).frequencies_hz[1] > 0


@pytest.mark.parametrize(
    "extra, message",
    [
        (
            'material = "s999"\nsegments = [{length = 1.0, od = 0.1}]',
            "material = 's999': unknown material; valid: steel",
        ),
        ('material = "steel"\nsegments = []', "segments = []: missing or empty"),
        (
            'material = "steel"\nstiffness = 1e5\nsegments = [{length = 1.0, od = 0.1}]',
            "stiffness = 100000.0: a shaft given by its geometry takes no stiffness",
        ),
        ("segments = [{length = 1.0, od = 0.1}]", "material: missing key"),
        (
            'material = "steel"\nsegments = [{length = 1.0, od = 0.1, id = 0.2}]',
            "segments[0].id = 0.2 m: the bore must be smaller than the outer diameter",
        ),
    ],
)
def test_bad_shaft_by_segments(extra, message):
    text = f'[[chain]]\nname = "p"\ntype = "shaft"\n{extra}\n'
    with pytest.raises(fs.ModelError) as info:
        fs.loads_model(text, source="m.toml")
    assert message in str(info.value) and str(info.value).startswith("m.toml: [[chain]] #1 'p'")


def test_bad_material_table():
    text = (
        '[materials.x]\nE = 2e11\nnu = 0.7\nrho = 7800\n[[chain]]\nname = "m"\ntype = "rigid"\ninertia = 1\n'
    )
    with pytest.raises(fs.ModelError, match=r"m.toml: \[materials.x\]: nu = 0.7: out of range"):
        fs.loads_model(text, source="m.toml")
    text = text.replace("materials.x", "materials.steel").replace("0.7", "0.3")
    with pytest.raises(fs.ModelError, match="redefines a built-in material"):
        fs.loads_model(text, source="m.toml")
