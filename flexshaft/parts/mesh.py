"""1D torsion elements of a part from its section table.

A part's mesh has a node at every station of its section table (so every
diameter step, flange face and keyway end is a node) and splits longer
intervals so no element exceeds ``max_element_length``. Each element carries
its interval's constant section: stiffness G·J/L, inertia ρ·Ip·L. The
elements are in series, so the part's end-to-end stiffness is exactly the
table's 1 / Σ L/(G·J), whatever the mesh.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..materials import Material
from ..sections.table import SectionTable

__all__ = ["TorsionMesh", "torsion_mesh", "MAX_MESH_ELEMENTS"]

#: Most elements one part's mesh may have: 4 million (~0.5 GB for a torsion model; a 6-DOF model of
#: that size would be 24 million DOFs, past what a 24 GB machine factors), or the environment's
#: FLEXSHAFT_MAX_ELEMENTS. A finer mesh is refused before it is built, with the estimate.
MAX_MESH_ELEMENTS = int(os.environ.get("FLEXSHAFT_MAX_ELEMENTS", "4000000"))


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


def torsion_mesh(
    table: SectionTable, material: Material, *, max_element_length: float | None = None, nodes_at=()
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
    """
    t = table.merged().split_at(nodes_at)
    pieces = np.ones(t.n_intervals, dtype=int)
    if max_element_length is not None:
        if not (np.isfinite(max_element_length) and max_element_length > 0):
            raise ModelError(
                "must be a finite length > 0",
                field="max_element_length",
                value=max_element_length,
                unit="m",
                valid="a finite number > 0 (m)",
            )
        # Count before allocating: a tiny max_element_length must not build 1e9 elements (or overflow).
        wanted = np.maximum(1.0, np.ceil(t.lengths / max_element_length - 1e-9))
        total = float(np.sum(wanted))
        if not np.isfinite(total) or total > MAX_MESH_ELEMENTS:
            raise ModelError(
                f"would cut the part into {total:.3g} elements",
                component=table.name,
                field="max_element_length",
                value=max_element_length,
                unit="m",
                valid=f"at most {MAX_MESH_ELEMENTS:,} elements per part: >= "
                f"{float(np.sum(t.lengths)) / MAX_MESH_ELEMENTS:.3g} m for this part's length "
                "(or raise the budget: FLEXSHAFT_MAX_ELEMENTS)",
            )
        pieces = wanted.astype(int)
    idx = np.repeat(np.arange(t.n_intervals), pieces)
    # Node positions: each interval cut into equal pieces.
    frac = np.concatenate([np.arange(p) / p for p in pieces])
    x = np.append(t.x[idx] + frac * t.lengths[idx], t.x[-1])
    le = np.diff(x)
    return TorsionMesh(x=x, stiffness=material.G * t.j[idx] / le, inertia=material.rho * t.ip[idx] * le)
