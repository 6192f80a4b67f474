"""The solid twist test: a solid part's stiffness at one end with the other clamped.

The part's solid mesh (10-node tetrahedra, :mod:`flexshaft.elements.tet10`) has its end faces tied
rigidly to master nodes (:mod:`flexshaft.parts.solid`); the ``clamp`` end is held, and the six unit
loads at the ``load`` end's master - forces along x, y, z and moments about them - are solved at once
(one factorisation or multigrid hierarchy, :class:`~flexshaft.linalg.spd.SpdSolver`). Their
displacements are the end's 6 x 6 compliance C; its inverse is the end's stiffness matrix, the part
as its neighbours feel it. The test bench's numbers are one load at a time: the torsional stiffness
T/θ_x = 1/C[θx, θx], the axial F_x/u_x = 1/C[ux, ux], the bending (a tip force over its deflection)
1/C[uy, uy] and 1/C[uz, uz]. A conforming finite-element model is stiffer than the solid it meshes
and converges to it from above; a circular tube twisted by rigid end faces is Saint-Venant's exact
solution (sections turn rigidly, no warping), so its stiffness tends to G·J/L.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements.materials import Material
from ..elements.tet10 import solid_matrices
from ..elements.tetmesh import TET10_EDGES, TetMesh
from ..errors import ModelError
from ..linalg.multigrid import linear_coarse_space
from ..linalg.spd import SolveReport, SpdSolver, rigid_body_modes
from ..parts.solid import INTERFACES, averaging_interface, constrain, determinate_support, rigid_interface
from ..reduction.solid import result_settings
from ..system.threads import follows_policy

__all__ = ["SolidStiffness", "solid_stiffness", "stiffness_result", "END_DOFS", "INTERFACES"]

#: The master node's DOFs, in the order of the stiffness matrix's rows and columns.
END_DOFS = ("ux", "uy", "uz", "θx", "θy", "θz")


@dataclass(frozen=True)
class SolidStiffness:
    """A solid part's end stiffness (:func:`solid_stiffness`), SI.

    Attributes
    ----------
    part : str
    clamp, load : str
        The clamped and the loaded end's face sets.
    compliance : ndarray (6, 6)
        The loaded master's displacements (m, rad) per unit load (N, N·m), in :data:`END_DOFS` order.
    stiffness : ndarray (6, 6)
        Its inverse: the end's stiffness matrix (N/m, N, N·m/rad).
    torsion : float
        T/θx with the torque alone, N·m/rad.
    axial : float
        F/u_x with the axial force alone, N/m.
    bending : (float, float)
        F/u with a tip force alone along y and along z, N/m.
    interface : str
        How the end faces are tied.
    dofs : int
        Unknowns of the constrained system.
    solver : SolveReport
    mesh_size : float
        The mesh's global element size, m.
    """

    part: str
    clamp: str
    load: str
    compliance: np.ndarray
    stiffness: np.ndarray
    torsion: float
    axial: float
    bending: tuple
    interface: str
    dofs: int
    solver: SolveReport
    mesh_size: float

    def to_dict(self) -> dict:
        """A JSON-ready document (units stated)."""
        return {
            "part": self.part,
            "clamp": self.clamp,
            "load": self.load,
            "units": {"torsion": "N·m/rad", "axial": "N/m", "bending": "N/m", "stiffness": "SI by DOF"},
            "torsion": self.torsion,
            "axial": self.axial,
            "bending": list(self.bending),
            "end_dofs": list(END_DOFS),
            "stiffness": self.stiffness.tolist(),
            "interface": self.interface,
            "dofs": self.dofs,
            "solver": self.solver.method,
            "iterations": self.solver.iterations,
            "mesh_size_m": self.mesh_size,
        }


def _dofs(nodes: np.ndarray) -> np.ndarray:
    return (3 * nodes[:, None] + np.arange(3)).ravel()


def _averaged(mesh: TetMesh, K, clamp: str, load: str, method: str):
    """The loaded master's compliance with both ends tied by averaging, the ``clamp`` master held.

    The body is free (K singular, its null space the rigid motions B, exactly): the clamp's six
    conditions C·u = 0 (C = its W) take the reactions λ = (CB)⁻ᵀBᵀf that leave g = f − Cᵀλ in
    equilibrium; K·u = g is then solved on a statically determinate support (whose reactions are zero
    for an equilibrated load) and the rigid motion that meets C·u = 0 added: the exact constrained
    solution.
    """
    n = mesh.n_nodes
    B = rigid_body_modes(mesh.nodes)
    held, loaded = averaging_interface(mesh, clamp), averaging_interface(mesh, load)
    C = np.zeros((6, 3 * n))
    C[:, _dofs(held.nodes)] = held.W
    f = np.zeros((3 * n, 6))
    f[_dofs(loaded.nodes)] = loaded.W.T
    CB = C @ B
    g = f - C.T @ np.linalg.solve(CB.T, B.T @ f)
    free = np.ones(3 * n, dtype=bool)
    free[determinate_support(mesh.nodes)] = False
    Kf = K.tocsr()[free][:, free]
    coarse = linear_coarse_space(mesh.tets, sp.identity(3 * n, format="csr")[:, free], edges=TET10_EDGES)
    what = f"{mesh.name}'s solid stiffness"
    solver = SpdSolver(Kf, near_null=B[free], method=method, what=what, coarse=coarse)
    u = np.zeros((3 * n, 6))
    u[free] = solver.solve(g[free])
    u -= B @ np.linalg.solve(CB, C @ u)
    return loaded.W @ u[_dofs(loaded.nodes)], solver, int(Kf.shape[0])


@follows_policy
def solid_stiffness(
    mesh: TetMesh,
    material: Material,
    *,
    clamp: str = "start",
    load: str = "end",
    interface: str = "rigid",
    method: str = "auto",
    cache=None,
) -> SolidStiffness:
    """The end stiffness of a solid part, its other end clamped (module docstring).

    Parameters
    ----------
    mesh : TetMesh
        The part's solid mesh with the face sets ``clamp`` and ``load``.
    material : Material
    clamp, load : str
        The face sets held and loaded (``"start"`` and ``"end"`` by default).
    interface : {"rigid", "average"}
        How both end faces are tied to their master nodes (:data:`INTERFACES`).
    method : {"auto", "direct", "amg"}
        The linear solver (:class:`~flexshaft.linalg.spd.SpdSolver`).
    cache : optional
        Where solid results are kept between runs (:class:`flexshaft.input.solidcache.SolidResults`),
        keyed by the mesh, the material, the ends, the interface and the solver's settings; None:
        always solved.

    Returns
    -------
    SolidStiffness
    """
    if clamp == load:
        raise ModelError("is the loaded end too", field="clamp", value=clamp, valid="the other end")
    if interface not in INTERFACES:
        raise ModelError("unknown interface", field="interface", value=interface, valid="rigid or average")
    settings = result_settings(
        "solid stiffness", material, clamp=clamp, load=load, interface=interface, method=method
    )
    if cache is not None:
        kept = cache.load(mesh, settings)
        if kept is not None:
            return kept
    K = solid_matrices(mesh, material, mass=False).K  # statics: no mass
    if interface == "average":
        C, solver, dofs = _averaged(mesh, K, clamp, load, method)
    else:
        ends = [rigid_interface(mesh, clamp), rigid_interface(mesh, load)]
        system = constrain(K, mesh, ends, clamped=(clamp,))
        master = system.masters[load]
        loads = np.zeros((system.K.shape[0], 6))
        loads[master, np.arange(6)] = 1.0
        what = f"{mesh.name}'s solid stiffness"
        coarse = linear_coarse_space(
            mesh.tets, system.T, edges=TET10_EDGES
        )  # the linear elements: multigrid's first level
        solver = SpdSolver(system.K, near_null=system.near_null, method=method, what=what, coarse=coarse)
        C, dofs = solver.solve(loads)[master], int(system.K.shape[0])
    C = 0.5 * (C + C.T)  # symmetric by Maxwell-Betti; the solves' residuals leave ~rtol·cond of asymmetry
    result = stiffness_result(
        mesh, C, clamp=clamp, load=load, interface=interface, dofs=dofs, solver=solver.report
    )
    if cache is not None:
        cache.store(mesh, settings, result)
    return result


def stiffness_result(
    mesh: TetMesh, compliance: np.ndarray, *, clamp: str, load: str, interface: str, dofs: int, solver
) -> SolidStiffness:
    """The :class:`SolidStiffness` of ``mesh`` from its loaded end's 6 x 6 ``compliance`` (m, rad per N,
    N·m): its inverse and the one-load stiffnesses."""
    C = compliance
    return SolidStiffness(
        part=mesh.name,
        clamp=clamp,
        load=load,
        compliance=C,
        stiffness=np.linalg.inv(C),
        torsion=float(1.0 / C[3, 3]),
        axial=float(1.0 / C[0, 0]),
        bending=(float(1.0 / C[1, 1]), float(1.0 / C[2, 2])),
        interface=INTERFACES[interface],
        dofs=int(dofs),
        solver=solver,
        mesh_size=float(mesh.size),
    )
