"""Assemble a drivetrain chain into sparse stiffness, inertia and damping matrices.

Node numbering follows the chain from the driving end, so every matrix of a
serial chain is tridiagonal (bandwidth 1). One DOF per node: the torsional
rotation θx, rad.

A shaft with ``reduce`` enters as a Craig–Bampton flexible body
(:func:`flexshaft.reduction.craig_bampton` on its own torsion mesh): only its
interface nodes (ends and named nodes) are chain nodes, and its modal
coordinates are extra DOFs numbered after every node. Node ``i`` is still DOF
``i``; the matrices are then tridiagonal plus one dense block per body (an
"arrow" whose modal rows come last, so a sparse factorisation has no fill).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements import torsion_consistent_inertia, torsion_lumped_inertia, torsion_stiffness
from ..errors import ModelError
from ..linalg.damping import modal_damping_matrix
from ..parts.model import PartModel
from ..reduction.craig_bampton import FlexibleBody, craig_bampton
from .components import Coupling, Drivetrain, Rigid, Shaft

__all__ = ["Station", "ChainBody", "AssembledModel", "assemble", "node_positions"]


@dataclass(frozen=True)
class Station:
    """A named node at a component boundary.

    Attributes
    ----------
    name : str
        ``"motor"`` where a rigid inertia sits, ``"part 1/part 2"`` between two
        flexible components, ``"part 4 end"`` / ``"part 1 start"`` at a free end.
    node : int
        Index of the node (and of its θx DOF).
    """

    name: str
    node: int


@dataclass(frozen=True)
class ChainBody:
    """A shaft reduced to a flexible body, and where its coordinates sit in the chain.

    Attributes
    ----------
    component : int
        Index of the shaft in the chain.
    body : FlexibleBody
        The reduction of the shaft's own torsion model (its K, M, C, T).
    dofs : ndarray of int
        Global DOF of each reduced coordinate: the boundary nodes' chain
        nodes, then the modal coordinates (numbered after every node).
    x : ndarray
        Positions of the shaft's mesh nodes from its driving end, m (the rows
        of ``body.T``).
    element_stiffness : ndarray
        Stiffness of the mesh elements between those nodes, N·m/rad.
    """

    component: int
    body: FlexibleBody
    dofs: np.ndarray
    x: np.ndarray
    element_stiffness: np.ndarray

    @property
    def interface_nodes(self) -> np.ndarray:
        """Chain nodes of the body's interface nodes, in order along the shaft."""
        return self.dofs[: self.body.boundary_nodes.size]

    def recover(self, V: np.ndarray) -> np.ndarray:
        """Rotations (rad) of every mesh node of the shaft from global vectors ``V`` (n_dof, m)."""
        return self.body.T @ V[self.dofs]


@dataclass(frozen=True)
class AssembledModel:
    """The drivetrain as matrices, with the bookkeeping to report per component.

    Attributes
    ----------
    drivetrain : Drivetrain
        What was assembled.
    inertia_model : str
        ``"consistent"`` or ``"lumped"``.
    K, M : scipy.sparse.csr_matrix
        Stiffness (N·m/rad) and inertia (kg·m²), symmetric, n × n.
    C : scipy.sparse.csr_matrix or None
        Damping (N·m·s/rad), or None for an undamped model.
    stations : tuple of Station
        Component boundaries, in chain order.
    start_node, end_node : ndarray of int
        Per component (chain order), its first and last node; equal for a rigid.
    element_nodes : ndarray of int, shape (n_el,)
        Left node of each element (the right one is ``+1``).
    element_stiffness, element_inertia : ndarray, shape (n_el,)
        N·m/rad and kg·m².
    element_component : ndarray of int, shape (n_el,)
        Index of the component each element belongs to.
    element_lumped : ndarray of bool, shape (n_el,)
        Whether the element's inertia is lumped at its ends (couplings always).
    point_nodes, point_inertia, point_component : ndarray
        Rigid inertias: node, kg·m², component index.
    bodies : tuple of ChainBody
        Shafts entered as Craig–Bampton flexible bodies (their elements are
        not among ``element_*``).
    n_nodes : int
        Number of chain nodes; DOFs from ``n_nodes`` on are modal coordinates
        of the bodies.
    """

    drivetrain: Drivetrain
    inertia_model: str
    K: sp.csr_matrix
    M: sp.csr_matrix
    C: sp.csr_matrix | None
    stations: tuple
    start_node: np.ndarray
    end_node: np.ndarray
    element_nodes: np.ndarray
    element_stiffness: np.ndarray
    element_inertia: np.ndarray
    element_component: np.ndarray
    element_lumped: np.ndarray
    point_nodes: np.ndarray
    point_inertia: np.ndarray
    point_component: np.ndarray
    bodies: tuple
    n_nodes: int

    @property
    def n_dof(self) -> int:
        """Number of DOFs: one θx per node, plus the bodies' modal coordinates."""
        return self.K.shape[0]

    @property
    def bandwidth(self) -> int | None:
        """Half-bandwidth of K, M and C in the chain numbering (None with flexible bodies)."""
        if self.bodies:
            return None
        return 1 if self.n_dof > 1 else 0

    @property
    def rigid_basis(self) -> np.ndarray:
        """The chain's rigid-body mode: every node turns by 1 rad, modal coordinates stay 0."""
        r = np.zeros((self.n_dof, 1))
        r[: self.n_nodes] = 1.0
        return r

    @property
    def station_nodes(self) -> np.ndarray:
        """Node index of every station, in chain order."""
        return np.array([s.node for s in self.stations], dtype=int)

    @property
    def component_names(self) -> tuple[str, ...]:
        """Component names in chain order."""
        return tuple(c.name for c in self.drivetrain.components)


def _station_names(drivetrain: Drivetrain, start: np.ndarray, end: np.ndarray, named: dict) -> tuple:
    """Name the nodes where components meet (see :class:`Station`).

    ``named`` maps a component index to the chain nodes of its named nodes.
    """
    rigid_at: dict[int, list[str]] = {}
    ends_at: dict[int, list[str]] = {}
    starts_at: dict[int, list[str]] = {}
    for comp, s, e in zip(drivetrain.components, start, end):
        if isinstance(comp, Rigid):
            rigid_at.setdefault(int(s), []).append(comp.name)
        else:
            starts_at.setdefault(int(s), []).append(comp.name)
            ends_at.setdefault(int(e), []).append(comp.name)
    stations = []
    for node in sorted(set(rigid_at) | set(ends_at) | set(starts_at)):
        if node in rigid_at:
            name = " + ".join(rigid_at[node])
        elif node in ends_at and node in starts_at:
            name = f"{ends_at[node][0]}/{starts_at[node][0]}"
        elif node in ends_at:
            name = f"{ends_at[node][0]} end"
        else:
            name = f"{starts_at[node][0]} start"
        stations.append(Station(name, node))
    # Named nodes inside shafts made from sections (a journal bearing, a sensor).
    for ci, nodes in named.items():
        comp = drivetrain.components[ci]
        for (mark, _), node in zip(comp.named_nodes, nodes):
            stations.append(Station(f"{comp.name}: {mark}", int(node)))
    return tuple(sorted(stations, key=lambda st: st.node))


def _shaft_x(comp: Shaft, n_el: int) -> np.ndarray:
    """Mesh node positions from the shaft's driving end, m (equal pieces of a given-numbers shaft)."""
    mesh = comp.torsion_mesh()
    if mesh is not None:
        return mesh.x - mesh.x[0]
    return np.linspace(0.0, 1.0, n_el + 1)  # no length: a unit parameter along the shaft


def _flexible_body(comp: Shaft, model: str, k, j, x, named) -> FlexibleBody:
    """Reduce a shaft's own torsion model (elements k, j on nodes x; named nodes kept at the interface)."""
    blocks = torsion_lumped_inertia(j) if model == "lumped" else torsion_consistent_inertia(j)
    part = PartModel(
        x=x, dofs="torsion", K=_pairs(torsion_stiffness(k)), M=_pairs(blocks), mass=model, name=comp.name
    )
    red = comp.reduce
    try:
        body = craig_bampton(
            part, modes=red.modes, cutoff_hz=red.cutoff_hz, nodes=named, damping_ratio=red.damping
        )
    except ModelError as err:
        raise err.located(component=repr(comp.name)) from None
    return body


def _pairs(blocks: np.ndarray, point=None) -> sp.csr_matrix:
    """Sum symmetric 2 × 2 element blocks of a chain into a tridiagonal CSR matrix.

    In a chain, element e joins nodes e and e + 1 (n elements, n + 1 nodes), so
    the CSR arrays can be written down directly (O(n), no COO sort).
    ``point = (nodes, values)`` adds values on the diagonal (rigid inertias).
    """
    diag = np.zeros(blocks.shape[0] + 1)
    diag[:-1] += blocks[:, 0, 0]
    diag[1:] += blocks[:, 1, 1]
    off = blocks[:, 0, 1].copy()
    if point is not None:
        np.add.at(diag, point[0], point[1])
    return _tridiagonal_csr(diag, off)


def _tridiagonal_csr(diag: np.ndarray, off: np.ndarray) -> sp.csr_matrix:
    """The symmetric tridiagonal matrix with ``diag`` and ``off`` as CSR."""
    n = diag.size
    if n == 1:
        return sp.csr_matrix(diag.reshape(1, 1))
    # Row i holds columns i-1, i, i+1 (the first and last rows one fewer).
    counts = np.full(n, 3)
    counts[0] = counts[-1] = 2
    indptr = np.concatenate([[0], np.cumsum(counts)])
    cols = np.empty(indptr[-1], dtype=np.int32 if n < 2**31 - 1 else np.int64)
    data = np.empty(indptr[-1])
    rows = np.arange(n)
    lo = indptr[:-1]
    # below-diagonal entries (rows 1..n-1), diagonal, above-diagonal (rows 0..n-2)
    cols[lo[1:]] = rows[1:] - 1
    data[lo[1:]] = off
    dpos = lo + (rows > 0)
    cols[dpos] = rows
    data[dpos] = diag
    cols[dpos[:-1] + 1] = rows[:-1] + 1
    data[dpos[:-1] + 1] = off
    return sp.csr_matrix((data, cols, indptr), shape=(n, n))


def _sparse(n: int, el_nodes, blocks, point=None, dense_blocks=()) -> sp.csr_matrix:
    """Sum 2 × 2 element blocks on (node, node + 1), point values and dense (dofs, block) pairs.

    Without dense blocks the elements are the whole chain and the fast
    tridiagonal path is taken.
    """
    if not dense_blocks and el_nodes.size == n - 1:
        return _pairs(blocks, point)
    rows = [np.stack([el_nodes, el_nodes, el_nodes + 1, el_nodes + 1], axis=1).ravel()]
    cols = [np.stack([el_nodes, el_nodes + 1, el_nodes, el_nodes + 1], axis=1).ravel()]
    data = [blocks.reshape(-1, 4).ravel()]
    if point is not None:
        rows.append(point[0])
        cols.append(point[0])
        data.append(point[1])
    for dofs, block in dense_blocks:
        r, c = np.meshgrid(dofs, dofs, indexing="ij")
        rows.append(r.ravel())
        cols.append(c.ravel())
        data.append(np.asarray(block).ravel())
    return sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def assemble(
    drivetrain: Drivetrain, inertia_model: str | None = None, *, reduce: bool = True
) -> AssembledModel:
    """Assemble the chain's K, M and C.

    Parameters
    ----------
    drivetrain : Drivetrain
        The chain.
    inertia_model : {"consistent", "lumped"}, optional
        Overrides ``drivetrain.inertia_model``.
    reduce : bool
        Enter shafts with ``reduce`` as Craig–Bampton flexible bodies (the
        default); False keeps every shaft's full mesh (a static test, which
        Craig–Bampton reproduces exactly anyway, or a reference).

    Returns
    -------
    AssembledModel

    Raises
    ------
    ModelError
        If a node carries no inertia at all (a massless free end), which makes
        the inertia matrix singular.
    """
    model = drivetrain.inertia_model if inertia_model is None else inertia_model
    if model not in ("consistent", "lumped"):
        raise ModelError(
            "unknown inertia model", field="inertia_model", value=model, valid="'consistent' or 'lumped'"
        )
    comps = drivetrain.components
    start = np.zeros(len(comps), dtype=int)
    end = np.zeros(len(comps), dtype=int)
    el_nodes, el_k, el_j, el_c, el_comp, el_lumped = [], [], [], [], [], []
    pt_nodes, pt_j, pt_comp = [], [], []
    named: dict[int, list[int]] = {}
    pending = []  # (component, body, x, element k, element c, boundary chain nodes)
    node = 0
    for ci, comp in enumerate(comps):
        start[ci] = node
        if isinstance(comp, Rigid):
            pt_nodes.append(node)
            pt_j.append(comp.inertia)
            pt_comp.append(ci)
        elif isinstance(comp, Shaft) and reduce and comp.reduce is not None:
            k, j, c = comp.element_properties()
            x = _shaft_x(comp, k.size)
            marks = comp.named_mesh_nodes(x)
            body = _flexible_body(comp, model, k, j, x, marks)
            chain_nodes = node + np.arange(body.boundary_nodes.size)
            where = {int(b): int(c) for b, c in zip(body.boundary_nodes, chain_nodes)}
            if marks:
                named[ci] = [where[m] for m in marks]
            pending.append((ci, body, x, k, c, chain_nodes))
            node = int(chain_nodes[-1])
        else:
            k, j, c = comp.element_properties()
            n = k.size
            el_nodes.append(np.arange(node, node + n))
            el_k.append(k)
            el_j.append(j)
            el_c.append(c)
            el_comp.append(np.full(n, ci))
            lumped = isinstance(comp, Coupling) or model == "lumped"
            el_lumped.append(np.full(n, lumped))
            if isinstance(comp, Shaft) and comp.named_nodes:
                named[ci] = [node + m for m in comp.named_mesh_nodes(_shaft_x(comp, n))]
            node += n
        end[ci] = node
    n_nodes = node + 1
    # Modal coordinates after every node, body by body.
    bodies = []
    n_dof = n_nodes
    extra_c = []
    for ci, body, x, k, c, chain_nodes in pending:
        dofs = np.concatenate([chain_nodes, n_dof + np.arange(body.n_modes)])
        n_dof += body.n_modes
        bodies.append(ChainBody(component=ci, body=body, dofs=dofs, x=x, element_stiffness=k))
        if np.any(c > 0):
            # A discrete damper along the shaft, projected on the body's coordinates.
            Cp = _pairs(torsion_stiffness(c))
            extra_c.append((dofs, body.T.T @ (Cp @ body.T)))

    def cat(parts, dtype):
        return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)

    el_nodes_a = cat(el_nodes, int)
    el_k_a, el_j_a, el_c_a = cat(el_k, float), cat(el_j, float), cat(el_c, float)
    el_comp_a, el_lumped_a = cat(el_comp, int), cat(el_lumped, bool)
    pt_nodes_a = np.asarray(pt_nodes, dtype=int)
    pt_j_a = np.asarray(pt_j, dtype=float)

    K = _sparse(
        n_dof, el_nodes_a, torsion_stiffness(el_k_a), dense_blocks=[(b.dofs, b.body.K) for b in bodies]
    )
    m_blocks = np.where(
        el_lumped_a[:, None, None], torsion_lumped_inertia(el_j_a), torsion_consistent_inertia(el_j_a)
    )
    M = _sparse(
        n_dof,
        el_nodes_a,
        m_blocks,
        point=(pt_nodes_a, pt_j_a),
        dense_blocks=[(b.dofs, b.body.M) for b in bodies],
    )

    stations = _station_names(drivetrain, start, end, named)
    _check_inertia(M, stations, start, end, comps)

    C = _damping(drivetrain, model, K, M, el_nodes_a, el_k_a, el_c_a, el_comp_a, start, end, bodies, extra_c)
    return AssembledModel(
        drivetrain=drivetrain,
        inertia_model=model,
        K=K,
        M=M,
        C=C,
        stations=stations,
        start_node=start,
        end_node=end,
        element_nodes=el_nodes_a,
        element_stiffness=el_k_a,
        element_inertia=el_j_a,
        element_component=el_comp_a,
        element_lumped=el_lumped_a,
        point_nodes=pt_nodes_a,
        point_inertia=pt_j_a,
        point_component=np.asarray(pt_comp, int),
        bodies=tuple(bodies),
        n_nodes=n_nodes,
    )


def _check_inertia(M, stations, start, end, comps) -> None:
    """Every node needs some inertia, or the eigenproblem has infinite roots."""
    bad = np.flatnonzero(M.diagonal() <= 0.0)
    if bad.size == 0:
        return
    node = int(bad[0])
    names = {s.node: s.name for s in stations}
    # The flexible component owning the node (the first whose node range holds it).
    owner = next(c.name for c, s, e in zip(comps, start, end) if not isinstance(c, Rigid) and s <= node <= e)
    where = f"station {names[node]!r}" if node in names else "a node inside it"
    raise ModelError(
        f"{where} carries no inertia, so the inertia matrix is singular",
        component=f"{owner!r}",
        field="inertia",
        value=0.0,
        unit="kg·m²",
        valid="give the shaft or coupling there an inertia > 0, or put a rigid inertia on it",
    )


def _damping(drivetrain, model, K, M, el_nodes, el_k, el_c, el_comp, start, end, bodies, extra_c):
    """C from discrete dampers, per-shaft modal damping, flexible bodies and Rayleigh damping."""
    n_dof = K.shape[0]
    parts = []
    dense = [(b.dofs, b.body.C) for b in bodies if np.any(b.body.C)] + list(extra_c)
    if np.any(el_c > 0) or dense:
        parts.append(_sparse(n_dof, el_nodes, torsion_stiffness(el_c), dense_blocks=dense))
    reduced = {b.component for b in bodies}
    for ci, comp in enumerate(drivetrain.components):
        if isinstance(comp, Shaft) and comp.damping_ratio > 0 and ci not in reduced:
            # The shaft's own free-free model: its elements only. Rigid inertias
            # and neighbours on its end nodes belong to other components.
            s, e = int(start[ci]), int(end[ci])
            _, j, _ = comp.element_properties()
            Kp = _pairs(torsion_stiffness(el_k[el_comp == ci])).toarray()
            blocks = torsion_lumped_inertia(j) if model == "lumped" else torsion_consistent_inertia(j)
            Mp = _pairs(blocks).toarray()
            Cp = modal_damping_matrix(Kp, Mp, comp.damping_ratio)
            rows, cols = np.meshgrid(np.arange(s, e + 1), np.arange(s, e + 1), indexing="ij")
            parts.append(
                sp.coo_matrix((Cp.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, n_dof)).tocsr()
            )
    ray = drivetrain.rayleigh
    if ray is not None and (ray.alpha or ray.beta):
        parts.append(ray.alpha * M + ray.beta * K)
    if not parts:
        return None
    return sp.csr_matrix(sum(parts[1:], parts[0]))


def node_positions(model: AssembledModel) -> np.ndarray:
    """Axial position of every node, m: shafts made from sections contribute their length, others none."""
    x = np.zeros(model.n_dof)
    for ci, comp in enumerate(model.drivetrain.components):
        s, e = int(model.start_node[ci]), int(model.end_node[ci])
        if e == s:
            continue
        mesh = comp.torsion_mesh() if isinstance(comp, Shaft) else None
        steps = np.diff(mesh.x) if mesh is not None else np.zeros(e - s)
        x[s + 1 : e + 1] = x[s] + np.cumsum(steps)
    return x
