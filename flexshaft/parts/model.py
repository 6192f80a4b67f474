"""A part's finite-element model from its section table: sparse K and M on a 1D mesh.

The mesh is the torsion mesh of :func:`flexshaft.parts.beammesh.torsion_mesh`: a
node at every station of the merged section table (every diameter step,
flange face, keyway end), longer intervals cut into equal pieces so that no
element exceeds ``max_element_length``; each element carries its interval's
constant section. With ``dofs="torsion"`` every node has θx alone and the
model is exactly that torsion chain (G·J/L, ρ·Ip·L). With ``dofs="full"``
every node has (ux, uy, uz, θx, θy, θz) and the elements are the 12-DOF
Timoshenko beams of :mod:`flexshaft.elements.timoshenko` (principal axes
along y and z; the table's iyz and centroid offsets yc, zc are not used).

The global DOF of node ``i``, local DOF ``k`` is ``i·d + k`` with ``d`` the
DOFs per node (1 or 6): numbered along the axis, so K and M are banded
(half-bandwidth 2·d − 1). The interface nodes, where a part connects to its
neighbours, are its first and last node.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements import (
    timoshenko_consistent_mass,
    timoshenko_gyroscopic,
    timoshenko_lumped_mass,
    timoshenko_stiffness,
    torsion_consistent_inertia,
    torsion_lumped_inertia,
    torsion_stiffness,
)
from ..elements.materials import Material
from ..errors import ModelError
from ..linalg.sparse import Triplets
from ..sections.table import SectionTable
from ..system.limits import CEILINGS, ceiling, check_ceiling
from ..system.threads import follows_policy
from ..validation import check_choice, check_real
from .beammesh import torsion_mesh

__all__ = ["PartModel", "part_model", "DOF_NAMES", "smooth_trial_shapes", "MAX_FULL_ELEMENTS"]

#: Most elements of one 6-DOF part model by default: the ``full_elements`` ceiling of
#: :mod:`flexshaft.system.limits` (100 000 elements, 600 006 DOFs; FLEXSHAFT_MAX_FULL_ELEMENTS sets another).
MAX_FULL_ELEMENTS = CEILINGS["full_elements"].value

#: The DOFs of a node, in order, for each kind of model.
DOF_NAMES: dict[str, tuple[str, ...]] = {
    "torsion": ("θx",),
    "full": ("ux", "uy", "uz", "θx", "θy", "θz"),
}


@dataclass(frozen=True)
class PartModel:
    """Stiffness and mass of one part on its 1D mesh (SI).

    Attributes
    ----------
    x : ndarray, shape (n_nodes,)
        Node positions along the shaft axis, m, increasing.
    dofs : {"torsion", "full"}
        θx per node, or (ux, uy, uz, θx, θy, θz) per node.
    K : scipy.sparse.csr_matrix, shape (n_dofs, n_dofs)
        Stiffness: N/m, N, N·m/rad by DOF pair. Symmetric positive
        semi-definite; a free part has the rigid-body motions
        (:meth:`rigid_body_modes`) as its null space.
    M : scipy.sparse.csr_matrix, shape (n_dofs, n_dofs)
        Mass: kg, kg·m, kg·m² by DOF pair. Symmetric positive definite.
    mass : {"consistent", "lumped"}
        How the elements' inertia was spread over their nodes.
    name : str
        The part's name (from its section table).
    G : scipy.sparse.csr_matrix or None
        Gyroscopic matrix per rad/s of spin about x (a 6-DOF part; kg·m², skew-symmetric):
        forces −Ω·G·q̇ at spin speed Ω. None for a torsion part.
    """

    x: np.ndarray
    dofs: str
    K: sp.csr_matrix
    M: sp.csr_matrix
    mass: str = "consistent"
    name: str = "part"
    G: sp.csr_matrix | None = None

    def __post_init__(self) -> None:
        x = np.array(self.x, dtype=float)
        x.setflags(write=False)
        object.__setattr__(self, "x", x)

    @property
    def dofs_per_node(self) -> int:
        """1 for a torsion model, 6 for a full one."""
        return len(DOF_NAMES[self.dofs])

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.x.size

    @property
    def n_elements(self) -> int:
        """Number of elements (a chain: nodes − 1)."""
        return self.x.size - 1

    @property
    def n_dofs(self) -> int:
        """Number of DOFs, nodes × DOFs per node."""
        return self.n_nodes * self.dofs_per_node

    @property
    def interface_nodes(self) -> tuple[int, int]:
        """The first and the last node, where the part connects to its neighbours."""
        return (0, self.n_nodes - 1)

    @property
    def interface_dofs(self) -> np.ndarray:
        """Global DOF indices of the interface nodes, first node's then last node's."""
        return np.concatenate([self.node_dofs(n) for n in self.interface_nodes])

    def node_dofs(self, node: int) -> np.ndarray:
        """Global DOF indices of one node, in the order of :data:`DOF_NAMES`.

        Parameters
        ----------
        node : int
            Node number, 0 … n_nodes − 1 (negative counts from the end).
        """
        if (
            isinstance(node, bool)
            or not isinstance(node, int | np.integer)
            or not (-self.n_nodes <= node < self.n_nodes)
        ):
            raise ModelError(
                "no such node",
                component=self.name,
                field="node",
                value=node,
                valid=f"an integer from {-self.n_nodes} to {self.n_nodes - 1}",
                has_value=True,
            )
        d = self.dofs_per_node
        return (int(node) % self.n_nodes) * d + np.arange(d)

    def nodes_dofs(self, nodes) -> np.ndarray:
        """Global DOF indices of several nodes, node-major (see :meth:`node_dofs`)."""
        return np.concatenate([self.node_dofs(int(n)) for n in nodes])

    def rigid_body_modes(self) -> np.ndarray:
        """The exact rigid-body motions of the free part, one per column.

        Returns
        -------
        ndarray, shape (n_dofs, r)
            r = 1 for torsion (a unit spin θx = 1 rad). For a full model r = 6:
            unit translations along x, y, z (m), then unit rotations (rad)
            about x, y and z through the first node; a rotation θy moves the
            nodes by uz = −θy·(x − x₀), a rotation θz by uy = +θz·(x − x₀).
        """
        if self.dofs == "torsion":
            return np.ones((self.n_nodes, 1))
        r = np.zeros((self.n_nodes, 6, 6))
        s = self.x - self.x[0]
        for k in range(3):
            r[:, k, k] = 1.0  # translations
        r[:, 3, 3] = 1.0  # spin about x
        r[:, 4, 4], r[:, 2, 4] = 1.0, -s  # about y: uz = −θy·s
        r[:, 5, 5], r[:, 1, 5] = 1.0, s  # about z: uy = +θz·s
        return r.reshape(self.n_nodes * 6, 6)


def smooth_trial_shapes(x: np.ndarray, dofs_per_node: int) -> np.ndarray:
    """One half sine and one half cosine along the axis per kind of DOF, node-major (n·d, 2d).

    They bound the lowest mode of each DOF family from above within a small
    factor, which is what :func:`flexshaft.linalg.eigen.lowest_modes` needs for its
    Lanczos shift; a ramp over interleaved ux … θz numbering would mix DOF
    kinds and bound λ₁ far too high.
    """
    s = (x - x[0]) / max(float(x[-1] - x[0]), 1e-300)
    d = dofs_per_node
    shapes = np.zeros((x.size * d, 2 * d))
    for k in range(d):
        shapes[k::d, 2 * k] = np.sin(np.pi * s)
        shapes[k::d, 2 * k + 1] = np.cos(np.pi * s)
    return shapes


def _assemble(blocks: np.ndarray, n_nodes: int, d: int) -> sp.csr_matrix:
    """Sum the element blocks (n_el, 2d, 2d) of a chain of elements into a sparse matrix."""
    n_el, nb = blocks.shape[0], blocks.shape[1]
    tr = Triplets()
    tr.add_elements((np.arange(n_el) * d)[:, None] + np.arange(nb)[None, :], blocks)
    return tr.build(n_nodes * d)


@follows_policy
def part_model(
    table: SectionTable,
    material: Material,
    *,
    dofs: str = "full",
    max_element_length: float | None = None,
    mass: str = "consistent",
    nodes_at=(),
    subdivide: int = 1,
) -> PartModel:
    """The finite-element model of a part from its section table.

    Parameters
    ----------
    table : SectionTable
        The part's sections, m and m² / m⁴ (neighbouring equal intervals are
        joined first).
    material : Material
        E, G (Pa) and ρ (kg/m³).
    dofs : {"full", "torsion"}
        Six DOFs per node with Timoshenko beam elements, or θx alone with
        torsion elements.
    max_element_length : float, optional
        Longest element, m; ``None`` keeps one element per table interval.
        (A Timoshenko element is exact in statics at any length; for modes,
        choose it below a tenth of the shortest wavelength of interest.)
    mass : {"consistent", "lumped"}
        Consistent mass (from the elements' shape functions, with rotary
        inertia) or half of each element's mass and inertias on each of its
        nodes.
    nodes_at : sequence of float
        Extra positions (m, inside the part) that must be nodes.
    subdivide : int
        Cut every element into this many equal pieces (a nested refinement, see
        :func:`flexshaft.parts.beammesh.torsion_mesh`).

    Returns
    -------
    PartModel
    """
    if not isinstance(table, SectionTable):
        raise ModelError(
            "not a section table", field="table", value=type(table).__name__, valid="a SectionTable"
        )
    if not isinstance(material, Material):
        raise ModelError(
            "not a material", field="material", value=type(material).__name__, valid="a Material"
        )
    dofs = check_choice(dofs, "dofs", tuple(DOF_NAMES))
    mass = check_choice(mass, "mass", ("consistent", "lumped"))
    if max_element_length is not None:
        max_element_length = check_real(max_element_length, "max_element_length", "m", lo=0.0, lo_open=True)

    mesh = torsion_mesh(
        table, material, max_element_length=max_element_length, nodes_at=nodes_at, subdivide=subdivide
    )
    n_nodes = mesh.x.size
    if dofs == "torsion":
        # Exactly the torsion chain: G·J/L and ρ·Ip·L per element.
        k_el = torsion_stiffness(mesh.stiffness)
        m_el = (torsion_consistent_inertia if mass == "consistent" else torsion_lumped_inertia)(mesh.inertia)
        return PartModel(
            x=mesh.x,
            dofs=dofs,
            K=_assemble(k_el, n_nodes, 1),
            M=_assemble(m_el, n_nodes, 1),
            mass=mass,
            name=table.name,
        )

    return _full_part(table, material, mesh, mass, max_element_length)


def _full_part(table: SectionTable, material: Material, mesh, mass: str, max_element_length) -> PartModel:
    """:func:`part_model` with six DOFs a node: Timoshenko beams on ``mesh``, the arguments checked."""
    n_nodes = mesh.x.size
    limit = ceiling("full_elements")
    if mesh.n_elements > limit:
        # 12 × 12 entries per element in the assembly: refuse before allocating them.
        check_ceiling(
            "full_elements",
            mesh.n_elements,
            component=table.name,
            field="max_element_length",
            value=max_element_length,
            unit="m",
            detail=f"would make a 6-DOF part model of {mesh.n_elements} elements ({6 * n_nodes} DOFs)",
            hint=f"max_element_length >= {table.length / limit:.3g} m for this part's length",
        )
    t = table.merged()
    for name in ("iy", "iz"):
        # The table only asks these to be finite; bending needs them positive.
        col = getattr(t, name)
        if np.any(col <= 0.0):
            raise ModelError(
                "must be positive for bending (dofs = 'full')",
                component=table.name,
                field=name,
                value=float(col[col <= 0.0][0]),
                unit="m⁴",
                valid="> 0",
            )
    L = np.diff(mesh.x)
    # Each element lies inside one table interval: find it from the element's midpoint.
    idx = np.searchsorted(t.x, 0.5 * (mesh.x[:-1] + mesh.x[1:])) - 1
    E, G, rho = material.E, material.G, material.rho
    A, Iy, Iz = t.area[idx], t.iy[idx], t.iz[idx]
    Ip, J = t.ip[idx], t.j[idx]
    Asy, Asz = t.shear_area_y[idx], t.shear_area_z[idx]
    k_el = timoshenko_stiffness(L=L, E=E, G=G, A=A, Iy=Iy, Iz=Iz, J=J, Asy=Asy, Asz=Asz)
    if mass == "consistent":
        m_el = timoshenko_consistent_mass(L=L, E=E, G=G, rho=rho, A=A, Iy=Iy, Iz=Iz, Ip=Ip, Asy=Asy, Asz=Asz)
        g_el = timoshenko_gyroscopic(L=L, E=E, G=G, rho=rho, Iy=Iy, Iz=Iz, Ip=Ip, Asy=Asy, Asz=Asz)
    else:
        m_el = timoshenko_lumped_mass(L=L, rho=rho, A=A, Iy=Iy, Iz=Iz, Ip=Ip)
        # Lumped: half the element's spinning inertia ρ·Ip·L at each node, on its own (θy, θz).
        g_el = np.zeros(L.shape + (12, 12))
        half = 0.5 * rho * Ip * L
        for a, b in ((4, 5), (10, 11)):
            g_el[:, b, a], g_el[:, a, b] = half, -half
    return PartModel(
        x=mesh.x,
        dofs="full",
        K=_assemble(k_el, n_nodes, 6),
        M=_assemble(m_el, n_nodes, 6),
        mass=mass,
        name=table.name,
        G=_assemble(g_el, n_nodes, 6),
    )
