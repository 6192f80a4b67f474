"""CAD parts in model files and on the command line (the test-bench library: tests/geometry/parts)."""

from __future__ import annotations

import json
import math

import pytest

pytest.importorskip("build123d")

import flexshaft as fs  # noqa: E402
from flexshaft.cli import main  # noqa: E402
from flexshaft.sections import tables_from_csv  # noqa: E402
from geometry import parts  # noqa: E402
from geometry.cadio import write_step  # noqa: E402

G, RHO = fs.STEEL.G, fs.STEEL.rho

PART_MODULE = '''
from geometry.parts import stepped_shaft


def tube(*, length=1.2, od=0.2, id=0.08):
    """A plain tube, SI metres."""
    return stepped_shaft([{"length": length, "od": od, "id": id}])
'''

MOTOR = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n'


def tube_stiffness(length=1.2, od=0.2, id=0.08):
    # G·Ip/L with Ip = π (D⁴ − d⁴)/32: the closed form of a uniform tube. The slicer reads the tube's
    # circles as an annulus, so the parts below match it to round-off (a few eps); their rel=1e-9 is
    # far above that and far below a faceted section's error (~1e-4).
    return G * math.pi * (od**4 - id**4) / 32 / length


def tube_inertia(length=1.2, od=0.2, id=0.08):
    return RHO * math.pi * (od**4 - id**4) / 32 * length


@pytest.fixture
def workdir(tmp_path):
    (tmp_path / "my_parts.py").write_text(PART_MODULE)
    return tmp_path


def test_cad_part_function_beside_the_model_file(workdir):
    model = workdir / "m.toml"
    model.write_text(
        MOTOR + '[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "my_parts:tube"\n'
        'material = "steel"\nparams = {length = 0.9}\ndamping_ratio = 0.0053\n'
    )
    d = fs.load_model(model, allow_code=True)
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
    model.write_text(
        MOTOR + '[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "cad/tube.step"\nmaterial = "steel"\n'
    )
    tube = fs.load_model(model).component("tube")
    assert tube.stiffness == pytest.approx(tube_stiffness(), rel=1e-9)


@pytest.mark.parametrize(
    "entry, message",
    [
        (
            'geometry = "my_parts:tube"\nmaterial = "steel"\nparams = {lenght = 1.0}',
            "params = {'lenght': 1.0}: parameters do not fit my_parts:tube",
        ),
        ('geometry = "my_parts:nothing"\nmaterial = "steel"', "module 'my_parts' has no function 'nothing'"),
        ('geometry = "no_such_module:f"\nmaterial = "steel"', "cannot import module 'no_such_module'"),
        ('geometry = "tube.step"\nmaterial = "steel"', "tube.step': file not found; valid: an existing STEP"),
        ('geometry = "my_parts"\nmaterial = "steel"', "is not 'module:function' or a file"),
        (
            'geometry = "my_parts:tube"\nmaterial = "steel"\nstiffness = 1e6',
            "stiffness: unknown key; valid: one of name, type, geometry",
        ),
        (
            'geometry = "my_parts:tube"\nmaterial = "steel"\nunit = "mm"',
            "unit = 'mm': only a mesh file (STL/OBJ/PLY) takes a length unit",
        ),
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
        fs.load_model(model, allow_code=True)
    text = str(info.value)
    assert message in text and text.startswith(f"{model}: [[chain]] #2 'tube'") and "\n" not in text


def test_cli_sections_of_a_model(workdir, capsys):
    model = workdir / "m.toml"
    model.write_text(
        MOTOR + '[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "my_parts:tube"\n'
        'material = "steel"\n\n[[chain]]\nname = "stub"\ntype = "shaft"\nmaterial = "steel"\n'
        "segments = [{length = 0.3, od = 0.1}]\n"
    )
    assert main(["sections", str(model), "--json", "--allow-code"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [p["name"] for p in doc["parts"]] == ["tube", "stub"]
    assert doc["parts"][0]["stiffness"] == pytest.approx(tube_stiffness(), rel=1e-9)
    assert doc["units"]["stiffness"] == "N·m/rad"
    assert main(["sections", str(model), "--allow-code"]) == 0
    out = capsys.readouterr().out
    assert "tube: cad my_parts:tube, steel" in out and "N·m/rad" in out
    csv_path = workdir / "t.csv"
    assert main(["sections", str(model), "-o", str(csv_path), "--allow-code"]) == 0
    tables = tables_from_csv(csv_path.read_text())
    assert [t.name for t in tables] == ["tube", "stub"]
    assert tables[0].torsional_stiffness(G) == pytest.approx(tube_stiffness(), rel=1e-9)
    # Never overwritten without --force.
    assert main(["sections", str(model), "-o", str(csv_path), "--allow-code"]) == 2
    assert "file exists" in capsys.readouterr().err
    assert main(["sections", str(model), "-o", str(csv_path), "--force", "--allow-code"]) == 0


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
