"""A meshed solid as a part model: K and M of its 10-node tetrahedra, its two master nodes and the ties.

A 1D part is a :class:`~flexshaft.parts.model.PartModel` (K, M on its nodes; the first and the last
its interface). A solid part is a :class:`SolidPartModel` with the same protocol - ``name``,
``dofs``, ``n_dofs``, ``rigid_body_modes()``, ``K`` and ``M`` (here assembled on demand by
:meth:`SolidPartModel.matrices`: a million-DOF solid's are gigabytes, kept only while a solve needs
them) - whose interface is its two end faces, each tied to a master node at its centroid, rigidly
(RBE2) or by averaging (RBE3) (:mod:`flexshaft.parts.solidties`). :meth:`SolidPartModel.tie` is the
one constraint step for both kinds: the rigid faces' nodes follow their masters (u = T·q), an
averaging face's master is the rows C·q of the unknowns, held or loaded through
:class:`~flexshaft.parts.solidties.HeldMasters`.

The solves a part model answers are building blocks of the analyses' one front end each:
:func:`end_compliance` (the twist test's end stiffness, :func:`flexshaft.analysis.twist.part_stiffness`)
and :func:`free_modes` (:func:`flexshaft.analysis.modal.part_modes`); the Craig-Bampton reduction is
:func:`flexshaft.reduction.craig_bampton.craig_bampton`'s. The linear solver is chosen by size
(``solver="auto"``: a sparse LU up to :data:`~flexshaft.linalg.spd.DIRECT_MAX` unknowns, conjugate
gradients preconditioned by multigrid beyond; ``"direct"`` or ``"amg"`` to force one), as scikit-fem's
``solve(..., solver=)`` is handed its strategy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements.materials import Material
from ..elements.tet10 import SolidMatrices, solid_matrices
from ..elements.tetmesh import TET10_EDGES, TetMesh
from ..errors import ModelError
from ..linalg.eigen import EigenSolution, lowest_modes
from ..linalg.multigrid import linear_coarse_space
from ..linalg.spd import SolveReport, SpdSolver, rigid_body_modes
from .solidties import (
    ENDS,
    INTERFACES,
    ConstrainedSystem,
    HeldMasters,
    averaging_interface,
    constrain,
    determinate_support,
    interface_kinds,
    interface_statement,
    master_rows,
    rigid_interface,
)

__all__ = [
    "SOLVERS",
    "EndCompliance",
    "SolidPartModel",
    "TiedSolid",
    "end_compliance",
    "free_modes",
    "solid_part_model",
]

#: The linear-solver strategies a solid part's solves take (:class:`~flexshaft.linalg.spd.SpdSolver`):
#: by size, a sparse LU, or conjugate gradients with multigrid.
SOLVERS = ("auto", "direct", "amg")
#: The rigid-body motions of a free solid.
RIGID = 6


@dataclass(frozen=True)
class SolidPartModel:
    """A solid part: its mesh, material and how its end faces are tied (module docstring).

    Attributes
    ----------
    mesh : TetMesh
        10-node tetrahedra (m) with the face sets ``"start"`` and ``"end"``.
    material : Material
    dofs : {"full", "torsion"}
        The interface of a reduction: each master's six DOFs, or θ_x alone.
    interface : (str, str)
        The start's and the end's tie, ``"rigid"`` or ``"average"``
        (:data:`~flexshaft.parts.solidties.INTERFACES`).
    """

    mesh: TetMesh
    material: Material
    dofs: str = "full"
    interface: tuple = ("rigid", "rigid")

    @property
    def name(self) -> str:
        """The part's name (its mesh's)."""
        return self.mesh.name

    @property
    def n_dofs(self) -> int:
        """u_x, u_y, u_z of every mesh node."""
        return 3 * self.mesh.n_nodes

    @property
    def statement(self) -> str:
        """How the end faces are tied, as results state it (``"end faces rigid (RBE2)"``)."""
        return interface_statement(self.interface)

    def matrices(self, *, mass: bool = True) -> SolidMatrices:
        """K (N/m) and, with ``mass``, M (kg) on the mesh's node-major DOFs, assembled now, not kept."""
        return solid_matrices(self.mesh, self.material, mass=mass)

    @property
    def K(self) -> sp.csr_matrix:
        """The stiffness (assembled on each access: :meth:`matrices` for K and M at once)."""
        return self.matrices(mass=False).K

    @property
    def M(self) -> sp.csr_matrix:
        """The consistent mass (assembled on each access)."""
        return self.matrices().M

    @property
    def masters(self) -> np.ndarray:
        """The master nodes, the start face's and the end face's area centroids (2, 3), m: the part's
        interface, as a 1D part's is its end nodes."""
        return np.array([rigid_interface(self.mesh, end).master for end in ENDS])

    def rigid_body_modes(self) -> np.ndarray:
        """The six rigid-body motions of the free solid (3n, 6): translations (m), then rotations (rad)."""
        return rigid_body_modes(self.mesh.nodes)

    def face(self, end: str):
        """The end face ``end`` (``"start"``, ``"end"``) tied as the part says."""
        kind = self.kind(end)
        return rigid_interface(self.mesh, end) if kind == "rigid" else averaging_interface(self.mesh, end)

    def kind(self, end: str) -> str:
        """How the end face ``end`` is tied."""
        if end not in ENDS:
            raise ModelError("is not an end face", field="interface", value=end, valid="start or end")
        return self.interface[ENDS.index(end)]

    def tie(self, K, M=None, *, clamped=()) -> TiedSolid:
        """The one constraint step: both end faces tied as the part says, ``clamped`` ones' rigid
        masters held at zero (an averaging master is held by :class:`HeldMasters` instead)."""
        faces = [self.face(end) for end in ENDS]
        rigid = [f for f, k in zip(faces, self.interface, strict=True) if k == "rigid"]
        system = constrain(K, self.mesh, rigid, clamped=clamped)
        Mc = None if M is None else (system.T.T @ M @ system.T).tocsr()
        loaded = [(f, k) for f, k in zip(faces, self.interface, strict=True) if f.name not in clamped]
        C = master_rows(self.mesh, system, [f for f, _ in loaded], [k for _, k in loaded])
        return TiedSolid(self.mesh, system, Mc, tuple(faces), C)


@dataclass(frozen=True)
class TiedSolid:
    """A solid part's matrices with its end faces tied (:meth:`SolidPartModel.tie`).

    Attributes
    ----------
    mesh : TetMesh
    system : ConstrainedSystem
        Tᵀ K T on the unknowns q (the free nodes' u first, then the rigid faces' masters), the
        recovery u = T·q, the near-null space.
    M : scipy.sparse.csr_matrix or None
        Tᵀ M T.
    faces : tuple
        The start's and the end's face (RigidInterface or AveragingInterface).
    C : scipy.sparse.csr_matrix (6k, m)
        The k loaded masters' DOFs as rows over q (:func:`~flexshaft.parts.solidties.master_rows`).
    """

    mesh: TetMesh
    system: ConstrainedSystem
    M: sp.csr_matrix | None
    faces: tuple
    C: sp.csr_matrix

    @property
    def K(self) -> sp.csr_matrix:
        return self.system.K

    @property
    def T(self) -> sp.csr_matrix:
        return self.system.T

    def inner(self) -> np.ndarray:
        """The free nodes (q's first unknowns are their u_x, u_y, u_z), x from the mesh's start, m."""
        nodes = self.mesh.nodes
        return nodes[self.system.free_nodes] - [nodes[:, 0].min(), 0.0, 0.0]

    def held(self, rows, solver: str, what: str) -> HeldMasters:
        """Solves with the master rows ``rows`` (k, m; of :attr:`C`) held - the one RBE3 formulation
        (:class:`~flexshaft.parts.solidties.HeldMasters`): the free part on a statically determinate
        support among the free nodes, solved by ``solver``'s strategy, the rows by multipliers."""
        system = self.system
        keep = np.setdiff1d(np.arange(system.K.shape[0]), determinate_support(self.inner()))
        # the mesh's linear elements as the multigrid's first coarse level (half the iterations)
        coarse = linear_coarse_space(self.mesh.tets, system.T, keep, edges=TET10_EDGES)
        spd = SpdSolver(
            system.K[keep][:, keep], near_null=system.near_null[keep], method=solver, what=what, coarse=coarse
        )
        return HeldMasters(system.K, rows, system.near_null, keep, spd)


def solid_part_model(
    mesh: TetMesh, material: Material, *, dofs: str = "full", interface="rigid"
) -> SolidPartModel:
    """The part model of a meshed solid, checked.

    Parameters
    ----------
    mesh : TetMesh
        With the face sets ``"start"`` and ``"end"``.
    material : Material
    dofs : {"full", "torsion"}
        A reduction's interface DOFs per master.
    interface : {"rigid", "average"}, (start, end) or {"start": ..., "end": ...}
        How the end faces are tied (:func:`~flexshaft.parts.solidties.interface_kinds`).
    """
    if not isinstance(mesh, TetMesh):
        raise ModelError("not a solid mesh", field="mesh", value=type(mesh).__name__, valid="a TetMesh")
    if not isinstance(material, Material):
        raise ModelError(
            "not a material", field="material", value=type(material).__name__, valid="a Material"
        )
    if dofs not in ("full", "torsion"):
        raise ModelError("unknown DOFs", field="dofs", value=dofs, valid="full or torsion")
    if isinstance(interface, str) and interface not in INTERFACES:
        raise ModelError("unknown interface", field="interface", value=interface, valid="rigid or average")
    return SolidPartModel(mesh, material, dofs, interface_kinds(interface))


@dataclass(frozen=True)
class EndCompliance:
    """The loaded master's compliance with the other end held (:func:`end_compliance`).

    Attributes
    ----------
    compliance : ndarray (6, 6)
        Displacements (m, rad) per unit load (N, N·m), u_x … θ_z, symmetric.
    unknowns : int
        Unknowns of the system solved.
    solver : SolveReport
    """

    compliance: np.ndarray
    unknowns: int
    solver: SolveReport


def end_compliance(part: SolidPartModel, *, clamp: str = "start", load: str = "end", solver: str = "auto"):
    """The ``load`` master's 6 x 6 compliance with the ``clamp`` master held (module docstring).

    The six unit loads at the loaded master - forces along x, y, z and moments about them, reaching
    an averaging face as Wᵀ - are solved at once (one factorisation or multigrid hierarchy). A rigid
    clamped master leaves the unknowns; an averaging one is held by its rows C·q = 0
    (:class:`~flexshaft.parts.solidties.HeldMasters`, the part free otherwise). The compliance is
    the loaded master's rows of the solution, made symmetric (Maxwell-Betti; the solves' residuals
    leave ~rtol·cond of asymmetry).
    """
    if clamp == load:
        raise ModelError("is the loaded end too", field="clamp", value=clamp, valid="the other end")
    if solver not in SOLVERS:
        raise ModelError("unknown solver", field="solver", value=solver, valid=", ".join(SOLVERS))
    K = part.matrices(mass=False).K  # statics: no mass
    what = f"{part.name}'s solid stiffness"
    if part.kind(clamp) == "rigid":
        # the clamped master leaves the unknowns: C holds the loaded master's rows alone
        tied = part.tie(K, clamped=(clamp,))
        system, rows = tied.system, tied.C
        # the linear elements: multigrid's first level
        coarse = linear_coarse_space(part.mesh.tets, system.T, edges=TET10_EDGES)
        spd = SpdSolver(system.K, near_null=system.near_null, method=solver, what=what, coarse=coarse)
        u, unknowns, report = spd.solve(rows.T.toarray()), int(system.K.shape[0]), spd.report
    else:
        tied = part.tie(K)
        at = {end: slice(6 * j, 6 * j + 6) for j, end in enumerate(ENDS)}
        held = tied.held(tied.C[at[clamp]], solver, what)
        rows = tied.C[at[load]]
        u, unknowns, report = held.solve(rows.T.toarray()), int(held.keep.size), held.solver.report
    C = np.asarray(rows @ u)
    return EndCompliance(0.5 * (C + C.T), unknowns, report)


def free_modes(part: SolidPartModel, count: int, *, solver: str = "auto") -> EigenSolution:
    """The ``count`` lowest elastic free-free modes of the solid and its six rigid ones (first, at 0).

    K and M of the mesh go to the one eigensolver (:func:`~flexshaft.linalg.eigen.lowest_modes`) with
    the six rigid-body motions as its exact null space and, for the shifted solves of its Lanczos
    iteration, as the multigrid's near-null space. The shift comes from the Rayleigh quotients of an
    axial stretch and a bend along the part - shapes of the size of its lowest modes, where the node
    numbering says nothing about the geometry. ``solver`` is the shifted solves' strategy (by size,
    a sparse LU or multigrid CG; or the one named).
    """
    mats = part.matrices()
    nodes = part.mesh.nodes
    B = part.rigid_body_modes()
    x = nodes[:, 0] - nodes[:, 0].mean()
    trial = np.zeros((part.n_dofs, 2))
    trial[0::3, 0] = x  # an axial stretch
    trial[1::3, 1] = x * x  # a bend
    return lowest_modes(
        mats.K,
        mats.M,
        count + RIGID,
        rigid_basis=B,
        method="lanczos",
        trial=trial,
        near_null=B,
        solver=solver,
    )
