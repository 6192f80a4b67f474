"""Craig–Bampton reduction of a solid part: a flexible body from its 3D mesh.

The part's 10-node tetrahedra (:mod:`flexshaft.elements.tet10`) have their end faces tied to master
nodes on the axis (rigidly by default, RBE2, :mod:`flexshaft.parts.solid`). The masters are the interface: the
body keeps their DOFs physical and adds the lowest fixed-interface modes (both faces held) and the
residual vectors, exactly as :func:`~flexshaft.reduction.craig_bampton.craig_bampton` does for a 1D
part, so the assembly, the state space, the exports and the views take it as they take a 1D one.

- ``dofs = "full"``: each master's six DOFs (u_x, u_y, u_z, θ_x, θ_y, θ_z) are the interface.
- ``dofs = "torsion"``: each master's θ_x alone; its other five DOFs are held (a drivetrain's
  shaft ends sit in bearings and couplings that carry the lateral and axial loads), and only the
  fixed-interface modes that are mostly twist are kept - a torsion model has no lateral or axial
  motion for the others to couple to. For a part of revolution both choices are exact: twist is
  then uncoupled from the other motions. The twist modes come from the Krylov space of the twist
  loads (:func:`_twist_ritz`): a few solves, where a Lanczos search would first find every bending
  and axial mode below them (a long tube's first twist mode sits above dozens of bending ones).

The interface stiffness is the static condensation of the solid onto the masters, exactly
(Craig-Bampton's constraint modes), so a twist test on the body is the solid twist test
(:func:`flexshaft.analysis.solidstiffness.solid_stiffness`).

An end face may instead be tied by averaging (RBE3, ``interface="average"``, per face): its master's
DOFs are then the face's least-squares rigid motion, rows C·q of the unknowns rather than unknowns
of their own, and the face deforms freely. The reduction holds them by Lagrange multipliers
(:class:`_HeldMasters`): the constraint modes are the least-energy shapes with one master DOF at 1
and the others at 0, the fixed-interface modes those with every master DOF at 0 (by Rayleigh-Ritz on
the Krylov space of the held solves), and the body takes the masters' DOFs as its boundary as before.

The body's ``T`` recovers an axis line (the part's 1D mesh nodes, where the chain's stations,
plots and exports read rotations): at each line node the least-squares rigid motion (varying
linearly along the axis) of the solid's nodes in a slab one element size thick across the axis
there - the section's mean translation and rotation; at the two ends the masters themselves.
Its ``solid`` carries the surface of the mesh and the displacement of the surface's nodes per
reduced coordinate (for views on the part's own surface).

Handed a ``cache`` (:class:`flexshaft.input.solidcache.SolidResults`, which the model-file loader gives
every solid part), a reduction is solved once: it is kept on disk under its mesh and
:func:`reduction_settings`, and read back by later runs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from ..elements.materials import Material
from ..elements.tet10 import solid_matrices
from ..elements.tetmesh import TET10_EDGES, TetMesh
from ..errors import ModelError
from ..linalg.eigen import lowest_modes
from ..linalg.multigrid import linear_coarse_space
from ..linalg.spd import SpdSolver, rigid_displacements
from ..parts.solid import (
    ENDS,
    averaging_interface,
    constrain,
    determinate_support,
    interface_kinds,
    interface_statement,
    rigid_interface,
)
from ..system.threads import follows_policy
from .check import CBCheck
from .craig_bampton import FlexibleBody, check_mode_choice, reduced_body, residual_vectors

__all__ = [
    "SolidReduction",
    "SolidShapes",
    "reduction_settings",
    "solid_shapes",
    "result_settings",
    "solver_settings",
    "solid_body",
    "solid_craig_bampton",
    "solid_reduction",
    "solid_check",
    "surface_triangles",
    "twist_share",
    "TWIST_SHARE",
    "MAX_MODE_SEARCH",
]

#: A fixed-interface mode counts as twist (kept in a torsion body) when more than this share of its
#: Σ|u|² is sections turning about the axis (:func:`twist_share`): a part of revolution's modes are
#: near 1 or near 0, a bolted flange's within a few per cent of those.
TWIST_SHARE = 0.5
#: Most fixed-interface modes searched for the twist modes a torsion body keeps (a stubby part's
#: lowest modes may be bending and axial ones).
MAX_MODE_SEARCH = 400
#: Axis lines a reduction keeps the recovery of (:attr:`SolidReduction.lines`): each is small, the
#: number of nodes on the line times the reduced coordinates.
LINES_KEPT = 8
#: The DOFs of a master node, in the order of a 1D part's node (:data:`flexshaft.parts.model.DOF_NAMES`).
MASTER_DOFS = ("ux", "uy", "uz", "θx", "θy", "θz")


@dataclass(frozen=True)
class SolidShapes:
    """A solid body's surface and its displacement per reduced coordinate.

    Attributes
    ----------
    mesh : TetMesh
        The part's mesh (m, the part's frame: x along the axis from its start).
    nodes : ndarray of int (k,)
        The surface's nodes (corners of the boundary triangles) in ``mesh``.
    triangles : ndarray of int (t, 3)
        The boundary triangles, as rows into ``nodes``, outward.
    U : ndarray (3k, nb + nm), float32
        u_x, u_y, u_z of each surface node (node-major), m, per unit reduced coordinate.
    interface : str
        How the end faces are tied, as results state it (``"end faces rigid (RBE2)"``).
    """

    mesh: TetMesh
    nodes: np.ndarray
    triangles: np.ndarray
    U: np.ndarray
    interface: str


def surface_triangles(tets: np.ndarray, *, midside: bool = False) -> np.ndarray:
    """The boundary triangles (outward) of a mesh of positively oriented 10-node tetrahedra: the faces
    that belong to one tetrahedron only - their corners (t, 3), or with ``midside`` each curved face
    cut at its mid-side nodes into four flat ones (4t, 3), which follow the curved geometry."""
    tets = np.asarray(tets)
    # each face opposite a corner, ordered so that its normal points away from that corner
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    faces = np.concatenate([tets[:, f] for f in local])
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    boundary = first[counts == 1]
    if not midside:
        return faces[boundary]
    # the mid-side node of each local corner pair (VTK order: TET10_EDGES are nodes 4-9)
    edge = {pair: 4 + k for k, pair in enumerate(TET10_EDGES)}
    edge |= {(b, a): n for (a, b), n in list(edge.items())}
    n_tets = tets.shape[0]
    which, tet = boundary // n_tets, boundary % n_tets
    out = []
    for f, corners in enumerate(local):
        rows = tet[which == f]
        a, b, c = (tets[rows, k] for k in corners)
        ab, bc, ca = (
            tets[rows, edge[pair]]
            for pair in ((corners[0], corners[1]), (corners[1], corners[2]), (corners[2], corners[0]))
        )
        out += [np.column_stack(t) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
    return np.concatenate(out)


#: A slab's fit of a rigid motion and its slope along x is taken when the fit's columns (scaled to unit
#: length) have a condition number below this: its normal equations then lose at most ~cond²·1e-16 =
#: 1e-8 of the fit; a slab too thin or too sparse to fix the motion and its slope is widened.
SLAB_CONDITION = 1e4


def _slab_fit(R: np.ndarray, F: np.ndarray, pick) -> np.ndarray | None:
    """Rows ``pick`` of the least-squares fit (RᵀR)⁻¹RᵀF of a slab's motions R (3k, 12) to the fields
    F (3k, m), or None when R's scaled columns are not well conditioned (:data:`SLAB_CONDITION`).

    The normal equations of the columns scaled to unit length: a 12 x 12 solve after one pass over
    R and F, where an SVD of R (``numpy.linalg.pinv``) factorises the whole tall matrix (PTSS part 2's
    slabs: ~9 000 nodes, 45 ms a line node by two SVDs, under 1 ms this way).
    """
    scale = np.sqrt(np.einsum("ij,ij->j", R, R))
    if not np.all(scale > 0):
        return None
    w, V = np.linalg.eigh((R.T @ R) / np.outer(scale, scale))
    if not w[0] > w[-1] / SLAB_CONDITION**2:
        return None
    return ((V[pick] / w) @ V.T @ ((R.T @ F) / scale[:, None])) / scale[pick, None]


def _line_motions(
    nodes: np.ndarray, line_x: np.ndarray, width: float, d: int, full: np.ndarray
) -> np.ndarray:
    """(len(line_x)·d, m): each line node's rigid motion (its d DOFs of :data:`MASTER_DOFS`) under each
    of the m fields ``full`` (3n, m: node-major u_x, u_y, u_z), from the nodes within ``width``/2 of
    its x: the least-squares fit of a rigid motion that varies linearly along x, read at the line
    node's point on the axis - exact for a field that is linear across the slab, whatever the nodes'
    spread in x (a plain rigid fit reads it at their centroid)."""
    pick = [3] if d == 1 else list(range(6))
    # the nodes and their fields in the order of x, once: every slab is then a contiguous slice
    order = np.argsort(nodes[:, 0], kind="stable")  # ties (a slab's nodes) in one order on every CPU
    ordered = nodes[order]
    xs = ordered[:, 0]
    m = full.shape[1]
    fields = full.reshape(nodes.shape[0], 3 * m)[order]
    out = np.empty((len(line_x) * d, m))
    for j, xj in enumerate(line_x):
        half = 0.5 * width
        while True:
            lo, hi = np.searchsorted(xs, xj - half), np.searchsorted(xs, xj + half, side="right")
            fit = None
            if hi - lo >= 6:
                R = rigid_displacements(ordered[lo:hi], np.array([xj, 0.0, 0.0]))  # (k, 3, 6)
                R = np.concatenate([R, R * (xs[lo:hi] - xj)[:, None, None]], axis=2).reshape(-1, 12)
                fit = _slab_fit(R, fields[lo:hi].reshape(R.shape[0], m), pick)  # (d, m)
            if fit is not None:
                break
            if hi - lo == nodes.shape[0]:
                raise ModelError(
                    "too few nodes to read a section's motion",
                    field="mesh",
                    value=f"{nodes.shape[0]} nodes",
                    valid="a solid mesh with nodes spread along and across the axis",
                )
            half *= 2.0  # too few nodes to fix the motion and its slope: a wider slab
        out[j * d : (j + 1) * d] = fit
    return out


def solid_shapes(mesh: TetMesh, full: np.ndarray, interface: str) -> SolidShapes:
    """The surface of ``mesh`` and its nodes' displacements from ``full`` (3n, k), for views."""
    tri = surface_triangles(mesh.tets, midside=True)  # flat pieces that follow the curved faces
    surf, tri_rows = np.unique(tri, return_inverse=True)
    sdofs = (3 * surf[:, None] + np.arange(3)).ravel()
    return SolidShapes(mesh, surf, tri_rows.reshape(-1, 3), full[sdofs].astype(np.float32), interface)


def _trial(nodes: np.ndarray, length: float) -> np.ndarray:
    """Clamped-clamped trial shapes (half sines along the axis) in x, y, z and in twist, node-major."""
    s = np.sin(np.pi * np.clip(nodes[:, 0] / length, 0.0, 1.0))
    t = np.zeros((nodes.shape[0], 3, 4))
    for k in range(3):
        t[:, k, k] = s
    t[:, 1, 3], t[:, 2, 3] = -nodes[:, 2] * s, nodes[:, 1] * s
    return t.reshape(-1, 4)


def twist_share(nodes: np.ndarray, shapes: np.ndarray, width: float) -> np.ndarray:
    """Each shape's share of Σ|u|² that is sections turning about the axis.

    The nodes are cut into slabs ``width`` thick along x; in each, the least-squares turn
    θ = Σ r·t / Σ r² of the tangential motions t at radii r, and the share is Σ θ²·Σr² over Σ|u|².
    A twist mode's is near 1 (less its warping); a bending mode's near 0, though half its motion is
    tangential (a section translating along y moves tangentially by −u_y·sin φ, which turns it by
    nothing on the whole).
    """
    u = shapes.reshape(nodes.shape[0], 3, -1)
    r = np.hypot(nodes[:, 1], nodes[:, 2])
    rt = -nodes[:, 2, None] * u[:, 1] + nodes[:, 1, None] * u[:, 2]  # r·t
    slab = np.floor((nodes[:, 0] - nodes[:, 0].min()) / width).astype(np.int64)
    den = np.bincount(slab, weights=r * r)
    num = np.stack([np.bincount(slab, weights=rt[:, k], minlength=den.size) for k in range(rt.shape[1])], 1)
    ok = den > 0
    turned = np.sum(num[ok] ** 2 / den[ok, None], axis=0)
    return turned / np.maximum(np.sum(u * u, axis=(0, 1)), np.finfo(float).tiny)


def _signs(nodes: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """+1 or −1 per mode (on the free nodes): its largest twist (tangential) motion positive, or,
    without twist, its largest translation - flexshaft's one sign convention."""
    u = phi.reshape(nodes.shape[0], 3, -1)
    r = np.hypot(nodes[:, 1], nodes[:, 2])
    safe = np.where(r > 0, r, 1.0)
    t = (-nodes[:, 2, None] * u[:, 1] + nodes[:, 1, None] * u[:, 2]) / safe[:, None]
    signs = np.ones(phi.shape[1])
    flat = phi
    for k in range(phi.shape[1]):
        v = t[:, k] if np.max(np.abs(t[:, k])) > 1e-3 * np.max(np.abs(flat[:, k])) else flat[:, k]
        top = float(np.max(np.abs(v)))
        if top > 0:
            signs[k] = 1.0 if v[np.flatnonzero(np.abs(v) >= (1 - 1e-6) * top)[0]] > 0 else -1.0
    return signs


@dataclass(frozen=True)
class SolidReduction:
    """A solid part reduced onto its masters, before a line and damping are chosen
    (:func:`solid_reduction`; :func:`solid_body` makes the flexible body).

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
        The axis lines :func:`solid_body` recovered (their x's bytes -> T), kept: one command
        assembles a model several times on the same lines (the mesh check, the twist test, the modes).
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


@follows_policy
def solid_craig_bampton(
    mesh: TetMesh, material: Material, *, damping_ratio=0.0053, line_x=None, **how
) -> FlexibleBody:
    """Reduce a solid part to its two master nodes plus fixed-interface modes (module docstring):
    :func:`solid_reduction` with ``how``, then :func:`solid_body` on ``line_x`` with ``damping_ratio``."""
    return solid_body(solid_reduction(mesh, material, **how), line_x=line_x, damping_ratio=damping_ratio)


def solid_body(reduction: SolidReduction, *, line_x=None, damping_ratio=0.0053) -> FlexibleBody:
    """The flexible body of a reduced solid part on an axis line, with its damping.

    Parameters
    ----------
    reduction : SolidReduction
    line_x : array, optional
        The axis line the body's ``T`` recovers, m from the part's start, ascending, from 0 to the
        part's length (default: the two ends).
    damping_ratio : float, sequence or ModalDamping
        As for :func:`~flexshaft.reduction.craig_bampton.craig_bampton`.

    Returns
    -------
    FlexibleBody
        Boundary nodes 0 and len(line_x) − 1 of the line; ``solid`` set.
    """
    mesh = reduction.mesh
    line = np.array([0.0, mesh.length]) if line_x is None else np.asarray(line_x, dtype=float)
    d = 6 if reduction.dofs == "full" else 1
    Tline = reduction.lines.get(line.tobytes())
    if Tline is None:
        nodes = mesh.nodes - [mesh.nodes[:, 0].min(), 0.0, 0.0]
        Tline = _line_motions(nodes, line, reduction.slab, d, reduction.full)
        Tline[:d] = 0.0
        Tline[-d:] = 0.0
        Tline[np.arange(d), np.arange(d)] = 1.0
        Tline[(line.size - 1) * d + np.arange(d), d + np.arange(d)] = 1.0
        if len(reduction.lines) >= LINES_KEPT:
            reduction.lines.pop(next(iter(reduction.lines)))
        reduction.lines[line.tobytes()] = Tline
    return reduced_body(
        name=mesh.name,
        dofs=reduction.dofs,
        boundary_nodes=np.array([0, line.size - 1]),
        boundary_x=line[[0, -1]],
        K=reduction.K,
        M=reduction.M,
        T=Tline.copy(),  # each body its own (the kept one stays as computed)
        eigenvalues=reduction.eigenvalues,
        n_residual=reduction.n_residual,
        damping_ratio=damping_ratio,
        solid=reduction.shapes,
    )


#: LOBPCG's relative residual for a 6-DOF body's fixed-interface modes (:func:`lowest_modes`), where
#: :data:`flexshaft.linalg.lobpcg.TOL` (1e-6) gives eigenvalues to ~1e-10. A Ritz value's error is at
#: most tol²·κ(M)·θ/δ (Kato-Temple; κ(M) = O(10-100) for quadratic tetrahedra, δ the gap to the next
#: mode): ~1e-6 at 1e-4 for modes a few per cent apart, the vectors within tol·√κ(M)·θ/δ, and the
#: body's frequencies as Rayleigh-Ritz on their span move with the square of that. Measured on the test
#: bench's parts 1 and 4 (8 modes, 170 000 and 124 000 DOFs) against 1e-6: fixed-interface modes
#: within 1.2e-11, the body's free-free ones within 4.5e-9, in 73-77 % of the iterations (19 and 10
#: against 26 and 13).
MODES_TOL = 1e-4
#: Krylov blocks the twist modes of a torsion body may take (each one K⁻¹ solve per master).
MAX_RITZ_BLOCKS = 60
#: A Ritz value has converged when a further block moves it by less than this (relative, of λ = ω²:
#: 5e-4 of a frequency). The blocks converge faster than geometrically, so the move bounds what is
#: left: on the test bench's solids (examples/customer1_solid.toml) the second block moved the kept
#: twist modes by up to 2.9e-4 (frequency) and left them within 1.1e-4 of converged (part 2's fourth,
#: 1138 Hz; the others within 3e-5), where 1e-5 took two blocks more on part 2 and one on parts 1 and
#: 4. The chain's modes depend on the space the modes span with the residual vectors, not on each
#: mode being converged: up to 204 Hz they moved by <= 4e-10, at 383 and 515 Hz by 5.5e-7 and 4.3e-6 -
#: all below the mesh's own error (a tube's twist modes at two elements across the wall: 1e-4).
RITZ_CONVERGED = 1e-3
#: Twist loads the Krylov space starts from besides the masters' inertia loads: the inertia of the
#: sections turning as sin(kπx/L), k = 1..RITZ_START (the fixed-fixed twist modes of a uniform part),
#: so that the first block already holds what the higher modes need, and every solve is a block of 8
#: columns (multigrid's products cost less per column in blocks). PTSS part 1: 13 blocks of 2 columns
#: (43 s) became 3 blocks of 8 (24 s).
RITZ_START = 6
#: The relative residual ‖b − Kx‖/‖b‖ of the Krylov blocks' solves. A solve to ε puts its vectors off
#: the exact Krylov space; Rayleigh-Ritz on the space as spanned still bounds every eigenvalue from
#: above, with an error quadratic in its eigenvector's distance to the space in the energy norm
#: (λ_ritz − λ <= λ·tan²∠(φ, space)), so what a solve leaves enters as the square of its energy-norm
#: error. For the blocks' inertia loads (M times smooth shapes) that error is ~20x below the Euclidean
#: residual (PTSS part 1: √(rᵀz / r₀ᵀz₀), z the multigrid's preconditioned residual, 8.6e-4 where
#: ‖r‖/‖b‖ is 1.5e-2). Measured on the test bench's solids (examples/customer1_solid.toml, 124 000 -
#: 545 000 DOFs) against solves to 1e-8: at 1e-2 (and :data:`RESIDUAL_RTOL`) the kept twist modes
#: move by <= 4e-7 and the chain's modes up to 515 Hz by <= 1.5e-8 (all at 1e-3: 2.5e-8 and 7e-9),
#: with 38 % of the CG iterations (per block on parts 1, 2, 4: 11, 17, 6 against 31, 39, 14) - far
#: below a 100 mm mesh's own error, or a tube's at two elements across its wall (1e-4).
RITZ_RTOL = 1e-2
#: The relative residual of the residual vectors' solves (K⁻¹ of the inertia loads the kept modes
#: leave): a few columns, so a tighter one costs little, and their error, not the modes', is what
#: moves the chain's modes most (at 1e-2 their Ritz values moved by up to 1.2e-3, at 1e-3 by 2e-5).
RESIDUAL_RTOL = 1e-3


def _twist_shapes(inner: np.ndarray, n: int) -> np.ndarray:
    """The sections of the nodes ``inner`` turning as sin(kπx/L), k = 1..:data:`RITZ_START` (n, k): the
    fixed-fixed twist modes of a uniform part, on the first 3·len(inner) unknowns (any after them - a
    rigid face's master - at rest)."""
    length = float(np.ptp(inner[:, 0])) or 1.0
    x, turn = inner[:, 0] / length, np.zeros((inner.shape[0], 3))
    turn[:, 1], turn[:, 2] = -inner[:, 2], inner[:, 1]  # the slab's unit turn about the axis
    sines = np.sin(np.pi * x[:, None] * np.arange(1, RITZ_START + 1))  # (nodes, k)
    shapes = np.zeros((n, RITZ_START))
    shapes[: 3 * inner.shape[0]] = (turn[:, :, None] * sines[:, None, :]).reshape(-1, RITZ_START)
    return shapes


def _twist_ritz(solver, Kii, Mii, load, inner, slab, n_keep, cutoff_hz):
    """The lowest twist modes of the fixed-interface solid, by Rayleigh-Ritz on the Krylov space of
    K⁻¹M from the twist inertia loads (load-dependent Ritz vectors, Wilson-Yuan-Dickens): the masters'
    and :data:`RITZ_START` sine-distributed turns'.

    The space K⁻¹F, (K⁻¹M)K⁻¹F, ... from loads that twist the part holds, for a part of revolution,
    its twist modes only (K and M keep the symmetry), so each block costs one solve per load instead
    of the many of a shift-invert Lanczos that finds every bending and axial mode below them first.
    (A part that is not of revolution lets other modes in; the twist share sorts them out.) The first
    3·len(inner) unknowns are the nodes ``inner``'s u_x, u_y, u_z (any after them are not read for the
    twist share). Returns (eigenvalues (rad/s)², M-orthonormal vectors) of the kept twist modes.
    """
    load = np.hstack([load, np.asarray(Mii @ _twist_shapes(inner, Mii.shape[0]))])
    rows = 3 * inner.shape[0]

    def twist(phi):
        return twist_share(inner, phi[:rows], slab) > TWIST_SHARE

    return _ritz(solver, Kii, Mii, load, twist, n_keep, cutoff_hz)


def _ritz(solver, K, M, load, kept, n_keep, cutoff_hz):
    """The lowest ``kept`` modes of (K, M) on the Krylov space of the solver's K⁻¹M from ``load``.

    Blocks are added until the ``n_keep`` lowest kept Ritz values (or those below ``cutoff_hz``, and
    the first above it) move by less than :data:`RITZ_CONVERGED`; ``kept(vectors)`` says which Ritz
    vectors count. Ritz values bound the eigenvalues from above. The solver's solves run at
    :data:`RITZ_RTOL`: Rayleigh-Ritz on a space spanned inexactly still bounds them, and the
    space's error enters the values squared. Returns (eigenvalues (rad/s)², M-orthonormal vectors).
    """
    exact, solver.rtol = solver.rtol, max(solver.rtol, RITZ_RTOL)
    try:
        return _ritz_blocks(solver, K, M, load, kept, n_keep, cutoff_hz)
    finally:
        solver.rtol = exact


def _ritz_blocks(solver, Kii, Mii, load, kept, n_keep, cutoff_hz):
    """:func:`_ritz`'s blocks, with the solver at :data:`RITZ_RTOL`."""
    n = Mii.shape[0]
    V = np.zeros((n, 0))
    KV = np.zeros((n, 0))
    R = solver.solve(load)
    size = float(np.max(np.einsum("ij,ij->j", R, Mii @ R), initial=0.0))
    prev = None
    for _ in range(MAX_RITZ_BLOCKS):
        for _ in range(2):  # M-orthogonal to the basis, twice for round-off
            R = R - V @ (V.T @ (Mii @ R))
        g = R.T @ (Mii @ R)
        mu, U = np.linalg.eigh(0.5 * (g + g.T))
        ok = mu > 1e-20 * max(size, np.finfo(float).tiny)
        if not ok.any():
            break  # the space is exhausted: every mode it can hold is in it
        B = (R @ U[:, ok]) / np.sqrt(mu[ok])
        V, KV = np.hstack([V, B]), np.hstack([KV, Kii @ B])
        k, mm = V.T @ KV, V.T @ (Mii @ V)
        # the generalized problem on the space as spanned (its M-orthonormality holds to round-off
        # only): the Ritz values are then true upper bounds
        lam, W = scipy.linalg.eigh(0.5 * (k + k.T), 0.5 * (mm + mm.T))
        phi = V @ W
        counted = kept(phi)
        lt = lam[counted]
        if n_keep is not None:
            want = lt[:n_keep]
            settled = lt.size >= n_keep
        else:
            below = lt < (2 * np.pi * cutoff_hz) ** 2
            want = lt[: int(below.sum()) + 1]
            settled = not below.all()
        if settled and prev is not None and prev.size >= want.size:
            if np.all(np.abs(prev[: want.size] - want) <= RITZ_CONVERGED * want):
                break
        prev = lt
        R = solver.solve(Mii @ B)
    keep = np.flatnonzero(counted)
    if n_keep is not None:
        keep = keep[:n_keep]
    else:
        keep = keep[lam[keep] < (2 * np.pi * cutoff_hz) ** 2]
    return lam[keep], phi[:, keep]


class _HeldMasters:
    """Solves of a solid part whose masters' DOFs are rows C·q of its unknowns (an averaging face's
    W over its nodes, a rigid face's master unknown itself): K x + Cᵀμ = f with C x = g.

    The part is free (K's null space the rigid motions B); six DOFs of a statically determinate
    support (:func:`~flexshaft.parts.solid.determinate_support`) are removed and the rest solved by
    :class:`~flexshaft.linalg.spd.SpdSolver` - exact for an equilibrated load, which meets no
    reaction there. With Y = K_p⁻¹Cᵀ (twelve solves, once), x = K_p⁻¹f − Yμ + B·a, and the 18
    unknowns (μ, a) from equilibrium Bᵀ(f − Cᵀμ) = 0 and C x = g: one support solve per load.
    """

    def __init__(self, K, C, near_null, keep, solver):
        self.C, self.B, self.keep, self.solver = C, near_null, keep, solver
        self.n = K.shape[0]
        self.Y = self._support_solve(C.T.toarray())
        CB, CY = C @ self.B, C @ self.Y
        nc, nr = C.shape[0], self.B.shape[1]
        A = np.zeros((nr + nc, nc + nr))
        A[:nr, :nc] = CB.T
        A[nr:, :nc] = -CY
        A[nr:, nc:] = CB
        # rows and columns scaled to unit size: μ (forces over lengths) and a (rigid motions) differ
        # by many orders of magnitude
        self._rows = 1.0 / np.abs(A).max(axis=1)
        A *= self._rows[:, None]
        self._cols = 1.0 / np.abs(A).max(axis=0)
        self._lu = scipy.linalg.lu_factor(A * self._cols)
        self._nc = nc

    @property
    def rtol(self) -> float:
        return self.solver.rtol

    @rtol.setter
    def rtol(self, value: float) -> None:
        self.solver.rtol = value

    def _support_solve(self, F):
        x = np.zeros((self.n, F.shape[1]))
        x[self.keep] = self.solver.solve(F[self.keep])
        return x

    def solve(self, F, G=None):
        """x for each column of the loads F (m, k) (and the masters' values G (rows of C, k); 0)."""
        F = np.asarray(F, dtype=float)
        cols = F.reshape(self.n, -1)
        x0 = self._support_solve(cols)
        target = -(self.C @ x0) if G is None else G - self.C @ x0
        rhs = np.vstack([self.B.T @ cols, target]) * self._rows[:, None]
        sol = scipy.linalg.lu_solve(self._lu, rhs) * self._cols[:, None]
        x = x0 - self.Y @ sol[: self._nc] + self.B @ sol[self._nc :]
        return x.reshape(F.shape)

    def constraint_modes(self, b):
        """The least-energy shapes with master row b[j] at 1 and every other row at 0 (m, len(b))."""
        G = np.zeros((self.C.shape[0], len(b)))
        G[b, np.arange(len(b))] = 1.0
        return self.solve(np.zeros((self.n, len(b))), G)


def _master_rows(mesh: TetMesh, system, faces, kinds) -> sp.csr_matrix:
    """C (12, m): the start's then the end's master DOFs (:data:`MASTER_DOFS`) as rows over the tied
    unknowns - an averaging face's W at its nodes' u_x, u_y, u_z, a rigid face's own master unknowns."""
    where = np.full(mesh.n_nodes, -1)
    where[system.free_nodes] = np.arange(system.free_nodes.size)
    rows, cols, vals = [], [], []
    for j, (face, kind) in enumerate(zip(faces, kinds, strict=True)):
        if kind == "rigid":
            rows.append(6 * j + np.arange(6))
            cols.append(system.masters[face.name])
            vals.append(np.ones(6))
        else:
            dof = (3 * where[face.nodes][:, None] + np.arange(3)).ravel()
            r, c = np.nonzero(face.W)
            rows.append(6 * j + r)
            cols.append(dof[c])
            vals.append(face.W[r, c])
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(12, system.K.shape[0])
    )


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
    solver and its tolerances (:func:`solver_settings`). :func:`solid_reduction`'s cache key."""
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
def solid_reduction(
    mesh: TetMesh,
    material: Material,
    *,
    dofs: str = "full",
    modes: int | None = None,
    cutoff_hz: float | None = None,
    residual: bool = True,
    method: str = "auto",
    interface="rigid",
    progress: Callable[[str, float | None], None] | None = None,
    cache=None,
) -> SolidReduction:
    """Reduce a solid part onto its two master nodes plus fixed-interface modes (module docstring).

    Parameters
    ----------
    mesh : TetMesh
        The part's mesh with the face sets ``"start"`` and ``"end"``.
    material : Material
    dofs : {"full", "torsion"}
        The interface: six DOFs per master, or θ_x alone.
    modes : int, optional
        Fixed-interface modes kept (a torsion body: twist modes).
    cutoff_hz : float, optional
        Keep every fixed-interface mode below this frequency, Hz (instead of ``modes``).
    residual : bool
        Add the residual vectors (``modes = 0`` and ``residual = False``: the static condensation
        alone, which a twist test needs).
    method : {"auto", "direct", "amg"}
        The linear solver (:class:`~flexshaft.linalg.spd.SpdSolver`).
    interface : {"rigid", "average"} or (start, end)
        How the end faces are tied to their masters (:data:`~flexshaft.parts.solid.INTERFACES`), both
        alike or each its own.
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
    settings = reduction_settings(
        material,
        dofs=dofs,
        modes=modes,
        cutoff_hz=cutoff_hz,
        residual=residual,
        method=method,
        interface=interface,
    )
    if cache is not None:
        kept = cache.load(mesh, settings)
        if kept is not None:
            report("read from the cache", 1.0)
            return kept
    reduction = _reduction(mesh, material, dofs, modes, cutoff_hz, residual, method, interface, report)
    report("done", 1.0)
    if cache is not None:
        cache.store(mesh, settings, reduction)
    return reduction


def _reduction(mesh, material, dofs, modes, cutoff_hz, residual, method, interface, report) -> SolidReduction:
    """:func:`solid_reduction`'s work, its arguments checked."""
    kinds = interface_kinds(interface)
    nodes = mesh.nodes
    length = mesh.length
    report("assembling the solid", 0.0)
    mats = solid_matrices(mesh, material)
    faces = [
        rigid_interface(mesh, end) if kind == "rigid" else averaging_interface(mesh, end)
        for end, kind in zip(ENDS, kinds, strict=True)
    ]
    # rigid faces are eliminated (their nodes follow their master); averaging faces' nodes stay free
    system = constrain(mats.K, mesh, [f for f, k in zip(faces, kinds, strict=True) if k == "rigid"])
    Tt = system.T
    Kc = system.K
    Mc = (Tt.T @ mats.M @ Tt).tocsr()
    # the rigid-body motions about the start master, for the check of the reduction (cb_check's)
    x_start, x_end = faces[0].master, faces[1].master
    R = rigid_displacements(nodes, x_start).reshape(-1, 6)
    pick = slice(None) if dofs == "full" else slice(3, 4)
    rigid_mass_full = (R.T @ (mats.M @ R))[pick, pick]
    del R, mats
    at_end = np.zeros((6, 6))
    at_end[:3] = rigid_displacements(x_end[None], x_start)[0]
    at_end[3:, 3:] = np.eye(3)
    rigid_boundary = np.vstack([np.eye(6), at_end])[:, pick]
    if dofs == "torsion":
        rigid_boundary = rigid_boundary[[3, 9]]
    # the first unknowns are the free nodes' DOFs, in their order (then a rigid face's master's)
    inner = nodes[system.free_nodes] - [nodes[:, 0].min(), 0.0, 0.0]
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
    if "average" in kinds:
        Q, lam, n_res, static_residual = _held_averages_basis(
            mesh, system, _master_rows(mesh, system, faces, kinds), Kc, Mc, method, what, **how
        )
    else:
        Q, lam, n_res, static_residual = _tied_basis(mesh, system, Kc, Mc, method, what, **how)
    report("reduced matrices", 0.9)
    Kr, Mr = Q.T @ (Kc @ Q), Q.T @ (Mc @ Q)
    full = np.asarray(Tt @ Q)
    del Q
    shapes = solid_shapes(mesh, full, interface_statement(kinds))
    return SolidReduction(
        mesh, dofs, Kr, Mr, lam, n_res, full, shapes, slab, rigid_boundary, rigid_mass_full, static_residual
    )


def _residual(solver, K, M, Mib, psi, phi):
    """:func:`~flexshaft.reduction.craig_bampton.residual_vectors` with the solves at
    :data:`RESIDUAL_RTOL`: like the modes, the residual vectors are Ritz basis vectors, whose error
    enters the frequencies squared (the static condensation's accuracy is the constraint modes',
    solved at the solver's own tolerance)."""
    exact, solver.rtol = solver.rtol, max(solver.rtol, RESIDUAL_RTOL)
    try:
        return residual_vectors(solver, K, M, Mib, psi, phi)
    finally:
        solver.rtol = exact


def _modes_wanted(n_keep) -> bool:
    """Whether any fixed-interface mode is asked for (``modes = 0``: the static condensation)."""
    return n_keep is None or n_keep > 0


def _tied_basis(
    mesh, system, Kc, Mc, method, what, *, dofs, n_keep, cutoff_hz, residual, inner, slab, report
):
    """Both end faces rigid: the masters' DOFs are unknowns of the tied system, partitioned off as
    the boundary (and, in torsion, the held five of each). Returns (Q, eigenvalues, residual vectors,
    the constraint modes' residual): Q (m, nb + nm) maps the reduced coordinates to the unknowns."""
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
    solver = SpdSolver(Kii, near_null=near, method=method, what=what, coarse=coarse)
    Kib = Kib.toarray()
    psi = -solver.solve(Kib)
    static_residual = float(np.linalg.norm(Kii @ psi + Kib) / max(np.linalg.norm(Kib), np.finfo(float).tiny))
    n_keep = None if n_keep is None else min(n_keep, i.size)
    phi, lam = np.zeros((i.size, 0)), np.zeros(0)
    if dofs == "torsion" and _modes_wanted(n_keep):
        report("fixed-interface twist modes", 0.3)
        load = np.asarray(Mii @ psi) + Mib.toarray()  # the inertia of the masters' unit twist accelerations
        lam, phi = _twist_ritz(solver, Kii, Mii, load, inner, slab, n_keep, cutoff_hz)
    elif _modes_wanted(n_keep):
        report("fixed-interface modes", 0.3)
        trial = _trial(inner, mesh.length)
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
    phi = phi * _signs(inner, phi)
    n_res = 0
    if residual:
        report("residual vectors", 0.8)
        if phi.shape[1]:  # the residual vectors' solves start from what the modes carry
            solver.start_from_modes(phi, lam)
        res, lam_res = _residual(solver, Kii, Mii, Mib, psi, phi)
        phi, lam, n_res = np.hstack([phi, res]), np.concatenate([lam, lam_res]), lam_res.size
    nb, nm = b.size, phi.shape[1]
    Q = np.zeros((m, nb + nm))
    Q[b, np.arange(nb)] = 1.0
    Q[i, :nb] = psi
    Q[i, nb:] = phi
    return Q, lam, n_res, static_residual


def _held_averages_basis(
    mesh, system, C, Kc, Mc, method, what, *, dofs, n_keep, cutoff_hz, residual, inner, slab, report
):
    """An averaging end face (or two): the masters' DOFs are the rows C·q of the unknowns, held by
    Lagrange multipliers (:class:`_HeldMasters`). The constraint modes are the least-energy shapes
    with one master DOF at 1 and the others at 0 (no solve beyond the twelve of Y); the fixed-interface
    modes - every row of C at zero - by Rayleigh-Ritz on the Krylov space of the held solves (twist
    modes in torsion, every mode in 6 DOFs); the residual vectors as in :func:`_tied_basis`. Returns
    what :func:`_tied_basis` returns."""
    m = Kc.shape[0]
    b = np.arange(12) if dofs == "full" else np.array([3, 9])  # the rest of C's rows are held at zero
    report("constraint modes", 0.1)
    pins = determinate_support(inner)  # DOFs of free nodes: q's first unknowns are theirs
    keep = np.setdiff1d(np.arange(m), pins)
    coarse = linear_coarse_space(mesh.tets, system.T, keep, edges=TET10_EDGES)
    solver = SpdSolver(
        Kc[keep][:, keep], near_null=system.near_null[keep], method=method, what=what, coarse=coarse
    )
    held = _HeldMasters(Kc, C, system.near_null, keep, solver)
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
            lam, phi = _twist_ritz(held, Kc, Mc, load, inner, slab, n_keep, cutoff_hz)
        else:
            report("fixed-interface modes", 0.3)
            trial = np.zeros((m, 4))
            trial[:rows] = _trial(inner, mesh.length)
            lam, phi = _ritz(
                held,
                Kc,
                Mc,
                np.hstack([load, np.asarray(Mc @ trial)]),
                lambda v: np.ones(v.shape[1], dtype=bool),
                n_keep,
                cutoff_hz,
            )
    phi = phi * _signs(inner, phi[:rows])
    n_res = 0
    if residual:
        report("residual vectors", 0.8)
        res, lam_res = _residual(held, Kc, Mc, sp.csr_matrix((m, b.size)), psi, phi)
        phi, lam, n_res = np.hstack([phi, res]), np.concatenate([lam, lam_res]), lam_res.size
    return np.hstack([psi, phi]), lam, n_res, static_residual


def solid_check(reduction: SolidReduction, body: FlexibleBody) -> CBCheck:
    """:func:`~flexshaft.reduction.cb_check`'s checks for a solid body: its rigid-body mass against the
    whole mesh's, the symmetry of K and M, and (as ``static_error``) the constraint modes' residual -
    the static condensation is the solve's, so its accuracy is the solve's."""
    Rb = reduction.rigid_boundary
    nb = Rb.shape[0]
    Rr = np.zeros((body.K.shape[0], Rb.shape[1]))
    Rr[:nb] = Rb
    rigid_mass = Rr.T @ body.M @ Rr
    sym = max(
        float(np.max(np.abs(body.K - body.K.T)) / np.max(np.abs(body.K))),
        float(np.max(np.abs(body.M - body.M.T)) / np.max(np.abs(body.M))),
    )
    L = body.M[nb:, :nb] @ Rb
    return CBCheck(
        rigid_mass_reduced=rigid_mass,
        rigid_mass_full=reduction.rigid_mass_full,
        symmetry=sym,
        static_error=reduction.static_residual,
        participation=L,
        effective_mass=L**2,
        effective_mass_percent=L**2 * (100.0 / np.diag(rigid_mass)),
    )
