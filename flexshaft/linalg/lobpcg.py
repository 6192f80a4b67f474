"""LOBPCG: the lowest eigenpairs of K·v = λ·M·v of a large solid part, with a multigrid preconditioner.

Knyazev's locally optimal block preconditioned conjugate gradient method (SIAM J. Sci. Comput. 23,
2001): each iteration takes the Rayleigh-Ritz step on the span of the current block X, the
preconditioned residuals W = T·(KX − MXΛ) and the previous step P. The preconditioner T ≈ K⁻¹ is one
multigrid V-cycle (:class:`~flexshaft.linalg.multigrid.Multigrid`) applied to the whole block at
once, so an iteration costs about one preconditioned CG step per vector, where shift-invert Lanczos
pays a whole inner solve per vector: 159 s for 20 modes of 52 000 DOFs with multigrid-CG inner
solves, against TODO s here.

The basis is kept M-orthonormal block by block - W against X, P against X and W, each block by
Stathopoulos and Wu's SVQB (SIAM J. Sci. Comput. 23, 2002), dropping directions that are nearly
dependent - which is what makes the method stable without restarts in long runs (Hetmaniuk and
Lehoucq, J. Comput. Phys. 218, 2006; Duersch et al., SIAM J. Sci. Comput. 40, 2018). Converged
columns stay in X (soft locking) but get no new directions.

Stopping criterion, per column: the relative residual ‖Kx − θMx‖₂ / (θ‖Mx‖₂) below ``tol``. For an
M-normalised x the Ritz value θ then is within ‖r‖²_{M⁻¹}/δ of an eigenvalue (Kato-Temple; δ the
distance to the rest of the spectrum), with ‖r‖_{M⁻¹} ≤ tol·θ·√κ(M) (κ(M) = μ_max/μ_min of the mass
matrix, h-independent for a quasi-uniform mesh): |θ − λ|/λ ≤ tol²·κ(M)·θ/δ - about 1e-10 at
tol = 1e-6 for modes a few per cent apart. The vector's angle to the eigenvector (Davis-Kahan in the
M-inner product) is at most ‖r‖_{M⁻¹}/δ ≤ tol·√κ(M)·θ/δ.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

__all__ = ["LobpcgResult", "lobpcg", "TOL", "MAX_ITERATIONS"]

#: Relative residual at which a column counts as converged (module docstring: eigenvalues to ~1e-10).
TOL = 1e-6
#: Iterations allowed: a multigrid-preconditioned block reaches 1e-6 in tens; hundreds mean the
#: preconditioner is not one.
MAX_ITERATIONS = 300
#: SVQB drops the directions of a block whose M-Gram matrix eigenvalue (the block's columns scaled to
#: unit M-norm) is below this share of the largest: nearly dependent directions, whose Rayleigh-Ritz
#: step would be ill-conditioned.
DROP = 1e-10


@dataclass(frozen=True)
class LobpcgResult:
    """The outcome of :func:`lobpcg`.

    Attributes
    ----------
    eigenvalues : ndarray (k,)
        Ritz values, ascending, (rad/s)² for a stiffness and an inertia.
    vectors : ndarray (n, k)
        Ritz vectors, M-orthonormal.
    residuals : ndarray (k,)
        ‖Kx − θMx‖₂ / (θ‖Mx‖₂) of each column at the end.
    iterations : int
    converged : bool
        Whether the first ``count`` columns reached the tolerance.
    """

    eigenvalues: np.ndarray
    vectors: np.ndarray
    residuals: np.ndarray
    iterations: int
    converged: bool


def _svqb(U: np.ndarray, *others: np.ndarray, M_U: np.ndarray) -> tuple[np.ndarray, ...]:
    """M-orthonormalise the columns of U (SVQB), dropping nearly dependent directions; the same
    column operations on M·U (``M_U``) and on ``others`` (K·U)."""
    G = U.T @ M_U
    G = 0.5 * (G + G.T)
    d = np.sqrt(np.clip(np.diag(G), 0.0, None))
    d = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    theta, Z = np.linalg.eigh(d[:, None] * G * d[None, :])
    keep = theta > DROP * max(float(theta.max(initial=0.0)), np.finfo(float).tiny)
    C = (d[:, None] * Z[:, keep]) / np.sqrt(theta[keep])
    return (U @ C, M_U @ C, *(o @ C for o in others))


def lobpcg(
    K,
    M,
    X: np.ndarray,
    precondition: Callable[[np.ndarray], np.ndarray],
    *,
    count: int,
    tol: float = TOL,
    maxiter: int = MAX_ITERATIONS,
    constraints: np.ndarray | None = None,
    product: Callable | None = None,
) -> LobpcgResult:
    """The lowest eigenpairs of K·v = λ·M·v by LOBPCG (module docstring).

    Parameters
    ----------
    K, M : sparse matrix (n, n)
        Symmetric; M positive definite, K positive definite on the complement of ``constraints``.
    X : ndarray (n, k)
        Starting block; its k columns are the block size (``count`` plus a few guard vectors, which
        speed the convergence of the last wanted ones).
    precondition : callable
        T·R for a block R (n, j): an approximation of K⁻¹ (or of (K − σM)⁻¹).
    count : int
        How many of the lowest pairs must converge (<= k).
    tol : float
        Relative residual per column.
    maxiter : int
    constraints : ndarray (n, r), optional
        Directions the eigenvectors are M-orthogonal to (a free body's rigid-body modes).
    product : callable, optional
        ``product(A, V)``: A·V for a sparse A and a block V (default ``A @ V``).

    Returns
    -------
    LobpcgResult
    """
    mul = product if product is not None else (lambda A, V: A @ V)
    n, k = X.shape
    if constraints is not None and constraints.shape[1]:
        Y = np.asarray(constraints, dtype=float)
        MY = mul(M, Y)
        gram = sla.cho_factor(Y.T @ MY)

        def project(V):
            return V - Y @ sla.cho_solve(gram, MY.T @ V)

    else:

        def project(V):
            return V

    X = project(np.asarray(X, dtype=float))
    X, MX = _svqb(X, M_U=mul(M, X))
    KX = mul(K, X)
    # Rayleigh-Ritz on the start block
    lam, C = np.linalg.eigh(0.5 * (X.T @ KX + KX.T @ X))
    X, KX, MX = X @ C, KX @ C, MX @ C
    k = X.shape[1]
    P = KP = MP = None
    residuals = np.full(k, np.inf)
    it = 0
    for it in range(1, maxiter + 1):
        R = KX - MX * lam
        scale = np.maximum(np.abs(lam), np.finfo(float).tiny) * np.linalg.norm(MX, axis=0)
        residuals = np.linalg.norm(R, axis=0) / scale
        active = ~(residuals < tol)  # NaN counts as not converged
        if not active[:count].any():
            break
        W = project(precondition(np.ascontiguousarray(R[:, active])))
        del R
        MW = mul(M, W)
        c = MX.T @ W  # XᵀMW: W made M-orthogonal to X
        W -= X @ c
        MW -= MX @ c
        W, MW = _svqb(W, M_U=MW)
        KW = mul(K, W)
        blocks = [(X, KX, MX), (W, KW, MW)]
        if P is not None:
            P, KP, MP = P[:, active], KP[:, active], MP[:, active]
            for B, KB, MB in blocks:  # P made M-orthogonal to X and W
                c = MB.T @ P
                P -= B @ c
                KP -= KB @ c
                MP -= MB @ c
            P, MP, KP = _svqb(P, KP, M_U=MP)
            if P.shape[1]:
                blocks.append((P, KP, MP))
        # Rayleigh-Ritz on span[X, W, P]: the Gram matrices block by block
        sizes = [b[0].shape[1] for b in blocks]
        edges = np.concatenate([[0], np.cumsum(sizes)])
        GK = np.empty((edges[-1], edges[-1]))
        GM = np.empty_like(GK)
        for i, (Bi, _, _) in enumerate(blocks):
            for j in range(i, len(blocks)):
                _, KBj, MBj = blocks[j]
                a, b = slice(edges[i], edges[i + 1]), slice(edges[j], edges[j + 1])
                GK[a, b] = Bi.T @ KBj
                GM[a, b] = Bi.T @ MBj
                GK[b, a] = GK[a, b].T
                GM[b, a] = GM[a, b].T
        theta, C = sla.eigh(0.5 * (GK + GK.T), 0.5 * (GM + GM.T), subset_by_index=[0, k - 1])
        lam = theta
        # the new search directions: the W and P parts of the Ritz vectors; then X = X·Cx + P
        Cx = C[: edges[1]]
        news = []
        for which in range(3):
            part = sum(blocks[b][which] @ C[edges[b] : edges[b + 1]] for b in range(1, len(blocks)))
            news.append(part)
        P, KP, MP = news
        X = X @ Cx + P
        KX = KX @ Cx + KP
        MX = MX @ Cx + MP
        del blocks, W, KW, MW
    converged = not active[:count].any() if it else False
    return LobpcgResult(lam, X, residuals, it, bool(converged))
