"""The frequency solve of a calibration: the frequencies and ratios met by the stiffness, inertia and
material parameters.

The residual of a target is its relative miss over its tolerance, ``(value/target − 1)/tolerance``,
so a target is met where ``|residual| <= 1`` and the tolerances weigh the targets against each other. It
is solved by ``scipy.optimize.least_squares`` (trust-region reflective, bounds) on parameters scaled
by their starting values, with the analytic Jacobian ∂λ = φᵀ(∂K − λ∂M)φ, to the targets' own
resolution (:data:`SOLVER_FRACTION`); parameters the cost pushes against a bound are then put onto it.
The modes are tracked by shape (:mod:`.tracking`). ``starts > 1`` adds Latin-hypercube starting points
inside the bounds (each reached along a tracked path) and keeps the best.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ModelError
from ...model.assembly import assemble
from ...model.components import Drivetrain
from ..modal import ModalResult
from ..parameters import with_parameters
from ..parametrised import ParametrisedModel
from ..sensitivity import frequency_derivatives
from .tracking import Tracker, target_values, undamped_modes

__all__ = ["FrequencySolution", "frequency_solve", "solver_options", "on_bounds", "SOLVER_FRACTION"]

#: The least-squares solver's xtol, ftol and gtol, as a fraction of the smallest target tolerance.
#: A residual is a miss in units of its target's tolerance, so this asks for the misses settled to
#: 1e-4 of the tightest tolerance: a relative parameter step of xtol moves a frequency or a ratio by
#: at most half of it (λ is homogeneous of degree 1 in the stiffnesses and −1 in the inertias, each
#: share of one sign, so ``|∂ln f/∂ln p| <= ½``), a relative fall of the cost by ftol moves the misses by
#: ~ftol/2 of their size. The stopping tests bound the last step, not the distance left, which along
#: a direction the cost barely sees is a few steps: the end point's misses are a 1e-12 solve's to
#: ~1e-4 of a tolerance (1e-3 saved 8 of the study's 49 Jacobians and was ~1e-3 off in such a
#: valley). 1e-12 for every problem spent 278 Jacobians on the study, most of them closing in on
#: bounds, which :func:`_onto_bounds` does in one evaluation per parameter.
SOLVER_FRACTION = 1e-4


def _alone(model, x, k, target, wanted, at_x) -> float | None:
    """The % change of parameter k alone (the others as tuned) that meets ``target``; None if no
    change within a factor 100 either way does. The mode is followed by shape along the way."""
    from scipy.optimize import brentq

    tracker = Tracker(model, x, np.asarray(at_x))
    index = {m: j for j, m in enumerate(wanted)}

    def miss(factor: float) -> float:
        z = x.copy()
        z[k] *= factor
        try:
            result, modes = tracker.go(z)
        except ModelError:
            return np.nan  # the value is out of the component's range, or tracking lost the mode
        modes_of = {m: int(modes[index[m]]) for m in wanted}
        return float(target_values(result, modes_of, [target])[0] / target.value - 1)

    m1 = miss(1.0)
    for direction in (1.5, 1 / 1.5):
        a, fa = 1.0, m1
        b = a
        while 1e-2 < b < 1e2:
            b = a * direction
            fb = miss(b)
            if not np.isfinite(fb):
                break
            if np.sign(fb) != np.sign(fa):
                try:
                    root = brentq(miss, min(a, b), max(a, b), xtol=1e-10, rtol=1e-10)
                except ValueError:
                    # The mode is followed by shape, so a point's value depends on the path to it: near a
                    # crossing brentq's own look at the ends can disagree with ours. Bisection keeps the
                    # signs we saw.
                    root = _bisect(miss, a, fa, b)
                if root is None:
                    return None
                return float(100 * (root - 1))
            a, fa = b, fb
        tracker.go(x)  # back to the tuned point before the other direction
    return None


def _bisect(miss, a: float, fa: float, b: float, rtol: float = 1e-9) -> float | None:
    """A root of ``miss`` between ``a`` (where it is ``fa``) and ``b`` (the other sign), by bisection;
    None when a point in between cannot be evaluated."""
    for _ in range(200):
        mid = 0.5 * (a + b)
        if abs(b - a) <= rtol * abs(mid):
            return mid
        fm = miss(mid)
        if not np.isfinite(fm):
            return None
        if fm == 0:
            return mid
        if np.sign(fm) == np.sign(fa):
            a, fa = mid, fm
        else:
            b = mid
    return 0.5 * (a + b)


def _parametrise(d: Drivetrain, names, x0, lo, hi, inertia_model) -> ParametrisedModel:
    """The model as a function of the tuned parameters, its affinity checked inside the bounds.

    The check's point moves every parameter by a distinct fraction (k + 1)/(p + 1) of the way to a
    bound, alternately the upper and the lower one, so that no symmetry of the bounds hides a term
    in which two parameters act on each other.
    """
    p = len(names)
    probe = np.array(x0, dtype=float)
    for k in range(p):
        up = (k % 2 == 0 and hi[k] > x0[k]) or lo[k] >= x0[k]
        probe[k] += (k + 1) / (p + 1) * ((hi[k] if up else lo[k]) - x0[k])
    return ParametrisedModel(
        d, names, x0, probe=probe, bounds=(np.asarray(lo), np.asarray(hi)), inertia_model=inertia_model
    )


def solver_options(stop: float, max_evaluations: int) -> dict:
    """least_squares' options: trust-region reflective on unit-scaled parameters, stopping at ``stop``."""
    return dict(x_scale=1.0, method="trf", max_nfev=max_evaluations, xtol=stop, ftol=stop, gtol=stop)


def _solver_tolerance(targets) -> float:
    """xtol, ftol and gtol of the least-squares solver (see :data:`SOLVER_FRACTION`)."""
    return SOLVER_FRACTION * min(t.tolerance for t in targets)


def _solve_start(args):
    """One start of the least-squares problem, from ``point``; picklable, so an executor can run it.

    Returns the optimiser's result and the tracked modes at its end point.
    """
    from scipy.optimize import least_squares

    model, d, names, x0, lo, hi, wanted, targets, inertia_model, max_evaluations, point, at_x0 = args
    if model is None:  # on a worker: its own, the same as the caller's (the same assemblies)
        model = _parametrise(d, names, x0, lo, hi, inertia_model)
    tol = np.array([t.tolerance for t in targets])
    goal = np.array([t.value for t in targets])
    tracker = Tracker(model, x0, np.array(wanted), at_x0)
    tracker.go(point)  # reach the start along a tracked path from the model's own values
    x_start = point
    index = {m: k for k, m in enumerate(wanted)}

    def state(z):
        result, modes = tracker.go(z * x0)
        modes_of = {m: int(modes[index[m]]) for m in wanted}
        return result, modes_of

    def residual(z):
        result, modes_of = state(z)
        return (target_values(result, modes_of, targets) / goal - 1) / tol

    def jacobian(z):
        result, modes_of = state(z)
        m = sorted(set(modes_of.values()))
        df = frequency_derivatives(result, model.derivatives(z * x0), m)
        row = {mode: df[i] for i, mode in enumerate(m)}
        f = result.frequencies_hz
        J = []
        for t in targets:
            a = modes_of[t.mode]
            if t.ratio_to is None:
                dv = row[a]
            else:
                b = modes_of[t.ratio_to]
                dv = (row[a] * f[b] - f[a] * row[b]) / f[b] ** 2
            J.append(dv * x0 / t.value / t.tolerance)
        return np.array(J)

    z0 = x_start / x0
    stop = _solver_tolerance(targets)
    sol = least_squares(
        residual,
        z0,
        jac=jacobian,
        bounds=(lo / x0, hi / x0),
        **solver_options(stop, max_evaluations),
    )
    _onto_bounds(sol, residual, jacobian, lo / x0, hi / x0, stop, max_evaluations)
    _, modes = tracker.go(sol.x * x0)
    return sol, modes


def _onto_bounds(sol, residual, jacobian, lower, upper, stop: float, max_evaluations: int) -> None:
    """Put the parameters the cost pushes against a bound onto it, then re-solve the others.

    Trust-region-reflective iterates stay strictly inside the bounds and close in on an active one
    by a fraction of the remaining distance per step, so a solver stopped at the targets' resolution
    leaves such a parameter a little short of its bound (up to ~1e-3 of its range in the study),
    and 1e-12 tolerances spent most of their Jacobians on that last approach. Each parameter whose
    gradient points at its nearer bound is tried on it, nearest first, and kept there if the cost
    does not rise: at the optimum an active bound holds it exactly, while a parameter that belongs
    inside raises the cost when moved off its optimum and stays where it is. The parameters left
    free are then solved again with those on bounds fixed (a smaller problem, started next to its
    optimum), kept if the cost does not rise. Updates ``sol`` (x, fun, jac, cost) in place.
    """
    from scipy.optimize import least_squares

    z = sol.x.copy()
    g = sol.jac.T @ sol.fun
    near_lower = z - lower <= upper - z
    bound = np.where(near_lower, lower, upper)
    pushed = np.where(near_lower, g > 0, g < 0) & (z != bound)
    cost, fun, held = sol.cost, sol.fun, np.zeros(z.size, dtype=bool)
    for k in sorted(np.flatnonzero(pushed), key=lambda k: abs(z[k] - bound[k])):
        trial = z.copy()
        trial[k] = bound[k]
        r = residual(trial)
        c = 0.5 * float(r @ r)
        if c <= cost:
            z, cost, fun = trial, c, r
            held[k] = True
    if not held.any():
        return
    free = np.flatnonzero(~held & (z > lower) & (z < upper))
    if free.size:

        def at(w):
            out = z.copy()
            out[free] = w
            return out

        sub = least_squares(
            lambda w: residual(at(w)),
            z[free],
            jac=lambda w: jacobian(at(w))[:, free],
            bounds=(lower[free], upper[free]),
            **solver_options(stop, max_evaluations),
        )
        if sub.cost <= cost:
            z, cost, fun = at(sub.x), sub.cost, sub.fun
    sol.x, sol.fun, sol.cost = z, fun, cost
    sol.jac = jacobian(z)


@dataclass
class FrequencySolution:
    """What the frequency solve leaves: the tuned values of its parameters (SI), the modes before and
    at the end (the unreduced model, :func:`undamped_modes`), the tracked modes (one per wanted mode), and its
    findings per parameter and target."""

    x: np.ndarray
    start_result: ModalResult
    result: ModalResult
    modes: np.ndarray
    active: list
    widen: list
    unmet: list
    cost: float
    message: str
    starts: int


def frequency_solve(
    d, names, x0, lo, hi, targets, wanted, *, starts, seed, inertia_model, max_evaluations, executor
) -> FrequencySolution:
    """The frequencies and ratios met by the (non-damping) parameters ``names``: the module docstring."""
    goal = np.array([t.value for t in targets])
    model = _parametrise(d, names, x0, lo, hi, inertia_model)
    base = Tracker(model, x0, np.array(wanted))
    points = [x0]
    if starts > 1:
        from scipy.stats import qmc  # here: importing scipy.stats takes ~1 s, a single start needs none

        u = qmc.LatinHypercube(d=len(names), seed=seed).random(starts - 1)
        points += list(lo + u * (hi - lo))
    # In turn, every start reuses the parametrised model and the starting model's modes; on an
    # executor each worker builds them itself rather than receiving them.
    shared = (model, base.result) if executor is None else (None, None)
    jobs = [
        (shared[0], d, names, x0, lo, hi, wanted, targets, inertia_model, max_evaluations, p, shared[1])
        for p in points
    ]
    runs = list(
        executor.map(_solve_start, jobs)
        if executor is not None and len(jobs) > 1
        else map(_solve_start, jobs)
    )
    sol, modes = min(runs, key=lambda run: run[0].cost)
    # on a bound: the bound itself, not (bound/x0)·x0 an ulp away
    x = np.where(sol.x <= lo / x0, lo, np.where(sol.x >= hi / x0, hi, sol.x * x0))
    # the reported values from the model assembled at the end point
    result = undamped_modes(
        assemble(with_parameters(d, dict(zip(names, x))), inertia_model, reduce=False, damping=False), modes
    )
    modes_of = {m: int(modes[k]) for k, m in enumerate(wanted)}
    values = target_values(result, modes_of, targets)
    active, widen = on_bounds(sol.jac.T @ sol.fun, x, x0, lo, hi)
    unmet = []
    errors = values / goal - 1
    at_tuned = np.array([modes_of[m] for m in wanted])
    for i, t in enumerate(targets):
        if abs(errors[i]) <= t.tolerance * (1 + 1e-9):
            continue
        need = []
        for k, n in enumerate(names):
            change = _alone(model, x, k, t, wanted, at_tuned)
            if change is not None:
                need.append({"parameter": n, "change_percent": change})
        need.sort(key=lambda e: abs(e["change_percent"]))
        unmet.append({"target": t.label, "error": float(errors[i]), "alone_would_need": need[:3]})
    return FrequencySolution(
        x=x,
        start_result=base.result,
        result=result,
        modes=np.asarray(modes),
        active=active,
        widen=widen,
        unmet=unmet,
        cost=float(sol.cost),
        message=str(sol.message),
        starts=len(points),
    )


def on_bounds(grad, x, scale, lo, hi) -> tuple[list, list]:
    """Which parameters end on a bound the cost pushes against, and the cost's fall per % that bound
    is widened (first order), from the gradient ``grad`` of the cost in the scaled parameters x/scale
    (per % of the parameter: × 0.01·x/scale; per % of its scale where it ends at 0, a damper off)."""
    span = hi - lo
    active, widen = [], []
    for k in range(len(x)):
        g = grad[k] * 0.01 * (x[k] / scale[k] if x[k] != 0 else 1.0)
        if x[k] <= lo[k] + 1e-9 * span[k] and g > 0:
            active.append("lower"), widen.append(float(g))
        elif x[k] >= hi[k] - 1e-9 * span[k] and g < 0:
            active.append("upper"), widen.append(float(-g))
        else:
            active.append(None), widen.append(0.0)
    return active, widen
