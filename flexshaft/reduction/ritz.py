"""Ritz building blocks of a solid part's Craig-Bampton basis: load-dependent Ritz vectors for its
fixed-interface (twist) modes, the residual vectors at their own tolerance, and the twist share and
sign convention of a solid's mode shapes.

The fixed-interface modes of a solid are found by Rayleigh-Ritz on the Krylov space of K⁻¹M from
inertia loads (:func:`ritz`, :func:`twist_ritz`): a few block solves with the part's solver
(:class:`~flexshaft.linalg.spd.SpdSolver`, or the held masters' solves of
:class:`~flexshaft.parts.solidties.HeldMasters`), where a Lanczos search would first find every bending
and axial mode below a long tube's first twist mode.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from .flexiblebody import residual_vectors

__all__ = [
    "MODES_TOL",
    "RESIDUAL_RTOL",
    "RITZ_RTOL",
    "TWIST_SHARE",
    "mode_signs",
    "residual_at_tolerance",
    "ritz",
    "trial_shapes",
    "twist_ritz",
    "twist_share",
]

#: A fixed-interface mode counts as twist (kept in a torsion body) when more than this share of its
#: Σ|u|² is sections turning about the axis (:func:`twist_share`): a part of revolution's modes are
#: near 1 or near 0, a bolted flange's within a few per cent of those.
TWIST_SHARE = 0.5
#: LOBPCG's relative residual for a 6-DOF body's fixed-interface modes (:func:`lowest_modes`), where
#: :data:`flexshaft.linalg.lobpcg.TOL` (1e-6) gives eigenvalues to ~1e-10. A Ritz value's error is at
#: most tol²·κ(M)·θ/δ (Kato-Temple; κ(M) = O(10-100) for quadratic tetrahedra, δ the gap to the next
#: mode): ~1e-6 at 1e-4 for modes a few per cent apart, the vectors within tol·√κ(M)·θ/δ, and the
#: body's frequencies as Rayleigh-Ritz on their span move with the square of that. Measured on the test
#: bench's parts 1 and 4 (8 modes, 170 000 and 124 000 DOFs) against 1e-6: fixed-interface modes
#: within 1.2e-11, the body's free-free ones within 4.5e-9, in 73-77 % of the iterations (19 and 10
#: against 26 and 13).
MODES_TOL = 1e-4
#: Krylov blocks the twist modes of a torsion body may take (each one K⁻¹ solve per master).
MAX_RITZ_BLOCKS = 60
#: A Ritz value has converged when a further block moves it by less than this (relative, of λ = ω²:
#: 5e-4 of a frequency). The blocks converge faster than geometrically, so the move bounds what is
#: left: on the test bench's solids (examples/customer1_solid.toml) the second block moved the kept
#: twist modes by up to 2.9e-4 (frequency) and left them within 1.1e-4 of converged (part 2's fourth,
#: 1138 Hz; the others within 3e-5), where 1e-5 took two blocks more on part 2 and one on parts 1 and
#: 4. The chain's modes depend on the space the modes span with the residual vectors, not on each
#: mode being converged: up to 204 Hz they moved by <= 4e-10, at 383 and 515 Hz by 5.5e-7 and 4.3e-6 -
#: all below the mesh's own error (a tube's twist modes at two elements across the wall: 1e-4).
RITZ_CONVERGED = 1e-3
#: Twist loads the Krylov space starts from besides the masters' inertia loads: the inertia of the
#: sections turning as sin(kπx/L), k = 1..RITZ_START (the fixed-fixed twist modes of a uniform part),
#: so that the first block already holds what the higher modes need, and every solve is a block of 8
#: columns (multigrid's products cost less per column in blocks). PTSS part 1: 13 blocks of 2 columns
#: (43 s) became 3 blocks of 8 (24 s).
RITZ_START = 6
#: The relative residual ‖b − Kx‖/‖b‖ of the Krylov blocks' solves. A solve to ε puts its vectors off
#: the exact Krylov space; Rayleigh-Ritz on the space as spanned still bounds every eigenvalue from
#: above, with an error quadratic in its eigenvector's distance to the space in the energy norm
#: (λ_ritz − λ <= λ·tan²∠(φ, space)), so what a solve leaves enters as the square of its energy-norm
#: error. For the blocks' inertia loads (M times smooth shapes) that error is ~20x below the Euclidean
#: residual (PTSS part 1: √(rᵀz / r₀ᵀz₀), z the multigrid's preconditioned residual, 8.6e-4 where
#: ‖r‖/‖b‖ is 1.5e-2). Measured on the test bench's solids (examples/customer1_solid.toml, 124 000 -
#: 545 000 DOFs) against solves to 1e-8: at 1e-2 (and :data:`RESIDUAL_RTOL`) the kept twist modes
#: move by <= 4e-7 and the chain's modes up to 515 Hz by <= 1.5e-8 (all at 1e-3: 2.5e-8 and 7e-9),
#: with 38 % of the CG iterations (per block on parts 1, 2, 4: 11, 17, 6 against 31, 39, 14) - far
#: below a 100 mm mesh's own error, or a tube's at two elements across its wall (1e-4).
RITZ_RTOL = 1e-2
#: The relative residual of the residual vectors' solves (K⁻¹ of the inertia loads the kept modes
#: leave): a few columns, so a tighter one costs little, and their error, not the modes', is what
#: moves the chain's modes most (at 1e-2 their Ritz values moved by up to 1.2e-3, at 1e-3 by 2e-5).
RESIDUAL_RTOL = 1e-3


def trial_shapes(nodes: np.ndarray, length: float) -> np.ndarray:
    """Clamped-clamped trial shapes (half sines along the axis) in x, y, z and in twist, node-major."""
    s = np.sin(np.pi * np.clip(nodes[:, 0] / length, 0.0, 1.0))
    t = np.zeros((nodes.shape[0], 3, 4))
    for k in range(3):
        t[:, k, k] = s
    t[:, 1, 3], t[:, 2, 3] = -nodes[:, 2] * s, nodes[:, 1] * s
    return t.reshape(-1, 4)


def twist_share(nodes: np.ndarray, shapes: np.ndarray, width: float) -> np.ndarray:
    """Each shape's share of Σ|u|² that is sections turning about the axis.

    The nodes are cut into slabs ``width`` thick along x; in each, the least-squares turn
    θ = Σ r·t / Σ r² of the tangential motions t at radii r, and the share is Σ θ²·Σr² over Σ|u|².
    A twist mode's is near 1 (less its warping); a bending mode's near 0, though half its motion is
    tangential (a section translating along y moves tangentially by −u_y·sin φ, which turns it by
    nothing on the whole).
    """
    u = shapes.reshape(nodes.shape[0], 3, -1)
    r = np.hypot(nodes[:, 1], nodes[:, 2])
    rt = -nodes[:, 2, None] * u[:, 1] + nodes[:, 1, None] * u[:, 2]  # r·t
    slab = np.floor((nodes[:, 0] - nodes[:, 0].min()) / width).astype(np.int64)
    den = np.bincount(slab, weights=r * r)
    num = np.stack([np.bincount(slab, weights=rt[:, k], minlength=den.size) for k in range(rt.shape[1])], 1)
    ok = den > 0
    turned = np.sum(num[ok] ** 2 / den[ok, None], axis=0)
    return turned / np.maximum(np.sum(u * u, axis=(0, 1)), np.finfo(float).tiny)


def mode_signs(nodes: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """+1 or −1 per mode (on the free nodes): its largest twist (tangential) motion positive, or,
    without twist, its largest translation - flexshaft's one sign convention."""
    u = phi.reshape(nodes.shape[0], 3, -1)
    r = np.hypot(nodes[:, 1], nodes[:, 2])
    safe = np.where(r > 0, r, 1.0)
    t = (-nodes[:, 2, None] * u[:, 1] + nodes[:, 1, None] * u[:, 2]) / safe[:, None]
    signs = np.ones(phi.shape[1])
    flat = phi
    for k in range(phi.shape[1]):
        v = t[:, k] if np.max(np.abs(t[:, k])) > 1e-3 * np.max(np.abs(flat[:, k])) else flat[:, k]
        top = float(np.max(np.abs(v)))
        if top > 0:
            signs[k] = 1.0 if v[np.flatnonzero(np.abs(v) >= (1 - 1e-6) * top)[0]] > 0 else -1.0
    return signs


def _twist_shapes(inner: np.ndarray, n: int) -> np.ndarray:
    """The sections of the nodes ``inner`` turning as sin(kπx/L), k = 1..:data:`RITZ_START` (n, k): the
    fixed-fixed twist modes of a uniform part, on the first 3·len(inner) unknowns (any after them - a
    rigid face's master - at rest)."""
    length = float(np.ptp(inner[:, 0])) or 1.0
    x, turn = inner[:, 0] / length, np.zeros((inner.shape[0], 3))
    turn[:, 1], turn[:, 2] = -inner[:, 2], inner[:, 1]  # the slab's unit turn about the axis
    sines = np.sin(np.pi * x[:, None] * np.arange(1, RITZ_START + 1))  # (nodes, k)
    shapes = np.zeros((n, RITZ_START))
    shapes[: 3 * inner.shape[0]] = (turn[:, :, None] * sines[:, None, :]).reshape(-1, RITZ_START)
    return shapes


def twist_ritz(solver, Kii, Mii, load, inner, slab, n_keep, cutoff_hz):
    """The lowest twist modes of the fixed-interface solid, by Rayleigh-Ritz on the Krylov space of
    K⁻¹M from the twist inertia loads (load-dependent Ritz vectors, Wilson-Yuan-Dickens): the masters'
    and :data:`RITZ_START` sine-distributed turns'.

    The space K⁻¹F, (K⁻¹M)K⁻¹F, ... from loads that twist the part holds, for a part of revolution,
    its twist modes only (K and M keep the symmetry), so each block costs one solve per load instead
    of the many of a shift-invert Lanczos that finds every bending and axial mode below them first.
    (A part that is not of revolution lets other modes in; the twist share sorts them out.) The first
    3·len(inner) unknowns are the nodes ``inner``'s u_x, u_y, u_z (any after them are not read for the
    twist share). Returns (eigenvalues (rad/s)², M-orthonormal vectors) of the kept twist modes.
    """
    load = np.hstack([load, np.asarray(Mii @ _twist_shapes(inner, Mii.shape[0]))])
    rows = 3 * inner.shape[0]

    def twist(phi):
        return twist_share(inner, phi[:rows], slab) > TWIST_SHARE

    return ritz(solver, Kii, Mii, load, twist, n_keep, cutoff_hz)


def ritz(solver, K, M, load, kept, n_keep, cutoff_hz):
    """The lowest ``kept`` modes of (K, M) on the Krylov space of the solver's K⁻¹M from ``load``.

    Blocks are added until the ``n_keep`` lowest kept Ritz values (or those below ``cutoff_hz``, and
    the first above it) move by less than :data:`RITZ_CONVERGED`; ``kept(vectors)`` says which Ritz
    vectors count. Ritz values bound the eigenvalues from above. The solver's solves run at
    :data:`RITZ_RTOL`: Rayleigh-Ritz on a space spanned inexactly still bounds them, and the
    space's error enters the values squared. Returns (eigenvalues (rad/s)², M-orthonormal vectors).
    """
    exact, solver.rtol = solver.rtol, max(solver.rtol, RITZ_RTOL)
    try:
        return _ritz_blocks(solver, K, M, load, kept, n_keep, cutoff_hz)
    finally:
        solver.rtol = exact


def _ritz_blocks(solver, Kii, Mii, load, kept, n_keep, cutoff_hz):
    """:func:`ritz`'s blocks, with the solver at :data:`RITZ_RTOL`."""
    n = Mii.shape[0]
    V = np.zeros((n, 0))
    KV = np.zeros((n, 0))
    R = solver.solve(load)
    size = float(np.max(np.einsum("ij,ij->j", R, Mii @ R), initial=0.0))
    prev = None
    for _ in range(MAX_RITZ_BLOCKS):
        for _ in range(2):  # M-orthogonal to the basis, twice for round-off
            R = R - V @ (V.T @ (Mii @ R))
        g = R.T @ (Mii @ R)
        mu, U = np.linalg.eigh(0.5 * (g + g.T))
        ok = mu > 1e-20 * max(size, np.finfo(float).tiny)
        if not ok.any():
            break  # the space is exhausted: every mode it can hold is in it
        B = (R @ U[:, ok]) / np.sqrt(mu[ok])
        V, KV = np.hstack([V, B]), np.hstack([KV, Kii @ B])
        k, mm = V.T @ KV, V.T @ (Mii @ V)
        # the generalized problem on the space as spanned (its M-orthonormality holds to round-off
        # only): the Ritz values are then true upper bounds
        lam, W = scipy.linalg.eigh(0.5 * (k + k.T), 0.5 * (mm + mm.T))
        phi = V @ W
        counted = kept(phi)
        lt = lam[counted]
        if n_keep is not None:
            want = lt[:n_keep]
            settled = lt.size >= n_keep
        else:
            below = lt < (2 * np.pi * cutoff_hz) ** 2
            want = lt[: int(below.sum()) + 1]
            settled = not below.all()
        if settled and prev is not None and prev.size >= want.size:
            if np.all(np.abs(prev[: want.size] - want) <= RITZ_CONVERGED * want):
                break
        prev = lt
        R = solver.solve(Mii @ B)
    keep = np.flatnonzero(counted)
    if n_keep is not None:
        keep = keep[:n_keep]
    else:
        keep = keep[lam[keep] < (2 * np.pi * cutoff_hz) ** 2]
    return lam[keep], phi[:, keep]


def residual_at_tolerance(solver, K, M, Mib, psi, phi):
    """:func:`~flexshaft.reduction.craig_bampton.residual_vectors` with the solves at
    :data:`RESIDUAL_RTOL`: like the modes, the residual vectors are Ritz basis vectors, whose error
    enters the frequencies squared (the static condensation's accuracy is the constraint modes',
    solved at the solver's own tolerance)."""
    exact, solver.rtol = solver.rtol, max(solver.rtol, RESIDUAL_RTOL)
    try:
        return residual_vectors(solver, K, M, Mib, psi, phi)
    finally:
        solver.rtol = exact
