"""Nested refinement of a part's mesh (what the mesh check's h/2 and h/4 solves stand on)."""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.parts.beammesh import mesh_size, torsion_mesh
from flexshaft.sections.table import table_from_segments

TABLE = table_from_segments(
    [{"length": 0.3, "od": 0.1}, {"length": 0.05, "od": 0.2}, {"length": 0.7, "od": 0.08}], name="stepped"
)


@pytest.mark.parametrize("cap", [None, 0.12])
def test_each_element_is_cut_into_equal_pieces_keeping_every_node(cap):
    coarse = torsion_mesh(TABLE, fs.STEEL, max_element_length=cap)
    for r in (2, 4):
        fine = torsion_mesh(TABLE, fs.STEEL, max_element_length=cap, subdivide=r)
        counted = mesh_size(TABLE, max_element_length=cap, subdivide=r)
        assert fine.n_elements == r * coarse.n_elements == counted
        assert np.allclose(fine.x[::r], coarse.x)  # nested: the coarse nodes are fine nodes
        # the elements are in series: the end-to-end stiffness is the table's, whatever the mesh
        assert 1 / np.sum(1 / fine.stiffness) == pytest.approx(TABLE.torsional_stiffness(fs.STEEL.G))


def test_a_shaft_subdivided_and_its_ceiling(monkeypatch):
    s = fs.Shaft("s", stiffness=1e5, inertia=1.0, elements=3, subdivide=4)
    assert s.n_elements == 12 and s.element_properties()[0].size == 12
    monkeypatch.setenv("FLEXSHAFT_MAX_ELEMENTS", "10")
    with pytest.raises(fs.ModelError, match="elements"):
        fs.Shaft("s", stiffness=1e5, inertia=1.0, elements=3, subdivide=4)
    with pytest.raises(fs.ModelError, match="elements"):
        torsion_mesh(TABLE, fs.STEEL, max_element_length=0.12, subdivide=4)
