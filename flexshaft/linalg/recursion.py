"""A discrete linear recursion run in blocks through the Schur form of its matrix.

``x_{k+1} = F x_k + G w_k``, ``y_k = H x_k + E w_k``: with ``F = U T Uᴴ`` (complex Schur, T upper
triangular, U unitary) the coordinates ``z = Uᴴ x`` obey ``z_{k+1} = T z_k + Uᴴ G w_k``, solved from
the last coordinate up: each is a scalar first-order recursion (``scipy.signal.lfilter``, compiled)
driven by its input and the coordinates below it, already known at every step. Unlike an
eigenvector basis this needs nothing of F: a defective F (a free drivetrain's rigid-body angle and
speed, a slipping coupling's second free rotation) is as well conditioned as any, and U is unitary,
so no digits are lost going in and out. Cost per block of L steps: n scalar recursions and about
n²/2 multiply-adds per step.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.signal import lfilter

__all__ = ["TriangularRecursion"]


class TriangularRecursion:
    """``x_{k+1} = F x_k + G w_k``, ``y_k = H x_k + E w_k`` in blocks (module docstring).

    Parameters
    ----------
    F : ndarray, shape (n, n)
    G : ndarray, shape (n, p)
    H : ndarray, shape (q, n)
    E : ndarray, shape (q, p)
    """

    def __init__(self, F, G, H, E) -> None:
        T, U = sla.schur(np.asarray(F, dtype=float), output="complex")
        self.F, self.G, self.H, self.E = F, G, H, E
        self.T, self.U = T, U
        self.diag = np.diag(T).copy()
        self.GU = U.conj().T @ G
        self.HU = H @ U

    def block(self, x0: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outputs at steps 0 … L−1 of a block starting at state ``x0`` under inputs ``W`` (L, p),
        and the state after it (step L)."""
        L, n = W.shape[0], self.T.shape[0]
        z0 = self.U.conj().T @ x0
        D = W @ self.GU.T
        Z = np.empty((L + 1, n), dtype=complex)
        Z[0] = z0
        T = self.T
        for i in range(n - 1, -1, -1):
            d = D[:, i]
            if i < n - 1:
                d = d + Z[:L, i + 1 :] @ T[i, i + 1 :]
            lam = self.diag[i]
            Z[1:, i] = lfilter([1.0], [1.0, -lam], d, zi=[lam * z0[i]])[0]
        Y = (Z[:L] @ self.HU.T).real + W @ self.E.T
        self._Z = Z
        return Y, (self.U @ Z[L]).real

    def state_at(self, j: int) -> np.ndarray:
        """The state at step ``j`` of the last block run (0 … its length): a block cut short needs no
        second run."""
        return (self.U @ self._Z[j]).real

    def one(self, x: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One step by the matrices themselves: the outputs at a state ``x`` under input ``w``, and the
        next state (cheaper than a block of one)."""
        return self.H @ x + self.E @ w, self.F @ x + self.G @ w
