"""Generalised symmetric eigensolvers for K·v = λ·M·v, lowest modes first.

Four paths, chosen by size and structure:

- dense LAPACK (``eigh``) for small models or when most modes are wanted;
- shift-invert Lanczos (ARPACK) with a banded Cholesky factor of K − σM for
  banded models (a chain numbered in order is tridiagonal), O(n) per solve;
- shift-invert Lanczos with a sparse LU for anything else;
- LOBPCG preconditioned by multigrid (:mod:`flexshaft.linalg.lobpcg`) for a
  large solid part (``near_null`` given, more than :data:`LOBPCG_MIN_DOF`
  DOFs): a shift-invert step there would be a whole multigrid-CG solve per
  Lanczos vector (52 000 DOFs: 159 s for 20 modes).

Rigid-body modes are not left to round-off: the caller passes their exact
basis, they are reported at λ = 0 and the elastic modes are made
inertia-orthogonal to them.

Memory: beside ARPACK's own workspace (the same as a plain ``eigsh`` call's)
a Lanczos solve holds the factor of K − σM, its start vector and, once
ARPACK is done, the result. The passes over the shapes after the solve
(rigid-mode projection, normalisation, Rayleigh quotients) go over blocks of
rows (:func:`row_blocks`), so their temporaries are blocks, not copies of the
(n, m) shapes: at 1 M DOFs and 10 modes a copy is 80 MB.
"""

from __future__ import annotations

import contextlib
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import ModelError
from ..system.limits import check_memory, dense_memory_bytes, model_memory_bytes

__all__ = [
    "EigenSolution",
    "lowest_modes",
    "solver_failures",
    "DENSE_MAX_DOF",
    "LOBPCG_MIN_DOF",
    "column_quadratics",
    "row_blocks",
    "row_block",
]

#: Up to this many DOFs a dense solve is faster than Lanczos and gets all modes.
DENSE_MAX_DOF = 600
#: Above this many DOFs a dense solve is refused (memory and O(n³) time).
DENSE_LIMIT_DOF = 12_000
#: Largest half-bandwidth handled by the banded Cholesky path.
BANDED_MAX = 64
#: Above this many DOFs a solid part's modes (``near_null`` given) are found by LOBPCG: below it the
#: shifted stiffness is factorised (SuperLU, :data:`~flexshaft.linalg.spd.DIRECT_MAX`) and
#: shift-invert Lanczos is exact and fast.
LOBPCG_MIN_DOF = 10_000
#: Guard vectors LOBPCG iterates beside the wanted modes: the last wanted ones converge at a rate set
#: by their gap to the block's first unwanted eigenvalue (20 modes of a 230 000-DOF PTSS tube: 4
#: guards 53 iterations, 8 guards 29, 16 guards 21 - 8 the least time).
LOBPCG_GUARD = 8


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
    """max |i − j| over the stored entries of A (row blocks of a CSR matrix: no COO copy)."""
    A = sp.csr_matrix(A)
    width = 0
    for rows in row_blocks(A.shape[0]):
        block = row_block(A, rows)
        if block.nnz:
            i = np.repeat(np.arange(rows.start, rows.stop), np.diff(block.indptr))
            width = max(width, int(np.max(np.abs(i - block.indices))))
    return width


def _factor_failed(info: int, what: str):
    # K − σM with σ < 0 is positive definite whenever M is; a failure means it is not.
    raise ModelError(
        f"the shifted stiffness is not positive definite ({what} info = {info})",
        field="inertia",
        valid="a positive-definite inertia matrix (every node with inertia)",
    )


def _shifted_band(K, M, sigma: float, b: int) -> np.ndarray:
    """K − σM in LAPACK lower banded storage, ab[i, j] = (K − σM)[j + i, j], read off the diagonals.

    The diagonals of K and M are all it needs: no shifted copy of the matrices.
    """
    n = K.shape[0]
    ab = np.zeros((b + 1, n))
    for i in range(b + 1):
        ab[i, : n - i] = K.diagonal(-i)
        ab[i, : n - i] -= sigma * M.diagonal(-i)
    return ab


def _shift_invert_operator(K, M, sigma: float, bandwidth: int, near_null=None, solver: str = "auto"):
    """A LinearOperator applying (K − σM)⁻¹, and the name of the factorisation.

    Tridiagonal matrices (a chain) use LAPACK's LDLᵀ for SPD tridiagonals
    (?pttrf/?pttrs), other narrow bands the banded Cholesky (?pbtrf/?pbtrs),
    anything else a sparse LU. The LAPACK routines are called directly: the
    solve runs ~40 times per eigensolve and wrapper checks would cost more
    than the O(n) work itself. The banded paths keep only their factor.
    """
    from scipy.linalg import lapack
    from scipy.sparse.linalg import LinearOperator, splu

    n = K.shape[0]
    if bandwidth == 1:
        ab = _shifted_band(K, M, sigma, 1)
        d, e, info = lapack.dpttrf(ab[0], ab[1, :-1])
        del ab
        if info != 0:
            _factor_failed(info, "dpttrf")

        def solve(x):
            return lapack.dpttrs(d, e, x)[0]

        name = "tridiagonal LDLᵀ"
    elif bandwidth <= BANDED_MAX:
        cb, info = lapack.dpbtrf(_shifted_band(K, M, sigma, bandwidth), lower=1)
        if info != 0:
            _factor_failed(info, "dpbtrf")

        def solve(x):
            return lapack.dpbtrs(cb, x, lower=1)[0]

        name = "banded Cholesky"
    elif near_null is not None:
        # a solid part: K − σM of 3D elements has no narrow band and its LU fills in (132 000 DOFs:
        # 14 GB), so SuperLU below a few thousand DOFs and multigrid-preconditioned CG beyond; a
        # relative residual of 1e-10 moves the Ritz values by far less than the mesh's error (``solver``
        # names one of them instead)
        from .spd import SpdSolver

        spd = SpdSolver(K - sigma * M, near_null=near_null, rtol=1e-10, method=solver, what="K − σM")
        solve = spd.solve
        name = spd.method
    else:
        lu = splu((K - sigma * M).tocsc())
        solve = lu.solve
        name = "sparse LU"
    return LinearOperator((n, n), matvec=solve, dtype=float), name


#: Rows per block in the passes over the mode shapes after the solve: the temporaries are a
#: block's rows of every mode (2¹⁵ rows × 10 modes = 2.6 MB), not full-length copies of the shapes.
ROW_BLOCK = 1 << 15


def row_blocks(n: int, block: int = ROW_BLOCK):
    """Slices of ``block`` consecutive rows covering range(n)."""
    for i in range(0, n, block):
        yield slice(i, min(i + block, n))


def row_block(A: sp.csr_matrix, rows: slice) -> sp.csr_matrix:
    """Rows ``rows`` (a step-1 slice) of a CSR matrix as a CSR matrix on A's own arrays (no copy).

    Built empty and given A's arrays afterwards: scipy's constructor copies a
    slice much smaller than the array it views (its ``_prune_array``), which
    for a block of a long chain is every time.
    """
    a, b = int(A.indptr[rows.start]), int(A.indptr[rows.stop])
    block = sp.csr_matrix((rows.stop - rows.start, A.shape[1]), dtype=A.dtype)
    block.indptr = A.indptr[rows.start : rows.stop + 1] - A.indptr.dtype.type(a)
    block.indices = A.indices[a:b]
    block.data = A.data[a:b]
    return block


def column_quadratics(A, V: np.ndarray, B=None, block: int = ROW_BLOCK):
    """diag(Vᵀ A V) (and diag(Vᵀ B V) with ``B``), one pass over row blocks, shape (m,) each.

    The same sums as ``np.einsum("ij,ij->j", V, A @ V)`` without the (n, m) product.
    """
    A = sp.csr_matrix(A)
    B = None if B is None else sp.csr_matrix(B)
    qa = np.zeros(V.shape[1])
    qb = None if B is None else np.zeros(V.shape[1])
    for rows in row_blocks(V.shape[0], block):
        Vb = V[rows]
        qa += np.einsum("ij,ij->j", Vb, row_block(A, rows) @ V)
        if B is not None:
            qb += np.einsum("ij,ij->j", Vb, row_block(B, rows) @ V)
    return qa if B is None else (qa, qb)


def _elastic_shapes(V, columns, R, gram, M, K=None) -> tuple[np.ndarray, np.ndarray]:
    """The modes' final shapes: rigid modes first, then ``V[:, columns]`` cleaned, in one new array.

    The rigid modes R (n × r, with gram = RᵀMR) come out M-orthonormal; each
    elastic column v loses its rigid content R·c, c = gram⁻¹RᵀMv (M-inner
    product), and is M-normalised. With ``K``, each elastic mode's
    eigenvalue is returned as the Rayleigh quotient of the cleaned vector
    u = v − Rc, uᵀKu / uᵀMu (error squared against the vector's).

    Both quadratic forms of u follow from v's, in the one pass over the
    matrices that v's take: uᵀMu = vᵀMv − cᵀ·gram·c and
    uᵀKu = vᵀKv − 2cᵀ(KR)ᵀv + cᵀ(RᵀKR)c, exact algebra whose correction
    terms are of the size of c², tiny for a Ritz vector already nearly
    M-orthogonal to the rigid modes. A second pass then writes the result,
    block by block: the only full-length arrays made are the result and the
    rigid modes' M·R and K·R.

    Returns
    -------
    shapes : ndarray, shape (n, r + len(columns))
        C-ordered.
    values : ndarray, shape (len(columns),)
        The Rayleigh quotients (with ``K``), else empty.
    """
    n, r = R.shape
    columns = np.asarray(columns, dtype=int)
    # Row blocks of a C-ordered V are contiguous; scipy copies a whole non-contiguous operand per product.
    V = np.ascontiguousarray(V)
    if K is None:
        vmv = column_quadratics(M, V)[columns]
    else:
        vkv, vmv = column_quadratics(K, V, M)
        vkv, vmv = vkv[columns], vmv[columns]
    if r:
        W = np.linalg.inv(np.linalg.cholesky(gram)).T  # R·W is M-orthonormal
        coef = np.linalg.solve(gram, (M @ R).T @ V)[:, columns]  # rigid content of each column, r × k
        umu = vmv - np.einsum("ik,ik->k", coef, gram @ coef)
        if K is not None:
            KR = K @ R
            ukv = (KR.T @ V)[:, columns]
            rkr = R.T @ KR
            uku = vkv - 2.0 * np.einsum("ik,ik->k", coef, ukv) + np.einsum("ik,ik->k", coef, rkr @ coef)
    else:
        umu = vmv
        uku = vkv if K is not None else None
    scale = 1.0 / np.sqrt(umu)
    out = np.empty((n, r + columns.size))
    # Columns in order (ARPACK's usually are) are a slice: a view, not a gathered copy.
    k = columns.size
    picked = slice(columns[0], columns[0] + k) if k and np.all(np.diff(columns) == 1) else columns
    for rows in row_blocks(n):
        block = V[rows, picked] * scale
        if r:
            # R·c for one rigid mode (the usual) is a broadcast product; a matmul otherwise.
            block -= R[rows] * (coef[0] * scale) if r == 1 else R[rows] @ (coef * scale)
            out[rows, :r] = R[rows] * W[0, 0] if r == 1 else R[rows] @ W
        out[rows, r:] = block
    return out, (np.zeros(0) if K is None else uku / umu)


def _shift(K, M, R: np.ndarray, gram: np.ndarray, trial: np.ndarray | None = None) -> float:
    """A negative shift of the size of the lowest elastic eigenvalue.

    The Rayleigh quotient of a trial shape (made inertia-orthogonal to the
    rigid modes R, with gram = RᵀMR) bounds λ₁ from above; the smallest over
    the trial shapes (default: a ramp over the node numbering, which for a
    shaft meshed along its axis sits within a small factor of λ₁) sets the
    shift.
    """
    n = K.shape[0]
    x = np.linspace(-1.0, 1.0, n)[:, None] if trial is None else np.asarray(trial, float).reshape(n, -1)
    if R.shape[1]:
        x = x - R @ np.linalg.solve(gram, R.T @ (M @ x))
    num, den = column_quadratics(K, x, M)
    ok = den > 0
    lam = float(np.min(num[ok] / den[ok])) if ok.any() else float("nan")
    if not np.isfinite(lam) or lam <= 0.0:
        lam = float(np.max(K.diagonal() / M.diagonal()))
    return -0.1 * lam


def _lobpcg_modes(K, M, count: int, R, gram, trial, near_null, coarse, preconditioner, tol=None):
    """The ``count`` lowest elastic modes by LOBPCG (M-orthogonal to the rigid modes R), in K's
    order, and the name of the preconditioner.

    The block is the modes and :data:`LOBPCG_GUARD` guard vectors, started from the trial shapes
    and random vectors (a fixed seed: the same model gives the same digits); everything runs in the
    multigrid's ordering of the unknowns (:func:`~flexshaft.linalg.multigrid.locality_order`).
    """
    from .lobpcg import TOL, lobpcg
    from .multigrid import block_product, permuted
    from .spd import SpdSolver

    n = K.shape[0]
    k = min(count + LOBPCG_GUARD, n // 2)
    # K and M reordered (f64), the preconditioner's matrices (~1.5 x K's), and ~12 blocks of k columns
    check_memory(
        12.0 * (2 * K.nnz + M.nnz) + 8.0 * K.nnz + 8.0 * n * k * 12,
        field="count",
        value=count,
        detail=f"LOBPCG for {count} modes of {n} DOFs",
        hint="fewer modes or a coarser mesh",
    )
    if preconditioner is None:
        # K − σM with the Lanczos path's negative shift: positive definite even for a free body
        sigma = _shift(K, M, R, gram, trial)
        preconditioner = SpdSolver(
            (K - sigma * M).tocsr(), near_null=near_null, method="amg", coarse=coarse, what="K − σM"
        )
    order = preconditioner.order
    if order is None:  # a direct solver: the matrices as they are
        order = np.arange(n)
    Kp, Mp = permuted(K, order), permuted(M, order)
    rng = np.random.default_rng(0)
    start = [] if trial is None else [np.asarray(trial, dtype=float).reshape(n, -1)[order]]
    start.append(rng.standard_normal((n, max(k - sum(t.shape[1] for t in start), 0))))
    X0 = np.hstack(start)[:, :k]
    Y = R[order] if R.shape[1] else None
    result = lobpcg(
        Kp,
        Mp,
        X0,
        lambda r: preconditioner.precondition(r, ordered=True),
        count=count,
        constraints=Y,
        product=block_product,
        tol=TOL if tol is None else tol,
    )
    del Kp, Mp, X0
    if not result.converged:
        worst = float(np.nanmax(result.residuals[:count]))
        raise ModelError(
            f"LOBPCG did not converge in {result.iterations} iterations (largest relative residual "
            f"{worst:.2g} of {count} modes)",
            field="model",
            valid="a constrained, well-shaped mesh (a free body needs its rigid modes given)",
            has_value=False,
        )
    vectors = np.empty((n, count))
    vectors[order] = result.vectors[:, :count]
    return vectors, preconditioner.method


def _dense_modes(K, M, m: int, R, gram) -> tuple[np.ndarray, np.ndarray, str]:
    """The ``m`` lowest modes by LAPACK on the dense matrices (the elastic ones after R's r)."""
    n, r = K.shape[0], R.shape[1]
    if n > DENSE_LIMIT_DOF:
        raise ModelError(
            "a dense eigensolve of this size is refused",
            field="count",
            value=m,
            valid=f"at most {n // 3} modes for a model of {n} DOFs",
        )
    check_memory(
        dense_memory_bytes(n, m),
        field="count",
        value=m,
        detail=f"a dense eigen-solve of all {n} DOFs",
        hint=f"at most {n // 3} modes, which a sparse solve finds",
    )
    lam_all, vec_all = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, m - 1], check_finite=False)
    vec, _ = _elastic_shapes(vec_all, np.arange(r, m), R, gram, M)
    lam = lam_all[r:]
    name = "dense LAPACK eigh"
    return vec, lam, name


def _lanczos_modes(K, M, m: int, R, gram, trial, bandwidth, near_null, solver) -> tuple:
    """The ``m`` lowest modes by shift-invert Lanczos (ARPACK), the shift below the lowest elastic
    eigenvalue (the elastic ones after R's r)."""
    from scipy.sparse.linalg import eigsh
    from threadpoolctl import threadpool_limits

    n, r = K.shape[0], R.shape[1]
    check_memory(
        model_memory_bytes(n, K.nnz, m),
        field="count",
        value=m,
        detail=f"a Lanczos solve for {m} modes of {n} DOFs",
        hint="fewer modes",
    )
    sigma = _shift(K, M, R, gram, trial)
    b = max(half_bandwidth(K), half_bandwidth(M)) if bandwidth is None else bandwidth
    op, fact = _shift_invert_operator(K, M, sigma, b, near_null, solver)
    # ARPACK's steps are level-2 BLAS on a few long vectors: threads buy
    # nothing there, and on a busy 2-core machine they stall each other
    # (measured: 0.25 s -> 2.8 s at 1e5 DOFs). One BLAS thread is steady.
    # (Below ~1e4 DOFs setting the limit costs more than the solve.)
    limit = threadpool_limits(limits=1, user_api="blas") if n > 10_000 else nullcontext()
    # A fixed start vector: the same model gives the same digits on every run.
    v0 = np.random.default_rng(0).standard_normal(n)
    with limit:
        lam_all, vec_all = eigsh(K, k=m, M=M, sigma=sigma, which="LM", OPinv=op, v0=v0)
    del op, v0
    # The r lowest Ritz pairs are ARPACK's rigid modes: the exact ones replace them. The
    # Rayleigh quotients of the cleaned, M-normalised Ritz vectors are the eigenvalues: their
    # error is the square of the vectors', so they gain digits for one product.
    vec, lam = _elastic_shapes(vec_all, np.argsort(lam_all, kind="stable")[r:], R, gram, M, K)
    del vec_all
    name = f"shift-invert Lanczos ({fact})"
    return vec, lam, name


def lowest_modes(
    K,
    M,
    count: int,
    rigid_basis: np.ndarray | None = None,
    method: str = "auto",
    bandwidth: int | None = None,
    trial: np.ndarray | None = None,
    near_null: np.ndarray | None = None,
    coarse=None,
    preconditioner=None,
    tol: float | None = None,
    solver: str = "auto",
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
    method : {"auto", "dense", "lanczos", "lobpcg"}
        Force a path; "auto" picks by size (and LOBPCG for a solid part of more than
        :data:`LOBPCG_MIN_DOF` DOFs).
    bandwidth : int, optional
        Half-bandwidth of K and M when the caller knows it (found otherwise).
    trial : ndarray, shape (n, t), optional
        Trial shapes whose smallest Rayleigh quotient bounds the lowest
        elastic eigenvalue; it sets the shift of the Lanczos path. Default: a
        ramp over the DOF numbering, right for a chain with one DOF per node
        but far too stiff when several kinds of DOF are interleaved.
    near_null : ndarray, shape (n, k), optional
        A solid part's rigid-body motions: its shifted stiffness is then solved by
        :class:`~flexshaft.linalg.spd.SpdSolver` (multigrid beyond a few thousand DOFs) rather than
        by a sparse LU, and beyond :data:`LOBPCG_MIN_DOF` DOFs the modes are found by LOBPCG.
    coarse : CoarseSpace, optional
        The multigrid's first coarse level for LOBPCG's preconditioner
        (:func:`~flexshaft.linalg.multigrid.linear_coarse_space`: the linear elements under 10-node
        tetrahedra, which halves the iterations).
    preconditioner : SpdSolver, optional
        A multigrid solver of K (or of any K − σM, σ <= 0) already built - a Craig-Bampton
        reduction's for its constraint modes - to precondition LOBPCG with, instead of building one
        for K − σM.
    tol : float, optional
        LOBPCG's relative residual (default :data:`flexshaft.linalg.lobpcg.TOL`, eigenvalues to
        ~1e-10; a Craig-Bampton basis needs less, :data:`flexshaft.reduction.ritz.MODES_TOL`).
    solver : {"auto", "direct", "amg"}
        A solid part's (``near_null`` given) shifted solves on the Lanczos path
        (:class:`~flexshaft.linalg.spd.SpdSolver`): by size, a sparse LU, or multigrid CG.

    Returns
    -------
    EigenSolution
    """
    K = sp.csr_matrix(K)
    M = sp.csr_matrix(M)
    n = K.shape[0]
    # The caller's rigid modes as given: they are made M-orthonormal only in the result, so that
    # no second full-length copy of them sits beside the solver's workspace.
    R = np.zeros((n, 0)) if rigid_basis is None else np.asarray(rigid_basis, dtype=float)
    r = R.shape[1]
    gram = R.T @ (M @ R)
    m = min(int(count), n)
    n_el = m - r
    if method == "auto":
        method = "dense" if (n <= DENSE_MAX_DOF or m > n // 3) else "lanczos"
        if method == "lanczos" and near_null is not None and n > LOBPCG_MIN_DOF:
            method = "lobpcg"
    if method not in ("dense", "lanczos", "lobpcg"):
        raise ModelError(
            "unknown eigen-solver", field="method", value=method, valid="auto, dense, lanczos or lobpcg"
        )
    if m >= n - 1:
        method = "dense"  # Lanczos needs fewer modes than DOFs
    if n_el <= 0:
        vec, _ = _elastic_shapes(np.zeros((n, 0)), [], R, gram, M)
        lam = np.zeros(m)
        vec = vec[:, :m]
        name = "rigid only"
    elif method == "dense":
        vec, lam, name = _dense_modes(K, M, m, R, gram)
    elif method == "lobpcg":
        vec_el, fact = _lobpcg_modes(K, M, n_el, R, gram, trial, near_null, coarse, preconditioner, tol)
        vec, lam = _elastic_shapes(vec_el, np.arange(n_el), R, gram, M, K)
        del vec_el
        name = f"LOBPCG ({fact})"
    else:
        vec, lam, name = _lanczos_modes(K, M, m, R, gram, trial, bandwidth, near_null, solver)
    if n_el > 0:
        lam = np.concatenate([np.zeros(r), np.maximum(lam, 0.0)])
    rigid = np.arange(lam.size) < r
    return EigenSolution(eigenvalues=lam, vectors=vec, rigid=rigid, method=name)
