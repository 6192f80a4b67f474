"""The 10-node isoparametric tetrahedron for linear isotropic elasticity, assembled over a mesh.

A :class:`~flexshaft.elements.tetmesh.TetMesh`'s elements are quadratic tetrahedra in VTK's
``QUADRATIC_TETRA`` order (corners 0-3, then the mid-side nodes of the edges 0-1, 1-2, 0-2, 0-3,
1-3, 2-3). On the reference tetrahedron ξ, η, ζ >= 0, ξ + η + ζ <= 1 with the barycentric
coordinates L0 = 1 − ξ − η − ζ, L1 = ξ, L2 = η, L3 = ζ, the shape functions are

- corner c:            N_c = L_c (2 L_c − 1)
- mid-side of (a, b):  N = 4 L_a L_b

and the map x(ξ) = Σ N_a x_a uses the same functions (isoparametric): a mid-side node off its
edge's midpoint curves the element. The Jacobian J = ∂x/∂ξ is formed at every quadrature point
from all ten nodes, and an element whose det J is not positive at one of them is refused.

With the Lamé constants λ = E ν / ((1 + ν)(1 − 2ν)) and μ = G, the stiffness between node a's
DOF i and node b's DOF j is

    K_ai,bj = ∫ λ ∂_i N_a ∂_j N_b + μ ∂_j N_a ∂_i N_b + μ δ_ij ∇N_a · ∇N_b dV,

integrated for a straight element with a 4-point degree-2 rule (exact: det J is constant and ∂N
linear), for a curved one with Walkington's 14-point degree-5 rule (which integrates ∫ ∇N_a dV
exactly, cof(J)ᵀ ∇_ξ N_a being a cubic: curved elements pass the patch test too); the consistent
mass ρ ∫ N_a N_b dV δ_ij with the 14-point rule (exact for a straight element's degree-4
integrand). The volume is Σ w det J with the same
14-point rule, which is exact also for a curved element (det J is a cubic), so the mass matrix
carries exactly ρ times the volume in each direction.

The global DOFs are node-major: node k's ux, uy, uz are 3k, 3k + 1, 3k + 2.

Assembly runs over chunks of elements, each chunk's entries summed into the final CSR arrays
(the matrices' sparsity is the node graph's, computed once): a million DOFs (230 000 tetrahedra)
never hold all 207 million element entries at once, which :class:`flexshaft.linalg.Triplets`
would (3.3 GB of blocks, and as much again to sort them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..system.limits import check_ceiling
from ..system.threads import follows_policy
from ..validation import check_int, check_type
from .materials import Material
from .tetmesh import TET10_EDGES, TetMesh

__all__ = [
    "TetRule",
    "TET4_RULE",
    "TET14_RULE",
    "tet10_shape",
    "tet10_reference_nodes",
    "SolidMatrices",
    "solid_matrices",
    "DEFAULT_CHUNK",
]

#: Elements per assembly chunk. A chunk's temporaries (Jacobians, gradients, strain matrices, the
#: element stiffness and its int64 targets) are about 17 kB per straight element and 40 kB per
#: curved one (its 14 points), measured with tracemalloc: 4096 elements hold 70 to 165 MB.
DEFAULT_CHUNK = 4096

# ∂(L0, L1, L2, L3)/∂(ξ, η, ζ): the barycentric coordinates' derivatives, (4, 3).
_DL_DXI = np.array([[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class TetRule:
    """A quadrature rule on the reference tetrahedron (volume 1/6).

    Attributes
    ----------
    points : ndarray, shape (q, 3)
        Natural coordinates (ξ, η, ζ) of the points, inside the tetrahedron.
    weights : ndarray, shape (q,)
        Positive weights, summing to 1/6.
    degree : int
        Every polynomial of this total degree is integrated exactly.
    source : str
        Where the rule is published.
    """

    points: np.ndarray
    weights: np.ndarray
    degree: int
    source: str


def _orbits(groups) -> tuple[np.ndarray, np.ndarray]:
    """Points (ξ, η, ζ) and weights of symmetric orbits given as (kind, a, weight) in barycentrics.

    ``s31``: the 4 points with three barycentric coordinates a and one 1 − 3a; ``s22``: the 6
    points with two coordinates a and two 1/2 − a.
    """
    points, weights = [], []
    for kind, a, w in groups:
        if kind == "s31":
            bary = [np.where(np.arange(4) == k, 1.0 - 3.0 * a, a) for k in range(4)]
        else:
            bary = [np.where(np.isin(np.arange(4), pair), 0.5 - a, a) for pair in TET10_EDGES]
        points += [b[1:] for b in bary]
        weights += [w] * len(bary)
    return np.array(points), np.array(weights)


def _rule(groups, degree: int, source: str) -> TetRule:
    points, weights = _orbits(groups)
    points.setflags(write=False)
    weights.setflags(write=False)
    return TetRule(points, weights, degree, source)


#: The 4-point degree-2 rule (a = (5 − √5)/20, weights 1/24): the stiffness's of straight elements.
TET4_RULE = _rule(
    [("s31", (5.0 - np.sqrt(5.0)) / 20.0, 1.0 / 24.0)],
    2,
    "P. C. Hammer, O. J. Marlowe, A. H. Stroud, 'Numerical integration over simplexes and cones', "
    "Math. Tables Aids Comput. 10 (1956) 130-137; also in P. Keast, Comput. Methods Appl. Mech. "
    "Eng. 55 (1986) 339-348",
)
#: Walkington's 14-point degree-5 rule, all weights positive: the mass's, the volume's and the
#: stiffness's of curved elements.
TET14_RULE = _rule(
    [
        ("s31", 0.31088591926330060980, 0.018781320953002641800),
        ("s31", 0.092735250310891226402, 0.012248840519393658257),
        ("s22", 0.045503704125649649492, 0.0070910034628469110730),
    ],
    5,
    "N. J. Walkington, 'Quadrature on simplices of arbitrary dimension', CNA report 00-CNA-023, "
    "Carnegie Mellon University (2000), the 14-point rule p5; the same rule is F. D. Witherden, "
    "P. E. Vincent, Comput. Math. Appl. 69 (2015) 1232-1241",
)


def tet10_shape(points) -> tuple[np.ndarray, np.ndarray]:
    """The 10-node tetrahedron's shape functions and their derivatives at reference points.

    Parameters
    ----------
    points : array_like, shape (p, 3)
        Natural coordinates (ξ, η, ζ) on the reference tetrahedron.

    Returns
    -------
    N : ndarray, shape (p, 10)
        The shape functions, VTK node order.
    dN : ndarray, shape (p, 10, 3)
        Their derivatives ∂N/∂(ξ, η, ζ).
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    L = np.column_stack([1.0 - p.sum(axis=1), p])  # (p, 4) barycentric coordinates
    N = np.empty((p.shape[0], 10))
    dN_dL = np.zeros((p.shape[0], 10, 4))
    for c in range(4):
        N[:, c] = L[:, c] * (2.0 * L[:, c] - 1.0)
        dN_dL[:, c, c] = 4.0 * L[:, c] - 1.0
    for k, (a, b) in enumerate(TET10_EDGES):
        N[:, 4 + k] = 4.0 * L[:, a] * L[:, b]
        dN_dL[:, 4 + k, a] = 4.0 * L[:, b]
        dN_dL[:, 4 + k, b] = 4.0 * L[:, a]
    return N, dN_dL @ _DL_DXI


def tet10_reference_nodes() -> np.ndarray:
    """The ten nodes' natural coordinates (ξ, η, ζ) on the reference tetrahedron, shape (10, 3)."""
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    mids = np.array([(corners[a] + corners[b]) / 2.0 for a, b in TET10_EDGES])
    return np.vstack([corners, mids])


_N4, _DN4 = tet10_shape(TET4_RULE.points)
_N14, _DN14 = tet10_shape(TET14_RULE.points)


@dataclass(frozen=True)
class SolidMatrices:
    """Stiffness and consistent mass of a solid mesh of 10-node tetrahedra (SI).

    Attributes
    ----------
    K : scipy.sparse.csr_array, shape (3n, 3n)
        Stiffness, N/m; symmetric, positive semi-definite with the six rigid-body motions as its
        null space. DOFs node-major (node k's ux, uy, uz at 3k, 3k + 1, 3k + 2); sorted indices.
    M : scipy.sparse.csr_array, shape (3n, 3n), or None
        Consistent mass, kg; symmetric positive definite, same DOFs. It couples only like
        directions, and stores only those entries. None when assembled without it (statics).
    volume : float
        The mesh's volume Σ w det J, m³ (exact for curved elements too: det J is a cubic).
    mass : float
        ρ · volume, kg: what M carries in each direction (1ᵀ M_x 1).
    """

    K: sp.csr_array
    M: sp.csr_array | None
    volume: float
    mass: float

    @property
    def n_dofs(self) -> int:
        """Number of DOFs, 3 per node."""
        return int(self.K.shape[0])


def _det_inv(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Determinants and inverses of stacked 3 x 3 matrices (cofactors: no LAPACK call per matrix)."""
    a, b, c = J[..., 0, 0], J[..., 0, 1], J[..., 0, 2]
    d, e, f = J[..., 1, 0], J[..., 1, 1], J[..., 1, 2]
    g, h, i = J[..., 2, 0], J[..., 2, 1], J[..., 2, 2]
    co = np.empty_like(J)
    co[..., 0, 0] = e * i - f * h
    co[..., 0, 1] = c * h - b * i
    co[..., 0, 2] = b * f - c * e
    co[..., 1, 0] = f * g - d * i
    co[..., 1, 1] = a * i - c * g
    co[..., 1, 2] = c * d - a * f
    co[..., 2, 0] = d * h - e * g
    co[..., 2, 1] = b * g - a * h
    co[..., 2, 2] = a * e - b * d
    det = a * co[..., 0, 0] + b * co[..., 1, 0] + c * co[..., 2, 0]
    with np.errstate(divide="ignore", invalid="ignore"):  # a det of 0 is refused by the caller
        inv = co / det[..., None, None]
    return det, inv


def _det(J: np.ndarray) -> np.ndarray:
    """Determinants of stacked 3 x 3 matrices."""
    return (
        J[..., 0, 0] * (J[..., 1, 1] * J[..., 2, 2] - J[..., 1, 2] * J[..., 2, 1])
        - J[..., 0, 1] * (J[..., 1, 0] * J[..., 2, 2] - J[..., 1, 2] * J[..., 2, 0])
        + J[..., 0, 2] * (J[..., 1, 0] * J[..., 2, 1] - J[..., 1, 1] * J[..., 2, 0])
    )


def _refuse_inverted(mesh: TetMesh, start: int, dets: list[np.ndarray]) -> None:
    bad = np.zeros(dets[0].shape[0], dtype=bool)
    for d in dets:
        bad |= ~(d > 0).all(axis=1)  # also catches nan
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        worst = min(float(np.min(d[k])) for d in dets)
        raise ModelError(
            f"tetrahedron {start + k} has a Jacobian determinant {worst:.3g} <= 0 at a quadrature "
            "point (a mid-side node too far from its edge's midpoint folds the element)",
            field=f"mesh of {mesh.name!r}.tets",
            valid="10-node tetrahedra whose det J is positive throughout (mid-side nodes near their edges)",
            has_value=False,
        )


# Both rules' ∂N/∂ξ side by side, (10, 3·(4 + 14)): one matrix product gives every Jacobian.
_DN_BOTH = np.concatenate([_DN4, _DN14]).transpose(1, 0, 2).reshape(10, -1)


def _upper_of(k: int) -> np.ndarray:
    """For each entry (r, s) of a k x k matrix, flattened, the flat index of (min, max)."""
    r = np.arange(k)
    return (np.minimum.outer(r, r) * k + np.maximum.outer(r, r)).ravel()


# The 14-point rule's N_a N_b for a <= b (55 pairs), and where each of the 100 pairs (a, b) finds
# its own: the element mass is computed once per pair, so it is symmetric to the last bit.
_UPPER10 = np.flatnonzero((np.arange(10)[:, None] <= np.arange(10)[None, :]).ravel())
_SYM10 = np.searchsorted(_UPPER10, _upper_of(10))
_NN14 = (_N14[:, :, None] * _N14[:, None, :]).reshape(14, 100)[:, _UPPER10]
# For each of the 900 entries (r, s) of an element stiffness, the entry (min, max) of its upper
# triangle: reading the matrix product through it makes the element stiffness exactly symmetric.
_SYM30 = _upper_of(30)
# ... listed in the order (j, a, i, b) of the assembly (entry (a, i) x (b, j) of the element).
_JAIB = np.arange(900).reshape(10, 3, 10, 3).transpose(3, 0, 1, 2).ravel()
_SYM30_JAIB = _SYM30[_JAIB]


def _elasticity(lam: float, mu: float) -> np.ndarray:
    """The isotropic elasticity matrix D in Voigt order (xx, yy, zz, xy, yz, xz; engineering shear), Pa."""
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[[0, 1, 2], [0, 1, 2]] += 2.0 * mu
    D[[3, 4, 5], [3, 4, 5]] = mu
    return D


#: An element counts as curved when one of its mid-side nodes is off its edge's midpoint by more
#: than this fraction of its longest corner edge (a mesher's midpoint is (a + b)/2 to round-off).
CURVED_TOLERANCE = 1e-10
_VOIGT = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))  # xx, yy, zz, xy, yz, xz


def _curved(X: np.ndarray) -> np.ndarray:
    """Which elements of a chunk (node coordinates X (E, 10, 3)) are curved, (E,) bool."""
    ends = np.array(TET10_EDGES)
    mid = 0.5 * (X[:, ends[:, 0]] + X[:, ends[:, 1]])  # (E, 6, 3)
    off = np.abs(X[:, 4:] - mid).max(axis=(1, 2))
    edge = np.abs(X[:, ends[:, 0]] - X[:, ends[:, 1]]).max(axis=(1, 2))
    return off > CURVED_TOLERANCE * edge


def _stiffness(g: np.ndarray, wdet: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Σ_q w det J Bᵀ D B from the shape functions' gradients g (E, q, 10, 3) and w det J (E, q):
    (E, 30, 30), DOF a·3 + i. Over groups of at most four points, so the strain matrices of a
    14-point rule take no more memory than the 4-point rule's."""
    E, q = wdet.shape
    K = None
    for s in range(0, q, 4):
        gq = g[:, s : s + 4]
        nq = gq.shape[1]
        B = np.zeros((E, nq, 6, 10, 3))  # strain-displacement matrices, Voigt order
        for row, (i, j) in enumerate(_VOIGT):
            B[:, :, row, :, i] = gq[..., j]
            B[:, :, row, :, j] = gq[..., i]
        B = B.reshape(E, nq, 6, 30)
        DB = np.matmul(D, B)
        DB *= wdet[:, s : s + 4, None, None]
        part = np.matmul(B.reshape(E, 6 * nq, 30).transpose(0, 2, 1), DB.reshape(E, 6 * nq, 30))
        if K is None:
            K = part
        else:
            K += part
    return K


def _element_matrices(X: np.ndarray, D: np.ndarray, rho: float):
    """A chunk's element matrices from its node coordinates X (E, 10, 3).

    The stiffness of a straight element takes the 4-point rule, exact for it; a curved element's
    the 14-point rule, which integrates ∫ ∇N_a dV exactly (cof(J)ᵀ ∇_ξ N_a is a cubic), so that a
    mesh of curved elements passes the patch test too (the 4-point rule misses it by the
    curvature: 7e-5 of a linear field on a mesh with mid-side nodes 5 % of an edge off).

    Returns the stiffness (E, 3, 10, 3, 10) - entry (a, i) x (b, j) at [e, j, a, i, b], the order
    of the assembly - the scalar mass ρ ∫ N_a N_b (E, 10, 10), and det J at both rules' points,
    (E, 4) and (E, 14).
    """
    E = X.shape[0]
    # J_ij = Σ_a x_a,i ∂N_a/∂ξ_j at all 18 points, as one (3E x 10) @ (10 x 54) product.
    Xt = np.ascontiguousarray(X.transpose(0, 2, 1)).reshape(3 * E, 10)
    J = (Xt @ _DN_BOTH).reshape(E, 3, 18, 3).transpose(0, 2, 1, 3)
    det4 = _det(J[:, :4])
    det14 = _det(J[:, 4:])
    curved = _curved(X)
    K = np.empty((E, 30, 30)) if curved.any() and not curved.all() else None
    for which, points, dN, rule in (
        (~curved, slice(0, 4), _DN4, TET4_RULE),
        (curved, slice(4, 18), _DN14, TET14_RULE),
    ):
        if not which.any():
            continue
        sel = slice(None) if which.all() else np.flatnonzero(which)
        det, inv = _det_inv(J[sel, points])
        g = np.matmul(dN[None], inv)  # ∂N_a/∂x_i = Σ_j ∂N_a/∂ξ_j (J⁻¹)_ji, (E', q, 10, 3)
        if which.all():
            K = _stiffness(g, rule.weights * det, D)
        else:
            K[sel] = _stiffness(g, rule.weights * det, D)
    K = np.take(K.reshape(E, 900), _SYM30_JAIB, axis=1).reshape(E, 3, 10, 3, 10)
    Me = ((rho * TET14_RULE.weights) * det14) @ _NN14  # (E, 55)
    Me = np.take(Me, _SYM10, axis=1).reshape(E, 10, 10)
    return K, Me, det4, det14


def _node_graph(tets: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The node graph's CSR structure (indptr and indices, int64, indices sorted in each row): the
    node pairs that share an element, from the element-node incidence T as Tᵀ T."""
    m = tets.shape[0]
    # int32 counts: an int8 count could wrap to 0 where many elements share a node, and scipy's
    # product drops the zeros it computes.
    T = sp.csr_array(
        (np.ones(m * 10, dtype=np.int32), tets.ravel(), np.arange(0, 10 * m + 1, 10)), shape=(m, n)
    )
    G = (T.T @ T).tocsr()
    G.sort_indices()
    return G.indptr.astype(np.int64), G.indices.astype(np.int64)


def _structures(indptr: np.ndarray, indices: np.ndarray, n: int):
    """CSR structures (indptr, indices) of M and K on the 3n DOFs from the node graph's.

    M couples like directions only: row 3a + i holds column 3b + i for each neighbour b of node a,
    in order, at 3·indptr[a] + i·len(a) + k (k: b's place among a's neighbours). K has full 3 x 3
    blocks: row 3a + i holds 3b, 3b + 1, 3b + 2 for each neighbour b, which is M's entry at p
    widened to the three entries 3p, 3p + 1, 3p + 2.
    """
    nnz = int(indptr[-1])
    idx = np.int32 if 9 * nnz < 2**31 and 3 * n < 2**31 else np.int64
    row_len = np.diff(indptr)
    m_indptr = np.concatenate([[0], np.cumsum(np.repeat(row_len, 3))])
    m_indices = np.empty(3 * nnz, dtype=idx)
    row_of = np.repeat(np.arange(n, dtype=np.int64), row_len)
    base = 2 * indptr[row_of] + np.arange(nnz, dtype=np.int64)  # 3·indptr[a] + k
    step = row_len[row_of]
    del row_of
    for i in range(3):
        m_indices[base + i * step] = 3 * indices + i
    del base, step
    k_indices = (m_indices - m_indices % 3)[:, None] + np.arange(3, dtype=idx)
    return (m_indptr.astype(idx), m_indices), ((3 * m_indptr).astype(idx), k_indices.reshape(-1))


#: A chunk whose node rows span at most this many node pairs per element is summed over that span
#: directly (a bincount and a slice); a wider one (a node numbering of large bandwidth) over the
#: rows it touches only, then scattered (slower per entry: about 20 ns against 2).
SPAN_PER_ELEMENT = 200


def _chunk_places(t: np.ndarray, row_len: np.ndarray, indptr: np.ndarray, keys: np.ndarray, n: int):
    """Where a chunk's element entries go, in a local accumulator laid out as M's data.

    Node row a owns 3·len(a) consecutive entries of M's data from 3·indptr[a] (its three DOF rows
    one after the other; _structures); the accumulator holds either the span of rows from the
    chunk's smallest node to its largest (where that span is narrow: the usual case) or just the
    rows it touches, so its size is the chunk's own, whatever the node numbering's bandwidth.

    Returns
    -------
    T : ndarray of int64, shape (E, 10, 3, 10)
        The accumulator place of each element entry (a, i, b); K's entry (a, i, b, j) is 3T + j.
    size : int
        The accumulator's size.
    where : slice or ndarray of int64
        Where the accumulator goes in M's data: a slice, or each entry's place.
    """
    lo_row, hi_row = int(t.min()), int(t.max()) + 1
    lo, hi = int(indptr[lo_row]), int(indptr[hi_row])
    if hi - lo <= SPAN_PER_ELEMENT * t.shape[0]:
        span_keys = keys[lo:hi]
        begin = indptr[t] - lo  # (E, 10): where node row a starts in the span, node-level
        where = slice(3 * lo, 3 * hi)
        size = 3 * (hi - lo)
    else:
        touched, inverse = np.unique(t, return_inverse=True)
        seg = row_len[touched]
        offset = np.concatenate([[0], np.cumsum(seg)])
        span_keys = keys[np.repeat(indptr[touched] - offset[:-1], seg) + np.arange(offset[-1])]
        begin = offset[:-1][inverse.reshape(t.shape)]
        where = np.repeat(3 * (indptr[touched] - offset[:-1]), 3 * seg) + np.arange(3 * offset[-1])
        size = 3 * int(offset[-1])
    # The node-level place of each pair (a, b), a search among the accumulator's rows only.
    place = np.searchsorted(span_keys, t[:, :, None] * n + t[:, None, :])  # (E, 10, 10)
    # M's layout: 3·begin(a) + i·len(a) + k, with k = place − begin(a) b's rank among a's neighbours.
    T = (2 * begin[:, :, None] + row_len[t][:, :, None] * np.arange(3))[:, :, :, None] + place[:, :, None, :]
    return T, size, where


@follows_policy
def solid_matrices(
    mesh: TetMesh, material: Material, *, chunk: int = DEFAULT_CHUNK, mass: bool = True
) -> SolidMatrices:
    """Stiffness and consistent mass of a mesh of 10-node tetrahedra (module docstring: the element).

    Parameters
    ----------
    mesh : TetMesh
        The solid's mesh, nodes in m.
    material : Material
        Isotropic linear elastic material: E (Pa), ν, ρ (kg/m³).
    chunk : int, keyword-only
        Elements per assembly chunk, >= 1: bounds the temporaries at about 17 kB per straight
        element and 40 kB per curved one (:data:`DEFAULT_CHUNK`, 4096: 70 to 165 MB). The result
        does not depend on it beyond round-off.
    mass : bool, keyword-only
        Assemble the consistent mass too (default). False leaves ``M`` None: a static solve (the
        twist test) needs K alone, and M's accumulation is about a quarter of the assembly's time
        and a quarter of its result's memory.

    Returns
    -------
    SolidMatrices
        K (N/m) and M (kg) as CSR on the node-major DOFs (ux, uy, uz per node), the volume (m³) and
        the mass (kg).

    Raises
    ------
    ModelError
        ``mesh`` is not a TetMesh, ``material`` not a Material, ``chunk`` not an integer >= 1, or
        an element's Jacobian determinant is not positive at one of its quadrature points (the
        message names the element and the mesh).

    Notes
    -----
    Memory: besides the chunk, the node graph (indptr and indices, 16 bytes per node pair) and
    the results - K 12 bytes per entry (9 per node pair) and M 12 bytes per entry (3 per node
    pair). A box of 985 527 DOFs (235 824 elements, 9.2 million node pairs) needs 0.99 GB for K
    and 0.33 GB for M; its assembly peaks 1.44 GB above the mesh, in 9 s on one core (12 s with
    every element curved; ``benchmarks/bench_tet10.py``).
    """
    check_type(mesh, TetMesh, "mesh", "a flexshaft.elements.tetmesh.TetMesh")
    check_type(material, Material, "material", "a flexshaft.Material (E, nu, rho)")
    chunk = check_int(chunk, "chunk", lo=1)
    check_ceiling(
        "solid_dofs",
        3 * mesh.n_nodes,
        field=f"mesh of {mesh.name!r}",
        value=mesh.n_nodes,
        unit="nodes",
        detail=f"has {3 * mesh.n_nodes} DOFs",
        hint="a coarser mesh (a larger element size)",
    )
    E, nu, rho = material.E, material.nu, material.rho
    D = _elasticity(E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), material.G)
    nodes, tets = mesh.nodes, mesh.tets
    n, m = mesh.n_nodes, mesh.n_elements

    indptr, indices = _node_graph(tets, n)
    row_len = np.diff(indptr)
    keys = np.repeat(np.arange(n, dtype=np.int64), row_len) * n + indices  # sorted: (row, col)
    nnz = int(indptr[-1])
    m_data = np.zeros(3 * nnz if mass else 0)  # M's CSR data (see _structures)
    k_data = np.zeros((3 * nnz, 3))  # K's: entry 3p + j for M's entry p
    k_flat = k_data.reshape(-1)
    volume = 0.0
    for start in range(0, m, chunk):
        t = tets[start : start + chunk]
        K, Me, det4, det14 = _element_matrices(nodes[t], D, rho)
        _refuse_inverted(mesh, start, [det4, det14])
        volume += float(np.sum(TET14_RULE.weights * det14))
        T, size, where = _chunk_places(t, row_len, indptr, keys, n)
        Tr = T.ravel()
        del T, det4, det14
        m_acc = (
            np.bincount(
                Tr, weights=np.broadcast_to(Me[:, :, None, :], (len(t), 10, 3, 10)).ravel(), minlength=size
            )
            if mass
            else 0.0
        )
        k_acc = np.empty((size, 3))
        for j in range(3):  # K's columns in (j, a, i, b) order: three contiguous blocks
            k_acc[:, j] = np.bincount(Tr, weights=K[:, j].ravel(), minlength=size)
        del K, Me, Tr
        if mass:
            m_data[where] += m_acc
        if isinstance(where, slice):
            k_data[where] += k_acc
        else:
            k_flat[(3 * where[:, None] + np.arange(3)).ravel()] += k_acc.ravel()
        del m_acc, k_acc, where
    del keys
    (m_indptr, m_indices), (k_indptr, k_indices) = _structures(indptr, indices, n)
    del indptr, indices
    Kg = sp.csr_array((k_data.reshape(-1), k_indices, k_indptr), shape=(3 * n, 3 * n))
    Mg = sp.csr_array((m_data, m_indices, m_indptr), shape=(3 * n, 3 * n)) if mass else None
    for A in (Kg, Mg) if mass else (Kg,):
        A.has_sorted_indices = True  # built sorted: the node graph's rows are
    return SolidMatrices(K=Kg, M=Mg, volume=volume, mass=rho * volume)
