"""One part as a model of its own: its modes go through the same analysis and result as a drivetrain's.

:func:`assemble_part` wraps a :class:`~flexshaft.parts.model.PartModel` (free,
or on lateral bearing springs at some of its nodes) as an
:class:`~flexshaft.model.assembly.AssembledModel` with one component, the
part, so that :func:`flexshaft.analysis.modal.modal_analysis` gives its modes
as a :class:`~flexshaft.analysis.modal.ModalResult` - energies, DOF families,
torques and station shapes included.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..linalg.sparse import Triplets
from ..parts.model import DOF_NAMES, PartModel
from ..validation import check_real
from .assembly import AssembledModel, Station
from .components import Drivetrain, Shaft

__all__ = ["assemble_part"]


def _torsion_elements(part: PartModel) -> np.ndarray:
    """Torsional stiffness of each element, N·m/rad: minus the θx-θx coupling of its two nodes.

    Torsion is uncoupled in both element kinds (torsion elements; Timoshenko
    beams, whose θx block is G·J/L·[[1, −1], [−1, 1]]).
    """
    d = part.dofs_per_node
    rows = np.arange(part.n_elements) * d + DOF_NAMES[part.dofs].index("θx")
    return -np.asarray(part.K[rows, rows + d]).ravel()


def _end_to_end(part: PartModel, k_el: np.ndarray) -> tuple[float, float]:
    """The part's torsional stiffness end to end (elements in series), N·m/rad, and axial inertia, kg·m²."""
    stiffness = 1.0 / float(np.sum(1.0 / k_el))
    d = part.dofs_per_node
    spin = np.zeros(part.n_dofs)
    spin[DOF_NAMES[part.dofs].index("θx") :: d] = 1.0
    return stiffness, float(spin @ (part.M @ spin))


def assemble_part(part: PartModel, bearings: Mapping[int, float] | None = None) -> AssembledModel:
    """A part model as a one-component model, free or on isotropic lateral springs.

    Parameters
    ----------
    part : PartModel
        From :func:`flexshaft.parts.model.part_model`.
    bearings : mapping of node index to stiffness, optional
        Isotropic lateral springs (N/m on uy and uz) at nodes of a full
        (6-DOF) part model. Each becomes a station ``"node i"``.

    Returns
    -------
    AssembledModel
        Its one component is a :class:`Shaft` carrying the part's end-to-end
        torsional stiffness and axial inertia; coordinates are the part's
        DOFs (T is the identity).
    """
    if not isinstance(part, PartModel):
        raise ModelError("not a part model", field="part", value=type(part).__name__, valid="a PartModel")
    bearings = dict(bearings or {})
    if bearings and part.dofs != "full":
        raise ModelError(
            "bearings act on lateral DOFs, which a torsion model has not",
            field="bearings",
            valid='a part model with dofs = "full"',
        )
    k_el = _torsion_elements(part)
    stiffness, inertia = _end_to_end(part, k_el)
    comp = Shaft(part.name, stiffness=stiffness, inertia=inertia)
    n, d = part.n_nodes, part.dofs_per_node
    named = {0: f"{part.name} start", n - 1: f"{part.name} end"}
    K, M = Triplets(), Triplets()
    K.add_sparse(part.K, owner=0)
    M.add_sparse(part.M, owner=0)
    held = []
    for b, (node, k) in enumerate(bearings.items()):
        k = check_real(k, f"bearings[{node}]", "N/m", lo=0.0, lo_open=True)
        dofs = part.node_dofs(node)
        K.add(dofs[1:3], dofs[1:3], [k, k], owner=1 + b)
        node = int(dofs[0] // d)
        named.setdefault(node, f"node {node}")
        held.append((node, k))
    stations = tuple(Station(name, node) for node, name in sorted(named.items()))
    by_node = {st.node: st for st in stations}
    k_entries, m_entries = K.entries(part.n_dofs), M.entries(part.n_dofs)
    Mp = sp.csr_matrix(part.M)
    return AssembledModel(
        drivetrain=Drivetrain(part.name, (comp,), dofs=part.dofs),
        inertia_model=part.mass,
        dofs=part.dofs,
        K=k_entries.matrix,
        M=Mp,
        C=None,
        T=sp.identity(part.n_dofs, format="csr"),
        x=np.asarray(part.x),
        stations=stations,
        start_node=np.array([0]),
        end_node=np.array([n - 1]),
        coordinate_dofs=np.arange(part.n_dofs),
        element_nodes=np.arange(part.n_elements),
        element_stiffness=k_el,
        element_damping=np.zeros(part.n_elements),
        element_component=np.zeros(part.n_elements, dtype=int),
        element_ratio=np.ones(part.n_elements),
        speed_ratio=np.ones(n),
        stiffness_entries=k_entries,
        mass_entries=m_entries,
        damping_entries=Triplets().entries(part.n_dofs),
        M_nodes=Mp,
        bodies=(),
        bearings=tuple((by_node[node], k) for node, k in held),
    )
