"""Large sparse symmetric positive definite systems K x = b: the stiffness of a solid part.

A solid part's stiffness (10-node tetrahedra, three displacements a node) has up to millions of
unknowns and a bandwidth no reordering makes small: a sparse LU of 132 000 unknowns took 284 s and
14 GB on these machines, while conjugate gradients preconditioned by multigrid take seconds to a
minute (:mod:`flexshaft.linalg.multigrid`). Smoothed aggregation needs the operator's near-null space
to build good coarse levels: for elasticity the six rigid-body modes, computed from the node
coordinates (:func:`rigid_body_modes`); without them it needs ten times the iterations. Given the
mesh's linear elements as the first coarse level (``coarse``,
:func:`~flexshaft.linalg.multigrid.linear_coarse_space`) it needs half the iterations again. Small
systems (up to :data:`DIRECT_MAX` unknowns) are factorised directly (SuperLU), which is then faster
and exact to round-off.

:class:`SpdSolver` is built once per matrix (the multigrid hierarchy or the factorisation) and solves
any number of right-hand sides, all at once (:func:`block_cg`) - a Craig-Bampton reduction's one per
interface DOF, a twist test's six loads. It also preconditions the eigen-solver
(:meth:`SpdSolver.precondition`), and can start its solves from known modes
(:meth:`SpdSolver.start_from_modes`). A PTSS part 1 meshed into 1 035 000 DOFs: the twist test (a
hierarchy in 7-11 s, six loads to 1e-8 in 20 iterations, 43-48 s) against 347 s for 417 000 DOFs
with pyamg's own CG, one load after the other, before.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ModelError
from .multigrid import CoarseSpace, Multigrid, block_product, locality_order, permuted, permuted_coarse

__all__ = [
    "DIRECT_MAX",
    "SolveReport",
    "SpdSolver",
    "block_cg",
    "rigid_body_modes",
    "rigid_displacements",
    "rigid_motions_at",
]

#: Up to this many unknowns a sparse LU (SuperLU) is the solver: a 3D mesh's LU grows as n^(4/3) in
#: memory and n² in time (132 000 unknowns: 284 s and 14 GB), so beyond a few thousand multigrid is
#: faster.
DIRECT_MAX = 10_000
#: The relative residual ‖b − Kx‖/‖b‖ conjugate gradients stop at unless told. A compliance read from x
#: (bᵀx, an energy) has the square of the error in energy norm: on a 230 000-DOF PTSS tube the twist
#: test's 6 x 6 compliance agreed with a 1e-12 solve to 1.1e-9 at 1e-8 (and 1e-10; 3.9e-8 at 1e-6),
#: which is the round-off the true residual itself stalls at (~1e-9: the end faces' masters make
#: cond(K) ~1e9), so a tighter target only adds iterations.
RTOL = 1e-8
#: The relative residual an LU solve must reach: round-off leaves ~cond(K)·1e-16, 1e-12 or less for a
#: constrained part; a free body's singular K (which SuperLU's pivoting does not always catch) leaves
#: O(1).
DIRECT_RESIDUAL = 1e-8
#: Conjugate-gradient iterations allowed: smoothed aggregation with the rigid-body modes converges in
#: tens of iterations on elasticity (53 at 863 000 unknowns); hundreds mean the hierarchy is broken.
MAX_ITERATIONS = 1000


def rigid_body_modes(nodes) -> np.ndarray:
    """The six rigid-body motions of a point set, node-major (u_x, u_y, u_z per node).

    Parameters
    ----------
    nodes : array (n, 3)
        Coordinates, m.

    Returns
    -------
    ndarray (3n, 6)
        Translations along x, y, z, then rotations about axes through the centroid parallel to x, y, z
        (u = θ × (x − c)), the rotations scaled by the point set's RMS radius so all six columns have
        comparable size (smoothed aggregation orthonormalises them per aggregate; a badly scaled
        column costs accuracy there).
    """
    x = np.asarray(nodes, dtype=float)
    return rigid_displacements(x, *_frame(x)).reshape(3 * x.shape[0], 6)


def rigid_motions_at(nodes, points) -> np.ndarray:
    """The six rigid-body motions of :func:`rigid_body_modes` seen at 6-DOF points (master nodes).

    Parameters
    ----------
    nodes : array (n, 3)
        The body's coordinates, m: they fix the centroid and the scale of the rotations.
    points : array (p, 3)
        Where the motions are read, m.

    Returns
    -------
    ndarray (6p, 6)
        Per point its translation u_x, u_y, u_z and rotation θ_x, θ_y, θ_z under each of the six columns
        of :func:`rigid_body_modes`.
    """
    x = np.asarray(nodes, dtype=float)
    centre, scale = _frame(x)
    p = np.atleast_2d(np.asarray(points, dtype=float))
    out = np.zeros((p.shape[0], 6, 6))
    out[:, :3] = rigid_displacements(p, centre, scale)
    out[:, 3:, 3:] = np.eye(3) / scale
    return out.reshape(6 * p.shape[0], 6)


def _frame(x: np.ndarray) -> tuple[np.ndarray, float]:
    """The centroid of a point set and its RMS radius about it (the rotations' scale)."""
    centre = x.mean(axis=0)
    return centre, float(np.sqrt(np.mean(np.sum((x - centre) ** 2, axis=1)))) or 1.0


def rigid_displacements(x: np.ndarray, centre: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """(n, 3, 6): the displacement of each point x under the three translations and the rotations
    θ = e/scale about ``centre``: u = t + θ × (x − centre)."""
    r = x - centre
    B = np.zeros((x.shape[0], 3, 6))
    B[:, 0, 0] = B[:, 1, 1] = B[:, 2, 2] = 1.0
    # θ × r for θ = e_x, e_y, e_z
    B[:, 1, 3], B[:, 2, 3] = -r[:, 2], r[:, 1]
    B[:, 0, 4], B[:, 2, 4] = r[:, 2], -r[:, 0]
    B[:, 0, 5], B[:, 1, 5] = -r[:, 1], r[:, 0]
    B[:, :, 3:] /= scale
    return B


@dataclass(frozen=True)
class SolveReport:
    """How the last solve went.

    Attributes
    ----------
    method : str
        ``"SuperLU"`` or ``"CG with smoothed-aggregation AMG (pyamg), N levels"``.
    iterations : int
        Conjugate-gradient iterations of the slowest right-hand side (0 for the direct solver).
    residual : float
        The largest relative residual ‖b − Kx‖/‖b‖ over the right-hand sides.
    setup_s, solve_s : float
        Seconds spent building the hierarchy (or factorising) and solving.
    """

    method: str
    iterations: int
    residual: float
    setup_s: float
    solve_s: float


class _Count:
    """A CG callback that counts the iterations."""

    def __init__(self) -> None:
        self.n = 0

    def __call__(self, _x) -> None:
        self.n += 1


class SpdSolver:
    """Solves K x = b for a sparse symmetric positive definite K (module docstring).

    Parameters
    ----------
    K : sparse matrix (n, n)
        Symmetric positive definite (constrained: no rigid-body motion left free).
    near_null : ndarray (n, k), optional
        The near-null space for multigrid (:func:`rigid_body_modes` restricted to K's unknowns);
        without it, constant vectors per unknown (a poor hierarchy for elasticity).
    rtol : float
        Relative residual at which conjugate gradients stop.
    method : {"auto", "direct", "amg"}
        ``"auto"``: direct up to :data:`DIRECT_MAX` unknowns, multigrid beyond.
    what : str
        What the matrix is, for error messages (``"part 2's solid stiffness"``).
    coarse : CoarseSpace, optional
        The multigrid's first coarse level (:func:`~flexshaft.linalg.multigrid.linear_coarse_space`
        for 10-node tetrahedra: the linear elements under them).

    Attributes
    ----------
    order : ndarray of int or None
        The multigrid path's ordering of the unknowns (its matrix is ``K[order][:, order]``); None
        for the direct solver.
    method : str
    report : SolveReport or None
        How the last solve went.
    """

    def __init__(
        self,
        K,
        *,
        near_null=None,
        rtol: float = RTOL,
        method: str = "auto",
        what: str = "K",
        coarse: CoarseSpace | None = None,
    ):
        K = sp.csr_matrix(K, dtype=float)
        n = K.shape[0]
        if K.shape != (n, n) or n == 0:
            raise ModelError(f"{what} is not square", field="K", value=K.shape, valid="an (n, n) matrix")
        if method not in ("auto", "direct", "amg"):
            raise ModelError("unknown solver", field="method", value=method, valid="auto, direct or amg")
        self.K, self.rtol, self.what = K, float(rtol), what
        self.direct = method == "direct" or (method == "auto" and n <= DIRECT_MAX)
        self.order: np.ndarray | None = None
        start = time.perf_counter()
        if self.direct:
            try:
                self._lu = spla.splu(K.tocsc())
            except RuntimeError as err:  # "Factor is exactly singular"
                raise ModelError(
                    f"{what} is singular ({err}): a rigid-body motion is left free",
                    field="K",
                    valid="a constrained stiffness (clamp an interface)",
                    has_value=False,
                ) from None
            self.method = "SuperLU"
        else:
            # the multigrid and the iterations run on the unknowns reordered for locality
            self.order = locality_order(K)
            self.K = permuted(K, self.order)
            B = (
                None
                if near_null is None
                else np.ascontiguousarray(np.asarray(near_null, dtype=float)[self.order])
            )
            self._mg = Multigrid(
                self.K,
                near_null=B,
                coarse=None if coarse is None else permuted_coarse(coarse, self.order),
            )
            first = "the linear elements, then " if coarse is not None else ""
            self.method = (
                f"block CG with multigrid: {first}smoothed-aggregation AMG (pyamg), "
                f"{len(self._mg.sizes)} levels"
            )
        self.setup_s = time.perf_counter() - start
        self.report: SolveReport | None = None
        self._modes = None

    def start_from_modes(self, shapes, eigenvalues) -> None:
        """Start later solves from what the given modes carry of the solution.

        With Φ M-orthonormal eigenvectors of (K, M) and Λ their eigenvalues, K⁻¹ = Σ φφᵀ/λ over all
        modes, so x₀ = Φ Λ⁻¹ Φᵀ b is the part of K⁻¹b along the given ones, exactly: conjugate
        gradients only add the rest. A load that mostly excites the lowest modes - the inertia
        loads of a Craig-Bampton reduction's residual vectors - then needs fewer iterations (the
        modes' residual 1e-6 leaves a first guess as good; a poor one costs an iteration or two, it
        cannot make the solution wrong). Ignored by the direct solver.

        Parameters
        ----------
        shapes : ndarray (n, m)
            M-orthonormal eigenvectors of K.
        eigenvalues : ndarray (m,)
            Their eigenvalues, > 0.
        """
        lam = np.asarray(eigenvalues, dtype=float)
        shapes = np.asarray(shapes, dtype=float)
        if self.direct or not lam.size:
            self._modes = None
            return
        if shapes.shape != (self.K.shape[0], lam.size) or not np.all(lam > 0):
            raise ModelError(
                "need M-orthonormal shapes, one column per eigenvalue > 0",
                field="modes",
                value=f"{shapes.shape} shapes, {lam.size} eigenvalues",
                valid=f"({self.K.shape[0]}, m) shapes and m eigenvalues > 0",
            )
        self._modes = (np.ascontiguousarray(shapes[self.order]), lam)

    def _first_guess(self, cols):
        """Φ Λ⁻¹ Φᵀ b for the columns b (in the solver's order), or None (:meth:`start_from_modes`)."""
        if self._modes is None:
            return None
        shapes, lam = self._modes
        return shapes @ ((shapes.T @ cols) / lam[:, None])

    def precondition(self, r, *, ordered: bool = False) -> np.ndarray:
        """An approximation of K⁻¹r ((n,) or (n, k)): one multigrid V-cycle, or the LU solve.

        With ``ordered`` r's rows are already in :attr:`order` (and so is the result).
        """
        r = np.asarray(r, dtype=float)
        if self.direct:
            return self._lu.solve(r)
        if ordered:
            return self._mg.apply(r)
        x = np.empty_like(r)
        x[self.order] = self._mg.apply(r[self.order])
        return x

    def solve(self, b) -> np.ndarray:
        """x with K x = b for each column of ``b`` ((n,) or (n, k)), with :attr:`report` set."""
        b = np.asarray(b, dtype=float)
        cols = b.reshape(b.shape[0], -1)
        cols = np.ascontiguousarray(cols if self.order is None else cols[self.order])
        start = time.perf_counter()
        norms = np.linalg.norm(cols, axis=0)
        x = np.zeros_like(cols)
        iterations = 0
        nonzero = np.flatnonzero(norms > 0)
        if nonzero.size and self.direct:
            x[:, nonzero] = self._lu.solve(cols[:, nonzero])
        elif nonzero.size:
            # all right-hand sides at once: every product is a sparse matrix times a block
            with np.errstate(all="ignore"):  # a singular K breaks CG: the check says so
                x[:, nonzero], iterations = block_cg(
                    self.K,
                    cols[:, nonzero],
                    self._mg.apply,
                    self.rtol,
                    MAX_ITERATIONS,
                    self._first_guess(cols[:, nonzero]),
                )
        worst = 0.0
        if nonzero.size:
            res = (
                np.linalg.norm(cols[:, nonzero] - block_product(self.K, x[:, nonzero]), axis=0)
                / norms[nonzero]
            )
            worst = float(np.max(res)) if np.all(np.isfinite(res)) else float("nan")
        # CG stops on its recursively updated residual; the true one, computed here, drifts from it by
        # the round-off of the iterations (1e-11 seen against 1e-12 asked): 100x is that drift, not a
        # failure to converge (which leaves residuals of order 1)
        if not worst <= (DIRECT_RESIDUAL if self.direct else 100 * self.rtol):  # NaN too
            how = (
                "the LU solve left"
                if self.direct
                else f"conjugate gradients reached in {iterations} iterations"
            )
            raise ModelError(
                f"{self.what}: {how} a relative residual of {worst:.3g}: singular or near it",
                field="K",
                valid="a constrained, well-shaped mesh (a free or degenerate part has no solution)",
                has_value=False,
            )
        self.report = SolveReport(self.method, iterations, worst, self.setup_s, time.perf_counter() - start)
        if self.order is not None:
            x[self.order] = x.copy()
        return x.reshape(b.shape)


def block_cg(A, B, precondition, rtol: float, maxiter: int, X0=None) -> tuple[np.ndarray, int]:
    """Preconditioned conjugate gradients for A X = B, all columns at once.

    Each column runs its own recurrence (its own step lengths: not block CG's shared Krylov space,
    which needs rank-revealing care for a few per cent fewer iterations here), but every product
    with A and every preconditioning is one block operation
    (:func:`~flexshaft.linalg.multigrid.block_product`); a column leaves the block when its residual
    reaches ``rtol`` of its right-hand side. The step β is Polak-Ribière's, zᵀ(r − r_old)/z_oldᵀr_old,
    which keeps CG converging with a preconditioner computed in single precision (not exactly
    linear). The work arrays are updated in place: at a million unknowns a block of six columns is
    48 MB, which the C library maps afresh for every new array (page faults: 20 % of the solve).

    Returns
    -------
    X : ndarray (n, k)
    iterations : int
        Iterations of the slowest column (maxiter when one did not converge).
    """
    X = np.zeros_like(B)
    target = rtol * np.linalg.norm(B, axis=0)
    active = np.flatnonzero(target > 0)  # a zero right-hand side has the zero solution
    if not active.size:
        return X, 0
    target = target[active]
    R = np.ascontiguousarray(B[:, active])
    if X0 is None:
        Xa = np.zeros((B.shape[0], active.size))  # the active columns' solutions
    else:  # from a first guess: its residual
        Xa = np.ascontiguousarray(X0[:, active], dtype=float)
        R -= block_product(A, Xa)
    Z = precondition(R)
    P = Z.copy()
    rz = np.einsum("ij,ij->j", R, Z)
    R_old, tmp = np.empty_like(R), np.empty_like(R)
    it = 0
    for it in range(1, maxiter + 1):  # noqa: B007 (the count is the result's)
        Q = block_product(A, P)
        alpha = rz / np.einsum("ij,ij->j", P, Q)
        np.multiply(P, alpha, out=tmp)
        Xa += tmp
        R_old[...] = R
        np.multiply(Q, alpha, out=tmp)
        R -= tmp
        del Q
        done = np.linalg.norm(R, axis=0) <= target
        if done.all() or not np.all(np.isfinite(alpha)):
            break
        if done.any():  # the converged columns leave the block
            X[:, active[done]] = Xa[:, done]
            keep = ~done
            active, rz, target = active[keep], rz[keep], target[keep]
            Xa, R, R_old, P = Xa[:, keep], R[:, keep], R_old[:, keep], P[:, keep]
            tmp = np.empty_like(R)
        Z = precondition(R)
        np.subtract(R, R_old, out=tmp)
        beta = np.einsum("ij,ij->j", Z, tmp) / rz
        rz = np.einsum("ij,ij->j", R, Z)
        P *= beta
        P += Z
    X[:, active] = Xa
    return X, it
