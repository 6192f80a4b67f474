"""Each shaft of a drivetrain as the assembly enters it: its elements on the line, its part model, its
Craig-Bampton body (1D or solid), and the size its mesh makes the model.

A shaft's elements (:func:`shaft_elements`) are its torsion mesh's; its part model
(:func:`shaft_part_model`) the torsion chain or, with six DOFs a node, its Timoshenko beams
(:func:`flexshaft.parts.model.part_model`); a shaft with ``reduce`` enters as the flexible body of
:func:`flexshaft.reduction.craig_bampton.craig_bampton`, and a solid part (``fe = "solid"``) as the
same front end's body of its :class:`~flexshaft.parts.solidpart.SolidPartModel`, recovered on the 1D
mesh's line. A solid's reduction is the costliest step of an assembly: this process keeps the last few
(:data:`_SOLID_BODIES`), and the disk cache the loader hands the part keeps them between runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elements import torsion_consistent_inertia, torsion_lumped_inertia, torsion_stiffness
from ..errors import ModelError
from ..linalg.eigen import solver_failures
from ..linalg.sparse import Triplets
from ..parts.model import DOF_NAMES, PartModel, part_model
from ..parts.solidpart import SolidPartModel
from ..reduction import FlexibleBody, craig_bampton
from ..reduction.axisline import body_on_line
from ..reduction.solidbasis import reduction_settings
from ..system.limits import ceiling, check_memory, model_memory_bytes
from ..validation import check_choice
from .components import INERTIA_MODELS, Coupling, Gear, Shaft

__all__ = [
    "MAX_MODAL_DAMPING_DOFS",
    "MAX_MODAL_DAMPING_ELEMENTS",
    "ShaftElements",
    "check_model_size",
    "check_modal_damping_size",
    "lean",
    "per_element",
    "reduced_body",
    "shaft_elements",
    "shaft_part",
    "shaft_part_model",
    "solid_part",
    "torsion_blocks",
]

# Part-level modal damping builds a dense block per shaft from the shaft's own
# free-free modes (a dense eigensolve of its DOFs); past these sizes that is no
# longer cheap. Larger shafts use `damping` (a discrete damper), `reduce` (a
# flexible body, damped per mode) or model-level Rayleigh damping instead.
MAX_MODAL_DAMPING_ELEMENTS = 2000
MAX_MODAL_DAMPING_DOFS = 3000


@dataclass(frozen=True)
class ShaftElements:
    """A shaft's elements along the line: torsion properties and mesh positions."""

    k: np.ndarray  # element torsional stiffness, N·m/rad
    j: np.ndarray  # element axial inertia, kg·m²
    c: np.ndarray  # element torsional damper, N·m·s/rad
    x: np.ndarray  # mesh node positions from the shaft's driving end, m (a unit parameter without length)
    has_length: bool


def shaft_elements(comp: Shaft) -> ShaftElements:
    k, j, c = (lean(a) for a in comp.element_properties())
    mesh = comp.torsion_mesh()
    if mesh is not None:
        return ShaftElements(k, j, c, mesh.x - mesh.x[0], True)
    return ShaftElements(k, j, c, np.linspace(0.0, 1.0, k.size + 1), False)


def torsion_blocks(j: np.ndarray, lumped: bool) -> np.ndarray:
    """Element inertia blocks, lumped (half on each end) or consistent."""
    return per_element(torsion_lumped_inertia if lumped else torsion_consistent_inertia, j)


def per_element(blocks, values: np.ndarray) -> np.ndarray:
    """``blocks(values)``, shape (n, 2, 2); one block broadcast over the elements when all values are equal.

    A uniform shaft's element blocks are all the same: one block read n
    times costs 32 bytes, not 32 per element.
    """
    values = np.asarray(values)
    if values.size > 1 and np.all(values == values.flat[0]):
        return np.broadcast_to(blocks(values[:1]), (values.size, 2, 2))
    return blocks(values)


def shaft_part(comp: Shaft, el: ShaftElements, dofs: str, inertia_model: str) -> PartModel:
    """The shaft's own FE model (free-free) on its mesh: torsion elements or Timoshenko beams."""
    if dofs == "torsion":
        n = el.k.size
        pairs = np.column_stack([np.arange(n), np.arange(n) + 1])
        K, M = Triplets(), Triplets()
        K.add_elements(pairs, torsion_stiffness(el.k))
        M.add_elements(pairs, torsion_blocks(el.j, inertia_model == "lumped"))
        return PartModel(
            x=el.x, dofs="torsion", K=K.build(n + 1), M=M.build(n + 1), mass=inertia_model, name=comp.name
        )
    if comp.sections is None:
        raise ModelError(
            "has no cross-sections, so no bending stiffness or mass",
            component=repr(comp.name),
            field="type",
            value="shaft",
            has_value=True,
            valid='dofs = "full" needs every shaft as a cad part or given by segments',
        )
    # nodes_at as in Shaft.torsion_mesh: the part must have the torsion mesh's nodes.
    pm = part_model(
        comp.sections,
        comp.material,
        dofs="full",
        max_element_length=comp.mesh_cap,
        mass=inertia_model,
        nodes_at=comp.named_positions,
        subdivide=comp.subdivide,
    )
    if pm.n_nodes != el.x.size:
        raise ModelError(
            f"its 6-DOF mesh has {pm.n_nodes} nodes where the torsion mesh has {el.x.size}",
            component=repr(comp.name),
            field="max_element_length",
            valid="the same mesh for both (a bug if it happens: please report it)",
        )
    return pm


def shaft_part_model(comp: Shaft, dofs: str = "torsion", inertia_model: str = "consistent") -> PartModel:
    """A shaft's own free-free FE model on the mesh a drivetrain gives it.

    Parameters
    ----------
    comp : Shaft
        Made from sections, or (torsion only) given by stiffness, inertia and
        ``elements`` equal pieces (its mesh then has no length: a unit
        parameter along it).
    dofs : {"torsion", "full"}
        θx per node, or six DOFs per node with Timoshenko beams (sections needed).
    inertia_model : {"consistent", "lumped"}
        How its inertia is spread.
    """
    if not isinstance(comp, Shaft):
        raise ModelError(
            "has no elements of its own",
            field="component",
            value=getattr(comp, "name", comp),
            valid="a shaft (a cad part, or a shaft given by segments or by numbers)",
        )
    check_choice(dofs, "dofs", tuple(DOF_NAMES))
    check_choice(inertia_model, "inertia_model", INERTIA_MODELS)
    return shaft_part(comp, shaft_elements(comp), dofs, inertia_model)


#: Half-bandwidth of an assembled chain: a torsion element couples neighbouring DOFs, a 6-DOF beam
#: element the twelve DOFs of its two nodes.
_HALF_BANDWIDTH = {"torsion": 1, "full": 11}
#: Modes a flexible body given by ``cutoff_hz`` is counted with before it is reduced.
_CUTOFF_MODES_GUESS = 20


def _elements_at_most(comp: Shaft) -> float:
    """A cheap upper bound of a shaft's elements: each table interval cut to the cap (intervals not
    merged), one more per named node."""
    if comp.sections is None:
        return float(comp.elements * comp.subdivide)
    cap, t = comp.mesh_cap, comp.sections
    if cap is None:
        return float(t.n_intervals + len(comp.named_nodes)) * comp.subdivide
    with np.errstate(over="ignore", invalid="ignore"):
        pieces = float(np.sum(np.maximum(1.0, np.ceil(t.lengths / cap))))
    return (pieces + len(comp.named_nodes)) * comp.subdivide


def _size_estimate(components, dofs: str, elements) -> tuple[float, float, tuple | None]:
    """The model's DOFs and estimated memory (bytes) with ``elements(shaft)`` elements a shaft, and
    the shaft with the most of them (with its count)."""
    d = len(DOF_NAMES[dofs])
    nodes, dense, largest = 1.0, 0.0, None
    for comp in components:
        if isinstance(comp, Shaft):
            n = elements(comp)
            nodes += n
            if largest is None or n > largest[1]:
                largest = (comp, n)
            if comp.reduce is not None:
                # its boundary DOFs and its modes, which are at most its interior DOFs
                boundary = d * (2 + len(comp.named_nodes))
                size = boundary + min(comp.reduce.modes or _CUTOFF_MODES_GUESS, d * (n + 1))
                dense += size * size
        elif isinstance(comp, (Coupling, Gear)):
            nodes += 1
    n_dof = d * nodes
    return n_dof, model_memory_bytes(n_dof, n_dof * (2 * _HALF_BANDWIDTH[dofs] + 1) + dense), largest


def check_model_size(components, dofs: str) -> None:
    """Refuse a model whose assembly and eigen-solve would not fit the ``memory_mb`` ceiling.

    Counted from the components before anything is built: every shaft's elements (its mesh
    counted, not made), the nodes couplings and gears add, and the dense blocks of flexible bodies;
    the estimate is :func:`flexshaft.system.limits.model_memory_bytes`. A cheap upper bound of the counts
    clears almost every model; only one above the ceiling by it is counted exactly. The error
    names the shaft with the most elements.
    """
    budget = ceiling("memory_mb") * 2**20
    if _size_estimate(components, dofs, _elements_at_most)[1] <= budget:
        return
    for comp in components:
        if isinstance(comp, Shaft) and comp.n_elements > ceiling("elements"):
            comp.torsion_mesh()  # refused there, with the element length that fits
    n_dof, estimate, largest = _size_estimate(components, dofs, lambda c: c.n_elements)
    if estimate <= budget or largest is None:
        return
    comp, n = largest
    by_length = comp.sections is not None and comp.max_element_length is not None
    check_memory(
        estimate,
        component=repr(comp.name),
        field="max_element_length" if by_length else "elements",
        value=comp.max_element_length if by_length else comp.elements,
        unit="m" if by_length else None,
        detail=f"assembling and solving the model's {n_dof:.6g} DOFs ({dofs}), {n:.6g} elements of them "
        "in this part,",
        hint="fewer elements: a smaller elements, a larger max_element_length",
    )


def check_modal_damping_size(comp: Shaft, part: PartModel) -> None:
    """Per-shaft modal damping needs a dense eigensolve of the shaft's own model: refuse huge ones."""
    alternatives = "(use `damping`, `reduce` or model-level Rayleigh damping for finer meshes)"
    if part.dofs == "torsion" and part.n_elements > MAX_MODAL_DAMPING_ELEMENTS:
        field, unit = "elements", None
        valid = f"at most {MAX_MODAL_DAMPING_ELEMENTS} with damping_ratio > 0 {alternatives}"
    elif part.dofs == "full" and part.n_dofs > MAX_MODAL_DAMPING_DOFS:
        field, unit = "max_element_length", "elements"
        valid = (
            f"at most {MAX_MODAL_DAMPING_DOFS // 6 - 1} elements in a 6-DOF shaft with damping_ratio > 0 "
            + alternatives
        )
    else:
        return
    raise ModelError(
        "modal damping per shaft mode needs the shaft's own modes",
        component=repr(comp.name),
        field=field,
        value=part.n_elements,
        unit=unit,
        valid=valid,
    )


def _reduce(comp: Shaft, part: PartModel, named: list[int]) -> FlexibleBody:
    """Craig–Bampton reduction of the shaft's part model; boundary = end nodes + named nodes."""
    red = comp.reduce
    try:
        with solver_failures(f"the Craig–Bampton reduction of {comp.name!r}"):
            return craig_bampton(
                part, modes=red.modes, cutoff_hz=red.cutoff_hz, nodes=named, damping_ratio=red.damping
            )
    except ModelError as err:
        raise err.located(component=repr(comp.name)) from None


#: Solid parts' reductions already made in this process, by part and settings: a Craig–Bampton
#: reduction of a solid is the costliest step of an assembly, and one command assembles its model
#: several times. A few entries (each holds its mesh, which keys it, and its shapes: ~8 bytes x DOFs x
#: (interface + modes + residual) columns, 40 MB for 540 000 DOFs).
_SOLID_BODIES: dict = {}
_SOLID_BODIES_KEPT = 8


def _remember(key, entry) -> None:
    """Keep a solid part's reduction for this process's later assemblies (the oldest leaves first)."""
    while len(_SOLID_BODIES) >= _SOLID_BODIES_KEPT:
        _SOLID_BODIES.pop(next(iter(_SOLID_BODIES)))
    _SOLID_BODIES[key] = entry


def solid_part(comp: Shaft, dofs: str) -> SolidPartModel:
    """The part model of a solid part (``fe = "solid"``): its mesh, material, DOFs and ties."""
    return SolidPartModel(comp.solid_mesh, comp.material, dofs, tuple(comp.interface))


def solid_line(comp: Shaft, x) -> np.ndarray:
    """The 1D mesh's line ``x`` (m from the part's start) on the solid's length: the table's length
    and the mesh's agree to ~1e-9."""
    line = np.asarray(x, dtype=float)
    return line * (comp.solid_mesh.length / line[-1])


def _kept_reduction(comp: Shaft, key, statics: bool):
    """A solid part's reduction made earlier in this process or kept on disk, or None."""
    hit = _SOLID_BODIES.get(key)
    if hit is None and statics:
        # a reduction with modes serves statics exactly: its static part is the constraint modes'
        # condensation, uncoupled from the modal coordinates (which a static load leaves at zero)
        hit = _SOLID_BODIES.get(key[:3] + (False,) + key[4:])
    red = comp.solid_reduce
    if hit is None and statics and comp.solid_cache is not None:
        # as in this process, so on disk: a reduction with modes kept by an earlier run serves statics
        settings = reduction_settings(
            comp.material, dofs=key[2], interface=comp.interface, modes=red.modes, cutoff_hz=red.cutoff_hz
        )
        kept = comp.solid_cache.load(comp.solid_mesh, settings)
        if kept is not None:
            hit = (comp.solid_mesh, kept)
            _remember(key[:3] + (False,) + key[4:], hit)  # for this run's modes too
    return hit[1] if hit is not None and hit[0] is comp.solid_mesh else None


def _solid_body(comp: Shaft, el: ShaftElements, dofs: str, statics: bool) -> FlexibleBody:
    """A solid part's Craig–Bampton body on its 1D line (:func:`~flexshaft.reduction.craig_bampton`)."""
    red = comp.solid_reduce
    key = (id(comp.solid_mesh), comp.material, dofs, statics, red.modes, red.cutoff_hz, comp.interface)
    line = solid_line(comp, el.x)
    reduction = _kept_reduction(comp, key, statics)
    try:
        if reduction is not None:
            return body_on_line(reduction, line_x=line, damping_ratio=red.damping)
        # statics alone (the twist test): the static condensation, no modes
        how = (
            {"modes": 0, "cutoff_hz": None, "residual": False}
            if statics
            else {"modes": red.modes, "cutoff_hz": red.cutoff_hz}
        )
        with solver_failures(f"the Craig–Bampton reduction of the solid {comp.name!r}"):
            # the loader's progress bar (a factory of labels), if it handed the part one
            bar = comp.solid_progress(f"reducing {comp.name}") if comp.solid_progress is not None else None
            body = craig_bampton(
                solid_part(comp, dofs),
                line_x=line,
                damping_ratio=red.damping,
                progress=getattr(bar, "stage", None),
                cache=comp.solid_cache,
                **how,
            )
    except ModelError as err:
        raise err.located(component=repr(comp.name)) from None
    _remember(key, (comp.solid_mesh, body.reduction))
    return body


def reduced_body(comp: Shaft, el: ShaftElements, part, marks, dofs: str, statics: bool) -> FlexibleBody:
    """The flexible body a shaft enters the chain as: its solid's (``fe = "solid"``) or its 1D part
    model's (``reduce``), boundary = end nodes + named nodes ``marks``."""
    return _solid_body(comp, el, dofs, statics) if comp.fe == "solid" else _reduce(comp, part, marks)


def lean(a: np.ndarray) -> np.ndarray:
    """``a``, or a read-only view of its one value when all its entries are equal.

    A uniform shaft's per-element and per-node arrays (its stiffness, damping,
    component, ratio, speed frame, positions without length) are constant: a
    broadcast view reads the same and costs one number, not one per element
    (8 MB each at 1 M elements).
    """
    a = np.asarray(a)
    if a.size > 1 and np.all(a == a.flat[0]):
        return np.broadcast_to(a[:1].copy(), a.shape)
    return a
