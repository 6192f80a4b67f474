"""Chains of rigid inertias and springs against their closed-form frequencies."""

import numpy as np
import pytest

import flexshaft as fs


def test_two_inertia_chain():
    # J1 - k - J2: ω² = k (J1 + J2) / (J1 J2)  (any vibrations text, two-rotor system).
    J1, J2, k = 58.1, 6.67, 5.5e4
    r = fs.modal_analysis(fs.Drivetrain("2", [fs.Rigid("a", J1), fs.Coupling("k", k), fs.Rigid("b", J2)]))
    assert r.frequencies_hz[0] == 0.0 and r.rigid[0]
    expected = np.sqrt(k * (J1 + J2) / (J1 * J2)) / (2 * np.pi)
    assert r.frequencies_hz[1] == pytest.approx(expected, rel=1e-12)


def test_three_inertia_chain():
    # J1 - k1 - J2 - k2 - J3: ω⁴ − [k1(J1+J2)/(J1J2) + k2(J2+J3)/(J2J3)] ω² + k1k2(J1+J2+J3)/(J1J2J3) = 0.
    J1, J2, J3, k1, k2 = 58.1, 0.75, 6.67, 3.08e5, 1.57e5
    dt = fs.Drivetrain("3", [fs.Rigid("a", J1), fs.Shaft("s1", k1, 0.0), fs.Rigid("b", J2),
                             fs.Shaft("s2", k2, 0.0), fs.Rigid("c", J3)])
    b = k1 * (J1 + J2) / (J1 * J2) + k2 * (J2 + J3) / (J2 * J3)
    c = k1 * k2 * (J1 + J2 + J3) / (J1 * J2 * J3)
    w2 = np.array([(b - np.sqrt(b * b - 4 * c)) / 2, (b + np.sqrt(b * b - 4 * c)) / 2])
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
    assert cond == pytest.approx(k * np.array([[1.0, -1.0], [-1.0, 1.0]]), rel=1e-12)


def test_shaft_inertia_sits_at_its_ends_when_lumped():
    # A lumped shaft of inertia j between rigids J1, J2 is the two-rotor system
    # with J1 + j/2 and J2 + j/2.
    J1, J2, j, k = 2.0, 3.0, 0.4, 1.0e5
    dt = fs.Drivetrain("s", [fs.Rigid("a", J1), fs.Shaft("s", k, j), fs.Rigid("b", J2)],
                       inertia_model="lumped")
    a, b = J1 + j / 2, J2 + j / 2
    assert fs.modal_analysis(dt).frequencies_hz[1] == pytest.approx(
        np.sqrt(k * (a + b) / (a * b)) / (2 * np.pi), rel=1e-12)


def test_coupling_inertia_is_split_in_halves_whatever_the_inertia_model():
    J1, J2, j, k = 2.0, 3.0, 0.4, 1.0e5
    a, b = J1 + j / 2, J2 + j / 2
    expected = np.sqrt(k * (a + b) / (a * b)) / (2 * np.pi)
    for model in ("consistent", "lumped"):
        dt = fs.Drivetrain("c", [fs.Rigid("a", J1), fs.Coupling("c", k, j), fs.Rigid("b", J2)],
                           inertia_model=model)
        assert fs.modal_analysis(dt).frequencies_hz[1] == pytest.approx(expected, rel=1e-12)


def test_single_rigid_inertia_has_only_the_rigid_mode():
    r = fs.modal_analysis(fs.Drivetrain("one", [fs.Rigid("m", 5.0)]))
    assert r.count == 1 and r.rigid[0] and r.frequencies_hz[0] == 0.0
    assert r.shapes[0, 0] == pytest.approx(1 / np.sqrt(5.0))
