"""Multigrid for a solid part's stiffness, applied to a block of vectors at once.

Smoothed aggregation (pyamg) coarsens 10-node tetrahedra badly: a corner node couples to ~80 others,
so its aggregates are ~80 nodes and conjugate gradients need ~90 iterations for a relative residual
of 1e-10 (a 230 000-DOF PTSS tube, both ends held, pyamg's defaults). The same mesh's linear elements
are the natural first coarse level - the quadratic field interpolated from the corner nodes, a
seventh of the unknowns (:func:`linear_coarse_space`) - and smoothed aggregation works well below
it: 44 iterations with the same Gauss-Seidel smoothing, the hierarchy built in a tenth of the time.

The cycle (:class:`Multigrid`) is built from products of a sparse matrix with a block of vectors,
which scipy makes in one pass over the matrix: Chebyshev smoothing (a polynomial in D⁻¹A instead of
Gauss-Seidel sweeps, which run one vector at a time), the transfers, a dense factor on the coarsest
level, and a W-cycle below the first coarse level (its work is a few per cent of the cycle's). A
block of 24 columns costs 2.7x less per column than single products (230 000 DOFs); the smoother's
matrices are kept in single precision (a preconditioner needs no more: 1.6x faster for blocks of 24
at a million DOFs), and the unknowns are reordered for locality (:func:`locality_order`, 1.3-1.6x).
The blocks are what the solvers hand it: all right-hand sides of a solve
(:class:`~flexshaft.linalg.spd.SpdSolver`), all unconverged residuals of an eigen-iteration
(:func:`~flexshaft.linalg.lobpcg.lobpcg`). On the PTSS tube at 1 035 000 DOFs, the twist test's six
loads take 20 iterations of block CG (relative residual 1e-8), 43-48 s.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

__all__ = [
    "CoarseSpace",
    "Multigrid",
    "block_product",
    "linear_coarse_space",
    "locality_order",
    "permuted",
    "permuted_coarse",
]

#: Degree of the Chebyshev smoothing polynomial (pre and post): each degree is one product with the
#: level's matrix. On a 230 000-DOF PTSS tube, a twist test took 46 / 35 / 31 iterations with degrees
#: 2 / 3 / 4 (the same time), 20 modes by LOBPCG 36 / 29 / 27 iterations in 49 / 40 / 41 s.
DEGREE = 3
#: The smoothing interval [ρ/RATIO, ρ·SAFETY] of D⁻¹A's spectrum (ρ its estimated largest eigenvalue):
#: Adams, Brezina, Hu and Tuminaro (J. Comput. Phys. 188, 2003) use ρ/30 for elasticity.
RATIO = 30.0
SAFETY = 1.1
#: Lanczos steps that estimate ρ(D⁻¹A): the largest Ritz value of 12 steps is within a few per cent of
#: it (and below it: hence :data:`SAFETY`).
LANCZOS_STEPS = 12
#: Smoothed aggregation coarsens until a level has at most this many unknowns; that one is factorised
#: densely (an eigen-decomposition, so that a singular matrix - a free body - gives a pseudo-inverse
#: and the outer solver reports the singularity).
MAX_COARSE = 1500
#: Fewer columns than this are multiplied one at a time (:func:`block_product`).
BLOCK_MIN = 6
#: Columns per V-cycle: the cycle's temporaries are a few blocks of this many columns.
BLOCK_MAX = 48


@dataclass(frozen=True)
class CoarseSpace:
    """A first coarse level given by the caller: u_fine = P · u_coarse.

    Attributes
    ----------
    P : scipy.sparse.csr_matrix (n, c)
        The prolongation.
    injected : ndarray of int (c,)
        For each coarse unknown, the fine unknown that is a copy of it (P's row there is that unit
        entry alone): the near-null space of the coarse level is the fine one read there.
    """

    P: sp.csr_matrix
    injected: np.ndarray


def linear_coarse_space(tets, T, rows=None, *, edges) -> CoarseSpace:
    """The linear elements' unknowns as the coarse space of a mesh of 10-node tetrahedra.

    The fine unknowns q give every node's displacement as u = T·q
    (:func:`~flexshaft.parts.solidties.constrain`: a free node's three DOFs are unknowns of q, an
    interface face's nodes follow its master's six, a clamped face's nodes are zero). The coarse
    unknowns are the q that are a corner node's DOF, and the master DOFs; a fine q is the quadratic
    field's value interpolated linearly from the corners: a corner node's own, a mid-side node's the
    mean of its edge's two corners (each given by T). For straight elements the coarse space holds
    every linear field exactly, the rigid motions among them.

    Parameters
    ----------
    tets : ndarray of int (m, 10)
        The elements (VTK order: corners, then the mid-side nodes of ``edges``).
    T : scipy.sparse matrix (3n, q)
        Node-major displacements from the unknowns.
    rows : ndarray of int, optional
        The unknowns of the matrix to precondition (a sub-matrix of q's: the others held at zero),
        in its order. Default: all of q.
    edges : sequence of (int, int)
        The corner pair of each mid-side node, in the elements' order
        (:data:`flexshaft.elements.tetmesh.TET10_EDGES`; passed in, as linalg knows no element).

    Returns
    -------
    CoarseSpace
    """
    tets = np.asarray(tets)
    T = sp.csc_matrix(T)
    T.sort_indices()
    n, q = T.shape[0] // 3, T.shape[1]
    # A column of T that is one unit entry is a free node's DOF (that row); the others are masters'.
    first = T.indptr[:-1].clip(max=max(T.nnz - 1, 0))
    single = (np.diff(T.indptr) == 1) & (T.data[first] == 1.0)
    unit_row = np.where(single, T.indices[first], -1)
    corner = np.zeros(n, dtype=bool)
    corner[tets[:, :4].ravel()] = True
    rows = np.arange(q) if rows is None else np.asarray(rows, dtype=np.int64)
    kept = np.zeros(q, dtype=bool)
    kept[rows] = True
    coarse = np.flatnonzero(kept & (~single | corner[unit_row // 3]))
    # every node from the corners (n x n): a corner itself, a mid-side node its edge ends' mean
    ends = np.array(edges)
    mid, at = np.unique(tets[:, 4:].ravel(), return_index=True)
    a, b = tets[:, ends[:, 0]].ravel()[at], tets[:, ends[:, 1]].ravel()[at]
    corners = np.flatnonzero(corner)
    L = sp.csr_matrix(
        (
            np.concatenate([np.ones(corners.size), np.full(2 * mid.size, 0.5)]),
            (np.concatenate([corners, mid, mid]), np.concatenate([corners, a, b])),
        ),
        shape=(n, n),
    )
    U = sp.kron(L, sp.identity(3), format="csr") @ T[:, coarse]  # every node DOF per coarse unknown
    # a free fine unknown reads its row of U, a master's is its own coarse unknown
    k = np.arange(rows.size)
    free = single[rows]
    pos = np.full(q, -1)
    pos[coarse] = np.arange(coarse.size)
    S = sp.csr_matrix((np.ones(free.sum()), (k[free], unit_row[rows[free]])), shape=(rows.size, 3 * n))
    E = sp.csr_matrix((np.ones((~free).sum()), (k[~free], pos[rows[~free]])), shape=(rows.size, coarse.size))
    P = (S @ U + E).tocsr()
    P.eliminate_zeros()
    where = np.full(q, -1)
    where[rows] = k
    return CoarseSpace(P=P, injected=where[coarse])


def locality_order(A) -> np.ndarray:
    """A permutation of A's unknowns that keeps coupled ones close: reverse Cuthill-McKee.

    A mesher numbers the corner nodes first and the mid-side nodes after them, so a product with the
    stiffness gathers from all over the vector; after this ordering the gathers stay within a band
    of the rows, and scipy's products run 1.3-1.6x faster (230 000 DOFs). When the unknowns come in
    threes (a node's u_x, u_y, u_z: consecutive rows of one pattern) the graph of the triples is
    ordered, nine times smaller.

    Returns
    -------
    ndarray of int (n,)
        ``A[order][:, order]`` is the reordered matrix.
    """
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    A = sp.csr_matrix(A)
    n = A.shape[0]
    lengths = np.diff(A.indptr)
    # a node's three DOFs have the same pattern (a tied face's master's six too): then triples
    triples = n % 3 == 0 and all(np.array_equal(lengths[0::3], lengths[j::3]) for j in (1, 2))
    group = 3 if triples else 1
    # each triple's rows are consecutive: its pattern is theirs together
    rows = np.ascontiguousarray(A.indptr[::group])
    G = sp.csr_matrix(
        (np.ones(A.nnz, dtype=np.int8), A.indices // group, rows), shape=(n // group, n // group)
    )
    G.sum_duplicates()
    order = reverse_cuthill_mckee(G, symmetric_mode=True).astype(np.int64)
    return (group * order[:, None] + np.arange(group)).ravel()


def permuted(A, order: np.ndarray) -> sp.csr_matrix:
    """``A[order][:, order]`` as CSR: the rows gathered, the column indices renamed and sorted (a
    third of the time scipy's column indexing takes)."""
    B = sp.csr_matrix(A)[order]
    where = np.empty(order.size, dtype=B.indices.dtype)
    where[order] = np.arange(order.size)
    for start in range(0, B.nnz, 1 << 22):  # in place, in pieces: no full-length temporary
        piece = B.indices[start : start + (1 << 22)]
        piece[...] = where[piece]
    B.has_sorted_indices = False
    B.sort_indices()
    return B


def permuted_coarse(coarse: CoarseSpace, order: np.ndarray) -> CoarseSpace:
    """The coarse space of the reordered fine unknowns: P's rows in ``order``, and its columns in the
    order of the fine unknowns they are injected at (so that the coarse level inherits the locality)."""
    where = np.empty_like(order)
    where[order] = np.arange(order.size)
    fine = where[coarse.injected]  # each coarse unknown's fine row after the reordering
    cols = np.argsort(fine, kind="stable")
    return CoarseSpace(P=sp.csr_matrix(coarse.P)[order][:, cols].tocsr(), injected=fine[cols])


def block_product(A, X) -> np.ndarray:
    """A @ X for a sparse CSR A and a block X (n, k), the fastest way scipy offers.

    scipy multiplies by one vector in a loop of its own (memory-bound: single precision halves the
    time) and by k vectors in a generic one whose cost is ~4 products of one vector plus ~0.3 of one
    per column (230 000 DOFs of 10-node tetrahedra, measured): a block of fewer than
    :data:`BLOCK_MIN` columns is cheaper column by column.
    """
    if X.ndim == 1 or X.shape[1] >= BLOCK_MIN:
        return A @ X
    out = np.empty((A.shape[0], X.shape[1]), dtype=np.result_type(A.dtype, X.dtype))
    for j in range(X.shape[1]):
        out[:, j] = A @ np.ascontiguousarray(X[:, j])
    return out


def _lanczos_max(A, dinv, steps: int, rng) -> float:
    """The largest Ritz value of ``steps`` Lanczos steps on D^-½ A D^-½ (= the spectrum of D⁻¹A); the
    products in A's precision, the recurrence in double."""
    n = A.shape[0]
    s = np.sqrt(dinv)
    v = rng.standard_normal(n)
    v /= np.linalg.norm(v)
    v_old = np.zeros(n)
    alpha, beta = [], []
    b = 0.0
    for _ in range(min(steps, n)):
        w = s * (A @ (s * v).astype(A.dtype))
        a = float(v @ w)
        w -= a * v + b * v_old
        alpha.append(a)
        b = float(np.linalg.norm(w))
        if b <= 1e-12 * abs(a):
            break
        beta.append(b)
        v_old, v = v, w / b
    k = len(alpha)
    return (
        float(sla.eigvalsh_tridiagonal(np.array(alpha), np.array(beta[: k - 1]))[-1]) if k > 1 else alpha[0]
    )


@dataclass
class _Level:
    A: sp.csr_matrix  # the level's matrix, in the smoother's precision
    P: sp.csr_matrix | None  # to this level from the next coarser one
    R: sp.csr_matrix | None  # Pᵀ, stored as CSR for fast products
    AP: sp.csr_matrix | None  # A·P: updates the residual after the coarse correction (~30 % of A's entries)
    dinv: np.ndarray  # 1 / diag(A)
    lo: float
    hi: float


class Multigrid:
    """A multigrid preconditioner for a sparse SPD matrix, applied to blocks of vectors (module docstring).

    Parameters
    ----------
    A : sparse matrix (n, n)
        Symmetric positive definite (a singular one - a free body - is handled: the coarsest level
        is pseudo-inverted, and the outer solver finds no solution).
    near_null : ndarray (n, k), optional
        The near-null space for smoothed aggregation (the rigid-body motions in A's unknowns).
    coarse : CoarseSpace, optional
        A first coarse level (:func:`linear_coarse_space`); smoothed aggregation starts below it.
    degree : int
        Chebyshev smoothing degree.
    dtype : numpy dtype
        Precision of the smoother's matrices and vectors.
    gamma : int
        Coarse-grid corrections per level below the first coarse one (2: a W-cycle there).
    ratio : float, optional
        The Chebyshev interval's lower end as a fraction of its upper one (default 1 / :data:`RATIO`).

    Attributes
    ----------
    sizes : list of int
        Unknowns per level, finest first.
    complexity : float
        Stored entries of all levels' matrices over the finest one's.
    setup_s : float
        Seconds the hierarchy took.
    """

    def __init__(
        self,
        A,
        *,
        near_null=None,
        coarse: CoarseSpace | None = None,
        degree: int = DEGREE,
        dtype=np.float32,
        gamma: int = 2,
        ratio: float | None = None,
    ):
        import pyamg

        start = time.perf_counter()
        A = sp.csr_matrix(A, dtype=float)
        self.n = A.shape[0]
        self.degree, self.dtype = int(degree), np.dtype(dtype)
        self.gamma = int(gamma)
        ratio = RATIO if ratio is None else ratio
        mats, prolongations = [A], []
        B = None if near_null is None else np.asarray(near_null, dtype=float)
        products = {}  # A·P of a level, where the Galerkin product made it already
        if coarse is not None:
            P = sp.csr_matrix(coarse.P, dtype=float)
            products[0] = (A @ P).tocsr()
            Ac = (P.T @ products[0]).tocsr()
            Ac = 0.5 * (Ac + Ac.T)
            prolongations.append(P)
            mats.append(sp.csr_matrix(Ac))
            B = None if B is None else B[coarse.injected]
        if mats[-1].shape[0] > MAX_COARSE:
            ml = pyamg.smoothed_aggregation_solver(
                mats[-1],
                B=B,
                symmetry="symmetric",
                improve_candidates=None,
                # pyamg counts a coarse level's blocks (one per aggregate, a row per near-null vector)
                max_coarse=MAX_COARSE // (1 if B is None else B.shape[1]),
            )
            prolongations += [sp.csr_matrix(lev.P) for lev in ml.levels[:-1]]
            mats += [sp.csr_matrix(lev.A) for lev in ml.levels[1:]]
        rng = np.random.default_rng(0)
        self.levels: list[_Level] = []
        for depth, M in enumerate(mats[:-1]):
            d = M.diagonal()
            dinv = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
            # the same index arrays, the values in the smoother's precision
            low = sp.csr_matrix((M.data.astype(self.dtype), M.indices, M.indptr), shape=M.shape, copy=False)
            rho = SAFETY * _lanczos_max(low, dinv, LANCZOS_STEPS, rng)
            P = prolongations[depth]
            self.levels.append(
                _Level(
                    A=low,
                    P=P.astype(self.dtype),
                    R=P.T.tocsr().astype(self.dtype),
                    AP=(products.pop(depth) if depth in products else M @ P).tocsr().astype(self.dtype),
                    dinv=dinv.astype(self.dtype),
                    lo=rho / ratio,
                    hi=rho,
                )
            )
        last = mats[-1].toarray()
        w, V = np.linalg.eigh(0.5 * (last + last.T))
        keep = w > 1e-12 * max(float(np.abs(w).max()), np.finfo(float).tiny)
        self._coarse_inv = (V[:, keep] / w[keep]) @ V[:, keep].T
        self.sizes = [M.shape[0] for M in mats]
        self.complexity = sum(M.nnz for M in mats) / A.nnz
        self.setup_s = time.perf_counter() - start

    def _smooth(self, lev: _Level, res, x=None):
        """Chebyshev smoothing (Saad, Iterative Methods, alg. 12.1) of A x = b from x (or 0), given
        the residual ``res`` = b − A x there; ``res`` is overwritten."""
        theta, delta = 0.5 * (lev.hi + lev.lo), 0.5 * (lev.hi - lev.lo)
        sigma = theta / delta
        rho = 1.0 / sigma
        dinv = lev.dinv if res.ndim == 1 else lev.dinv[:, None]
        d = res * dinv
        d *= self.dtype.type(1.0 / theta)
        x = d.copy() if x is None else x + d
        for _ in range(self.degree - 1):
            res -= block_product(lev.A, d)
            rho_new = 1.0 / (2.0 * sigma - rho)
            d *= self.dtype.type(rho_new * rho)
            step = res * dinv
            step *= self.dtype.type(2.0 * rho_new / delta)
            d += step
            x += d
            rho = rho_new
        return x

    def _cycle(self, depth: int, r):
        if depth == len(self.levels):
            return (self._coarse_inv @ r.astype(float)).astype(self.dtype)
        lev = self.levels[depth]
        x = self._smooth(lev, r.copy())
        res = r - block_product(lev.A, x)
        rc = block_product(lev.R, res)
        e = self._cycle(depth + 1, rc)
        if depth >= 1 and self.gamma > 1 and depth + 1 < len(self.levels):
            for _ in range(self.gamma - 1):  # a W-cycle below the first level
                nxt = self.levels[depth + 1]
                e += self._cycle(depth + 1, rc - block_product(nxt.A, e))
        x += block_product(lev.P, e)
        res -= block_product(lev.AP, e)  # b − A(x + P e) without a product with A
        return self._smooth(lev, res, x)

    def apply(self, r) -> np.ndarray:
        """One multigrid cycle on r ((n,) or (n, k)): an approximation of A⁻¹r, float64 (``r``'s shape)."""
        r = np.asarray(r, dtype=float)
        block = r.reshape(r.shape[0], -1)
        k = block.shape[1]
        # each column scaled to unit size: single precision then never under- or overflows
        scale = np.abs(block).max(axis=0)
        scale[scale == 0] = 1.0
        x = np.empty_like(block)
        if k < BLOCK_MIN:  # one vector at a time: scipy's fast single-vector product at every level
            for j in range(k):
                x[:, j] = self._cycle(0, (block[:, j] / scale[j]).astype(self.dtype))
        else:
            for j in range(0, k, BLOCK_MAX):
                cols = slice(j, min(j + BLOCK_MAX, k))
                x[:, cols] = self._cycle(0, (block[:, cols] / scale[cols]).astype(self.dtype))
        x *= scale
        return x.reshape(r.shape)
