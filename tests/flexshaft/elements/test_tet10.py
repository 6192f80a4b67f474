"""The 10-node tetrahedron (flexshaft.elements.tet10) against closed forms.

References, none of them flexshaft's own output:

- the integral of a monomial over the unit tetrahedron, ∫ x^a y^b z^c = a! b! c! / (a + b + c + 3)!,
  and of barycentric monomials, ∫ L0^a L1^b L2^c L3^d dV = 6V a! b! c! d! / (a + b + c + d + 3)!;
- the P2 Lagrange basis is the one quadratic basis with N_a(node b) = δ_ab;
- patch tests: a displacement field in the element's space (linear on any isoparametric mesh,
  quadratic on straight elements) is the finite-element solution exactly;
- a bar in uniaxial tension: u_x = σ x / E, stiffness E·A/L;
- Saint-Venant torsion of a square bar, whose warping the elements only approximate: stiffness
  G·J/L with J = a⁴ [1/3 − 64/π⁵ Σ tanh(nπ/2)/n⁵] (Timoshenko & Goodier, Theory of Elasticity,
  3rd ed., §109), approached from above at the elements' rate;
- a curved element's volume from a Gauss-Legendre product rule on the collapsed cube (Duffy).

Every tolerance carries its reason; "eps" is the double precision unit round-off 2.2e-16.
"""

from itertools import permutations
from math import factorial, pi, tanh

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from flexshaft.elements import tet10
from flexshaft.elements.materials import Material
from flexshaft.elements.tet10 import (
    TET4_RULE,
    TET14_RULE,
    SolidMatrices,
    solid_matrices,
    tet10_reference_nodes,
    tet10_shape,
)
from flexshaft.elements.tetmesh import TET10_EDGES, TetMesh
from flexshaft.errors import ModelError

EPS = np.finfo(float).eps
STEEL = Material(E=210e9, nu=0.29, rho=7850.0)

# --- meshes written here, independently of the module -------------------------------------------


def box_mesh(cells, size, origin=(0.0, 0.0, 0.0)):
    """A box cut into nx x ny x nz cells, each into the 6 Kuhn (Freudenthal) tetrahedra along its
    main diagonal, mid-side nodes at the edges' midpoints.

    The Kuhn tetrahedra of a cell are the paths 0 -> e_p0 -> e_p0 + e_p1 -> (1, 1, 1) over the
    permutations p of the axes; the same split in every cell makes the faces match. Nodes live on
    the doubled grid (an edge from v to v + d, d in {0, 1}³, has its midpoint at 2v + d, one point
    per edge), numbered x slowest.
    """
    cells = np.asarray(cells)
    shape = 2 * cells + 1
    grid = np.stack(np.meshgrid(*(np.arange(s) for s in shape), indexing="ij"), -1).reshape(-1, 3)
    nodes = np.asarray(origin, float) + grid * (np.asarray(size, float) / (2 * cells))
    eye = np.eye(3, dtype=int)
    kuhn = []
    for p in permutations(range(3)):
        path = np.array([[0, 0, 0], eye[p[0]], eye[p[0]] + eye[p[1]], [1, 1, 1]])
        if np.linalg.det(path[1:] - path[0]) < 0:  # an odd permutation: swap two corners
            path = path[[0, 2, 1, 3]]
        kuhn.append(path)
    origins = np.stack(np.meshgrid(*(np.arange(c) for c in cells), indexing="ij"), -1).reshape(-1, 3)
    corners = 2 * origins[:, None, None, :] + 2 * np.array(kuhn)[None]  # doubled grid
    mids = np.stack([(corners[:, :, a] + corners[:, :, b]) // 2 for a, b in TET10_EDGES], axis=2)
    at = np.concatenate([corners, mids], axis=2).reshape(-1, 10, 3)
    tets = (at[..., 0] * shape[1] + at[..., 1]) * shape[2] + at[..., 2]
    return nodes, tets


def corner_volumes(nodes, tets):
    c = nodes[tets[:, :4]]
    return np.einsum("ij,ij->i", c[:, 1] - c[:, 0], np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0])) / 6.0


def straighten(nodes, tets):
    """Mid-side nodes back at their edges' midpoints (after the corners moved)."""
    nodes = nodes.copy()
    for k, (a, b) in enumerate(TET10_EDGES):
        nodes[tets[:, 4 + k]] = 0.5 * (nodes[tets[:, a]] + nodes[tets[:, b]])
    return nodes


def boundary_mask(nodes, lo, hi):
    return np.any(
        np.isclose(nodes, lo, rtol=0, atol=1e-12) | np.isclose(nodes, hi, rtol=0, atol=1e-12), axis=1
    )


def shaken(cells, size, corner_shift, mid_shift, seed):
    """A box mesh with its interior nodes moved at random: corners by up to corner_shift·h (the
    elements stay straight when mid_shift is 0), then mid-side nodes off their midpoints by up to
    mid_shift·h (curved elements)."""
    nodes, tets = box_mesh(cells, size)
    h = np.min(np.asarray(size) / np.asarray(cells))
    rng = np.random.default_rng(seed)
    inner = ~boundary_mask(nodes, 0.0, np.asarray(size))
    is_corner = np.zeros(len(nodes), bool)
    is_corner[tets[:, :4]] = True
    move = inner & is_corner
    nodes[move] += rng.uniform(-corner_shift * h, corner_shift * h, (move.sum(), 3))
    nodes = straighten(nodes, tets)
    move = inner & ~is_corner
    nodes[move] += rng.uniform(-mid_shift * h, mid_shift * h, (move.sum(), 3))
    return nodes, tets


def dense(result: SolidMatrices):
    return result.K.toarray(), result.M.toarray()


def rigid_modes(nodes):
    """The six rigid-body motions (translations, rotations ω x x) on node-major DOFs, (3n, 6)."""
    n = len(nodes)
    R = np.zeros((n, 3, 6))
    for i in range(3):
        R[:, i, i] = 1.0
        w = np.zeros(3)
        w[i] = 1.0
        R[:, :, 3 + i] = np.cross(w, nodes)
    return R.reshape(3 * n, 6)


def dirichlet_solve(K, f, fixed, values):
    """Dense solve with some DOFs prescribed; also the condition number of the free block."""
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    Kff = K[np.ix_(free, free)]
    u = np.zeros(K.shape[0])
    u[fixed] = values
    u[free] = np.linalg.solve(Kff, f[free] - K[np.ix_(free, fixed)] @ values)
    return u, np.linalg.cond(Kff)


# --- quadrature ---------------------------------------------------------------------------------


def monomials(degree):
    return [
        (a, b, c) for a in range(degree + 1) for b in range(degree + 1 - a) for c in range(degree + 1 - a - b)
    ]


def exact_monomial(a, b, c):
    return factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3)


@pytest.mark.parametrize("rule", [TET4_RULE, TET14_RULE], ids=["4-point", "14-point"])
def test_rules_integrate_monomials_to_their_degree(rule):
    p, w = rule.points, rule.weights
    assert np.all(w > 0) and np.all(p > 0) and np.all(p.sum(axis=1) < 1)  # positive, inside
    for a, b, c in monomials(rule.degree):
        got = np.sum(w * p[:, 0] ** a * p[:, 1] ** b * p[:, 2] ** c)
        # Positive terms: no cancellation, so the relative error is at most the terms' own (the
        # coordinates' rounding times the degree, the products', the weight's) plus one rounding
        # per addition.
        assert got == pytest.approx(exact_monomial(a, b, c), rel=(2 * rule.degree + 2 + len(w)) * EPS, abs=0)
    # ... and the degree is the rule's: some monomial one degree higher is missed by far more.
    errors = [
        abs(np.sum(w * p[:, 0] ** a * p[:, 1] ** b * p[:, 2] ** c) / exact_monomial(a, b, c) - 1)
        for a, b, c in monomials(rule.degree + 1)
        if a + b + c == rule.degree + 1
    ]
    assert max(errors) > 1e-6


# --- shape functions ----------------------------------------------------------------------------


def test_shape_functions_are_the_quadratic_lagrange_basis():
    rng = np.random.default_rng(7)
    pts = rng.dirichlet(np.ones(4), size=200)[:, 1:]  # uniform in the reference tetrahedron
    N, dN = tet10_shape(pts)
    # Partition of unity; values are at most 1 in size and each carries a few roundings: 10 terms
    # give a few tens of eps.
    np.testing.assert_allclose(N.sum(axis=1), 1.0, rtol=0, atol=50 * EPS)
    # Derivatives are at most 4 in size (4L − 1, 4L): their sum vanishes to a few hundred eps.
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, rtol=0, atol=400 * EPS)
    # Kronecker delta at the nodes (the values there are 0, 1/2, 1: sums and products of binary
    # fractions, exact; a few eps of slack only).
    N_nodes, _ = tet10_shape(tet10_reference_nodes())
    np.testing.assert_allclose(N_nodes, np.eye(10), rtol=0, atol=4 * EPS)
    # Quadratics are reproduced, values and gradients: f = c0 + c·ξ + ξᵀQξ with O(1) coefficients
    # (|f| <= ~6 in the element, gradients <= ~10): ten terms of that size, some eps each.
    c0, c, Q = rng.normal(), rng.normal(size=3), rng.normal(size=(3, 3))
    Q = Q + Q.T
    f = lambda x: c0 + x @ c + np.einsum("pi,ij,pj->p", x, Q, x)  # noqa: E731
    grad = lambda x: c + 2 * x @ Q  # noqa: E731
    values = f(tet10_reference_nodes())
    np.testing.assert_allclose(N @ values, f(pts), rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.einsum("pai,a->pi", dN, values), grad(pts), rtol=0, atol=1e-13)


# --- one element --------------------------------------------------------------------------------


def one_element(curved=False, name="one"):
    corners = np.array([[0.0, 0.0, 0.0], [0.11, 0.01, -0.005], [0.02, 0.09, 0.01], [0.015, 0.02, 0.1]])
    nodes = np.vstack([corners, [(corners[a] + corners[b]) / 2 for a, b in TET10_EDGES]])
    if curved:  # mid-side nodes off their edges by up to 8 % of the edge
        rng = np.random.default_rng(3)
        nodes[4:] += rng.uniform(-0.008, 0.008, (6, 3))
    return TetMesh(name, nodes, np.arange(10)[None])


def barycentric_mass(volume):
    """∫ N_a N_b dV of a straight element from the barycentric integration formula."""
    # Each shape function as {exponents of (L0, L1, L2, L3): coefficient}.
    basis = []
    for c in range(4):
        sq, lin = [0] * 4, [0] * 4
        sq[c], lin[c] = 2, 1
        basis.append({tuple(sq): 2.0, tuple(lin): -1.0})
    for a, b in TET10_EDGES:
        e = [0] * 4
        e[a] += 1
        e[b] += 1
        basis.append({tuple(e): 4.0})

    def integral(exps):
        return 6.0 * volume * np.prod([factorial(k) for k in exps]) / factorial(sum(exps) + 3)

    M = np.zeros((10, 10))
    for i, Ni in enumerate(basis):
        for j, Nj in enumerate(basis):
            M[i, j] = sum(
                ci * cj * integral(tuple(p + q for p, q in zip(ei, ej, strict=True)))
                for ei, ci in Ni.items()
                for ej, cj in Nj.items()
            )
    return M


@pytest.mark.parametrize("curved", [False, True], ids=["straight", "curved"])
def test_one_element_has_the_rigid_motions_as_null_space(curved):
    mesh = one_element(curved)
    r = solid_matrices(mesh, STEEL)
    K, M = dense(r)
    norm = np.abs(K).max()
    np.testing.assert_allclose(K, K.T, rtol=0, atol=4 * EPS * norm)  # symmetric by construction
    # A rigid motion is linear in x, which an isoparametric element represents exactly: K·r is
    # round-off only - 30 terms per row, each of relative error up to ~100 eps (the Jacobian's
    # inverse, sums over the points): 3000 eps, 7e-13, of ||K||·||r||.
    R = rigid_modes(mesh.nodes)
    assert np.abs(K @ R).max() <= 1e-12 * norm * np.abs(R).max()
    lam = np.linalg.eigvalsh(K)
    # Six zero eigenvalues (round-off of a symmetric eigensolver: ~30 eps·λmax), the other 24
    # well above: the element's softest deformation mode stores energy of the order of its
    # stiffness for an element of aspect ~1 (the rigid modes' 1e-13 and this 1e-6 are 7 orders apart).
    assert np.all(np.abs(lam[:6]) <= 1e-13 * lam[-1])
    assert np.all(lam[6:] >= 1e-6 * lam[-1])
    # Mass: symmetric positive definite and the element's mass in each direction.
    np.testing.assert_allclose(M, M.T, rtol=0, atol=4 * EPS * np.abs(M).max())
    assert np.linalg.eigvalsh(M)[0] > 0
    for i in range(3):
        ones = np.zeros(30)
        ones[i::3] = 1.0
        # 900 entries summed, of either sign: some hundreds of eps of the mass.
        assert ones @ M @ ones == pytest.approx(r.mass, rel=1e-13)
    assert r.mass == pytest.approx(STEEL.rho * r.volume, rel=2 * EPS)
    if not curved:
        V = corner_volumes(mesh.nodes, mesh.tets)[0]
        assert r.volume == pytest.approx(V, rel=1e-14)  # 14 positive terms of the constant det J
        # The straight element's mass is exact with a degree-5 rule (N_a N_b is of degree 4): the
        # closed form to round-off (terms of either sign; 1e-14 of the largest entry, ~50 eps).
        expected = STEEL.rho * barycentric_mass(V)
        np.testing.assert_allclose(M[0::3, 0::3], expected, rtol=0, atol=1e-14 * expected.max())
        np.testing.assert_allclose(M[0::3, 1::3], 0.0, rtol=0, atol=0)  # directions uncoupled


# --- a small mesh -------------------------------------------------------------------------------

SIZE = (0.3, 0.2, 0.25)


def test_box_mesh_is_conforming_and_positively_oriented():
    nodes, tets = box_mesh((3, 2, 2), SIZE)
    vol = corner_volumes(nodes, tets)
    assert np.all(vol > 0)
    assert vol.sum() == pytest.approx(np.prod(SIZE), rel=1e-14)  # 72 positive terms
    # Faces match: an interior face belongs to two tetrahedra, a boundary face to one, and the
    # boundary faces cover the box's surface.
    faces = np.sort(
        np.concatenate([tets[:, f] for f in ([0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3])]), axis=1
    )
    _, counts = np.unique(faces, axis=0, return_counts=True)
    assert set(counts.tolist()) == {1, 2}
    nx, ny, nz = 3, 2, 2
    assert np.sum(counts == 1) == 2 * 2 * (nx * ny + ny * nz + nx * nz)  # two triangles per face cell
    # Mid-side nodes are at their edges' midpoints.
    for k, (a, b) in enumerate(TET10_EDGES):
        np.testing.assert_allclose(
            nodes[tets[:, 4 + k]], (nodes[tets[:, a]] + nodes[tets[:, b]]) / 2, atol=1e-15
        )


def test_small_mesh_matrices():
    nodes, tets = shaken((2, 2, 1), SIZE, corner_shift=0.08, mid_shift=0.0, seed=1)
    mesh = TetMesh("small", nodes, tets)
    r = solid_matrices(mesh, STEEL)
    assert r.K.shape == r.M.shape == (3 * mesh.n_nodes,) * 2
    r.K.check_format(full_check=True)
    r.M.check_format(full_check=True)
    K, M = dense(r)
    norm = np.abs(K).max()
    np.testing.assert_allclose(K, K.T, rtol=0, atol=4 * EPS * norm)
    lam = np.linalg.eigvalsh(K)
    # Exactly six rigid-body modes: eigvalsh's error is ~n·eps·||K|| (n = 225: 5e-14 of λmax).
    assert np.all(np.abs(lam[:6]) <= 1e-12 * lam[-1])
    assert lam[6] >= 1e-6 * lam[-1]
    R = rigid_modes(nodes)
    assert np.abs(K @ R).max() <= 1e-12 * norm * np.abs(R).max()  # as for one element
    mu = np.linalg.eigvalsh(M)
    assert mu[0] > 0
    np.testing.assert_allclose(M, M.T, rtol=0, atol=4 * EPS * np.abs(M).max())
    V = np.prod(SIZE)  # the interior moved, the box did not: straight elements fill it exactly
    assert r.volume == pytest.approx(V, rel=1e-13)
    for i in range(3):
        ones = np.zeros(K.shape[0])
        ones[i::3] = 1.0
        assert ones @ M @ ones == pytest.approx(STEEL.rho * V, rel=1e-13)


def test_assembly_is_the_sum_of_its_elements():
    # A mesh curved in one half only (its chunks mix the two rules), assembled in chunks, against
    # each element's own matrices summed by hand.
    nodes, tets = shaken((3, 2, 2), SIZE, corner_shift=0.08, mid_shift=0.0, seed=3)
    rng = np.random.default_rng(8)
    curved = np.zeros(len(nodes), bool)
    curved[tets[:, 4:]] = True
    curved &= (nodes[:, 0] < SIZE[0] / 2) & ~boundary_mask(nodes, 0.0, np.array(SIZE))
    nodes[curved] += rng.uniform(-0.003, 0.003, (curved.sum(), 3))
    which = tet10._curved(nodes[tets])
    assert 0 < which.sum() < len(tets)
    r = solid_matrices(TetMesh("half", nodes, tets), STEEL, chunk=16)
    K = np.zeros((3 * len(nodes),) * 2)
    M = np.zeros_like(K)
    for t in tets:
        Ke, Me = dense(solid_matrices(TetMesh("e", nodes[t], np.arange(10)[None]), STEEL))
        d = (3 * t[:, None] + np.arange(3)).ravel()
        K[np.ix_(d, d)] += Ke
        M[np.ix_(d, d)] += Me
    Kg, Mg = dense(r)
    # The same element matrices summed in another order: a few eps of the largest entry.
    np.testing.assert_allclose(Kg, K, rtol=0, atol=1e-14 * np.abs(K).max())
    np.testing.assert_allclose(Mg, M, rtol=0, atol=1e-14 * np.abs(M).max())


@pytest.mark.parametrize("span", [0, 10**9], ids=["touched-rows", "span"])
def test_assembly_does_not_depend_on_chunks_or_node_numbering(monkeypatch, span):
    # Both ways of summing a chunk (over its span of rows, or over the rows it touches) and any
    # chunk size give the same matrices, and renumbering the nodes permutes them.
    monkeypatch.setattr(tet10, "SPAN_PER_ELEMENT", span)
    nodes, tets = shaken((3, 2, 2), SIZE, corner_shift=0.08, mid_shift=0.03, seed=2)
    ref = solid_matrices(TetMesh("a", nodes, tets), STEEL, chunk=10**6)
    K0, M0 = dense(ref)
    perm = np.random.default_rng(5).permutation(len(nodes))  # node k becomes perm[k]
    moved = np.empty_like(nodes)
    moved[perm] = nodes
    dofs = (3 * perm[:, None] + np.arange(3)).ravel()
    for chunk in (1, 7, 1000):
        for mesh, d in (
            (TetMesh("a", nodes, tets), np.arange(3 * len(nodes))),
            (TetMesh("b", moved, perm[tets]), dofs),
        ):
            r = solid_matrices(mesh, STEEL, chunk=chunk)
            K, M = dense(r)
            # The same element matrices summed in another grouping: a few eps of the largest entry.
            np.testing.assert_allclose(K[np.ix_(d, d)], K0, rtol=0, atol=1e-14 * np.abs(K0).max())
            np.testing.assert_allclose(M[np.ix_(d, d)], M0, rtol=0, atol=1e-14 * np.abs(M0).max())
            assert r.volume == pytest.approx(ref.volume, rel=1e-14)
            # statics' K alone: the same K, entry for entry (the same sums in the same order), no M
            alone = solid_matrices(mesh, STEEL, chunk=chunk, mass=False)
            assert alone.M is None and alone.volume == r.volume
            assert (alone.K != r.K).nnz == 0


# --- patch tests --------------------------------------------------------------------------------


@pytest.mark.parametrize("mid_shift", [0.0, 0.05], ids=["straight", "curved"])
def test_linear_patch_test(mid_shift):
    # Any isoparametric element reproduces a linear field: prescribed on the boundary, it is the
    # solution inside, on distorted and curved elements alike.
    nodes, tets = shaken((3, 3, 3), (1.0, 0.8, 1.2), corner_shift=0.08, mid_shift=mid_shift, seed=11)
    K, _ = dense(solid_matrices(TetMesh("patch", nodes, tets), STEEL))
    rng = np.random.default_rng(4)
    A, c = rng.normal(scale=1e-3, size=(3, 3)), rng.normal(scale=1e-3, size=3)
    exact = (nodes @ A.T + c).ravel()
    on_boundary = boundary_mask(nodes, 0.0, np.array([1.0, 0.8, 1.2]))
    fixed = (3 * np.flatnonzero(on_boundary)[:, None] + np.arange(3)).ravel()
    u, cond = dirichlet_solve(K, np.zeros(K.shape[0]), fixed, exact[fixed])
    # A backward-stable solve: relative error <= cond·(a small multiple of eps); 10 cond eps here.
    assert np.abs(u - exact).max() <= 10 * cond * EPS * np.abs(exact).max()


def test_quadratic_patch_test_with_its_body_force():
    # On straight elements (an affine map per element) P2 holds every quadratic field. The one
    # chosen, u_i = ½ xᵀH_i x + (A x)_i, has a constant stress divergence, so a constant body force
    # b = −div σ balances it; its consistent load ∫ N_a b is M b / ρ (the mass with ρ = 1, exact
    # with the degree-5 rule). With u prescribed on the boundary, u is then the solution.
    size = np.array([1.0, 0.8, 1.2])
    nodes, tets = shaken((3, 3, 3), size, corner_shift=0.08, mid_shift=0.0, seed=12)
    r = solid_matrices(TetMesh("patch", nodes, tets), STEEL)
    K, M = dense(r)
    rng = np.random.default_rng(9)
    H = rng.normal(scale=1e-3, size=(3, 3, 3))
    H = H + H.transpose(0, 2, 1)  # H[i] symmetric: the Hessian of u_i
    A = rng.normal(scale=1e-3, size=(3, 3))
    exact = (0.5 * np.einsum("pj,ijk,pk->pi", nodes, H, nodes) + nodes @ A.T).ravel()
    E, nu = STEEL.E, STEEL.nu
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    # ∂_j σ_ij = λ ∂_i div u + μ (Δu_i + ∂_i div u) with ∂_j ∂_k u_i = H[i, j, k].
    grad_div = np.einsum("kik->i", H)
    lap = np.einsum("ijj->i", H)
    b = -((lam + mu) * grad_div + mu * lap)
    f = M @ np.tile(b, len(nodes)) / STEEL.rho
    on_boundary = boundary_mask(nodes, 0.0, size)
    fixed = (3 * np.flatnonzero(on_boundary)[:, None] + np.arange(3)).ravel()
    u, cond = dirichlet_solve(K, f, fixed, exact[fixed])
    assert np.abs(u - exact).max() <= 10 * cond * EPS * np.abs(exact).max()  # as for the linear test


# --- a bar in tension ---------------------------------------------------------------------------


def tri6_faces_on(nodes, tets, axis, value):
    """The 6-node boundary triangles of the tetrahedra lying in the plane x_axis = value."""
    faces = []
    edge_of = {frozenset(e): 4 + k for k, e in enumerate(TET10_EDGES)}
    for corners in ([0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]):
        on = np.all(np.isclose(nodes[tets[:, corners], axis], value, rtol=0, atol=1e-12), axis=1)
        mids = [
            edge_of[frozenset(p)]
            for p in ((corners[0], corners[1]), (corners[1], corners[2]), (corners[2], corners[0]))
        ]
        faces.append(tets[on][:, corners + mids])
    return np.concatenate(faces)


def test_bar_in_tension_has_the_axial_stiffness_EA_over_L():
    L, a, b = 0.5, 0.1, 0.08
    nodes, tets = box_mesh((4, 2, 2), (L, a, b))
    K, _ = dense(solid_matrices(TetMesh("bar", nodes, tets), STEEL))
    # Uniform traction p on x = L: a straight 6-node triangle's consistent loads are 0 at the
    # corners and A/3 at each mid-side node (∫ L(2L − 1) dA = 0, ∫ 4 L_a L_b dA = A/3).
    p = 1e6
    f = np.zeros(K.shape[0])
    for tri in tri6_faces_on(nodes, tets, 0, L):
        y, z = nodes[tri[:3], 1], nodes[tri[:3], 2]
        area = 0.5 * abs((y[1] - y[0]) * (z[2] - z[0]) - (y[2] - y[0]) * (z[1] - z[0]))
        f[3 * tri[3:]] += p * area / 3
    assert f.sum() == pytest.approx(p * a * b, rel=1e-14)
    # Rollers: u_x = 0 on x = 0, u_y = 0 on y = 0, u_z = 0 on z = 0 (frictionless symmetry planes).
    fixed = np.concatenate([3 * np.flatnonzero(np.isclose(nodes[:, i], 0.0)) + i for i in range(3)])
    u, cond = dirichlet_solve(K, f, fixed, np.zeros(fixed.size))
    # The exact field is linear, u = (σx/E, −νσy/E, −νσz/E): the elements hold it, so it is the
    # solution to round-off (10 cond eps, as in the patch tests).
    sigma, E, nu = p, STEEL.E, STEEL.nu
    exact = np.column_stack(
        [sigma * nodes[:, 0] / E, -nu * sigma * nodes[:, 1] / E, -nu * sigma * nodes[:, 2] / E]
    )
    assert np.abs(u - exact.ravel()).max() <= 10 * cond * EPS * np.abs(exact).max()
    end = np.isclose(nodes[:, 0], L)
    stiffness = p * a * b / u[3 * np.flatnonzero(end)].mean()
    assert stiffness == pytest.approx(E * a * b / L, rel=10 * cond * EPS)


# --- Saint-Venant torsion: convergence ------------------------------------------------------------


def square_torsion_constant(a):
    """J of a square of side a (Timoshenko & Goodier §109): a⁴ [1/3 − 64/π⁵ Σ_odd tanh(nπ/2)/n⁵]."""
    series = sum(tanh(n * pi / 2) / n**5 for n in range(1, 200, 2))  # terms fall as n⁻⁵: 1e-12 at 200
    return a**4 * (1 / 3 - 64 / pi**5 * series)


def torsion_stiffness_of_slab(n, a=0.1):
    """Torsional stiffness of a square bar of side a, one layer of n x n cubic cells long.

    Twist θ about the section's centre line imposed on the end faces' in-plane displacements
    (u_y = u_z = 0 at x = 0; u_y = −θ z, u_z = θ y at x = L), axial displacement free (one node
    holds the rigid axial motion): Saint-Venant's solution - warping u_x = θ' ψ(y, z), free at the
    ends - is then the exact elastic one, of energy ½ (G J / L) θ².
    """
    L = a / n
    nodes, tets = box_mesh((1, n, n), (L, a, a), origin=(0.0, -a / 2, -a / 2))
    K = solid_matrices(TetMesh("slab", nodes, tets), STEEL).K.tocsc()
    theta = 1e-3
    start, end = np.flatnonzero(np.isclose(nodes[:, 0], 0.0)), np.flatnonzero(np.isclose(nodes[:, 0], L))
    centre = start[np.argmin(np.abs(nodes[start, 1]) + np.abs(nodes[start, 2]))]
    fixed = np.concatenate([3 * start + 1, 3 * start + 2, 3 * end + 1, 3 * end + 2, [3 * centre]])
    values = np.concatenate([np.zeros(2 * start.size), -theta * nodes[end, 2], theta * nodes[end, 1], [0.0]])
    u = np.zeros(K.shape[0])
    u[fixed] = values
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    u[free] = spla.spsolve(K[free][:, free], -(K[free][:, fixed] @ values))
    return (u @ (K @ u)) / theta**2, STEEL.G * square_torsion_constant(a) / L


def test_torsion_of_a_square_bar_converges_from_above_at_the_elements_rate():
    errors = []
    for n in (4, 8, 16):
        k, exact = torsion_stiffness_of_slab(n)
        errors.append(k / exact - 1)
    # The finite-element solution minimises the energy over fewer fields with the same end
    # conditions (exactly representable, linear), so it is stiffer than the continuum.
    assert all(e > 0 for e in errors)
    # P2 elements: the energy error falls as h^(2p) = h⁴ for a smooth warping function. At the
    # square's corners the torsion solution has r² log r terms (the Prandtl problem's resonance
    # at a right angle), which cost logarithms: e ∝ h⁴ logᵏ(1/h) with k <= 2 has, from h = a/8
    # to a/16, the local rate 4 − k·log2(log 16 / log 8), between 3.17 (k = 2) and 4; it rises
    # towards 4 as the mesh is refined.
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert 3.17 <= rates[-1] <= 4.2, rates
    assert rates[-1] > rates[0], rates
    assert errors[-1] < 1e-4  # 16 x 16 cells: the stiffness to 0.01 %


# --- curved elements ----------------------------------------------------------------------------


def duffy_volume(nodes10, order=8):
    """∫ det J over the reference tetrahedron by a Gauss-Legendre product rule on the cube,
    collapsed onto the tetrahedron (ξ = u, η = (1 − u) v, ζ = (1 − u)(1 − v) w, Jacobian
    (1 − u)² (1 − v)): exact for the cubic det J of a quadratic map, independent of the module's
    rules."""
    g, w = np.polynomial.legendre.leggauss(order)
    g, w = (g + 1) / 2, w / 2
    U, V, W = np.meshgrid(g, g, g, indexing="ij")
    weight = (w[:, None, None] * w[None, :, None] * w[None, None, :]) * (1 - U) ** 2 * (1 - V)
    xi = np.column_stack([U.ravel(), ((1 - U) * V).ravel(), ((1 - U) * (1 - V) * W).ravel()])
    _, dN = tet10_shape(xi)
    J = np.einsum("ai,paj->pij", nodes10, dN)
    return np.sum(weight.ravel() * np.linalg.det(J))


def test_curved_element_volume_and_mass():
    # An octant of a sphere of radius R in one element: corners at the centre and on the three
    # axes, the three mid-side nodes between the surface corners moved onto the sphere.
    R = 0.05
    corners = np.array([[0.0, 0.0, 0.0], [R, 0.0, 0.0], [0.0, R, 0.0], [0.0, 0.0, R]])
    nodes = np.vstack([corners, [(corners[a] + corners[b]) / 2 for a, b in TET10_EDGES]])
    for k, (a, b) in enumerate(TET10_EDGES):
        if 0 not in (a, b):
            nodes[4 + k] *= R / np.linalg.norm(nodes[4 + k])
    r = solid_matrices(TetMesh("octant", nodes, np.arange(10)[None]), STEEL)
    reference = duffy_volume(nodes)
    # Both rules are exact for the cubic det J: equal to the roundings of their sums (1e-14).
    assert r.volume == pytest.approx(reference, rel=1e-14)
    # Sanity of the map: more than the straight tetrahedron, less than the true octant.
    assert R**3 / 6 < r.volume < pi * R**3 / 6
    M = r.M.toarray()
    ones = np.zeros(30)
    ones[0::3] = 1.0
    assert ones @ M @ ones == pytest.approx(STEEL.rho * reference, rel=1e-13)  # as for one element


def test_an_element_folded_by_its_mid_side_node_is_refused():
    # Two elements sharing a face; the second one's mid-side node on its edge 0-1 pushed across the
    # element: the corners stay positively oriented (the mesh is accepted), det J does not.
    nodes, tets = box_mesh((1, 1, 1), (1.0, 1.0, 1.0))
    tets = tets[:2]
    used, tets = np.unique(tets, return_inverse=True)
    nodes, tets = nodes[used], tets.reshape(2, 10)
    a, b = nodes[tets[1, 0]], nodes[tets[1, 1]]
    other = nodes[tets[1, 2:4]].mean(axis=0)
    mild = nodes.copy()
    mild[tets[1, 4]] += 0.1 * (other - (a + b) / 2)  # a slightly curved edge: accepted
    solid_matrices(TetMesh("mild", mild, tets), STEEL)
    folded = nodes.copy()
    folded[tets[1, 4]] += 1.5 * (other - (a + b) / 2)
    with pytest.raises(ModelError, match=r"mesh of 'folded'\.tets.*tetrahedron 1 has a Jacobian determinant"):
        solid_matrices(TetMesh("folded", folded, tets), STEEL)


# --- bad input ----------------------------------------------------------------------------------


def test_bad_input_is_refused():
    mesh = one_element()
    # The material's own checks refuse a bad material before any element is built.
    with pytest.raises(ModelError, match="E = -1"):
        solid_matrices(mesh, Material(E=-1.0, nu=0.3, rho=7850.0))
    with pytest.raises(ModelError, match="nu = 0.5"):
        solid_matrices(mesh, Material(E=210e9, nu=0.5, rho=7850.0))
    with pytest.raises(ModelError, match="material: is a dict"):
        solid_matrices(mesh, {"E": 210e9, "nu": 0.3, "rho": 7850.0})
    with pytest.raises(ModelError, match="mesh: is a tuple"):
        solid_matrices((mesh.nodes, mesh.tets), STEEL)
    with pytest.raises(ModelError, match="chunk = 0"):
        solid_matrices(mesh, STEEL, chunk=0)
    assert getattr(solid_matrices, "__flexshaft_thread_policy__", False)


def test_a_mesh_beyond_the_ceiling_is_refused_before_assembly(monkeypatch):
    # the ceiling counts DOFs, three a node; FLEXSHAFT_MAX_SOLID_DOFS sets it for one run
    nodes, tets = box_mesh(np.array((1, 1, 1)), (1.0, 1.0, 1.0))
    monkeypatch.setenv("FLEXSHAFT_MAX_SOLID_DOFS", str(3 * len(nodes) - 1))
    with pytest.raises(ModelError, match="FLEXSHAFT_MAX_SOLID_DOFS") as e:
        solid_matrices(TetMesh("cube", nodes, tets), STEEL)
    assert e.value.field == "mesh of 'cube'" and f"has {3 * len(nodes)} DOFs" in str(e.value)
    monkeypatch.setenv("FLEXSHAFT_MAX_SOLID_DOFS", str(3 * len(nodes)))
    assert solid_matrices(TetMesh("cube", nodes, tets), STEEL).n_dofs == 3 * len(nodes)
