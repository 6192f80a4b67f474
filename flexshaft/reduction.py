"""Craig–Bampton reduction of a part model, with damping set per mode.

The reduced part keeps its boundary (interface) DOFs physical and adds the
lowest fixed-interface normal modes:

    u = [u_b; u_i] = T·[u_b; q],   T = [[I, 0], [Ψ, Φ]],   Ψ = −K_ii⁻¹ K_ib

(static constraint modes Ψ, fixed-interface modes Φ, mass-normalised). The
reduced stiffness and mass are Tᵀ K T and Tᵀ M T; the interface stiffness
block equals the static condensation of the full model exactly (Craig &
Bampton, AIAA J. 6 (1968) 1313–1319). For multibody tools the basis is also
offered orthonormalised: the reduced model's own free-free modes, each with a
frequency, on which damping is set per mode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as spla

from .eigen import lowest_modes
from .errors import ModelError
from .partmodel import PartModel, smooth_trial_shapes

__all__ = ["FlexibleBody", "craig_bampton", "CBCheck", "cb_check"]


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

    @property
    def n_boundary(self) -> int:
        """Number of boundary DOFs."""
        return self.boundary_nodes.size * (6 if self.dofs == "full" else 1)

    @property
    def n_modes(self) -> int:
        """Number of fixed-interface modes kept."""
        return self.fixed_interface_hz.size


def _boundary_dofs(part: PartModel, nodes: np.ndarray) -> np.ndarray:
    return np.concatenate([part.node_dofs(int(n)) for n in nodes])


def craig_bampton(
    part: PartModel,
    *,
    modes: int | None = None,
    cutoff_hz: float | None = None,
    nodes=(),
    damping_ratio=0.0053,
) -> FlexibleBody:
    """Reduce a part model to its interface DOFs plus fixed-interface modes.

    Parameters
    ----------
    part : PartModel
        From :func:`flexshaft.partmodel.part_model`.
    modes : int, optional
        Number of fixed-interface modes to keep.
    cutoff_hz : float, optional
        Keep every fixed-interface mode below this frequency, Hz (instead of
        ``modes``).
    nodes : sequence of int
        Extra boundary nodes besides the two end nodes (e.g. a bearing node).
    damping_ratio : float or sequence of float
        Damping ratio of every elastic free-free mode of the reduced part, or
        one per mode of the orthonormalised basis (rigid ones ignored). The
        study's 0.53 % by default.

    Returns
    -------
    FlexibleBody
    """
    if (modes is None) == (cutoff_hz is None):
        raise ModelError(
            "give either modes or cutoff_hz", field="reduce", valid="{modes = n} or {cutoff_hz = f}"
        )
    nb_nodes = np.unique(np.concatenate([np.asarray(part.interface_nodes), np.asarray(nodes, int)]))
    b = _boundary_dofs(part, nb_nodes)
    i = np.setdiff1d(np.arange(part.n_dofs), b)
    K, M = part.K.tocsr(), part.M.tocsr()
    Kii, Kib = K[i][:, i].tocsc(), K[i][:, b]
    Mii = M[i][:, i]
    lu = spla.splu(Kii)
    psi = -lu.solve(Kib.toarray())
    if modes is not None:
        if int(modes) < 0 or int(modes) != modes:
            raise ModelError(
                "must be an integer >= 0", field="reduce.modes", value=modes, valid="an integer >= 0"
            )
        n_keep = min(int(modes), i.size)
    else:
        if not (np.isfinite(cutoff_hz) and cutoff_hz > 0):
            raise ModelError(
                "must be a frequency > 0",
                field="reduce.cutoff_hz",
                value=cutoff_hz,
                unit="Hz",
                valid="a finite number > 0 (Hz)",
            )
        n_keep = 0
    trial = smooth_trial_shapes(part.x, part.dofs_per_node)[i]
    if modes is not None and n_keep == 0:
        phi, lam = np.zeros((i.size, 0)), np.zeros(0)
    else:
        want = n_keep if modes is not None else 8
        while True:
            sol = lowest_modes(Kii, Mii, min(want, i.size), trial=trial)
            lam = sol.eigenvalues
            f = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
            if modes is not None or f[-1] > cutoff_hz or want >= i.size:
                break
            want *= 2
        phi = sol.vectors
        if cutoff_hz is not None:
            keep = f < cutoff_hz
            phi, lam = phi[:, keep], lam[keep]
    nb, nm = b.size, phi.shape[1]
    T = np.zeros((part.n_dofs, nb + nm))
    T[b, np.arange(nb)] = 1.0
    T[np.ix_(i, np.arange(nb))] = psi
    T[np.ix_(i, nb + np.arange(nm))] = phi
    Kr = T.T @ (K @ T)
    Mr = T.T @ (M @ T)
    Kr, Mr = 0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T)
    # Orthonormalised basis: the reduced part's own free-free modes.
    w2, V = la.eigh(Kr, Mr)
    scale = max(float(np.max(np.abs(w2))), 1.0)
    rigid = w2 < 1e-9 * scale
    w2 = np.where(rigid, 0.0, w2)
    omega = np.sqrt(w2)
    ratios = (
        np.broadcast_to(np.asarray(damping_ratio, float), omega.shape).copy()
        if np.ndim(damping_ratio) == 0
        else np.asarray(damping_ratio, float)
    )
    if ratios.shape != omega.shape:
        raise ModelError(
            f"has {ratios.size} ratios for {omega.size} modes",
            field="damping_ratio",
            valid=f"one ratio, or {omega.size} (one per mode of the reduced part)",
        )
    if np.any(ratios < 0) or np.any(ratios >= 1) or not np.all(np.isfinite(ratios)):
        raise ModelError(
            "must be in [0, 1)",
            field="damping_ratio",
            value=float(ratios[(ratios < 0) | (ratios >= 1) | ~np.isfinite(ratios)][0]),
            valid="a fraction in [0, 1), e.g. 0.0053",
        )
    ratios[rigid] = 0.0
    # C in CB coordinates from diag(2 ξ ω) on the mass-normalised free modes: C = M V diag Vᵀ M.
    MV = Mr @ V
    Cr = MV @ np.diag(2.0 * ratios * omega) @ MV.T
    return FlexibleBody(
        name=part.name,
        dofs=part.dofs,
        boundary_nodes=nb_nodes,
        boundary_x=part.x[nb_nodes],
        K=Kr,
        M=Mr,
        C=0.5 * (Cr + Cr.T),
        T=T,
        fixed_interface_hz=np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi),
        free_hz=omega / (2 * np.pi),
        free_modes=V,
        damping_ratios=ratios,
    )


@dataclass(frozen=True)
class CBCheck:
    """Checks of a reduced part against its full model (after pyyeti's ``cbcheck``), SI.

    ``rigid_mass_reduced`` / ``rigid_mass_full`` are the rigid-body mass
    matrices Rᵀ M R (6 × 6 for a full model: mass, first and second moments;
    1 × 1 for torsion: the axial inertia); ``symmetry`` the largest relative
    asymmetry of K and M; ``static_error`` the largest relative difference of
    the reduced interface stiffness from the full model's static condensation.
    """

    rigid_mass_reduced: np.ndarray
    rigid_mass_full: np.ndarray
    symmetry: float
    static_error: float

    @property
    def rigid_mass_error(self) -> float:
        """Largest relative difference of the rigid-body mass matrices."""
        return float(
            np.max(np.abs(self.rigid_mass_reduced - self.rigid_mass_full))
            / np.max(np.abs(self.rigid_mass_full))
        )


def cb_check(body: FlexibleBody, part: PartModel) -> CBCheck:
    """Rigid-body mass, symmetry and static exactness of a reduced part."""
    R = part.rigid_body_modes()
    b = _boundary_dofs(part, body.boundary_nodes)
    i = np.setdiff1d(np.arange(part.n_dofs), b)
    # The rigid motions in reduced coordinates: boundary values, zero modal participation.
    Rr = np.zeros((body.K.shape[0], R.shape[1]))
    Rr[: b.size] = R[b]
    K, M = part.K.tocsr(), part.M.tocsr()
    Kbb, Kbi, Kii = K[b][:, b].toarray(), K[b][:, i], K[i][:, i].tocsc()
    condensed = Kbb - Kbi @ spla.splu(Kii).solve(Kbi.T.toarray())
    kr = body.K[: b.size, : b.size]
    sym = max(
        float(np.max(np.abs(body.K - body.K.T)) / np.max(np.abs(body.K))),
        float(np.max(np.abs(body.M - body.M.T)) / np.max(np.abs(body.M))),
    )
    return CBCheck(
        rigid_mass_reduced=Rr.T @ body.M @ Rr,
        rigid_mass_full=R.T @ (M @ R),
        symmetry=sym,
        static_error=float(np.max(np.abs(kr - condensed)) / np.max(np.abs(condensed))),
    )
