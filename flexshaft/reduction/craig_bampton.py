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

from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla

from ..errors import ModelError
from ..linalg.eigen import lowest_modes
from ..linalg.spd import SpdSolver
from ..parts.model import PartModel, smooth_trial_shapes
from ..parts.solidpart import SOLVERS, SolidPartModel
from ..system.threads import follows_policy
from .axisline import body_on_line
from .flexiblebody import FlexibleBody, check_mode_choice, reduced_body, residual_vectors
from .solidbasis import solid_basis

__all__ = ["FlexibleBody", "check_mode_choice", "craig_bampton", "reduced_body", "residual_vectors"]


@follows_policy
def craig_bampton(
    part,
    *,
    modes: int | None = None,
    cutoff_hz: float | None = None,
    nodes=(),
    damping_ratio=0.0053,
    residual: bool = True,
    solver: str = "auto",
    line_x=None,
    progress: Callable[[str, float | None], None] | None = None,
    cache=None,
) -> FlexibleBody:
    """Reduce a part model - 1D or solid - to its interface DOFs plus fixed-interface modes.

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

    A solid part (:class:`~flexshaft.parts.solidpart.SolidPartModel`) is reduced the same way onto
    its two master nodes (:mod:`flexshaft.reduction.solidbasis`: constraint modes, fixed-interface
    modes by Ritz blocks or LOBPCG, residual vectors), and its body's ``T`` recovers an axis line
    (:mod:`flexshaft.reduction.axisline`). Only the linear solver differs with the size: ``solver``.

    Parameters
    ----------
    part : PartModel or SolidPartModel
        From :func:`flexshaft.parts.model.part_model` or
        :func:`flexshaft.parts.solidpart.solid_part_model`.
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
    solver : {"auto", "direct", "amg"}
        The linear solver of the interior: ``"auto"`` by size - a sparse LU for a 1D part (banded)
        and for a solid up to :data:`~flexshaft.linalg.spd.DIRECT_MAX` unknowns, conjugate gradients
        preconditioned by multigrid beyond - or the one named (:class:`~flexshaft.linalg.spd.SpdSolver`).
    line_x : array, optional
        A solid part: the axis line its body's ``T`` recovers, m from its start (default: its ends).
    progress : callable, optional
        A solid part: ``progress(stage, fraction)`` as its reduction goes.
    cache : optional
        A solid part: where its reduction is kept between runs
        (:class:`flexshaft.input.solidcache.SolidResults`); None: always solved.

    Returns
    -------
    FlexibleBody
    """
    check_mode_choice(modes, cutoff_hz)
    if not isinstance(part, PartModel):
        if not isinstance(part, SolidPartModel):
            kind = type(part).__name__
            raise ModelError("not a part model", field="part", value=kind, valid="a 1D or solid part model")
        if len(nodes):
            raise ModelError(
                "a solid part's interface is its two end faces",
                field="nodes",
                value=list(nodes),
                valid="no extra boundary nodes",
            )
        how = {"modes": modes, "cutoff_hz": cutoff_hz, "residual": residual, "solver": solver}
        reduction = solid_basis(part, progress=progress, cache=cache, **how)
        return body_on_line(reduction, line_x=line_x, damping_ratio=damping_ratio)
    if solver not in SOLVERS:
        raise ModelError("unknown solver", field="solver", value=solver, valid=", ".join(SOLVERS))
    return _one_d_body(part, modes, cutoff_hz, nodes, damping_ratio, residual, solver)


def _one_d_body(part: PartModel, modes, cutoff_hz, nodes, damping_ratio, residual, solver) -> FlexibleBody:
    """:func:`craig_bampton` of a 1D part, its arguments checked."""
    nb_nodes = np.unique(np.concatenate([np.asarray(part.interface_nodes), np.asarray(nodes, int)]))
    b = part.nodes_dofs(nb_nodes)
    i = np.setdiff1d(np.arange(part.n_dofs), b)
    K, M = part.K.tocsr(), part.M.tocsr()
    Kii, Kib = K[i][:, i].tocsc(), K[i][:, b]
    Mii = M[i][:, i]
    # a 1D part is banded: a sparse LU by default, multigrid only when asked
    lu = spla.splu(Kii) if solver != "amg" else SpdSolver(Kii, method="amg", what=f"{part.name}'s interior")
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
