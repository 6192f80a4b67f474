"""The commands that move parameters: ``sensitivity`` (how the modes move), ``sweep`` (a parameter
study) and ``calibrate`` (tuning to target frequencies and damping ratios, in stages)."""

from __future__ import annotations

import json
from pathlib import Path

from ...errors import ModelError
from ..console import write_plot
from ..loadmodel import load
from ..options import (
    DEFAULT_MODES,
    force_option,
    json_option,
    output_option,
    plot_option,
    table_output_option,
    whole,
)
from ..registry import PLOT, TABLE, Command

__all__ = ["COMMANDS", "calibrate", "sweep", "sensitivity"]


def calibrate(args) -> str:
    from datetime import date

    from ...analysis.staged import calibrate_stages
    from ...study.tunedfile import read_targets, write_tuned_model

    if args.output and not args.output.lower().endswith(".toml"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="TUNED.toml")
    tf = read_targets(args.targets)
    executor = None
    if args.scheduler:
        from ...analysis.sweep import dask_executor

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
    from ...analysis.parameters import find_parameter
    from ...analysis.sensitivity import lowest_elastic
    from ...analysis.sweep import check_values, dask_executor, grid_points, lhs_points, parse_range, sweep
    from ...model.assembly import assemble
    from ...system.atomic import atomic_write_text
    from ...views.progress import ProgressBar

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
    if args.modes is not None:  # more modes than the model has is refused, as `modes --modes` refuses it
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
    from ...analysis.sensitivity import lowest_elastic, sensitivities
    from ...model.assembly import assemble

    d = load(args, args.model)
    # --modes N: the lowest N elastic modes, refused beyond the model's (as `modes --modes` is);
    # without it, up to DEFAULT_MODES
    model = assemble(d, reduce=False, damping=False)
    elastic = model.n_dof - model.rigid_basis.shape[1]
    count = args.modes if args.modes is not None else max(1, min(DEFAULT_MODES, elastic))
    sens = sensitivities(d, args.params, modes=lowest_elastic(model, count, "--modes"))
    if args.plot:
        from ...views.plots import sensitivity_figure

        write_plot(args.plot, sensitivity_figure(sens), args.force)
    if args.json:
        return json.dumps(sens.to_dict(), ensure_ascii=False)
    return sens.table(d.name)


def _sensitivity_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--param",
        dest="params",
        action="append",
        metavar="NAME",
        help="COMPONENT.FIELD or MATERIAL.FIELD (repeatable; default: every parameter)",
    )
    p.add_argument(
        "--modes",
        type=whole("--modes", 1),
        metavar="N",
        help=f"the lowest N elastic modes (default: {DEFAULT_MODES}, or all the model has if fewer)",
    )
    plot_option(p, "the normalised sensitivities as a heat map")
    json_option(p)
    table_output_option(p, "the sensitivity table")
    force_option(p)


def _calibrate_options(p) -> None:
    p.add_argument("model", help="TOML model file (the stages of a targets file may name others)")
    p.add_argument("--targets", required=True, metavar="T.toml", help="targets and parameters (TOML)")
    p.add_argument(
        "--starts", type=whole("--starts", 1, "starts"), help="starting points (overrides the file's)"
    )
    json_option(p)
    output_option(p, "TUNED.toml", "write the tuned model file")
    force_option(p)
    p.add_argument("--scheduler", metavar="ADDRESS", help="run the starts on this Dask scheduler")


def _sweep_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--param",
        dest="params",
        action="append",
        required=True,
        metavar="NAME=LO:HI:N",
        help="a parameter and its values: LO:HI:N evenly spaced, or V1,V2,... (repeatable: a full grid)",
    )
    p.add_argument(
        "--lhs",
        type=whole("--lhs", 1, "sweep_points"),
        metavar="N",
        help="N Latin-hypercube points in LO:HI instead",
    )
    p.add_argument("--seed", type=whole("--seed", 0), default=0, help="seed of the hypercube (0)")
    p.add_argument(
        "--modes",
        type=whole("--modes", 1),
        metavar="N",
        help=f"elastic modes per point (default: {DEFAULT_MODES}, or all the model has if fewer)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (tcp://host:8786)")
    json_option(p, "a summary")
    output_option(p, "SWEEP.csv", "write every point as CSV")
    force_option(p)


COMMANDS = (
    Command(
        "sensitivity",
        "how every mode moves with every parameter (analytic)",
        _sensitivity_options,
        sensitivity,
        files={"-o": TABLE, "--plot": PLOT},
        table=True,
    ),
    Command(
        "calibrate",
        "tune parameters to target frequencies and damping ratios (bounded least squares)",
        _calibrate_options,
        calibrate,
        files={"-o": {".toml": "the tuned model file"}},
    ),
    Command(
        "sweep",
        "a parameter study: frequencies and damping over a grid or a hypercube",
        _sweep_options,
        sweep,
        files={"-o": {".csv": "every point"}},
    ),
)
