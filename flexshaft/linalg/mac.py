"""The modal assurance criterion (MAC): how alike two mode shapes are, whatever their scale.

For shapes a and b (real or complex) and an optional weighting M (Hermitian, positive semi-definite:
a model's inertia matrix),

    ``MAC(a, b) = |aᴴ M b|² / ((aᴴ M a) · (bᴴ M b))``,

M the identity when not given (Allemang's MAC). It is 1 for shapes that agree up to a complex factor
and 0 for orthogonal ones. Weighted by the inertia matrix the modes of a model are orthogonal in, two
different modes have MAC 0 exactly; unweighted, two modes of a finely meshed chain can look 90 % alike
(the many nodes of the long shafts barely move in either, the few heavy ones that differ count once).
Measured shapes, known at a few stations only, are compared unweighted.

This is flexshaft's one MAC: the identification's stabilisation and pairing, the calibration's mode
tracking and shape checks, and the damped modes' pairing with the undamped ones all call it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mac"]


def mac(a, b, M=None):
    """The MAC of every column of ``a`` with every column of ``b``.

    Parameters
    ----------
    a : array_like, shape (n,) or (n, p)
        Shapes, one per column (a 1-D array is one shape); real or complex, any units.
    b : array_like, shape (n,) or (n, q)
        Shapes, as ``a``.
    M : sparse or dense matrix, shape (n, n), optional
        Hermitian positive semi-definite weighting (the inertia matrix, kg·m²); the identity if not
        given.

    Returns
    -------
    float or ndarray, shape (p, q), (p,) or (q,)
        ``|aᴴMb|² / ((aᴴMa)(bᴴMb))``, in [0, 1] (dimensionless); a float when ``a`` and ``b`` are both
        1-D, and the axis of a 1-D argument dropped otherwise. 0 where either shape has no norm
        (a zero vector, or one in M's null space): it resembles nothing.
    """
    a, b = np.asarray(a), np.asarray(b)
    A = a[:, None] if a.ndim == 1 else a
    B = b[:, None] if b.ndim == 1 else b
    if M is None:
        num = np.abs(A.conj().T @ B) ** 2
        den = np.outer(np.sum(np.abs(A) ** 2, axis=0), np.sum(np.abs(B) ** 2, axis=0))
    else:
        MA, MB = M @ A, M @ B
        num = np.abs(MA.conj().T @ B) ** 2  # aᴴMb = (Ma)ᴴb: M is Hermitian
        # .conj() and np.real return real arrays' values as they are: real shapes stay real
        den = np.outer(
            np.real(np.einsum("ij,ij->j", A.conj(), MA)), np.real(np.einsum("ij,ij->j", B.conj(), MB))
        )
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 0, num / den, 0.0)
    if a.ndim == 1 and b.ndim == 1:
        return float(out[0, 0])
    if a.ndim == 1:
        return out[0]
    if b.ndim == 1:
        return out[:, 0]
    return out
