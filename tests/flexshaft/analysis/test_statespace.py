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
        "--at",
        "motor",
        "--measure",
        "speed:generator",
        "--measure",
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
                "--at",
                "motor",
                "--measure",
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


def test_frf_files_are_what_their_suffix_says(tmp_path, capsys):
    # -o y.npz is a real npz (frequencies in Hz, the complex response, units in its metadata), the same
    # numbers as the JSON document (both printed from one array: equal to the JSON's 17 digits);
    # --plot writes the type its suffix names, any case.
    base = ["frf", str(EXAMPLES / "customer1.toml"), "--at", "motor"]
    base += ["--measure", "speed:generator", "--measure", "torque:part 3", "--to", "300", "--points", "50"]
    assert main([*base, "-o", str(tmp_path / "y.NPZ"), "--plot", str(tmp_path / "b.Svg")]) == 0
    assert "y.NPZ" in capsys.readouterr().out
    assert main([*base, "-o", str(tmp_path / "y.json"), "--plot", str(tmp_path / "b.pdf")]) == 0
    doc = json.loads((tmp_path / "y.json").read_text())
    with np.load(tmp_path / "y.NPZ", allow_pickle=False) as z:
        f, H, meta = z["frequency_hz"], z["H"], json.loads(str(z["metadata"]))
    assert H.dtype == complex and H.shape == (len(f), 2, 1)
    np.testing.assert_array_equal(f, doc["frequency_hz"])
    np.testing.assert_array_equal(H[:, :, 0].real, doc["real"])
    np.testing.assert_array_equal(H[:, :, 0].imag, doc["imag"])
    assert meta["format"] == "flexshaft-frequency-response" and meta["units"]["frequency"] == "Hz"
    assert meta["outputs"] == ["speed:generator", "torque:part 3"]
    assert meta["units"]["output"] == ["rad/s", "N·m"]
    assert (tmp_path / "b.Svg").read_bytes().lstrip().startswith(b"<?xml")
    assert (tmp_path / "b.pdf").read_bytes().startswith(b"%PDF")


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
    base = ["frf", str(EXAMPLES / "customer1.toml"), "--at", "motor", "--measure", "angle:generator"]
    assert main(base + ["--at", "generator"]) == 2
    assert "one input" in capsys.readouterr().err
    for extra in (["--to", "inf"], ["--from", "0"], ["--from", "nan"]):
        assert main(base + extra) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Hz" in err


def test_frequencies_and_speeds_past_any_drivetrain_are_range_errors(capsys):
    # ω² of 1e300 Hz overflowed (a RuntimeWarning, then an "unexpected" line); 1e308 rpm the
    # gyroscopic block. The ceilings (1e9 Hz, 1e6 rpm) are far above any drivetrain and far below that.
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ss = state_space(r, ["motor"], ["angle:generator"])
    with pytest.raises(fs.ModelError, match=r"frequencies = 1e\+300 Hz: .* <= 1e\+09 Hz"):
        frequency_response(ss, [1.0, 1e300])
    with pytest.raises(fs.ModelError, match=r"^to = 1e\+300 Hz: out of range; valid: .* <= 1e\+09 \(Hz\)"):
        fs.frequency_grid(ss, 0.1, 1e300, 100)
    with pytest.raises(fs.ModelError, match=r"^speed = 1e\+308 rpm: out of range"):
        state_space(r, ["motor"], ["angle:generator"], speed_rpm=1e308)
    with pytest.raises(fs.ModelError, match=r"^max_hz = inf Hz: not finite"):
        state_space(r, ["motor"], ["angle:generator"], max_hz=np.inf)
    resp = frequency_response(ss, [1.0, 1e9])  # the ceiling itself is a frequency like any other
    assert np.all(np.isfinite(resp.H))
    # 1e-300 Hz beside the free line's rigid-body pole: |H| ~ 1/(ω²J) = 1e598, an overflow in the
    # output product (a RuntimeWarning, then "unexpected") - now the frequency is named
    with pytest.raises(fs.ModelError, match=r"^frequencies = 1e-300 Hz: the response there is beyond double"):
        frequency_response(ss, [1e-300, 1.0])
    resp = frequency_response(ss, [1e-100])  # 1e185 rad/(N·m): huge, but a number
    assert np.all(np.isfinite(resp.H))
    base = ["frf", str(EXAMPLES / "customer1.toml"), "--at", "motor", "--measure", "angle:generator"]
    for extra, says in (
        (["--to", "1e308"], "--to = 1e+308 Hz"),
        (["--speed", "1e308"], "--speed = 1e+308 rpm"),
    ):
        assert main(base + extra) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err and "valid" in err


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


# --- The stacked / modal-damping evaluation of the FRF against a dense first-order reference ---------

EPS = np.finfo(float).eps


def _lu_error_bound(Z, x):
    """|Z⁻¹| Pᵀ|L||U| |x|: the first-order forward error of a solve of Z x = b by LU with partial
    pivoting, per unit roundoff (Higham, Accuracy and Stability of Numerical Algorithms, Thm 9.4:
    the computed x solves (Z + ΔZ) x = b with |ΔZ| <= γ₃ₙ Pᵀ|L||U|, so |Δx| <= |Z⁻¹||ΔZ||x|), with
    the factors LAPACK's getrf computes for Z."""
    from scipy.linalg import lu

    P, L, U = lu(Z)  # Z = P L U
    return np.abs(np.linalg.inv(Z)) @ (P @ (np.abs(L) @ (np.abs(U) @ np.abs(x))))


def _dense_reference(ss, f):
    """C (sI − A)⁻¹ B + D by one dense solve of the full 2m × 2m state matrix per frequency, and the
    bound on its difference from the modal evaluation, entry by entry.

    The reference solves Z = sI − A for x; the modal evaluation solves M = Ω² − ω²I + iω·Dm for
    η = x[:m] (by LU, or by division when M is diagonal: LU of a diagonal matrix) and reads
    y = (Cq + iω·Cv) η. Each answer is off by at most γ·|rows| |Z⁻¹|Pᵀ|L||U| |solution| (the LU
    bound, see ``_lu_error_bound``) plus γ·|rows||solution| for the sums that read the outputs;
    the tolerance is the sum of both evaluations' bounds, γ = 4nε with n = 2m: Higham's γ₃ₙ ≈ 3nε
    for real LU and substitution, a third more for complex products (each rounds to √2·2ε).
    Unlike a normwise κ(Z)‖C‖‖x‖ (0.5 % of the peak here: the first-order matrix mixes ω² ≈ 1e7
    with 1) it follows each entry: under 3e-10 of the peak, at a lightly damped resonance.
    """
    n = ss.A.shape[0]
    m = n // 2
    gamma = 4 * n * EPS
    H = np.empty((f.size, ss.C.shape[0], ss.B.shape[1]), dtype=complex)
    tol = np.empty(H.shape)
    for k, fk in enumerate(f):
        s = 2j * np.pi * fk
        Z = s * np.eye(n) - ss.A
        x = np.linalg.solve(Z, ss.B)
        H[k] = ss.C @ x + ss.D
        M = -ss.A[m:, :m] + s * s * np.eye(m) - s * ss.A[m:, m:]
        rows = np.abs(ss.C[:, :m] + s * ss.C[:, m:])
        eta = x[:m]
        tol[k] = gamma * (
            np.abs(ss.C) @ (_lu_error_bound(Z, x) + np.abs(x))
            + rows @ (_lu_error_bound(M, eta) + np.abs(eta))
        )
    return H, tol


def _damped_coupling_line():
    """Customer 1 with a dashpot across the coupling and Rayleigh damping on top of the shafts' own
    modal damping: the modal damping block ΦᵀCΦ is full (the dashpot couples every mode)."""
    from dataclasses import replace

    d = fs.load_model(EXAMPLES / "customer1.toml")
    comps = [replace(c, damping=12.0) if c.name == "part 3" else c for c in d.components]
    return fs.Drivetrain(d.name, comps, rayleigh=fs.Rayleigh(0.05, 2e-6))


def _assert_matches_reference(ss, f, resp):
    H, tol = _dense_reference(ss, f)
    assert resp.H.shape == H.shape
    assert np.all(np.abs(resp.H - H) <= tol)


def test_frf_with_diagonal_modal_damping_needs_no_solve(monkeypatch):
    # Modal damping written diagonal (2ξω per mode, the model's own damping ratios): every mode is
    # its own oscillator, so the response is elementwise - np.linalg.solve must not be called.
    from dataclasses import replace

    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ss = state_space(r, ["motor", "generator"], OUTPUTS)
    m = ss.A.shape[0] // 2
    A = ss.A.copy()
    A[m:, m:] = -np.diag(2 * r.damping_ratios * r.omega)
    ss = replace(ss, A=A)
    f = fs.frequency_grid(ss, 0.5, 1000.0, 300)
    H, tol = _dense_reference(ss, f)

    def no_solve(*args, **kwargs):
        raise AssertionError("a diagonal damping block needs no solve")

    monkeypatch.setattr(np.linalg, "solve", no_solve)
    resp = frequency_response(ss, f)
    assert np.all(np.abs(resp.H - H) <= tol)


def test_frf_with_coupled_modal_damping_is_the_dense_solve():
    # A coupling dashpot plus Rayleigh damping: Dm is full, the stacked solve runs, on a grid
    # refined around each resonance (where the matrices are worst conditioned).
    r = fs.modal_analysis(_damped_coupling_line())
    ss = state_space(r, ["motor", "generator"], OUTPUTS)
    m = ss.A.shape[0] // 2
    Dm = -ss.A[m:, m:]
    assert np.count_nonzero(Dm - np.diag(np.diag(Dm))) > 0  # the coupled case, not the diagonal one
    f = fs.frequency_grid(ss, 0.5, 1000.0, 300)
    _assert_matches_reference(ss, f, frequency_response(ss, f))


@pytest.mark.parametrize("damping", ["coupled", "diagonal"])
def test_frf_across_chunk_boundaries(monkeypatch, damping):
    # A chunk budget of a few frequencies' matrices: 53 frequencies in uneven chunks give the same
    # response (to the reference's tolerance) as one chunk, and each chunk is one batched solve.
    from dataclasses import replace

    import flexshaft.analysis.statespace as statespace

    r = fs.modal_analysis(_damped_coupling_line())
    ss = state_space(r, ["motor", "generator"], OUTPUTS)
    if damping == "diagonal":
        m = ss.A.shape[0] // 2
        A = ss.A.copy()
        A[m:, m:] = np.diag(np.diag(A[m:, m:]))
        ss = replace(ss, A=A)
    f = np.linspace(0.5, 900.0, 53)
    whole = frequency_response(ss, f).H
    sizes = []
    solve = np.linalg.solve

    def counted(a, b):
        sizes.append(a.shape[0] if a.ndim == 3 else 1)
        return solve(a, b)

    monkeypatch.setattr(np.linalg, "solve", counted)
    monkeypatch.setattr(statespace, "FRF_CHUNK_BYTES", 5000)
    chunked = frequency_response(ss, f)
    monkeypatch.undo()
    if damping == "coupled":
        assert len(sizes) > 2 and max(sizes) < f.size and sum(sizes) == f.size and f.size % max(sizes)
    else:
        assert sizes == []
    _assert_matches_reference(ss, f, chunked)
    H, tol = _dense_reference(ss, f)
    assert np.all(np.abs(whole - H) <= tol)


@pytest.mark.parametrize("damping", ["coupled", "diagonal"])
def test_frf_names_the_frequency_on_an_undamped_pole_inside_a_chunk(monkeypatch, damping):
    # Mode 2 loses its damping and its stiffness is set to ω₂ = 2π·f₀ with f₀ = 123.25 Hz, written
    # as the code forms ω² (the same floating-point product): at f₀ its row and column of
    # Ω² − ω²I + iω·Dm are exactly zero. Chunks of 3 frequencies put f₀ mid-chunk in the third; a
    # batched solve only says "singular": the error must name f₀, the first such frequency in the
    # list (0 Hz, the free line's rigid-body pole, comes later), as the loop per frequency did.
    from dataclasses import replace

    import flexshaft.analysis.statespace as statespace

    r = fs.modal_analysis(_damped_coupling_line())
    ss = state_space(r, ["motor"], ["speed:generator"])
    m = ss.A.shape[0] // 2
    A = ss.A.copy()
    if damping == "diagonal":
        A[m:, m:] = np.diag(np.diag(A[m:, m:]))
    f0 = 123.25
    w0 = 2 * np.pi * f0
    A[m + 2, 2] = -(w0 * w0)
    A[m + 2, m:] = 0.0
    A[m:, m + 2] = 0.0
    ss = replace(ss, A=A)
    # 3 frequencies a chunk: 16 bytes per complex entry of each one's matrix (or diagonal), B and η.
    per_frequency = 16 * m * ((m if damping == "coupled" else 1) + 2)
    monkeypatch.setattr(statespace, "FRF_CHUNK_BYTES", 3 * per_frequency)
    f = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, f0, 140.0, 200.0, 0.0]
    with pytest.raises(fs.ModelError, match=r"frequencies = 123\.25 Hz: the response is infinite there"):
        frequency_response(ss, f)
    # Off the pole the same system answers (the other frequencies are fine).
    assert np.all(np.isfinite(frequency_response(ss, [100.0, 150.0]).H))
