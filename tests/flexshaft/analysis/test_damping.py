"""Damped modes against the damping that was put in."""

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.damped import DAMPED_FULL_MAX_DOF, damped_modes
from flexshaft.linalg.eigen import lowest_modes


def _chain(n=3):
    return fs.Drivetrain(
        "c",
        [
            fs.Rigid("motor", 58.1),
            fs.Shaft("p1", 3.08e5, 0.44, elements=n),
            fs.Shaft("p2", 1.57e5, 0.75, elements=n),
            fs.Coupling("p3", 5.5e4, 0.06),
            fs.Rigid("gen", 6.67),
        ],
    )


def test_damping_set_per_mode_is_recovered_from_the_complex_eigenvalues():
    # C = M Φ diag(2 ξ_i ω_i) Φᵀ M is diagonal in the modes, so each complex pair is
    # exactly λ = −ξω ± iω√(1−ξ²): ω = |λ|, ξ = −Re λ/|λ| (REFERENCE.md, damping).
    mdl = fs.assemble(_chain())
    sol = lowest_modes(mdl.K, mdl.M, mdl.n_dof, rigid_basis=np.ones((mdl.n_dof, 1)))
    n_el = mdl.n_dof - 1
    xi = np.linspace(0.002, 0.3, n_el)
    C = fs.modal_damping_matrix(mdl.K, mdl.M, xi)
    dm = damped_modes(mdl.K, mdl.M, C, sol.eigenvalues, sol.vectors, sol.rigid)
    # Round-off of the first-order solve (its matrix's norm is ω_max = 88 ω₁): λ to ~eps·ω_max, so ω to
    # eps·ω_max/ω ≈ 2e-14 and ξ to that over ξ, 1e-11 of the smallest ratio (0.002). 1e-8 and 1e-9
    # leave 1e3-1e5; the MAC's error is of second order in the vectors'.
    assert dm.damping_ratios[1:] == pytest.approx(xi, rel=1e-8)
    assert dm.natural_frequencies_hz[1:] == pytest.approx(
        np.sqrt(sol.eigenvalues[1:]) / (2 * np.pi), rel=1e-9
    )
    assert dm.damped_frequencies_hz[1:] == pytest.approx(
        np.sqrt(sol.eigenvalues[1:] * (1 - xi**2)) / (2 * np.pi), rel=1e-9
    )
    assert dm.damping_ratios[0] == 0.0 and dm.natural_frequencies_hz[0] == 0.0  # rigid: set, not solved
    assert dm.mac[1:] == pytest.approx(np.ones(n_el), rel=1e-9)


def test_modal_damping_leaves_the_rigid_mode_undamped():
    mdl = fs.assemble(_chain())
    C = fs.modal_damping_matrix(mdl.K, mdl.M, 0.05)
    # The elastic modes are M-orthogonal to the rigid one to round-off: C·1 ~ n·eps·max|C|; 1e-9 is loose.
    assert C @ np.ones(mdl.n_dof) == pytest.approx(np.zeros(mdl.n_dof), abs=1e-9 * np.abs(C).max())


@pytest.mark.parametrize("n_per_shaft", [3, DAMPED_FULL_MAX_DOF])
def test_rayleigh_damping_gives_alpha_over_2w_plus_beta_w_over_2(n_per_shaft):
    # ξ_i = α/(2ω_i) + βω_i/2 at every mode (REFERENCE.md, Rayleigh). The large case
    # goes through the modal-subspace path, exact here since C is diagonal in the modes.
    alpha, beta = 0.8, 2.0e-5
    dt = _chain(n_per_shaft)
    dt = fs.Drivetrain(dt.name, dt.components, rayleigh=fs.Rayleigh(alpha, beta))
    r = fs.modal_analysis(dt, min(12, fs.assemble(dt).n_dof))  # the small chain has 8 DOFs: all of them
    w = r.omega[1:]
    expected = alpha / (2 * w) + beta * w / 2
    # Round-off ~eps·(ω_max/ω)/ξ with the first-order matrix's norm ω_max: 3e-12 on mode 1 of the small
    # chain; the subspace path's basis stops at the 12th mode, less still. 1e-7 and 1e-9 are loose.
    assert r.damped.damping_ratios[1:] == pytest.approx(expected, rel=1e-7)
    assert r.damped.natural_frequencies_hz[1:] == pytest.approx(r.frequencies_hz[1:], rel=1e-9)
    assert ("subspace" in r.damped.method) == (r.model.n_dof > DAMPED_FULL_MAX_DOF)


def test_rayleigh_coefficients_hit_their_two_targets():
    alpha, beta = fs.rayleigh_coefficients(10.0, 0.0053, 90.0, 0.0053)
    # A 2 × 2 solve of condition ~(90/10)² and its evaluation: ~100 eps at most
    assert fs.rayleigh_ratio(alpha, beta, [10.0, 90.0]) == pytest.approx([0.0053, 0.0053], rel=1e-12)
    with pytest.raises(fs.ModelError, match=r"f2_hz = 10.0 Hz: the two frequencies must differ"):
        fs.rayleigh_coefficients(10.0, 0.01, 10.0, 0.02)


@pytest.mark.parametrize(
    "args, says",
    [
        # ω² of 1e300 Hz raised OverflowError in Python floats; a ratio of 1 or more is no target
        ((1e200, 0.01, 1e300, 0.02), r"^f1_hz = 1e\+200 Hz: out of range; valid: .* <= 1e\+09 \(Hz\)"),
        ((10.0, 0.01, 90.0, 1e308), r"^ratio2 = 1e\+308: out of range; valid: .* < 1$"),
    ],
)
def test_rayleigh_targets_past_floating_point_are_range_errors(args, says):
    with pytest.raises(fs.ModelError, match=says):
        fs.rayleigh_coefficients(*args)


def test_rayleigh_coefficients_past_any_damping_are_range_errors():
    # α = 1e300 and β = 1e300 overflowed the damped solve and the response (RuntimeWarnings first).
    with pytest.raises(fs.ModelError, match=r"^rayleigh.alpha = 1e\+300 1/s: out of range; .* <= 1e\+06"):
        fs.Rayleigh(alpha=1e300)
    with pytest.raises(fs.ModelError, match=r"^rayleigh.beta = 2.0 s: out of range; .* <= 1 \(s\)"):
        fs.Rayleigh(beta=2.0)
    assert fs.Rayleigh(alpha=1e6, beta=1.0).beta == 1.0  # the limits themselves are accepted


def test_discrete_damper_between_two_rotors():
    # J1 - (k, c) - J2: relative coordinate with J = J1J2/(J1+J2), so
    # ω² = k/J and ξ = c / (2 √(k J)).
    J1, J2, k, c = 2.0, 3.0, 1.0e5, 40.0
    Jr = J1 * J2 / (J1 + J2)
    dt = fs.Drivetrain("d", [fs.Rigid("a", J1), fs.Coupling("k", k, damping=c), fs.Rigid("b", J2)])
    r = fs.modal_analysis(dt)
    # One elastic mode: the first-order matrix's norm is ω itself, so a few eps (ξ = 0.058: /ξ, ~1e-14)
    assert r.damped.damping_ratios[1] == pytest.approx(c / (2 * np.sqrt(k * Jr)), rel=1e-12)
    assert r.damped.natural_frequencies_hz[1] == pytest.approx(np.sqrt(k / Jr) / (2 * np.pi), rel=1e-12)


def test_shaft_damping_ratio_is_set_on_the_shafts_own_free_free_mode():
    # One consistent element has a single elastic free-free mode with ω² = 12k/j;
    # damping that mode by ξ makes C = (2ξ/ω)·K_e, so a free shaft shows exactly ξ.
    k, j, xi = 3.0e5, 0.44, 0.0053
    r = fs.modal_analysis(fs.Drivetrain("s", [fs.Shaft("s", k, j, damping_ratio=xi)]))
    # One elastic mode: a few eps on ω, over ξ = 0.0053 on ξ (~1e-13); C's entries a few eps.
    assert r.frequencies_hz[1] == pytest.approx(np.sqrt(12 * k / j) / (2 * np.pi), rel=1e-12)
    assert r.damped.damping_ratios[1] == pytest.approx(xi, rel=1e-9)
    C = r.model.C.toarray()
    assert C == pytest.approx(2 * xi / np.sqrt(12 * k / j) * k * np.array([[1, -1], [-1, 1]]), rel=1e-9)


def test_free_shaft_with_many_elements_carries_its_ratio_on_every_mode():
    r = fs.modal_analysis(fs.Drivetrain("s", [fs.Shaft("s", 3e5, 0.44, elements=20, damping_ratio=0.0053)]))
    # Round-off eps·(ω_max/ω)/ξ <= 1e-12 (ω_max/ω₁ = 22): 1e-7 is loose
    assert r.damped.damping_ratios[1:] == pytest.approx(np.full(20, 0.0053), rel=1e-7)


def test_system_modes_see_part_damping_through_strain_energy():
    # REFERENCE.md: damping on the parts reaches a system mode only through the share of
    # that mode's strain energy the damped parts carry. A one-element part damped by ξ on
    # its free-free mode ω_p = √(12k/j) has C_p = (2ξ/ω_p)·K_p, so to first order in the
    # damping (modal perturbation, ξ_i ≈ φᵢᵀCφᵢ / 2ω_i for inertia-normalised φᵢ)
    #   ξ_i ≈ Σ_p ξ · (ω_i/ω_p) · (k_p Δθ_p² / ω_i²).
    # The error is second order in ξ: 1e-3 relative is ample.
    dt = fs.load_model("examples/customer1.toml")
    r = fs.modal_analysis(dt)
    mdl = r.model
    expected = np.zeros(r.count)
    for ci, comp in enumerate(dt.components):
        if getattr(comp, "damping_ratio", 0.0) > 0:
            s, e = mdl.start_node[ci], mdl.end_node[ci]
            w_p = np.sqrt(12 * comp.stiffness / comp.inertia)
            twist = r.shapes[e] - r.shapes[s]
            expected += comp.damping_ratio * comp.stiffness * twist**2 / (w_p * np.where(r.rigid, 1, r.omega))
    assert r.damped.damping_ratios[1:] == pytest.approx(expected[1:], rel=1e-3)
    # Mode 1 lives in the undamped coupling: far less than the parts' 0.53 %, as in the study.
    assert r.damped.damping_ratios[1] < 0.1 * 0.0053


def test_overdamped_mode_is_reported_with_ratio_above_one():
    J1, J2, k = 2.0, 3.0, 1.0e3
    Jr = J1 * J2 / (J1 + J2)
    c = 3.0 * 2 * np.sqrt(k * Jr)  # ξ = 3
    r = fs.modal_analysis(
        fs.Drivetrain("o", [fs.Rigid("a", J1), fs.Coupling("k", k, damping=c), fs.Rigid("b", J2)])
    )
    # Two real roots of a 2-DOF model, ω = √(λa·λb): a few eps; 1e-9 is loose
    assert r.damped.damping_ratios[1] == pytest.approx(3.0, rel=1e-9)
    assert r.damped.damped_frequencies_hz[1] == 0.0
    assert r.damped.natural_frequencies_hz[1] == pytest.approx(np.sqrt(k / Jr) / (2 * np.pi), rel=1e-9)


def test_rayleigh_alpha_leaves_the_rigid_body_mode_undamped():
    # Rayleigh damps deformation only: its αM, taken literally, would give the rigid spin M r̈ + αM ṙ = 0
    # a real root −α (a drag to ground); on the elastic modes only, the rigid root stays at 0 and the
    # elastic modes keep ξ = α/(2ω) + βω/2.
    alpha, beta = 0.5, 1e-5
    dt = _chain()
    r = fs.modal_analysis(fs.Drivetrain(dt.name, dt.components, rayleigh=fs.Rayleigh(alpha, beta)))
    # rᵀ(αM + βK)r − α = α·(rᵀMr − 1) (n·eps) + β·(K·r's round-off, ~1e-16 absolute): below the
    # solver's round-off threshold (1e-12·ω_max), so the root is set to 0
    assert r.damped.eigenvalues[0] == 0.0
    assert r.damped.decay_rates[0] == 0.0
    w = r.omega[1:]
    # eps·(ω_max/ω)/ξ <= 5e-12 (as above): 1e-7 is loose
    assert r.damped.damping_ratios[1:] == pytest.approx(alpha / (2 * w) + beta * w / 2, rel=1e-7)
    plain = fs.modal_analysis(fs.load_model("examples/customer1.toml"))
    assert plain.damped.eigenvalues[0] == 0.0  # below its round-off threshold the rigid root is set to 0


@pytest.mark.parametrize("setup", ["customer1", "customer2"])
def test_damping_contributions_add_up_to_each_modes_ratio(setup):
    # First order in the damping (ξ ≈ φᵀCφ/2ω): with the parts' 0.53 % the contributions add up to the
    # damped ratio within 5 % (measured 1e-4), and only the damped parts contribute (the coupling and
    # the rigid inertias carry no damping).
    r = fs.modal_analysis(fs.load_model(f"examples/{setup}.toml"))
    d = r.damping_contributions()
    el = ~r.rigid
    np.testing.assert_allclose(d[el].sum(axis=1), r.damping_ratios[el], rtol=0.05)
    names = r.model.component_names
    for ci, name in enumerate(names):
        if name in ("motor", "generator", "part 3"):
            assert np.all(d[:, ci] == 0.0)  # they own no damping entry: nothing is summed
    # The coupling mode (mode 1) gets almost none: its strain energy lives in the undamped coupling.
    assert d[1].sum() < 0.1 * 0.0053


def test_the_damped_eigen_solver_gives_the_closed_form_roots_of_each_modal_oscillator():
    # Modal coordinates with diagonal damping D = diag(2ξω) are independent oscillators
    # η̈ + 2ξω η̇ + ω² η = 0: roots −ξω ± iω√(1 − ξ²), and for ξ > 1 the two real roots −ω(ξ ∓ √(ξ² − 1));
    # a rigid-body coordinate (ω = 0) with damping c has the roots 0 and −c. The balanced matrix's norm is
    # ω_max = 400: round-off ~eps·400, 1e-12 relative to the smallest root (2) is loose.
    from flexshaft.linalg.firstorder import damped_eigen

    w = np.array([0.0, 10.0, 120.0, 400.0])
    xi = np.array([0.0, 0.05, 0.3, 2.0])
    D = np.diag(2 * xi * w)
    D[0, 0] = 1.5  # the rigid coordinate's damping, 1/s
    lam = np.sort_complex(damped_eigen(omega=w, damping=D))
    s = np.sqrt(1 - xi[1:3] ** 2)
    over = np.sqrt(xi[3] ** 2 - 1)
    ref = np.sort_complex(
        np.concatenate(
            [
                [0.0, -1.5],
                -xi[1:3] * w[1:3] + 1j * w[1:3] * s,
                -xi[1:3] * w[1:3] - 1j * w[1:3] * s,
                [-w[3] * (xi[3] - over), -w[3] * (xi[3] + over)],
            ]
        ).astype(complex)
    )
    np.testing.assert_allclose(lam, ref, rtol=0, atol=1e-12 * 2.0)
    # the same system as a modal state space [[0, I], [−Ω², −D]]: found modal, solved balanced - the
    # same matrix, so the same numbers to the last bit
    A = np.block([[np.zeros((4, 4)), np.eye(4)], [-np.diag(w**2), -D]])
    assert np.array_equal(np.sort_complex(damped_eigen(A)), lam)
    # vectors: A z = λ z of the balanced matrix, whose velocity half is the oscillator's coordinate
    lam_v, Z = damped_eigen(omega=w, damping=D, vectors=True)
    B = np.block([[np.zeros((4, 4)), np.diag(w)], [-np.diag(w), -D]])
    np.testing.assert_allclose(B @ Z, Z * lam_v[None, :], rtol=0, atol=1e-12 * 400)
    with pytest.raises(np.linalg.LinAlgError, match="overflows"):
        damped_eigen(omega=w, damping=np.full((4, 4), np.inf))
