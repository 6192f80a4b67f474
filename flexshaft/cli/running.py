"""The commands about a turning line: ``simulate`` (time runs), ``campbell`` (modes against speed)
and ``spectrum`` (a simulated or measured signal's spectrum, peaks and damping)."""

from __future__ import annotations

import json

from ..errors import ModelError
from .common import load, signal_units, write_plot

__all__ = ["simulate", "campbell", "spectrum"]

# simulate: the library names its arguments; the command line names the options that set them.
SIMULATE_OPTION_OF = {
    "torque": "--torque",
    "time": "--step-time",
    "frequency": "--frequency",
    "speed": "--speed",
    "end_speed": "--end-speed",
    "ramp_time": "--ramp-time",
    "load": "--load",
    "kp": "--kp",
    "ki": "--ki",
    "tau": "--tau",
    "bandwidth": "--bandwidth",
    "torque_min": "--torque-limit",
    "torque_max": "--torque-limit",
    "torque_limit": "--torque-limit",
    "measure": "--measure",
    "rate": "--rate",
    "duration": "--duration",
    "max_hz": "--max-hz",
    "series": "--series",
    "output": "--output",
    "at": "--at",
    "load_at": "--load-at",
}
# The options only a ramp takes, by their names on args (checked before any work).
_RAMP_ONLY = ("kp", "ki", "bandwidth", "torque_limit", "measure", "end_speed", "ramp_time")


def _torque_history(args):
    """The csv scenario's drive torque history from ``--series`` and ``--column``: (time s, torque N·m)."""
    from ..measurement.signalfile import read_torque_history

    if not args.series or not args.column:
        raise ModelError(
            "the csv scenario reads a torque history",
            field="--series",
            valid="--series FILE.csv --column NAME",
        )
    units = signal_units(args.units)
    try:
        return read_torque_history(
            args.series,
            args.column,
            units=units,
            time_column=args.time_column,
            group=args.group,
            field="--column",
        )
    except ModelError as err:  # the library's names for what the options set
        option = {"time_column": "--time-column", "group": "--group"}.get(err.field)
        raise (err.replaced(field=option) if option and err.file is None else err) from None


def _scenario(args, result):
    """The scenario the options describe (:func:`flexshaft.analysis.simulate.scenario_from_options`)."""
    from ..analysis.simulate import scenario_from_options

    kind = args.scenario
    series = _torque_history(args) if kind == "csv" else None
    if kind == "ramp" and (args.end_speed is None or args.ramp_time is None):
        raise ModelError(
            "a ramp needs its final speed and duration",
            field="--end-speed" if args.end_speed is None else "--ramp-time",
            valid="--end-speed RPM --ramp-time S",
        )
    options = {
        "torque": args.torque,
        "at": args.at,
        "step_time": args.step_time,
        "frequency_hz": args.frequency,
        "speed_rpm": args.speed,
        "load": args.load,
        "load_at": args.load_at,
        "tau": args.tau,
        "series": series,
    }
    if kind == "ramp":
        options |= {
            "end_speed_rpm": args.end_speed,
            "ramp_time": args.ramp_time,
            "kp": args.kp,
            "ki": args.ki,
            "bandwidth_hz": args.bandwidth,
            "torque_limit": args.torque_limit,
            "measure": args.measure,
        }
    return scenario_from_options(kind, result, **options)


def simulate(args) -> str:
    from ..analysis.modal import response_modes
    from ..analysis.simulate import simulate as run_scenario
    from ..model.assembly import assemble
    from ..views.progress import ProgressBar

    if args.output and not args.output.lower().endswith(".csv"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="FILE.csv")
    kind = args.scenario
    if kind != "ramp":  # refused before any work
        for name in _RAMP_ONLY:
            if getattr(args, name) is not None:
                raise ModelError(
                    "belongs to the ramp scenario (the closed speed loop)",
                    field="--" + name.replace("_", "-"),
                    valid="--scenario ramp, or leave it out",
                )
    if kind == "csv" and args.column:
        from ..measurement.checks import check_not_time

        check_not_time(args.column, args.time_column or "time", "--column")
    result = response_modes(assemble(load(args, args.model)))
    try:
        sc = _scenario(args, result)
        # every result is checked in there: a stable loop, inputs below Nyquist, enough samples,
        # finite outputs - so nothing below prints or writes a number that is not one
        run = run_scenario(
            result,
            sc,
            args.outputs,
            rate=args.rate,
            duration=args.duration,
            max_hz=args.max_hz,
            progress=ProgressBar("simulating"),
        )
    except ModelError as err:
        if err.file is not None or err.field not in SIMULATE_OPTION_OF:
            raise
        valid = err.valid.replace("max_hz", "--max-hz") if err.valid else err.valid
        raise err.replaced(field=SIMULATE_OPTION_OF[err.field], valid=valid) from None
    lines = [run.table(sc, kind, result.model.stations[0].name)]
    if args.plot:
        from ..views.plots import simulation_figure

        write_plot(args.plot, simulation_figure(run), args.force)
        lines.append(f"plot: {args.plot}")
    if args.output:
        from ..measurement.signalfile import write_signals

        cols = {name: (y, run.units[name]) for name, y in run.outputs.items()}
        path = write_signals(args.output, run.time, cols, overwrite=args.force)
        lines.append(f"samples: {path}")
    return "\n".join(lines)


def campbell(args) -> str:
    from ..analysis.campbell import campbell as campbell_diagram
    from ..analysis.modal import response_modes
    from ..measurement.checks import parse_orders
    from ..model.assembly import assemble
    from ..system.limits import check_ceiling

    lo, sep, hi = args.speed.partition(":")
    try:
        speeds = (float(lo), float(hi)) if sep else None
    except ValueError:
        speeds = None
    if speeds is None:
        raise ModelError(
            "not a speed range", field="--speed", value=args.speed, unit="rpm", valid="LO:HI, e.g. 0:1800"
        )
    top = max(abs(v) for v in speeds)
    check_ceiling("speed_rpm", top, field="--speed", value=args.speed, unit="rpm", detail=f"{top:g} rpm")
    orders = parse_orders(args.orders, "--orders")  # each > 0, finite, at most MAX_ORDER
    result = response_modes(assemble(load(args, args.model)))
    try:
        diagram = campbell_diagram(result, speeds, orders, reference=args.reference)
    except ModelError as err:  # the library's names for what --speed and --orders set
        option = {"speed (low)": "--speed", "speed (high)": "--speed", "orders": "--orders"}.get(err.field)
        if err.file is not None or option is None:
            raise
        raise ModelError(
            err.message,
            field=option,
            value=err.value,
            unit=err.unit,
            valid=err.valid,
            has_value=err.has_value,
        ) from None
    if args.plot:
        from ..views.plots import campbell_figure

        write_plot(args.plot, campbell_figure(diagram), args.force)
    if args.json:
        return json.dumps(diagram.to_dict(), ensure_ascii=False)
    return diagram.table(speeds)


def _check_spectrum_options(args) -> None:
    """The analysis options' combination, named as the command line names them."""
    if args.decay:
        window = args.window or "exponential"
        if window not in ("rect", "exponential"):
            raise ModelError(
                "a free decay needs a window that leaves its damping alone (Hann about halves it)",
                field="--window",
                value=window,
                valid="rect or exponential with --decay",
            )
        if args.segment is not None:
            raise ModelError(
                "a free decay is one transient: it is not averaged",
                field="--segment",
                valid="leave it out with --decay",
            )
    elif args.window == "exponential":
        raise ModelError(
            "the exponential window is for a free decay",
            field="--window",
            valid="--decay --window exponential",
        )


def spectrum(args) -> str:
    import numpy as np

    from ..measurement.analyse import analyse_signal
    from ..measurement.checks import as_signal, bare_name, check_not_time, parse_orders
    from ..measurement.signalfile import read_signals

    # options first, before the file is read: an order list of positive numbers, signals that are
    # neither the time nor each other
    orders = parse_orders(args.orders, "--orders")
    time_column = args.time_column or "time"  # a CSV file's default; a measured file's time may be none
    check_not_time(args.column, time_column, "--column")
    if args.speed_column:
        check_not_time(args.speed_column, time_column, "--speed-column")
        if bare_name(args.speed_column) == bare_name(args.column):
            raise ModelError(
                "is the signal itself",
                field="--speed-column",
                value=args.speed_column,
                valid="a shaft-speed column other than --column",
            )
    wanted = [args.column] + ([args.speed_column] if args.speed_column else [])
    try:
        table = read_signals(
            args.signals,
            columns=wanted,
            units=signal_units(args.units),
            time_column=args.time_column,
            group=args.group,
            rate=args.rate,
        )
    except ModelError as err:  # the library's names for what the options set
        option = {"time_column": "--time-column", "group": "--group", "rate": "--rate"}.get(err.field)
        raise (err.replaced(field=option) if option and err.file is None else err) from None
    names = list(table.columns)
    x, unit = table.columns[names[0]], table.units[names[0]]
    x = as_signal(x, "--column", unit)  # within ±MAX_SIGNAL: the spectrum's sums stay numbers
    speed_rpm = None
    if args.speed_column:
        if table.units[names[1]] != "rad/s":
            raise ModelError(
                "is not a speed",
                field="--speed-column",
                value=args.speed_column,
                unit=table.units[names[1]],
                valid="a column in rad/s or rpm",
            )
        speed_rpm = as_signal(table.columns[names[1]], "--speed-column", "rad/s") * 30.0 / np.pi
    eigen = None
    if args.model:
        from ..analysis.modal import modal_analysis

        res = modal_analysis(load(args, args.model))
        eigen = [(int(i), float(f)) for i, f in enumerate(res.frequencies_hz) if not res.rigid[i]]
    _check_spectrum_options(args)  # here, as the analysis checks them: a bad file or model says so first
    analysis = analyse_signal(
        table.time,
        x,
        name=names[0],
        unit=unit,
        source=table.source,
        decay=args.decay,
        window=args.window,
        segment=args.segment,
        peaks=args.peaks,
        speed_rpm=speed_rpm,
        eigenfrequencies=eigen,
        rate_hz=table.rate_hz,
    )
    if args.plot:
        from ..views.plots import signal_figure

        fig = signal_figure(analysis, spectrogram=args.spectrogram, orders=orders)
        write_plot(args.plot, fig, args.force)
    if args.json:
        return json.dumps(analysis.to_dict(), ensure_ascii=False)
    # what reading did to a measured file's samples (channels of different rates on one time base)
    return "\n".join([analysis.table(), *(f"note: {n}" for n in table.notes)])
