"""CAD parts in model files and on the command line; the test-bench library against its own solids."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

pytest.importorskip("build123d")

import flexshaft as fs  # noqa: E402
from flexshaft.cli import main  # noqa: E402
from flexshaft.sections import tables_from_csv  # noqa: E402
from geometry import parts  # noqa: E402
from geometry.cadio import read_mesh, write_step, write_stl  # noqa: E402
from geometry.parts import testbench  # noqa: E402
from geometry.slicing import sections  # noqa: E402

G, RHO = fs.STEEL.G, fs.STEEL.rho

PART_MODULE = '''
from geometry.parts import stepped_shaft


def tube(*, length=1.2, od=0.2, id=0.08):
    """A plain tube, SI metres."""
    return stepped_shaft([{"length": length, "od": od, "id": id}])
'''

MOTOR = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n'


def tube_stiffness(length=1.2, od=0.2, id=0.08):
    # G·Ip/L with Ip = π (D⁴ − d⁴)/32: the closed form of a uniform tube.
    return G * math.pi * (od**4 - id**4) / 32 / length


def tube_inertia(length=1.2, od=0.2, id=0.08):
    return RHO * math.pi * (od**4 - id**4) / 32 * length


@pytest.fixture
def workdir(tmp_path):
    (tmp_path / "my_parts.py").write_text(PART_MODULE)
    return tmp_path


def test_cad_part_function_beside_the_model_file(workdir):
    model = workdir / "m.toml"
    model.write_text(MOTOR + '[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "my_parts:tube"\n'
                     'material = "steel"\nparams = {length = 0.9}\ndamping_ratio = 0.0053\n')
    d = fs.load_model(model)
    tube = d.component("tube")
    assert tube.source == "cad"
    assert tube.stiffness == pytest.approx(tube_stiffness(length=0.9), rel=1e-9)
    assert tube.inertia == pytest.approx(tube_inertia(length=0.9), rel=1e-9)
    # Two inertias and a spring with consistent inertia: the one elastic mode of motor + free tube.
    r = fs.modal_analysis(d)
    assert r.frequencies_hz[1] > 0


def test_cad_step_file_relative_to_the_model(workdir):
    sub = workdir / "cad"
    sub.mkdir()
    write_step(parts.stepped_shaft([{"length": 1.2, "od": 0.2, "id": 0.08}]), sub / "tube.step")
    model = workdir / "m.toml"
    model.write_text(MOTOR + '[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "cad/tube.step"\n'
                     'material = "steel"\n')
    tube = fs.load_model(model).component("tube")
    assert tube.stiffness == pytest.approx(tube_stiffness(), rel=1e-9)


@pytest.mark.parametrize(
    "entry, message",
    [
        ('geometry = "my_parts:tube"\nmaterial = "steel"\nparams = {lenght = 1.0}',
         "params = {'lenght': 1.0}: parameters do not fit my_parts:tube"),
        ('geometry = "my_parts:nothing"\nmaterial = "steel"', "module 'my_parts' has no function 'nothing'"),
        ('geometry = "no_such_module:f"\nmaterial = "steel"', "cannot import module 'no_such_module'"),
        ('geometry = "tube.step"\nmaterial = "steel"', "tube.step': file not found; valid: an existing file"),
        ('geometry = "my_parts"\nmaterial = "steel"', "is not 'module:function' or a file"),
        ('geometry = "my_parts:tube"\nmaterial = "steel"\nstiffness = 1e6',
         "stiffness: unknown key; valid: one of name, type, geometry"),
        ('geometry = "my_parts:tube"\nmaterial = "steel"\nunit = "mm"',
         "unit = 'mm': only a mesh file (STL/OBJ/PLY) takes a length unit"),
        ('geometry = "my_parts:tube"', "material: missing key"),
        ('geometry = "my_parts:tube"\nmaterial = "steel"\nparams = {length = -1.0}', "length = -1.0 m"),
        ('geometry = "c.stl"\nmaterial = "steel"', "a mesh file carries no length unit"),
    ],
)
def test_bad_cad_entries(workdir, entry, message):
    import trimesh

    trimesh.creation.cylinder(radius=50.0, height=400.0).export(workdir / "c.stl")
    model = workdir / "m.toml"
    model.write_text(MOTOR + f'[[chain]]\nname = "tube"\ntype = "cad"\n{entry}\n')
    with pytest.raises(fs.ModelError) as info:
        fs.load_model(model)
    text = str(info.value)
    assert message in text and text.startswith(f"{model}: [[chain]] #2 'tube'") and "\n" not in text


TESTBENCH = ["motor_shaft_end", "coupling_hub", "ptss_part1", "torque_flange", "ptss_part2", "ptss_part4",
             "generator_shaft_end"]


class _Tables(dict):
    def __missing__(self, name):
        self[name] = table = sections(getattr(testbench, name)(), name=name)
        return table


@pytest.fixture(scope="session")
def testbench_tables():
    """The test-bench parts' section tables, each sliced once, when first asked for (so the slow STL
    round trip, run alone by `pytest -m slow`, slices only the part it needs)."""
    return _Tables()


@pytest.mark.parametrize("name", TESTBENCH)
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


def test_cli_sections_of_a_model(workdir, capsys):
    model = workdir / "m.toml"
    model.write_text(MOTOR + '[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "my_parts:tube"\n'
                     'material = "steel"\n\n[[chain]]\nname = "stub"\ntype = "shaft"\nmaterial = "steel"\n'
                     'segments = [{length = 0.3, od = 0.1}]\n')
    assert main(["sections", str(model), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [p["name"] for p in doc["parts"]] == ["tube", "stub"]
    assert doc["parts"][0]["stiffness"] == pytest.approx(tube_stiffness(), rel=1e-9)
    assert doc["units"]["stiffness"] == "N·m/rad"
    assert main(["sections", str(model)]) == 0
    out = capsys.readouterr().out
    assert "tube: cad my_parts:tube, steel" in out and "N·m/rad" in out
    csv_path = workdir / "t.csv"
    assert main(["sections", str(model), "-o", str(csv_path)]) == 0
    tables = tables_from_csv(csv_path.read_text())
    assert [t.name for t in tables] == ["tube", "stub"]
    assert tables[0].torsional_stiffness(G) == pytest.approx(tube_stiffness(), rel=1e-9)
    # Never overwritten without --force.
    assert main(["sections", str(model), "-o", str(csv_path)]) == 2
    assert "file exists" in capsys.readouterr().err
    assert main(["sections", str(model), "-o", str(csv_path), "--force"]) == 0


def test_cli_sections_of_files(workdir, capsys):
    write_step(parts.stepped_shaft([{"length": 1.2, "od": 0.2, "id": 0.08}]), workdir / "tube.step")
    assert main(["sections", str(workdir / "tube.step"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["parts"][0]["stiffness"] == pytest.approx(tube_stiffness(), rel=1e-9)
    import trimesh

    trimesh.creation.cylinder(radius=50.0, height=400.0).export(workdir / "c.stl")
    assert main(["sections", str(workdir / "c.stl")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a mesh file carries no length unit" in err
    assert main(["sections", str(workdir / "c.stl"), "--unit", "mm"]) == 0
    (workdir / "bad.step").write_text("garbage")
    assert main(["sections", str(workdir / "bad.step")]) == 2
    assert capsys.readouterr().err.startswith("flexshaft: error: geometry = ")
