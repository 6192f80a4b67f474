"""1D torsion elements of a part from its section table.

A part's mesh has a node at every station of its section table (so every
diameter step, flange face and keyway end is a node) and splits longer
intervals so no element exceeds ``max_element_length``. Each element carries
its interval's constant section: stiffness G·J/L, inertia ρ·Ip·L. The
elements are in series, so the part's end-to-end stiffness is exactly the
table's 1 / Σ L/(G·J), whatever the mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elements.materials import Material
from ..sections.table import SectionTable
from ..system.limits import CEILINGS, ceiling, check_ceiling
from ..validation import check_positive

__all__ = ["TorsionMesh", "torsion_mesh", "mesh_size", "MAX_MESH_ELEMENTS"]

#: Most elements one part's mesh may have by default: the ``elements`` ceiling of
#: :mod:`flexshaft.system.limits` (a million; FLEXSHAFT_MAX_ELEMENTS sets another). A finer mesh is refused
#: before it is built, with the count and the element length that fits.
MAX_MESH_ELEMENTS = CEILINGS["elements"].value


@dataclass(frozen=True)
class TorsionMesh:
    """Torsion elements along a part (SI).

    Attributes
    ----------
    x : ndarray, shape (n + 1,)
        Node positions along the axis, m.
    stiffness : ndarray, shape (n,)
        Element torsional stiffness G·J/L, N·m/rad.
    inertia : ndarray, shape (n,)
        Element axial inertia ρ·Ip·L, kg·m².
    """

    x: np.ndarray
    stiffness: np.ndarray
    inertia: np.ndarray

    @property
    def n_elements(self) -> int:
        """Number of elements."""
        return self.stiffness.size


def mesh_size(
    table: SectionTable, *, max_element_length: float | None = None, nodes_at=(), subdivide: int = 1
) -> float:
    """How many elements :func:`torsion_mesh` cuts the part into, counted without building them
    (``inf`` where the count leaves floating point); the arguments are :func:`torsion_mesh`'s."""
    t = table.merged().split_at(nodes_at)
    if max_element_length is None:
        return float(t.n_intervals * subdivide)
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.sum(np.maximum(1.0, np.ceil(t.lengths / max_element_length - 1e-9)))) * subdivide


def torsion_mesh(
    table: SectionTable,
    material: Material,
    *,
    max_element_length: float | None = None,
    nodes_at=(),
    subdivide: int = 1,
) -> TorsionMesh:
    """Torsion elements of a part: one per table interval, split to ``max_element_length``.

    Parameters
    ----------
    table : SectionTable
        The part's sections (neighbouring equal intervals are joined first).
    material : Material
        G (Pa) and ρ (kg/m³).
    max_element_length : float, optional
        Longest element, m; ``None`` keeps one element per interval.
    nodes_at : sequence of float
        Extra positions (m, inside the part) that must be nodes: named stations.
    subdivide : int
        Cut every element of that mesh into this many equal pieces, >= 1: a refinement whose mesh
        contains the coarse one's nodes (nested), as the mesh-convergence estimate needs.
    """
    t = table.merged().split_at(nodes_at)
    pieces = np.ones(t.n_intervals, dtype=int)
    subdivide = int(subdivide)
    if subdivide > 1:
        wanted = mesh_size(
            table, max_element_length=max_element_length, nodes_at=nodes_at, subdivide=subdivide
        )
        check_ceiling(
            "elements",
            wanted,
            component=table.name,
            field="elements",
            detail=f"each element cut into {subdivide} would make {wanted:.6g} elements",
        )
    if max_element_length is not None:
        check_positive(max_element_length, "max_element_length", "m", "must be a finite length > 0")
        # Count before allocating: a tiny max_element_length must not build 1e9 elements (or overflow).
        wanted = np.maximum(1.0, np.ceil(t.lengths / max_element_length - 1e-9))
        total = float(np.sum(wanted))
        limit = ceiling("elements")
        if not np.isfinite(total) or total > limit:
            check_ceiling(
                "elements",
                total,
                component=table.name,
                field="max_element_length",
                value=max_element_length,
                unit="m",
                detail=f"would cut the part into {total:.3g} elements",
                hint=f"max_element_length >= {float(np.sum(t.lengths)) / limit:.3g} m for this part's length",
            )
        pieces = wanted.astype(int)
    pieces = pieces * subdivide
    idx = np.repeat(np.arange(t.n_intervals), pieces)
    # Node positions: each interval cut into equal pieces.
    frac = np.concatenate([np.arange(p) / p for p in pieces])
    x = np.append(t.x[idx] + frac * t.lengths[idx], t.x[-1])
    le = np.diff(x)
    return TorsionMesh(x=x, stiffness=material.G * t.j[idx] / le, inertia=material.rho * t.ip[idx] * le)
