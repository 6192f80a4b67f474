"""The drivetrain with six DOFs per node: Timoshenko shafts, couplings, rigid inertias, bearings.

Every shaft must be made from sections (a ``cad`` part or ``segments``): its
6-DOF part model (:func:`flexshaft.partmodel.part_model`, on the same mesh as
the torsion chain, so node numbers and stations are shared) is placed on the
chain's nodes. A coupling is a torsional spring (and inertia, half on each
side, on θx) whose other five DOFs are a rigid link: the two nodes share
ux, uy, uz, θy, θz (eliminated exactly, not by a penalty). A rigid inertia acts
on θx only (its mass and tilting inertia are not in the model file).
Bearings are isotropic lateral springs (uy, uz) at named stations.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .assembly import assemble
from .components import Coupling, Drivetrain, Rigid, Shaft
from .eigen import lowest_modes
from .errors import ModelError
from .partmodel import part_model, smooth_trial_shapes
from .twist import node_positions

__all__ = ["FullModel", "FullModes", "assemble_full", "full_modes", "FAMILIES"]

#: DOF families of a node, by local index.
FAMILIES = {"axial": (0,), "lateral": (1, 2, 4, 5), "torsion": (3,)}


@dataclass(frozen=True)
class FullModel:
    """K and M of the 6-DOF chain in reduced coordinates (coupling links eliminated), SI.

    ``T`` maps reduced DOFs to the 6 DOFs of every node (``u_full = T @ u``);
    ``x`` the node positions (m); ``stations`` (name, node) as in the torsion
    chain; ``bearings`` node → N/m.
    """

    drivetrain: Drivetrain
    K: sp.csr_matrix
    M: sp.csr_matrix
    T: sp.csr_matrix
    x: np.ndarray
    stations: tuple
    bearings: Mapping[int, float]

    @property
    def n_nodes(self) -> int:
        """Nodes of the chain."""
        return self.x.size

    @property
    def representatives(self) -> np.ndarray:
        """For each reduced coordinate, the full DOF (6·node + k) it stands for."""
        return np.asarray(self.T.argmax(axis=0)).ravel()


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


def assemble_full(drivetrain: Drivetrain, bearings: Mapping[str, float] | None = None) -> FullModel:
    """Assemble the chain with 6 DOFs per node.

    Parameters
    ----------
    drivetrain : Drivetrain
        Every shaft made from sections.
    bearings : mapping of station name to lateral stiffness (N/m), optional
    """
    for comp in drivetrain.components:
        if isinstance(comp, Shaft) and comp.reduce is not None:
            raise ModelError(
                "a flexible body (reduce) is assembled in torsion models only so far",
                component=repr(comp.name),
                field="reduce",
                valid='[model] dofs = "torsion", or take the 6-DOF part out with `flexshaft reduce`',
            )
    tors = assemble(drivetrain, reduce=False)
    n_nodes = tors.n_dof
    nd = 6 * n_nodes
    blocks_k, blocks_m = [], []
    diag_rows, diag_k, diag_m = [], [], []
    link = np.arange(nd)  # full DOF -> representative full DOF (coupling links)
    for ci, comp in enumerate(drivetrain.components):
        s = int(tors.start_node[ci])
        if isinstance(comp, Shaft):
            if comp.sections is None:
                raise ModelError(
                    "has no cross-sections, so no bending stiffness or mass",
                    component=repr(comp.name),
                    field="type",
                    value="shaft",
                    has_value=True,
                    valid='dofs = "full" needs every shaft as a cad part or given by segments',
                )
            pm = part_model(
                comp.sections,
                comp.material,
                dofs="full",
                max_element_length=comp.mesh_cap,
                mass="lumped" if drivetrain.inertia_model == "lumped" else "consistent",
            )
            off = 6 * s
            blocks_k.append(_shifted(pm.K, off, nd))
            blocks_m.append(_shifted(pm.M, off, nd))
        elif isinstance(comp, Coupling):
            a, b = 6 * s + 3, 6 * (s + 1) + 3
            blocks_k.append(
                sp.csr_matrix(
                    (
                        [comp.stiffness, -comp.stiffness, -comp.stiffness, comp.stiffness],
                        ([a, a, b, b], [a, b, a, b]),
                    ),
                    shape=(nd, nd),
                )
            )
            diag_rows += [a, b]
            diag_k += [0.0, 0.0]
            diag_m += [comp.inertia / 2, comp.inertia / 2]
            for k in (0, 1, 2, 4, 5):
                link[6 * (s + 1) + k] = link[6 * s + k]
        elif isinstance(comp, Rigid):
            diag_rows.append(6 * s + 3)
            diag_k.append(0.0)
            diag_m.append(comp.inertia)
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
        diag_rows += [6 * node + 1, 6 * node + 2]
        diag_k += [k, k]
        diag_m += [0.0, 0.0]
    K = sum(blocks_k, sp.csr_matrix((nd, nd))) + sp.csr_matrix(
        (diag_k, (diag_rows, diag_rows)), shape=(nd, nd)
    )
    M = sum(blocks_m, sp.csr_matrix((nd, nd))) + sp.csr_matrix(
        (diag_m, (diag_rows, diag_rows)), shape=(nd, nd)
    )
    # Reduced coordinates: one per representative DOF, in order (keeps the band narrow).
    reps, col = np.unique(link, return_inverse=True)
    T = sp.csr_matrix((np.ones(nd), (np.arange(nd), col)), shape=(nd, reps.size))
    Kr = (T.T @ K @ T).tocsr()
    Mr = (T.T @ M @ T).tocsr()
    if np.any(Mr.diagonal() <= 0):
        raise ModelError(
            "a node carries no mass in some DOF",
            field="inertia",
            valid="shafts from sections on both sides of every rigid inertia and coupling",
        )
    return FullModel(
        drivetrain=drivetrain,
        K=Kr,
        M=Mr,
        T=T,
        x=node_positions(tors),
        stations=tuple((st.name, st.node) for st in tors.stations),
        bearings=nodes,
    )


def _shifted(A: sp.spmatrix, off: int, n: int) -> sp.csr_matrix:
    c = A.tocoo()
    return sp.csr_matrix((c.data, (c.row + off, c.col + off)), shape=(n, n))


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
    """Exact rigid motions of the chain in reduced coordinates, given its bearings."""
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
    # Reduced coordinates are a subset of the full ones (representatives): read them off.
    return full[fm.representatives]


def full_modes(fm: FullModel, count: int = 12) -> FullModes:
    """The ``count`` lowest modes of a 6-DOF chain (rigid-body modes included)."""
    reps = fm.representatives
    trial = smooth_trial_shapes(fm.x, 6)
    sol = lowest_modes(fm.K, fm.M, count, rigid_basis=_rigid_basis(fm), trial=trial[reps])
    shapes = fm.T @ sol.vectors
    Mfull_diag_energy = {}
    Mr_v = fm.M @ sol.vectors
    # Kinetic energy per reduced DOF: v_i (M v)_i, summed by family of the DOF it stands for.
    per_dof = sol.vectors * Mr_v
    local = reps % 6
    for fam, ks in FAMILIES.items():
        Mfull_diag_energy[fam] = per_dof[np.isin(local, ks)].sum(axis=0)
    f = np.sqrt(np.clip(sol.eigenvalues, 0.0, None)) / (2 * np.pi)
    return FullModes(
        frequencies_hz=f, shapes=shapes, rigid=sol.rigid, energy=Mfull_diag_energy, method=sol.method
    )
