"""Checks of a Craig–Bampton reduction against its full model, after pyyeti's ``cbcheck``.

Rigid-body mass, symmetry, exactness of the interface stiffness (static
condensation) and modal effective mass of each kept mode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from ..system.threads import follows_policy
from .flexiblebody import FlexibleBody

__all__ = ["CBCheck", "cb_check"]


@dataclass(frozen=True)
class CBCheck:
    """Checks of a reduced part against its full model (after pyyeti's ``cbcheck``), SI.

    Attributes
    ----------
    rigid_mass_reduced, rigid_mass_full : ndarray, shape (r, r)
        Rigid-body mass matrices Rᵀ M R of the reduced and the full model,
        about the first boundary node (the part's first node): 6 × 6 for a
        full model (kg, kg·m, kg·m² by row and column; R in the order ux, uy,
        uz, θx, θy, θz), 1 × 1 for torsion (the axial inertia, kg·m²).
    symmetry : float
        Largest relative asymmetry of the reduced K and M.
    static_error : float
        Largest relative difference of the reduced interface stiffness from
        the full model's static condensation.
    participation : ndarray, shape (nm, r)
        Modal participation L = M_qb R_b of each kept fixed-interface mode in
        each rigid-body motion R_b of the boundary (the boundary rows of R):
        kg^½, kg^½·m for rotations. Its sign follows the mode's, which is
        arbitrary.
    effective_mass : ndarray, shape (nm, r)
        Modal effective mass L², kg (translations) and kg·m² (rotations about
        the axes through the first boundary node), the modes being
        mass-normalised. Same convention as pyyeti's ``cbcheck`` (its
        ``effmass``, from geometry-based rigid-body modes at ``uref``).
    effective_mass_percent : ndarray, shape (nm, r)
        ``effective_mass`` in percent of the rigid-body mass's diagonal
        (``rigid_mass_reduced``), as pyyeti's ``effmass_percent``.

    Notes
    -----
    With every fixed-interface mode kept, the effective masses of a direction
    sum to its rigid-body mass less the residual Rbᵀ(M_bb − M_bi M_ii⁻¹ M_ib)Rb
    of the boundary; with a few modes, ``effective_mass_total_percent`` says
    how much of the part's mass and inertia the kept modes carry.
    """

    rigid_mass_reduced: np.ndarray
    rigid_mass_full: np.ndarray
    symmetry: float
    static_error: float
    participation: np.ndarray
    effective_mass: np.ndarray
    effective_mass_percent: np.ndarray

    @property
    def rigid_mass_error(self) -> float:
        """Largest relative difference of the rigid-body mass matrices."""
        return float(
            np.max(np.abs(self.rigid_mass_reduced - self.rigid_mass_full))
            / np.max(np.abs(self.rigid_mass_full))
        )

    @property
    def effective_mass_total_percent(self) -> np.ndarray:
        """Effective mass of all kept modes per rigid-body direction, % (shape (r,))."""
        return self.effective_mass_percent.sum(axis=0)


@follows_policy
def cb_check(body: FlexibleBody, part) -> CBCheck:
    """Rigid-body mass, symmetry, static exactness and modal effective mass of a reduced part.

    A solid part's body is checked against what its reduction kept of the whole mesh
    (:attr:`FlexibleBody.reduction`): its rigid-body mass Rᵀ M R about the start master, and as
    ``static_error`` the constraint modes' residual - its static condensation is the solve's, so
    its accuracy is the solve's.

    Parameters
    ----------
    body : FlexibleBody
        From :func:`craig_bampton` of ``part``.
    part : PartModel or SolidPartModel
        The full model it was reduced from.

    Returns
    -------
    CBCheck
    """
    if body.reduction is not None:
        return _solid_check(body)
    R = part.rigid_body_modes()
    b = part.nodes_dofs(body.boundary_nodes)
    i = np.setdiff1d(np.arange(part.n_dofs), b)
    # The rigid motions in reduced coordinates: boundary values, zero modal participation.
    Rr = np.zeros((body.K.shape[0], R.shape[1]))
    Rr[: b.size] = R[b]
    K, M = part.K.tocsr(), part.M.tocsr()
    Kbb, Kbi, Kii = K[b][:, b].toarray(), K[b][:, i], K[i][:, i].tocsc()
    condensed = Kbb - Kbi @ spla.splu(Kii).solve(Kbi.T.toarray())
    kr = body.K[: b.size, : b.size]
    sym = _symmetry(body)
    rigid_mass = Rr.T @ body.M @ Rr
    # Participation of the fixed-interface modes in the boundary's rigid motions (pyyeti: m[q, b] @ rbg).
    L = body.M[b.size :, : b.size] @ R[b]
    return CBCheck(
        rigid_mass_reduced=rigid_mass,
        rigid_mass_full=R.T @ (M @ R),
        symmetry=sym,
        static_error=float(np.max(np.abs(kr - condensed)) / np.max(np.abs(condensed))),
        participation=L,
        effective_mass=L**2,
        effective_mass_percent=L**2 * (100.0 / np.diag(rigid_mass)),
    )


def _symmetry(body: FlexibleBody) -> float:
    """Largest relative asymmetry of the reduced K and M."""
    return max(
        float(np.max(np.abs(body.K - body.K.T)) / np.max(np.abs(body.K))),
        float(np.max(np.abs(body.M - body.M.T)) / np.max(np.abs(body.M))),
    )


def _solid_check(body: FlexibleBody) -> CBCheck:
    """:func:`cb_check` of a solid body, from its reduction's rigid-body data and residual."""
    reduction = body.reduction
    Rb = reduction.rigid_boundary
    nb = Rb.shape[0]
    Rr = np.zeros((body.K.shape[0], Rb.shape[1]))
    Rr[:nb] = Rb
    rigid_mass = Rr.T @ body.M @ Rr
    L = body.M[nb:, :nb] @ Rb
    return CBCheck(
        rigid_mass_reduced=rigid_mass,
        rigid_mass_full=reduction.rigid_mass_full,
        symmetry=_symmetry(body),
        static_error=reduction.static_residual,
        participation=L,
        effective_mass=L**2,
        effective_mass_percent=L**2 * (100.0 / np.diag(rigid_mass)),
    )
