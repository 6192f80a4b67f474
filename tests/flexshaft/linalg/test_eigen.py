"""The eigensolver's passes over the mode shapes: exact rigid modes, no full-length temporaries."""

import tracemalloc

import numpy as np
import pytest
import scipy.sparse as sp

import flexshaft as fs
from flexshaft.linalg import eigen


def _chain(n, **kw):
    return fs.assemble(
        fs.Drivetrain(
            "u", [fs.Rigid("m", 5.0), fs.Shaft("s", 1e6, 2.0, elements=n), fs.Rigid("g", 1.0)], **kw
        )
    )


def test_row_blocks_read_the_matrix_in_place_and_sum_like_one_product():
    m = _chain(1000)
    V = np.random.default_rng(3).standard_normal((m.n_dof, 4))
    rows = slice(100, 357)
    block = eigen.row_block(m.K, rows)
    assert abs(block - m.K[rows]).max() == 0.0
    assert np.shares_memory(block.data, m.K.data) and np.shares_memory(block.indices, m.K.indices)
    qk, qm = eigen.column_quadratics(m.K, V, m.M, block=97)
    # The same products summed block by block: a few ulps of the terms' size.
    ref_k = np.einsum("ij,ij->j", V, m.K @ V)
    size_k = np.einsum("ij,ij->j", np.abs(V), abs(m.K) @ np.abs(V))
    assert qk == pytest.approx(ref_k, abs=1e-13 * size_k.max())
    assert qm == pytest.approx(np.einsum("ij,ij->j", V, m.M @ V), rel=1e-13)  # M > 0: no cancellation
    assert [(s.start, s.stop) for s in eigen.row_blocks(10, 4)] == [(0, 4), (4, 8), (8, 10)]


@pytest.mark.parametrize("method", ["dense", "lanczos"])
def test_modes_are_m_orthonormal_and_the_rigid_mode_exact(method):
    m = _chain(700)
    sol = eigen.lowest_modes(m.K, m.M, 8, rigid_basis=m.rigid_basis, method=method, bandwidth=1)
    V = sol.vectors
    assert V.flags.c_contiguous and V.shape == (m.n_dof, 8)
    # ΦᵀMΦ = I to round-off (M-normalised in the same arithmetic: ~n·eps).
    assert V.T @ (m.M @ V) == pytest.approx(np.eye(8), abs=1e-12)
    # The rigid mode is the exact spin (one value on every node, the same product each: equal to the
    # bit, 4 ulps allowed), at exactly 0.
    assert sol.rigid[0] and sol.eigenvalues[0] == 0.0
    assert np.ptp(V[:, 0]) <= 4 * np.finfo(float).eps * abs(V[0, 0])
    # The elastic eigenvalues are their vectors' Rayleigh quotients (Lanczos) or LAPACK's. vᵀKv of a
    # smooth mode cancels in K·v: any two ways of summing it differ by ~eps·λ_max/λ (~1e-11 here).
    rq = np.einsum("ij,ij->j", V, m.K @ V)
    assert sol.eigenvalues[1:] == pytest.approx(rq[1:], rel=1e-10)


def test_dense_lanczos_and_rigid_only_paths_agree():
    m = _chain(700)
    a = eigen.lowest_modes(m.K, m.M, 6, rigid_basis=m.rigid_basis, method="dense")
    b = eigen.lowest_modes(m.K, m.M, 6, rigid_basis=m.rigid_basis, method="lanczos")
    # Two solvers of one well-separated problem: 1e-10 of λ (Lanczos refines by Rayleigh quotients).
    assert b.eigenvalues == pytest.approx(a.eigenvalues, rel=1e-10, abs=0.0)
    r = eigen.lowest_modes(m.K, m.M, 1, rigid_basis=m.rigid_basis)
    assert r.method == "rigid only" and r.eigenvalues[0] == 0.0
    # The same M-normalised spin in all three (to round-off of one normalisation).
    assert r.vectors[:, 0] == pytest.approx(a.vectors[:, 0], rel=1e-14)
    assert r.vectors[:, 0] == pytest.approx(b.vectors[:, 0], rel=1e-14)


def test_cleaning_the_ritz_vectors_makes_no_full_length_copy_of_them():
    # The result, M·R and K·R are the only full-length arrays made: not (n, m) products of K or M.
    m = _chain(100_000)
    n, cols = m.n_dof, 10
    V = np.random.default_rng(5).standard_normal((n, cols))
    R = m.rigid_basis
    gram = R.T @ (m.M @ R)
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        out, lam = eigen._elastic_shapes(V, np.arange(1, cols), R, gram, m.M, m.K)
        peak = tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()
    # Result + M·R and K·R + a few row blocks (2¹⁵ rows × 10 modes × 8 B = 2.6 MB each).
    assert peak <= out.nbytes + 2 * R.nbytes + 4 * eigen.ROW_BLOCK * cols * 8
    assert out.shape == (n, cols) and lam.shape == (cols - 1,)


def test_a_band_matrix_factor_reads_only_the_diagonals():
    # K − σM in banded storage straight from the diagonals equals the dense shifted matrix's band.
    K = sp.diags([[-1.0] * 5, [2.0] * 6, [-1.0] * 5], [-1, 0, 1], format="csr")
    M = sp.diags([[0.5] * 5, [2.0] * 6, [0.5] * 5], [-1, 0, 1], format="csr")
    ab = eigen._shifted_band(K, M, -0.3, 2)
    A = (K + 0.3 * M).toarray()
    for i in range(3):
        assert ab[i, : 6 - i] == pytest.approx(np.diag(A, -i), rel=1e-15)  # one multiply-add: 1 ulp
        assert np.all(ab[i, 6 - i :] == 0.0)
