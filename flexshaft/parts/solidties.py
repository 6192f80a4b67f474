"""A solid part's interfaces: its end faces tied to 6-DOF master nodes, rigidly (RBE2) or by averaging (RBE3).

A solid part meets its neighbours at its end faces. Each face is tied to a master node at the face's
centroid (on the shaft axis for a part of revolution) with six DOFs - translations u_x, u_y, u_z (m)
and rotations θ_x, θ_y, θ_z (rad) - so the part joins a chain of 1D elements and rigid bodies as
their nodes do. Tied rigidly (Nastran's RBE2): every node of the face moves with the master,
u = t + θ × (x − x_m); the face stays plane and undeformed, as a flange bolted to a stiff neighbour
or a shrink-fitted hub. Tied by averaging (Nastran's RBE3): the master moves as the face's
least-squares rigid motion, u_m = W·u_face with W = (RᵀDR)⁻¹RᵀD (R the face nodes' rigid motion about
the master, D their consistent nodal areas ∫N_i dA), and a load on the master reaches the face as
Wᵀ·F - a traction that is uniform for a force and grows with the radius for a torque, as Saint-Venant
torsion's does; the face deforms freely (a coupling hub's bore, a weld).

The tie is a transformation u = T·[u_free; u_master]: the face nodes' DOFs are replaced by their
master's six, K' = Tᵀ K T (sparse; a face of k nodes adds a 3k x 6 block). A clamped interface's face
nodes are held at zero. The near-null space of the constrained system - what smoothed-aggregation
multigrid builds its coarse levels from - is the rigid-body motions of the part expressed in those
unknowns: the free nodes' rigid motions and each master's own six (with the masters' rigid motions
entered as the face nodes' sum, the conjugate-gradient iterations doubled on a tube).

An averaging face's master is no unknown of its own: its six DOFs are rows C·q of the unknowns
(:func:`master_rows`: W at the face's nodes; a rigid face's row picks its master's unknown). Holding
or loading it is one formulation for every solve (:class:`HeldMasters`: Lagrange multipliers on a
statically determinate support), which the twist test's held end and a Craig-Bampton reduction's
constraint and fixed-interface modes all use.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from ..elements.tetmesh import TetMesh
from ..errors import ModelError
from ..linalg.spd import rigid_body_modes, rigid_displacements, rigid_motions_at

__all__ = [
    "ENDS",
    "INTERFACES",
    "AveragingInterface",
    "ConstrainedSystem",
    "HeldMasters",
    "RigidInterface",
    "averaging_interface",
    "constrain",
    "determinate_support",
    "interface_kinds",
    "interface_statement",
    "master_rows",
    "rigid_interface",
]


#: A solid part's end faces, in the order of its masters (the body's boundary DOFs: the start's first).
ENDS = ("start", "end")
#: How an end face may be tied to its master node (the model file's ``interface``).
INTERFACES = {
    "rigid": "rigid (RBE2): each end face moves as a rigid body with its master node at its centroid",
    "average": "averaging (RBE3): each master node follows its end face's least-squares rigid motion; "
    "the faces deform freely, a load reaches them as the matching traction",
}


def interface_kinds(interface) -> tuple[str, str]:
    """(start's, end's) kind of tie from ``"rigid"``, ``"average"``, a pair of them or a mapping
    ``{"start": ..., "end": ...}`` (a face left out is rigid); checked."""
    if isinstance(interface, str):
        pair = (interface, interface)
    elif isinstance(interface, dict):
        unknown = set(interface) - set(ENDS)
        if unknown:
            raise ModelError(
                "names no end face", field="interface", value=sorted(unknown)[0], valid="start, end"
            )
        pair = tuple(interface.get(end, "rigid") for end in ENDS)
    elif isinstance(interface, (tuple, list)) and len(interface) == 2:
        pair = tuple(interface)
    else:
        raise ModelError(
            "must be a kind or one per end face",
            field="interface",
            value=interface,
            valid='"rigid", "average" or {start = ..., end = ...}',
        )
    for end, kind in zip(ENDS, pair, strict=True):
        if kind not in INTERFACES:
            raise ModelError(
                "unknown tie", field=f"interface.{end}", value=kind, valid="rigid (RBE2) or average (RBE3)"
            )
    return pair


def interface_statement(kinds) -> str:
    """How a part's end faces are tied, for the record: "end faces rigid (RBE2)", "start face rigid
    (RBE2), end face averaged (RBE3)"."""
    said = {"rigid": "rigid (RBE2)", "average": "averaged (RBE3)"}
    if kinds[0] == kinds[1]:
        return f"end faces {said[kinds[0]]}"
    return f"start face {said[kinds[0]]}, end face {said[kinds[1]]}"


@dataclass(frozen=True)
class RigidInterface:
    """A face of a solid part tied rigidly to a master node.

    Attributes
    ----------
    name : str
        The face set's name in the mesh (``"start"``, ``"end"``).
    master : ndarray (3,)
        The master node: the face's area centroid, m.
    nodes : ndarray of int
        The face's nodes (corner and mid-side), each once.
    area : float
        The face's area (its 6-node triangles' corners), m².
    """

    name: str
    master: np.ndarray
    nodes: np.ndarray
    area: float


def rigid_interface(mesh: TetMesh, face: str) -> RigidInterface:
    """The face set ``face`` of ``mesh`` tied rigidly to a master node at its area centroid."""
    if face not in mesh.faces:
        raise ModelError(
            "is not a face set of the mesh",
            field="interface",
            value=face,
            valid="one of " + (", ".join(mesh.faces) or "(the mesh has none)"),
        )
    tri = mesh.faces[face]
    c = mesh.nodes[tri[:, :3]]
    areas = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    area = float(areas.sum())
    if not area > 0:
        raise ModelError("has no area", field="interface", value=face, valid="a face of triangles with area")
    master = (areas[:, None] * c.mean(axis=1)).sum(axis=0) / area
    return RigidInterface(face, master, np.unique(tri), area)


@dataclass(frozen=True)
class AveragingInterface:
    """A face of a solid part whose master node follows its mean motion (RBE3).

    Attributes
    ----------
    name : str
    master : ndarray (3,)
        The face's area centroid, m.
    nodes : ndarray of int
        The face's nodes, each once.
    W : ndarray (6, 3k)
        u_master = W · u[nodes] (node-major u_x, u_y, u_z).
    area : float
        The face's area, m².
    """

    name: str
    master: np.ndarray
    nodes: np.ndarray
    W: np.ndarray
    area: float


def _face_weights(mesh: TetMesh, tri: np.ndarray) -> np.ndarray:
    """∫N_i dA of every node of 6-node triangles (curved edges included), per triangle (m, 6).

    Quadratic map of the reference triangle, integrated by a collapsed (Duffy) Gauss-Legendre rule of
    5 x 5 points, exact for polynomials of degree 9 per direction: N_i·|J| of a planar 6-node triangle
    is of degree 4 (|J| of degree 2); a face that is not planar is integrated to the rule's accuracy.
    """
    g, w = np.polynomial.legendre.leggauss(5)
    g, w = 0.5 * (g + 1), 0.5 * w
    u, v = np.meshgrid(g, g, indexing="ij")
    wu, wv = np.meshgrid(w, w, indexing="ij")
    xi, eta = u.ravel(), (v * (1 - u)).ravel()
    weight = (wu * wv * (1 - u)).ravel()
    l1, l2, l3 = 1 - xi - eta, xi, eta
    N = np.stack(
        [l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), l3 * (2 * l3 - 1), 4 * l1 * l2, 4 * l2 * l3, 4 * l3 * l1]
    )
    dxi = np.stack([-(4 * l1 - 1), 4 * l2 - 1, 0 * xi, 4 * (l1 - l2), 4 * l3, -4 * l3])
    deta = np.stack([-(4 * l1 - 1), 0 * xi, 4 * l3 - 1, -4 * l2, 4 * l2, 4 * (l1 - l3)])
    X = mesh.nodes[tri]  # (m, 6, 3)
    a = np.einsum("kq,mkc->mqc", dxi, X)
    b = np.einsum("kq,mkc->mqc", deta, X)
    detj = np.linalg.norm(np.cross(a, b), axis=2)  # (m, q)
    return np.einsum("kq,mq,q->mk", N, detj, weight)


def averaging_interface(mesh: TetMesh, face: str) -> AveragingInterface:
    """The face set ``face`` of ``mesh`` tied by averaging (RBE3) to a master node at its centroid."""
    rigid = rigid_interface(mesh, face)
    tri = mesh.faces[face]
    per = _face_weights(mesh, tri)
    weights = np.zeros(mesh.n_nodes)
    np.add.at(weights, tri, per)
    w = weights[rigid.nodes]
    R = rigid_displacements(mesh.nodes[rigid.nodes], rigid.master).reshape(-1, 6)
    D = np.repeat(w, 3)
    W = np.linalg.solve(R.T @ (D[:, None] * R), R.T * D)
    return AveragingInterface(face, rigid.master, rigid.nodes, W, float(w.sum()))


@dataclass(frozen=True)
class ConstrainedSystem:
    """A solid part's stiffness with its interfaces tied (module docstring).

    Attributes
    ----------
    K : scipy.sparse.csr_matrix (m, m)
        Tᵀ K T, the clamped interfaces' face nodes removed.
    T : scipy.sparse.csr_matrix (3n, m)
        The full displacement vector from the unknowns: u = T·q.
    masters : dict of str to ndarray of int (6,)
        Each loaded (not clamped) interface's six master DOFs in q (u_x, u_y, u_z, θ_x, θ_y, θ_z).
    near_null : ndarray (m, 6)
        The rigid-body motions in q (for multigrid).
    interfaces : tuple of RigidInterface
    clamped : tuple of str
    free_nodes : ndarray of int
        The mesh nodes on no interface: unknown 3k + c of q is node free_nodes[k]'s u_c.
    """

    K: sp.csr_matrix
    T: sp.csr_matrix
    masters: dict
    near_null: np.ndarray
    interfaces: tuple
    clamped: tuple
    free_nodes: np.ndarray


def constrain(K, mesh: TetMesh, interfaces, clamped=()) -> ConstrainedSystem:
    """Tie ``interfaces`` (RigidInterface) of a solid part with stiffness ``K`` (3n x 3n, node-major);
    the names in ``clamped`` are held at zero."""
    interfaces, clamped = tuple(interfaces), tuple(clamped)
    names = [i.name for i in interfaces]
    for c in clamped:
        if c not in names:
            raise ModelError(
                "is not an interface", field="clamp", value=c, valid="one of " + ", ".join(names)
            )
    n = mesh.n_nodes
    owner = np.full(n, -1)
    for j, face in enumerate(interfaces):
        if np.any(owner[face.nodes] >= 0):
            raise ModelError(
                f"shares nodes with interface {interfaces[int(owner[face.nodes].max())].name!r}",
                field="interface",
                value=face.name,
                valid="faces that do not touch (a part with length between its ends)",
            )
        owner[face.nodes] = j
    free_nodes = np.flatnonzero(owner < 0)
    nf = 3 * free_nodes.size
    loaded = [j for j, face in enumerate(interfaces) if face.name not in clamped]
    masters = {interfaces[j].name: nf + 6 * i + np.arange(6) for i, j in enumerate(loaded)}
    m = nf + 6 * len(loaded)
    rows = [(3 * free_nodes[:, None] + np.arange(3)).ravel()]
    cols = [np.arange(nf)]
    vals = [np.ones(nf)]
    B = rigid_body_modes(mesh.nodes)
    null = np.zeros((m, 6))
    null[:nf] = B.reshape(n, 3, 6)[free_nodes].reshape(nf, 6)
    for j in loaded:
        face = interfaces[j]
        # u = t + θ × (x − x_m) at every face node: its nonzero entries are T's rows there
        u = rigid_displacements(mesh.nodes[face.nodes], face.master)
        node, comp, dof = np.nonzero(u)
        rows.append(3 * face.nodes[node] + comp)
        cols.append(masters[face.name][dof])
        vals.append(u[node, comp, dof])
        null[masters[face.name]] = rigid_motions_at(mesh.nodes, face.master)  # the master's own
    T = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, m))
    Kc = (T.T @ sp.csr_matrix(K) @ T).tocsr()
    return ConstrainedSystem(Kc, T, masters, null, interfaces, clamped, free_nodes)


def determinate_support(nodes: np.ndarray) -> np.ndarray:
    """Six DOFs (node-major: 3k + c) that hold a body of these nodes statically determinately (3-2-1):
    all three of the node at the lowest x, the two across the line to the node farthest from it, and
    at the node farthest off that line the one along the plane's normal. An equilibrated load meets
    no reaction at them, so a free body's K with these DOFs removed solves it exactly (up to a rigid
    motion)."""
    a = int(np.argmin(nodes[:, 0]))
    b = int(np.argmax(np.linalg.norm(nodes - nodes[a], axis=1)))
    d = nodes[b] - nodes[a]
    off = np.linalg.norm(np.cross(nodes - nodes[a], d), axis=1)
    c = int(np.argmax(off))
    normal = np.cross(d, nodes[c] - nodes[a])
    across = np.argsort(np.abs(d), kind="stable")[:2]
    return np.array([3 * a, 3 * a + 1, 3 * a + 2, *(3 * b + across), 3 * c + int(np.argmax(np.abs(normal)))])


class HeldMasters:
    """Solves of a solid part whose masters' DOFs are rows C·q of its unknowns (an averaging face's
    W over its nodes, a rigid face's master unknown itself): K x + Cᵀμ = f with C x = g.

    The part is free (K's null space the rigid motions B); six DOFs of a statically determinate
    support (:func:`determinate_support`) are removed and the rest solved by
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


def master_rows(mesh: TetMesh, system, faces, kinds) -> sp.csr_matrix:
    """C (6·len(faces), m): each face's master DOFs (u_x, u_y, u_z, θ_x, θ_y, θ_z), in the order of
    ``faces``, as rows over the tied unknowns - an averaging face's W at its nodes' u_x, u_y, u_z, a
    rigid face's own master unknowns."""
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
    shape = (6 * len(faces), system.K.shape[0])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=shape)
