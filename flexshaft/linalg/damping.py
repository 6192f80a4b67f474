"""Damping models: modal damping set per mode, and Rayleigh damping.

Modal damping with ratios ξ_i on the elastic modes φ_i (inertia-normalised) of
a model (K, M) is the matrix

    C = M · Φ · diag(2 ξ_i ω_i) · Φᵀ · M,

which makes ΦᵀCΦ = diag(2 ξ_i ω_i) and leaves rigid-body modes undamped.
Rayleigh damping C = αM + βK gives ξ_i = α/(2ω_i) + βω_i/2. Its inertia term αM would also
damp a free chain's rigid-body rotation - a drag to ground of α·J·ω that no material has (at the
test bench's α ≈ 3.7 1/s it holds the spinning drivetrain near standstill). flexshaft takes
Rayleigh damping on the deformation only, as the modal form C_η = diag(2ξω) does with ξ = 0 on
the 0 Hz mode: :func:`modal_damping_block` removes αM's part on the rigid-body modes.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import ModelError
from ..system.threads import follows_policy
from ..validation import (  # the largest Rayleigh coefficients are the validation's, named here too
    FRACTION,
    RAYLEIGH_ALPHA,
    RAYLEIGH_ALPHA_MAX,
    RAYLEIGH_BETA,
    RAYLEIGH_BETA_MAX,
    check_frequency,
)

__all__ = [
    "modal_damping_matrix",
    "modal_damping_block",
    "rayleigh_coefficients",
    "frequency_pair",
    "rayleigh_ratio",
    "check_rayleigh",
    "RAYLEIGH_ALPHA_MAX",
    "RAYLEIGH_BETA_MAX",
]


# Eigenvalues below this fraction of the largest are rigid-body modes of a
# free part; a part of a few thousand elements has λ1/λmax ~ 1e-7, far above.
_RIGID_TOL = 1e-10


def dense(A) -> np.ndarray:
    """A sparse or dense matrix as a dense float array."""
    return np.asarray(A.toarray() if hasattr(A, "toarray") else A, dtype=float)


def modal_damping_block(C, Phi: np.ndarray, rigid: np.ndarray, alpha: float = 0.0) -> np.ndarray:
    """The damping matrix in modal coordinates, ΦᵀCΦ (symmetric part), N·m·s/rad per unit mass.

    Parameters
    ----------
    C : sparse or dense matrix, shape (n, n), or None
        The model's damping, N·m·s/rad, including Rayleigh's αM + βK.
    Phi : ndarray, shape (n, m)
        Inertia-normalised modes (ΦᵀMΦ = I), rigid-body modes among them.
    rigid : ndarray of bool, shape (m,)
        Which columns of ``Phi`` are rigid-body modes.
    alpha : float
        The Rayleigh inertia coefficient α in ``C``, 1/s.

    Returns
    -------
    ndarray, shape (m, m)
        ΦᵀCΦ with α taken off the rigid-body block: αΦᵀMΦ = αI there (inertia-normalised), so
        subtracting αI leaves the rigid-body modes what every other damper gives them (none: a
        damper between two stations does not see a rigid rotation) and the elastic modes exactly
        as they were - Rayleigh damping on the deformation only (see the module docstring).
    """
    m = Phi.shape[1]
    if C is None:
        return np.zeros((m, m))
    Cm = Phi.T @ (C @ Phi)
    Cm = 0.5 * (Cm + Cm.T)
    rigid = np.asarray(rigid, dtype=bool)
    if alpha and rigid.any():
        idx = np.flatnonzero(rigid)
        Cm[idx, idx] -= alpha
    return Cm


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


def frequency_pair(f1_hz, f2_hz, names: tuple[str, str] = ("f1_hz", "f2_hz")) -> tuple[float, float]:
    """The two distinct frequencies, Hz, > 0, a Rayleigh fit is stated at (``names``: their fields)."""
    f1 = check_frequency(f1_hz, names[0], lo_open=True)  # ω² of 1e300 Hz overflowed
    f2 = check_frequency(f2_hz, names[1], lo_open=True)
    if f1 == f2:
        raise ModelError(
            "the two frequencies must differ",
            field=names[1],
            value=f2,
            unit="Hz",
            valid=f"a frequency other than {names[0]} = {f1:g} Hz",
        )
    return f1, f2


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
    f1, f2 = frequency_pair(f1_hz, f2_hz)
    z1 = FRACTION.check(ratio1, "ratio1")
    z2 = FRACTION.check(ratio2, "ratio2")
    w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
    # ξ = α/(2ω) + βω/2 at both frequencies, solved in closed form.
    beta = 2.0 * (z2 * w2 - z1 * w1) / (w2**2 - w1**2)
    alpha = 2.0 * w1 * w2 * (z1 * w2 - z2 * w1) / (w2**2 - w1**2)
    return float(alpha), float(beta)


def check_rayleigh(alpha: object, beta: object, field: str = "rayleigh") -> tuple[float, float]:
    """``(alpha, beta)`` as floats, each from 0 to :data:`RAYLEIGH_ALPHA_MAX` / :data:`RAYLEIGH_BETA_MAX`.

    Parameters
    ----------
    alpha, beta : object
        The coefficients of C = αM + βK as given, 1/s and s.
    field : str
        Their table's name, for messages (``"rayleigh"`` -> ``rayleigh.alpha``).
    """
    return RAYLEIGH_ALPHA.check(alpha, f"{field}.alpha"), RAYLEIGH_BETA.check(beta, f"{field}.beta")


def rayleigh_ratio(alpha: float, beta: float, f_hz):
    """Damping ratio ξ = α/(2ω) + βω/2 of Rayleigh damping at ``f_hz`` (Hz)."""
    w = 2 * np.pi * np.asarray(f_hz, dtype=float)
    return alpha / (2 * w) + beta * w / 2
