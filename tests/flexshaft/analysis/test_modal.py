"""Properties every modal result must have, whatever the model."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import flexshaft as fs


def _testbench():
    return fs.load_model("examples/customer1.toml")


def test_modes_are_inertia_orthonormal_and_diagonalise_stiffness():
    r = fs.modal_analysis(_testbench())
    mdl = r.model
    V = r.shapes
    # M-orthonormality of a dense 5-DOF solve: ~n·eps times M's condition number after diagonal scaling
    # (2.3; 2e3 unscaled, which the Cholesky-based solve does not see on this graded M): ~1e-15 (4e-16
    # seen); abs 1e-12 on entries of order 1.
    assert V.T @ (mdl.M @ V) == pytest.approx(np.eye(r.count), abs=1e-12)
    assert V.T @ (mdl.K @ V) == pytest.approx(np.diag(r.omega**2), abs=1e-6 * r.omega.max() ** 2)


def test_stiffness_normalisation():
    r = fs.modal_analysis(_testbench())
    mdl = r.model
    V = r.normalized("stiffness")
    el = ~r.rigid
    # K_η = I and J_η = diag(1/ω²) on the elastic modes (REFERENCE.md, modal coordinates).
    Kq = V[:, el].T @ (mdl.K @ V[:, el])
    Mq = V[:, el].T @ (mdl.M @ V[:, el])
    # Vᵀ K V against ω² of the solve: eps·λ_max/λ₁ = 5e-13 at most (λ_max/λ₁ = 2300); Mq's diagonal is
    # 1/ω² to n·eps relative, its off-diagonals eps/(ω_iω_j) ~ 4e-20 absolute.
    assert Kq == pytest.approx(np.eye(el.sum()), abs=1e-10)
    assert Mq == pytest.approx(np.diag(1 / r.omega[el] ** 2), rel=1e-10, abs=1e-18)
    # The rigid mode has no strain energy to normalise: it stays inertia-normalised.
    assert V[:, 0] @ (mdl.M @ V[:, 0]) == pytest.approx(1.0)


def test_max_normalisation_and_station_shapes():
    r = fs.modal_analysis(_testbench())
    V = r.normalized("max")
    assert np.max(np.abs(V), axis=0) == pytest.approx(np.ones(r.count))
    assert np.all(np.max(V, axis=0) == pytest.approx(1.0))
    S = r.station_shapes()
    assert S.shape == (len(r.model.stations), r.count)
    assert S[:, 0] == pytest.approx(np.ones(len(r.model.stations)))  # rigid mode: all turn together


def test_normalisation_name_is_checked():
    r = fs.modal_analysis(_testbench())
    with pytest.raises(
        fs.ModelError, match=r"normalization = 'mass'.*valid: one of 'inertia', 'stiffness', 'max'"
    ):
        r.normalized("mass")


def test_energy_fractions_sum_to_one_and_rigid_mode_has_no_strain():
    r = fs.modal_analysis(_testbench())
    se, ke = r.strain_energy_fractions(), r.kinetic_energy_fractions()
    assert se[0] == pytest.approx(np.zeros(se.shape[1]))
    assert se[1:].sum(axis=1) == pytest.approx(np.ones(r.count - 1))
    assert ke.sum(axis=1) == pytest.approx(np.ones(r.count))
    # Kinetic energy of the rigid mode is shared in proportion to inertia.
    inertias = np.array([c.inertia for c in r.model.drivetrain.components])
    assert ke[0] == pytest.approx(inertias / inertias.sum())
    # Rigid components never store strain energy.
    names = r.model.component_names
    assert se[:, names.index("motor")] == pytest.approx(0.0)


def test_first_testbench_mode_lives_in_the_coupling():
    # The study: the composite coupling (part 3) is the softest element and sets mode 1.
    r = fs.modal_analysis(_testbench())
    assert r.dominant_components()[:2] == [None, "part 3"]


def test_dense_and_lanczos_paths_agree():
    dt = fs.Drivetrain("u", [fs.Rigid("m", 5.0), fs.Shaft("s", 1e6, 2.0, elements=900), fs.Rigid("g", 1.0)])
    a = fs.modal_analysis(dt, 8, method="dense")
    b = fs.modal_analysis(dt, 8, method="lanczos")
    assert "LAPACK" in a.method and "Lanczos" in b.method
    # The dense solve's round-off dominates: eps·λ_max/λ₁/2 = 6e-10 at most on the lowest mode
    # (λ_max/λ₁ = 5.8e6; 3e-11 seen); the Lanczos path's Rayleigh quotients are better. 3e-9.
    assert b.frequencies_hz == pytest.approx(a.frequencies_hz, rel=3e-9)
    # Shapes agree up to sign (1 − MAC is of second order in the vectors' error: ~1e-14).
    mac = (a.shapes.T @ (a.model.M @ b.shapes)) ** 2
    assert np.diag(mac) == pytest.approx(np.ones(8), rel=1e-8)


def test_default_count_all_for_small_ten_for_large():
    small = fs.modal_analysis(_testbench())
    assert small.count == small.model.n_dof
    big = fs.modal_analysis(fs.Drivetrain("b", [fs.Shaft("s", 1e6, 2.0, elements=5000)]), damped=False)
    assert big.count == 10


def test_count_is_validated():
    with pytest.raises(fs.ModelError, match=r"count = 0: out of range; valid: an integer >= 1"):
        fs.modal_analysis(_testbench(), 0)


chains = st.lists(
    st.tuples(
        st.sampled_from(["rigid", "shaft", "coupling"]),
        st.floats(1e3, 1e8),
        st.floats(1e-3, 1e2),
        st.integers(1, 4),
    ),
    min_size=1,
    max_size=8,
)


@settings(max_examples=60, deadline=None)
@given(chains, st.sampled_from(["consistent", "lumped"]))
def test_random_chains_have_symmetric_psd_matrices_with_the_rigid_null_space(spec, model):
    comps = []
    for i, (kind, k, j, n) in enumerate(spec):
        if kind == "rigid":
            comps.append(fs.Rigid(f"c{i}", j))
        elif kind == "shaft":
            comps.append(fs.Shaft(f"c{i}", k, j, elements=n))
        else:
            comps.append(fs.Coupling(f"c{i}", k, j))
    mdl = fs.assemble(fs.Drivetrain("r", comps, inertia_model=model))
    K, M = mdl.K.toarray(), mdl.M.toarray()
    assert np.allclose(K, K.T) and np.allclose(M, M.T)
    # Rigid rotation: no strain energy, and 1ᵀM1 is the total inertia (mass conserved).
    # Row sums (k_a + k_b) − k_a − k_b: one rounding of the largest, ~eps·max|K|; 1e-9 is loose.
    assert np.allclose(K @ np.ones(len(K)), 0.0, atol=1e-9 * np.abs(K).max(initial=1.0))
    assert np.ones(len(M)) @ M @ np.ones(len(M)) == pytest.approx(sum(c.inertia for c in comps))
    assert np.all(np.linalg.eigvalsh(M) > 0)
    kev = np.linalg.eigvalsh(K) / max(np.abs(K).max(initial=1.0), 1.0)
    # The zero eigenvalue is round-off, ~n·eps (< 1e-14); the next one, with stiffnesses spanning 1e5 and
    # at most 32 springs in series, stays above ~1e-8: 1e-12 splits them.
    assert np.all(kev > -1e-12)
    assert np.sum(kev < 1e-12) == 1  # a connected free chain: exactly one rigid mode
    r = fs.modal_analysis(mdl, damped=False)
    assert r.frequencies_hz[0] == 0.0 and r.rigid.sum() == 1
    assert np.all(np.diff(r.frequencies_hz) >= 0)


def test_component_torque_of_a_two_rotor_mode():
    # J1 - k - J2: the elastic mode has θ2/θ1 = −J1/J2 (momentum balance). Scaled to a
    # peak rotation of 1 rad at the lighter rotor, the spring twists by 1 + J2/J1... here
    # J1 > J2, so θ2 = 1, θ1 = −J2/J1 and the torque is k (1 + J2/J1).
    J1, J2, k = 58.1, 6.67, 5.5e4
    r = fs.modal_analysis(fs.Drivetrain("2", [fs.Rigid("a", J1), fs.Coupling("k", k), fs.Rigid("b", J2)]))
    T = r.component_torques()
    assert T[1] == pytest.approx([0.0, k * (1 + J2 / J1), 0.0], rel=1e-12)  # 2-DOF: a few eps
    assert np.all(T[0] == 0.0)  # rigid-body mode: set to 0


def test_case_study_coupling_carries_most_torque_in_mode_one():
    # REFERENCE.md, Customer 2: in mode 1 motor and generator swing against each other
    # and the section at the coupling carries the largest dynamic torque; in mode 2 it
    # carries little compared with the most loaded section of that mode.
    r = fs.modal_analysis(fs.load_model("examples/customer2.toml"))
    T = r.component_torques()[1:]
    c = r.model.component_names.index("part 3")
    share = T[:, c] / T.max(axis=1)
    assert share[0] == pytest.approx(1.0)
    assert share[1] < 0.5


def test_customer2_the_sliding_coupling_carries_mode_1_and_little_of_mode_2():
    # The study's slip explanation (REFERENCE.md, Customer 2's friction coupling): in mode 1 the
    # section of the coupling (part 3, between parts 2 and 4) carries the largest dynamic torque of the
    # line; in mode 2 it carries the least of the flexible parts, a fraction of what part 1 does.
    r = fs.modal_analysis(fs.load_model("examples/customer2.toml"))
    t = r.component_torques()
    names = list(r.model.component_names)
    c3 = names.index("part 3")
    flexible = [names.index(n) for n in ("part 1", "part 2", "part 3", "part 4")]
    assert t[1, c3] == max(t[1, i] for i in flexible)
    assert t[2, c3] == min(t[2, i] for i in flexible)
    assert t[2, c3] < 0.25 * t[2, names.index("part 1")]


def test_torsion_chain_node_shapes_are_the_shapes_themselves():
    # A chain's coordinates are its nodes (T = I): node_shapes is a read-only view, not a copy.
    r = fs.modal_analysis(_testbench())
    assert np.shares_memory(r.node_shapes, r.shapes) and not r.node_shapes.flags.writeable
    theta = r.dof_shapes("θx")
    assert theta.flags.writeable and not np.shares_memory(theta, r.shapes)  # the caller's own copy
    assert np.array_equal(theta, r.shapes)


def test_component_torques_by_element_blocks_match_the_formula():
    # k·(n·θ_right − θ_left) per element at 1 rad peak station rotation, maximum per component,
    # computed here over all elements at once; the result sums blocks of elements.
    from flexshaft.linalg.eigen import ROW_BLOCK

    n = ROW_BLOCK + 123  # more elements than one block
    dt = fs.Drivetrain(
        "u",
        [
            fs.Rigid("m", 5.0),
            fs.Shaft("a", 1e6, 2.0, elements=n // 2),
            fs.Coupling("c", 3e5, 0.1),
            fs.Shaft("b", 2e6, 1.0, elements=n - n // 2),
            fs.Rigid("g", 1.0),
        ],
    )
    r = fs.modal_analysis(dt, 5, damped=False)
    mdl = r.model
    theta = r.dof_shapes("θx")
    V = theta / np.max(np.abs(theta[mdl.station_nodes]), axis=0)
    e = mdl.element_nodes
    t = np.abs(mdl.element_stiffness[:, None] * (mdl.element_ratio[:, None] * V[e + 1] - V[e]))
    ref = np.zeros((len(mdl.component_names), r.count))
    np.maximum.at(ref, mdl.element_component, t)
    ref[:, r.rigid] = 0.0
    # The same products with the scaling applied after the difference of neighbours, which nearly
    # cancel on a fine mesh: the two orders differ by eps·|θ|/|Δθ| ~ n·eps (7e-12 here), relative.
    assert r.component_torques() == pytest.approx(ref.T, rel=1e-10, abs=0.0)


def test_checking_the_modes_makes_no_full_length_copy_of_them():
    # The residual check works over row blocks: its temporaries are blocks, not (n, m) arrays.
    import tracemalloc

    from flexshaft.analysis.modal import _check_modes
    from flexshaft.linalg.eigen import ROW_BLOCK

    r = fs.modal_analysis(fs.Drivetrain("u", [fs.Shaft("s", 1e6, 2.0, elements=200_000)]), 10, damped=False)
    lam = r.omega**2
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        _check_modes(r.model, lam, r.shapes)
        peak = tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()
    assert peak <= 6 * ROW_BLOCK * r.count * 8 + 2 * r.model.n_dof * 8  # a few blocks, a vector of ones
