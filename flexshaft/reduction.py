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

from .eigen import lowest_modes
from .errors import ModelError
from .modaldamping import _FRACTION, ModalDamping
from .partmodel import PartModel, smooth_trial_shapes

__all__ = [
    "FlexibleBody",
    "ModalDamping",
    "craig_bampton",
    "ModalBody",
    "select_modes",
    "CBCheck",
    "cb_check",
]


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


def _boundary_dofs(part: PartModel, nodes: np.ndarray) -> np.ndarray:
    return np.concatenate([part.node_dofs(int(n)) for n in nodes])


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
        From :func:`flexshaft.partmodel.part_model`.
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
    n_res = 0
    if residual:
        res, lam_res = _residual_vectors(lu, Kii, Mii, M[i][:, b], psi, phi)
        phi, lam, n_res = np.hstack([phi, res]), np.concatenate([lam, lam_res]), lam_res.size
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
    Cr, ratios = _reduced_damping(damping_ratio, Kr, Mr, V, omega, rigid)
    return FlexibleBody(
        name=part.name,
        dofs=part.dofs,
        boundary_nodes=nb_nodes,
        boundary_x=part.x[nb_nodes],
        K=Kr,
        M=Mr,
        C=Cr,
        T=T,
        fixed_interface_hz=np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi),
        free_hz=omega / (2 * np.pi),
        free_modes=V,
        damping_ratios=ratios,
        n_residual=n_res,
    )


# A residual direction is dropped when, after projection off the kept modes, its
# mass norm² is below this fraction of the vectors' own: an amplitude of 1e-10,
# far above the 1e-16 round-off of the projection yet far below anything that
# moves a frequency (at 1e-12 real directions were dropped, costing 3e-6).
_RESIDUAL_DROP = 1e-20


def _residual_vectors(lu, Kii, Mii, Mib, psi, phi) -> tuple[np.ndarray, np.ndarray]:
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
            valid=_FRACTION,
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
# relative size; Rayleigh's α gives α there, far above it.
_RIGID_DAMPING_ROUNDOFF = 1e-9


@dataclass(frozen=True)
class ModalBody:
    """A flexible body in its orthonormalised coordinates, some modes kept (SI).

    The physical DOFs of the part are u = ``shapes`` · η with η the modal
    coordinates; the equations of motion are M η̈ + C η̇ + K η = shapesᵀ f.

    Attributes
    ----------
    name : str
        The part's name.
    dofs : {"torsion", "full"}
        DOFs per node of the part model: θx, or (ux, uy, uz, θx, θy, θz).
    modes : ndarray of int, shape (k,)
        The kept modes, as indices into ``FlexibleBody.free_hz``, ascending.
    frequencies_hz : ndarray, shape (k,)
        Their frequencies, Hz; rigid-body modes 0.
    damping_ratios : ndarray, shape (k,)
        Their damping ratios (fractions); rigid-body modes 0.
    shapes : ndarray, shape (n_part_dofs, k)
        The modes on every DOF of the part model (``T @ free_modes[:, modes]``),
        node-major. Mass-normalised, shapesᵀ M shapes = I with M the part
        model's mass: a modal coordinate is in kg^½·m (kinetic energy ½ η̇ᵀη̇),
        so the shapes are in kg^-½ on translations and rad·kg^-½·m⁻¹ on
        rotations.
    boundary_nodes : ndarray of int
        Nodes of the part model that were the Craig–Bampton boundary.
    boundary_x : ndarray
        Their axial positions, m.
    K : ndarray, shape (k, k)
        Modal stiffness diag(ω²), 1/s² (the modal masses being 1).
    M : ndarray, shape (k, k)
        Modal mass, the identity (dimensionless in these coordinates).
    C : ndarray, shape (k, k)
        Modal damping diag(2 ξ ω), rad/s. On rigid-body modes it is 0, or
        Rayleigh's α (1/s) when the body was damped with α > 0.
    """

    name: str
    dofs: str
    modes: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray
    boundary_nodes: np.ndarray
    boundary_x: np.ndarray
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray

    @property
    def rigid(self) -> np.ndarray:
        """Which kept modes are rigid-body modes (frequency exactly 0)."""
        return self.frequencies_hz == 0.0

    @property
    def boundary_shapes(self) -> np.ndarray:
        """Rows of ``shapes`` at the boundary DOFs, node-major, shape (nb, k)."""
        d = 6 if self.dofs == "full" else 1
        rows = (self.boundary_nodes[:, None] * d + np.arange(d)).ravel()
        return self.shapes[rows]


def _modal_damping_diagonal(body: FlexibleBody) -> np.ndarray:
    """diag(2 ξ ω) on the elastic modes; on the rigid-body modes what C really does there, rad/s."""
    rigid = body.free_hz == 0.0
    c = 2.0 * body.damping_ratios * (2 * np.pi * body.free_hz)
    # Rayleigh's αM damps rigid motion too (α there): keep it rather than the reported ratio 0.
    V = body.free_modes
    projected = np.einsum("ij,ij->j", V, body.C @ V)
    scale = float(np.max(np.abs(projected), initial=0.0))
    on_rigid = np.where(np.abs(projected) <= _RIGID_DAMPING_ROUNDOFF * scale, 0.0, projected)
    return np.where(rigid, on_rigid, c)


def _kept_indices(keep, n: int) -> np.ndarray:
    """``keep`` (indices or a boolean mask over n modes) as sorted unique indices."""
    valid = f"indices from 0 to {n - 1} (each once), or {n} booleans"
    arr = np.asarray(keep)
    if arr.ndim != 1:
        raise ModelError("must be one-dimensional", field="keep", value=keep, valid=valid, has_value=True)
    if arr.dtype == bool:
        if arr.size != n:
            raise ModelError(f"has {arr.size} flags for {n} modes", field="keep", valid=valid)
        idx = np.flatnonzero(arr)
    elif arr.size == 0 or np.issubdtype(arr.dtype, np.integer):
        idx = arr.astype(int)
        for k, i in enumerate(idx):
            if not 0 <= i < n:
                raise ModelError("no such mode", field=f"keep[{k}]", value=int(i), valid=valid)
        if np.unique(idx).size != idx.size:
            raise ModelError("names a mode twice", field="keep", value=idx.tolist(), valid=valid)
    else:
        raise ModelError("not indices or a mask", field="keep", value=keep, valid=valid, has_value=True)
    if idx.size == 0:
        raise ModelError("keeps no mode", field="keep", valid=valid)
    return np.sort(idx)


def _check_rigid_kept(idx: np.ndarray, rigid: np.ndarray, drop_rigid: bool) -> None:
    """All rigid-body modes kept, or (with drop_rigid) none of them: never a part."""
    r = np.flatnonzero(rigid)
    kept = np.isin(r, idx)
    names = ", ".join(str(i) for i in r)
    if drop_rigid and kept.any():
        raise ModelError(
            f"names rigid-body mode(s) {', '.join(str(i) for i in r[kept])} although drop_rigid is true",
            field="keep",
            valid=f"no rigid-body mode ({names}) with drop_rigid = true",
        )
    if not drop_rigid and not kept.all():
        raise ModelError(
            f"leaves out rigid-body mode(s) {', '.join(str(i) for i in r[~kept])}",
            field="keep",
            valid=f"every rigid-body mode ({names}), or none of them with drop_rigid = true",
        )


def select_modes(body: FlexibleBody, keep, *, drop_rigid: bool = False) -> ModalBody:
    """The body in its orthonormalised coordinates with only the kept free-free modes.

    This is mode enable/disable for a multibody tool: the body's free-free
    modes (``body.free_hz``), each a coordinate of its own, the unwanted ones
    left out.

    Parameters
    ----------
    body : FlexibleBody
        From :func:`craig_bampton`.
    keep : sequence of int or array_like of bool
        Indices into ``body.free_hz`` (0 … nb + nm − 1, each once, any order;
        they are sorted), or one flag per mode.
    drop_rigid : bool
        The rigid-body modes share frequency 0, so which combination of rigid
        motions each one is, is arbitrary: they are kept or dropped as a whole.
        ``False`` (default): ``keep`` must name every rigid-body mode, so that
        the body can still translate and turn as a whole. ``True``: ``keep``
        must name none of them and the body keeps only elastic modes (for a
        tool that carries the rigid motion itself).

    Returns
    -------
    ModalBody

    Raises
    ------
    ModelError
        On an index out of range or repeated, a mask of the wrong length, an
        empty selection, or rigid-body modes kept in part, left out without
        ``drop_rigid`` or named with it.
    """
    if not isinstance(body, FlexibleBody):
        raise ModelError(
            "not a flexible body",
            field="body",
            value=type(body).__name__,
            valid="a FlexibleBody from craig_bampton",
        )
    rigid = body.free_hz == 0.0
    idx = _kept_indices(keep, body.free_hz.size)
    _check_rigid_kept(idx, rigid, bool(drop_rigid))
    V = body.free_modes[:, idx]
    omega = 2 * np.pi * body.free_hz[idx]
    return ModalBody(
        name=body.name,
        dofs=body.dofs,
        modes=idx,
        frequencies_hz=body.free_hz[idx].copy(),
        damping_ratios=body.damping_ratios[idx].copy(),
        shapes=body.T @ V,
        boundary_nodes=body.boundary_nodes.copy(),
        boundary_x=body.boundary_x.copy(),
        K=np.diag(omega**2),
        M=np.eye(idx.size),
        C=np.diag(_modal_damping_diagonal(body)[idx]),
    )


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


def cb_check(body: FlexibleBody, part: PartModel) -> CBCheck:
    """Rigid-body mass, symmetry, static exactness and modal effective mass of a reduced part.

    Parameters
    ----------
    body : FlexibleBody
        From :func:`craig_bampton` of ``part``.
    part : PartModel
        The full model it was reduced from.

    Returns
    -------
    CBCheck
    """
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
