"""The 2-node torsion element (one rotation θx per node).

With linear shape functions over an element of torsional stiffness ``k`` and
axial mass moment of inertia ``j``:

- stiffness           k · [[1, -1], [-1, 1]],  k = G·Ip/L
- consistent inertia  j · [[1/3, 1/6], [1/6, 1/3]]
- lumped inertia      j · [[1/2, 0], [0, 1/2]]

All functions are vectorised: given arrays of length ``n`` they return arrays
of shape ``(n, 2, 2)``; given scalars, ``(2, 2)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["torsion_stiffness", "torsion_consistent_inertia", "torsion_lumped_inertia"]

_K = np.array([[1.0, -1.0], [-1.0, 1.0]])
_M_CONSISTENT = np.array([[1.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 1.0 / 3.0]])
_M_LUMPED = np.array([[0.5, 0.0], [0.0, 0.5]])


def _scaled(pattern: np.ndarray, factor) -> np.ndarray:
    f = np.asarray(factor, dtype=float)
    return f[..., None, None] * pattern


def torsion_stiffness(k) -> np.ndarray:
    """Element stiffness matrix.

    Parameters
    ----------
    k : float or array_like
        Torsional stiffness of the element end to end, N·m/rad.

    Returns
    -------
    ndarray, shape (..., 2, 2)
        N·m/rad.
    """
    return _scaled(_K, k)


def torsion_consistent_inertia(j) -> np.ndarray:
    """Consistent inertia matrix (linear shape functions).

    Parameters
    ----------
    j : float or array_like
        Axial mass moment of inertia of the element, kg·m².

    Returns
    -------
    ndarray, shape (..., 2, 2)
        kg·m².
    """
    return _scaled(_M_CONSISTENT, j)


def torsion_lumped_inertia(j) -> np.ndarray:
    """Lumped inertia matrix: half the element's inertia on each node, kg·m²."""
    return _scaled(_M_LUMPED, j)
