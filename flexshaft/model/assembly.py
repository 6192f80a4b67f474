"""The drivetrain as one assembled model: K, M, C on its coordinates, and how to read them.

One assembler for every DOF set. ``dofs = "torsion"`` gives each node θx
alone; ``dofs = "full"`` gives it (ux, uy, uz, θx, θy, θz) with Timoshenko
shafts. Torsion is the one-DOF-per-node case of the same model, not a second
code path.

Nodes follow the chain from the driving end: every node of every shaft's own
mesh (the interior nodes of a Craig–Bampton body included), so a mode can be
read anywhere along the line. The *coordinates* the matrices act on are

- the node DOFs that stay physical, in node order - except the five lateral
  and axial DOFs a coupling links rigidly across it (its two nodes share
  them, eliminated exactly) and the interior nodes of flexible bodies;
- then the modal coordinates of each flexible body, body by body.

So a torsion chain without bodies is tridiagonal (coordinate = node), and a
flexible body is a dense block on its interface and modal coordinates (an
"arrow" whose modal rows come last, which a sparse factorisation does not
fill). ``T`` recovers every node DOF from the coordinates.

What each component contributes:

- a rigid inertia: θx of its node; in a full model also its mass on the
  translations, its diametral inertia on the tilts and its polar inertia's
  gyroscopic coupling of the tilts;
- a shaft: its elements (torsion: k·[[1,−1],[−1,1]] with the consistent or
  lumped inertia; full: its Timoshenko part model), or its Craig–Bampton body
  (``reduce``); a discrete damper along it, on θx, split like the stiffness;
  modal damping of its own free-free modes (``damping_ratio``);
- a coupling: a torsional spring and damper, its inertia on its two ends
  (by the model's inertia rule, or two rigid halves), rigid in the other
  five DOFs;
- a gear stage (torsion models): each wheel's inertia on its node, and either
  a rigid mesh - the driven wheel's angle is the driving wheel's over the
  ratio, one coordinate for both - or a mesh spring and damper
  k·[[1, −n], [−n, n²]] on (θ_in, θ_out). Every node DOF is in its own
  shaft's speed frame (``speed_ratio``), so T carries the factor 1/n where a
  rigid mesh ties a driven node to its coordinate;
- a bearing (full models): isotropic lateral springs at a station;
- Rayleigh damping αM + βK on the whole model.

Every stiffness and mass entry keeps its owner (a component, or a bearing),
so each mode's energy splits exactly into the components' shares.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements import torsion_stiffness
from ..errors import ModelError
from ..linalg.damping import modal_damping_matrix
from ..linalg.eigen import solver_failures
from ..linalg.sparse import Entries, Triplets
from ..parts.model import DOF_NAMES, smooth_trial_shapes
from ..reduction import FlexibleBody
from ..system.threads import follows_policy
from ..validation import check_choice
from .components import INERTIA_MODELS, Coupling, Drivetrain, Gear, Rigid, Shaft, check_torsion_gears
from .shaftparts import (
    MAX_MODAL_DAMPING_DOFS,
    MAX_MODAL_DAMPING_ELEMENTS,
    ShaftElements,
    check_modal_damping_size,
    check_model_size,
    lean,
    per_element,
    reduced_body,
    shaft_elements,
    shaft_part,
    shaft_part_model,
    torsion_blocks,
)

__all__ = [
    "Station",
    "Body",
    "AssembledModel",
    "assemble",
    "FAMILIES",
    "MAX_MODAL_DAMPING_ELEMENTS",
    "MAX_MODAL_DAMPING_DOFS",
    "shaft_part_model",
]

#: DOF families of a node, by DOF name.
FAMILIES: dict[str, tuple[str, ...]] = {
    "axial": ("ux",),
    "lateral": ("uy", "uz", "θy", "θz"),
    "torsion": ("θx",),
}


@dataclass(frozen=True)
class Station:
    """A named node: a component boundary or a named node inside a shaft.

    Attributes
    ----------
    name : str
        ``"motor"`` where a rigid inertia sits, ``"part 1/part 2"`` between two
        flexible components, ``"part 4 end"`` / ``"part 1 start"`` at a free
        end, ``"part 2: journal"`` for a named node inside a shaft.
    node : int
        Index of the node.
    """

    name: str
    node: int


@dataclass(frozen=True)
class Body:
    """A shaft entered as a Craig–Bampton flexible body, and where it sits in the model.

    Attributes
    ----------
    component : int
        Index of the shaft in the chain.
    body : FlexibleBody
        The reduction of the shaft's own part model (torsion or 6-DOF): K, M,
        C, T.
    first_node : int
        Node of the shaft's first mesh node: its mesh node ``j`` is node
        ``first_node + j``.
    columns : ndarray of int
        Coordinate of each of the body's reduced coordinates: its boundary
        DOFs (node-major), then its modal coordinates.
    scale : ndarray
        Each reduced coordinate is ``scale`` times its coordinate (1, but 1/n
        on a driven wheel's node tied by a rigid gear mesh to the coordinate
        of the driving wheel).
    """

    component: int
    body: FlexibleBody
    first_node: int
    columns: np.ndarray
    scale: np.ndarray

    @property
    def interface_nodes(self) -> np.ndarray:
        """Nodes of the body's interface (boundary) nodes, in order along the shaft."""
        return self.first_node + self.body.boundary_nodes

    @property
    def modal_columns(self) -> np.ndarray:
        """Coordinates of the body's modal coordinates."""
        return self.columns[self.body.n_boundary :]

    def recover(self, V: np.ndarray) -> np.ndarray:
        """Every DOF of every mesh node of the shaft (node-major, m and rad) from coordinates ``V``."""
        Vc = V[self.columns]
        return self.body.T @ (Vc * self.scale.reshape((-1,) + (1,) * (Vc.ndim - 1)))


@dataclass(frozen=True)
class AssembledModel:
    """The drivetrain as matrices on its coordinates, with the bookkeeping to read them (SI).

    A per-element or per-node array whose entries are all equal (a uniform
    shaft's stiffness, damping, speed frame...) is one value broadcast to its
    length (``np.broadcast_to``, read-only): it reads as the full array and
    costs 8 bytes, not 8 MB per million elements.

    Attributes
    ----------
    drivetrain : Drivetrain
        What was assembled.
    inertia_model : {"consistent", "lumped"}
        How shaft inertia was spread.
    dofs : {"torsion", "full"}
        θx per node, or (ux, uy, uz, θx, θy, θz) per node.
    K, M : scipy.sparse.csr_matrix, shape (n, n)
        Stiffness (N/m, N, N·m/rad by DOF pair) and mass (kg, kg·m, kg·m²) on
        the coordinates; symmetric.
    C : scipy.sparse.csr_matrix or None
        Damping (N·s/m, N·m·s/rad), or None for an undamped model.
    T : scipy.sparse.csr_matrix, shape (d·n_nodes, n)
        Recovery of every node DOF from the coordinates (node-major,
        ``u = T @ q``), interior nodes of flexible bodies included.
    x : ndarray, shape (n_nodes,)
        Node positions along the line, m (components not made from geometry
        have no length: their nodes share a position).
    stations : tuple of Station
        Named nodes, in node order.
    start_node, end_node : ndarray of int
        Per component (chain order), its first and last node; equal for a rigid.
    coordinate_dofs : ndarray of int, shape (n,)
        For each coordinate, the node DOF (d·node + k) it stands for; −1 for
        a modal coordinate of a flexible body.
    element_nodes : ndarray of int, shape (n_el,)
        Left node of each torsion element along the line (the right one is
        ``+1``), flexible bodies' meshes and couplings included.
    element_stiffness : ndarray, shape (n_el,)
        Its torsional stiffness, N·m/rad.
    element_damping : ndarray, shape (n_el,)
        Its dashpot across the same relative rotation, N·m·s/rad (a shaft's ``damping`` split like
        its stiffness, a coupling's damper, a gear's mesh damper; modal damping is not a dashpot).
    element_component : ndarray of int, shape (n_el,)
        The component it belongs to.
    element_ratio : ndarray, shape (n_el,)
        n of each element's torque k·(n·θ_right − θ_left) in its left node's
        frame: 1, but a gear mesh's ratio.
    speed_ratio : ndarray, shape (n_nodes,)
        Each node's speed frame: its speed over the driving end's in a rigid
        spin (1 everywhere without gear stages; 1/n past a stage of ratio n).
        Node angles, speeds and torques are in this frame.
    stiffness_entries, mass_entries, damping_entries : Entries
        K, M and C on the coordinates with the owner of every stored entry:
        the component index, or ``n_components + b`` for bearing ``b`` (see
        :class:`~flexshaft.linalg.sparse.Entries`; its ``matrix`` is ``K``,
        ``M`` or the dampers' part of ``C`` itself, not a copy). Rayleigh
        damping (model-wide, αM + βK) is not among the damping entries; it is
        ``drivetrain.rayleigh``.
    M_nodes : scipy.sparse.csr_matrix, shape (d·n_nodes, d·n_nodes)
        The unreduced mass on every node DOF; ``M = Tᵀ M_nodes T`` (a body's
        mass is its part's mass projected on its recovery matrix), so the
        kinetic energy of a recovered shape is exact, DOF by DOF.
    bodies : tuple of Body
        Shafts entered as flexible bodies.
    bearings : tuple of (Station, float)
        Lateral bearing springs, N/m, at their stations.
    G : scipy.sparse.csr_matrix or None
        Gyroscopic matrix of a 6-DOF model per rad/s of line speed (kg·m², skew-symmetric): the
        shafts' spinning inertia and the rigid components' polar inertia on their node's tilts,
        forces −Ω·G·q̇ at speed Ω. None for a torsion model.
    """

    drivetrain: Drivetrain
    inertia_model: str
    dofs: str
    K: sp.csr_matrix
    M: sp.csr_matrix
    C: sp.csr_matrix | None
    T: sp.csr_matrix
    x: np.ndarray
    stations: tuple
    start_node: np.ndarray
    end_node: np.ndarray
    coordinate_dofs: np.ndarray
    element_nodes: np.ndarray
    element_stiffness: np.ndarray
    element_damping: np.ndarray
    element_component: np.ndarray
    element_ratio: np.ndarray
    speed_ratio: np.ndarray
    stiffness_entries: Entries
    mass_entries: Entries
    damping_entries: Entries
    M_nodes: sp.csr_matrix
    bodies: tuple
    bearings: tuple
    G: sp.csr_matrix | None = None

    @property
    def n_dof(self) -> int:
        """Number of coordinates."""
        return self.K.shape[0]

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.x.size

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Names of a node's DOFs, in order."""
        return DOF_NAMES[self.dofs]

    @property
    def dofs_per_node(self) -> int:
        """1 for a torsion model, 6 for a full one."""
        return len(self.dof_names)

    @property
    def modal(self) -> np.ndarray:
        """Which coordinates are modal coordinates of a flexible body."""
        return self.coordinate_dofs < 0

    @property
    def n_owners(self) -> int:
        """Components, then bearings: who owns stiffness and mass entries."""
        return len(self.drivetrain.components) + len(self.bearings)

    @property
    def bandwidth(self) -> int | None:
        """Half-bandwidth of K, M and C when it is known to be 1 (a torsion chain), else None."""
        if self.dofs == "torsion" and not self.bodies:
            return 1 if self.n_dof > 1 else 0
        return None

    @property
    def station_nodes(self) -> np.ndarray:
        """Node of every station, in order."""
        return np.array([s.node for s in self.stations], dtype=int)

    @property
    def component_names(self) -> tuple[str, ...]:
        """Component names in chain order."""
        return tuple(c.name for c in self.drivetrain.components)

    @property
    def coordinate_labels(self) -> tuple[str, ...]:
        """What each coordinate is: ``"node 12 θx"`` (a node DOF; for DOFs a coupling links, the
        first node's), or ``"part 2 mode 3"`` / ``"part 2 residual 1"`` (a flexible body's modal
        coordinates, numbered from 1 as in its exports)."""
        d = self.dofs_per_node
        labels = [
            f"node {int(c) // d} {self.dof_names[int(c) % d]}" if c >= 0 else "" for c in self.coordinate_dofs
        ]
        for b in self.bodies:
            name = self.drivetrain.components[b.component].name
            n_fixed = b.body.n_modes - b.body.n_residual
            for k, col in enumerate(b.modal_columns):
                kind, j = ("mode", k + 1) if k < n_fixed else ("residual", k - n_fixed + 1)
                labels[int(col)] = f"{name} {kind} {j}"
        return tuple(labels)

    def node_dof(self, nodes, dof: str = "θx") -> np.ndarray:
        """Rows of ``T`` (node DOF indices) of one DOF at the given nodes."""
        if dof not in self.dof_names:
            raise ModelError("no such DOF", field="dof", value=dof, valid=", ".join(self.dof_names))
        return np.asarray(nodes, dtype=int) * self.dofs_per_node + self.dof_names.index(dof)

    def station(self, name: str, field: str = "station") -> Station:
        """The station called ``name``; an error lists the valid ones."""
        for st in self.stations:
            if st.name == name:
                return st
        raise ModelError(
            "no such station", field=field, value=name, valid=", ".join(repr(s.name) for s in self.stations)
        )

    def at_coordinates(self, node_vectors: np.ndarray) -> np.ndarray:
        """Node-DOF vectors (d·n_nodes, m) read at the physical coordinates, 0 on modal ones."""
        reps = self.coordinate_dofs
        out = np.zeros((reps.size, node_vectors.shape[1]))
        phys = reps >= 0
        out[phys] = node_vectors[reps[phys]]
        return out

    @property
    def rigid_basis(self) -> np.ndarray:
        """The exact rigid-body motions the supports allow, on the coordinates, one per column.

        Torsion: the spin (every node turns by its speed ratio, 1 rad at the
        driving end, in its own frame past a gear stage). Full: axial motion and
        spin always; lateral translations and tilts as the bearings allow
        (none: both; one: tilting about it; two or more: neither). A flexible
        body's modal coordinates are 0 in a rigid motion: its constraint modes
        carry any motion with K u = 0 exactly.
        """
        n, d = self.n_nodes, self.dofs_per_node
        if d == 1:
            return self.at_coordinates(self.speed_ratio[:, None])
        s = self.x - self.x[0]
        cols = []
        for k in (0, 3):  # axial and spin are never held
            v = np.zeros((n, 6))
            v[:, k] = 1.0
            cols.append(v.ravel())
        held = sorted({st.node for st, _ in self.bearings})
        if len(held) <= 1:
            pivot = s[held[0]] if held else 0.0
            if not held:
                for k in (1, 2):
                    v = np.zeros((n, 6))
                    v[:, k] = 1.0
                    cols.append(v.ravel())
            vy = np.zeros((n, 6))
            vy[:, 4], vy[:, 2] = 1.0, -(s - pivot)
            vz = np.zeros((n, 6))
            vz[:, 5], vz[:, 1] = 1.0, s - pivot
            cols += [vy.ravel(), vz.ravel()]
        return self.at_coordinates(np.column_stack(cols))

    def trial_shapes(self) -> np.ndarray | None:
        """Shapes whose Rayleigh quotients bound the lowest elastic mode (the eigensolver's shift).

        None for a torsion chain (the solver's ramp over the DOF numbering
        fits it); a ramp over its physical coordinates with modal coordinates
        at rest when it has flexible bodies (modal coordinates are not
        positions along the chain); smooth half waves per DOF family for a
        full model (a ramp over interleaved ux … θz would mix DOF kinds and
        bound λ₁ far too high).
        """
        if self.dofs == "torsion":
            if not self.bodies:
                return None
            trial = np.zeros((self.n_dof, 1))
            phys = ~self.modal
            trial[phys, 0] = np.linspace(-1.0, 1.0, int(phys.sum()))
            return trial
        return self.at_coordinates(smooth_trial_shapes(self.x, self.dofs_per_node))


def _station_names(drivetrain: Drivetrain, start: np.ndarray, end: np.ndarray, named: dict) -> tuple:
    """Name the nodes where components meet (see :class:`Station`).

    ``named`` maps a component index to the nodes of its named nodes.
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


@follows_policy
def assemble(
    drivetrain: Drivetrain,
    inertia_model: str | None = None,
    *,
    reduce: bool = True,
    dofs: str | None = None,
    damping: bool = True,
    statics: bool = False,
) -> AssembledModel:
    """Assemble the drivetrain's K, M and C on its coordinates.

    Parameters
    ----------
    drivetrain : Drivetrain
        The chain, its bearings and its Rayleigh damping.
    inertia_model : {"consistent", "lumped"}, optional
        Overrides ``drivetrain.inertia_model``.
    reduce : bool
        Enter shafts with ``reduce`` as Craig–Bampton flexible bodies (the
        default); False keeps every shaft's full mesh (a static test, which
        Craig–Bampton reproduces exactly anyway, or a reference).
    dofs : {"torsion", "full"}, optional
        Overrides ``drivetrain.dofs`` (a full model's torsion chain, e.g. for
        the twist test; its bearings are then not used).
    damping : bool
        False leaves out the shafts' modal damping (``damping_ratio``), whose
        dense damping matrix costs an eigen-solve of each part's full model:
        for analyses that read K and M alone (the mesh check, the twist test).
        Dampers, flexible bodies' damping and Rayleigh damping stay.
    statics : bool
        Only K is read (the twist test): a solid part (``fe = "solid"``) enters as its static
        condensation onto its end faces' master nodes, without its modes. Solid parts are always
        Craig–Bampton bodies, whatever ``reduce`` says: their full mesh never enters the chain.

    Returns
    -------
    AssembledModel

    Raises
    ------
    ModelError
        If a node carries no inertia at all (a massless free end), which
        makes the inertia matrix singular; if a full model has a shaft without
        sections; a bearing at an unknown station.
    """
    model = drivetrain.inertia_model if inertia_model is None else inertia_model
    check_choice(model, "inertia_model", INERTIA_MODELS)
    dofs = drivetrain.dofs if dofs is None else check_choice(dofs, "dofs", tuple(DOF_NAMES))
    check_torsion_gears(drivetrain.components, dofs)
    comps = drivetrain.components
    check_model_size(comps, dofs)

    # 1. Nodes: every mesh node of every flexible component, in chain order.
    start, end, shafts, x, speed = _chain_nodes(comps)
    # 2. Entries on the extended DOFs: node DOFs [0, nd), then the bodies' modal coordinates.
    acc = _Entries(dofs, speed.size)
    how = {"model": model, "reduce": reduce, "damping": damping, "statics": statics}
    for ci, comp in enumerate(comps):
        s = int(start[ci])
        if isinstance(comp, Rigid):
            acc.rigid(ci, comp, s)
        elif isinstance(comp, Coupling):
            acc.coupling(ci, comp, s, model)
        elif isinstance(comp, Gear):
            acc.gear(ci, comp, s)
        else:
            acc.shaft(ci, comp, s, shafts[ci], **how)
    stations = _station_names(drivetrain, start, end, acc.named)
    bearings = acc.bearings(drivetrain, stations)
    acc.bodies()
    # The per-element arrays now, and the shafts' own let go, before the matrices are summed.
    element_arrays = acc.element_arrays()
    del shafts

    # 3. Coordinates: one per representative physical DOF, in order (a chain stays banded), then the
    # modal coordinates.
    reps, col, ext_cols, ext_scale, n = acc.coordinates()
    # The model's K and M are the entries' own matrices (one copy, the owners beside it).
    k_entries, m_entries = acc.K.entries(n, ext_cols, ext_scale), acc.M.entries(n, ext_cols, ext_scale)
    Kr, Mr = k_entries.matrix, m_entries.matrix
    _check_inertia(Mr, reps, stations, start, end, comps, acc.d)

    # 4. Recovery: physical DOFs copy their coordinate; a body's interior DOFs are rows of its own T.
    T, bodies = acc.recovery(col, ext_cols, ext_scale, n)
    c_entries = acc.C.entries(n, ext_cols, ext_scale)
    Cr = c_entries.matrix if acc.C.n_entries else None
    ray = drivetrain.rayleigh
    if ray is not None and (ray.alpha or ray.beta):
        R = ray.alpha * Mr + ray.beta * Kr
        Cr = R if Cr is None else Cr + R
    if Cr is not None:
        Cr = sp.csr_matrix(Cr)

    return AssembledModel(
        drivetrain=drivetrain,
        inertia_model=model,
        dofs=dofs,
        K=Kr,
        M=Mr,
        C=Cr,
        T=T,
        x=lean(x),
        stations=stations,
        start_node=start,
        end_node=end,
        coordinate_dofs=np.concatenate([reps, np.full(acc.n_modal, -1)]) if acc.n_modal else reps,
        **element_arrays,
        speed_ratio=lean(speed),
        stiffness_entries=k_entries,
        mass_entries=m_entries,
        damping_entries=c_entries,
        M_nodes=Mr if ext_cols is None and not bodies else acc.M_nodes.build(acc.nd),
        bodies=tuple(bodies),
        bearings=tuple(bearings),
        G=acc.Gy.build(n, ext_cols, ext_scale) if dofs == "full" else None,
    )


def _chain_nodes(comps) -> tuple:
    """Each component's first and last node, the shafts' elements, every node's position (m) and
    speed frame: every mesh node of every flexible component, in chain order."""
    n_comp = len(comps)
    start = np.zeros(n_comp, dtype=int)
    end = np.zeros(n_comp, dtype=int)
    shafts: dict[int, ShaftElements] = {}
    steps = []
    node = 0
    for ci, comp in enumerate(comps):
        start[ci] = node
        if isinstance(comp, Shaft):
            el = shafts[ci] = shaft_elements(comp)
            steps.append(np.diff(el.x) if el.has_length else np.zeros(el.k.size))
            node += el.k.size
        elif isinstance(comp, (Coupling, Gear)):
            steps.append(np.zeros(1))
            node += 1
        end[ci] = node
    n_nodes = node + 1
    speed = np.ones(n_nodes)
    for ci, comp in enumerate(comps):
        if isinstance(comp, Gear):
            speed[end[ci] :] /= comp.ratio
    x = np.concatenate([[0.0], np.cumsum(np.concatenate(steps))]) if steps else np.zeros(1)
    return start, end, shafts, x, speed


class _Entries:
    """The entries of K, M, C (and the nodes' own M, the gyroscopic G) on the extended DOFs, with each
    entry's owner, and how the node DOFs are linked, while :func:`assemble` walks the chain."""

    def __init__(self, dofs: str, n_nodes: int):
        self.dofs, self.d = dofs, len(DOF_NAMES[dofs])
        self.th = DOF_NAMES[dofs].index("θx")
        self.nd = nd = self.d * n_nodes
        self.K, self.M, self.C = Triplets(), Triplets(), Triplets()
        self.M_nodes, self.Gy = Triplets(), Triplets()
        self.link = np.arange(nd)  # node DOF -> the node DOF it is linked to (couplings, full; rigid gears)
        self.scale = np.ones(nd)  # node DOF = scale · the DOF it is linked to (1/n across a rigid gear mesh)
        self.physical = np.ones(nd, dtype=bool)  # False on interior nodes of flexible bodies
        self.el_nodes, self.el_k, self.el_c, self.el_comp, self.el_ratio = [], [], [], [], []
        self.named: dict[int, list[int]] = {}
        self.pending = []  # (component, body, first node, first modal coordinate, damper projected, G)
        self.n_modal = 0
        self.ext = []  # (component, body, first node, extended DOFs)

    def _element(self, nodes, k, c, ci, ratio) -> None:
        self.el_nodes.append(nodes)
        self.el_k.append(k)
        self.el_c.append(c)
        self.el_comp.append(ci)
        self.el_ratio.append(ratio)

    def rigid(self, ci: int, comp: Rigid, s: int) -> None:
        d, th = self.d, self.th
        for tr in (self.M, self.M_nodes):
            tr.add([d * s + th], [d * s + th], [comp.inertia], ci)
        if self.dofs == "full":
            # its mass on ux, uy, uz, its diametral inertia on θy, θz; spinning, its polar inertia
            # turns the tilts as a shaft slice's does (the same sign as the element's G)
            dof = d * s + np.array([0, 1, 2, 4, 5])
            values = [comp.mass] * 3 + [comp.diametral_inertia] * 2
            for tr in (self.M, self.M_nodes):
                tr.add(dof, dof, values, ci)
            self.Gy.add([d * s + 5, d * s + 4], [d * s + 4, d * s + 5], [comp.inertia, -comp.inertia], ci)

    def coupling(self, ci: int, comp: Coupling, s: int, model: str) -> None:
        d, th = self.d, self.th
        pair = np.array([[d * s + th, d * (s + 1) + th]])
        self.K.add_elements(pair, torsion_stiffness(np.array([comp.stiffness])), ci)
        # The study's matrix models spread it like any element; "halves" keeps two rigid hubs.
        lumped = comp.inertia_split == "halves" or model == "lumped"
        for tr in (self.M, self.M_nodes):
            tr.add_elements(pair, torsion_blocks(np.array([comp.inertia]), lumped), ci)
        if comp.damping:
            self.C.add_elements(pair, torsion_stiffness(np.array([comp.damping])), ci)
        for k in range(d):
            if k != th:
                self.link[d * (s + 1) + k] = self.link[d * s + k]
        self._element([s], [comp.stiffness], [comp.damping], [ci], [1.0])

    def gear(self, ci: int, comp: Gear, s: int) -> None:
        i_in, i_out = self.d * s + self.th, self.d * (s + 1) + self.th
        for tr in (self.M, self.M_nodes):
            tr.add([i_in, i_out], [i_in, i_out], [comp.inertia_in, comp.inertia_out], ci)
        if comp.rigid_mesh:
            # θ_out = θ_in / n exactly: the driven wheel's DOF is the driving wheel's coordinate
            # times 1/n (a chain of stages multiplies the factors: i_in may itself be tied).
            self.link[i_out] = self.link[i_in]
            self.scale[i_out] = self.scale[i_in] / comp.ratio
            return
        # The mesh's relative rotation in the driving frame, θ_in − n·θ_out, carries the spring.
        block = np.array([[1.0, -comp.ratio], [-comp.ratio, comp.ratio**2]])
        with np.errstate(over="ignore"):  # an overflow is refused with the assembled matrices' check
            self.K.add_dense([i_in, i_out], comp.mesh_stiffness * block, ci)
            if comp.mesh_damping:
                self.C.add_dense([i_in, i_out], comp.mesh_damping * block, ci)
        self._element([s], [comp.mesh_stiffness], [comp.mesh_damping], [ci], [comp.ratio])

    def shaft(self, ci: int, comp: Shaft, s: int, el: ShaftElements, *, model, reduce, damping, statics):
        d, th, dofs = self.d, self.th, self.dofs
        n = el.k.size
        self._element(s + np.arange(n), el.k, el.c, np.broadcast_to(ci, n), np.broadcast_to(1.0, n))
        marks = comp.named_mesh_nodes(el.x)
        if marks:
            self.named[ci] = [s + m for m in marks]
        reduced = (reduce and comp.reduce is not None) or comp.fe == "solid"
        damped_modally = damping and comp.damping_ratio > 0 and not reduced
        part = None
        if dofs == "full" or reduced or damped_modally:
            part = shaft_part(comp, el, dofs, model)
        theta_pairs = np.empty((n, 2), dtype=np.int64)  # θx of each element's two nodes
        theta_pairs[:, 0] = d * (s + np.arange(n)) + th
        theta_pairs[:, 1] = theta_pairs[:, 0] + d
        dampers = torsion_stiffness(el.c) if np.any(el.c > 0) else None
        if dofs == "full":
            self.M_nodes.add_sparse(part.M, d * s, ci)
        else:
            m_blocks = torsion_blocks(el.j, model == "lumped")
            self.M_nodes.add_elements(theta_pairs, m_blocks, ci)
        if reduced:
            self._body(ci, comp, s, el, part, marks, dampers, statics)
            return
        if dofs == "full":
            self.K.add_sparse(part.K, d * s, ci)
            self.M.add_sparse(part.M, d * s, ci)
            self.Gy.add_sparse(part.G, d * s, ci)
        else:
            self.K.add_elements(theta_pairs, per_element(torsion_stiffness, el.k), ci)
            self.M.add_elements(theta_pairs, m_blocks, ci)
        if dampers is not None:
            self.C.add_elements(theta_pairs, dampers, ci)
        if damped_modally:
            # The shaft's own free-free model: its elements only. Rigid inertias
            # and neighbours on its end nodes belong to other components.
            check_modal_damping_size(comp, part)
            with solver_failures(f"the modal damping of {comp.name!r}"):
                Cp = modal_damping_matrix(part.K, part.M, comp.damping_ratio)
            self.C.add_dense(d * s + np.arange(part.n_dofs), Cp, ci)

    def _body(self, ci, comp, s, el, part, marks, dampers, statics) -> None:
        """A shaft entering as a flexible body: its interior nodes leave the coordinates."""
        d, th, n = self.d, self.th, el.k.size
        body = reduced_body(comp, el, part, marks, self.dofs, statics)
        interior = np.setdiff1d(np.arange(n + 1), body.boundary_nodes)
        self.physical[((d * (s + interior))[:, None] + np.arange(d)).ravel()] = False
        extra_c = None
        if dampers is not None:
            # A discrete damper along the shaft, projected on the body's coordinates.
            Cp = Triplets()
            Cp.add_elements(d * np.column_stack([np.arange(n), np.arange(n) + 1]) + th, dampers)
            T = body.T
            extra_c = T.T @ (Cp.build(d * (n + 1)) @ T)
        self.pending.append((ci, body, s, self.n_modal, extra_c, part.G if self.dofs == "full" else None))
        self.n_modal += body.n_modes

    def bearings(self, drivetrain: Drivetrain, stations) -> list:
        """Each bearing's lateral springs at its station (a torsion model has no lateral DOFs: a full
        drivetrain's torsion chain leaves its bearings out)."""
        by_name = {st.name: st for st in stations}
        n_comp, d = len(drivetrain.components), self.d
        out = []
        for b, (name, k) in enumerate(drivetrain.bearings if self.dofs == "full" else ()):
            if name not in by_name:
                raise ModelError(
                    "no such station",
                    field="bearings.station",
                    value=name,
                    valid=", ".join(repr(s.name) for s in stations),
                )
            st = by_name[name]
            # Stations are component ends and named nodes: a flexible body's boundary, never its interior.
            lateral = [d * st.node + 1, d * st.node + 2]
            self.K.add(lateral, lateral, [k, k], n_comp + b)
            out.append((st, float(k)))
        return out

    def bodies(self) -> None:
        """The flexible bodies' dense blocks on their boundary DOFs and modal coordinates."""
        d, nd = self.d, self.nd
        for ci, body, s, m0, extra_c, part_g in self.pending:
            ext = np.concatenate(
                [
                    ((d * (s + body.boundary_nodes))[:, None] + np.arange(d)).ravel(),
                    nd + m0 + np.arange(body.n_modes),
                ]
            )
            self.K.add_dense(ext, body.K, ci)
            self.M.add_dense(ext, body.M, ci)
            if part_g is not None:
                # the body's spin, on its coordinates
                self.Gy.add_dense(ext, body.T.T @ (part_g @ body.T), ci)
            Cb = body.C if extra_c is None else body.C + extra_c
            if np.any(Cb):
                self.C.add_dense(ext, Cb, ci)
            self.ext.append((ci, body, s, ext))

    def element_arrays(self) -> dict:
        """The per-element arrays, the lists they were gathered in let go."""
        out = dict(
            element_nodes=_joined(self.el_nodes, int),
            element_stiffness=_joined(self.el_k, float),
            element_damping=_joined(self.el_c, float),
            element_component=_joined(self.el_comp, int),
            element_ratio=_joined(self.el_ratio, float),
        )
        self.el_nodes = self.el_k = self.el_c = self.el_comp = self.el_ratio = None
        return out

    def coordinates(self) -> tuple:
        """The representative node DOFs, each node DOF's coordinate, the extended DOFs' coordinates and
        scales (None: the identity), and the number of coordinates."""
        nd, physical, link, scale = self.nd, self.physical, self.link, self.scale
        # A linked DOF points at the first DOF of its group, which points at itself (and is physical: a
        # coupling's nodes are component ends, never a body's interior).
        reps = np.flatnonzero(physical & (link == np.arange(nd)))
        n_phys = reps.size
        n = n_phys + self.n_modal
        if n_phys == nd:
            ext_cols = None  # coordinates are the node DOFs: nothing to map
            col = np.arange(nd)
        else:
            col = np.full(nd, -1)
            col[reps] = np.arange(n_phys)
            col = np.where(physical, col[link], -1)
            ext_cols = np.concatenate([col, n_phys + np.arange(self.n_modal)])
        tied = np.any(scale != 1.0)
        ext_scale = np.concatenate([scale, np.ones(self.n_modal)]) if tied else None
        return reps, col, ext_cols, ext_scale, n

    def recovery(self, col, ext_cols, ext_scale, n) -> tuple:
        """T (nd, n) and the bodies: physical DOFs copy their coordinate, a body's interior DOFs are
        rows of its own T (without bodies or linked DOFs T is the identity: no triplets for it)."""
        d, nd, physical, scale = self.d, self.nd, self.physical, self.scale
        plain = ext_cols is None and not self.ext
        t_rows, t_cols, t_data = [], [], []
        if not plain:
            t_rows, t_cols, t_data = [np.flatnonzero(physical)], [col[physical]], [scale[physical]]
        bodies = []
        for ci, body, s, ext in self.ext:
            columns = ext if ext_cols is None else ext_cols[ext]
            factor = np.ones(ext.size) if ext_scale is None else ext_scale[ext]
            inner = np.flatnonzero(~physical[d * s : d * s + body.T.shape[0]])
            r, c = np.nonzero(body.T[inner])
            t_rows.append(d * s + inner[r])
            t_cols.append(columns[c])
            t_data.append(body.T[inner[r], c] * factor[c])
            bodies.append(Body(component=ci, body=body, first_node=s, columns=columns, scale=factor))
        if ext_cols is None and not bodies:
            return sp.identity(nd, format="csr"), bodies
        T = sp.csr_matrix(
            (np.concatenate(t_data), (np.concatenate(t_rows), np.concatenate(t_cols))), shape=(nd, n)
        )
        return T, bodies


def _joined(parts: list, dtype) -> np.ndarray:
    """The parts end to end as one array of ``dtype``; one value broadcast when all are equal (see _lean)."""
    parts = [np.asarray(p, dtype=dtype).reshape(-1) for p in parts]  # reshape: a broadcast stays one
    filled = [p for p in parts if p.size]
    total = sum(p.size for p in filled)
    if total > 1:
        v = filled[0][0]
        if all(np.all(p == v) for p in filled):
            # The full array is never made.
            return np.broadcast_to(np.asarray(v, dtype=dtype), (total,))
    return np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)


def _check_inertia(M, reps, stations, start, end, comps, d: int) -> None:
    """Every coordinate needs some inertia, or the eigenproblem has infinite roots."""
    bad = np.flatnonzero(M.diagonal() <= 0.0)
    if bad.size == 0:
        return
    if d > 1 or bad[0] >= reps.size:
        raise ModelError(
            "a node carries no mass in some DOF",
            field="inertia",
            valid="shafts from sections on both sides of every rigid inertia and coupling",
        )
    node = int(reps[bad[0]])
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
