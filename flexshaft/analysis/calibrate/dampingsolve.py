"""The damping solve of a calibration: damping ratios met by the damping parameters alone, on the
frequency-tuned model.

A damping parameter (a shaft's or flexible body's ``damping_ratio``, a damper, ``rayleigh.alpha``/``beta``
or the two ``rayleigh.damping_ratios``) enters C alone and leaves the undamped modes - the frequency
solve's - where they are. The ratio compared is the damped mode's, ``ξ = −Re λ/|λ|``, of the model as
``flexshaft modes`` assembles it; the solve is linear to first order in the damping
(:func:`damping_solve`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ModelError
from ...linalg.mac import mac
from ...model.assembly import assemble
from ...model.components import Drivetrain
from ..modal import DEFAULT_LISTED, ModalResult, modal_analysis
from ..parameters import parameter_domain, with_parameters
from .frequencysolve import SOLVER_FRACTION, on_bounds, solver_options
from .tracking import MAC_CLEAR

__all__ = ["DampedRatios", "DampingSolution", "damping_solve", "damping_unmet", "DAMPING_STEPS"]

#: Steps of the damping solve (first-order Jacobian, damped-mode residual) before it reports that the
#: damped ratios did not settle; each step gains a factor O(ξ²) (the damped ratio's part beyond first
#: order): two or three suffice.
DAMPING_STEPS = 20
#: Step of the difference that gives the damping Jacobian, a fraction of each parameter's scale (its
#: value, or its bounds' width from 0): small enough to stay where the model takes the value (two
#: Rayleigh ratios far apart imply a negative α or β), large against round-off.
DAMPING_STEP = 1e-3
#: The first-order ratios φᵀCφ/(2ω) are affine in every damping parameter (C is, the modes do not move):
#: the prediction from one linearisation agrees with an evaluation to round-off, ~1e-13 of the ratio;
#: beyond this fraction of the target ratio the solve linearises afresh (a safeguard, not expected).
AFFINE_DAMPING = 1e-9


class DampedRatios:
    """The damping ratios of some modes as a function of the damping parameters ``names`` of ``d``.

    The model is the one ``flexshaft modes`` reports: assembled with flexible bodies reduced and
    every damping (a shaft's modal damping, a body's own, dampers, Rayleigh), its damped modes solved
    (:func:`~flexshaft.analysis.damped.damped_modes`: ``ξ = −Re λ/|λ|``). The modes are named as numbers
    of ``result`` (the unreduced undamped modes the frequency solve tracked); where the model has
    flexible bodies, the reduced model's modes are paired with them by shape (inertia-weighted MAC
    of the node DOFs), once: no damping parameter moves an undamped mode.
    """

    def __init__(self, d: Drivetrain, names, inertia_model, result: ModalResult, modes):
        self.d, self.names, self.inertia_model = d, list(names), inertia_model
        self.result, self.modes = result, np.asarray(modes, dtype=int)
        self.count: int | None = None
        self.index: np.ndarray | None = None

    def _pair(self, r: ModalResult) -> np.ndarray:
        if not r.model.bodies:
            return self.modes  # the same K and M as the unreduced model: the same modes, in order
        ref = self.result.model
        macs = mac(ref.T @ self.result.shapes[:, self.modes], r.model.T @ r.shapes, ref.M_nodes)
        macs[:, r.rigid] = 0.0
        best = np.argmax(macs, axis=1)
        top = macs[np.arange(best.size), best]
        if np.any(top < MAC_CLEAR) or np.unique(best).size != best.size:
            k = int(np.argmin(top))
            raise ModelError(
                f"mode {int(self.modes[k])} has no clear partner among the modes of the model with its "
                f"flexible bodies reduced (best MAC {top[k]:.2f})",
                field="target.damping_ratio",
                valid="flexible bodies reduced with enough modes for the targets' modes (reduce = "
                "{modes = n} or {cutoff_hz = f} above them)",
            )
        return best

    def at(self, x, *, damped: bool = True):
        """(ξ of the damped modes or None without ``damped``, first-order ξ = φᵀCφ/(2ω)) of the modes at
        the damping parameters' values ``x`` (SI)."""
        m = assemble(with_parameters(self.d, dict(zip(self.names, x))), self.inertia_model)
        if self.count is None:
            # as many as `flexshaft modes` lists by default, or past the highest target's mode: a large
            # model's damped modes are solved in their subspace (to second order in the damping)
            self.count = min(m.n_dof, max(DEFAULT_LISTED, int(self.modes.max()) + 6))
        r = modal_analysis(m, self.count, damped=damped)
        if self.index is None:
            self.index = self._pair(r)
        phi, w = r.shapes[:, self.index], r.omega[self.index]
        C = m.C
        first = np.zeros(w.size) if C is None else np.einsum("ij,ij->j", phi, C @ phi) / (2 * w)
        return (r.damping_ratios[self.index] if damped else None), first


@dataclass
class DampingSolution:
    """The damping solve's end: the parameters (SI), the damped ratios there, the first-order Jacobian
    ∂ξ/∂x, the cost and findings, and what the solve did."""

    x: np.ndarray
    values: np.ndarray
    jacobian: np.ndarray
    active: list
    widen: list
    cost: float
    message: str


def _damping_jacobian(ratios: DampedRatios, x, first, lo, hi, scale) -> np.ndarray:
    """∂ξ/∂x of the first-order ratios, one difference per parameter: φᵀCφ/(2ω) is affine in every
    damping parameter (C is; the modes stay), so any step is exact up to round-off, ~1e-13 of ξ over
    the step's :data:`DAMPING_STEP` of the parameter's scale: 1e-10 of the derivative. The step goes
    towards the farther bound, or the other way where the model refuses the value (two Rayleigh ratios
    whose α or β would be negative)."""
    G = np.empty((first.size, x.size))
    for k in range(x.size):
        ahead = 1.0 if hi[k] - x[k] >= x[k] - lo[k] else -1.0
        for sign in (ahead, -ahead):
            y = np.array(x, dtype=float)
            y[k] = min(max(x[k] + sign * DAMPING_STEP * scale[k], lo[k]), hi[k])
            try:
                G[:, k] = (ratios.at(y, damped=False)[1] - first) / (y[k] - x[k])
                break
            except ModelError:
                if sign != ahead:
                    raise
    return G


def damping_solve(ratios: DampedRatios, x0, lo, hi, targets, max_evaluations: int) -> DampingSolution:
    """Meet the damping targets with the damping parameters (bounded least squares).

    The residual of a target is (ξ/ξ_target − 1)/damping_tolerance, ξ the damped mode's ratio
    ``−Re λ/|λ|`` (what ``flexshaft modes`` reports). To first order in the damping ξ = φᵀCφ/(2ω), which
    is affine in every damping parameter - for Rayleigh damping exactly α/(2ω) + βω/2 - so its
    Jacobian G, taken once (:func:`_damping_jacobian`), makes each step a linear bounded least
    squares problem, solved to the targets' resolution (:data:`SOLVER_FRACTION`) by a dogbox
    trust-region method from the present point (Gauss-Newton steps of least norm: an
    under-determined problem - α and β for one target - moves the parameters least). The damped
    ratio differs from the first-order one by a fraction O(ξ²) of it (nothing for proportional
    damping, whose modes stay real; ~1e-7 on Customer 1 at 0.53 % on its parts), far inside any
    damping tolerance - yet it is what the model reports, so that difference, evaluated at the last
    point, is carried as a constant into the next step (Newton with the first-order Jacobian), until
    the damped ratios agree with the prediction to the resolution: one or two steps more. Parameters
    are scaled by their starting value, or by their bounds' width where they start at 0.
    """
    from scipy.optimize import least_squares

    goal = np.array([t.damping_ratio for t in targets], dtype=float)
    tol = np.array([t.damping_tolerance for t in targets], dtype=float)
    stop = SOLVER_FRACTION * float(tol.min())
    scale = np.where(x0 != 0, np.abs(x0), hi - lo)
    exact, first = ratios.at(x0)
    G = _damping_jacobian(ratios, x0, first, lo, hi, scale)
    base, f_base, x = np.array(x0, dtype=float), first, np.array(x0, dtype=float)
    settled, steps = False, 0
    lower, upper = lo / scale, hi / scale
    while steps < DAMPING_STEPS and not settled:
        steps += 1
        A = G * scale[None, :] / (goal * tol)[:, None]  # ∂residual/∂(x/scale), constant
        delta = exact - first  # the damped ratios beyond first order, carried as a constant

        def residual(u, G=G, base=base, f_base=f_base, delta=delta):
            return ((f_base + G @ (u * scale - base) + delta) / goal - 1) / tol

        def jacobian(u, A=A):
            return A

        # dogbox: its steps leave a bound at once (trust-region reflective crawls off one, and a damper
        # starts at its bound 0), and it ends on the bounds it holds
        options = solver_options(stop, max_evaluations) | {"method": "dogbox"}
        sol = least_squares(residual, x / scale, jac=jacobian, bounds=(lower, upper), **options)
        x_new = np.where(sol.x <= lower, lo, np.where(sol.x >= upper, hi, sol.x * scale))
        linear = f_base + G @ (x_new - base)
        exact, first = ratios.at(x_new)
        settled = bool(np.max(np.abs(exact - (linear + delta)) / (goal * tol)) <= stop)
        if np.any(np.abs(first - linear) > AFFINE_DAMPING * goal):  # not affine after all: afresh here
            G, base, f_base = _damping_jacobian(ratios, x_new, first, lo, hi, scale), x_new, first
            settled = False
        x = x_new
    r = (exact / goal - 1) / tol
    A = G * scale[None, :] / (goal * tol)[:, None]
    active, widen = on_bounds(A.T @ r, x, scale, lo, hi)
    how = "step" if steps == 1 else "steps"
    message = (
        f"damping: {steps} {how} of bounded least squares on the first-order ratios, corrected to the "
        "damped modes"
    )
    if not settled:
        message += f" - the damped ratios did not settle in {DAMPING_STEPS} steps (reported as reached)"
    return DampingSolution(
        x=x, values=exact, jacobian=G, active=active, widen=widen, cost=0.5 * float(r @ r), message=message
    )


def damping_unmet(d: Drivetrain, names, zs: DampingSolution, targets) -> list:
    """For each damping target missed: the damping parameters that alone would meet it (the change, %,
    from the first-order Jacobian: exact to O(ξ²) relative), within a factor 100 of the tuned value and
    the values the parameter can take; the three smallest changes."""
    out = []
    for i, t in enumerate(targets):
        error = zs.values[i] / t.damping_ratio - 1
        if abs(error) <= t.damping_tolerance * (1 + 1e-9):
            continue
        need = []
        for k, n in enumerate(names):
            g, v = zs.jacobian[i, k], zs.x[k]
            if g == 0 or v == 0:
                continue
            new = v + (t.damping_ratio - zs.values[i]) / g
            if parameter_domain(d, n).contains(new) and 1e-2 <= new / v <= 1e2:
                need.append({"parameter": n, "change_percent": float(100 * (new / v - 1))})
        need.sort(key=lambda e: abs(e["change_percent"]))
        out.append({"target": t.damping_label, "error": float(error), "alone_would_need": need[:3]})
    return out
