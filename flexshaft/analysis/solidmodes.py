"""Free-free modes of a solid part: its natural frequencies and shapes from the 10-node tetrahedra.

K and M of the part's solid mesh (:mod:`flexshaft.elements.tet10`) go to the one eigensolver
(:func:`~flexshaft.linalg.eigen.lowest_modes`) with the six rigid-body motions as its exact null space
(reported at 0 Hz) and, for the shifted solves of its Lanczos iteration, as the multigrid's near-null
space. The shift comes from the Rayleigh quotients of an axial stretch and a bend along the part -
shapes of the size of its lowest modes, where the node numbering says nothing about the geometry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elements.materials import Material
from ..elements.tet10 import solid_matrices
from ..elements.tetmesh import TetMesh
from ..linalg.eigen import lowest_modes
from ..linalg.spd import rigid_body_modes
from ..reduction.solid import result_settings
from ..system.threads import follows_policy
from ..validation import check_int

__all__ = ["SolidModes", "solid_modes", "tangential_share"]

#: The rigid-body motions of a free solid.
RIGID = 6


@dataclass(frozen=True)
class SolidModes:
    """A solid part's lowest free-free modes (:func:`solid_modes`).

    Attributes
    ----------
    part : str
    frequencies_hz : ndarray (m,)
        Ascending, Hz; the six rigid-body modes first, at 0.
    shapes : ndarray (3n, m)
        Mass-normalised (ΦᵀMΦ = I), node-major u_x, u_y, u_z.
    rigid : ndarray of bool (m,)
    method : str
        The eigensolver's path and its linear solver.
    """

    part: str
    frequencies_hz: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    method: str


def tangential_share(nodes: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """Each shape's share of Σ|u|² in the direction about the x axis (−z·u_y + y·u_z)/r."""
    u = shapes.reshape(nodes.shape[0], 3, -1)
    r = np.hypot(nodes[:, 1], nodes[:, 2])
    on = r > 1e-12 * max(float(r.max()), 1e-300)
    t = (-nodes[on, 2, None] * u[on, 1] + nodes[on, 1, None] * u[on, 2]) / r[on, None]
    return np.sum(t * t, axis=0) / np.sum(u * u, axis=(0, 1))


@follows_policy
def solid_modes(mesh: TetMesh, material: Material, *, count: int = 10, cache=None) -> SolidModes:
    """The ``count`` lowest elastic free-free modes of a solid part (and its six rigid ones).

    Parameters
    ----------
    mesh : TetMesh
    material : Material
    count : int
        Elastic modes wanted.
    cache : optional
        Where solid results are kept between runs (:class:`flexshaft.input.solidcache.SolidResults`),
        keyed by the mesh, the material, the count and the solver's settings; None: always solved.

    Returns
    -------
    SolidModes
    """
    count = check_int(count, "count", lo=1, hi=1000)
    settings = result_settings("solid modes", material, count=count)
    if cache is not None:
        kept = cache.load(mesh, settings)
        if kept is not None:
            return kept
    mats = solid_matrices(mesh, material)
    nodes = mesh.nodes
    B = rigid_body_modes(nodes)
    x = nodes[:, 0] - nodes[:, 0].mean()
    trial = np.zeros((3 * mesh.n_nodes, 2))
    trial[0::3, 0] = x  # an axial stretch
    trial[1::3, 1] = x * x  # a bend
    solution = lowest_modes(
        mats.K, mats.M, count + RIGID, rigid_basis=B, method="lanczos", trial=trial, near_null=B
    )
    f = np.sqrt(np.maximum(solution.eigenvalues, 0.0)) / (2 * np.pi)
    result = SolidModes(mesh.name, f, solution.vectors, solution.rigid, solution.method)
    if cache is not None:
        cache.store(mesh, settings, result)
    return result
