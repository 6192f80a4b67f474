"""Gear stages: closed forms through the ratio, own speed frames, the twist test and signals through a stage.

References we did not write: the two- and three-inertia closed forms with reflected inertia and
stiffness (J/n², k/n² referred to the driving side), power conservation through a lossless stage,
the NREL 5-MW reference drivetrain's published damping (5 % of critical), and openTorsion's gear
constraint on the same model (a peer, run in its own virtualenv).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.statespace import frequency_response, state_space
from flexshaft.cli import main
from flexshaft.model.components import Coupling, Drivetrain, Gear, Reduce, Rigid, Shaft
from tests.conftest import EXAMPLES, run_peer

# Dense symmetric eigen-solves of small, well-conditioned problems are accurate to ~κ·ε (≤ 1e-12 here,
# stiffness and inertia spread < 1e4); closed forms are evaluated in double precision too. 1e-9 leaves
# three orders of margin for any BLAS or numpy version.
RTOL = 1e-9


def _two_inertia(n, *, shaft_after=True, j_in=0.1, j_out=0.4):
    """motor - [shaft] - gear n - [shaft] - generator, the shaft massless on one side."""
    k, j1, j2 = 1e5, 2.0, 5.0
    shaft = Shaft("shaft", stiffness=k, inertia=0.0)
    gear = Gear("gearbox", ratio=n, inertia_in=j_in, inertia_out=j_out)
    chain = (
        (Rigid("motor", j1), gear, shaft, Rigid("generator", j2))
        if shaft_after
        else (Rigid("motor", j1), shaft, gear, Rigid("generator", j2))
    )
    return Drivetrain("two inertias", chain), k, j1, j2


@pytest.mark.parametrize("n", [3.0, 0.25, 97.0])
@pytest.mark.parametrize("shaft_after", [True, False])
def test_two_inertias_through_a_gear_match_the_reflected_closed_form(n, shaft_after):
    # Referred to the driving side, everything past the stage is reflected by 1/n² (n = ω_in/ω_out):
    # J_a = J1 + J_in + J_out/n² ; J_b = J2/n² ; a shaft past the stage k/n². Before it, the wheels sit
    # with the generator: J_a = J1, J_b = J_in + (J_out + J2)/n², the shaft unreflected.
    d, k, j1, j2 = _two_inertia(n, shaft_after=shaft_after)
    j_in, j_out = 0.1, 0.4
    if shaft_after:
        ja, jb, kk = j1 + j_in + j_out / n**2, j2 / n**2, k / n**2
    else:
        ja, jb, kk = j1, j_in + (j_out + j2) / n**2, k
    expected = math.sqrt(kk * (1 / ja + 1 / jb)) / (2 * math.pi)
    r = fs.modal_analysis(d)
    assert r.frequencies_hz[0] == 0.0 and r.rigid[0]  # rigid-body modes are set, not solved for
    assert r.frequencies_hz[1] == pytest.approx(expected, rel=RTOL)
    # The rigid-body mode turns every station in its own frame: the generator 1/n of the motor (the
    # rigid basis is built from 1 and 1/n: a rounding or two).
    theta = r.dof_shapes("θx")[:, 0]
    motor, gen = (r.model.station(s).node for s in ("motor", "generator"))
    assert theta[gen] / theta[motor] == pytest.approx(1 / n, rel=1e-12)
    # In the elastic mode the generator swings against the motor in the ratio of the reflected inertias,
    # read in its own frame: θ_gen/θ_motor = −(J_a/J_b)/n (eigenvector components of a small, well
    # separated problem: ~eps·λ_max/gap, ~1e-15).
    theta = r.dof_shapes("θx")[:, 1]
    assert theta[gen] / theta[motor] == pytest.approx(-(ja / jb) / n, rel=1e-8)


def _chain(n1, n2, mesh=None, mesh_damping=0.0):
    """A geared chain with shafts of several elements and two stages (the second elastic if ``mesh``)."""
    return Drivetrain(
        "geared",
        (
            Rigid("motor", 10.0),
            Shaft("input shaft", stiffness=1e5, inertia=0.1, elements=3),
            Gear("stage 1", ratio=n1, inertia_in=0.2, inertia_out=0.05),
            Shaft("middle shaft", stiffness=4e4, inertia=0.02, elements=2),
            Gear(
                "stage 2",
                ratio=n2,
                inertia_in=0.03,
                inertia_out=0.01,
                mesh_stiffness=mesh,
                mesh_damping=mesh_damping,
            ),
            Coupling("coupling", stiffness=3e3, inertia=0.004),
            Rigid("generator", 0.05),
        ),
    )


@pytest.mark.parametrize("inertia_model", ["consistent", "lumped"])
@pytest.mark.parametrize("mesh", [None, 2e5])
def test_a_geared_chain_equals_the_chain_reflected_to_the_driving_side(inertia_model, mesh):
    # The classical reduction: a stage of ratio n scales the stiffness and inertia past it by 1/n². The
    # reflected chain has no gear (the elastic mesh becomes a coupling of stiffness k_m on the driving
    # side), so it is assembled without any of the gear code.
    n1, n2 = 2.5, 4.0
    geared = _chain(n1, n2, mesh)
    a, b = 1 / n1**2, 1 / (n1 * n2) ** 2
    comps = [
        Rigid("motor", 10.0),
        Shaft("input shaft", stiffness=1e5, inertia=0.1, elements=3),
        Rigid("wheel 1", 0.2 + 0.05 * a),
        Shaft("middle shaft", stiffness=4e4 * a, inertia=0.02 * a, elements=2),
    ]
    if mesh is None:
        comps.append(Rigid("wheels 2", 0.03 * a + 0.01 * b))
    else:
        comps += [
            Rigid("wheel in", 0.03 * a),
            Coupling("mesh", stiffness=mesh * a),
            Rigid("wheel out", 0.01 * b),
        ]
    comps += [Coupling("coupling", stiffness=3e3 * b, inertia=0.004 * b), Rigid("generator", 0.05 * b)]
    reflected = Drivetrain("reflected", tuple(comps))
    f_geared = fs.modal_analysis(geared, inertia_model=inertia_model).frequencies_hz
    f_reflected = fs.modal_analysis(reflected, inertia_model=inertia_model).frequencies_hz
    np.testing.assert_allclose(f_geared, f_reflected, rtol=RTOL, atol=1e-9)


def test_an_elastic_mesh_matches_the_three_inertia_closed_form():
    # J1 -k1- J2 (driving wheel) =mesh k_m, n= J3 (driven wheel + generator): referred to the driving side
    # a free three-inertia chain J_a, J_b, J_c = J3/n², springs k1 and k_m, whose elastic ω² are the roots
    # of ω⁴ − ω²[k1(1/Ja + 1/Jb) + km(1/Jb + 1/Jc)] + k1·km·(Ja + Jb + Jc)/(Ja·Jb·Jc) = 0.
    n, k1, km = 5.0, 8e4, 3e5
    d = Drivetrain(
        "mesh",
        (
            Rigid("motor", 3.0),
            Shaft("shaft", stiffness=k1, inertia=0.0),
            Gear("stage", ratio=n, inertia_in=0.4, inertia_out=0.2, mesh_stiffness=km),
            Rigid("generator", 1.3),
        ),
    )
    ja, jb, jc = 3.0, 0.4, (0.2 + 1.3) / n**2
    b = k1 * (1 / ja + 1 / jb) + km * (1 / jb + 1 / jc)
    c = k1 * km * (ja + jb + jc) / (ja * jb * jc)
    roots = np.sort([(b - math.sqrt(b * b - 4 * c)) / 2, (b + math.sqrt(b * b - 4 * c)) / 2])
    r = fs.modal_analysis(d)
    np.testing.assert_allclose(r.frequencies_hz[1:], np.sqrt(roots) / (2 * math.pi), rtol=RTOL)


def test_nrel_5mw_example_gives_its_published_damping_and_closed_form_frequency():
    # Jonkman et al. (NREL/TP-500-38060, 2009): the drive-shaft damper of 6 215 000 N·m·s/rad is 5 % of
    # critical in the free-free drivetrain mode. Two masses through the 97:1 stage: the relative motion is
    # exactly a 1-DOF oscillator J_eff·ẍ + c·ẋ + k·x = 0 with J_eff = J_r·J_g'/(J_r + J_g'), J_g' = 97²·J_g.
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "nrel5mw.toml"))
    k, c, jr, jg = 867637000.0, 6215000.0, 38759228.0, 534.116 * 97**2
    je = jr * jg / (jr + jg)
    assert r.frequencies_hz[1] == pytest.approx(math.sqrt(k / je) / (2 * math.pi), rel=RTOL)
    zeta = c / (2 * math.sqrt(k * je))
    assert zeta == pytest.approx(0.05, abs=5e-5)  # the published statement, to its rounding
    # The damped solve of a 2-DOF model: its eigenvalue to ~1e-12; 1e-9 as above.
    assert r.damping_ratios[1] == pytest.approx(zeta, rel=RTOL)


def test_torque_through_a_rigid_stage_obeys_newton_with_the_reflected_wheels():
    # At the tied wheels, in the driving frame: J_eff·θ̈_in = T_in − T_out/n, J_eff = J_in + J_out/n²
    # (the driven wheel reflected); so T_out = n·(T_in + ω²·J_eff·θ_in) at every frequency - with
    # massless wheels, power passes unchanged (T_out·ω_out = T_in·ω_in). Torques include the dashpots.
    n, j_in, j_out = 4.0, 0.1, 0.05
    d = Drivetrain(
        "stage",
        (
            Rigid("motor", 2.0),
            Shaft("in", stiffness=5e4, inertia=0.0, damping=3.0),
            Gear("stage", ratio=n, inertia_in=j_in, inertia_out=j_out),
            Shaft("out", stiffness=2e4, inertia=0.0, damping=1.0),
            Rigid("generator", 0.3),
        ),
    )
    r = fs.modal_analysis(d)
    out = ["torque:in", "torque:out", "angle:in/stage", "speed:in/stage", "speed:stage/out"]
    f = np.linspace(1.0, 200.0, 37)
    H = frequency_response(state_space(r, ["motor"], out), f).H[:, :, 0]
    w2 = (2 * np.pi * f) ** 2
    # Outputs of the same solves: round-off ~eps·ω_max/(ξω) near a mode (ξ ≈ 0.006, ω_max/ω₁ = 3), ~1e-13.
    np.testing.assert_allclose(H[:, 1], n * (H[:, 0] + w2 * (j_in + j_out / n**2) * H[:, 2]), rtol=1e-9)
    # the same state through output rows 1/n apart: a rounding
    np.testing.assert_allclose(H[:, 4], H[:, 3] / n, rtol=1e-12)


def test_mesh_torque_is_the_direct_solve():
    # The mesh torque on the driving wheel, k_m·(θ_in − n·θ_out) + c_m·(θ̇_in − n·θ̇_out), against a dense
    # solve of (K − ω²M + iωC) x = f on the same model: all modes kept, a change of coordinates. The grid
    # stays off the modes (the direct solve's condition number is at most 2.2e4 on it): ~5e-12; 1e-8.
    d = _chain(2.0, 3.0, mesh=2e5, mesh_damping=4.0)
    r = fs.modal_analysis(d)
    m = r.model
    ss = state_space(r, ["motor"], ["torque:stage 2"])
    f = np.linspace(1.0, 400.0, 50)
    H = frequency_response(ss, f).H[:, 0, 0]
    K, M, C = (A.toarray() for A in (m.K, m.M, m.C))
    motor = m.T[m.node_dof([m.station("motor").node])[0]].toarray().ravel()
    s = int(m.start_node[4])
    rows = m.T[m.node_dof([s, s + 1])].toarray()
    for fk, h in zip(f, H):
        w = 2 * np.pi * fk
        x = np.linalg.solve(K - w * w * M + 1j * w * C, motor)
        rel = (rows[0] - 3.0 * rows[1]) @ x
        assert h == pytest.approx((2e5 + 1j * w * 4.0) * rel, rel=1e-8)


def test_poles_of_a_geared_model_are_its_damped_modes():
    d = _chain(2.0, 3.0, mesh=2e5)
    d = Drivetrain(d.name, d.components, rayleigh=fs.Rayleigh(alpha=0.5, beta=1e-5))
    r = fs.modal_analysis(d)
    p = state_space(r, ["motor"], ["speed:generator"]).poles()
    p = np.sort_complex(p[p.imag > 1e-9])
    # Both are eigenvalues of the same scaled first-order matrix: eps·ω_max/|λ| ~ 1e-14; 1e-8 is loose.
    np.testing.assert_allclose(p, np.sort_complex(r.damped.eigenvalues[~r.rigid]), rtol=1e-8)


def test_a_flexible_body_past_a_rigid_stage_keeps_its_frame():
    # A Craig–Bampton body whose first interface node is a driven wheel tied by a rigid mesh: with all its
    # fixed-interface modes kept the reduction is exact, so the modes equal the unreduced chain's.
    def chain(reduce):
        return Drivetrain(
            "body past a gear",
            (
                Rigid("motor", 1.0),
                Shaft("in", stiffness=3e4, inertia=0.02, elements=2),
                Gear("stage", ratio=3.0, inertia_in=0.01),
                Shaft("out", stiffness=2e4, inertia=0.05, elements=6, reduce=reduce),
                Rigid("generator", 0.2),
            ),
        )

    full = fs.modal_analysis(chain(None))
    body = fs.modal_analysis(chain(Reduce(modes=5)))
    # Two dense solves of 9 DOFs, eps·λ_max/λ₁ ~ 1e-14: 1e-8 is loose (atol: the rigid modes' 0).
    np.testing.assert_allclose(body.frequencies_hz, full.frequencies_hz, rtol=1e-8, atol=1e-9)
    # Recovered interior angles are in the driven frame: the rigid mode turns them by 1/3 (through the
    # constraint modes: eps·κ(K_ii) ~ 1e-14).
    rigid = body.dof_shapes("θx")[:, 0]
    np.testing.assert_allclose(rigid[body.model.start_node[3] :] / rigid[0], 1 / 3, rtol=1e-10)


@pytest.mark.parametrize("mesh", [None, 2e5])
def test_twist_test_through_a_stage(mesh):
    # Each part reads its own stiffness (its torque over its own twist, in its own frame), the torque it
    # carries is the load torque times load speed over its speed, and clamp to load is the series of all
    # parts reflected into the load's frame: 1/k = Σ (s_load/s_part)² / k_part.
    n1, n2, torque = 2.5, 4.0, 700.0
    d = _chain(n1, n2, mesh)
    t = fs.twist_test(d, torque)
    parts = {p.name: p for p in t.parts}
    expected = {"input shaft": (1e5, 1.0), "middle shaft": (4e4, 1 / n1), "coupling": (3e3, 1 / (n1 * n2))}
    if mesh is not None:
        expected["stage 2"] = (mesh, 1 / n1)
    assert set(parts) == set(expected)  # a rigid mesh does not twist, so it is no part of the test
    s_load = 1 / (n1 * n2)
    # Round-off of the clamped chain's solve (condition number 330 / 1.1e3 with the mesh): ~3e-13; the
    # speed ratios and torques are products of the ratios, a rounding or two.
    for name, (k, s) in expected.items():
        assert parts[name].stiffness == pytest.approx(k, rel=1e-10)
        assert parts[name].speed_ratio == pytest.approx(s, rel=1e-14)
        assert parts[name].torque == pytest.approx(torque * s_load / s, rel=1e-12)
    series = 1 / sum((s_load / s) ** 2 / k for k, s in expected.values())
    assert t.total_stiffness == pytest.approx(series, rel=1e-10)
    # Loaded at the driving end instead, clamped at the far end: the same stiffness per part.
    back = fs.twist_test(d, torque, clamp="generator", load="motor")
    for p in back.parts:
        assert p.stiffness == pytest.approx(expected[p.name][0], rel=1e-10)


def test_twist_refuses_a_clamp_and_load_tied_by_a_rigid_mesh():
    d = _chain(2.0, 3.0)
    with pytest.raises(fs.ModelError, match="turn together"):
        fs.twist_test(d, clamp="middle shaft/stage 2", load="stage 2/coupling")


def test_modes_json_and_table_say_which_frame(capsys):
    assert main(["modes", str(EXAMPLES / "nrel5mw.toml"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    frames = doc["frames"]
    assert frames["stations"]["rotor"] == 1.0
    assert frames["stations"]["generator"] == pytest.approx(97.0, rel=1e-14)  # 1/(1/97): a rounding
    assert frames["components"]["gearbox"] == 1.0  # listed by its driving side
    gear = next(c for c in doc["components"] if c["name"] == "gearbox")
    # 1/97 as stored, through JSON (every digit kept): equal, or a rounding apart
    assert gear["ratio"] == pytest.approx(1 / 97, rel=1e-15) and "mesh_stiffness" not in gear
    assert "gearbox" not in doc["modes"][1]["torque_per_rad"]  # a rigid mesh has no spring of its own
    assert main(["modes", str(EXAMPLES / "nrel5mw.toml")]) == 0
    assert "past 'gearbox' speed × 97" in capsys.readouterr().out


def test_twist_cli_through_a_stage(capsys):
    assert main(["twist", str(EXAMPLES / "nrel5mw.toml"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    (shaft,) = doc["parts"]
    # a 2-DOF static solve (JSON keeps every digit): a few eps
    assert shaft["stiffness"] == pytest.approx(867637000.0, rel=1e-10)
    assert shaft["torque"] == pytest.approx(97 * doc["torque"], rel=1e-12)
    assert doc["total_stiffness"] == pytest.approx(867637000.0 / 97**2, rel=1e-10)


BAD_GEARS = [
    ("ratio = 0.0", "ratio = 0.0: out of range; valid: a finite number >= 0.001 and <= 1000"),
    ("ratio = -2.0", "ratio"),
    ("ratio = nan", "ratio"),
    ("ratio = 1e5", "ratio"),
    ('ratio = "1/0"', "ratio = '1/0': is not a number or a fraction"),
    ('ratio = "fast"', "ratio = 'fast': is not a number or a fraction"),
    (
        "ratio = 2.0\nmesh_damping = 3.0",
        "mesh_damping = 3.0 N·m·s/rad: a rigid mesh has no relative motion to damp",
    ),
    ("ratio = 2.0\nmesh_stiffness = -1.0", "mesh_stiffness"),
    ("ratio = 2.0\ninertia_in = -1.0", "inertia_in"),
    ("ratio = 2.0\nteeth = 31", "teeth"),
    ("inertia_in = 1.0", "ratio: missing key for a gear"),
]


@pytest.mark.parametrize("entry,message", BAD_GEARS, ids=[b[0] for b in BAD_GEARS])
def test_bad_gear_input_names_the_field(entry, message):
    text = (
        '[model]\nname = "m"\n[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 1.0\n'
        f'[[chain]]\nname = "g"\ntype = "gear"\n{entry}\n'
        '[[chain]]\nname = "s"\ntype = "shaft"\nstiffness = 1e4\ninertia = 0.1\n'
    )
    with pytest.raises(fs.ModelError) as info:
        fs.loads_model(text, source="m.toml")
    assert message in str(info.value)
    assert "[[chain]] #2" in str(info.value) or "'g'" in str(info.value)


def test_a_gear_in_a_six_dof_model_is_refused():
    with pytest.raises(fs.ModelError, match="gear stage is a torsion component"):
        Drivetrain("full", (Rigid("m", 1.0), Gear("g", ratio=2.0)), dofs="full")
    with pytest.raises(fs.ModelError, match="gear stage is a torsion component"):
        fs.assemble(_chain(2.0, 3.0), dofs="full")


def _opentorsion(spec: dict) -> np.ndarray:
    out = run_peer("opentorsion_gear.py", spec, what="openTorsion", timeout=120)
    return np.asarray(out["frequencies_hz"])


@pytest.mark.parametrize("mesh", [None, 5e5])
def test_gear_chain_matches_opentorsion(mesh):
    # The same chain in openTorsion: motor disk, a 3-element input shaft, a gear pair (parent radius 1,
    # child radius n: the child turns n times slower, ratio n), a 4-element output shaft, generator disk.
    # openTorsion's consistent shaft mass is I·[[2, 1], [1, 2]], so an element of inertia j takes I = j/6.
    # Both solve small dense symmetric eigenproblems of the same discrete model: agreement to round-off,
    # each eigenvalue to ~eps·λ_max, so f to eps·(f_max/f)²/2 <= 1e-12 relative (f_max/f₁ = 95).
    n, k1, j1, k2, j2 = 3.0, 1e5, 0.12, 2e4, 0.08
    d = Drivetrain(
        "peer",
        (
            Rigid("motor", 10.0),
            Shaft("a", stiffness=k1, inertia=j1, elements=3),
            Gear("g", ratio=n, inertia_in=0.2, inertia_out=0.5, mesh_stiffness=mesh),
            Shaft("b", stiffness=k2, inertia=j2, elements=4),
            Rigid("generator", 4.0),
        ),
    )
    shafts = [[i, i + 1, 3 * k1, j1 / 3 / 6] for i in range(3)] + [
        [4 + i, 5 + i, 4 * k2, j2 / 4 / 6] for i in range(4)
    ]
    spec = {"shafts": shafts, "disks": [[0, 10.0], [8, 4.0]]}
    if mesh is None:
        spec["gears"] = [[3, 0.2, 1.0, None], [4, 0.5, n, 0]]
    else:
        spec["elastic_gears"] = [[3, 0.2, 1.0, None, None], [4, 0.5, n, mesh, 0]]
    peer = _opentorsion(spec)
    ours = fs.modal_analysis(d).frequencies_hz
    assert peer.size == ours.size
    # The rigid-body mode: ours is set to 0; the peer's is the root of a round-off eigenvalue, |λ| up to
    # ~eps·λ_max, so up to √eps·f_max = 1.6e-5 Hz (clipped to 0 when negative; the PRESCOTT kernels give
    # +1.5e-6 Hz - over the 1.2e-6 Hz this test once allowed).
    assert ours[0] == 0.0 and 0.0 <= peer[0] <= np.sqrt(np.finfo(float).eps) * peer.max()
    np.testing.assert_allclose(ours[1:], peer[1:], rtol=1e-9)
