"""Multigrid for solid parts: the linear elements' coarse space, the reordering, the block CG.

References: a 10-node tetrahedron interpolates a linear field exactly from its corners (a straight
edge's mid-side node takes its ends' mean), and rigid motions are linear; the RBE2 tie reproduces
them exactly (tests/flexshaft/parts/test_solidties.py); SuperLU, exact to round-off, for the solves.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import shortest_path

from flexshaft.elements.materials import STEEL
from flexshaft.elements.tet10 import solid_matrices
from flexshaft.elements.tetmesh import TET10_EDGES, TetMesh
from flexshaft.errors import ModelError
from flexshaft.linalg.multigrid import (
    Multigrid,
    block_product,
    linear_coarse_space,
    locality_order,
    permuted,
    permuted_coarse,
)
from flexshaft.linalg.spd import SpdSolver, block_cg
from flexshaft.parts.solidties import constrain, rigid_interface
from tests.flexshaft.elements.test_tet10 import box_mesh, tri6_faces_on


def _bar(cells=(6, 2, 2), size=(0.6, 0.15, 0.1)):
    nodes, tets = box_mesh(np.array(cells), size)
    faces = {"start": tri6_faces_on(nodes, tets, 0, 0.0), "end": tri6_faces_on(nodes, tets, 0, size[0])}
    return TetMesh("bar", nodes, tets, faces=faces)


def _tied(mesh, clamped=()):
    K = solid_matrices(mesh, STEEL).K
    ends = [rigid_interface(mesh, "start"), rigid_interface(mesh, "end")]
    return constrain(K, mesh, ends, clamped=clamped)


def test_the_coarse_space_interpolates_linear_fields_exactly():
    mesh = _bar()
    n = mesh.n_nodes
    cs = linear_coarse_space(mesh.tets, sp.identity(3 * n, format="csr"), edges=TET10_EDGES)
    corners = np.unique(mesh.tets[:, :4])
    assert cs.P.shape == (3 * n, 3 * corners.size)
    # each coarse unknown is a copy of one fine unknown: that row of P is the unit entry alone
    np.testing.assert_array_equal(cs.P[cs.injected].toarray(), np.eye(cs.P.shape[1]))
    # u = A·x + c at every node from its values at the corners: exact for straight elements (the
    # weights are 1 and ½, the sums those of the coordinates: round-off of 1e-16 · |u| ~ 1e-15)
    rng = np.random.default_rng(2)
    A, c = rng.standard_normal((3, 3)), rng.standard_normal(3)
    u = (mesh.nodes @ A.T + c).ravel()
    np.testing.assert_allclose(cs.P @ u[cs.injected], u, rtol=0, atol=1e-14 * np.abs(u).max())


def test_the_coarse_space_follows_the_rigid_ties():
    mesh = _bar()
    system = _tied(mesh)
    cs = linear_coarse_space(mesh.tets, system.T, edges=TET10_EDGES)
    B = system.near_null
    # the six rigid motions (linear fields, the tie exact for them) come out of their corner and
    # master values exactly: round-off of the coordinates
    np.testing.assert_allclose(cs.P @ B[cs.injected], B, rtol=0, atol=1e-14 * np.abs(B).max())
    # the masters are coarse unknowns of their own
    masters = np.concatenate(list(system.masters.values()))
    assert np.isin(masters, cs.injected).all()
    # a sub-matrix (one master held): its rows in order, the held master gone from the coarse space
    rows = np.setdiff1d(np.arange(system.K.shape[0]), system.masters["start"])
    sub = linear_coarse_space(mesh.tets, system.T, rows, edges=TET10_EDGES)
    assert sub.P.shape == (rows.size, cs.P.shape[1] - 6)
    np.testing.assert_array_equal(rows[sub.injected], np.setdiff1d(cs.injected, system.masters["start"]))


def test_reordering_narrows_the_band_and_permutes_exactly():
    mesh = _bar((8, 3, 3))
    K = solid_matrices(mesh, STEEL).K.tocsr()
    nodes = np.random.default_rng(4).permutation(K.shape[0] // 3)  # nodes numbered at random
    shuffle = (3 * nodes[:, None] + np.arange(3)).ravel()
    Ks = K[shuffle][:, shuffle].tocsr()
    order = locality_order(Ks)
    Kp = permuted(Ks, order)
    assert sorted(order) == list(range(K.shape[0]))
    assert abs(Kp - Ks[order][:, order]).max() == 0.0

    def band(A):
        coo = A.tocoo()
        return int(np.abs(coo.row - coo.col).max())

    # What Cuthill-McKee guarantees whatever the tie order (numpy's SIMD sorts break ties per CPU,
    # so its start node and the order within a level differ between machines): the nodes come level
    # by level of a breadth-first search from its start node, and a node couples only to its own
    # level and the two beside it, so the band is below |L_i| + |L_i+1| for the widest pair of
    # levels (in DOFs: three per node, 3 b + 2). Reversing the order keeps the band.
    n_nodes = K.shape[0] // 3
    graph = sp.csr_matrix((np.ones(Ks.nnz), Ks.indices // 3, Ks.indptr[::3]), shape=(n_nodes, n_nodes))
    node_order = order[::3] // 3
    levels = shortest_path(graph, unweighted=True, indices=node_order[-1]).astype(int)
    assert np.all(np.diff(levels[node_order[::-1]]) >= 0)  # level by level from the start node
    widths = np.bincount(levels)
    assert band(Kp) <= 3 * (int((widths[:-1] + widths[1:]).max()) - 1) + 2
    # and that narrows a random numbering (which spans the whole matrix) from ANY start node: the
    # bound from the worst one is well inside it
    every = shortest_path(graph, unweighted=True).astype(int)
    worst = max(int((w[:-1] + w[1:]).max()) - 1 for w in map(np.bincount, every))
    assert band(Ks) > 0.9 * K.shape[0] and band(Kp) <= 3 * worst + 2 < 0.6 * K.shape[0]
    # the coarse space reordered with it is the same space: a field in it is rebuilt from its values
    # at the (renumbered) coarse unknowns
    cs = linear_coarse_space(mesh.tets, sp.identity(K.shape[0], format="csr")[:, shuffle], edges=TET10_EDGES)
    moved = permuted_coarse(cs, order)
    rng = np.random.default_rng(5)
    uc = rng.standard_normal(cs.P.shape[1])
    fine = cs.P @ uc
    np.testing.assert_allclose(moved.P @ fine[order][moved.injected], fine[order], rtol=0, atol=1e-14)


def test_block_products_of_few_and_many_columns_agree():
    K = solid_matrices(_bar(), STEEL).K.tocsr()
    X = np.random.default_rng(6).standard_normal((K.shape[0], 9))
    for k in (1, 3, 9):  # the column loop below BLOCK_MIN, scipy's block product above
        # the same sums in another order: ~eps·Σ|K||x|
        bound = 1e-14 * (abs(K) @ np.abs(X[:, :k])).max()
        np.testing.assert_allclose(block_product(K, X[:, :k]), K @ X[:, :k], rtol=0, atol=bound)


@pytest.mark.parametrize("coarse", [False, True])
def test_the_twist_solve_agrees_with_the_direct_one(coarse):
    mesh = _bar()
    system = _tied(mesh, clamped=("start",))
    K = system.K
    loads = np.zeros((K.shape[0], 6))
    loads[system.masters["end"], np.arange(6)] = 1.0
    x = SpdSolver(K, method="direct").solve(loads)
    cs = linear_coarse_space(mesh.tets, system.T, edges=TET10_EDGES) if coarse else None
    amg = SpdSolver(K, near_null=system.near_null, method="amg", coarse=cs, rtol=1e-10)
    y = amg.solve(loads)
    assert ("linear elements" in amg.report.method) == coarse
    # ‖x − y‖/‖x‖ <= cond(K)·‖r‖/‖b‖ for each column, with ‖r‖/‖b‖ the true residual the report gives
    w = np.linalg.eigvalsh(K.toarray())
    bound = w[-1] / w[0] * amg.report.residual
    assert amg.report.residual <= 100 * 1e-10
    err = np.linalg.norm(x - y, axis=0) / np.linalg.norm(x, axis=0)
    assert np.all(err <= bound), (err, bound)


def test_block_cg_lets_converged_columns_go():
    # columns of very different size and a zero one: each stops at its own tolerance
    mesh = _bar()
    system = _tied(mesh, clamped=("start", "end"))
    K = system.K
    mg = Multigrid(
        K, near_null=system.near_null, coarse=linear_coarse_space(mesh.tets, system.T, edges=TET10_EDGES)
    )
    rng = np.random.default_rng(7)
    B = rng.standard_normal((K.shape[0], 7)) * np.array([1.0, 1e6, 1e-6, 1.0, 1.0, 1.0, 1.0])
    B[:, 3] = 0.0
    X, its = block_cg(K, B, mg.apply, 1e-10, 500)
    assert its < 500
    res = np.linalg.norm(B - K @ X, axis=0)
    # the recursive residual reaches 1e-10 of each column; the true one drifts from it by round-off
    assert np.all(res[[0, 1, 2, 4, 5, 6]] <= 1e-8 * np.linalg.norm(B[:, [0, 1, 2, 4, 5, 6]], axis=0))
    assert np.all(X[:, 3] == 0.0)


def test_a_load_of_the_given_modes_is_solved_by_the_first_guess():
    # K⁻¹ = Φ Λ⁻¹ Φᵀ over all modes (Φ M-orthonormal): for b = M Φ c the first guess Φ Λ⁻¹ Φᵀ b is
    # K⁻¹b itself, to the modes' accuracy (exact here: a dense eigen-solve)
    mesh = _bar((4, 2, 2))
    system = _tied(mesh, clamped=("start", "end"))
    mats = solid_matrices(mesh, STEEL)
    K = system.K
    M = (system.T.T @ mats.M @ system.T).tocsr()
    lam, phi = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, 5])
    solver = SpdSolver(K, near_null=system.near_null, method="amg", rtol=1e-10)
    b = M @ phi @ np.array([1.0, -2.0, 0.5, 3.0, 1.0, -1.0])
    cold = solver.solve(b)
    cold_its = solver.report.iterations
    solver.start_from_modes(phi, lam)
    warm = solver.solve(b)
    assert solver.report.iterations <= 1 < cold_its
    exact = phi @ (np.array([1.0, -2.0, 0.5, 3.0, 1.0, -1.0]) / lam)
    for x in (cold, warm):
        # ‖x − x*‖/‖x*‖ <= cond(K)·‖r‖/‖b‖
        w = np.linalg.eigvalsh(K.toarray())
        assert np.linalg.norm(x - exact) <= w[-1] / w[0] * 1e-8 * np.linalg.norm(exact)
    # the modes must be one per eigenvalue > 0
    with pytest.raises(ModelError, match="M-orthonormal"):
        solver.start_from_modes(phi, -lam)
