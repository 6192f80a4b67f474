"""A solid part's axis line and surface: what a solid flexible body shows its neighbours and views.

A solid body's ``T`` recovers an axis line (the part's 1D mesh nodes, where the chain's stations,
plots and exports read rotations): at each line node the least-squares rigid motion (varying
linearly along the axis) of the solid's nodes in a slab one element size thick across the axis
there - the section's mean translation and rotation; at the two ends the masters themselves.
Its ``solid`` carries the surface of the mesh and the displacement of the surface's nodes per
reduced coordinate (for views on the part's own surface). :func:`body_on_line` makes the body of a
reduced solid (:class:`~flexshaft.reduction.solidbasis.SolidReduction`) on a line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elements.tetmesh import TET10_EDGES, TetMesh
from ..errors import ModelError
from ..linalg.spd import rigid_displacements
from .flexiblebody import FlexibleBody, reduced_body

__all__ = ["LINES_KEPT", "SolidShapes", "body_on_line", "solid_shapes", "surface_triangles"]

#: Axis lines a reduction keeps the recovery of (``SolidReduction.lines``): each is small, the number
#: of nodes on the line times the reduced coordinates.
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


def body_on_line(reduction, *, line_x=None, damping_ratio=0.0053) -> FlexibleBody:
    """The flexible body of a reduced solid part on an axis line, with its damping.

    Parameters
    ----------
    reduction : SolidReduction
        From :func:`~flexshaft.reduction.solidbasis.solid_basis`.
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
        reduction=reduction,
    )
