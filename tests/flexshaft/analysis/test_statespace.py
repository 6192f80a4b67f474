"""State space and frequency response against the damped modes and a direct solve of the physical system."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.statespace import frequency_response, state_space
from flexshaft.cli import main
from tests.conftest import EXAMPLES

OUTPUTS = ["speed:generator", "torque:part 3", "angle:motor"]


@pytest.mark.parametrize(
    "setup", ["customer1.toml", "customer2.toml", "without_dut.toml", "customer1_flex.toml"]
)
def test_poles_are_the_damped_modes(setup):
    # All modes kept: A is the first-order system in modal coordinates, so its oscillating poles are the
    # damped eigenvalues of `flexshaft modes` (dense eigen-solves of the same small matrices: 1e-8).
    r = fs.modal_analysis(fs.load_model(EXAMPLES / setup))
    ss = state_space(r, ["motor"], ["speed:motor"])
    p = ss.poles()
    p = np.sort_complex(p[p.imag > 1e-9])
    d = np.sort_complex(r.damped.eigenvalues[~r.rigid])
    np.testing.assert_allclose(p, d, rtol=1e-8)
    # The free line's rigid-body mode is kept exactly: a pole at 0 (nothing drifts).
    assert np.min(np.abs(ss.poles())) < 1e-9


def test_frequency_response_is_the_direct_solve_of_the_physical_system():
    # (K − ω²M + iωC) x = f at 50 frequencies, outputs read off x: all modes kept, the modal form is a
    # change of coordinates, so both agree to round-off of the small dense solves (1e-8).
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    m = r.model
    ss = state_space(r, ["motor"], OUTPUTS)
    f = np.linspace(1.0, 600.0, 50)
    H = frequency_response(ss, f).H
    K, M, C = m.K.toarray(), m.M.toarray(), m.C.toarray()
    st = {s.name: s.node for s in m.stations}
    k3 = m.drivetrain.component("part 3").stiffness
    for i, fk in enumerate(f):
        w = 2 * np.pi * fk
        F = np.zeros(m.n_dof)
        F[st["motor"]] = 1.0
        x = np.linalg.solve(K - w * w * M + 1j * w * C, F)
        y = [
            1j * w * x[st["generator"]],
            k3 * (x[st["part 2/part 3"]] - x[st["part 3/part 4"]]),  # transmitted: θ₁ − θ₂
            x[st["motor"]],
        ]
        np.testing.assert_allclose(H[i, :, 0], y, rtol=1e-8)


def test_a_peaks_half_power_width_gives_back_its_damping():
    # A well-separated, lightly damped peak: (f₂ − f₁)/(2 f) = ξ within 2 %, on a fine frequency grid.
    d = fs.load_model(EXAMPLES / "customer1.toml")
    d = fs.Drivetrain(d.name, d.components, rayleigh=fs.Rayleigh(0.0, 2e-5))
    r = fs.modal_analysis(d)
    ss = state_space(r, ["motor"], ["speed:generator"])
    f2 = r.frequencies_hz[2]
    resp = frequency_response(ss, np.linspace(0.9 * f2, 1.1 * f2, 4001))
    (peak,) = [p for p in resp.peaks() if abs(p["frequency_hz"] / f2 - 1) < 0.01]
    assert peak["damping_ratio"] == pytest.approx(r.damping_ratios[2], rel=0.02)


def test_truncation_and_unknown_signals():
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ss = state_space(r, ["motor"], ["speed:generator"], max_hz=100.0)
    assert list(ss.modes) == [0, 1, 2] and ss.A.shape == (6, 6)
    with pytest.raises(fs.ModelError, match="input = 'rotor': no such signal; valid: 'motor'|no such"):
        state_space(r, ["rotor"], ["speed:generator"])
    with pytest.raises(fs.ModelError, match="no such signal.*torque:part 3"):
        state_space(r, ["motor"], ["torque:part 9"])


def test_python_control_gives_the_same_response():
    control = pytest.importorskip("control", reason="python-control is optional (pip install control)")
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ss = state_space(r, ["motor"], ["speed:generator"])
    f = np.array([5.0, 50.0, 300.0])
    ours = frequency_response(ss, f).H[:, 0, 0]
    theirs = control.frequency_response(ss.to_control(), 2 * np.pi * f).complex.ravel()
    np.testing.assert_allclose(ours, theirs, rtol=1e-8)


def test_cli_statespace_and_frf(tmp_path, capsys):
    out = tmp_path / "ss.npz"
    args = [
        "statespace",
        str(EXAMPLES / "customer1.toml"),
        "--input",
        "motor",
        "--output",
        "speed:generator",
        "--output",
        "torque:part 3",
        "-o",
        str(out),
    ]
    assert main(args) == 0
    capsys.readouterr()
    with np.load(out, allow_pickle=False) as z:
        # Customer 1 has 5 DOFs, so 5 modes (all kept): 10 states; 1 input, 2 outputs.
        assert z["A"].shape == (10, 10) and z["B"].shape == (10, 1) and z["C"].shape == (2, 10)
        meta = json.loads(str(z["metadata"]))
    assert meta["outputs"] == ["speed:generator", "torque:part 3"] and meta["output_units"] == [
        "rad/s",
        "N·m",
    ]
    assert (
        main(
            [
                "frf",
                str(EXAMPLES / "customer1.toml"),
                "--input",
                "motor",
                "--output",
                "speed:generator",
                "--from",
                "1",
                "--to",
                "600",
                "--points",
                "200",
                "--json",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    n = len(doc["frequency_hz"])
    assert n > 200 and len(doc["real"]) == n and doc["units"]["output"] == ["rad/s"]
    # The half-power reading of the FRF is an independent estimate of what the eigen
    # solution gives. Tolerances: the grid is refined to ξf/2 around each resonance, so
    # the peak sample lies within ξf/4 of f_n (and the other modes shift it by far less
    # than ξf); linear interpolation of |H| between samples ξf/2 apart on the resonance
    # flank reads the half-power band within a few per cent, so 10 % on ξ.
    res = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    peaks = doc["peaks"]
    assert len(peaks) == 4
    flexible = ~res.rigid
    for p, fn, xi in zip(
        peaks, res.damped.natural_frequencies_hz[flexible], res.damping_ratios[flexible], strict=True
    ):
        assert abs(p["frequency_hz"] - fn) <= xi * fn
        assert p["damping_ratio"] == pytest.approx(xi, rel=0.10)


def test_bad_frequencies_are_one_clear_error(capsys):
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ss = state_space(r, ["motor"], ["angle:generator"])
    # A free drivetrain answers a static torque with unbounded rotation: 0 Hz is its rigid-body pole.
    with pytest.raises(fs.ModelError, match="infinite.*0 Hz"):
        frequency_response(ss, [0.0, 1.0])
    for bad in ([np.nan], [-1.0], [], [[1.0]], "abc"):
        with pytest.raises(fs.ModelError, match="frequencies"):
            frequency_response(ss, bad)
    with pytest.raises(fs.ModelError, match="to"):
        fs.frequency_grid(ss, 10.0, 5.0, 100)
    with pytest.raises(fs.ModelError, match="points"):
        fs.frequency_grid(ss, 1.0, 5.0, 1)
    base = ["frf", str(EXAMPLES / "customer1.toml"), "--input", "motor", "--output", "angle:generator"]
    assert main(base + ["--input", "generator"]) == 2
    assert "one input" in capsys.readouterr().err
    for extra in (["--to", "inf"], ["--from", "0"], ["--from", "nan"]):
        assert main(base + extra) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Hz" in err


@pytest.mark.parametrize("inertia", ["consistent", "lumped"])
def test_quasi_static_torque_is_the_inertia_share(inertia):
    # Far below the first mode a motor torque T accelerates the free line as one body,
    # α = T / J_total, and a shaft transmits what the inertia behind it needs: the
    # components after it plus half of its own one-element inertia (consistent and lumped
    # element mass both put J/2 on the far node's side), from the model file's inertias.
    # The flexible modes add (f/f₁)² ≈ 2e-5 at 0.05 Hz: rtol 1e-4.
    d = fs.load_model(EXAMPLES / "customer1.toml")
    r = fs.modal_analysis(d, inertia_model=inertia)
    J = {c.name: c.inertia for c in r.model.drivetrain.components}
    total = sum(J.values())
    behind = {
        "part 1": J["part 1"] / 2 + J["part 2"] + J["part 3"] + J["part 4"] + J["generator"],
        "part 3": J["part 3"] / 2 + J["part 4"] + J["generator"],
    }
    ss = state_space(r, ["motor"], ["torque:part 1", "torque:part 3"])
    H = frequency_response(ss, [0.05]).H[0, :, 0]
    np.testing.assert_allclose(H.real, [behind["part 1"] / total, behind["part 3"] / total], rtol=1e-4)


def test_poles_of_a_damped_six_dof_chain_are_its_damped_modes():
    # A 6-DOF chain (Timoshenko shafts, a coupling dashpot, modal damping on a shaft) with the modes
    # `flexshaft modes` computes (16): the damped solver works in the subspace of those modes, and A is
    # the same projected system, so the poles agree to the accuracy of the damped solver's unbalanced
    # first-order pencil (backward error ~1e-16 of a pencil whose norm spans ω² ≈ 1e11: ~1e-9 here;
    # the balanced eigen-solve of A has a backward error of 1e-18): 1e-8 relative.
    from tests.flexshaft.model.test_fullchain import shaft

    d = fs.Drivetrain(
        "six",
        [
            fs.Rigid("motor", 5.0),
            shaft("a", [{"length": 1.0, "od": 0.1}], damping_ratio=0.01),
            fs.Coupling("c", stiffness=2e4, inertia=0.02, damping=3.0),
            shaft("b", [{"length": 0.8, "od": 0.09}]),
            fs.Rigid("gen", 2.0),
        ],
        dofs="full",
    )
    r = fs.modal_analysis(d)
    ss = state_space(r, ["motor"], ["speed:gen", "torque:c"])
    p = ss.poles()
    p = p[p.imag > 1e-9]
    dm = r.damped.eigenvalues[~r.rigid]
    dm = dm[dm.imag > 1e-9]
    assert p.size == dm.size
    # Bending pairs of an axisymmetric shaft are double roots, so sorting cannot pair them: match
    # each pole with its nearest damped eigenvalue, both ways.
    gap = np.abs(p[:, None] - dm[None, :])
    assert np.all(gap.min(axis=1) <= 1e-8 * np.abs(p)) and np.all(gap.min(axis=0) <= 1e-8 * np.abs(dm))


def test_a_spinning_six_dof_line_responds_as_its_gyroscopic_direct_solve():
    # At a fixed speed Ω the gyroscopic forces −Ω·G·q̇ join the damping: the FRF from the modal state
    # space (all modes kept) equals a dense solve of (K − ω²M + iω(C + ΩG)) x = f on the physical matrices
    # at 50 frequencies (1e-8), and the poles are the whirl roots the Campbell diagram draws.
    from flexshaft.analysis.campbell import campbell
    from flexshaft.model.components import Drivetrain, Rigid, Shaft
    from flexshaft.sections import table_from_segments

    def shaft(name):
        t = table_from_segments([{"length": 0.5, "od": 0.05}], name=name)
        return Shaft.from_sections(name, t, fs.STEEL, max_element_length=0.05)

    d = Drivetrain(
        "rotor",
        (shaft("a"), Rigid("disc", 0.12, mass=12.0, diametral_inertia=0.06), shaft("b")),
        dofs="full",
        bearings=(("a start", 1e7), ("b end", 1e7)),
        rayleigh=fs.Rayleigh(beta=2e-6),
    )
    r = fs.modal_analysis(fs.assemble(d), fs.assemble(d).n_dof)
    m = r.model
    rpm = 9000.0
    ss = state_space(r, ["disc"], ["angle:disc", "speed:b end"], speed_rpm=rpm)
    f = np.linspace(5.0, 400.0, 50)
    H = frequency_response(ss, f).H[:, :, 0]
    K, M, C, G = (A.toarray() for A in (m.K, m.M, m.C, m.G))
    omega = rpm * 2 * np.pi / 60
    force = m.T[m.node_dof([m.station("disc").node])[0]].toarray().ravel()
    rows = np.vstack([m.T[m.node_dof([m.station(s).node])[0]].toarray().ravel() for s in ("disc", "b end")])
    for k, fk in enumerate(f):
        w = 2 * np.pi * fk
        x = np.linalg.solve(K - w * w * M + 1j * w * (C + omega * G), force)
        np.testing.assert_allclose(H[k], rows @ x * np.array([1.0, 1j * w]), rtol=1e-8)
    p = ss.poles()
    whirl = campbell(r, (0.0, rpm), (1,), points=2, max_hz=500.0).frequencies_hz[-1]
    for fw in whirl[:6]:
        assert np.min(np.abs(p.imag / (2 * np.pi) - fw)) <= 1e-9 * fw
