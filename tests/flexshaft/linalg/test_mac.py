"""The one MAC against closed forms: identical, orthogonal, complex-scaled and mass-weighted shapes."""

import numpy as np
import pytest
import scipy.sparse as sp

from flexshaft.linalg.mac import mac

# A MAC of a few O(1) numbers is a dozen roundings of at most eps/2 each, in whatever order the BLAS
# sums (a product, two norms, a quotient): 64 eps bounds it with room for any kernel.
TOL = 64 * np.finfo(float).eps
# Against the definition written out (the same sums in another order and association): the error of
# each side's inner products, relative to the terms' magnitudes, for vectors of 6 random entries.
REF_TOL = 1e-13


def test_a_shape_matches_itself_and_any_multiple_of_it():
    a = np.array([1.0, -0.4, 2.5, 0.3])
    assert mac(a, a) == pytest.approx(1.0, abs=TOL)
    assert mac([1.0, 2.0], [-2.0, -4.0]) == pytest.approx(1.0, abs=TOL)  # a real factor, of either sign
    z = np.array([1.0 + 0.5j, -0.2 + 1.0j, 0.7 - 0.1j])
    factor = 3.0 * np.exp(0.83j)  # a complex factor: the conjugate transpose takes its phase out
    assert mac(z, factor * z) == pytest.approx(1.0, abs=TOL)
    assert mac(factor * z, z) == pytest.approx(1.0, abs=TOL)


def test_orthogonal_shapes_have_mac_zero():
    assert mac([1.0, 0.0], [0.0, 1.0]) == 0.0
    # complex orthogonality is aᴴb = 0, not aᵀb = 0: [1, i] and [1, −i] are orthogonal (aᴴb = 1 − 1)
    # though aᵀb = 2; [i, −1] is i·[1, i], the same shape
    assert mac([1.0, 1.0j], [1.0, -1.0j]) == pytest.approx(0.0, abs=TOL)
    assert mac([1.0, 1.0j], [1.0j, -1.0]) == pytest.approx(1.0, abs=TOL)


def test_a_closed_form_value():
    # a = [1, 0], b = [1, 1]: |aᵀb|² / (|a|²|b|²) = 1 / 2 (the cosine² of 45°)
    assert mac([1.0, 0.0], [1.0, 1.0]) == pytest.approx(0.5, abs=TOL)
    # complex: a = [1, i], b = [1, 0]: |aᴴb|² = 1, aᴴa = 2, bᴴb = 1
    assert mac([1.0, 1.0j], [1.0, 0.0]) == pytest.approx(0.5, abs=TOL)


def test_mass_weighted_by_a_diagonal_matrix_by_hand():
    # M = diag(2, 1, 3), a = [1, 2, 0], b = [1, -1, 1]:
    # aᵀMb = 2·1·1 + 1·2·(−1) + 3·0·1 = 0           -> MAC 0 (M-orthogonal, not orthogonal: aᵀb = −1)
    # c = [1, 1, 1]: aᵀMc = 2 + 2 + 0 = 4, aᵀMa = 2 + 4 = 6, cᵀMc = 6 -> MAC 16/36 = 4/9
    M = np.diag([2.0, 1.0, 3.0])
    a, b, c = np.array([1.0, 2.0, 0.0]), np.array([1.0, -1.0, 1.0]), np.ones(3)
    assert mac(a, b, M) == pytest.approx(0.0, abs=TOL)
    assert mac(a, b) == pytest.approx(1.0 / 15.0, abs=TOL)  # unweighted: (aᵀb)² / (aᵀa·bᵀb) = 1/(5·3)
    assert mac(a, c, M) == pytest.approx(4.0 / 9.0, abs=TOL)
    assert mac(a, c, sp.diags([2.0, 1.0, 3.0])) == pytest.approx(4.0 / 9.0, abs=TOL)  # sparse M alike
    # complex with M: a = [1, i, 0], c = [1, 1, 1]: aᴴMc = 2·1 + 1·(−i)·1 = 2 − i, |.|² = 5;
    # aᴴMa = 2 + 1 = 3, cᴴMc = 6 -> 5/18
    assert mac(np.array([1.0, 1.0j, 0.0]), c, M) == pytest.approx(5.0 / 18.0, abs=TOL)


def test_mode_sets_give_the_matrix_of_every_pair():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((6, 3)) + 1j * rng.standard_normal((6, 3))
    B = rng.standard_normal((6, 4))
    M = np.diag(rng.uniform(0.5, 2.0, 6))
    got = mac(A, B, M)
    assert got.shape == (3, 4)
    for i in range(3):
        for j in range(4):
            a, b = A[:, i], B[:, j]
            # the definition, written out: |aᴴMb|² / ((aᴴMa)(bᴴMb))
            ref = abs(a.conj() @ M @ b) ** 2 / ((a.conj() @ M @ a).real * (b @ M @ b))
            assert got[i, j] == pytest.approx(ref, rel=REF_TOL)
    assert mac(A[:, 0], B).shape == (4,) and mac(A, B[:, 0]).shape == (3,)
    assert np.allclose(mac(A[:, 0], B, M), got[0], rtol=TOL, atol=0)  # one row of the same computation


def test_a_shape_without_norm_resembles_nothing():
    assert mac([0.0, 0.0], [1.0, 2.0]) == 0.0
    # in M's null space: M = diag(1, 0), a = [0, 1]
    assert mac([0.0, 1.0], [1.0, 1.0], np.diag([1.0, 0.0])) == 0.0
