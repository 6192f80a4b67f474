"""LOBPCG: the lowest eigenpairs of K·v = λ·M·v of a large solid part, with a multigrid preconditioner.

Knyazev's locally optimal block preconditioned conjugate gradient method (SIAM J. Sci. Comput. 23,
2001): each iteration takes the Rayleigh-Ritz step on the span of the current block X, the
preconditioned residuals W = T·(KX − MXΛ) and the previous step P. The preconditioner T ≈ K⁻¹ is one
multigrid cycle (:class:`~flexshaft.linalg.multigrid.Multigrid`) applied to the whole block at once,
so an iteration costs about one preconditioned CG step per vector, where shift-invert Lanczos pays a
whole inner solve per vector (52 000 DOFs: 159 s for 20 modes with multigrid-CG inner solves).

The Gram matrices of [X, W, P] are formed block by block (X's own are Λ and I) and the basis is
made M-orthonormal on them, by Stathopoulos and Wu's SVQB (SIAM J. Sci. Comput. 23, 2002): the
columns scaled to unit M-norm, the directions whose Gram eigenvalue falls below :data:`DROP` of the
largest dropped - what keeps the Rayleigh-Ritz step well conditioned when a direction becomes nearly
dependent (Hetmaniuk and Lehoucq, J. Comput. Phys. 218, 2006; Duersch et al., SIAM J. Sci. Comput.
40, 2018). A wanted column that has converged is locked: it leaves the block, whose later directions
are kept M-orthogonal to it, so the block and the dense work on it shrink as the modes converge.

Stopping criterion, per column: the relative residual ‖Kx − θMx‖₂ / (θ‖Mx‖₂) below ``tol``. For an
M-normalised x the Ritz value θ is then within ‖r‖²_{M⁻¹}/δ of an eigenvalue (Kato-Temple; δ the
distance to the rest of the spectrum), with ‖r‖_{M⁻¹} <= tol·θ·√κ(M) (κ(M) = μ_max/μ_min of the mass
matrix, O(10-100) for quadratic tetrahedra whatever the mesh size): ``|θ − λ|/λ <= tol²·κ(M)·θ/δ``, about
1e-10 at tol = 1e-6 for modes a few per cent apart. The vector's angle to the eigenvector
(Davis-Kahan in the M-inner product) is at most ‖r‖_{M⁻¹}/δ <= tol·√κ(M)·θ/δ: 1e-5 for such modes,
far below what a Craig-Bampton body's 20 modes leave out. Measured on a 13 000-DOF bar
(tests/flexshaft/linalg/test_lobpcg.py): eigenvalues within 1e-14 of an exact factorisation's.

Why this one and not ``scipy.sparse.linalg.lobpcg`` (benchmarks/bench_lobpcg.py: both with the same
multigrid preconditioner, start block and products, PTSS part 1 held at both ends, 20 modes). scipy
stops on one absolute residual for the whole block, so matching the per-column criterion above means
choosing its ``tol`` for the lowest mode: then scipy took 1.48x this solver's time at 132 k DOFs
(quiet machine) and 1.64x at 315 k (busy). Only with ``tol`` set for the highest mode - a scale known
only once the answer is - did it come within 1.14-1.19x, the lower modes then less accurate. The
rule kept: the own solver stays while scipy's, at the same guaranteed accuracy, is ~1.5x slower.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

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


def _svqb(U: np.ndarray, M_U: np.ndarray, *others: np.ndarray) -> tuple[np.ndarray, ...]:
    """M-orthonormalise the columns of U (SVQB), dropping nearly dependent directions; the same
    column operations on M·U (``M_U``) and on ``others`` (K·U)."""
    C = _orthonormaliser(U.T @ M_U)
    return (U @ C, M_U @ C, *(o @ C for o in others))


def _orthonormaliser(G: np.ndarray) -> np.ndarray:
    """C with CᵀGC = I for a symmetric positive semi-definite Gram matrix G, dropping the directions
    whose eigenvalue (columns scaled to unit norm) is below :data:`DROP` of the largest (SVQB)."""
    G = 0.5 * (G + G.T)
    d = np.sqrt(np.clip(np.diag(G), 0.0, None))
    d = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    theta, Z = np.linalg.eigh(d[:, None] * G * d[None, :])
    keep = theta > DROP * max(float(theta.max(initial=0.0)), np.finfo(float).tiny)
    return (d[:, None] * Z[:, keep]) / np.sqrt(theta[keep])


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
    # the constraints, then the locked vectors: M-orthonormal directions the block stays M-orthogonal to
    Q = MQ = None
    fixed = 0  # Q's columns that are constraints
    locked_lam, locked_res = [], []  # the locked vectors' θ and residual
    if constraints is not None and constraints.shape[1]:
        Y = np.asarray(constraints, dtype=float)
        Q, MQ = _svqb(Y, mul(M, Y))
        fixed = Q.shape[1]

    def project(V):
        if Q is not None:
            V -= Q @ (MQ.T @ V)
        return V

    X = project(np.array(X, dtype=float))
    k = X.shape[1]
    X, MX = _svqb(X, mul(M, X))
    rng = np.random.default_rng(1)
    while X.shape[1] < k:  # dependent start vectors dropped: random ones in their place
        extra = project(rng.standard_normal((X.shape[0], k - X.shape[1])))
        extra -= X @ (MX.T @ extra)
        extra, Mextra = _svqb(extra, mul(M, extra))
        X, MX = np.hstack([X, extra]), np.hstack([MX, Mextra])
    KX = mul(K, X)
    # Rayleigh-Ritz on the start block
    lam, C = np.linalg.eigh(0.5 * (X.T @ KX + KX.T @ X))
    X, KX, MX = X @ C, KX @ C, MX @ C
    P = KP = MP = None
    residuals = np.full(X.shape[1], np.inf)
    it = 0
    for it in range(1, maxiter + 1):  # noqa: B007 (the count is the result's)
        R = MX * lam
        np.subtract(KX, R, out=R)
        norm_r = np.sqrt(np.einsum("ij,ij->j", R, R))
        norm_mx = np.sqrt(np.einsum("ij,ij->j", MX, MX))
        residuals = norm_r / (np.maximum(np.abs(lam), np.finfo(float).tiny) * norm_mx)
        done = residuals < tol  # NaN counts as not converged
        wanted = count - len(locked_lam)
        if done[:wanted].all():
            break
        # hard locking: a converged wanted column leaves the block for good (the block's later
        # Rayleigh-Ritz steps stay M-orthogonal to it), so the block - and the dense work on it -
        # shrinks as the modes converge
        lock = np.flatnonzero(done[:wanted])
        if lock.size:
            locked_lam += lam[lock].tolist()
            locked_res += residuals[lock].tolist()
            newQ, newKQ, newMQ = X[:, lock], KX[:, lock], MX[:, lock]
            keep = np.ones(X.shape[1], dtype=bool)
            keep[lock] = False
            X, KX, MX, R, lam, done = X[:, keep], KX[:, keep], MX[:, keep], R[:, keep], lam[keep], done[keep]
            if P is not None:  # the last step's directions lose their part along the locked vectors
                P, KP, MP = P[:, keep], KP[:, keep], MP[:, keep]
                c = newMQ.T @ P
                P -= newQ @ c
                KP -= newKQ @ c
                MP -= newMQ @ c
            Q = newQ if Q is None else np.hstack([Q, newQ])
            MQ = newMQ if MQ is None else np.hstack([MQ, newMQ])
            del newQ, newKQ, newMQ
        active = ~done
        every = active.all()  # then the blocks as they are, not copies of their columns
        W = project(precondition(R if every else np.ascontiguousarray(R[:, active])))
        del R
        KW, MW = mul(K, W), mul(M, W)
        blocks = [(X, KX, MX), (W, KW, MW)]
        if P is not None and active.any():
            blocks.append((P, KP, MP) if every else (P[:, active], KP[:, active], MP[:, active]))
        del W, KW, MW  # held by ``blocks`` alone, which the step empties once it has used them
        lam, (X, KX, MX), (P, KP, MP) = _rayleigh_ritz(blocks, lam)
    wanted = count - len(locked_lam)
    converged = it > 0 and bool(np.all(residuals[:wanted] < tol))
    if locked_lam:
        X = np.hstack([Q[:, fixed:], X])
        lam = np.concatenate([locked_lam, lam])
        residuals = np.concatenate([locked_res, residuals])
        order = np.argsort(lam, kind="stable")
        X, lam, residuals = X[:, order], lam[order], residuals[order]
    return LobpcgResult(lam, X, residuals, it, converged)


def _rayleigh_ritz(blocks: list, lam: np.ndarray):
    """One Rayleigh-Ritz step on span[X, W, P] (``blocks``: each block with its K- and M-products).

    The Gram matrices are formed block by block (X's own are Λ and I), then the basis is made
    orthonormal on the small matrices (SVQB's dropping of nearly dependent directions), so no block of
    n rows is orthogonalised explicitly. Returns the new Ritz values, (X, KX, MX) and the new
    directions (P, KP, MP): the W and P parts of the Ritz vectors, X being X·Cx + P. ``blocks`` is
    emptied once its W and P are used, so their memory goes before the new X is formed.
    """
    X, KX, MX = blocks[0]
    edges = np.concatenate([[0], np.cumsum([b[0].shape[1] for b in blocks])])
    GK = np.zeros((edges[-1], edges[-1]))
    GM = np.zeros_like(GK)
    GK[: edges[1], : edges[1]] = np.diag(lam)
    GM[: edges[1], : edges[1]] = np.eye(edges[1])
    for i, (Bi, _, _) in enumerate(blocks):
        for j in range(max(i, 1), len(blocks)):
            a, b = slice(edges[i], edges[i + 1]), slice(edges[j], edges[j + 1])
            GK[a, b] = Bi.T @ blocks[j][1]
            GM[a, b] = Bi.T @ blocks[j][2]
            GK[b, a] = GK[a, b].T
            GM[b, a] = GM[a, b].T
    Z = _orthonormaliser(GM)
    theta, V = np.linalg.eigh(Z.T @ (0.5 * (GK + GK.T)) @ Z)
    k = X.shape[1]
    C = Z @ V[:, :k]
    news = []
    for which in range(3):
        part = blocks[1][which] @ C[edges[1] : edges[2]]
        if len(blocks) == 3:
            part += blocks[2][which] @ C[edges[2] :]
        news.append(part)
    blocks.clear()
    Cx = C[: edges[1]]
    X, KX, MX = X @ Cx, KX @ Cx, MX @ Cx
    P, KP, MP = news
    X += P
    KX += KP
    MX += MP
    return theta[:k], (X, KX, MX), (P, KP, MP)
