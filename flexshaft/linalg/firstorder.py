"""Eigenvalues of first-order state matrices: flexshaft's one damped eigen-solver.

A linear system's poles are the eigenvalues of its first-order state matrix: M q̈ + C q̇ + K q = 0 in
modal coordinates (the damped modes, a Campbell diagram's whirl roots at each speed with the
gyroscopic matrix in the damping), a state space's A (its poles), a speed loop closed around it
(continuous, or its discrete transition matrix per step), a state matrix identified from measured
signals (SSI). :func:`damped_eigen` solves them all. In modal coordinates it solves the balanced
matrix [[0, Ω], [−Ω, −D]] (state [Ωη, η̇]): its norm is ω_max where [[0, I], [−Ω², −D]]'s is ω_max²,
and an eigenvalue's error goes as ε times the norm.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["damped_eigen"]


def _modal_frequencies(A: np.ndarray) -> np.ndarray | None:
    """Ω of a state matrix of the modal form [[0, I], [−Ω², D]] exactly (a modal state space), else None."""
    n = A.shape[0]
    if A.ndim != 2 or A.shape != (n, n) or n % 2:
        return None
    m = n // 2
    w2 = -np.diag(A[m:, :m])
    modal = (
        np.array_equal(A[:m, :m], np.zeros((m, m)))
        and np.array_equal(A[:m, m:], np.eye(m))
        and np.array_equal(A[m:, :m], np.diag(-w2))
        and np.all(w2 >= 0)
    )
    return np.sqrt(w2) if modal else None


def damped_eigen(A=None, *, omega=None, damping=None, vectors: bool = False):
    """Eigenvalues (and right eigenvectors) of a first-order state matrix (see the module docstring).

    Given the modal coordinates (``omega`` and ``damping``), or a state matrix ``A`` of the modal form
    [[0, I], [−Ω², −D]] exactly (a modal state space, x = [η, η̇]), it solves the similar matrix
    [[0, Ω], [−Ω, −D]] (state [Ωη, η̇]): its norm is ω_max where the other's is ω_max², so a model with a
    few very stiff modes (a 6-DOF line's MHz axial modes, a flexible body's residual vectors) keeps the
    eigenvalues of its low modes to full precision (an eigenvalue's error goes as ε times the norm). A
    rigid-body mode (ω = 0) keeps its roots 0 and −rᵀCr either way. Any other ``A`` (a closed loop, a
    discrete loop's transition matrix) is solved as it is.

    Parameters
    ----------
    A : ndarray, shape (n, n), optional
        The state matrix: ẋ = A x (eigenvalues in 1/s), or x_{k+1} = A x_k of a discrete loop
        (eigenvalues per step).
    omega : ndarray, shape (m,), optional
        Instead of ``A``: the modal coordinates' undamped circular frequencies ω, rad/s (>= 0) ...
    damping : ndarray, shape (m, m), optional
        ... and their damping matrix D, 1/s (ΦᵀCΦ of mass-normalised modes, with Ω_shaft·ΦᵀGΦ added for
        a spinning line's gyroscopic forces): η̈ + D η̇ + Ω² η = 0.
    vectors : bool
        Also return the right eigenvectors.

    Returns
    -------
    ndarray, shape (2m,) or (n,)
        The eigenvalues λ (1/s; per step for a discrete loop), complex in conjugate pairs and real
        roots, in LAPACK's order (a real dtype when numpy finds them all real, eigenvalues only).
    ndarray of complex, shape (2m, 2m) or (n, n)
        With ``vectors``: the right eigenvectors of the matrix solved, one per column (for the modal
        form the balanced matrix's, z = [Ωη, η̇]: the velocity half has the mode's shape).

    Raises
    ------
    numpy.linalg.LinAlgError
        For a matrix with an entry that is not a number (checked here, not by LAPACK: its complaint
        about a NaN argument goes to stdout), or when LAPACK does not converge.
    """
    if A is None:
        W, D = np.diag(np.asarray(omega, dtype=float)), np.asarray(damping)
    else:
        A = np.asarray(A)
        w = _modal_frequencies(A)
        W, D = (None, None) if w is None else (np.diag(w), -A[w.size :, w.size :])
    if W is not None:
        A = np.block([[np.zeros_like(W), W], [-W, -D]])
    if not np.all(np.isfinite(A)):
        raise np.linalg.LinAlgError(
            "the first-order matrix overflows (damping or gains far out of scale with the model)"
        )
    if vectors:
        return sla.eig(A, check_finite=False)
    return np.linalg.eigvals(A)
