"""Chains of rigid inertias and springs against their closed-form frequencies."""

import numpy as np
import pytest

import flexshaft as fs


def test_two_inertia_chain():
    # J1 - k - J2: ω² = k (J1 + J2) / (J1 J2)  (any vibrations text, two-rotor system).
    J1, J2, k = 58.1, 6.67, 5.5e4
    r = fs.modal_analysis(fs.Drivetrain("2", [fs.Rigid("a", J1), fs.Coupling("k", k), fs.Rigid("b", J2)]))
    assert r.frequencies_hz[0] == 0.0 and r.rigid[0]  # rigid-body modes are set to 0, not solved for
    expected = np.sqrt(k * (J1 + J2) / (J1 * J2)) / (2 * np.pi)
    # A 2-DOF eigen-solve with one elastic mode: a few eps; 1e-12 leaves three orders.
    assert r.frequencies_hz[1] == pytest.approx(expected, rel=1e-12)


def test_three_inertia_chain():
    # J1 - k1 - J2 - k2 - J3: ω⁴ − [k1(J1+J2)/(J1J2) + k2(J2+J3)/(J2J3)] ω² + k1k2(J1+J2+J3)/(J1J2J3) = 0.
    J1, J2, J3, k1, k2 = 58.1, 0.75, 6.67, 3.08e5, 1.57e5
    dt = fs.Drivetrain(
        "3",
        [
            fs.Rigid("a", J1),
            fs.Shaft("s1", k1, 0.0),
            fs.Rigid("b", J2),
            fs.Shaft("s2", k2, 0.0),
            fs.Rigid("c", J3),
        ],
    )
    b = k1 * (J1 + J2) / (J1 * J2) + k2 * (J2 + J3) / (J2 * J3)
    c = k1 * k2 * (J1 + J2 + J3) / (J1 * J2 * J3)
    w2 = np.array([(b - np.sqrt(b * b - 4 * c)) / 2, (b + np.sqrt(b * b - 4 * c)) / 2])
    # Round-off on both sides ~eps·λ₂/λ₁ = 37 eps ≈ 8e-15 (the eigen-solve's, and the cancellation in
    # b − √(b² − 4c)); 1e-12 leaves 100x.
    for model in ("consistent", "lumped"):  # massless shafts: the inertia model cannot matter
        r = fs.modal_analysis(dt, inertia_model=model)
        assert r.frequencies_hz[0] == 0.0
        assert r.frequencies_hz[1:] == pytest.approx(np.sqrt(w2) / (2 * np.pi), rel=1e-12)


def test_sub_elements_are_springs_in_series():
    # n sub-elements of stiffness n·k in series are k again: statically condensing
    # the inner nodes of the assembled K leaves k·[[1, -1], [-1, 1]].
    k, n = 1.0e5, 7
    mdl = fs.assemble(fs.Drivetrain("s", [fs.Shaft("s", k, 0.3, elements=n)]))
    K = mdl.K.toarray()
    b, i = [0, n], list(range(1, n))
    cond = K[np.ix_(b, b)] - K[np.ix_(b, i)] @ np.linalg.solve(K[np.ix_(i, i)], K[np.ix_(i, b)])
    # Round-off: the solve's condition number (19) times the cancellation of n·k down to k (7): ~3e-14.
    assert cond == pytest.approx(k * np.array([[1.0, -1.0], [-1.0, 1.0]]), rel=1e-12)


def test_shaft_inertia_sits_at_its_ends_when_lumped():
    # A lumped shaft of inertia j between rigids J1, J2 is the two-rotor system
    # with J1 + j/2 and J2 + j/2.
    J1, J2, j, k = 2.0, 3.0, 0.4, 1.0e5
    dt = fs.Drivetrain(
        "s", [fs.Rigid("a", J1), fs.Shaft("s", k, j), fs.Rigid("b", J2)], inertia_model="lumped"
    )
    a, b = J1 + j / 2, J2 + j / 2
    # 2-DOF solve, one elastic mode: a few eps (1e-12 leaves three orders); the same for the cases below.
    assert fs.modal_analysis(dt).frequencies_hz[1] == pytest.approx(
        np.sqrt(k * (a + b) / (a * b)) / (2 * np.pi), rel=1e-12
    )


def test_coupling_inertia_follows_the_inertia_model_or_sits_in_two_halves():
    # Two inertias on a coupling with inertia j: the free 2-DOF system K = k[[1, −1], [−1, 1]],
    # M = [[J1 + m11, m12], [m12, J2 + m22]] has ω² = k (M11 + M22 + 2 M12) / det M. The study's matrix
    # models spread j like any element (consistent j/3, j/6; lumped j/2, 0: docs/theory/08-test-bench.md);
    # two rigid halves put j/2 on each end whatever the model.
    J1, J2, j, k = 2.0, 3.0, 0.4, 1.0e5

    def f(m11, m12, m22):
        a, b = J1 + m11, J2 + m22
        return np.sqrt(k * (a + b + 2 * m12) / (a * b - m12**2)) / (2 * np.pi)

    cases = [
        ("consistent", "model", f(j / 3, j / 6, j / 3)),
        ("lumped", "model", f(j / 2, 0.0, j / 2)),
        ("consistent", "halves", f(j / 2, 0.0, j / 2)),
        ("lumped", "halves", f(j / 2, 0.0, j / 2)),
    ]
    for model, split, expected in cases:
        c = fs.Coupling("c", k, j, inertia_split=split)
        dt = fs.Drivetrain("c", [fs.Rigid("a", J1), c, fs.Rigid("b", J2)], inertia_model=model)
        assert fs.modal_analysis(dt).frequencies_hz[1] == pytest.approx(expected, rel=1e-12), (model, split)
    with pytest.raises(fs.ModelError, match="inertia_split = 'thirds'"):
        fs.Coupling("c", k, j, inertia_split="thirds")


def test_single_rigid_inertia_has_only_the_rigid_mode():
    r = fs.modal_analysis(fs.Drivetrain("one", [fs.Rigid("m", 5.0)]))
    assert r.count == 1 and r.rigid[0] and r.frequencies_hz[0] == 0.0  # set, not solved for
    assert r.shapes[0, 0] == pytest.approx(1 / np.sqrt(5.0))


@pytest.mark.parametrize("setup", ["customer1", "customer2"])
def test_the_test_benches_are_the_studys_matrix_models(setup):
    # docs/theory/08-test-bench.md, "The study's matrix model": every part, the coupling included, is an
    # element with k·[[1, −1], [−1, 1]] and (consistent) j·[[1/3, 1/6], [1/6, 1/3]]; motor and generator
    # add to their nodes. Assembled here by hand from the model file's numbers and solved densely.
    from scipy.linalg import eigh

    from tests.conftest import EXAMPLES

    d = fs.load_model(EXAMPLES / f"{setup}.toml")
    comps = d.components
    parts = [c for c in comps if c.type != "rigid"]
    n = len(parts) + 1
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for e, c in enumerate(parts):
        K[e : e + 2, e : e + 2] += c.stiffness * np.array([[1, -1], [-1, 1]])
        M[e : e + 2, e : e + 2] += c.inertia * np.array([[1 / 3, 1 / 6], [1 / 6, 1 / 3]])
    M[0, 0] += comps[0].inertia
    M[-1, -1] += comps[-1].inertia
    expected = np.sqrt(np.clip(eigh(K, M, eigvals_only=True), 0, None)) / (2 * np.pi)
    # Dense LAPACK on both sides: round-off of the 5 × 5 problem, eps·λ_max/λ₁ ≈ 5e-13 at most
    # (λ_max/λ₁ ≈ 2300 on both benches); 1e-10 leaves 200x.
    np.testing.assert_allclose(fs.modal_analysis(d).frequencies_hz[1:], expected[1:], rtol=1e-10)
    # Two rigid halves instead move Customer 2's higher modes visibly (its coupling is heavy, 0.58).
    halves = [
        type(c)(c.name, c.stiffness, c.inertia, c.damping, inertia_split="halves")
        if c.type == "coupling"
        else c
        for c in comps
    ]
    other = fs.modal_analysis(fs.Drivetrain(d.name, halves)).frequencies_hz
    assert np.max(np.abs(other[1:] / expected[1:] - 1)) > (0.01 if setup == "customer2" else 1e-6)
