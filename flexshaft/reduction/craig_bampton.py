"""Craig–Bampton reduction of a part model, with damping set per mode.

The reduced part keeps its boundary (interface) DOFs physical and adds the
lowest fixed-interface normal modes:

    u = [u_b; u_i] = T·[u_b; q],   T = [[I, 0], [Ψ, Φ]],   Ψ = −K_ii⁻¹ K_ib

(static constraint modes Ψ, fixed-interface modes Φ, mass-normalised). The
reduced stiffness and mass are Tᵀ K T and Tᵀ M T; the interface stiffness
block equals the static condensation of the full model exactly (Craig &
Bampton, AIAA J. 6 (1968) 1313–1319). For multibody tools the basis is also
offered orthonormalised: the reduced model's own free-free modes, each with a
frequency, on which damping is set per mode (:class:`ModalDamping`); a
multibody tool that wants only some of them gets them from
:func:`select_modes`. :func:`cb_check` checks a reduction the way pyyeti's
``cb.cbcheck`` does, modal effective mass included.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as spla

from ..errors import ModelError
from ..linalg.eigen import lowest_modes
from ..parts.model import PartModel, smooth_trial_shapes
from ..system.threads import follows_policy
from ..validation import FRACTION_VALID
from .modaldamping import ModalDamping

__all__ = ["FlexibleBody", "check_mode_choice", "craig_bampton", "reduced_body", "residual_vectors"]


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
        A solid part's body (:mod:`flexshaft.reduction.solid`): its mesh and the displacement of its
        surface nodes per reduced coordinate, for views on the part's own surface; None for a 1D
        part (``T`` then recovers its own mesh; a solid body's ``T`` recovers its axis line).
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
    elif not (np.isfinite(cutoff_hz) and cutoff_hz > 0):
        raise ModelError(
            "must be a frequency > 0",
            field="reduce.cutoff_hz",
            value=cutoff_hz,
            unit="Hz",
            valid="a finite number > 0 (Hz)",
        )


@follows_policy
def craig_bampton(
    part: PartModel,
    *,
    modes: int | None = None,
    cutoff_hz: float | None = None,
    nodes=(),
    damping_ratio=0.0053,
    residual: bool = True,
) -> FlexibleBody:
    """Reduce a part model to its interface DOFs plus fixed-interface modes.

    With ``residual`` (the default) the kept modes are followed by residual
    vectors: the interior's static response to the inertia load of a unit
    acceleration of each boundary DOF, made orthogonal to the kept modes
    (MacNeal's residual flexibility, Nastran's RESVEC). They leave the
    interface stiffness exact and the boundary uncoupled from the modal
    coordinates in K, and they carry the static part of every truncated mode:
    the error of a free-free frequency f then falls like (f/f_c)⁴ or faster
    instead of about (f/f_c)², f_c the highest kept mode (a 4-mode torsion
    part: 1.5e-3 → 2.5e-7 on its first mode; every mode below f_c/2 within
    3e-5, tested). They appear as extra modal coordinates (``n_residual``
    of them, after the modes) with the Ritz frequencies of the fixed-interface
    problem in ``fixed_interface_hz``.

    Parameters
    ----------
    part : PartModel
        From :func:`flexshaft.parts.model.part_model`.
    modes : int, optional
        Number of fixed-interface modes to keep.
    cutoff_hz : float, optional
        Keep every fixed-interface mode below this frequency, Hz (instead of
        ``modes``).
    nodes : sequence of int
        Extra boundary nodes besides the two end nodes (e.g. a bearing node).
    damping_ratio : float, sequence of float or ModalDamping
        Damping ratio (fraction, [0, 1)) of every elastic free-free mode of
        the reduced part; or one per mode of the orthonormalised basis (nb +
        nm of them, rigid ones ignored); or a :class:`ModalDamping` (ratios
        per elastic mode, per frequency band, or Rayleigh C = αM + βK on the
        reduced matrices). The study's 0.53 % by default.
    residual : bool
        Add the residual vectors (above); False gives textbook Craig–Bampton.

    Returns
    -------
    FlexibleBody
    """
    check_mode_choice(modes, cutoff_hz)
    nb_nodes = np.unique(np.concatenate([np.asarray(part.interface_nodes), np.asarray(nodes, int)]))
    b = part.nodes_dofs(nb_nodes)
    i = np.setdiff1d(np.arange(part.n_dofs), b)
    K, M = part.K.tocsr(), part.M.tocsr()
    Kii, Kib = K[i][:, i].tocsc(), K[i][:, b]
    Mii = M[i][:, i]
    lu = spla.splu(Kii)
    psi = -lu.solve(Kib.toarray())
    n_keep = min(int(modes), i.size) if modes is not None else 0
    trial = smooth_trial_shapes(part.x, part.dofs_per_node)[i]
    if (modes is not None and n_keep == 0) or i.size == 0:  # nothing to keep, or no interior at all
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
    phi = phi * _signs(phi, part, i)
    n_res = 0
    if residual:
        res, lam_res = residual_vectors(lu, Kii, Mii, M[i][:, b], psi, phi)
        phi, lam, n_res = np.hstack([phi, res]), np.concatenate([lam, lam_res]), lam_res.size
    nb, nm = b.size, phi.shape[1]
    T = np.zeros((part.n_dofs, nb + nm))
    T[b, np.arange(nb)] = 1.0
    T[np.ix_(i, np.arange(nb))] = psi
    T[np.ix_(i, nb + np.arange(nm))] = phi
    Kr = T.T @ (K @ T)
    Mr = T.T @ (M @ T)
    return reduced_body(
        name=part.name,
        dofs=part.dofs,
        boundary_nodes=nb_nodes,
        boundary_x=part.x[nb_nodes],
        K=Kr,
        M=Mr,
        T=T,
        eigenvalues=lam,
        n_residual=n_res,
        damping_ratio=damping_ratio,
    )


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


def _signs(phi: np.ndarray, part, interior: np.ndarray) -> np.ndarray:
    """+1 or -1 per fixed-interface mode: its largest θx entry positive (flexshaft's one convention,
    as :func:`flexshaft.analysis.modal.mode_signs` for system modes); a mode without twist (bending,
    axial) by its largest translation. The first entry within 1e-6 of the largest decides (stable
    under round-off, ~1e-12 of the entries)."""
    from ..parts.model import DOF_NAMES

    names = DOF_NAMES[part.dofs]
    kind = np.asarray(names)[interior % len(names)]
    twist = kind == "θx"
    move = np.isin(kind, ("ux", "uy", "uz"))
    signs = np.ones(phi.shape[1])
    for k in range(phi.shape[1]):
        v = phi[twist, k]
        if not v.size or np.max(np.abs(v)) <= 1e-9 * np.max(np.abs(phi[:, k])):
            v = phi[move, k]
        top = float(np.max(np.abs(v))) if v.size else 0.0
        if top > 0:
            signs[k] = 1.0 if v[np.flatnonzero(np.abs(v) >= (1 - 1e-6) * top)[0]] > 0 else -1.0
    return signs


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
