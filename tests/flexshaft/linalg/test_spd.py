"""The solver of solid parts' stiffness: the rigid-body modes, the direct and the multigrid paths.

References: the rigid motions are the null space of an unconstrained elastic body's stiffness (exact
for the 10-node tetrahedron, tests/flexshaft/elements/test_tet10.py); a clamped bar's solution from
SuperLU (exact to round-off) against conjugate gradients with smoothed aggregation.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexshaft.elements.materials import STEEL
from flexshaft.elements.tet10 import solid_matrices
from flexshaft.elements.tetmesh import TetMesh
from flexshaft.errors import ModelError
from flexshaft.linalg.spd import SpdSolver, rigid_body_modes
from tests.flexshaft.elements.test_tet10 import box_mesh


def _bar(cells=(8, 3, 3)):
    nodes, tets = box_mesh(np.array(cells), (0.4, 0.15, 0.15))
    return nodes, solid_matrices(TetMesh("bar", nodes, tets), STEEL).K.tocsr()


def test_rigid_body_modes_are_the_null_space_of_a_free_body():
    nodes, K = _bar((3, 2, 2))
    B = rigid_body_modes(nodes)
    assert B.shape == (K.shape[0], 6) and np.linalg.matrix_rank(B) == 6
    # K·B = 0 up to round-off in K's entries (each row sums ~30 entries of size ‖K‖): 1e-12 relative
    assert np.abs(K @ B).max() <= 1e-12 * abs(K).max() * np.abs(B).max()
    # the rotations are scaled to the translations' size: columns of comparable norm
    norms = np.linalg.norm(B, axis=0)
    assert norms.max() / norms.min() < 3


def _clamped(nodes, K):
    free = np.repeat(nodes[:, 0] > 1e-12, 3)  # the face x = 0 clamped
    rng = np.random.default_rng(1)
    f = rng.standard_normal(int(free.sum()))
    return K[free][:, free], f, rigid_body_modes(nodes)[free]


def test_multigrid_and_the_direct_solver_agree():
    nodes, K = _bar()
    Kf, f, B = _clamped(nodes, K)
    direct = SpdSolver(Kf, method="direct")
    x = direct.solve(f)
    amg = SpdSolver(Kf, near_null=B, method="amg", rtol=1e-12)
    y = amg.solve(f)
    assert direct.report.method == "SuperLU" and "smoothed-aggregation" in amg.report.method
    # ‖x − y‖_K ≤ ‖K‖^½‖K⁻¹‖^½... the residual bound: ‖x − y‖/‖x‖ ≤ cond(K)·rtol; cond of this mesh
    # is ~1e5 (a steel bar, elements of aspect ~2), so 1e-12 · 1e5 leaves 1e-7
    assert np.linalg.norm(x - y) <= 1e-6 * np.linalg.norm(x)
    # the true residual: CG's recursive one reaches rtol, round-off over the iterations may add ~10x
    assert amg.report.residual <= 100 * 1e-12 and 0 < amg.report.iterations < 200
    # several right-hand sides at once, one per column
    both = amg.solve(np.column_stack([f, 2 * f]))
    np.testing.assert_allclose(both[:, 1], 2 * both[:, 0], rtol=1e-9)


@pytest.mark.parametrize("method", ["direct", "amg"])
def test_a_free_body_is_refused(method):
    # a load with a net force on a body free to move has no static solution: a residual of order 1
    nodes, K = _bar((2, 1, 1))
    with pytest.raises(ModelError, match="singular") as e:
        SpdSolver(K, near_null=rigid_body_modes(nodes), method=method, what="the bar").solve(
            np.ones(K.shape[0])
        )
    assert str(e.value).startswith("K: the bar:")
