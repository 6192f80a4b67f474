"""Generalised symmetric eigensolvers for K·v = λ·M·v, lowest modes first.

Three paths, chosen by size and structure:

- dense LAPACK (``eigh``) for small models or when most modes are wanted;
- shift-invert Lanczos (ARPACK) with a banded Cholesky factor of K − σM for
  banded models (a chain numbered in order is tridiagonal), O(n) per solve;
- shift-invert Lanczos with a sparse LU for anything else.

Rigid-body modes are not left to round-off: the caller passes their exact
basis, they are reported at λ = 0 and the elastic modes are made
inertia-orthogonal to them.
"""

from __future__ import annotations

import contextlib
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import ModelError

__all__ = ["EigenSolution", "lowest_modes", "solver_failures", "DENSE_MAX_DOF"]

#: Up to this many DOFs a dense solve is faster than Lanczos and gets all modes.
DENSE_MAX_DOF = 600
#: Above this many DOFs a dense solve is refused (memory and O(n³) time).
DENSE_LIMIT_DOF = 12_000
#: Largest half-bandwidth handled by the banded Cholesky path.
BANDED_MAX = 64


@dataclass(frozen=True)
class EigenSolution:
    """Lowest eigenpairs of (K, M).

    Attributes
    ----------
    eigenvalues : ndarray, shape (m,)
        λ = ω², (rad/s)², ascending; exactly 0 for rigid-body modes.
    vectors : ndarray, shape (n, m)
        Inertia-normalised: VᵀMV = I.
    rigid : ndarray of bool, shape (m,)
        True for the rigid-body modes.
    method : str
        Which path solved it.
    """

    eigenvalues: np.ndarray
    vectors: np.ndarray
    rigid: np.ndarray
    method: str


@contextlib.contextmanager
def solver_failures(what: str):
    """LAPACK and ARPACK failures (numbers out of range, no convergence) as one ModelError."""
    from scipy.sparse.linalg import ArpackError, ArpackNoConvergence

    try:
        with np.errstate(all="ignore"):
            yield
    except ModelError:  # (a ValueError too) already says what is wrong
        raise
    except (np.linalg.LinAlgError, ValueError, RuntimeError, ArpackError, ArpackNoConvergence) as err:
        detail = str(err).splitlines()[0] if str(err) else ""
        raise ModelError(
            f"{what} failed ({type(err).__name__}: {detail})",
            field="model",
            valid="stiffness, inertia and damping of one scale, within double precision's range",
        ) from None


def half_bandwidth(A: sp.spmatrix) -> int:
    """max |i − j| over the stored entries of A."""
    coo = A.tocoo()
    return int(np.max(np.abs(coo.row - coo.col))) if coo.nnz else 0


def _lower_band(A: sp.spmatrix, b: int) -> np.ndarray:
    """A in LAPACK lower banded storage: ab[i, j] = A[j + i, j]."""
    n = A.shape[0]
    ab = np.zeros((b + 1, n))
    for i in range(b + 1):
        ab[i, : n - i] = A.diagonal(-i)
    return ab


def _factor_failed(info: int, what: str):
    # K − σM with σ < 0 is positive definite whenever M is; a failure means it is not.
    raise ModelError(
        f"the shifted stiffness is not positive definite ({what} info = {info})",
        field="inertia",
        valid="a positive-definite inertia matrix (every node with inertia)",
    )


def _shift_invert_operator(K, M, sigma: float, bandwidth: int):
    """A LinearOperator applying (K − σM)⁻¹, and the name of the factorisation.

    Tridiagonal matrices (a chain) use LAPACK's LDLᵀ for SPD tridiagonals
    (?pttrf/?pttrs), other narrow bands the banded Cholesky (?pbtrf/?pbtrs),
    anything else a sparse LU. The LAPACK routines are called directly: the
    solve runs ~40 times per eigensolve and wrapper checks would cost more
    than the O(n) work itself.
    """
    from scipy.linalg import lapack
    from scipy.sparse.linalg import LinearOperator, splu

    A = (K - sigma * M).tocsr()
    n = A.shape[0]
    if bandwidth == 1:
        d, e, info = lapack.dpttrf(A.diagonal(), A.diagonal(1))
        if info != 0:
            _factor_failed(info, "dpttrf")

        def solve(x):
            return lapack.dpttrs(d, e, x)[0]

        name = "tridiagonal LDLᵀ"
    elif bandwidth <= BANDED_MAX:
        cb, info = lapack.dpbtrf(_lower_band(A, bandwidth), lower=1)
        if info != 0:
            _factor_failed(info, "dpbtrf")

        def solve(x):
            return lapack.dpbtrs(cb, x, lower=1)[0]

        name = "banded Cholesky"
    else:
        lu = splu(A.tocsc())
        solve = lu.solve
        name = "sparse LU"
    return LinearOperator((n, n), matvec=solve, dtype=float), name


def _orthogonalise(V: np.ndarray, R: np.ndarray, M) -> np.ndarray:
    """Remove the rigid-body content of V (M-inner product) and M-normalise."""
    MV = M @ V
    if R.shape[1]:
        c = R.T @ MV
        V = V - R @ c
        MV = MV - (M @ R) @ c
    return V / np.sqrt(np.einsum("ij,ij->j", V, MV))


def _shift(K, M, R: np.ndarray, trial: np.ndarray | None = None) -> float:
    """A negative shift of the size of the lowest elastic eigenvalue.

    The Rayleigh quotient of a trial shape (made inertia-orthogonal to the
    rigid modes) bounds λ₁ from above; the smallest over the trial shapes
    (default: a ramp over the node numbering, which for a shaft meshed along
    its axis sits within a small factor of λ₁) sets the shift.
    """
    n = K.shape[0]
    x = np.linspace(-1.0, 1.0, n)[:, None] if trial is None else np.asarray(trial, float).reshape(n, -1)
    if R.shape[1]:
        x = x - R @ (R.T @ (M @ x))
    num = np.einsum("ij,ij->j", x, K @ x)
    den = np.einsum("ij,ij->j", x, M @ x)
    ok = den > 0
    lam = float(np.min(num[ok] / den[ok])) if ok.any() else float("nan")
    if not np.isfinite(lam) or lam <= 0.0:
        lam = float(np.max(K.diagonal() / M.diagonal()))
    return -0.1 * lam


def lowest_modes(
    K,
    M,
    count: int,
    rigid_basis: np.ndarray | None = None,
    method: str = "auto",
    bandwidth: int | None = None,
    trial: np.ndarray | None = None,
) -> EigenSolution:
    """The ``count`` lowest eigenpairs of K·v = λ·M·v.

    Parameters
    ----------
    K, M : scipy.sparse matrix, shape (n, n)
        Symmetric stiffness (positive semi-definite) and inertia (positive
        definite).
    count : int
        How many modes, rigid-body modes included; clipped to n.
    rigid_basis : ndarray, shape (n, r), optional
        The exact rigid-body modes (null space of K). They are returned first,
        at λ = 0, inertia-normalised.
    method : {"auto", "dense", "lanczos"}
        Force a path; "auto" picks by size.
    bandwidth : int, optional
        Half-bandwidth of K and M when the caller knows it (found otherwise).
    trial : ndarray, shape (n, t), optional
        Trial shapes whose smallest Rayleigh quotient bounds the lowest
        elastic eigenvalue; it sets the shift of the Lanczos path. Default: a
        ramp over the DOF numbering, right for a chain with one DOF per node
        but far too stiff when several kinds of DOF are interleaved.

    Returns
    -------
    EigenSolution
    """
    K = sp.csr_matrix(K)
    M = sp.csr_matrix(M)
    n = K.shape[0]
    R = np.zeros((n, 0)) if rigid_basis is None else np.asarray(rigid_basis, dtype=float)
    r = R.shape[1]
    if r:
        R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ (M @ R))).T  # M-orthonormal
    m = min(int(count), n)
    n_el = m - r
    if method == "auto":
        method = "dense" if (n <= DENSE_MAX_DOF or m > n // 3) else "lanczos"
    if m >= n - 1:
        method = "dense"  # Lanczos needs fewer modes than DOFs
    if n_el <= 0:
        lam = np.zeros(m)
        vec = R[:, :m]
        name = "rigid only"
    elif method == "dense":
        if n > DENSE_LIMIT_DOF:
            raise ModelError(
                "a dense eigensolve of this size is refused",
                field="count",
                value=m,
                valid=f"at most {n // 3} modes for a model of {n} DOFs",
            )
        lam_all, vec_all = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, m - 1], check_finite=False)
        lam, vec = lam_all[r:], vec_all[:, r:]
        name = "dense LAPACK eigh"
    else:
        from scipy.sparse.linalg import eigsh
        from threadpoolctl import threadpool_limits

        sigma = _shift(K, M, R, trial)
        b = half_bandwidth(K + M) if bandwidth is None else bandwidth
        op, fact = _shift_invert_operator(K, M, sigma, b)
        # ARPACK's steps are level-2 BLAS on a few long vectors: threads buy
        # nothing there, and on a busy 2-core machine they stall each other
        # (measured: 0.25 s -> 2.8 s at 1e5 DOFs). One BLAS thread is steady.
        # (Below ~1e4 DOFs setting the limit costs more than the solve.)
        limit = threadpool_limits(limits=1, user_api="blas") if n > 10_000 else nullcontext()
        # A fixed start vector: the same model gives the same digits on every run.
        v0 = np.random.default_rng(0).standard_normal(n)
        with limit:
            lam_all, vec_all = eigsh(K, k=m, M=M, sigma=sigma, which="LM", OPinv=op, v0=v0)
        order = np.argsort(lam_all)
        lam, vec = lam_all[order][r:], vec_all[:, order][:, r:]
        name = f"shift-invert Lanczos ({fact})"
    if n_el > 0:
        vec = _orthogonalise(vec, R, M)
        if name.startswith("shift-invert"):
            # Rayleigh quotients of the (M-normalised) Ritz vectors: their error is the
            # square of the vectors', so the eigenvalues gain digits for one product.
            lam = np.einsum("ij,ij->j", vec, K @ vec)
        lam = np.maximum(lam, 0.0)
        lam = np.concatenate([np.zeros(r), lam])
        vec = np.hstack([R, vec])
    rigid = np.arange(lam.size) < r
    return EigenSolution(eigenvalues=lam, vectors=vec, rigid=rigid, method=name)
