"""The commands about a turning line: ``simulate`` (time runs), ``amplitude`` (a stepped sine at
several drive amplitudes: the apparent modes of a nonlinear line), ``campbell`` (modes against speed)
and ``spectrum`` (a simulated or measured signal's spectrum, peaks and damping)."""

from __future__ import annotations

import json
import re

from ...errors import ModelError
from ..console import write_plot
from ..loadmodel import load
from ..options import (
    force_option,
    hz,
    json_option,
    note,
    output_option,
    plot_option,
    renamed,
    signal_file_options,
    signal_units,
    table_options,
    whole,
)
from ..registry import PLOT, TABLE, Command

__all__ = ["COMMANDS", "simulate", "amplitude", "campbell", "spectrum"]

# simulate: the library names its arguments; the command line names the options that set them.
SIMULATE_OPTION_OF = {
    "torque": "--torque",
    "time": "--step-time",
    "frequency": "--frequency",
    "speed": "--speed",
    "end_speed": "--end-speed",
    "ramp_time": "--ramp-time",
    "load": "--load-torque",
    "kp": "--kp",
    "ki": "--ki",
    "tau": "--tau",
    "bandwidth": "--bandwidth",
    "torque_min": "--torque-limit",
    "torque_max": "--torque-limit",
    "torque_limit": "--torque-limit",
    "power_limit": "--power-limit",
    "measure": "--feedback",
    "rate": "--rate",
    "duration": "--duration",
    "max_hz": "--max-hz",
    "series": "--series",
    "output": "--measure",
    "at": "--at",
    "load_at": "--load-at",
    # Scenario.of's settings
    "step_time": "--step-time",
    "frequency_hz": "--frequency",
    "speed_rpm": "--speed",
    "end_speed_rpm": "--end-speed",
    "bandwidth_hz": "--bandwidth",
    "scenario": "--scenario",
    "steady": "--steady",
    # stepped_sine's arguments
    "amplitudes": "--torque",
    "modes": "--mode",
    "points": "--points",
}


def _torque_history(args):
    """The csv scenario's drive torque history from ``--series`` and ``--column``: (time s, torque N·m)."""
    from ...measurement.signalfile import read_torque_history

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


def _settings(args) -> dict:
    """The scenario's settings from the options, by the library's names (:meth:`Scenario.of`)."""
    return {
        "at": args.at,
        "load": args.load,
        "load_at": args.load_at,
        "torque": args.torque,
        "step_time": args.step_time,
        "frequency_hz": args.frequency,
        "speed_rpm": args.speed,
        "end_speed_rpm": args.end_speed,
        "ramp_time": args.ramp_time,
        "kp": args.kp,
        "ki": args.ki,
        "bandwidth_hz": args.bandwidth,
        "tau": args.tau,
        "torque_limit": args.torque_limit,
        "power_limit": args.power_limit,
        "measure": args.feedback,
        "steady": args.steady or None,
    }


def _as_options(err: ModelError) -> ModelError:
    """The library's error, naming the option where it names a setting (``end_speed_rpm``: --end-speed)."""
    if err.file is not None or err.field not in SIMULATE_OPTION_OF:
        return err
    valid = err.valid
    for name, option in SIMULATE_OPTION_OF.items():
        if valid and "_" in name:
            valid = re.sub(rf"\b{name}\b", option, valid)
    return err.replaced(field=SIMULATE_OPTION_OF[err.field], valid=valid)


def _old_outputs(args) -> None:
    """Until ``--measure`` named simulate's outputs, they were ``--output SPEC`` and ``--measure`` was
    the loop's speed: for one release a command line with ``--output SPEC`` is read so, with a note."""
    if args.old_outputs is None:
        return
    if args.outputs:
        if len(args.outputs) > 1 or args.feedback is not None:
            raise ModelError(
                "with --output SIGNAL (deprecated), --measure is the loop's speed, once",
                field="--measure",
                value=", ".join(args.outputs),
                valid="--measure SIGNAL... for the outputs and --feedback speed:STATION for the loop",
            )
        note("--measure as the loop's speed is deprecated; use --feedback")
        args.feedback = args.outputs[0]
    args.outputs = args.old_outputs


def simulate(args) -> str:
    from ...analysis.modal import response_modes
    from ...analysis.scenario import Scenario, check_settings
    from ...analysis.simulate import simulate as run_scenario
    from ...model.assembly import assemble
    from ...views.progress import ProgressBar

    if args.output and not args.output.lower().endswith(".csv"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="FILE.csv")
    _old_outputs(args)
    kind, settings = args.scenario, _settings(args)
    try:
        check_settings(kind, settings)  # refused before any work
    except ModelError as err:
        raise _as_options(err) from None
    if kind == "csv" and args.column:
        from ...measurement.checks import check_not_time

        check_not_time(args.column, args.time_column or "time", "--column")
    result = response_modes(assemble(load(args, args.model)))
    try:
        series = _torque_history(args) if kind == "csv" else None
        sc = Scenario.of(kind, settings, result, series=series)
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
        raise _as_options(err) from None
    lines = [] if args.json else [run.table(sc, kind, result.model.stations[0].name)]
    if args.plot:
        from ...views.plots import simulation_figure

        write_plot(args.plot, simulation_figure(run), args.force)
        lines.append(f"plot: {args.plot}")
    if args.output:
        from ...measurement.signalfile import write_signals

        cols = {name: (y, run.units[name]) for name, y in run.outputs.items()}
        path = write_signals(args.output, run.time, cols, overwrite=args.force)
        lines.append(f"samples: {path}")
    if args.json:  # the document, then what was written where (as the table has it)
        lines.insert(0, json.dumps(run.to_dict(), ensure_ascii=False))
    return "\n".join(lines)


def amplitude(args) -> str:
    from ...analysis.amplitude import stepped_sine
    from ...analysis.modal import response_modes
    from ...model.assembly import assemble
    from ...views.progress import ProgressBar

    if args.outputs and len(args.outputs) > 1:
        raise ModelError(
            "reads one output", field="--measure", value=", ".join(args.outputs), valid="one SIGNAL"
        )
    result = response_modes(assemble(load(args, args.model)))
    try:
        sweep = stepped_sine(
            result,
            args.torques,
            at=args.at,
            measure=args.outputs[0] if args.outputs else None,
            modes=args.mode,
            points=args.points,
            rate=args.rate,
            progress=ProgressBar("stepped sine"),
        )
    except ModelError as err:
        if err.field and err.field.startswith("amplitudes["):
            err = err.replaced(field="--torque")
        raise _as_options(err) from None
    if args.plot:
        write_plot(args.plot, sweep.plot(), args.force)
    if args.json:
        return json.dumps(sweep.to_dict(), ensure_ascii=False)
    return sweep.table()


def campbell(args) -> str:
    from ...analysis.campbell import campbell as campbell_diagram
    from ...analysis.modal import response_modes
    from ...measurement.checks import parse_orders
    from ...model.assembly import assemble
    from ...system.limits import check_ceiling

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
        from ...views.plots import campbell_figure

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


def _measured_frf(args):
    """The frequency response (dataset 58, function type 4) ``--column`` names in a universal file;
    None where the file is none, or the name is none of its frequency responses either."""
    from pathlib import Path

    if Path(args.signals).suffix.lower() not in (".uff", ".unv"):
        return None
    from ...measurement.files import read_frf_records

    found = [r for r in read_frf_records(args.signals) if r["name"] == args.column.strip()]
    if not found:
        return None  # no record of that name: the channels' reading says so
    from ...measurement.measuredfrf import measured_frf

    return measured_frf(found[0], args.signals)


#: The options of a time record's analysis, which a measured frequency response has no use for.
_TIME_ONLY = {
    "speed_column": "--speed-column",
    "decay": "--decay",
    "window": "--window",
    "segment": "--segment",
    "spectrogram": "--spectrogram",
    "rate": "--rate",
    "time_column": "--time-column",
}


def _frf_peaks(args, frf) -> str:
    """``spectrum`` of a measured frequency response: its peaks with their half-power damping."""
    for dest, option in _TIME_ONLY.items():
        if getattr(args, dest, None):
            raise ModelError(
                "applies to a time record; this one is a frequency response",
                field=option,
                value=args.column,
                valid="leave it out for a frequency response (dataset 58, function type 4)",
            )
    from ...measurement.measuredfrf import analyse_frf

    eigen = None
    if args.model:
        from ...analysis.modal import modal_analysis

        res = modal_analysis(load(args, args.model))
        eigen = [(int(i), float(f)) for i, f in enumerate(res.frequencies_hz) if not res.rigid[i]]
    analysis = analyse_frf(frf, count=args.peaks, eigenfrequencies=eigen)
    if args.plot:
        from ...analysis.statespace import FrequencyResponse

        out_unit, _, in_unit = frf.unit.rpartition("/")
        measured = FrequencyResponse(
            frf.frequencies_hz, frf.H[:, None, None], ("reference",), (frf.name,), (in_unit,), (out_unit,)
        )
        write_plot(args.plot, measured.plot(damping="as measured"), args.force)
    if args.json:
        return json.dumps(analysis.to_dict(), ensure_ascii=False)
    return analysis.table()


def spectrum(args) -> str:
    import numpy as np

    from ...measurement.analyse import analyse_signal
    from ...measurement.checks import as_signal, bare_name, check_not_time, parse_orders
    from ...measurement.signalfile import read_signals

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
    except ModelError as err:
        # not a time record: a universal file's frequency response, whose peaks need no spectrum (read
        # only then, so a time record's file is read once)
        frf = _measured_frf(args) if err.message.startswith("no such channel") else None
        if frf is not None:
            return _frf_peaks(args, frf)
        # the library's names for what the options set
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
        from ...analysis.modal import modal_analysis

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
        from ...views.plots import signal_figure

        fig = signal_figure(analysis, spectrogram=args.spectrogram, orders=orders)
        write_plot(args.plot, fig, args.force)
    if args.json:
        return json.dumps(analysis.to_dict(), ensure_ascii=False)
    # what reading did to a measured file's samples (channels of different rates on one time base)
    return "\n".join([analysis.table(), *(f"note: {n}" for n in table.notes)])


def _simulate_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--scenario",
        required=True,
        choices=("step", "ramp", "coast", "sine", "csv"),
        help="step: a drive-torque step (--torque at --step-time), no control; ramp: a speed set-point "
        "ramp (--speed to --end-speed in --ramp-time) in a PI speed loop; coast: turning at --speed "
        "with --torque through the line, drive and load drop to zero at t = 0 (a free decay); sine: "
        "a sinusoidal drive torque (--torque, --frequency) from rest; csv: a drive-torque history "
        "read from --series",
    )
    p.add_argument(
        "--measure",
        dest="outputs",
        action="append",
        metavar="SIGNAL",
        help="angle:STATION, speed:STATION, torque:COMPONENT; with a ramp also control:torque, "
        "control:setpoint (repeatable)",
    )
    renamed(p, "--output", "--measure", "old_outputs", append=True)  # -o's long form after this release
    p.set_defaults(old_outputs=None)
    p.require("--measure", "outputs", "old_outputs")
    p.add_argument("--rate", type=float, default=1000.0, help="sample and controller rate, Hz (1000)")
    p.add_argument("--duration", type=float, help="run length, s (10; a ramp: its time + 10 %%)")
    p.add_argument("--torque", type=float, default=0.0, help="step or sine amplitude, coast preload, N·m")
    p.add_argument(
        "--at", metavar="STATION", help="station of the drive (air-gap) torque (default: the driving end)"
    )
    p.add_argument("--step-time", type=float, default=0.0, help="when the step comes, s (0)")
    p.add_argument("--frequency", type=float, default=0.0, help="sine frequency, Hz")
    p.add_argument(
        "--steady",
        action="store_true",
        help="sine: start on the linear line's steady oscillation instead of from rest (no start-up)",
    )
    p.add_argument(
        "--speed", type=float, default=0.0, help="start speed (ramp) or running speed (coast), rpm"
    )
    p.add_argument("--end-speed", type=float, help="ramp: final speed, rpm")
    p.add_argument("--ramp-time", type=float, help="ramp: its duration, s")
    p.add_argument(
        "--load-torque",
        dest="load",
        type=float,
        default=0.0,
        metavar="N·m",
        help="constant load torque, N·m (a generator: < 0)",
    )
    renamed(p, "--load", "--load-torque", "load", type=float)
    p.add_argument("--load-at", metavar="STATION", help="station of the load torque (default: the far end)")
    p.add_argument("--kp", type=float, help="PI gain, N·m per rad/s (default: tuned from the model)")
    p.add_argument("--ki", type=float, help="PI integral gain, N·m per rad (default: tuned from the model)")
    p.add_argument("--bandwidth", type=float, help="speed-loop bandwidth for the default gains, Hz")
    p.add_argument("--tau", type=float, default=0.0, help="low-pass to the air-gap torque, s (0: none)")
    p.add_argument("--torque-limit", type=float, help="|commanded torque| limit, N·m (anti-windup)")
    p.add_argument(
        "--power-limit",
        type=float,
        metavar="W",
        help="drive power limit, W: the torque also within ±W/|speed| (anti-windup)",
    )
    p.add_argument(
        "--feedback",
        metavar="SIGNAL",
        help="the speed the loop controls, speed:STATION (default: the drive's)",
    )
    p.add_argument(
        "--series",
        metavar="FILE",
        help="csv scenario: the file with the torque history (CSV, or measured: "
        ".tdms .mf4 .mdf .dat .h5 .hdf5 .mat .uff .unv)",
    )
    p.add_argument("--column", help="csv scenario: the torque column (header, with or without its unit)")
    signal_file_options(p, "csv scenario: ", rate=False)  # its --rate is the simulation's
    p.add_argument(
        "--max-hz", type=hz("--max-hz", positive=True), metavar="F", help="keep only the modes up to F Hz"
    )
    plot_option(p, "draw the outputs against time to FILE")
    json_option(p)
    output_option(p, "FILE.csv", "write the samples: time [s], NAME [unit]…", long=False)
    force_option(p)


def _amplitude_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--torque",
        dest="torques",
        type=float,
        nargs="+",
        required=True,
        metavar="N·m",
        help="the drive-torque amplitudes, N·m (each a stepped sine around every mode looked at)",
    )
    p.add_argument("--at", metavar="STATION", help="station of the drive torque (default: the driving end)")
    p.add_argument(
        "--measure",
        dest="outputs",
        action="append",
        metavar="SIGNAL",
        help="the output read: angle:STATION, speed:STATION, torque:COMPONENT (default: the far end's speed)",
    )
    p.add_argument(
        "--mode",
        type=whole("--mode", 1),
        action="append",
        metavar="N",
        help="a mode to look at, numbered as `modes` lists them (repeatable; default the elastic modes"
        " below rate/4)",
    )
    p.add_argument(
        "--points",
        type=whole("--points", 5),
        default=21,
        help="sine frequencies per mode, over 0.6 … 1.15 times its linear frequency (21)",
    )
    p.add_argument("--rate", type=float, default=1000.0, help="sample rate, Hz (1000)")
    plot_option(p, "draw the response curves to FILE")
    table_options(p, "the table of apparent frequencies and damping")


def _campbell_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument("--speed", default="0:1800", help="speed range LO:HI, rpm (0:1800)")
    p.add_argument("--orders", default="1,2,6", help="excitation orders, comma-separated (1,2,6)")
    p.add_argument(
        "--reference",
        metavar="STATION",
        help="the station whose speed the axis is (default: the driving end)",
    )
    plot_option(p, "draw the diagram to FILE")
    table_options(p, "the Campbell table (each mode's crossings with the orders)")


def _spectrum_options(p) -> None:
    p.add_argument(
        "signals",
        help="CSV: a 'time [s]' column, then 'NAME [unit]' columns; or a measured file: "
        ".tdms .mf4 .mdf .dat .h5 .hdf5 .mat .uff .unv",
    )
    p.add_argument(
        "--column",
        required=True,
        help="the signal (its header, with or without the unit); in a universal file also a measured "
        "frequency response (its peaks and half-power damping)",
    )
    signal_file_options(p, "", rate=True)
    p.add_argument(
        "--window",
        choices=("hann", "rect", "flattop", "exponential"),
        help="hann (default: stationary signals), rect, flattop; with --decay rect or exponential (default)",
    )
    p.add_argument(
        "--segment",
        type=float,
        metavar="SECONDS",
        help="Welch averaging over segments this long, 50 %% overlap",
    )
    p.add_argument(
        "--decay",
        action="store_true",
        help="the record is a free decay: damping by a window fit for a transient and by log decrement",
    )
    p.add_argument("--peaks", type=whole("--peaks", 1, "peaks"), default=8, help="how many peaks to list (8)")
    p.add_argument("--speed-column", help="a shaft-speed column: peaks get their order, plots the orders")
    p.add_argument("--orders", default="1,2,6", help="order lines of the spectrogram plot (1,2,6)")
    p.add_argument("--model", help="a model file: peaks get the nearest eigenfrequency, plots mark them")
    p.add_argument(
        "--plot",
        metavar="FILE",
        help="the spectrum; with --speed-column the spectrogram against speed, --spectrogram: against time",
    )
    p.add_argument(
        "--spectrogram",
        action="store_true",
        help="--plot draws the spectrogram (against time without a speed)",
    )
    table_options(p, "the table of peaks")


COMMANDS = (
    Command(
        "simulate",
        "time run of a scenario (step, speed ramp in closed loop, coast, ...)",
        _simulate_options,
        simulate,
        files={"-o": {".csv": "the samples"}, "--plot": PLOT},
    ),
    Command(
        "amplitude",
        "stepped sine at several drive amplitudes: how the modes of a nonlinear line shift",
        _amplitude_options,
        amplitude,
        files={"-o": TABLE, "--plot": PLOT},
        table=True,
    ),
    Command(
        "campbell",
        "Campbell diagram: modes against speed, order lines and crossings",
        _campbell_options,
        campbell,
        files={"-o": TABLE, "--plot": PLOT},
        table=True,
    ),
    Command(
        "spectrum",
        "amplitude spectrum, peaks and damping of a signal (simulated or measured)",
        _spectrum_options,
        spectrum,
        files={"-o": TABLE, "--plot": PLOT},
        source="signals",
        table=True,
    ),
)
