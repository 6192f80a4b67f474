"""The commands that move parameters: ``sensitivity`` (how the modes move), ``sweep`` (a parameter
study) and ``calibrate`` (tuning to target frequencies and damping ratios, in stages)."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import ModelError
from .common import DEFAULT_MODES, load, write_plot

__all__ = ["calibrate", "sweep", "sensitivity"]


def calibrate(args) -> str:
    from datetime import date

    from ..analysis.staged import calibrate_stages
    from ..study.tunedfile import read_targets, write_tuned_model

    if args.output and not args.output.lower().endswith(".toml"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="TUNED.toml")
    tf = read_targets(args.targets)
    executor = None
    if args.scheduler:
        from ..analysis.sweep import dask_executor

        def executor():  # connected once every stage is checked
            return dask_executor(args.scheduler)

    staged = calibrate_stages(
        tf, lambda path: load(args, path), model=args.model, starts=args.starts, executor=executor
    )
    tuned_model = None
    if args.output:
        last, values = staged.last, staged.tuned_values()
        header = (
            f"{last.drivetrain.name}, tuned by flexshaft calibrate on {date.today().isoformat()} "
            f"against {Path(tf.source).name}\n"
            f"from {last.model}; tuned values (SI): " + ", ".join(f"{k} = {v:.9g}" for k, v in values.items())
        )
        out = write_tuned_model(
            args.output, last.model, last.drivetrain, values, header=header, overwrite=args.force
        )
        tuned_model = f"{out}"
    if args.json:
        doc = staged.to_dict()
        if tuned_model is not None:
            doc["tuned_model"] = tuned_model
        return json.dumps(doc, ensure_ascii=False)
    text = staged.table().rstrip()
    if tuned_model is not None:
        text += f"\n\ntuned model: {tuned_model}"
    return text


def sweep(args) -> str:
    from ..analysis.sensitivity import find_parameter, lowest_elastic
    from ..analysis.sweep import check_values, dask_executor, grid_points, lhs_points, parse_range, sweep
    from ..model.assembly import assemble
    from ..system.atomic import atomic_write_text
    from ..views.progress import ProgressBar

    if args.output and not args.output.lower().endswith(".csv"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="SWEEP.csv")
    ranges = dict(parse_range(p) for p in args.params)
    if len(ranges) != len(args.params):
        raise ModelError("a parameter is given twice", field="--param", value=", ".join(args.params))
    d = load(args, args.model)
    for spec, name in zip(args.params, ranges):  # names and values checked before any point is built
        try:
            find_parameter(d, name)
        except ModelError as err:
            raise ModelError(err.message, field="--param", value=spec, valid=err.valid) from None
        check_values(d, name, ranges[name], "--param", spec)
    if args.modes is not None:  # more modes than the model has is refused, as `modes --count` refuses it
        lowest_elastic(assemble(d), args.modes, "--modes")
    if args.lhs:
        points = lhs_points({n: (v.min(), v.max()) for n, v in ranges.items()}, args.lhs, args.seed)
    else:
        points = grid_points(ranges)
    executor = dask_executor(args.scheduler) if args.scheduler else None
    res = sweep(d, list(ranges), points, modes=args.modes, executor=executor, progress=ProgressBar("sweep"))
    lines = []
    if args.output:
        path = atomic_write_text(args.output, res.to_csv(), overwrite=args.force)
        lines.append(f"sweep: {path}")
    if args.json:
        return json.dumps(res.to_dict(), ensure_ascii=False)
    lines.insert(0, res.summary(lhs=bool(args.lhs), scheduler=args.scheduler))
    lines.append(res.table())
    return "\n".join(lines)


def sensitivity(args) -> str:
    from ..analysis.sensitivity import lowest_elastic, sensitivities
    from ..model.assembly import assemble

    d = load(args, args.model)
    # --modes N: the lowest N elastic modes, refused beyond the model's (as `modes --count` is);
    # without it, up to DEFAULT_MODES
    model = assemble(d, reduce=False, damping=False)
    elastic = model.n_dof - model.rigid_basis.shape[1]
    count = args.modes if args.modes is not None else max(1, min(DEFAULT_MODES, elastic))
    sens = sensitivities(d, args.params, modes=lowest_elastic(model, count, "--modes"))
    if args.plot:
        from ..views.plots import sensitivity_figure

        write_plot(args.plot, sensitivity_figure(sens), args.force)
    if args.json:
        return json.dumps(sens.to_dict(), ensure_ascii=False)
    return sens.table(d.name)
