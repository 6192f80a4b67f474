"""A calibration in stages: each stage tunes its parameters of its model, later stages carry the values
earlier ones tuned (fixed), and the last stage's values make the tuned model.

The stages come from a targets file (:func:`flexshaft.study.tunedfile.read_targets`); every stage's
targets and parameters are checked against its model before the first one runs, so a mistake in
stage 3 costs no solve of stages 1 and 2. Errors are located in the targets file, its entries named
as the file has them (``[[stage]] #2 [[target]] #1``). A stage's targets may carry damping ratios,
met by its damping parameters (:func:`~flexshaft.analysis.calibrate.calibrate`); tuned damping is
carried into later stages like any other value. Writing the tuned model is
:func:`flexshaft.study.tunedfile.write_tuned_model`'s (the command line and the study both call it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..errors import ModelError
from ..model.components import Drivetrain
from ..system.threads import follows_policy
from .calibrate import CalibrationResult, calibrate, check_problem
from .parameters import parameters, with_parameters

__all__ = ["CalibrationStage", "StagedCalibration", "calibrate_stages"]


@dataclass(frozen=True)
class CalibrationStage:
    """One stage's calibration.

    Attributes
    ----------
    name : str
        The stage's name (``""`` for a targets file without stages).
    model : Path
        The model file it tuned.
    drivetrain : Drivetrain
        That model, as loaded (before any value was put in).
    carried : dict
        Values earlier stages tuned that this model has a parameter for, SI, held fixed here.
    result : CalibrationResult
        The calibration itself.
    """

    name: str
    model: Path
    drivetrain: Drivetrain
    carried: dict
    result: CalibrationResult

    def to_dict(self) -> dict:
        """This stage's entry of the ``flexshaft calibrate --json`` document."""
        carried = {k: float(v) for k, v in self.carried.items()}
        return {"name": self.name, "model": str(self.model), "carried": carried} | self.result.to_dict()

    def tuned_values(self) -> dict:
        """Every value this stage's model is run with: carried, fixed and tuned (SI)."""
        res = self.result
        return self.carried | res.fixed | dict(zip(res.names, res.tuned))


@dataclass(frozen=True)
class StagedCalibration:
    """The stages of a calibration, in the order they ran.

    Attributes
    ----------
    stages : tuple of CalibrationStage
    source : str
        The targets file.
    """

    stages: tuple
    source: str

    @property
    def last(self) -> CalibrationStage:
        """The last stage: its model with its values is the tuned model."""
        return self.stages[-1]

    def tuned_values(self) -> dict:
        """What the tuned model gets: the last stage's carried, fixed and tuned values (SI)."""
        return self.last.tuned_values()

    def to_dict(self) -> dict:
        """The ``flexshaft calibrate --json`` document (without ``tuned_model``, which the writer adds)."""
        return {"stages": [s.to_dict() for s in self.stages]}

    def table(self) -> str:
        """The ``flexshaft calibrate`` table: per stage
        its parameters (initial, tuned, bounds, change %, active bounds), its targets (initial, tuned,
        error %, tolerance %, met), its damping targets (target, initial and tuned damping ratio in %,
        error %, tolerance %, met) and what one parameter alone would need for a missed target."""
        import numpy as np

        body = []
        for st in self.stages:
            res, fx = st.result, st.carried
            body += [
                f"stage {st.name!r} ({st.model}): {res.starts} start(s), cost {res.cost:.4g}; {res.message}"
            ]
            if fx:
                body.append("  carried, fixed: " + ", ".join(f"{k} = {v:.6g}" for k, v in fx.items()))
            width = max(12, *(len(n) for n in res.names))
            body.append(
                f"  {'parameter':<{width}} {'initial':>12} {'tuned':>12} {'lower':>12} {'upper':>12} "
                f"{'change %':>9}  bound"
            )
            for k, n in enumerate(res.names):
                act = res.active[k]
                note = f"{act}: widening it 1 % lowers the cost by {res.widen[k]:.3g}" if act else ""
                change = res.change_percent[k]
                change = f"{change:9.3f}" if np.isfinite(change) else f"{'-':>9}"  # a damper from 0
                body.append(
                    f"  {n:<{width}} {res.initial[k]:12.6g} {res.tuned[k]:12.6g} {res.lower[k]:12.6g} "
                    f"{res.upper[k]:12.6g} {change}  {note}"
                )
            if res.targets:
                body.append(
                    f"  {'target':<16} {'mode':>4} {'initial':>10} {'tuned':>10} {'error %':>8} "
                    f"{'tol %':>6}  met"
                )
            rows = zip(res.targets, res.modes, res.initial_values, res.values, res.errors, res.met)
            for k, (t, mo, a, v, e, ok) in enumerate(rows):
                # a measured shape: its MAC with the mode before and after
                mac = res.shape_mac[k] if k < len(res.shape_mac) else np.nan
                shape = f"  shape MAC {res.initial_shape_mac[k]:.3f} -> {mac:.3f}" if np.isfinite(mac) else ""
                body.append(
                    f"  {t.label:<16} {mo:>4} {a:10.5g} {v:10.5g} {100 * e:8.3f} {100 * t.tolerance:6.2f}  "
                    f"{'yes' if ok else 'NO '}{shape}".rstrip()
                )
            if res.damping_targets:
                body.append(
                    f"  {'damping target':<16} {'mode':>4} {'initial %':>10} {'tuned %':>10} {'error %':>8} "
                    f"{'tol %':>6}  met"
                )
            rows = zip(
                res.damping_targets,
                res.damping_modes,
                res.initial_damping,
                res.damping,
                res.damping_errors,
                res.damping_met,
            )
            for t, mo, a, v, e, ok in rows:
                body.append(
                    f"  {t.damping_label:<16} {mo:>4} {100 * a:10.4f} {100 * v:10.4f} {100 * e:8.3f} "
                    f"{100 * t.damping_tolerance:6.2f}  {'yes' if ok else 'NO'}"
                )
            for u in res.unmet:
                need = "; ".join(
                    f"{e['parameter']} {e['change_percent']:+.1f} %" for e in u["alone_would_need"]
                )
                body.append(
                    f"  {u['target']} is missed by {100 * u['error']:+.2f} %: alone it would need {need}"
                )
            body.append("")
        return "\n".join(body)

    def plot(self):
        """Each stage's targets before and after tuning and its parameters' changes, a matplotlib
        Figure (never shown)."""
        from ..views.plots import calibration_figure

        return calibration_figure(self)


def _in_stage(err: ModelError, stage, source: str) -> ModelError:
    """The error located in the targets file, its entry named as the file has it."""
    component = err.component
    if stage.where and component and component.startswith("[["):
        component = stage.where + component
    elif stage.where and not component:  # the stage as a whole (its optimiser lost a mode): say which
        component = f"{stage.where.strip()} {stage.name!r}"
    return err.replaced(file=err.file or source, component=component)


def _carried(d: Drivetrain, tuned: dict) -> dict:
    """The earlier stages' tuned values this model has a parameter for."""
    names = {p.name for p in parameters(d)}
    return {k: v for k, v in tuned.items() if k in names}


def _checked_models(targets, load, model) -> list:
    """Every stage's (model path, drivetrain), its targets and parameters checked against it."""
    models, earlier = [], {}  # earlier: stage name -> the parameters it tunes
    for stage in targets.stages:
        path = stage.model or Path(model)
        d = load(str(path))
        try:
            check_problem(d, stage.targets, stage.parameters)
        except ModelError as err:
            raise _in_stage(err, stage, targets.source) from None
        has = {p.name for p in parameters(d)}
        for name in stage.carry_from if stage.carry_from is not None else earlier:
            for k, b in enumerate(stage.parameters):
                if b.name in earlier[name] and b.name in has:
                    raise ModelError(
                        f"was tuned in the earlier stage {name!r} and is carried into {stage.name!r}, fixed",
                        file=targets.source,
                        component=f"{stage.where}[[parameter]] #{k + 1}",
                        field="parameter",
                        value=b.name,
                        valid="leave it out of the later stage",
                    )
        earlier[stage.name] = {b.name for b in stage.parameters if b.fixed is None}
        models.append((path, d))
    return models


@follows_policy
def calibrate_stages(
    targets,
    load: Callable[[str], Drivetrain],
    *,
    model=None,
    starts: int | None = None,
    executor=None,
) -> StagedCalibration:
    """Run the stages of a targets file in order, each carrying what the earlier ones tuned.

    Parameters
    ----------
    targets : TargetsFile
        As :func:`flexshaft.study.tunedfile.read_targets` reads it: stages, ``starts``, ``seed``, ``source``.
    load : callable
        ``load(path) -> Drivetrain``: loads a stage's model file (the caller's trust and cache settings).
    model : str or Path, optional
        The model file of stages that name none.
    starts : int, optional
        Starting points of each stage's optimiser (default: the targets file's).
    executor : concurrent.futures.Executor or callable, optional
        Runs the starts (e.g. :func:`flexshaft.analysis.sweep.dask_executor`); a callable without
        ``submit`` is called for it once every stage is checked (a mistake in the file then costs
        no connection to a cluster).

    Returns
    -------
    StagedCalibration
        Per stage: its name, model path, drivetrain, carried values and :class:`CalibrationResult`.

    Raises
    ------
    ModelError
        Located in the targets file (``file``, its entry as ``component``), before any stage runs
        where a stage's targets or parameters do not fit its model.
    """
    if model is None and any(stage.model is None for stage in targets.stages):
        raise ModelError(
            "a stage names no model",
            file=targets.source,
            field="model",
            valid="model = FILE.toml, or a model",
        )
    starts = starts or targets.starts
    models = _checked_models(targets, load, model)
    if callable(executor) and not hasattr(executor, "submit"):
        executor = executor()
    tuned: dict = {}  # stage name -> its tuned values
    done = []
    for stage, (path, d) in zip(targets.stages, models):
        pool: dict = {}
        for name in stage.carry_from if stage.carry_from is not None else tuned:
            pool |= tuned[name]
        fixed = _carried(d, pool)
        try:
            res = calibrate(
                with_parameters(d, fixed) if fixed else d,
                stage.targets,
                stage.parameters,
                starts=starts,
                seed=targets.seed,
                executor=executor,
            )
        except ModelError as err:
            raise _in_stage(err, stage, targets.source) from None
        tuned[stage.name] = dict(zip(res.names, res.tuned))
        done.append(CalibrationStage(stage.name, path, d, fixed, res))
    return StagedCalibration(tuple(done), targets.source)
