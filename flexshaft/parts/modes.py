"""Modes of one part's 1D model, free or on lateral bearing springs.

A free part has its rigid-body motions (1 for torsion, 6 for a full model) as
exact zero modes; springs on lateral DOFs (bearings) remove the lateral and
tilting ones. The solver is :func:`flexshaft.eigen.lowest_modes`: banded
shift-invert Lanczos on the part's node-major numbering.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..linalg.eigen import lowest_modes
from ..validation import check_real
from .model import DOF_NAMES, PartModel, smooth_trial_shapes

__all__ = ["PartModes", "part_modes"]


@dataclass(frozen=True)
class PartModes:
    """The lowest modes of a part (SI).

    Attributes
    ----------
    frequencies_hz : ndarray
        Undamped natural frequencies, Hz, ascending; rigid-body modes exactly 0.
    shapes : ndarray, shape (n_dofs, count)
        Mass-normalised mode shapes (ΦᵀMΦ = I).
    rigid : ndarray of bool
        Rigid-body modes.
    dof_names : tuple of str
        Names of a node's DOFs, in order.
    method : str
        The eigensolver path used.
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    dof_names: tuple
    method: str

    def node_shape(self, mode: int, dof: str) -> np.ndarray:
        """One DOF (e.g. ``"uy"``) of one mode at every node."""
        if dof not in self.dof_names:
            raise ModelError("no such DOF", field="dof", value=dof, valid=", ".join(self.dof_names))
        d = len(self.dof_names)
        return self.shapes[self.dof_names.index(dof) :: d, mode]


def part_modes(part: PartModel, count: int = 10, *, bearings: Mapping[int, float] | None = None) -> PartModes:
    """The ``count`` lowest modes of a part, free or on lateral springs.

    Parameters
    ----------
    part : PartModel
        From :func:`flexshaft.partmodel.part_model`.
    count : int
        Modes wanted, rigid-body modes included.
    bearings : mapping of node index to stiffness, optional
        Isotropic lateral springs (N/m on uy and uz) at nodes of a full model.

    Returns
    -------
    PartModes
    """
    K = part.K
    rigid = part.rigid_body_modes()
    if bearings:
        if part.dofs != "full":
            raise ModelError(
                "bearings act on lateral DOFs, which a torsion model has not",
                field="bearings",
                valid='a part model with dofs = "full"',
            )
        rows = []
        vals = []
        for node, k in bearings.items():
            k = check_real(k, f"bearings[{node}]", "N/m", lo=0.0, lo_open=True)
            dofs = part.node_dofs(node)
            rows += [dofs[1], dofs[2]]
            vals += [k, k]
        K = (K + sp.csr_matrix((vals, (rows, rows)), shape=K.shape)).tocsr()
        # Lateral and tilting rigid motions are now resisted; axial and torsion stay free. One bearing
        # still lets the part tilt about it: rotations about that node instead of the first one.
        if len(bearings) >= 2:
            rigid = rigid[:, [0, 3]]
        else:
            (node,) = bearings
            shift = part.x[node] - part.x[0]
            tilt = rigid[:, [4, 5]].copy()
            tilt[2::6, 0] += shift  # uz = −θy·(x − x_b)
            tilt[1::6, 1] -= shift  # uy = +θz·(x − x_b)
            rigid = np.hstack([rigid[:, [0, 3]], tilt])
    sol = lowest_modes(
        K, part.M, count, rigid_basis=rigid, trial=smooth_trial_shapes(part.x, part.dofs_per_node)
    )
    f = np.sqrt(np.clip(sol.eigenvalues, 0.0, None)) / (2 * np.pi)
    return PartModes(
        frequencies_hz=f,
        shapes=sol.vectors,
        rigid=sol.rigid,
        dof_names=DOF_NAMES[part.dofs],
        method=sol.method,
    )
