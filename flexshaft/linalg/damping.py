"""Damping models: modal damping set per mode, and Rayleigh damping.

Modal damping with ratios ξ_i on the elastic modes φ_i (inertia-normalised) of
a model (K, M) is the matrix

    C = M · Φ · diag(2 ξ_i ω_i) · Φᵀ · M,

which makes ΦᵀCΦ = diag(2 ξ_i ω_i) and leaves rigid-body modes undamped.
Rayleigh damping C = αM + βK gives ξ_i = α/(2ω_i) + βω_i/2.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import ModelError
from ..threads import follows_policy
from ..validation import check_real

__all__ = ["modal_damping_matrix", "rayleigh_coefficients", "rayleigh_ratio"]

# Eigenvalues below this fraction of the largest are rigid-body modes of a
# free part; a part of a few thousand elements has λ1/λmax ~ 1e-7, far above.
_RIGID_TOL = 1e-10


def dense(A) -> np.ndarray:
    """A sparse or dense matrix as a dense float array."""
    return np.asarray(A.toarray() if hasattr(A, "toarray") else A, dtype=float)


@follows_policy
def modal_damping_matrix(K, M, ratios) -> np.ndarray:
    """Dense damping matrix that puts ``ratios`` on the elastic modes of (K, M).

    Parameters
    ----------
    K, M : array_like, shape (n, n)
        Stiffness (N·m/rad) and inertia (kg·m²), symmetric; M positive definite.
    ratios : float or array_like
        Damping ratio per elastic mode (fractions), lowest mode first; a scalar
        applies to all. An array shorter than the number of elastic modes
        leaves the remaining modes undamped.

    Returns
    -------
    ndarray, shape (n, n)
        Damping matrix, N·m·s/rad.
    """
    K, M = dense(K), dense(M)
    lam, phi = sla.eigh(K, M)
    lam_max = max(float(lam[-1]), 0.0)
    elastic = lam > _RIGID_TOL * lam_max
    omega = np.sqrt(lam[elastic])
    xi = np.asarray(ratios, dtype=float)
    if xi.ndim == 0:
        xi = np.full(omega.size, float(xi))
    else:
        xi = np.concatenate([xi, np.zeros(max(0, omega.size - xi.size))])[: omega.size]
    if np.any(~np.isfinite(xi)) or np.any(xi < 0):
        raise ModelError(
            "damping ratios must be finite and >= 0",
            field="ratios",
            valid="fractions >= 0 (0.0053 for 0.53 %)",
        )
    MPhi = M @ phi[:, elastic]
    C = (MPhi * (2.0 * xi * omega)) @ MPhi.T
    return 0.5 * (C + C.T)


def rayleigh_coefficients(f1_hz: float, ratio1: float, f2_hz: float, ratio2: float) -> tuple[float, float]:
    """α and β of C = αM + βK that give two target ratios at two frequencies.

    Parameters
    ----------
    f1_hz, f2_hz : float
        Distinct frequencies, Hz, > 0.
    ratio1, ratio2 : float
        Target damping ratios (fractions) at those frequencies.

    Returns
    -------
    alpha : float
        1/s.
    beta : float
        s.
    """
    f1 = check_real(f1_hz, "f1_hz", "Hz", lo=0.0, lo_open=True)
    f2 = check_real(f2_hz, "f2_hz", "Hz", lo=0.0, lo_open=True)
    z1 = check_real(ratio1, "ratio1", "", lo=0.0)
    z2 = check_real(ratio2, "ratio2", "", lo=0.0)
    if f1 == f2:
        raise ModelError(
            "the two frequencies must differ",
            field="f2_hz",
            value=f2,
            unit="Hz",
            valid=f"a frequency other than f1_hz = {f1:g} Hz",
        )
    w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
    # ξ = α/(2ω) + βω/2 at both frequencies, solved in closed form.
    beta = 2.0 * (z2 * w2 - z1 * w1) / (w2**2 - w1**2)
    alpha = 2.0 * w1 * w2 * (z1 * w2 - z2 * w1) / (w2**2 - w1**2)
    return float(alpha), float(beta)


def rayleigh_ratio(alpha: float, beta: float, f_hz):
    """Damping ratio ξ = α/(2ω) + βω/2 of Rayleigh damping at ``f_hz`` (Hz)."""
    w = 2 * np.pi * np.asarray(f_hz, dtype=float)
    return alpha / (2 * w) + beta * w / 2
