"""A mesh beyond what the machine can hold is refused before it is built, with the estimate."""

from __future__ import annotations

import pytest

import flexshaft as fs
from flexshaft.parts.mesh import MAX_MESH_ELEMENTS, torsion_mesh
from flexshaft.parts.model import MAX_FULL_ELEMENTS
from flexshaft.sections import table_from_segments

TABLE = table_from_segments([{"length": 1.0, "od": 0.1}], name="s")


@pytest.mark.parametrize("h", [1e-9, 1e-300])
def test_a_tiny_element_length_is_refused_with_the_count(h):
    # 1 m / 1e-9 m = 1e9 elements (the 23.7 GB); 1e-300 used to overflow and be ignored.
    with pytest.raises(fs.ModelError, match=r"max_element_length = .* m: would cut the part into 1e\+"):
        torsion_mesh(TABLE, fs.STEEL, max_element_length=h)


def test_the_limits_themselves_build():
    # Right at the torsion limit the mesh builds (arrays of 4e6 floats); one 6-DOF element more than its
    # limit is refused before the 12 × 12 blocks are made.
    mesh = torsion_mesh(TABLE, fs.STEEL, max_element_length=1.0 / MAX_MESH_ELEMENTS)
    assert mesh.n_elements == MAX_MESH_ELEMENTS
    too_many = f"would make a 6-DOF part model of {MAX_FULL_ELEMENTS + 1} elements"
    with pytest.raises(fs.ModelError, match=too_many):
        fs.part_model(TABLE, fs.STEEL, dofs="full", max_element_length=1.0 / (MAX_FULL_ELEMENTS + 1))
