"""The drivetrain with six DOFs per node: Timoshenko shafts, couplings, rigid inertias, bearings.

Every shaft must be made from sections (a ``cad`` part or ``segments``): its
6-DOF part model (:func:`flexshaft.partmodel.part_model`, on the same mesh as
the torsion chain, so node numbers and stations are shared) is placed on the
chain's nodes. A coupling is a torsional spring (and inertia, half on each
side, on θx) whose other five DOFs are a rigid link: the two nodes share
ux, uy, uz, θy, θz (eliminated exactly, not by a penalty). A rigid inertia acts
on θx only (its mass and tilting inertia are not in the model file).
Bearings are isotropic lateral springs (uy, uz) at named stations.

A shaft with ``reduce`` enters as a Craig–Bampton flexible body
(:func:`flexshaft.reduction.craig_bampton` of that same 6-DOF part model):
its end and named nodes (the boundary, where neighbours, stations and
bearings attach) keep their six physical DOFs, its interior nodes carry none,
and its modal coordinates are extra coordinates numbered after every
physical one (as in the torsion chain, :mod:`flexshaft.assembly`). ``T``
still recovers all six DOFs of every node, interior ones through the body's
own recovery matrix.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..linalg.eigen import lowest_modes
from ..parts.model import PartModel, part_model, smooth_trial_shapes
from ..reduction.craig_bampton import FlexibleBody, craig_bampton
from .assembly import assemble, node_positions
from .components import Coupling, Drivetrain, Rigid, Shaft

__all__ = ["FullModel", "FullBody", "FullModes", "assemble_full", "full_modes", "FAMILIES"]

#: DOF families of a node, by local index.
FAMILIES = {"axial": (0,), "lateral": (1, 2, 4, 5), "torsion": (3,)}


@dataclass(frozen=True)
class FullBody:
    """A shaft entered in the 6-DOF chain as a Craig–Bampton flexible body.

    Attributes
    ----------
    component : int
        Index of the shaft in the chain.
    body : FlexibleBody
        The reduction of the shaft's 6-DOF part model (its K, M, C, T).
    first_node : int
        Chain node of the part's node 0: part node ``j`` is chain node
        ``first_node + j``.
    columns : ndarray of int
        Reduced coordinate of each of the body's coordinates: its boundary
        DOFs (node-major, ux … θz), then its modal coordinates.
    """

    component: int
    body: FlexibleBody
    first_node: int
    columns: np.ndarray

    @property
    def interface_nodes(self) -> np.ndarray:
        """Chain nodes of the body's interface nodes, in order along the shaft."""
        return self.first_node + self.body.boundary_nodes

    def recover(self, V: np.ndarray) -> np.ndarray:
        """All six DOFs of every node of the shaft (m, rad; node-major) from reduced vectors ``V``."""
        return self.body.T @ V[self.columns]


@dataclass(frozen=True)
class FullModel:
    """K and M of the 6-DOF chain in reduced coordinates (coupling links eliminated), SI.

    Attributes
    ----------
    drivetrain : Drivetrain
        What was assembled.
    K, M : scipy.sparse.csr_matrix
        Stiffness (N/m, N, N·m/rad) and mass (kg, kg·m, kg·m²) in reduced
        coordinates: the physical DOFs that remain (one per coupling link),
        then the flexible bodies' modal coordinates.
    T : scipy.sparse.csr_matrix, shape (6·n_nodes, n)
        Recovery of the 6 DOFs of every node of the unreduced chain
        (``u_full = T @ u``, node-major), interior nodes of flexible bodies
        included.
    x : ndarray
        Node positions along the chain, m.
    stations : tuple of (str, int)
        (name, node) as in the torsion chain.
    bearings : mapping of int to float
        Node → lateral stiffness, N/m.
    M_nodes : scipy.sparse.csr_matrix, shape (6·n_nodes, 6·n_nodes)
        The unreduced chain's mass on every node's DOFs; ``M = Tᵀ M_nodes T``
        (a flexible body's mass is its part's mass projected on its recovery
        matrix), so the kinetic energy of a recovered shape is exact.
    coordinate_dofs : ndarray of int, shape (n,)
        For each reduced coordinate, the full DOF (6·node + k) it stands for;
        −1 for a modal coordinate.
    bodies : tuple of FullBody
        Shafts entered as flexible bodies.
    """

    drivetrain: Drivetrain
    K: sp.csr_matrix
    M: sp.csr_matrix
    T: sp.csr_matrix
    x: np.ndarray
    stations: tuple
    bearings: Mapping[int, float]
    M_nodes: sp.csr_matrix
    coordinate_dofs: np.ndarray
    bodies: tuple = ()

    @property
    def n_nodes(self) -> int:
        """Nodes of the chain."""
        return self.x.size

    @property
    def representatives(self) -> np.ndarray:
        """For each reduced coordinate, the full DOF (6·node + k) it stands for; −1 for a modal one."""
        return self.coordinate_dofs

    @property
    def modal(self) -> np.ndarray:
        """Which reduced coordinates are modal coordinates of a flexible body."""
        return self.coordinate_dofs < 0


def _station_node(stations, name: str) -> int:
    for st in stations:
        if st.name == name:
            return st.node
    raise ModelError(
        "no such station",
        field="bearings.station",
        value=name,
        valid=", ".join(repr(s.name) for s in stations),
    )


class _Triplets:
    """COO entries of a sparse matrix, summed when it is built (one sort for all blocks)."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.data: list[np.ndarray] = []

    def add_sparse(self, A: sp.spmatrix, off: int) -> None:
        c = A.tocoo()
        self.rows.append(c.row + off)
        self.cols.append(c.col + off)
        self.data.append(c.data)

    def add_dense(self, dofs: np.ndarray, block: np.ndarray) -> None:
        r, c = np.meshgrid(dofs, dofs, indexing="ij")
        self.rows.append(r.ravel())
        self.cols.append(c.ravel())
        self.data.append(np.asarray(block, dtype=float).ravel())

    def add(self, rows, cols, data) -> None:
        self.rows.append(np.asarray(rows, dtype=int))
        self.cols.append(np.asarray(cols, dtype=int))
        self.data.append(np.asarray(data, dtype=float))

    def build(self, n: int) -> sp.csr_matrix:
        if not self.rows:
            return sp.csr_matrix((n, n))
        return sp.csr_matrix(
            (np.concatenate(self.data), (np.concatenate(self.rows), np.concatenate(self.cols))), shape=(n, n)
        )


def _shaft_part(comp: Shaft, inertia_model: str, n_nodes: int) -> PartModel:
    """The shaft's 6-DOF part model on the torsion chain's mesh (``n_nodes`` nodes)."""
    if comp.sections is None:
        raise ModelError(
            "has no cross-sections, so no bending stiffness or mass",
            component=repr(comp.name),
            field="type",
            value="shaft",
            has_value=True,
            valid='dofs = "full" needs every shaft as a cad part or given by segments',
        )
    # nodes_at as in Shaft.torsion_mesh: a named node off the element grid adds a node there, and
    # the part must have the chain's nodes, or every node after it is shifted.
    pm = part_model(
        comp.sections,
        comp.material,
        dofs="full",
        max_element_length=comp.mesh_cap,
        mass="lumped" if inertia_model == "lumped" else "consistent",
        nodes_at=comp.named_positions,
    )
    if pm.n_nodes != n_nodes:
        raise ModelError(
            f"its 6-DOF mesh has {pm.n_nodes} nodes where the torsion chain has {n_nodes}",
            component=repr(comp.name),
            field="max_element_length",
            valid="the same mesh for both (a bug if it happens: please report it)",
        )
    return pm


def _reduce_part(comp: Shaft, pm: PartModel) -> FlexibleBody:
    """Craig–Bampton reduction of the shaft's part model; boundary = end nodes + named nodes."""
    named = comp.named_mesh_nodes(pm.x - pm.x[0])
    red = comp.reduce
    try:
        return craig_bampton(
            pm, modes=red.modes, cutoff_hz=red.cutoff_hz, nodes=named, damping_ratio=red.damping
        )
    except ModelError as err:
        raise err.located(component=repr(comp.name)) from None


def assemble_full(drivetrain: Drivetrain, bearings: Mapping[str, float] | None = None) -> FullModel:
    """Assemble the chain with 6 DOFs per node.

    Parameters
    ----------
    drivetrain : Drivetrain
        Every shaft made from sections; a shaft with ``reduce`` enters as a
        Craig–Bampton flexible body of its 6-DOF part model (boundary: its
        end and named nodes; ``reduce.modes`` / ``cutoff_hz`` / ``damping``
        as given; the damping is not used by :func:`full_modes`).
    bearings : mapping of station name to lateral stiffness (N/m), optional

    Returns
    -------
    FullModel
    """
    tors = assemble(drivetrain, reduce=False)
    n_nodes = tors.n_dof
    nd = 6 * n_nodes
    # Two assemblies: the chain in its coordinates before reduction (node DOFs, then modal ones;
    # interior nodes of flexible bodies left empty), and the unreduced mass on node DOFs (energies).
    k_ext, m_ext, m_nodes = _Triplets(), _Triplets(), _Triplets()
    link = np.arange(nd)  # full DOF -> representative full DOF (coupling links)
    physical = np.ones(nd, dtype=bool)  # False on interior nodes of flexible bodies
    pending = []  # (component, body, first node, first modal coordinate after the node DOFs)
    n_modal = 0
    for ci, comp in enumerate(drivetrain.components):
        s = int(tors.start_node[ci])
        if isinstance(comp, Shaft):
            pm = _shaft_part(comp, drivetrain.inertia_model, int(tors.end_node[ci]) - s + 1)
            m_nodes.add_sparse(pm.M, 6 * s)
            if comp.reduce is None:
                k_ext.add_sparse(pm.K, 6 * s)
                m_ext.add_sparse(pm.M, 6 * s)
                continue
            body = _reduce_part(comp, pm)
            interior = np.setdiff1d(np.arange(pm.n_nodes), body.boundary_nodes)
            physical[(6 * (s + interior))[:, None] + np.arange(6)] = False
            pending.append((ci, body, s, n_modal))
            n_modal += body.n_modes
        elif isinstance(comp, Coupling):
            a, b = 6 * s + 3, 6 * (s + 1) + 3
            kt = comp.stiffness
            k_ext.add([a, a, b, b], [a, b, a, b], [kt, -kt, -kt, kt])
            for tr in (m_ext, m_nodes):
                tr.add([a, b], [a, b], [comp.inertia / 2] * 2)
            for k in (0, 1, 2, 4, 5):
                link[6 * (s + 1) + k] = link[6 * s + k]
        elif isinstance(comp, Rigid):
            for tr in (m_ext, m_nodes):
                tr.add([6 * s + 3], [6 * s + 3], [comp.inertia])
    nodes = {}
    for name, k in (bearings or {}).items():
        if not (np.isfinite(k) and k > 0):
            raise ModelError(
                "must be a finite stiffness > 0",
                field=f"bearings[{name!r}]",
                value=k,
                unit="N/m",
                valid="a finite number > 0 (N/m)",
            )
        node = _station_node(tors.stations, name)
        nodes[node] = nodes.get(node, 0.0) + float(k)
        # Stations are component ends and named nodes: a flexible body's boundary, never its interior.
        k_ext.add([6 * node + 1, 6 * node + 2], [6 * node + 1, 6 * node + 2], [k, k])
    bodies_ext = []
    for ci, body, s, m0 in pending:
        dofs = np.concatenate(
            [
                ((6 * (s + body.boundary_nodes))[:, None] + np.arange(6)).ravel(),
                nd + m0 + np.arange(body.n_modes),
            ]
        )
        k_ext.add_dense(dofs, body.K)
        m_ext.add_dense(dofs, body.M)
        bodies_ext.append((ci, body, s, dofs))
    n_ext = nd + n_modal
    K = k_ext.build(n_ext)
    M = m_ext.build(n_ext)

    # Reduced coordinates: one per representative physical DOF, in order (keeps the band narrow
    # without flexible bodies), then the modal coordinates.
    reps = np.unique(link[physical])
    n_phys = reps.size
    col = np.full(nd, -1)
    col[reps] = np.arange(n_phys)
    col = np.where(physical, col[link], -1)
    n_red = n_phys + n_modal
    ext_cols = np.concatenate([col, n_phys + np.arange(n_modal)])
    keep = ext_cols >= 0
    S = sp.csr_matrix((np.ones(keep.sum()), (np.flatnonzero(keep), ext_cols[keep])), shape=(n_ext, n_red))
    Kr = (S.T @ K @ S).tocsr()
    Mr = (S.T @ M @ S).tocsr()
    if np.any(Mr.diagonal() <= 0):
        raise ModelError(
            "a node carries no mass in some DOF",
            field="inertia",
            valid="shafts from sections on both sides of every rigid inertia and coupling",
        )

    # Recovery: physical DOFs copy their coordinate; a body's interior DOFs are rows of its own T.
    t_rows, t_cols, t_data = [np.flatnonzero(physical)], [col[physical]], [np.ones(int(physical.sum()))]
    bodies = []
    for ci, body, s, dofs in bodies_ext:
        columns = ext_cols[dofs]
        inner = np.flatnonzero(~physical[6 * s : 6 * s + body.T.shape[0]])
        r, c = np.nonzero(body.T[inner])
        t_rows.append(6 * s + inner[r])
        t_cols.append(columns[c])
        t_data.append(body.T[inner[r], c])
        bodies.append(FullBody(component=ci, body=body, first_node=s, columns=columns))
    T = sp.csr_matrix(
        (np.concatenate(t_data), (np.concatenate(t_rows), np.concatenate(t_cols))), shape=(nd, n_red)
    )
    return FullModel(
        drivetrain=drivetrain,
        K=Kr,
        M=Mr,
        T=T,
        x=node_positions(tors),
        stations=tuple((st.name, st.node) for st in tors.stations),
        bearings=nodes,
        M_nodes=m_nodes.build(nd),
        coordinate_dofs=np.concatenate([reps, np.full(n_modal, -1)]),
        bodies=tuple(bodies),
    )


@dataclass(frozen=True)
class FullModes:
    """Modes of the 6-DOF chain (SI): frequencies (Hz), shapes on every node's 6 DOFs, families.

    ``energy[family]`` is each mode's share of kinetic energy in the axial,
    lateral (uy, uz, θy, θz) and torsion (θx) DOFs; ``kind`` the largest.
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    energy: Mapping[str, np.ndarray]
    method: str

    @property
    def kind(self) -> tuple[str, ...]:
        """'axial', 'lateral' or 'torsion' per mode (the family with the most kinetic energy)."""
        names = list(self.energy)
        e = np.vstack([self.energy[n] for n in names])
        return tuple(names[i] for i in np.argmax(e, axis=0))


def _rigid_basis(fm: FullModel) -> np.ndarray:
    """Exact rigid motions of the chain in reduced coordinates, given its bearings.

    A flexible body's modal coordinates are 0 in a rigid motion: its constraint
    modes Ψ = −K_ii⁻¹ K_ib carry any motion with K u = 0 exactly.
    """
    n = fm.n_nodes
    s = fm.x - fm.x[0]
    cols = []
    for k in (0, 3):  # axial and spin are never held
        v = np.zeros((n, 6))
        v[:, k] = 1.0
        cols.append(v.ravel())
    if len(fm.bearings) == 0 or (len(fm.bearings) == 1):
        pivot = s[next(iter(fm.bearings))] if fm.bearings else 0.0
        if not fm.bearings:
            for k in (1, 2):
                v = np.zeros((n, 6))
                v[:, k] = 1.0
                cols.append(v.ravel())
        vy = np.zeros((n, 6))
        vy[:, 4], vy[:, 2] = 1.0, -(s - pivot)
        vz = np.zeros((n, 6))
        vz[:, 5], vz[:, 1] = 1.0, s - pivot
        cols += [vy.ravel(), vz.ravel()]
    full = np.column_stack(cols)
    return _at_coordinates(fm, full)


def _at_coordinates(fm: FullModel, full: np.ndarray) -> np.ndarray:
    """Node-DOF vectors (6·n_nodes, m) read at the physical coordinates, 0 on the modal ones."""
    reps = fm.representatives
    out = np.zeros((reps.size, full.shape[1]))
    phys = reps >= 0
    out[phys] = full[reps[phys]]
    return out


def full_modes(fm: FullModel, count: int = 12) -> FullModes:
    """The ``count`` lowest modes of a 6-DOF chain (rigid-body modes included).

    Shapes are recovered on all six DOFs of every node (flexible bodies'
    interiors included). ``energy`` splits each mode's kinetic energy
    uᵀ M_nodes u of the recovered shape u by the family of the node DOF
    (row by row, u_r·(M_nodes u)_r; consistent mass couples uy and θz, so a
    share is a row's, not a positive-definite part): the reduced coordinates
    of a flexible body mix families, the recovered shape does not, and since
    M = Tᵀ M_nodes T the shares of a mass-normalised mode sum to 1.
    """
    # Trial shapes for the eigensolver's shift: smooth along the axis on the physical coordinates,
    # modal coordinates at rest (the bodies' interiors then follow their constraint modes).
    trial = _at_coordinates(fm, smooth_trial_shapes(fm.x, 6))
    sol = lowest_modes(fm.K, fm.M, count, rigid_basis=_rigid_basis(fm), trial=trial)
    shapes = fm.T @ sol.vectors
    per_dof = shapes * (fm.M_nodes @ shapes)
    local = np.arange(shapes.shape[0]) % 6
    energy = {fam: per_dof[np.isin(local, ks)].sum(axis=0) for fam, ks in FAMILIES.items()}
    f = np.sqrt(np.clip(sol.eigenvalues, 0.0, None)) / (2 * np.pi)
    return FullModes(frequencies_hz=f, shapes=shapes, rigid=sol.rigid, energy=energy, method=sol.method)
