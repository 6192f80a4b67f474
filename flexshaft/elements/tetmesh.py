"""A part's solid mesh: the seam between geometry's tetrahedral mesher and the solid finite elements.

:mod:`geometry` meshes a part's solid into a :class:`TetMesh` (second-order tetrahedra whose mid-side
nodes lie on the curved geometry); everything downstream - the 10-node tetrahedron's matrices, the
interfaces tied to master nodes, the twist test of a solid part, the Craig-Bampton body - reads only this.

Conventions (SI, the part's own frame as the section table's: the shaft axis is x, the part starts
at x = 0):

- ``nodes``: (n, 3) coordinates, m.
- ``tets``: (m, 10) node indices of each 10-node tetrahedron in VTK's ``QUADRATIC_TETRA`` order: the
  corners 0-3, then the mid-side nodes of the edges 0-1, 1-2, 0-2, 0-3, 1-3, 2-3. The corners are
  positively oriented: (x1 − x0) · ((x2 − x0) × (x3 − x0)) > 0.
- ``faces``: named boundary face sets, each (k, 6) node indices of 6-node triangles in VTK's
  ``QUADRATIC_TRIANGLE`` order: corners 0-2, then the edges 0-1, 1-2, 2-0; ``"start"`` and
  ``"end"`` are the faces at the part's axial ends, where it is joined to its neighbours.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError

__all__ = ["TetMesh", "TET10_EDGES", "TRI6_EDGES"]

#: The corner pairs whose mid-side nodes are a 10-node tetrahedron's nodes 4-9 (VTK order).
TET10_EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))
#: The corner pairs whose mid-side nodes are a 6-node triangle's nodes 3-5 (VTK order).
TRI6_EDGES = ((0, 1), (1, 2), (2, 0))


def _array(value, field_name: str, dtype, ncols: int) -> np.ndarray:
    try:
        a = np.array(value, dtype=dtype)
    except (TypeError, ValueError, OverflowError):
        raise ModelError(
            "is not an array of numbers", field=field_name, valid=f"an (n, {ncols}) array", has_value=False
        ) from None
    if a.ndim != 2 or a.shape[1] != ncols or a.shape[0] == 0:
        raise ModelError(
            f"has the shape {a.shape}",
            field=field_name,
            valid=f"an (n, {ncols}) array, n >= 1",
            has_value=False,
        )
    a.setflags(write=False)
    return a


def _indices(value, field_name: str, ncols: int, n: int) -> np.ndarray:
    """An (m, ncols) array of node indices, each of the n nodes'."""
    a = _array(value, field_name, np.int64, ncols)
    if a.min() < 0 or a.max() >= n:
        raise ModelError(
            "refers to a node that does not exist",
            field=field_name,
            valid=f"node indices 0 … {n - 1}",
            has_value=False,
        )
    return a


@dataclass(frozen=True)
class TetMesh:
    """A solid part meshed into 10-node tetrahedra (module docstring: frame, units, node order).

    Attributes
    ----------
    name : str
        The part's name.
    nodes : ndarray, shape (n, 3)
        Node coordinates, m.
    tets : ndarray of int, shape (m, 10)
        The tetrahedra, VTK ``QUADRATIC_TETRA`` order, positively oriented.
    faces : dict of str to ndarray of int, shape (k, 6)
        Named boundary face sets of 6-node triangles; ``"start"`` and ``"end"`` at the axial ends.
    size : float
        The global element size the mesher was asked for, m.
    source : str
        What was meshed, for the record (a part's description or a file).
    """

    name: str
    nodes: np.ndarray
    tets: np.ndarray
    faces: dict = field(default_factory=dict)
    size: float = float("nan")
    source: str = ""

    def __post_init__(self) -> None:
        where = f"mesh of {self.name!r}"
        nodes = _array(self.nodes, f"{where}.nodes", float, 3)
        if not np.all(np.isfinite(nodes)):
            raise ModelError("has a coordinate that is not a finite number", field=f"{where}.nodes")
        n = nodes.shape[0]
        tets = _indices(self.tets, f"{where}.tets", 10, n)
        c = nodes[tets[:, :4]]
        volume6 = np.einsum("ij,ij->i", c[:, 1] - c[:, 0], np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]))
        if not np.all(volume6 > 0):
            k = int(np.argmin(volume6))
            raise ModelError(
                f"tetrahedron {k} is inverted or flat (6·volume of its corners {float(volume6[k]):.3g} m³)",
                field=f"{where}.tets",
                valid="positively oriented tetrahedra (VTK order)",
                has_value=False,
            )
        faces = {}
        for key, tri in dict(self.faces).items():
            faces[str(key)] = _indices(tri, f"{where}.faces[{key!r}]", 6, n)
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "tets", tets)
        object.__setattr__(self, "faces", faces)

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def n_elements(self) -> int:
        return int(self.tets.shape[0])

    @property
    def length(self) -> float:
        """The part's extent along its axis (x), m."""
        return float(np.ptp(self.nodes[:, 0]))
