"""A Craig–Bampton flexible body: reduced K, M and C on [u_b; q], its recovery T, its free-free basis.

What every reduction makes, 1D or solid (:func:`~flexshaft.reduction.craig_bampton.craig_bampton`):
the reduced matrices with the boundary DOFs first, then the modal coordinates; the orthonormalised
basis - the reduced part's own free-free modes, each with a frequency - on which damping is set per
mode (:class:`~flexshaft.reduction.modaldamping.ModalDamping`, :func:`reduced_body`); the residual
vectors that follow the kept modes (:func:`residual_vectors`); the check of a mode choice.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la

from ..errors import ModelError
from ..validation import FRACTION_VALID, check_positive
from .modaldamping import ModalDamping

__all__ = ["FlexibleBody", "check_mode_choice", "reduced_body", "residual_vectors"]


@dataclass(frozen=True)
class FlexibleBody:
    """A part reduced by Craig–Bampton (SI).

    Attributes
    ----------
    name : str
        The part's name.
    dofs : {"torsion", "full"}
        DOFs per boundary node: θx, or (ux, uy, uz, θx, θy, θz).
    boundary_nodes : ndarray of int
        Nodes of the part model kept physical.
    boundary_x : ndarray
        Their axial positions, m.
    K, M, C : ndarray, shape (nb + nm, nb + nm)
        Reduced stiffness, mass and damping in Craig–Bampton coordinates
        [u_b; q]: boundary DOFs first (node-major), then modal coordinates.
    T : ndarray, shape (n_dofs, nb + nm)
        Recovery of every DOF of the part model from the reduced coordinates.
    fixed_interface_hz : ndarray, shape (nm,)
        Frequencies of the kept fixed-interface modes, Hz.
    free_hz : ndarray, shape (nb + nm,)
        Frequencies of the orthonormalised basis (the reduced part's free-free
        modes), Hz; rigid-body modes 0.
    free_modes : ndarray, shape (nb + nm, nb + nm)
        That basis in Craig–Bampton coordinates, mass-normalised.
    damping_ratios : ndarray, shape (nb + nm,)
        Damping ratio of each free-free mode (0 on rigid-body modes).
    n_residual : int
        How many of the ``nm`` modal coordinates are residual vectors (the
        last ones) rather than fixed-interface modes.
    solid : SolidShapes or None
        A solid part's body (:mod:`flexshaft.reduction.axisline`): its mesh and the displacement of its
        surface nodes per reduced coordinate, for views on the part's own surface; None for a 1D
        part (``T`` then recovers its own mesh; a solid body's ``T`` recovers its axis line).
    reduction : SolidReduction or None
        A solid body's reduction (:mod:`flexshaft.reduction.solidbasis`), which :func:`cb_check
        <flexshaft.reduction.check.cb_check>` reads and other lines are recovered from; None for a
        1D part.
    """

    name: str
    dofs: str
    boundary_nodes: np.ndarray
    boundary_x: np.ndarray
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    T: np.ndarray
    fixed_interface_hz: np.ndarray
    free_hz: np.ndarray
    free_modes: np.ndarray
    damping_ratios: np.ndarray
    n_residual: int = 0
    solid: object = None
    reduction: object = field(default=None, repr=False, compare=False)

    @property
    def n_boundary(self) -> int:
        """Number of boundary DOFs."""
        return self.boundary_nodes.size * (6 if self.dofs == "full" else 1)

    @property
    def n_mesh_nodes(self) -> int:
        """Nodes of the part's own mesh (the rows of ``T`` per DOF of a node)."""
        return self.T.shape[0] // (6 if self.dofs == "full" else 1)

    @property
    def n_modes(self) -> int:
        """Number of modal coordinates: fixed-interface modes kept plus residual vectors."""
        return self.fixed_interface_hz.size


def check_mode_choice(modes, cutoff_hz) -> None:
    """A reduction keeps ``modes`` fixed-interface modes (an integer >= 0) or every one below
    ``cutoff_hz`` (Hz, > 0): exactly one of them, checked."""
    if (modes is None) == (cutoff_hz is None):
        raise ModelError(
            "give either modes or cutoff_hz", field="reduce", valid="{modes = n} or {cutoff_hz = f}"
        )
    if modes is not None:
        if int(modes) < 0 or int(modes) != modes:
            raise ModelError(
                "must be an integer >= 0", field="reduce.modes", value=modes, valid="an integer >= 0"
            )
    else:
        check_positive(cutoff_hz, "reduce.cutoff_hz", "Hz", "must be a frequency > 0")


def reduced_body(
    *, name, dofs, boundary_nodes, boundary_x, K, M, T, eigenvalues, n_residual, damping_ratio, **extra
) -> FlexibleBody:
    """The flexible body of reduced matrices ``K``, ``M`` (boundary DOFs first, then the modal
    coordinates, whose fixed-interface eigenvalues are ``eigenvalues``, (rad/s)²): its orthonormalised
    free-free basis and its damping. One path for a 1D part's reduction and a solid part's."""
    Kr, Mr = 0.5 * (K + K.T), 0.5 * (M + M.T)
    # Orthonormalised basis: the reduced part's own free-free modes.
    w2, V = la.eigh(Kr, Mr)
    scale = max(float(np.max(np.abs(w2))), 1.0)
    rigid = w2 < 1e-9 * scale
    w2 = np.where(rigid, 0.0, w2)
    omega = np.sqrt(w2)
    Cr, ratios = _reduced_damping(damping_ratio, Kr, Mr, V, omega, rigid)
    return FlexibleBody(
        name=name,
        dofs=dofs,
        boundary_nodes=np.asarray(boundary_nodes),
        boundary_x=np.asarray(boundary_x, dtype=float),
        K=Kr,
        M=Mr,
        C=Cr,
        T=T,
        fixed_interface_hz=np.sqrt(np.clip(eigenvalues, 0, None)) / (2 * np.pi),
        free_hz=omega / (2 * np.pi),
        free_modes=V,
        damping_ratios=ratios,
        n_residual=n_residual,
        **extra,
    )


# A residual direction is dropped when, after projection off the kept modes, its
# mass norm² is below this fraction of the vectors' own: an amplitude of 1e-10,
# far above the 1e-16 round-off of the projection yet far below anything that
# moves a frequency (at 1e-12 real directions were dropped, costing 3e-6).
_RESIDUAL_DROP = 1e-20


def residual_vectors(lu, Kii, Mii, Mib, psi, phi) -> tuple[np.ndarray, np.ndarray]:
    """Residual vectors of the interior and their Ritz eigenvalues, (rad/s)².

    Load: the interior's inertia force when the part moves as its constraint
    modes with unit acceleration, F = Mii Ψ + Mib; response Kii⁻¹ F, made
    Mii-orthogonal to the kept modes (twice, for round-off), then diagonalised
    in its own subspace so that the reduced K stays diagonal in the modal
    block. Directions the kept modes already span are dropped.
    """
    n = Mii.shape[0]
    if n == 0:
        return np.zeros((0, 0)), np.zeros(0)
    R = lu.solve(np.asarray(Mii @ psi + Mib.toarray()))
    size = float(np.max(np.einsum("ij,ij->j", R, Mii @ R), initial=0.0))
    for _ in range(2):
        R = R - phi @ (phi.T @ (Mii @ R))
    m = R.T @ (Mii @ R)
    m = 0.5 * (m + m.T)
    mu, U = la.eigh(m)
    # Keep the directions the kept modes do not span (measured against the vectors'
    # size before the projection) and M-normalise them.
    ok = mu > _RESIDUAL_DROP * max(size, np.finfo(float).tiny)
    if not ok.any():
        return np.zeros((n, 0)), np.zeros(0)
    B = (R @ U[:, ok]) / np.sqrt(mu[ok])
    k = B.T @ (Kii @ B)
    lam, W = la.eigh(0.5 * (k + k.T))
    return B @ W, lam


def _ratios_from_numbers(damping_ratio, n: int) -> np.ndarray:
    """One ratio for all modes, or one per mode of the orthonormalised basis (n of them)."""
    ratios = (
        np.full(n, float(damping_ratio)) if np.ndim(damping_ratio) == 0 else np.asarray(damping_ratio, float)
    )
    if ratios.shape != (n,):
        raise ModelError(
            f"has {ratios.size} ratios for {n} modes",
            field="damping_ratio",
            valid=f"one ratio, or {n} (one per mode of the reduced part)",
        )
    bad = (ratios < 0) | (ratios >= 1) | ~np.isfinite(ratios)
    if np.any(bad):
        raise ModelError(
            "must be in [0, 1)",
            field="damping_ratio",
            value=float(ratios[bad][0]),
            valid=FRACTION_VALID,
        )
    return ratios


def _reduced_damping(damping_ratio, Kr, Mr, V, omega, rigid) -> tuple[np.ndarray, np.ndarray]:
    """Reduced damping matrix and the ratio of each free-free mode (0 on rigid-body modes).

    Rayleigh damping is αMr + βKr as given; every other kind is modal damping
    diag(2 ξ ω) on the mass-normalised free modes V, mapped back to
    Craig–Bampton coordinates as C = Mr V diag(2 ξ ω) Vᵀ Mr (VᵀMrV = I).
    """
    if isinstance(damping_ratio, ModalDamping):
        ratios = damping_ratio.ratios(omega / (2 * np.pi), rigid)
        if damping_ratio.rayleigh is not None:
            alpha, beta = damping_ratio.rayleigh
            return alpha * Mr + beta * Kr, ratios
    else:
        ratios = _ratios_from_numbers(damping_ratio, omega.size)
        ratios[rigid] = 0.0
    MV = Mr @ V
    Cr = MV @ np.diag(2.0 * ratios * omega) @ MV.T
    return 0.5 * (Cr + Cr.T), ratios


# Under modal damping ΦᵣᵀCΦᵣ on the rigid-body modes is round-off of this
