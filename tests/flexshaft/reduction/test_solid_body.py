"""Craig-Bampton bodies of solid parts against closed forms, the unreduced solid and the solid twist test.

References: Saint-Venant torsion of a circular tube (G·J/L; rigid end faces impose nothing the exact
solution does not do); torsion waves in a circular bar are not dispersive, so the clamped-clamped and
the free-free twist modes are f_k = k·√(G/ρ)/(2L) for the solid exactly; the polar inertia ρ·Ip·L;
Craig-Bampton's constraint modes make the interface stiffness the static condensation of the whole
mesh (so it must equal the twist test of the solid part on the same mesh, which solves the unreduced
system), and its free-free modes converge to the unreduced tied solid's as modes are added.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.sparse.linalg import eigsh

from flexshaft.analysis.twist import part_stiffness
from flexshaft.cli import main
from flexshaft.elements.materials import STEEL
from flexshaft.elements.tet10 import solid_matrices
from flexshaft.parts.solidpart import solid_part_model
from flexshaft.parts.solidties import constrain, rigid_interface
from flexshaft.reduction.axisline import surface_triangles
from flexshaft.reduction.craig_bampton import craig_bampton
from flexshaft.reduction.ritz import twist_share
from tests.conftest import gmsh_loads

pytestmark = pytest.mark.skipif(
    not gmsh_loads(), reason="gmsh does not import: pip install 'flexshaft[solid]' and its system libraries"
)

OD, ID, L = 0.2, 0.08, 0.5  # m: the tube
IP = math.pi / 32 * (OD**4 - ID**4)
GJ_L = STEEL.G * IP / L
WAVE = math.sqrt(STEEL.G / STEEL.rho) / (2 * L)  # Hz: the first twist mode, clamped or free


def solid_cb(mesh, material, *, dofs="full", interface="rigid", **how):
    """The one Craig-Bampton front end on the solid part model of ``mesh``."""
    return craig_bampton(solid_part_model(mesh, material, dofs=dofs, interface=interface), **how)


@pytest.fixture(scope="module")
def mesh():
    from flexshaft.input.cad import solid_mesh

    return solid_mesh(name="tube", segments=[{"length": L, "od": OD, "id": ID}], size=0.04, use_cache=False)


@pytest.fixture(scope="module")
def torsion(mesh):
    return solid_cb(mesh, STEEL, dofs="torsion", modes=3, line_x=np.linspace(0, L, 6))


def test_a_torsion_body_is_stiff_as_the_solid_twist_test(mesh, torsion):
    k = torsion.K[1, 1]  # θ_end's row: the constraint modes leave the boundary uncoupled from the modes
    assert GJ_L <= k <= 1.005 * GJ_L  # the 0.5 %, from above (a conforming model)
    # the static condensation of the same mesh: equal to the solver's round-off (LU, residual < 1e-8)
    assert k == pytest.approx(part_stiffness(solid_part_model(mesh, STEEL)).torsion, rel=1e-8)
    np.testing.assert_allclose(torsion.K[:2, 2:], 0.0, atol=1e-9 * k)


def test_a_torsion_body_keeps_the_twist_modes_only(torsion):
    # the lowest fixed-interface modes of this stubby tube are bending pairs (2275 Hz) and axial ones;
    # the kept three are the twist family k·c/2L, from above within 1e-3 (2 elements across the wall)
    f = torsion.fixed_interface_hz[:3]
    exact = WAVE * np.arange(1, 4)
    assert np.all(exact <= f) and np.all(f < 1.001 * exact)
    assert torsion.free_hz[0] == 0.0
    assert WAVE <= torsion.free_hz[1] < 1.001 * WAVE  # free-free: the same wave solution


def test_a_torsion_body_spins_with_the_tubes_polar_inertia(torsion):
    spin = np.zeros(torsion.K.shape[0])
    spin[:2] = 1.0  # both masters turned by 1 rad: the constraint modes make it the rigid spin
    # curved P2 geometry: the volume is exact to O(h⁴) (2.7e-5 here)
    assert spin @ torsion.M @ spin == pytest.approx(STEEL.rho * IP * L, rel=1e-3)
    np.testing.assert_allclose(torsion.K @ spin, 0.0, atol=1e-9 * torsion.K[1, 1])


def test_the_axis_line_reads_the_sections_turn(torsion):
    # clamped start, a torque at the end: Saint-Venant's twist is linear along the tube
    K = torsion.K
    u = np.zeros(K.shape[0])
    u[1:] = np.linalg.solve(K[1:, 1:], np.eye(K.shape[0] - 1)[0])
    theta = torsion.T @ u
    x = np.linspace(0, L, 6)
    # the slab fit is exact for a linear field; the mesh's own error is ~1e-4
    np.testing.assert_allclose(theta / theta[-1], x / L, atol=1e-3)


def test_a_six_dof_body_is_the_solid_twist_tests_end_matrix(mesh):
    body = solid_cb(mesh, STEEL, dofs="full", modes=0, residual=False)
    end = body.K[6:12, 6:12]  # the start master clamped: its rows and columns drop out
    ref = part_stiffness(solid_part_model(mesh, STEEL)).stiffness
    np.testing.assert_allclose(end, ref, rtol=1e-7, atol=1e-7 * end.max())
    assert np.sum(body.free_hz == 0.0) == 6  # free: the six rigid-body motions


@pytest.mark.slow  # a convergence study: two reductions and the unreduced solid's eigensolve (~5 s)
def test_six_dof_free_modes_converge_to_the_unreduced_solid(mesh):
    mats = solid_matrices(mesh, STEEL)
    tied = constrain(mats.K, mesh, [rigid_interface(mesh, "start"), rigid_interface(mesh, "end")])
    M = tied.T.T @ mats.M @ tied.T
    # scipy's shift-invert Lanczos below zero (K − σM is then positive definite): the six rigid-body
    # modes and the three lowest elastic ones, the bending pair and the first twist mode
    lam = eigsh(tied.K, k=9, M=M, sigma=-((2 * np.pi * 100.0) ** 2), which="LM")[0]
    exact = np.sqrt(np.sort(lam)[6:]) / (2 * np.pi)
    errors = []
    for n in (4, 16):
        body = solid_cb(mesh, STEEL, dofs="full", modes=n)
        err = body.free_hz[6:9] / exact - 1
        assert np.all(err > -1e-9)  # a Ritz reduction: from above
        errors.append(np.max(err))
    # with residual vectors the error falls like (f/f_c)⁴ or faster: f/f_c 0.6 -> 0.3 at least 10x
    assert errors[1] < errors[0] / 10 and errors[1] < 1e-4


def test_the_surface_is_closed_and_outward(mesh):
    tri = surface_triangles(mesh.tets)
    p = mesh.nodes[tri]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    # the divergence theorem: Σ (x·n)/6 over the outward surface is the mesh's straight-sided volume
    corners = mesh.nodes[mesh.tets[:, :4]]
    volume = (
        np.sum(
            np.einsum(
                "ij,ij->i",
                corners[:, 1] - corners[:, 0],
                np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 0]),
            )
        )
        / 6
    )
    assert np.sum(np.einsum("ij,ij->i", p[:, 0], n)) / 6 == pytest.approx(volume, rel=1e-9)


def test_twist_share_tells_twist_from_bending(mesh):
    nodes = mesh.nodes
    twist = np.zeros_like(nodes)
    twist[:, 1], twist[:, 2] = -nodes[:, 2] * nodes[:, 0], nodes[:, 1] * nodes[:, 0]
    bend = np.zeros_like(nodes)
    bend[:, 1] = np.sin(np.pi * nodes[:, 0] / L)  # half its motion is tangential, none of it turns
    share = twist_share(nodes, np.column_stack([twist.ravel(), bend.ravel()]), 0.04)
    # a turn growing along x loses its variation across each slab: (θ'·w)²/12 of it, w the slab
    assert share[0] > 0.99
    assert share[1] < 0.05


def test_refused_settings(mesh):
    from flexshaft.errors import ModelError

    with pytest.raises(ModelError, match="dofs"):
        solid_cb(mesh, STEEL, dofs="lateral", modes=1)
    with pytest.raises(ModelError, match="modes or cutoff_hz"):
        solid_cb(mesh, STEEL, dofs="full")


# --- the model file: fe = "solid" ---------------------------------------------------------------------

TUBE = """[model]
name = "tube"

[[chain]]
name = "tube"
type = "shaft"
material = "steel"
fe = "solid"
mesh_size = "40 mm"
segments = [{length = 0.5, od = 0.2, id = 0.08}]
"""


def _run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_the_twist_command_tests_a_solid_tube(tmp_path, capsys):
    model = tmp_path / "tube.toml"
    model.write_text(TUBE)
    code, out, err = _run(capsys, "twist", str(model), "--torque", "1000", "--json")
    assert code == 0, err
    doc = json.loads(out)
    (part,) = doc["parts"]
    assert GJ_L <= part["stiffness"] <= 1.005 * GJ_L  # the demand: G·J/L within 0.5 %
    assert part["elements"].startswith("solid:") and "RBE2" in part["elements"]
    # and the modes: the tube's free-free twist mode (a body of 4 twist modes + residual vectors)
    code, out, err = _run(capsys, "modes", str(model))
    assert code == 0, err
    f1 = float(out.split("\n   1 ")[1].split()[0])
    assert WAVE <= f1 < 1.001 * WAVE


def test_the_twist_test_reuses_a_reduction_with_modes(tmp_path, monkeypatch):
    import flexshaft as fs
    from flexshaft.model import shaftparts as assembly  # where the assembly keeps solid reductions

    model = tmp_path / "tube.toml"
    model.write_text(TUBE)
    drivetrain = fs.load_model(model)
    monkeypatch.setattr(assembly, "_SOLID_BODIES", {})
    alone = fs.twist_test(drivetrain).parts[0].stiffness  # the static condensation alone
    monkeypatch.setattr(assembly, "_SOLID_BODIES", {})
    fs.modal_analysis(drivetrain)
    (key,) = assembly._SOLID_BODIES
    after = fs.twist_test(drivetrain).parts[0].stiffness
    assert list(assembly._SOLID_BODIES) == [key]  # no second reduction for the statics
    # a Craig-Bampton body's boundary stiffness is that same condensation (its modal coordinates are
    # uncoupled and unloaded): equal to the LU solves' round-off (this mesh is below DIRECT_MAX)
    assert after == pytest.approx(alone, rel=1e-9)
    assert GJ_L <= after <= 1.005 * GJ_L


def test_a_solid_part_is_meshed_once(tmp_path, monkeypatch):
    import flexshaft as fs

    monkeypatch.setenv("FLEXSHAFT_CACHE_DIR", str(tmp_path / "cache"))
    model = tmp_path / "tube.toml"
    model.write_text(TUBE)
    first = fs.load_model(model)
    (entry,) = (tmp_path / "cache" / "meshes").glob("*.npz")
    second = fs.load_model(model)
    a, b = first.components[0].solid_mesh, second.components[0].solid_mesh
    np.testing.assert_array_equal(a.nodes, b.nodes)
    np.testing.assert_array_equal(a.tets, b.tets)
    entry.write_bytes(b"not a mesh")  # a damaged entry is rebuilt, never trusted
    again = fs.load_model(model).components[0].solid_mesh
    np.testing.assert_array_equal(again.tets, a.tets)


@pytest.mark.parametrize(
    "change, message",
    [
        (('fe = "solid"', 'fe = "3d"'), "fe = '3d': unknown option; valid: one of '1d', 'solid'"),
        (('mesh_size = "40 mm"', 'mesh_size = "-4 mm"'), "mesh_size = -0.004 m: "),
        (
            ("segments =", "stations = {journal = 0.2}\nsegments ="),
            "stations = 'journal': stations inside a solid part are not supported yet",
        ),
        (
            (
                'material = "steel"\nfe = "solid"\nmesh_size = "40 mm"\n'
                "segments = [{length = 0.5, od = 0.2, id = 0.08}]",
                'fe = "solid"\nstiffness = 1e6\ninertia = 1.0',
            ),
            "fe = 'solid': a solid part needs its solid mesh",
        ),
    ],
)
def test_bad_solid_settings_get_one_line(tmp_path, capsys, change, message):
    model = tmp_path / "tube.toml"
    model.write_text(TUBE.replace(*change))
    code, out, err = _run(capsys, "twist", str(model))
    assert code == 2 and out == ""
    assert message in err and err.count("\n") == 1, err


def test_reduce_exports_the_solid_body(tmp_path, capsys):
    from flexshaft.exports.bodies import read_flexible_body

    model = tmp_path / "tube.toml"
    model.write_text(TUBE)
    out_file = tmp_path / "tube.npz"
    code, out, err = _run(capsys, "reduce", str(model), "--part", "tube", "--modes", "2", "-o", str(out_file))
    assert code == 0, err
    assert "a solid of" in out and "RBE2" in out
    body = read_flexible_body(out_file).body
    # the exported body is the solid's: its first free-free elastic mode the wave solution
    assert WAVE <= body.free_hz[1] < 1.001 * WAVE
    # its rigid-body inertia the tube's (the check's rigid mass error: round-off of ΦᵀMΦ sums)
    assert "rigid-body mass" in out
    err_mass = float(out.split("rigid-body mass ")[1].split(",")[0])
    assert err_mass < 1e-10


def test_a_solid_reduction_reports_its_stages(mesh):
    import io

    from flexshaft.views.progress import ProgressBar

    stream = io.StringIO()
    bar = ProgressBar("reducing tube", stream=stream, enabled=True)
    solid_cb(mesh, STEEL, dofs="torsion", modes=1, progress=bar.stage)
    text = stream.getvalue()
    for stage in (
        "assembling the solid",
        "constraint modes",
        "fixed-interface twist modes",
        "residual vectors",
    ):
        assert f"reducing tube: {stage}" in text
    assert text.endswith("100 %\n")  # the bar ends its line when done


def test_a_solid_parts_own_surface_turns_with_its_mode(tmp_path):
    import flexshaft as fs
    from flexshaft.views.deformed import mode_surface

    model = tmp_path / "tube.toml"
    model.write_text(TUBE)
    result = fs.modal_analysis(fs.load_model(model))
    first = int(np.flatnonzero(~result.rigid)[0])  # the free-free twist mode, θ ∝ cos(πx/L)
    s = mode_surface(result, first, colour="twist")
    assert s.triangles.shape[0] > 0 and s.faces.shape[0] == 0  # the mesh's surface, not revolved rings
    x = s.points[:, 0]
    turn = s.theta / s.amplitude  # each point's own turn, the largest station rotation 1
    expected = np.cos(np.pi * x / L) * np.sign(turn[np.argmin(x)])
    # the solid's mode against the wave solution: the mesh's error (3e-4 in frequency, ~1e-2 in shape
    # at two elements across the wall) plus the end faces' master reading the section's turn
    np.testing.assert_allclose(turn, expected, atol=0.02)


STEP = """[model]
name = "step"

[[chain]]
name = "stepped"
type = "shaft"
material = "steel"
mesh_size = "60 mm"
segments = [{length = 0.25, od = 0.2}, {length = 0.25, od = 0.12}]
"""


def test_sections_compares_each_part_with_its_solid(tmp_path, capsys):
    from flexshaft.sections.table import table_from_segments, tables_from_csv

    model = tmp_path / "step.toml"
    model.write_text(STEP)
    # one run (the solid twist test is the cost): the tables corrected to the solids' torsion;
    # tests/flexshaft/analysis/test_solidcompare.py checks the amount against BICERA's chart and the
    # JSON document
    csv = tmp_path / "corrected.csv"
    code, out, err = _run(capsys, "sections", str(model), "--compare-solid", "--modes", "0", "-o", str(csv))
    assert code == 0, err
    (table,) = tables_from_csv(csv.read_text())
    segments = [{"length": 0.25, "od": 0.2}, {"length": 0.25, "od": 0.12}]
    one_d = table_from_segments(segments, nu=STEEL.nu)
    ratio = table.torsional_stiffness(STEEL.G) / one_d.torsional_stiffness(STEEL.G)
    assert 0.9 < ratio < 1.0  # softer at the step, by some per cent (BICERA: 4.3 % for this shaft)
    np.testing.assert_allclose(table.ip, one_d.ip, rtol=1e-12)  # the inertia is the table's


def test_compare_solid_needs_a_model_file(tmp_path, capsys):
    part = tmp_path / "part.step"
    part.write_text("not read")
    code, out, err = _run(capsys, "sections", str(part), "--compare-solid")
    assert code == 2 and "compares the parts of a model file" in err and err.count("\n") == 1


def test_the_drawn_surface_follows_the_curved_faces(mesh):
    tri = surface_triangles(mesh.tets, midside=True)
    p = mesh.nodes[tri]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.abs(n.sum(axis=0)).max() < 1e-12 * np.abs(n).sum()  # closed: the area vectors cancel
    # outward, and the flat pieces between nodes on the circles hold the tube's volume to the chords'
    # sagitta: (π/N)²/3 of it for N pieces round a circle (N ~ 24 here: 6e-3)
    volume = np.sum(np.einsum("ij,ij->i", p[:, 0], n)) / 6
    assert volume == pytest.approx(math.pi / 4 * (OD**2 - ID**2) * L, rel=6e-3)
