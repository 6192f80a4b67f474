"""The linear-system commands: ``statespace`` (A, B, C, D to a file), ``fmu`` (the same system as a
Functional Mock-up Unit), ``frf`` (frequency response) and ``forced`` (steady torque amplitudes under
a sinusoidal torque)."""

from __future__ import annotations

import json
from pathlib import Path

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
    rpm,
    table_output_option,
    whole,
)
from ..registry import PLOT, TABLE, Command

__all__ = ["COMMANDS", "statespace", "fmu", "frf", "forced"]

#: Above this many states ``fmu`` says what a co-simulation step size costs, and how to keep fewer modes.
LARGE_FMU_STATES = 400


def _system(args):
    """The modes and the state space between the command's inputs and outputs."""
    from ...analysis.statespace import response_system

    return response_system(
        load(args, args.model), args.inputs, args.outputs, max_hz=args.max_hz, speed_rpm=args.speed
    )


def statespace(args) -> str:
    from ...exports.statespacefile import write_state_space
    from ...model.describe import damping_line

    modes, ss = _system(args)
    try:
        path = write_state_space(
            ss, args.output, overwrite=args.force, damping=damping_line(modes.model.drivetrain)
        )
    except ModelError as err:
        if err.field != "path":
            raise
        raise ModelError(err.message, field="-o", value=err.value, valid=err.valid) from None
    from ...model.describe import linearised_line

    linear = linearised_line(modes.model.drivetrain)
    return (
        f"state space: {ss.A.shape[0]} states ({len(ss.modes)} modes), {len(ss.inputs)} inputs, "
        f"{len(ss.outputs)} outputs: {path}"
    ) + ("" if linear is None else "\n" + linear)


def fmu(args) -> str:
    from ...exports.fmu import fmu_system, write_fmu
    from ...model.describe import linearised_line

    drivetrain = load(args, args.model)
    try:
        system = fmu_system(
            drivetrain, args.inputs, args.outputs, max_hz=args.max_hz, system_ratio=args.system_damping
        )
    except ModelError as err:
        if err.field != "system_ratio":
            raise
        raise err.replaced(field="--system-damping") from None
    try:
        built = write_fmu(
            system,
            args.output,
            fmi=args.fmi,
            compile=not args.sources_only,
            default_variant=args.damping,
            overwrite=args.force,
            say=note,
        )
    except ModelError as err:
        if err.field != "path":
            raise
        raise err.replaced(field="-o") from None
    if built.states > LARGE_FMU_STATES:
        note(
            f"{built.states} states: the FMU's co-simulation computes a matrix exponential of that order "
            "once per step size (minutes at thousands of states); --max-hz F keeps only the modes up to F Hz"
        )
    if args.json:
        return json.dumps(built.to_dict(), indent=1, ensure_ascii=False)
    linear = linearised_line(drivetrain)
    return built.table() + ("" if linear is None else "\n" + linear)


def frf(args) -> str:
    from ...analysis.statespace import default_frf_range, frequency_grid, frequency_response
    from ...exports.statespacefile import frf_npz
    from ...model.describe import linearised_document, linearised_line

    if len(args.inputs) != 1:
        raise ModelError(
            "frf takes one input (its outputs are repeatable)",
            field="--at",
            value=", ".join(args.inputs),
            valid="one station; run frf once per input, or use statespace for several",
        )
    modes, ss = _system(args)
    ss_model = modes.model
    try:
        f_from, f_to = default_frf_range(ss, args.f_from, args.f_to)
    except ModelError as err:  # the library names its arguments, the command line its options
        raise ModelError(
            "must be below --to",
            field="--from",
            value=err.value,
            unit=err.unit,
            valid=err.valid.replace("f_from", "--from").replace("f_to", "--to"),
        ) from None
    resp = frequency_response(ss, frequency_grid(ss, f_from, f_to, args.points))
    doc = resp.to_dict()
    linear = linearised_line(ss_model.drivetrain)
    if linear is not None:
        doc["linearised"] = linearised_document(ss_model.drivetrain)
    if args.plot:
        from ...views.plots import bode_figure

        write_plot(args.plot, bode_figure(resp), args.force)
    kind = Path(args.output).suffix.lower() if args.output else None
    if kind == ".npz":
        return _written(resp, args, frf_npz(resp, doc))
    if kind in (".uff", ".unv"):
        from ...exports.universalfile import write_frf_uff

        path = write_frf_uff(resp, modes.model, args.output, overwrite=args.force)
        return (
            f"frequency response {resp.inputs[0]} -> {', '.join(resp.outputs)}, "
            f"{resp.frequencies_hz.size} frequencies: {path} (units 164, one FRF 58 each)"
        )
    if kind == ".csv":
        text = resp.csv()
    elif args.json or kind == ".json":
        text = json.dumps(doc, ensure_ascii=False)
    else:
        text = resp.table(doc["peaks"]) + ("" if linear is None else "\n" + linear)
    return _written(resp, args, (text + "\n").encode("utf-8")) if args.output else text


def _written(resp, args, data: bytes) -> str:
    """Write frf's -o file (its type checked before the work) and say what went where."""
    from ...system.atomic import atomic_write_bytes

    path = atomic_write_bytes(args.output, data, overwrite=args.force)
    return (
        f"frequency response {resp.inputs[0]} -> {', '.join(resp.outputs)}, "
        f"{resp.frequencies_hz.size} frequencies: {path}"
    )


def forced(args) -> str:
    from ...analysis.forced import forced_response
    from ...analysis.modal import response_modes
    from ...model.assembly import assemble
    from ...model.describe import linearised_document, linearised_line

    result = response_modes(assemble(load(args, args.model)))
    station, frequencies = _forced_at(args, result.model)
    try:
        fr = forced_response(result, station, amplitude=args.torque, frequencies_hz=frequencies)
    except ModelError as err:
        option = {"amplitude": "--torque", "input": "--at"}.get(err.field)
        if option is not None:  # the library names its argument, the CLI its option
            err = ModelError(err.message, field=option, value=err.value, unit=err.unit, valid=err.valid)
        raise err from None
    linear = linearised_line(result.model.drivetrain)
    if args.json:
        doc = fr.to_dict()
        if linear is not None:
            doc["linearised"] = linearised_document(result.model.drivetrain)
        return json.dumps(doc, ensure_ascii=False)
    return fr.table() + ("" if linear is None else "\n" + linear)


def _forced_at(args, model) -> tuple[str | None, list[float] | None]:
    """forced's station and excitation frequencies (Hz; None: each mode's).

    Until ``--at`` named the station, ``--at HZ`` was an excitation frequency: for one release a
    number that is no station of the model is still read so, with a note.
    """
    station, frequencies, old = None, args.frequencies, []
    for value in args.at or ():
        try:
            model.station(value, "--at")
        except ModelError:
            try:
                old.append(float(value))
                continue
            except ValueError:
                pass
        if station is not None:
            raise ModelError(
                "the torque acts at one station", field="--at", value=value, valid=f"only --at {station}"
            )
        station = value
    if old:
        note("--at HZ is deprecated (--at names the station); use --frequency HZ")
        frequencies = [*(frequencies or []), *old]
    return station, frequencies  # None: the driving end (forced_response's default)


def _system_options(p, *, ats: str) -> None:
    """The options statespace and frf share: the model, the stations driven and the outputs measured."""
    p.add_argument("model", help="TOML model file")
    p.add_argument("--at", dest="inputs", action="append", metavar="STATION", help=ats)
    renamed(p, "--input", "--at", "inputs", append=True)
    p.require("--at", "inputs")
    p.add_argument(
        "--measure",
        dest="outputs",
        action="append",
        metavar="SIGNAL",
        help="angle:STATION, speed:STATION or torque:COMPONENT (repeatable)",
    )
    renamed(p, "--output", "--measure", "outputs", append=True)  # -o's long form after this release
    p.require("--measure", "outputs")
    force_option(p)
    p.add_argument(
        "--max-hz", type=hz("--max-hz", positive=True), metavar="F", help="keep only the modes up to F Hz"
    )
    p.add_argument(
        "--speed",
        type=rpm("--speed"),
        default=0.0,
        metavar="RPM",
        help="the line spinning at RPM: a 6-DOF model's gyroscopic terms join the damping (0)",
    )


def _statespace_options(p) -> None:
    _system_options(p, ats="a station driven by a torque, N·m (repeatable)")
    output_option(
        p,
        "FILE",
        "write A, B, C, D and their names and units: FILE.npz, FILE.mat or FILE.json",
        long=False,
        required=True,
    )


def _fmu_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--at",
        dest="inputs",
        action="append",
        metavar="STATION",
        help="a station driven by a torque, N·m: an FMU input (repeatable; default both ends)",
    )
    p.add_argument(
        "--measure",
        dest="outputs",
        action="append",
        metavar="SIGNAL",
        help="angle:STATION, speed:STATION or torque:COMPONENT: an FMU output (repeatable; default the "
        "speeds of both ends)",
    )
    p.add_argument(
        "--max-hz", type=hz("--max-hz", positive=True), metavar="F", help="keep only the modes up to F Hz"
    )
    p.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version (2)")
    p.add_argument(
        "--damping",
        choices=("parts", "system"),
        default="parts",
        help="the damping_variant parameter's start value: parts (each part's own damping, the "
        "default) or system (Rayleigh damping fitted to --system-damping); the FMU carries both",
    )
    p.add_argument(
        "--system-damping",
        type=float,
        metavar="RATIO",
        help="the system variant's damping ratio on the first two elastic modes, a fraction (0.0053)",
    )
    p.add_argument(
        "--sources-only",
        action="store_true",
        help="no binary: the FMU carries its C sources only (built without a compiler too, with a note)",
    )
    json_option(p, "the summary")
    output_option(p, "FILE.fmu", "the FMU to write", long=False, required=True)
    force_option(p)


def _frf_options(p) -> None:
    _system_options(p, ats="the station driven by a torque, N·m")
    p.add_argument("--from", dest="f_from", type=hz("--from"), default=0.1, help="first frequency, Hz (0.1)")
    p.add_argument(
        "--to",
        dest="f_to",
        type=hz("--to", positive=True),
        help="last frequency, Hz (default: 1.5 × the highest mode kept, at most 1e9)",
    )
    p.add_argument(
        "--points",
        type=whole("--points", 2, "frf_points"),
        default=1000,
        help="evenly spaced frequencies (1000); 13 more are added around each resonance",
    )
    plot_option(p, "write the Bode plot to FILE")
    json_option(p)
    output_option(
        p,
        "FILE",
        "write the response: FILE.csv, .json, .npz (complex H), .txt (the peaks table) or .uff/.unv",
        long=False,
    )


def _forced_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--at",
        action="append",
        metavar="STATION",
        help="the station the torque is applied at (default: the driving end)",
    )
    renamed(p, "--input", "--at", "at", append=True)
    p.add_argument("--torque", type=float, default=1.0, help="torque amplitude, N·m (1)")
    renamed(p, "--amplitude", "--torque", "torque", type=float)
    p.add_argument(
        "--frequency",
        dest="frequencies",
        type=float,
        action="append",
        metavar="HZ",
        help="excitation frequency, Hz (repeatable; default: each flexible mode's natural frequency)",
    )
    json_option(p)
    table_output_option(p, "the forced-response table")
    force_option(p)


COMMANDS = (
    Command(
        "statespace",
        "state space A, B, C, D between named inputs and outputs",
        _statespace_options,
        statespace,
        files={"-o": {s: "A, B, C, D and their names and units" for s in (".npz", ".mat", ".json")}},
    ),
    Command(
        "fmu",
        "the linear drivetrain as an FMU (FMI 2 or 3, model exchange and co-simulation)",
        _fmu_options,
        fmu,
        files={"-o": {".fmu": "a Functional Mock-up Unit: model description, C sources, binary"}},
    ),
    Command(
        "frf",
        "frequency response between named inputs and outputs",
        _frf_options,
        frf,
        files={
            "-o": {
                ".csv": "frequency and real, imaginary parts",
                ".json": "the JSON document",
                ".npz": "frequency_hz and complex H, units in metadata",
                ".txt": "the peaks table",
                ".uff": "a universal file: units 164, one FRF 58 (binary) per output",
                ".unv": "a universal file: units 164, one FRF 58 (binary) per output",
            },
            "--plot": PLOT,
        },
    ),
    Command(
        "forced",
        "steady torque amplitudes in every part under a sinusoidal torque at each mode",
        _forced_options,
        forced,
        files={"-o": TABLE},
        table=True,
    ),
)
