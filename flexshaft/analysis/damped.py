"""Damped modes from the first-order system, paired with the undamped modes.

With state z = [θ, θ̇], the damped system M θ̈ + C θ̇ + K θ = 0 becomes the
generalised eigenproblem

    [[0, I], [−K, −C]] z = λ [[I, 0], [0, M]] z,

solved without inverting M. Each underdamped mode gives a conjugate pair
λ = −ξω ± iω√(1 − ξ²); we keep the member with Im λ > 0 and read
``ω = |λ|``, ``ξ = −Re λ / |λ|``. An overdamped mode gives two real roots
λa, λb < 0, read as ω = √(λa·λb), ξ = −(λa + λb) / (2ω) ≥ 1.

Small models are solved in full; large ones in the subspace of the computed
undamped modes (exact when C is diagonal in them, and accurate to second
order in the damping otherwise).

The first-order problem is solved by :func:`~flexshaft.linalg.firstorder.damped_eigen`, flexshaft's
one solver of first-order state matrices, on the similar matrix [[0, Ω], [−Ω, −ΦᵀCΦ]] (state [Ωq, q̇]),
whose norm is ω_max where [[0, I], [−Ω², −ΦᵀCΦ]]'s is ω_max².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..linalg.damping import dense, modal_damping_block
from ..linalg.firstorder import damped_eigen
from ..linalg.mac import mac

__all__ = ["DampedModes", "damped_modes", "DAMPED_FULL_MAX_DOF"]

#: Up to this many DOFs the full first-order problem (2n states) is solved densely.
DAMPED_FULL_MAX_DOF = 400


@dataclass(frozen=True)
class DampedModes:
    """Damped modes, one per undamped mode and in the same order.

    Attributes
    ----------
    eigenvalues : ndarray of complex, shape (m,)
        λ with Im λ >= 0 (1/s). For an overdamped mode the real root of smaller
        magnitude. A rigid-body mode's root is real: −rᵀCr, with Rayleigh's αM taken
        off (it damps deformation only) - 0 when nothing damps rigid motion.
    natural_frequencies_hz : ndarray, shape (m,)
        ``|λ| / 2π`` (Hz): the mode's undamped natural frequency as the damped
        system sees it.
    damped_frequencies_hz : ndarray, shape (m,)
        Im λ / 2π (Hz): the frequency the mode rings at; 0 when overdamped.
    damping_ratios : ndarray, shape (m,)
        ``ξ = −Re λ / |λ|`` (fractions); >= 1 when overdamped.
    mac : ndarray, shape (m,)
        Modal assurance criterion between each damped mode's rotations and its
        undamped partner (1 = same shape); a low value flags strong coupling by
        non-proportional damping. 0 where no damped mode could be paired with
        it: that mode's values are the first-order estimate ξ = φᵀCφ/(2ω).
    method : str
        ``"full first-order"`` or ``"modal subspace (m modes)"``.
    """

    eigenvalues: np.ndarray
    natural_frequencies_hz: np.ndarray
    damped_frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    mac: np.ndarray
    method: str

    @property
    def decay_rates(self) -> np.ndarray:
        """−Re λ per mode, 1/s: ξω for an elastic mode, the rigid-body root's rate (Rayleigh's α)."""
        return -self.eigenvalues.real


def _modal_problem(K, M, C, eigenvalues, vectors, rigid, alpha: float):
    """The frequencies ω (rad/s), modal damping block and basis (n × N) the first-order problem is
    solved in, and the method's name (see :func:`damped_modes`)."""
    n, m = vectors.shape
    if m == n or n > DAMPED_FULL_MAX_DOF:
        # In the computed undamped modes q (θ = Vq, VᵀMV = I, VᵀKV = Ω²): with every mode this is the
        # full problem in other coordinates; with some, its Galerkin projection. Ω is taken from the
        # given (Rayleigh-refined) eigenvalues, not re-solved from VᵀKV: a dense re-solve loses
        # ε·ω_max² in every λ, which in a 6-DOF model with MHz axial modes is 1e-6 of its 10 Hz mode.
        Cm = modal_damping_block(C, vectors, rigid, alpha)
        w = np.sqrt(np.clip(np.asarray(eigenvalues, dtype=float), 0.0, None))
        return w, Cm, vectors, "full first-order" if m == n else f"modal subspace ({m} modes)"
    # Every undamped mode of the small model, densely (the given ones are some of them): the undamped
    # problem K φ = ω² M φ, symmetric-definite, whose modes are the basis the damped one is solved in.
    Kd, Md, Cd = dense(K), dense(M), dense(C)
    w2, Phi = sla.eigh(Kd, Md, check_finite=False)
    w = np.sqrt(np.clip(w2, 0.0, None))
    # eigh sorts ascending: the given modes' rigid-body ones are its lowest
    Cm = modal_damping_block(Cd, Phi, np.arange(w.size) < int(np.sum(rigid)), alpha)
    return w, Cm, Phi, "full first-order"


def _rigid_roots(out_lam, C, eigenvalues, vectors, rigid, alpha: float) -> None:
    """Set each rigid-body mode's root in ``out_lam``: a mass-normalised r under damping moves as
    r̈ + (rᵀCr) ṙ = 0, one real root −rᵀCr.

    Dampers between stations and modal damping leave it at 0 (round-off), and so does Rayleigh's
    αM, taken on the deformation only (α off: see modal_damping_block); a damper to ground would not.
    Round-off there is ~eps·2ξ·ω_max; 1e-12·ω_max is far above it and far below any real damper.
    """
    tol = 1e-12 * max(float(np.sqrt(np.max(np.abs(eigenvalues)))), 1.0)
    rigid_modes = np.flatnonzero(np.asarray(rigid))
    if rigid_modes.size:
        # rᵀCr of each, Rayleigh's α taken off as everywhere (the one modal damping block)
        block = modal_damping_block(C, vectors[:, rigid_modes], np.ones(rigid_modes.size, dtype=bool), alpha)
        for mode, c in zip(rigid_modes, np.diag(block)):
            if c > tol:
                out_lam[mode] = complex(-float(c), 0.0)


def _pair_oscillating(mac_osc: np.ndarray, root_w: np.ndarray, w_und: np.ndarray, scale: float) -> dict:
    """Undamped elastic mode i -> its oscillating root j (indices of ``mac_osc``'s rows and columns).

    Greedy on MAC, best pairs first (ties broken by closeness of the root's |λ|, ``root_w``, to the
    mode's ω, ``w_und``); a pair needs MAC >= 0.5.
    """
    n_modes, n_roots = mac_osc.shape
    closeness = -np.abs(root_w[None, :] - w_und[:, None]) / scale
    order = np.lexsort((-closeness.ravel(), -mac_osc.ravel()))
    taken: set[int] = set()
    assigned: dict[int, int] = {}
    for flat in order:
        i, j = divmod(int(flat), n_roots)
        if i in assigned or j in taken or mac_osc[i, j] < 0.5:
            continue
        assigned[i] = j
        taken.add(j)
        if len(assigned) == n_modes:
            break
    # A mode of a degenerate pair (a 6-DOF line's lateral y and z) may have any mix of the pair as
    # its damped vector, MAC 0.5 against each: pair what is left by frequency instead, where a
    # damped root sits on the mode's own |λ| (1e-6: far closer than any two distinct modes here).
    for i in range(n_modes):
        if i in assigned:
            continue
        free = [j for j in range(n_roots) if j not in taken]
        if not free:
            break
        j = min(free, key=lambda j: abs(root_w[j] - w_und[i]))
        if abs(root_w[j] - w_und[i]) <= 1e-6 * w_und[i]:
            assigned[i] = j
            taken.add(j)
    return assigned


def damped_modes(K, M, C, eigenvalues, vectors, rigid, *, alpha: float = 0.0) -> DampedModes:
    """Damped modes of (K, M, C), paired with given undamped modes.

    Parameters
    ----------
    K, M, C : sparse or dense matrix, shape (n, n)
        Stiffness (N·m/rad), inertia (kg·m²), damping (N·m·s/rad).
    eigenvalues : ndarray, shape (m,)
        Undamped λ = ω², (rad/s)².
    vectors : ndarray, shape (n, m)
        Undamped modes, inertia-normalised.
    rigid : ndarray of bool, shape (m,)
        Rigid-body flags of the undamped modes.
    alpha : float
        The Rayleigh inertia coefficient in ``C``, 1/s: taken off the rigid-body modes
        (:func:`~flexshaft.linalg.damping.modal_damping_block`: Rayleigh damps deformation only).

    Returns
    -------
    DampedModes
    """
    m = vectors.shape[1]
    w, Cm, basis, method = _modal_problem(K, M, C, eigenvalues, vectors, rigid, alpha)
    N = w.size
    lam, Z = damped_eigen(omega=w, damping=Cm, vectors=True)
    # q̇ = λq: the velocity half has the shape of the mode (rigid λ = 0 is not used).
    Psi = basis @ Z[N:]
    scale = max(float(np.max(np.abs(lam))), 1.0)
    zero = np.abs(lam) <= 1e-9 * scale
    osc = (lam.imag > 1e-9 * scale) & ~zero
    real = (np.abs(lam.imag) <= 1e-9 * scale) & ~zero

    out_lam = np.zeros(m, dtype=complex)
    out_mac = np.ones(m)
    _rigid_roots(out_lam, C, eigenvalues, vectors, rigid, alpha)
    elastic = np.flatnonzero(~np.asarray(rigid))
    Phi = vectors[:, elastic]
    mac_osc = mac(Phi, Psi[:, osc], M) if osc.any() else np.zeros((elastic.size, 0))
    cand = np.flatnonzero(osc)
    assigned = (
        _pair_oscillating(mac_osc, np.abs(lam[cand]), np.sqrt(np.asarray(eigenvalues)[elastic]), scale)
        if mac_osc.size
        else {}
    )
    real_idx = np.flatnonzero(real)
    mac_real = mac(Phi, Psi[:, real], M) if real.any() else np.zeros((elastic.size, 0))
    used_real: set[int] = set()
    omega = np.zeros(m)
    omega_d = np.zeros(m)
    xi = np.zeros(m)
    for i, mode in enumerate(elastic):
        if i in assigned:
            j = cand[assigned[i]]
            out_lam[mode] = lam[j]
            out_mac[mode] = mac_osc[i, assigned[i]]
            omega[mode] = abs(lam[j])
            omega_d[mode] = lam[j].imag
            xi[mode] = -lam[j].real / abs(lam[j])
            continue
        ranked = np.argsort(-mac_real[i], kind="stable") if mac_real.size else []
        free = [j for j in ranked if j not in used_real][:2]
        w_i = float(np.sqrt(max(eigenvalues[mode], 0.0)))
        if len(free) == 2:
            la, lb = lam[real_idx[free]].real
            # Two real roots are this mode overdamped only if their product is its ω² (exact for one
            # DOF; within a factor 2 here): a damped rigid-body root is no partner of an elastic mode.
            if not (la * lb > 0 and 0.5 * w_i <= np.sqrt(la * lb) <= 2.0 * w_i):
                free = []
        if len(free) == 2:
            # Overdamped: the two real roots whose vectors look most like this mode.
            used_real.update(free)
            la, lb = lam[real_idx[free]].real
            out_lam[mode] = complex(max(la, lb), 0.0)
            out_mac[mode] = float(np.mean(mac_real[i, free]))
            omega[mode] = np.sqrt(la * lb)
            xi[mode] = -(la + lb) / (2.0 * omega[mode])
        else:
            # No damped partner found (close modes the non-proportional damping mixes, or the top of
            # a projected subspace): the first-order estimate ξ = φᵀCφ/(2ω) of the mass-normalised
            # mode, exact for proportional damping; MAC 0 marks it as unpaired.
            w = float(np.sqrt(eigenvalues[mode]))
            v = vectors[:, mode]
            out_mac[mode] = 0.0
            omega[mode] = w
            xi[mode] = float(v @ (C @ v)) / (2.0 * w) if w > 0 else np.nan
            if 0.0 <= xi[mode] < 1.0:
                omega_d[mode] = w * np.sqrt(1.0 - xi[mode] ** 2)
                out_lam[mode] = complex(-xi[mode] * w, omega_d[mode])
    two_pi = 2.0 * np.pi
    return DampedModes(
        eigenvalues=out_lam,
        natural_frequencies_hz=omega / two_pi,
        damped_frequencies_hz=omega_d / two_pi,
        damping_ratios=xi,
        mac=out_mac,
        method=method,
    )
