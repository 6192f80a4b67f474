"""LOBPCG with the multigrid preconditioner against shift-invert Lanczos with an exact factor.

Reference: the same discrete eigenproblem solved by shift-invert Lanczos on a sparse LU of K − σM
(``lowest_modes(method="lanczos")``, exact to round-off). The tolerances are the textbook bounds for
an approximate eigenpair (θ, v), v M-normalised, with residual r = Kv − θMv measured in the M⁻¹ norm
(Parlett, The Symmetric Eigenvalue Problem, §10.5 and §11.7, in the M-inner product):

- Kato-Temple: if (a, b) holds θ and only the eigenvalue λ, then θ − ‖r‖²/(b − θ) <= λ <= θ + ‖r‖²/(θ − a);
- Davis-Kahan: sin∠(v, u) <= ‖r‖/δ, δ the distance from θ to the rest of the spectrum.

a and b are the reference's neighbouring eigenvalues. A priori, the stopping criterion
‖r‖₂ <= tol·θ·‖Mv‖₂ gives ‖r‖_{M⁻¹} <= tol·θ·√κ(M), so |θ − λ|/λ <= tol²·κ(M)·θ/δ: with tol = 1e-6,
κ(M) of quadratic tetrahedra of O(100) and modes 5-30 % apart, ~1e-9 at worst - the a posteriori
bounds, computed from the actual residuals, are what the tests assert. Evaluating vᵀKv in floating
point adds up to eps·|v|ᵀ|K||v| (the terms' size, not the sum's), added to each bound.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexshaft.elements.materials import STEEL
from flexshaft.elements.tet10 import solid_matrices
from flexshaft.elements.tetmesh import TET10_EDGES, TetMesh
from flexshaft.errors import ModelError
from flexshaft.linalg import eigen
from flexshaft.linalg.lobpcg import TOL, lobpcg
from flexshaft.linalg.multigrid import linear_coarse_space
from flexshaft.linalg.spd import SpdSolver, rigid_body_modes
from tests.flexshaft.elements.test_tet10 import box_mesh

EPS = np.finfo(float).eps


def _clamped_bar(cells, size=(0.6, 0.15, 0.1)):
    """A steel bar of rectangular section (bending in y and z apart), both end faces clamped: K, M,
    its rigid motions (multigrid's near-null space) and the linear elements' coarse space."""
    nodes, tets = box_mesh(np.array(cells), size)
    mats = solid_matrices(TetMesh("bar", nodes, tets), STEEL)
    inner = (nodes[:, 0] > 1e-9) & (nodes[:, 0] < size[0] - 1e-9)
    keep = np.flatnonzero(np.repeat(inner, 3))
    K = mats.K.tocsr()[keep][:, keep]
    M = mats.M.tocsr()[keep][:, keep]
    T = sp.csr_matrix((np.ones(keep.size), (keep, np.arange(keep.size))), shape=(3 * len(nodes), keep.size))
    return K, M, rigid_body_modes(nodes)[keep], linear_coarse_space(tets, T, edges=TET10_EDGES)


def _residual_norms(K, M, values, vectors):
    """‖Kv − θMv‖ in the M⁻¹ norm (a CG solve with M, well conditioned) and in the 2-norm relative to
    θ‖Mv‖, and eps·|v|ᵀ|K||v|/vᵀMv, per column."""
    d = 1.0 / M.diagonal()
    jacobi = spla.LinearOperator(M.shape, matvec=lambda x: d * x, dtype=float)
    dual, relative, roundoff = [], [], []
    for theta, v in zip(values, vectors.T, strict=True):
        r = K @ v - theta * (M @ v)
        z, info = spla.cg(M, r, rtol=1e-13, atol=0.0, M=jacobi, maxiter=2000)
        assert info == 0
        vmv = float(v @ (M @ v))
        dual.append(np.sqrt(max(float(r @ z), 0.0) / vmv))
        relative.append(np.linalg.norm(r) / (theta * np.linalg.norm(M @ v)))
        roundoff.append(EPS * float(np.abs(v) @ (abs(K) @ np.abs(v))) / vmv)
    return np.array(dual), np.array(relative), np.array(roundoff)


def _check_against(ref, sol, K, M, count):
    """Each LOBPCG pair within the Kato-Temple and Davis-Kahan bounds of the reference's."""
    lam, V = sol.eigenvalues[:count], sol.vectors[:, :count]
    ref_lam = ref.eigenvalues  # count + 1 of them: the last one bounds the last mode from above
    dual, relative, roundoff = _residual_norms(K, M, lam, V)
    _, _, ref_roundoff = _residual_norms(K, M, ref_lam[:count], ref.vectors[:, :count])
    # the stopping criterion held (the returned values are the vectors' Rayleigh quotients, whose
    # residual is the one LOBPCG measured)
    assert np.all(relative <= TOL * (1 + 1e-6)), relative
    for j in range(count):
        a = ref_lam[j - 1] if j else -np.inf
        b = ref_lam[j + 1]
        theta = lam[j]
        assert a < theta < b
        lo = theta - dual[j] ** 2 / (b - theta)
        hi = theta + (dual[j] ** 2 / (theta - a) if j else 0.0)  # the lowest: θ >= λ₁ (min-max)
        slack = roundoff[j] + ref_roundoff[j]
        assert lo - slack <= ref_lam[j] <= hi + slack, (j, theta, ref_lam[j], lo, hi, slack)
        # the eigenvector: sin² of the angle to the reference's (both M-normalised)
        delta = min(b - theta, theta - a)
        cos = abs(float(ref.vectors[:, j] @ (M @ V[:, j])))
        sin2 = max(1.0 - cos**2, 0.0)
        assert sin2 <= (dual[j] / delta) ** 2 + 1e-12, (j, sin2, dual[j] / delta)


@pytest.fixture(scope="module")
def bar():
    # 20 x 6 x 4 cells: 12 999 DOFs once the end faces are clamped, above LOBPCG_MIN_DOF
    K, M, B, coarse = _clamped_bar((20, 6, 4))
    ref = eigen.lowest_modes(K, M, 13, method="lanczos")
    return K, M, B, coarse, ref


def test_lobpcg_finds_the_exact_solvers_modes(bar):
    K, M, B, coarse, ref = bar
    assert K.shape[0] > eigen.LOBPCG_MIN_DOF
    sol = eigen.lowest_modes(K, M, 12, near_null=B, coarse=coarse)  # "auto": LOBPCG for a solid
    assert sol.method.startswith("LOBPCG (block CG with multigrid: the linear elements")
    assert sol.vectors.shape == (K.shape[0], 12) and not sol.rigid.any()
    # M-orthonormal to round-off
    np.testing.assert_allclose(sol.vectors.T @ (M @ sol.vectors), np.eye(12), rtol=0, atol=1e-12)
    _check_against(ref, sol, K, M, 12)


def test_lobpcg_takes_a_ready_preconditioner(bar):
    K, M, B, coarse, ref = bar
    solver = SpdSolver(K, near_null=B, coarse=coarse, method="amg")  # K's own, as a reduction has
    sol = eigen.lowest_modes(K, M, 12, near_null=B, preconditioner=solver)
    assert sol.method.startswith("LOBPCG")
    _check_against(ref, sol, K, M, 12)


def test_lobpcg_keeps_a_free_bodys_rigid_modes_exact():
    nodes, tets = box_mesh(np.array((8, 3, 2)), (0.6, 0.15, 0.1))
    mats = solid_matrices(TetMesh("bar", nodes, tets), STEEL)
    K, M = mats.K.tocsr(), mats.M.tocsr()
    R = rigid_body_modes(nodes)
    ref = eigen.lowest_modes(K, M, 6 + 6, rigid_basis=R, method="lanczos")
    sol = eigen.lowest_modes(K, M, 6 + 5, rigid_basis=R, method="lobpcg", near_null=R)
    assert sol.method.startswith("LOBPCG") and sol.rigid[:6].all() and not sol.rigid[6:].any()
    assert np.all(sol.eigenvalues[:6] == 0.0)
    # the elastic modes M-orthogonal to the rigid ones
    assert np.abs(R.T @ (M @ sol.vectors[:, 6:])).max() <= 1e-10 * np.abs(R.T @ (M @ R)).max()

    class Elastic:  # the reference's elastic pairs, in _check_against's terms
        eigenvalues = ref.eigenvalues[6:]
        vectors = ref.vectors[:, 6:]

    class Found:
        eigenvalues = sol.eigenvalues[6:]
        vectors = sol.vectors[:, 6:]

    _check_against(Elastic, Found, K, M, 5)


def test_lobpcg_says_when_it_did_not_converge():
    K, M, _, _ = _clamped_bar((6, 2, 2))
    X = np.random.default_rng(3).standard_normal((K.shape[0], 6))
    out = lobpcg(K, M, X, lambda r: r, count=4, maxiter=3)  # no preconditioner, three steps
    assert not out.converged and out.iterations == 3 and np.any(out.residuals[:4] > TOL)


def test_an_unknown_method_is_refused():
    K, M, _, _ = _clamped_bar((3, 1, 1))
    with pytest.raises(ModelError, match="unknown eigen-solver"):
        eigen.lowest_modes(K, M, 2, method="arnoldi")
