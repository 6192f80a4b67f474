"""Torsion element matrices against their textbook definitions."""

import numpy as np
import pytest

from flexshaft.elements import torsion_consistent_inertia, torsion_lumped_inertia, torsion_stiffness


def test_stiffness_is_k_times_difference_operator():
    # k·[[1,-1],[-1,1]] (docs/theory/08-test-bench.md, "The study's matrix model").
    K = torsion_stiffness(2.5e5)
    assert np.array_equal(K, 2.5e5 * np.array([[1.0, -1.0], [-1.0, 1.0]]))
    # A rigid rotation stores no strain energy: k·1 − k·1 is exactly 0 in any summation order.
    assert np.array_equal(K @ np.ones(2), np.zeros(2))


@pytest.mark.parametrize("builder", [torsion_consistent_inertia, torsion_lumped_inertia])
def test_inertia_matrices_carry_the_element_inertia(builder):
    # A rigid rotation of unit speed has kinetic energy j/2: 1ᵀ M 1 = j.
    j = 0.37
    M = builder(j)
    # Four entries rounded once each and three additions: at most ~2 eps·j off (atol=0: the default
    # 1e-8 would swamp the relative tolerance on j = 0.37).
    assert np.isclose(np.ones(2) @ M @ np.ones(2), j, rtol=1e-15, atol=0)
    assert np.array_equal(M, M.T)  # one pattern entry times j, placed twice
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_single_free_free_element_frequency():
    # One element, free-free: φ = [1, -1] gives φᵀKφ = 4k and φᵀMφ = j/3 (consistent)
    # or j (lumped), so ω² = 12 k/j and 4 k/j.
    k, j = 3.0e5, 0.6
    for builder, factor in ((torsion_consistent_inertia, 12.0), (torsion_lumped_inertia, 4.0)):
        lam = np.linalg.eigvals(np.linalg.solve(builder(j), torsion_stiffness(k)))
        # A 2 × 2 solve and eigen-solve, condition ~3: a few eps; 1e-12 leaves three orders.
        assert np.isclose(np.max(lam.real), factor * k / j, rtol=1e-12, atol=0)


def test_vectorised_shapes():
    k = np.array([1.0, 2.0, 3.0])
    assert torsion_stiffness(k).shape == (3, 2, 2)
    # The same products, element by element: identical.
    assert np.array_equal(torsion_consistent_inertia(k)[2], torsion_consistent_inertia(3.0))
