"""A drivetrain's assembled K and M as functions of some of its parameters, for a caller that evaluates
many points (a calibration).

:class:`ParametrisedModel` takes ∂K and ∂M once, and for the fields K and M are affine in
(:data:`~flexshaft.analysis.parameters.AFFINE_FIELDS`: every stiffness, inertia, E and ρ) forms
K(x) = K0 + Σ Δx_k ∂K_k with no assembly at all - checked against an assembly at a moved point, never
assumed. ``scale``, ``ratio`` and ``nu`` are not affine (k ∝ s⁴; a mesh block k·[1, −n; −n, n²], a
rigid mesh's 1/n²; G = E/2(1+ν)) and are assembled and differenced at each point, as is an affine
field whose derivative another parameter changes (a shaft's stiffness next to its scale, anything past
a gear whose ratio is tuned).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..model.assembly import assemble
from ..model.components import Drivetrain
from .parameters import AFFINE_FIELDS, DAMPING_FIELDS, find_parameter, parameter_value, with_parameters

__all__ = ["ParametrisedModel", "in_double_precision", "STEP"]

#: Relative step of the central difference of the assembled matrices (exact for linear and
#: quadratic dependence; the round-off it leaves is ~1e-16/h = 1e-10 of the derivative).
STEP = 1e-6
#: Relative step of the central difference of an affine field: any step is exact for an affine
#: dependence, and a wide one leaves round-off of eps·|K|/h ~ 1e-15 of the derivative (against
#: 1e-10 at :data:`STEP`); 1/4 keeps every value positive, as the components require.
AFFINE_STEP = 0.25
#: An assembly at a moved point equals the affine model K0 + Σ Δx_k ∂K_k entry by entry, ij within
#: this fraction of √(d_i·d_j), d the diagonals of the terms (which bound every term summed into ij,
#: see :func:`_agrees`). Each side sums a few terms rounded to eps = 2.2e-16 (a node's elements, the
#: p + 1 terms of the model, whose derivatives err by ~eps·Δx/h, h the step), ~1e-15 in all with any
#: BLAS kernel's summation order; 1e-12 leaves a thousandfold margin. It guards AFFINE_FIELDS: two
#: of its fields acting on each other (a product of their changes) or a field not affine after all
#: would move an entry by a product of relative changes - (Δx/x)², 1e-4 for ±1 % bounds.
AFFINE_RTOL = 1e-12


def in_double_precision(func):
    """Run ``func`` with numpy's floating-point errors raised, each refused as one ModelError: the
    central differences of a parameter of extreme size (an inertia of 1e-308, a damper of 1e308)
    leave double precision, and a warning beside the table would hide that its numbers are not."""

    @functools.wraps(func)
    def run(*args, **kwargs):
        try:
            with np.errstate(over="raise", divide="raise", invalid="raise"):
                return func(*args, **kwargs)
        except FloatingPointError as err:
            raise ModelError(
                f"the derivatives leave double precision ({err})",
                field="parameter",
                valid="stiffness, inertia and damping within a few hundred orders of 1 in SI units",
            ) from None

    return run


def _magnitude_pattern(mats) -> tuple:
    """The union sparsity pattern of ``mats`` (CSR indptr, indices) and each one's values on it,
    one column per matrix (duplicates summed)."""
    n = mats[0].shape[1]
    P = sp.csr_matrix(mats[0].shape)
    for A in mats:
        P = P + abs(sp.csr_matrix(A))
    P.sum_duplicates()
    P.sort_indices()
    keys = np.repeat(np.arange(P.shape[0], dtype=np.int64), np.diff(P.indptr)) * n + P.indices
    out = np.zeros((P.nnz, len(mats)))
    for j, A in enumerate(mats):
        A = sp.coo_matrix(A)
        keep = A.data != 0  # an explicit zero adds nothing and may sit off the pattern
        pos = np.searchsorted(keys, A.row[keep].astype(np.int64) * n + A.col[keep])
        np.add.at(out[:, j], pos, A.data[keep])
    return P.indptr, P.indices, out


def _agrees(A, B, diagonal: np.ndarray, rtol: float) -> bool:
    """|A − B|_ij <= rtol·√(d_i·d_j) for every entry, d = ``diagonal`` (>= 0).

    K and M and the derivatives of the affine fields are sums of positive semi-definite element
    blocks, whose entries obey |a_ij| <= √(a_ii·a_jj) and whose diagonals add without cancelling: so
    √(d_i·d_j) bounds every term that went into entry ij (Cauchy-Schwarz), and an entry that should
    cancel to 0 (a coupling term of a 6-DOF model, left as ~eps times its terms) is judged against
    those terms rather than against its own round-off.
    """
    D = sp.coo_matrix(abs(sp.csr_matrix(A) - sp.csr_matrix(B)))
    return bool(np.all(D.data <= rtol * np.sqrt(diagonal[D.row] * diagonal[D.col])))


class ParametrisedModel:
    """The assembled K and M of a drivetrain as functions of named parameters.

    Each point ``x`` (the parameters' values, SI, in the order of ``names``) stands for the model
    ``with_parameters(drivetrain, dict(zip(names, x)))`` assembled unreduced. The derivatives
    ∂K/∂x_k, ∂M/∂x_k are taken once, at ``x0``, by central differences of that assembly. For the
    fields K and M are affine in (:data:`AFFINE_FIELDS`) the derivative is the same everywhere;
    where every parameter is such a field,

        K(x) = K(x0) + Σ_k (x_k − x0_k)·∂K/∂x_k    (M likewise)

    is the assembly at every point, exactly to round-off, and a point needs no assembly at all.
    That is checked, not assumed: the assembly at ``probe`` (a point with every parameter moved)
    must equal the affine model entry by entry (:data:`AFFINE_RTOL`). A parameter of another field
    (``scale``, ``ratio``, ``nu``), or a model failing the check, is assembled at each point and its
    derivative differenced afresh there; an affine field whose derivative at ``probe`` equals the
    one at ``x0`` (the same test) keeps it even then.

    Parameters
    ----------
    drivetrain : Drivetrain
    names : sequence of str
        The parameters (see :func:`parameters`).
    x0 : array_like, optional
        The point the derivatives are taken at, SI (default: the drivetrain's values).
    probe : array_like, optional
        A point with every parameter moved (distinct relative moves, so that no coincidence hides
        a term; within the values to be used). Default: ``x0`` times 1 ± 5 %·(k + 1)/(p + 1), the
        sign alternating.
    bounds : (array_like, array_like), optional
        Lower and upper values the model will be evaluated within, SI: the affine model is used
        only if the components accept every value inside them (checked at both corners).
    inertia_model : str, optional

    Attributes
    ----------
    names : tuple of str
    x0 : ndarray
    model0 : AssembledModel
        The assembly at ``x0`` (undamped: C is not needed for K and M).
    dK, dM : tuple of scipy.sparse.csr_matrix
        ∂K/∂x_k and ∂M/∂x_k at ``x0`` (K's and M's units per parameter unit, SI).
    constant : ndarray of bool
        Whose derivative is the same at every point.
    affine : bool
        Whether K(x), M(x) come from the affine model (every derivative constant and the check
        at ``probe`` met) or from an assembly at each point.
    """

    @in_double_precision
    def __init__(
        self, drivetrain: Drivetrain, names, x0=None, *, probe=None, bounds=None, inertia_model=None
    ):
        self.drivetrain = drivetrain
        self.names = tuple(names)
        self.inertia_model = inertia_model
        fields = [find_parameter(drivetrain, n).field for n in self.names]
        self.x0 = (
            np.array([parameter_value(drivetrain, n) for n in self.names], dtype=float)
            if x0 is None
            else np.array(x0, dtype=float)
        )
        self.model0 = self._assemble(self.x0)
        candidate = np.array([f in AFFINE_FIELDS for f in fields])
        self._step = np.where(candidate, AFFINE_STEP, STEP)  # relative, per parameter
        zero = sp.csr_matrix(self.model0.K.shape)
        derivs = [
            (zero, zero) if f in DAMPING_FIELDS else self._difference(self.x0, k)
            for k, f in enumerate(fields)
        ]
        self.dK = tuple(d[0] for d in derivs)
        self.dM = tuple(d[1] for d in derivs)
        if probe is None:
            k = np.arange(len(self.names))
            probe = self.x0 * (1 + 0.05 * (k + 1) / (k.size + 1) * (-1.0) ** k)
        probe = np.array(probe, dtype=float)
        K0, M0 = self.model0.K, self.model0.M
        # the union pattern of K0 and every ∂K (M likewise): a point's K is one product of its values
        self._k_pattern = _magnitude_pattern([K0, *self.dK])
        self._m_pattern = _magnitude_pattern([M0, *self.dM])
        try:
            at = self._assemble(probe)
        except ModelError:  # a probe the components refuse: nothing verified, every point assembled
            at = None
        affine = (
            at is not None and bool(candidate.all()) and self._affine_at(probe, at) and self._valid(bounds)
        )
        constant = candidate & (at is not None)
        constant |= np.isin(fields, list(DAMPING_FIELDS))  # 0 wherever they are
        if not affine:
            for k in np.flatnonzero(constant & ~np.isin(fields, list(DAMPING_FIELDS))):
                # an affine field keeps its derivative if it is the same at the probe
                try:
                    dk, dm = self._difference(probe, k)
                except ModelError:
                    constant[k] = False
                    continue
                constant[k] = self._close(dk, self.dK[k]) and self._close(dm, self.dM[k])
        self.constant = constant
        self.affine = affine
        # what is differenced afresh at each point takes the small step: its dependence is not known
        # to be affine there
        self._step = np.where(constant, AFFINE_STEP, STEP)

    def _valid(self, bounds) -> bool:
        """Whether every value inside ``bounds`` is one the components accept: each affine field is
        valid on an interval (> 0, >= 0, a damping ratio < 1), so the box is where both corners are. The
        affine model skips the components' checks, so outside such a box every point is assembled
        (and a value out of range is refused there, as always)."""
        if bounds is None:
            return True
        for corner in bounds:
            try:
                with_parameters(self.drivetrain, dict(zip(self.names, corner)))
            except ModelError:
                return False
        return True

    def _assemble(self, x):
        m = assemble(
            with_parameters(self.drivetrain, dict(zip(self.names, x))),
            self.inertia_model,
            reduce=False,
            damping=False,
        )
        return m

    def _difference(self, x, k: int):
        """∂K/∂x_k and ∂M/∂x_k at x by a central difference of the assembly (relative step
        :data:`AFFINE_STEP` for an affine field, :data:`STEP` for another; a unit step from 0)."""
        h = self._step[k] * (abs(x[k]) if x[k] != 0 else 1.0)
        lo, hi = x.copy(), x.copy()
        lo[k] -= h
        hi[k] += h
        if x[k] == 0:  # at the bound 0: a forward difference, as exact for an affine dependence
            lo[k] = x[k]
        span = hi[k] - lo[k]
        a, b = self._assemble(lo), self._assemble(hi)
        if a.K.shape != self.model0.K.shape or b.K.shape != self.model0.K.shape:
            raise ModelError(
                "changes the model's mesh, so it has no derivative here",
                field="parameter",
                value=self.names[k],
            )
        return (b.K - a.K) / span, (b.M - a.M) / span

    @staticmethod
    def _close(A, B) -> bool:
        return _agrees(A, B, np.abs(A.diagonal()) + np.abs(B.diagonal()), AFFINE_RTOL)

    def _affine_at(self, x, at) -> bool:
        """Whether the assembly ``at`` (at x) is the affine model there (see :data:`AFFINE_RTOL`)."""
        if at.K.shape != self.model0.K.shape:
            return False
        K, M = self.matrices(x, force=True)
        dx = np.abs(x - self.x0)
        ok = True
        for A, B, A0, dA in ((at.K, K, self.model0.K, self.dK), (at.M, M, self.model0.M, self.dM)):
            # the diagonal of every term of the affine model and of the assembly itself
            d = np.abs(A0.diagonal()) + np.abs(A.diagonal())
            d += sum((a * np.abs(D.diagonal()) for a, D in zip(dx, dA)), np.zeros(d.size))
            ok = ok and _agrees(A, B, d, AFFINE_RTOL)
        return ok

    def matrices(self, x, *, force: bool = False):
        """K and M at x (CSR): the affine model, or the assembly where the model is not affine.

        Parameters
        ----------
        x : array_like
            The parameters' values, SI.
        force : bool
            Evaluate the affine model even where it is not exact (for the check).
        """
        x = np.asarray(x, dtype=float)
        if not (force or self.affine):
            m = self._assemble(x)
            return m.K, m.M
        c = np.concatenate([[1.0], x - self.x0])
        n = self.model0.K.shape
        out = []
        for indptr, indices, values in (self._k_pattern, self._m_pattern):
            out.append(sp.csr_matrix((values @ c, indices, indptr), shape=n))
        return tuple(out)

    def model(self, x):
        """The AssembledModel at x: the one at ``x0`` with K and M of x (affine), else assembled.

        Only K and M (and what no parameter changes: coordinates, stations, rigid-body motions)
        belong to x in the affine case; its C is None (K and M alone are parametrised).
        """
        x = np.asarray(x, dtype=float)
        if not self.affine:
            return self._assemble(x)
        K, M = self.matrices(x)
        return dataclasses.replace(self.model0, K=K, M=M, C=None)

    def derivatives(self, x) -> list:
        """[(∂K/∂x_k, ∂M/∂x_k)] at x: the constant ones as taken at ``x0``, the rest differenced there."""
        x = np.asarray(x, dtype=float)
        return [
            (self.dK[k], self.dM[k]) if self.constant[k] else self._difference(x, k)
            for k in range(len(self.names))
        ]
