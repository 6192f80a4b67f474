"""Tune a model to measured frequencies and damping ratios: bounded least squares, modes tracked by
their shape.

Targets are frequencies (Hz) or ratios to another mode (published and measured data is often
normalised to f1), each with a relative tolerance; parameters (see
:mod:`flexshaft.analysis.parameters`) move inside bounds. The residual of a target is its relative
miss over its tolerance, so a target is met where ``|residual| <= 1``. Frequencies and ratios are met by
the stiffness, inertia and material parameters in bounded least squares with the analytic Jacobian
(:mod:`.frequencysolve`), the modes followed by their shape, never by their number (:mod:`.tracking`).

The model is a :class:`~flexshaft.analysis.parametrised.ParametrisedModel`: ∂K and ∂M of every
parameter are taken once per calibration, and where K and M are affine in all the parameters
(stiffnesses, inertias, E, ρ: checked at a point inside the bounds) an evaluation forms
K0 + Σ Δx_k ∂K_k and assembles nothing; a ``scale``, gear ``ratio`` or ``nu`` is assembled at each
point and differenced afresh.

Damping ratios (a target's ``damping_ratio``, with its own relative ``damping_tolerance``) are met
by the damping parameters alone, in a second solve on the frequency-tuned model
(:mod:`.dampingsolve`). Each kind of target needs a parameter of its kind and each tuned parameter a
target (:func:`~.problem.check_pairing`), checked before any solve (:mod:`.problem`) - except that a
damping ratio beside a frequency, with no damping parameter tuned, is compared and not met (the
model's damped ratio before and after, and a note): a targets file from ``flexshaft identify``
carries the measured damping with every frequency, and tuning stiffness alone is a question of its
own.

The package: :mod:`.targets` (Target, Bound), :mod:`.problem` (the checks), :mod:`.tracking`,
:mod:`.frequencysolve`, :mod:`.dampingsolve`, :mod:`.result` (CalibrationResult) and here
:func:`calibrate`, which runs them in that order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ModelError
from ...model.assembly import assemble
from ...model.components import Drivetrain
from ...system.limits import check_ceiling
from ...system.threads import follows_policy
from ...validation import check_int
from ..parameters import is_damping, parameter_value, with_parameters
from .dampingsolve import DAMPING_STEPS, DampedRatios, damping_solve, damping_unmet
from .frequencysolve import SOLVER_FRACTION, FrequencySolution, frequency_solve
from .problem import by_shape, check_bounds, check_pairing, check_parameters, check_problem, check_targets
from .result import PLAUSIBLE, SHAPE_MAC_FALL, CalibrationResult, physical_terms, shape_macs, shape_notes
from .targets import DAMPING_TOLERANCE, DEFAULT_TOLERANCE, Bound, Target
from .tracking import MAC_CLEAR, target_values, undamped_modes

__all__ = [
    "Target",
    "Bound",
    "CalibrationResult",
    "calibrate",
    "check_problem",
    "MAC_CLEAR",
    "SHAPE_MAC_FALL",
    "PLAUSIBLE",
    "SOLVER_FRACTION",
    "DEFAULT_TOLERANCE",
    "DAMPING_TOLERANCE",
    "DAMPING_STEPS",
]


@dataclass(frozen=True)
class _Problem:
    """A calibration problem checked against its model (:func:`_problem`), as the solves take it.

    Attributes
    ----------
    drivetrain : Drivetrain
        The model with the fixed parameters set.
    fixed : dict
        The fixed parameters' values, SI.
    names : list of str
        The tuned parameters.
    x0, lower, upper : ndarray
        Their starting values and absolute bounds, SI.
    frequency_parameters, damping_parameters : ndarray of int
        Which of them move the frequencies, and which only the damping (indices into ``names``).
    frequency_targets, damping_targets : list of Target
        The targets with a frequency or ratio, and those with a damping ratio.
    wanted : list of int
        The starting model's modes the targets name.
    start_model : AssembledModel
        The starting model, unreduced and undamped.
    """

    drivetrain: Drivetrain
    fixed: dict
    names: list
    x0: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    frequency_parameters: np.ndarray
    damping_parameters: np.ndarray
    frequency_targets: list
    damping_targets: list
    wanted: list
    start_model: object


def _problem(drivetrain: Drivetrain, targets, params, inertia_model) -> _Problem:
    """The problem checked before any solve (:func:`~.problem.check_problem`'s checks, the bounds
    against the starting values, the measured shapes against the modes); ``targets`` is not empty."""
    check_parameters(drivetrain, params)
    fixed = {b.name: b.fixed for b in params if b.fixed is not None}
    d = with_parameters(drivetrain, fixed) if fixed else drivetrain
    free = [b for b in params if b.fixed is None]
    if not free:
        raise ModelError(
            "nothing to tune", field="parameter", valid="at least one parameter with bounds or percent"
        )
    names = [b.name for b in free]
    x0 = np.array([parameter_value(d, n) for n in names])
    lims = np.array([b.limits(v) for b, v in zip(free, x0)])
    lo, hi = lims[:, 0], lims[:, 1]
    check_bounds(d, params, free, x0, lo, hi)
    m0 = assemble(d, inertia_model, reduce=False, damping=False)
    check_targets(targets, m0)
    check_pairing(d, targets, params)
    targets = by_shape(m0, targets)
    ftargets = [t for t in targets if t.has_frequency]
    damp = np.array([is_damping(d, n) for n in names])
    return _Problem(
        drivetrain=d,
        fixed=fixed,
        names=names,
        x0=x0,
        lower=lo,
        upper=hi,
        frequency_parameters=np.flatnonzero(~damp),
        damping_parameters=np.flatnonzero(damp),
        frequency_targets=ftargets,
        damping_targets=[t for t in targets if t.damping_ratio is not None],
        wanted=sorted({t.mode for t in targets} | {t.ratio_to for t in ftargets if t.ratio_to is not None}),
        start_model=m0,
    )


def _frequency_stage(p: _Problem, **solve) -> FrequencySolution:
    """The frequency solve over the parameters that move the frequencies; with none, the starting model's
    modes as they are."""
    k = p.frequency_parameters
    if k.size:
        names = [p.names[j] for j in k]
        return frequency_solve(
            p.drivetrain, names, p.x0[k], p.lower[k], p.upper[k], p.frequency_targets, p.wanted, **solve
        )
    result = undamped_modes(p.start_model, p.wanted)
    return FrequencySolution(
        x=np.zeros(0),
        start_result=result,
        result=result,
        modes=np.array(p.wanted),
        active=[],
        widen=[],
        unmet=[],
        cost=0.0,
        message="",
        starts=1,
    )


def _damping_stage(
    p: _Problem, tuned, fsol: FrequencySolution, modes_of: dict, inertia_model, max_evaluations
):
    """The damping ratios at the start and the end, and the damping solve (None without damping
    parameters: the ratios beside frequencies are then compared, not met).

    ``tuned`` is the model with the frequency solve's values, ``modes_of`` its tracked modes.
    """
    k, targets = p.damping_parameters, p.damping_targets
    if not targets:
        return np.zeros(0), np.zeros(0), None
    start_modes, end_modes = [t.mode for t in targets], [modes_of[t.mode] for t in targets]
    names = [p.names[j] for j in k]
    zinit = DampedRatios(p.drivetrain, names, inertia_model, fsol.start_result, start_modes).at(p.x0[k])[0]
    ratios = DampedRatios(tuned, names, inertia_model, fsol.result, end_modes)
    if not k.size:
        return zinit, ratios.at([])[0], None
    zsol = damping_solve(ratios, p.x0[k], p.lower[k], p.upper[k], targets, max_evaluations)
    return zinit, zsol.values, zsol


def _joined(*messages: str) -> str:
    """The solves' messages and the notes, in one line."""
    return "; ".join(m.rstrip(".") for m in messages if m)


@follows_policy
def calibrate(
    drivetrain: Drivetrain,
    targets,
    params,
    *,
    starts: int = 1,
    seed: int = 0,
    inertia_model: str | None = None,
    max_evaluations: int = 1000,
    executor=None,
) -> CalibrationResult:
    """Tune parameters inside their bounds so the modes hit their targets.

    Frequencies and ratios are met by the stiffness, inertia and material parameters (bounded least
    squares, modes tracked by shape: the module docstring). Damping ratios are met by the damping
    parameters (:data:`~flexshaft.analysis.parameters.DAMPING_FIELDS`: a shaft's ``damping_ratio``
    or ``damping``, a flexible body's ``damping_ratio``, a coupling's ``damping``, a gear's
    ``mesh_damping``, ``rayleigh.alpha``/``beta`` or the two ``rayleigh.damping_ratios``) in a
    second solve on the tuned model: they leave the undamped modes where the first put them (see
    :func:`damping_solve`).

    Parameters
    ----------
    drivetrain : Drivetrain
    targets : sequence of Target
    params : sequence of Bound
        Parameters to tune (bounds or ± %) or to fix. A damping parameter may start at 0 (no damper
        yet) where it has absolute bounds.
    starts : int
        Starting points of the frequency solve: the model's own values, and ``starts − 1``
        Latin-hypercube points inside the bounds (for a problem that is not convex). The best end
        point is kept. (The damping solve is linear to first order in the damping: one start.)
    seed : int
        Seed of those points.
    inertia_model : str, optional
    max_evaluations : int
        Model evaluations per start (the optimiser's ``max_nfev``).
    executor : concurrent.futures.Executor, optional
        Runs the starts in parallel (local processes, or a Dask cluster's executor); in turn
        without one.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    ModelError
        Before the optimiser starts, for a problem the model cannot pose (:func:`check_problem`:
        mode numbers that are not the model's elastic modes, a target given twice, a shape of the
        wrong length, an unknown or repeated parameter, a fixed value or bounds outside what the
        parameter can take, a damping-only target without a damping parameter to tune (beside a
        frequency the ratio is then compared, not met) or a damping parameter without a damping
        target, and likewise for frequencies), or bounds that do not
        contain the model's value or leave no room.
    """
    targets, params = list(targets), list(params)
    if not targets:
        raise ModelError("no targets", field="target", valid="at least one [[target]]")
    starts = check_ceiling("starts", check_int(starts, "starts", lo=1), field="starts")
    problem = _problem(drivetrain, targets, params, inertia_model)
    names, fk, zk = problem.names, problem.frequency_parameters, problem.damping_parameters
    fsol = _frequency_stage(
        problem,
        starts=starts,
        seed=seed,
        inertia_model=inertia_model,
        max_evaluations=max_evaluations,
        executor=executor,
    )
    x = problem.x0.copy()
    x[fk] = fsol.x
    active, widen = [None] * len(names), [0.0] * len(names)
    for j, k in enumerate(fk):
        active[k], widen[k] = fsol.active[j], fsol.widen[j]
    unmet, cost, message = list(fsol.unmet), fsol.cost, fsol.message
    modes_of = {m: int(fsol.modes[j]) for j, m in enumerate(problem.wanted)}
    tuned_frequencies = with_parameters(problem.drivetrain, {names[k]: x[k] for k in fk})
    zinit, zvalues, zsol = _damping_stage(
        problem, tuned_frequencies, fsol, modes_of, inertia_model, max_evaluations
    )
    if zsol is None and problem.damping_targets:
        message = _joined(message, "damping ratios compared, not tuned: no damping parameter is tuned")
    if zsol is not None:
        x[zk] = zsol.x
        for j, k in enumerate(zk):
            active[k], widen[k] = zsol.active[j], zsol.widen[j]
        unmet += damping_unmet(problem.drivetrain, [names[k] for k in zk], zsol, problem.damping_targets)
        cost += zsol.cost
        message = _joined(message, zsol.message)
    return _result(problem, fsol, modes_of, x, active, widen, unmet, float(cost), message, zinit, zvalues)


def _result(
    p: _Problem, fsol: FrequencySolution, modes_of, x, active, widen, unmet, cost, message, zinit, zvalues
):
    """The CalibrationResult: the solves' findings, the targets' values before and after (from the
    models assembled at the start and the end point) and the measured shapes' MAC with their modes."""
    d, ftargets, ztargets, wanted = p.drivetrain, p.frequency_targets, p.damping_targets, p.wanted
    start_result, result = fsol.start_result, fsol.result
    values = target_values(result, modes_of, ftargets) if ftargets else np.zeros(0)
    initial_values = (
        target_values(start_result, {m: m for m in wanted}, ftargets) if ftargets else np.zeros(0)
    )
    shape_mac = shape_macs(result, modes_of, ftargets)
    initial_shape_mac = shape_macs(start_result, {m: m for m in wanted}, ftargets)
    message = _joined(message, *shape_notes(ftargets, initial_shape_mac, shape_mac))
    return CalibrationResult(
        physics=physical_terms(d, p.names, p.x0, x),
        names=tuple(p.names),
        initial=p.x0,
        tuned=x,
        lower=p.lower,
        upper=p.upper,
        targets=tuple(ftargets),
        initial_values=initial_values,
        values=values,
        modes=np.array([modes_of[t.mode] for t in ftargets], dtype=int),
        active=tuple(active),
        widen=tuple(widen),
        unmet=tuple(unmet),
        drivetrain=with_parameters(d, dict(zip(p.names, x))),
        fixed=p.fixed,
        cost=cost,
        starts=fsol.starts,
        message=message,
        damping_targets=tuple(ztargets),
        initial_damping=np.asarray(zinit, dtype=float),
        damping=np.asarray(zvalues, dtype=float),
        damping_modes=np.array([modes_of[t.mode] for t in ztargets], dtype=int),
        initial_shape_mac=initial_shape_mac,
        shape_mac=shape_mac,
    )
