"""The Craig–Bampton basis of a solid part: its constraint modes, fixed-interface modes and residual
vectors, solved on its 3D mesh (the numerics behind :func:`~flexshaft.reduction.craig_bampton.craig_bampton`
for a :class:`~flexshaft.parts.solidpart.SolidPartModel`).

The part's end faces are tied to master nodes on the axis (:meth:`SolidPartModel.tie
<flexshaft.parts.solidpart.SolidPartModel.tie>`, rigidly or by averaging). The masters are the
interface: the body keeps their DOFs physical and adds the lowest fixed-interface modes (both faces
held) and the residual vectors, exactly as a 1D part's reduction does, so the assembly, the state
space, the exports and the views take it as they take a 1D one.

- ``dofs = "full"``: each master's six DOFs (u_x, u_y, u_z, θ_x, θ_y, θ_z) are the interface.
- ``dofs = "torsion"``: each master's θ_x alone; its other five DOFs are held (a drivetrain's
  shaft ends sit in bearings and couplings that carry the lateral and axial loads), and only the
  fixed-interface modes that are mostly twist are kept - a torsion model has no lateral or axial
  motion for the others to couple to. For a part of revolution both choices are exact: twist is
  then uncoupled from the other motions. The twist modes come from the Krylov space of the twist
  loads (:func:`~flexshaft.reduction.ritz.twist_ritz`): a few solves, where a Lanczos search would
  first find every bending and axial mode below them (a long tube's first twist mode sits above
  dozens of bending ones).

The interface stiffness is the static condensation of the solid onto the masters, exactly
(Craig-Bampton's constraint modes), so a twist test on the body is the part's end stiffness
(:func:`flexshaft.analysis.twist.part_stiffness`).

An averaging face's master DOFs are rows C·q of the unknowns, held by Lagrange multipliers
(:class:`~flexshaft.parts.solidties.HeldMasters`, the one RBE3 formulation): the constraint modes
are the least-energy shapes with one master DOF at 1 and the others at 0, the fixed-interface modes
those with every master DOF at 0 (by Rayleigh-Ritz on the Krylov space of the held solves).

Handed a ``cache`` (:class:`flexshaft.input.solidcache.SolidResults`, which the model-file loader gives
every solid part), a basis is solved once: it is kept on disk under its mesh and
:func:`reduction_settings`, and read back by later runs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..elements.materials import Material
from ..elements.tetmesh import TET10_EDGES, TetMesh
from ..errors import ModelError
from ..linalg.eigen import lowest_modes
from ..linalg.multigrid import linear_coarse_space
from ..linalg.spd import SpdSolver, rigid_displacements
from ..parts.solidpart import SOLVERS, SolidPartModel
from ..parts.solidties import interface_kinds
from ..system.threads import follows_policy
from .axisline import SolidShapes, solid_shapes
from .flexiblebody import check_mode_choice
from .ritz import (
    MAX_RITZ_BLOCKS,
    MODES_TOL,
    RESIDUAL_RTOL,
    RITZ_CONVERGED,
    RITZ_RTOL,
    RITZ_START,
    TWIST_SHARE,
    mode_signs,
    residual_at_tolerance,
    ritz,
    trial_shapes,
    twist_ritz,
)

__all__ = [
    "MAX_MODE_SEARCH",
    "SolidReduction",
    "reduction_settings",
    "result_settings",
    "solid_basis",
    "solver_settings",
]

#: Most fixed-interface modes searched for the twist modes a torsion body keeps (a stubby part's
#: lowest modes may be bending and axial ones).
MAX_MODE_SEARCH = 400


@dataclass(frozen=True)
class SolidReduction:
    """A solid part reduced onto its masters, before a line and damping are chosen
    (:func:`solid_basis`; :func:`~flexshaft.reduction.axisline.body_on_line` makes the flexible body).

    Attributes
    ----------
    mesh : TetMesh
    dofs : {"full", "torsion"}
    K, M : ndarray (nb + nm, nb + nm)
        Reduced stiffness and mass: boundary DOFs first (start's, then end's), then the modal
        coordinates.
    eigenvalues : ndarray (nm,)
        The modal coordinates' fixed-interface eigenvalues (Ritz values for residual vectors), (rad/s)².
    n_residual : int
    full : ndarray (3n, nb + nm)
        Every mesh node's u_x, u_y, u_z per reduced coordinate, m.
    shapes : SolidShapes
    slab : float
        The thickness of the slabs sections are read in, m.
    rigid_boundary : ndarray (nb, r)
        The rigid-body motions about the start master at the boundary DOFs (r = 6; torsion 1).
    rigid_mass_full : ndarray (r, r)
        Rᵀ M R of the whole mesh for those motions (kg, kg·m, kg·m²).
    static_residual : float
        ‖K_ii Ψ + K_ib‖ / ‖K_ib‖ of the constraint modes (Frobenius): how exactly they condense.
    lines : dict
        The axis lines :func:`~flexshaft.reduction.axisline.body_on_line` recovered (their x's bytes
        -> T), kept: one command assembles a model several times on the same lines (the mesh check,
        the twist test, the modes).
    """

    mesh: TetMesh
    dofs: str
    K: np.ndarray
    M: np.ndarray
    eigenvalues: np.ndarray
    n_residual: int
    full: np.ndarray
    shapes: SolidShapes
    slab: float
    rigid_boundary: np.ndarray
    rigid_mass_full: np.ndarray
    static_residual: float
    lines: dict = field(default_factory=dict, repr=False, compare=False)


def solver_settings() -> dict:
    """The solver settings a solid part's results depend on, as plain values (part of their cache
    key: results computed to other tolerances are other entries)."""
    from ..linalg import lobpcg, spd

    return {
        "rtol": spd.RTOL,
        "direct_max": spd.DIRECT_MAX,
        "ritz_rtol": RITZ_RTOL,
        "residual_rtol": RESIDUAL_RTOL,
        "ritz_converged": RITZ_CONVERGED,
        "ritz_start": RITZ_START,
        "ritz_blocks": MAX_RITZ_BLOCKS,
        "twist_share": TWIST_SHARE,
        "mode_search": MAX_MODE_SEARCH,
        "lobpcg_tol": lobpcg.TOL,
        "modes_tol": MODES_TOL,
    }


def result_settings(result: str, material: Material, **choices) -> dict:
    """What a solid part's ``result`` (``"solid reduction"``, ``"solid stiffness"``, ``"solid
    modes"``) depends on besides its mesh, as plain JSON values - its cache key: the material
    (E, ν, ρ), the caller's ``choices`` and the solver's settings (:func:`solver_settings`)."""
    return {
        "result": result,
        "material": [float(material.E), float(material.nu), float(material.rho)],
        **choices,
        "solver": solver_settings(),
    }


def reduction_settings(
    material: Material,
    *,
    dofs="full",
    modes=None,
    cutoff_hz=None,
    residual=True,
    method="auto",
    interface="rigid",
) -> dict:
    """Everything a solid reduction depends on besides its mesh, checked, as plain JSON values: the
    material (E, ν, ρ), the interface DOFs and ties, the modes asked for, the residual vectors, the
    solver and its tolerances (:func:`solver_settings`). :func:`solid_basis`'s cache key."""
    if dofs not in ("full", "torsion"):
        raise ModelError("unknown DOFs", field="dofs", value=dofs, valid="full or torsion")
    check_mode_choice(modes, cutoff_hz)
    if not isinstance(material, Material):
        raise ModelError(
            "not a material", field="material", value=type(material).__name__, valid="a Material"
        )
    return result_settings(
        "solid reduction",
        material,
        dofs=dofs,
        modes=None if modes is None else int(modes),
        cutoff_hz=None if cutoff_hz is None else float(cutoff_hz),
        residual=bool(residual),
        method=str(method),
        interface=list(interface_kinds(interface)),
    )


@follows_policy
def solid_basis(
    part: SolidPartModel,
    *,
    modes: int | None = None,
    cutoff_hz: float | None = None,
    residual: bool = True,
    solver: str = "auto",
    progress: Callable[[str, float | None], None] | None = None,
    cache=None,
) -> SolidReduction:
    """A solid part reduced onto its two master nodes plus fixed-interface modes (module docstring).

    Parameters
    ----------
    part : SolidPartModel
        The mesh (with the face sets ``"start"`` and ``"end"``), material, interface DOFs and ties.
    modes : int, optional
        Fixed-interface modes kept (a torsion body: twist modes).
    cutoff_hz : float, optional
        Keep every fixed-interface mode below this frequency, Hz (instead of ``modes``).
    residual : bool
        Add the residual vectors (``modes = 0`` and ``residual = False``: the static condensation
        alone, which a twist test needs).
    solver : {"auto", "direct", "amg"}
        The linear solver (:class:`~flexshaft.linalg.spd.SpdSolver`): by size, a sparse LU, or
        conjugate gradients with multigrid.
    progress : callable, optional
        ``progress(stage, fraction)``.
    cache : optional
        Where solid results are kept between runs (:class:`flexshaft.input.solidcache.SolidResults`:
        ``load(mesh, settings)`` and ``store(mesh, settings, result)``), keyed by the mesh and
        :func:`reduction_settings`; None: always computed.

    Returns
    -------
    SolidReduction
    """
    report = progress if progress is not None else (lambda stage, fraction: None)
    if solver not in SOLVERS:
        raise ModelError("unknown solver", field="solver", value=solver, valid=", ".join(SOLVERS))
    settings = reduction_settings(
        part.material,
        dofs=part.dofs,
        modes=modes,
        cutoff_hz=cutoff_hz,
        residual=residual,
        method=solver,
        interface=part.interface,
    )

    def solve():
        reduction = _reduction(part, modes, cutoff_hz, residual, solver, report)
        report("done", 1.0)
        return reduction

    if cache is None:
        return solve()
    reduction, read = cache.kept(part.mesh, settings, solve)
    if read:
        report("read from the cache", 1.0)
    return reduction


def _rigid_check(tied, M, dofs: str, nodes) -> tuple[np.ndarray, np.ndarray]:
    """The rigid-body motions about the start master at the boundary DOFs (nb, r) and the whole
    mesh's rigid-body mass Rᵀ M R for them (r, r): what :func:`~flexshaft.reduction.check.cb_check`
    holds a solid body's against."""
    x_start, x_end = tied.faces[0].master, tied.faces[1].master
    R = rigid_displacements(nodes, x_start).reshape(-1, 6)
    pick = slice(None) if dofs == "full" else slice(3, 4)
    rigid_mass_full = (R.T @ (M @ R))[pick, pick]
    at_end = np.zeros((6, 6))
    at_end[:3] = rigid_displacements(x_end[None], x_start)[0]
    at_end[3:, 3:] = np.eye(3)
    rigid_boundary = np.vstack([np.eye(6), at_end])[:, pick]
    if dofs == "torsion":
        rigid_boundary = rigid_boundary[[3, 9]]
    return rigid_boundary, rigid_mass_full


def _reduction(part: SolidPartModel, modes, cutoff_hz, residual, solver, report) -> SolidReduction:
    """:func:`solid_basis`'s work, its arguments checked."""
    mesh, dofs = part.mesh, part.dofs
    nodes = mesh.nodes
    length = mesh.length
    report("assembling the solid", 0.0)
    mats = part.matrices()
    # rigid faces are eliminated (their nodes follow their master); averaging faces' nodes stay free
    tied = part.tie(mats.K, mats.M)
    rigid_boundary, rigid_mass_full = _rigid_check(tied, mats.M, dofs, nodes)
    del mats  # the tied matrices are what the solves need: the mesh's own go before them
    # the first unknowns are the free nodes' DOFs, in their order (then a rigid face's master's)
    inner = tied.inner()
    slab = max(float(mesh.size), 1e-3 * length)  # the slabs sections are read in, m
    how = {
        "dofs": dofs,
        "n_keep": None if modes is None else int(modes),
        "cutoff_hz": cutoff_hz,
        "residual": residual,
        "inner": inner,
        "slab": slab,
        "report": report,
    }
    what = f"{mesh.name}'s solid with both ends held"
    if "average" in part.interface:
        Q, lam, n_res, static_residual = _held_averages_basis(mesh, tied, solver, what, **how)
    else:
        Q, lam, n_res, static_residual = _tied_basis(mesh, tied, solver, what, **how)
    report("reduced matrices", 0.9)
    Kr, Mr = Q.T @ (tied.K @ Q), Q.T @ (tied.M @ Q)
    full = np.asarray(tied.T @ Q)
    del Q
    shapes = solid_shapes(mesh, full, part.statement)
    return SolidReduction(
        mesh, dofs, Kr, Mr, lam, n_res, full, shapes, slab, rigid_boundary, rigid_mass_full, static_residual
    )


def _modes_wanted(n_keep) -> bool:
    """Whether any fixed-interface mode is asked for (``modes = 0``: the static condensation)."""
    return n_keep is None or n_keep > 0


def _tied_basis(mesh, tied, strategy, what, *, dofs, n_keep, cutoff_hz, residual, inner, slab, report):
    """Both end faces rigid: the masters' DOFs are unknowns of the tied system, partitioned off as
    the boundary (and, in torsion, the held five of each). Returns (Q, eigenvalues, residual vectors,
    the constraint modes' residual): Q (m, nb + nm) maps the reduced coordinates to the unknowns."""
    system, Kc, Mc = tied.system, tied.K, tied.M
    m = Kc.shape[0]
    start, end = system.masters["start"], system.masters["end"]
    # the boundary: both masters' six DOFs, or their θx (the other five of each are held)
    b = np.concatenate([start, end]) if dofs == "full" else np.array([start[3], end[3]])
    # the interior is every unknown but the masters' (boundary or held), and constrain puts the free
    # nodes' DOFs first, the masters' after them: a leading block, sliced rather than gathered
    # (scipy's fancy column indexing takes ~5 s per matrix at a million DOFs)
    nf = m - 12
    i = np.arange(nf)
    Kii, Kib = Kc[:nf, :nf], Kc[:nf, nf:][:, b - nf]
    Mii, Mib = Mc[:nf, :nf], Mc[:nf, nf:][:, b - nf]
    near = system.near_null[:nf]
    report("constraint modes", 0.1)
    # the mesh's linear elements as the multigrid's first coarse level (half the iterations)
    coarse = linear_coarse_space(mesh.tets, system.T, i, edges=TET10_EDGES)
    solver = SpdSolver(Kii, near_null=near, method=strategy, what=what, coarse=coarse)
    Kib = Kib.toarray()
    psi = -solver.solve(Kib)
    static_residual = float(np.linalg.norm(Kii @ psi + Kib) / max(np.linalg.norm(Kib), np.finfo(float).tiny))
    n_keep = None if n_keep is None else min(n_keep, i.size)
    phi, lam = np.zeros((i.size, 0)), np.zeros(0)
    if dofs == "torsion" and _modes_wanted(n_keep):
        report("fixed-interface twist modes", 0.3)
        load = np.asarray(Mii @ psi) + Mib.toarray()  # the inertia of the masters' unit twist accelerations
        lam, phi = twist_ritz(solver, Kii, Mii, load, inner, slab, n_keep, cutoff_hz)
    elif _modes_wanted(n_keep):
        report("fixed-interface modes", 0.3)
        trial = trial_shapes(inner, mesh.length)
        want = max(n_keep or 0, 8)
        while True:
            want = min(want, MAX_MODE_SEARCH, i.size - 1)
            sol = lowest_modes(
                Kii, Mii, want, trial=trial, near_null=near, preconditioner=solver, tol=MODES_TOL
            )
            lam, phi = sol.eigenvalues, sol.vectors
            f = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
            enough = lam.size >= n_keep if n_keep is not None else f[-1] > cutoff_hz
            if enough or want >= min(MAX_MODE_SEARCH, i.size - 1):
                break
            want *= 2
        keep = np.arange(lam.size) < n_keep if n_keep is not None else f < cutoff_hz
        lam, phi = lam[keep], phi[:, keep]
    phi = phi * mode_signs(inner, phi)
    n_res = 0
    if residual:
        report("residual vectors", 0.8)
        if phi.shape[1]:  # the residual vectors' solves start from what the modes carry
            solver.start_from_modes(phi, lam)
        res, lam_res = residual_at_tolerance(solver, Kii, Mii, Mib, psi, phi)
        phi, lam, n_res = np.hstack([phi, res]), np.concatenate([lam, lam_res]), lam_res.size
    nb, nm = b.size, phi.shape[1]
    Q = np.zeros((m, nb + nm))
    Q[b, np.arange(nb)] = 1.0
    Q[i, :nb] = psi
    Q[i, nb:] = phi
    return Q, lam, n_res, static_residual


def _held_averages_basis(
    mesh, tied, strategy, what, *, dofs, n_keep, cutoff_hz, residual, inner, slab, report
):
    """An averaging end face (or two): the masters' DOFs are the rows C·q of the unknowns, held by
    Lagrange multipliers (:meth:`~flexshaft.parts.solidpart.TiedSolid.held`). The constraint modes are
    the least-energy shapes with one master DOF at 1 and the others at 0 (no solve beyond the twelve of
    Y); the fixed-interface modes - every row of C at zero - by Rayleigh-Ritz on the Krylov space of
    the held solves (twist modes in torsion, every mode in 6 DOFs); the residual vectors as in
    :func:`_tied_basis`. Returns what :func:`_tied_basis` returns."""
    Kc, Mc, C = tied.K, tied.M, tied.C
    m = Kc.shape[0]
    b = np.arange(12) if dofs == "full" else np.array([3, 9])  # the rest of C's rows are held at zero
    report("constraint modes", 0.1)
    held = tied.held(C, strategy, what)
    psi = held.constraint_modes(b)
    # Kc Ψ must lie in the range of Cᵀ (the multipliers' forces): its part outside it, relative
    KP = np.asarray(Kc @ psi)
    CCt = (C @ C.T).toarray()
    mu = np.linalg.solve(CCt, np.asarray(C @ KP))
    static_residual = float(np.linalg.norm(KP - C.T @ mu) / max(np.linalg.norm(KP), np.finfo(float).tiny))
    rows = 3 * inner.shape[0]
    phi, lam = np.zeros((m, 0)), np.zeros(0)
    if _modes_wanted(n_keep):
        load = np.asarray(Mc @ psi)  # the inertia of the masters' unit accelerations
        if dofs == "torsion":
            report("fixed-interface twist modes", 0.3)
            lam, phi = twist_ritz(held, Kc, Mc, load, inner, slab, n_keep, cutoff_hz)
        else:
            report("fixed-interface modes", 0.3)
            trial = np.zeros((m, 4))
            trial[:rows] = trial_shapes(inner, mesh.length)
            lam, phi = ritz(
                held,
                Kc,
                Mc,
                np.hstack([load, np.asarray(Mc @ trial)]),
                lambda v: np.ones(v.shape[1], dtype=bool),
                n_keep,
                cutoff_hz,
            )
    phi = phi * mode_signs(inner, phi[:rows])
    n_res = 0
    if residual:
        report("residual vectors", 0.8)
        res, lam_res = residual_at_tolerance(held, Kc, Mc, sp.csr_matrix((m, b.size)), psi, phi)
        phi, lam, n_res = np.hstack([phi, res]), np.concatenate([lam, lam_res]), lam_res.size
    return np.hstack([psi, phi]), lam, n_res, static_residual
