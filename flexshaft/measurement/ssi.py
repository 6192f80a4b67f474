"""Covariance-driven stochastic subspace identification (SSI-COV) on one record, with its stabilisation.

The algorithm of Peeters & De Roeck (1999, "Reference-based stochastic subspace identification for
output-only modal analysis", MSSP 13(6)); Brincker & Ventura (2015, "Introduction to Operational Modal
Analysis", ch. 9) tell it the same way. For outputs y (l channels, r of them references) of a linear
system driven by white noise, the output correlations are R_k = E[y_{t+k} y_refᵀ] = C A^(k−1) G, so the
block Toeplitz matrix of lags 1..2i−1

    T = [[R_i,      R_{i−1}, ..., R_1],
         [R_{i+1},  R_i,     ..., R_2],
         ...
         [R_{2i−1}, ...,          R_i]]          (l·i × r·i)

factors as (observability O_i) · (reversed controllability): its SVD T = U S Vᵀ gives O = U_n S_n^½ for
model order n, C its first block row, and A from the shift structure O[l:] = O[:−l] A (least squares).
The eigenvalues μ of A give the continuous poles λ = ln(μ)·fs, ``f = |λ|/2π``, ``ζ = −Re λ/|λ|``, and the
eigenvectors ψ the mode shapes C·ψ. A free decay (an impulse response) is the same sum of decaying
exponentials, so it is identified by the same steps; its correlation then holds the poles exactly.

:func:`correlations` estimates R_k (FFT, block-wise: memory bounded whatever the record's length),
:func:`ssi_poles` gives the poles of every model order from one SVD, :func:`stabilise` flags the stable
ones, and :func:`cluster_modes` groups them into modes. SI throughout: Hz, seconds; damping ratios as
fractions. Everything here works in the channels' own (possibly normalised) units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.fft
import scipy.linalg

from ..linalg.firstorder import damped_eigen
from ..linalg.mac import mac

__all__ = [
    "CLUSTER_FREQUENCY",
    "CLUSTER_MAC",
    "MAX_DAMPING",
    "STABLE_DAMPING",
    "STABLE_FREQUENCY",
    "STABLE_MAC",
    "OrderPoles",
    "PoleCluster",
    "cluster_modes",
    "group",
    "physical",
    "normalised",
    "aligned_median",
    "correlations",
    "mpc",
    "ssi_poles",
    "stabilise",
]

#: A pole is stable when a pole of the previous model order lies within this relative distance in
#: frequency ...
STABLE_FREQUENCY = 0.01
#: ... within this relative distance in damping ratio ...
STABLE_DAMPING = 0.05
#: ... and its shape has at least this MAC with that pole's shape.
STABLE_MAC = 0.98
#: The largest damping ratio a structural pole may have (fraction): above it a pole is noise or the
#: drift's filter, not a mode of a steel drivetrain.
MAX_DAMPING = 0.20
#: Stable poles belong to one mode when their frequencies lie within this relative distance of each
#: other (on average over the cluster) ...
CLUSTER_FREQUENCY = 0.01
#: ... and their shapes' MAC is at least this (on average): the clustering's distance is the larger of
#: the two, each relative to its threshold.
CLUSTER_MAC = 0.95

# Samples of a block of the correlation's FFT, as a multiple of the longest lag (at least 4096): the
# FFT's length is a block plus the longest lag, so longer blocks waste less on the zero padding, and
# a chunk of blocks holds about _CHUNK_VALUES values per channel.
_BLOCK_LAGS = 8
_MIN_BLOCK = 4096
_CHUNK_VALUES = 1 << 18


def correlations(y: np.ndarray, max_lag: int, references=None) -> np.ndarray:
    """The output correlations R_k = (1/N)·Σ_t y[:, t+k] y[ref, t]ᵀ for k = 0..max_lag.

    Parameters
    ----------
    y : ndarray, shape (l, N)
        The channels (rows), in any units.
    max_lag : int
        The longest lag, samples (< N).
    references : sequence of int, optional
        The reference channels' rows (default: all).

    Returns
    -------
    ndarray, shape (max_lag + 1, l, r)
        R_k for k = 0..max_lag, each divided by the record's length N (the biased estimate).

    Notes
    -----
    Divided by N, not by N − k: for a free decay that has died out within the record the sums are then
    exactly C A^(k−1) G, the poles unchanged; for a stationary record the factor (1 − k/N) adds an
    apparent damping of 1/(ω·T) (T the record, s), which the callers keep below 2 % of ζ by the segment
    length they choose. Computed block-wise with FFTs: each block of samples is correlated with itself
    plus the next ``max_lag`` samples (zero-padded so the circular correlation is the linear one), the
    cross-spectra summed over blocks, one inverse FFT at the end. Every product y[t+k]·y[t] with both
    samples in the record is counted once: the result equals the direct sum to round-off.
    """
    y = np.asarray(y, dtype=float)
    l, n = y.shape
    refs = np.arange(l) if references is None else np.asarray(references, dtype=int)
    block = max(_MIN_BLOCK, _BLOCK_LAGS * max_lag)
    block = min(block, n)
    nfft = scipy.fft.next_fast_len(block + max_lag, real=True)
    blocks = -(-n // block)
    padded = np.zeros((l, blocks * block + max_lag))
    padded[:, :n] = y
    # windows of block + max_lag samples starting at every block: a view, copied a chunk at a time
    ahead = np.lib.stride_tricks.sliding_window_view(padded, block + max_lag, axis=1)[:, ::block]
    spectra = np.zeros((nfft // 2 + 1, l, refs.size), dtype=complex)
    chunk = max(1, _CHUNK_VALUES // nfft)
    for first in range(0, blocks, chunk):
        last = min(blocks, first + chunk)
        here = padded[refs, first * block : last * block].reshape(refs.size, last - first, block)
        x = scipy.fft.rfft(here, n=nfft, axis=-1)  # (r, b, f): the block alone
        z = scipy.fft.rfft(ahead[:, first:last], n=nfft, axis=-1)  # (l, b, f): the block and what follows
        # Σ over blocks of Z_a · conj(X_b), per frequency: a batched (l × b)·(b × r) product
        spectra += np.matmul(z.transpose(2, 0, 1), x.conj().transpose(2, 1, 0))
    corr = scipy.fft.irfft(spectra, n=nfft, axis=0)[: max_lag + 1]
    return corr / n


@dataclass(frozen=True)
class OrderPoles:
    """The poles of one model order (one of each complex-conjugate pair: the one with ω_d > 0).

    Attributes
    ----------
    order : int
        The model order n (the state's dimension).
    frequency_hz : ndarray, shape (m,)
        Undamped natural frequencies ``|λ|/2π``, Hz.
    damping_ratio : ndarray, shape (m,)
        ``−Re λ/|λ|`` (fraction; negative for an unstable pole).
    shapes : ndarray, shape (l, m), complex
        The mode shapes C·ψ, in the units of the channels given, each of unit norm.
    """

    order: int
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray


def _toeplitz(corr: np.ndarray, block_rows: int) -> np.ndarray:
    """The block Toeplitz matrix of lags 1..2i−1 (l·i × r·i) from ``corr`` (lags 0..≥2i−1)."""
    i = block_rows
    _, l, r = corr.shape
    # block (p, q) is R_{i+p−q}: rows p = 0..i−1 and columns q = 0..i−1
    lags = i + np.arange(i)[:, None] - np.arange(i)[None, :]
    return corr[lags].transpose(0, 2, 1, 3).reshape(l * i, r * i)


def ssi_poles(corr: np.ndarray, rate_hz: float, orders, block_rows: int) -> tuple[OrderPoles, ...]:
    """The poles of every model order from the output correlations.

    Parameters
    ----------
    corr : ndarray, shape (≥ 2i, l, r)
        R_k for k = 0, 1, ... (:func:`correlations`).
    rate_hz : float
        The sampling rate of the correlations' lags, Hz.
    orders : sequence of int
        Model orders n (even, increasing, each <= r·i).
    block_rows : int
        i, the Toeplitz matrix's block rows.

    Returns
    -------
    tuple of OrderPoles
        One per order. Real eigenvalues (no oscillation) and those at the origin are left out.
    """
    l = corr.shape[1]
    t = _toeplitz(corr, block_rows)
    u, s, _ = scipy.linalg.svd(t, full_matrices=False, check_finite=False)
    # The matrix's numerical rank: directions below round-off (noise-free data of a lower order than
    # asked, a record of zeros) carry no poles, so an order above the rank uses the rank.
    rank = int(np.sum(s > s[0] * np.finfo(float).eps * max(t.shape))) if s.size and s[0] > 0 else 0
    out = []
    for n in orders:
        n_used = min(n, rank)
        if n_used == 0:
            out.append(OrderPoles(n, np.zeros(0), np.zeros(0), np.zeros((l, 0), dtype=complex)))
            continue
        o = u[:, :n_used] * np.sqrt(s[:n_used])
        a, *_ = scipy.linalg.lstsq(o[:-l], o[l:], check_finite=False)
        mu, psi = damped_eigen(a, vectors=True)  # the identified discrete state matrix's poles
        shapes = o[:l] @ psi
        norms = np.linalg.norm(shapes, axis=0)
        keep = (mu.imag > 0) & (norms > 0)  # one of each conjugate pair; real poles do not oscillate
        lam = np.log(mu[keep]) * rate_hz
        wn = np.abs(lam)
        out.append(OrderPoles(n, wn / (2 * math.pi), -lam.real / wn, shapes[:, keep] / norms[keep]))
    return tuple(out)


def mpc(shape) -> float:
    """The modal phase collinearity ``|φᵀφ|² / (φᴴφ)²`` of a complex shape: 1 when all its components share
    one phase (up to sign: a real, normal mode), down to 0 for components spread evenly in phase.

    This is Pappa et al.'s MPC: ((λ1 − λ2)/(λ1 + λ2))² of the 2×2 scatter of (Re φ, Im φ).
    """
    phi = np.asarray(shape, dtype=complex)
    den = np.vdot(phi, phi).real
    return float(abs(np.sum(phi * phi)) ** 2 / den**2) if den > 0 else 0.0


def stabilise(poles: tuple[OrderPoles, ...]) -> tuple[np.ndarray, ...]:
    """Flag the stable poles: each order's poles against those of the order before it.

    A pole is stable when a pole of the previous order lies within :data:`STABLE_FREQUENCY` in
    frequency and :data:`STABLE_DAMPING` in damping (both relative to this pole's) and their shapes'
    MAC is at least :data:`STABLE_MAC`. The first order's poles have nothing to compare with: none is
    stable.

    Returns
    -------
    tuple of ndarray of bool
        One per order, one flag per pole.
    """
    flags = [np.zeros(poles[0].frequency_hz.size, dtype=bool)] if poles else []
    for prev, this in zip(poles[:-1], poles[1:], strict=False):
        if this.frequency_hz.size == 0 or prev.frequency_hz.size == 0:
            flags.append(np.zeros(this.frequency_hz.size, dtype=bool))
            continue
        f, z = this.frequency_hz[:, None], this.damping_ratio[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            df = np.abs(f - prev.frequency_hz[None, :]) / f
            dz = np.abs(z - prev.damping_ratio[None, :]) / np.abs(z)
        ok = (df <= STABLE_FREQUENCY) & (dz <= STABLE_DAMPING) & (mac(this.shapes, prev.shapes) >= STABLE_MAC)
        flags.append(ok.any(axis=1))
    return tuple(flags)


def physical(poles: OrderPoles, min_hz: float, max_hz: float) -> np.ndarray:
    """Poles that may be a structural mode: 0 < ζ <= :data:`MAX_DAMPING`, min_hz < f < max_hz."""
    z, f = poles.damping_ratio, poles.frequency_hz
    return (z > 0) & (z <= MAX_DAMPING) & (f > min_hz) & (f < max_hz)


@dataclass(frozen=True)
class PoleCluster:
    """Stable poles of one mode, across model orders (one per order: the one nearest the median).

    Attributes
    ----------
    frequency_hz, damping_ratio : float
        The medians of the members' (Hz; fraction).
    shape : ndarray, shape (l,), complex
        The members' shapes, each turned so its largest component is real and positive and scaled to
        it, then the median of the real and of the imaginary parts, per component.
    orders : ndarray of int
        The model orders of the members.
    members : tuple of (int, int)
        (index of the order in the list given, index of the pole in that order) per member.
    """

    frequency_hz: float
    damping_ratio: float
    shape: np.ndarray
    orders: np.ndarray
    members: tuple


def normalised(shape: np.ndarray) -> np.ndarray:
    """A complex shape turned and scaled so its largest component (by magnitude) is 1."""
    shape = np.asarray(shape, dtype=complex)
    return shape / shape[int(np.argmax(np.abs(shape)))]


def aligned_median(shapes: np.ndarray) -> np.ndarray:
    """The median shape of columns ``shapes`` (l, m): each normalised (:func:`normalised`), turned by a
    sign to agree with the first, then the median of the real and imaginary parts per component."""
    unit = shapes / shapes[np.argmax(np.abs(shapes), axis=0), np.arange(shapes.shape[1])]
    ref = unit[:, 0]
    signs = np.where(np.real(ref.conj() @ unit) < 0, -1.0, 1.0)
    unit = unit * signs
    return normalised(np.median(unit.real, axis=1) + 1j * np.median(unit.imag, axis=1))


def group(
    frequency_hz: np.ndarray, shapes: np.ndarray, frequency_tol: float, min_mac: float, apart=None
) -> np.ndarray:
    """Labels grouping poles (or modes) that lie close in frequency and agree in shape.

    Average-linkage hierarchical clustering (scipy) with the distance
    ``max(|f_a − f_b| / max(f_a, f_b) / frequency_tol, (1 − MAC_ab) / (1 − min_mac))``, cut at 1: on
    average over a group, frequencies within ``frequency_tol`` (relative) and MAC at least ``min_mac``.

    Parameters
    ----------
    frequency_hz : ndarray, shape (m,)
    shapes : ndarray, shape (l, m)
    frequency_tol, min_mac : float
    apart : ndarray of int, shape (m,), optional
        Items with the same value here never share a group (the modes of one run, or the poles of one
        model order): their distance is made too large for any average to bridge.

    Returns
    -------
    ndarray of int, shape (m,)
        A label per pole, from 1.
    """
    f = np.asarray(frequency_hz, dtype=float)
    if f.size < 2:
        return np.ones(f.size, dtype=int)
    import scipy.cluster.hierarchy as hierarchy

    df = np.abs(f[:, None] - f[None, :]) / np.maximum(f[:, None], f[None, :]) / frequency_tol
    dm = (1.0 - mac(shapes, shapes)) / (1.0 - min_mac)
    dist = np.maximum(df, np.maximum(dm, dm.T))  # symmetric to round-off
    if apart is not None:
        apart = np.asarray(apart)
        dist[apart[:, None] == apart[None, :]] = 1e6 * f.size
    np.fill_diagonal(dist, 0.0)
    condensed = dist[np.triu_indices(f.size, 1)]
    return hierarchy.fcluster(hierarchy.linkage(condensed, method="average"), 1.0, criterion="distance")


def cluster_modes(
    poles: tuple[OrderPoles, ...],
    stable: tuple[np.ndarray, ...],
    keep: tuple[np.ndarray, ...],
    min_members: int,
) -> tuple[PoleCluster, ...]:
    """Group the stable poles into modes.

    Parameters
    ----------
    poles : tuple of OrderPoles
        Every order's poles (:func:`ssi_poles`).
    stable : tuple of ndarray of bool
        :func:`stabilise`'s flags.
    keep : tuple of ndarray of bool
        Further flags per pole (:func:`physical`): only poles both stable and kept are clustered.
    min_members : int
        The fewest orders a cluster must span to be a mode.

    Returns
    -------
    tuple of PoleCluster
        Sorted by frequency.

    Notes
    -----
    :func:`group` with :data:`CLUSTER_FREQUENCY` and :data:`CLUSTER_MAC`: poles within 1 % in frequency
    whose shapes agree. A cluster then keeps one pole per order (the nearest its median frequency), and
    is a mode when it spans ``min_members`` orders.
    """
    where = [(j, p) for j, (s, k) in enumerate(zip(stable, keep, strict=True)) for p in np.flatnonzero(s & k)]
    if not where:
        return ()
    f = np.array([poles[j].frequency_hz[p] for j, p in where])
    z = np.array([poles[j].damping_ratio[p] for j, p in where])
    shapes = np.column_stack([poles[j].shapes[:, p] for j, p in where])
    order_of = np.array([poles[j].order for j, _ in where])
    labels = group(f, shapes, CLUSTER_FREQUENCY, CLUSTER_MAC)
    out = []
    for label in np.unique(labels):
        idx = np.flatnonzero(labels == label)
        centre = np.median(f[idx])
        # one pole per order: the one nearest the cluster's median frequency
        chosen = []
        for n in np.unique(order_of[idx]):
            at = idx[order_of[idx] == n]
            chosen.append(at[np.argmin(np.abs(f[at] - centre))])
        chosen = np.array(chosen)
        if chosen.size < min_members:
            continue
        out.append(
            PoleCluster(
                frequency_hz=float(np.median(f[chosen])),
                damping_ratio=float(np.median(z[chosen])),
                shape=aligned_median(shapes[:, chosen]),
                orders=order_of[chosen],
                members=tuple(where[c] for c in chosen),
            )
        )
    return tuple(sorted(out, key=lambda c: c.frequency_hz))
