"""The solid-mesh seam: a TetMesh holds checked arrays, or it is one error naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from flexshaft.elements.tetmesh import TET10_EDGES, TetMesh
from flexshaft.errors import ModelError

CORNERS = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
NODES = np.vstack([CORNERS, [(CORNERS[a] + CORNERS[b]) / 2 for a, b in TET10_EDGES]])


def test_a_positive_tetrahedron_is_held_read_only():
    m = TetMesh("t", NODES, [list(range(10))], faces={"start": [[0, 2, 1, 6, 5, 4]]}, size=0.5)
    assert (m.n_nodes, m.n_elements, m.length) == (10, 1, 1.0)
    assert m.tets.dtype == np.int64 and m.faces["start"].shape == (1, 6)
    with pytest.raises(ValueError):
        m.nodes[0, 0] = 1.0  # the arrays between stages are not to be changed


@pytest.mark.parametrize(
    "nodes,tets,faces,field,says",
    [
        (NODES, [[1, 0, 2, 3, 4, 5, 6, 7, 8, 9]], {}, "tets", "inverted"),
        (NODES, [list(range(9))], {}, "tets", "shape"),
        (NODES, [[0, 1, 2, 3, 4, 5, 6, 7, 8, 10]], {}, "tets", "does not exist"),
        (np.where(NODES == 1, np.nan, NODES), [list(range(10))], {}, "nodes", "finite"),
        (NODES, [list(range(10))], {"end": [[0, 1, 2, 3, 4, 11]]}, "faces['end']", "does not exist"),
    ],
)
def test_bad_meshes_are_one_error_naming_the_field(nodes, tets, faces, field, says):
    with pytest.raises(ModelError, match=says) as e:
        TetMesh("t", nodes, tets, faces=faces)
    assert e.value.field == f"mesh of 't'.{field}"
