"""The ``flexshaft`` command: a thin shell over the library.

Exit codes: 0 success, 2 bad input (one line on stderr, nothing on stdout).
"""

from __future__ import annotations

import argparse
import json
import sys
from importlib import resources
from pathlib import Path

from .errors import ModelError

__all__ = ["main"]

DEMO_MODEL = "customer1.toml"
MESH_CHECK_AUTO_DOFS = 20_000  # the check doubles the solve; above this it runs only when asked
PLOTS = ".png, .svg or .pdf"  # what --plot writes (the suffix picks)
DEFAULT_MODES = 6  # sensitivity and sweep: the lowest elastic modes reported without --modes


def _whole(name: str, lo: int, ceiling: str | None = None):
    """An argparse type: a whole number >= ``lo`` (and within the ceiling of that name in
    :data:`flexshaft.limits.CEILINGS`), the error naming the option."""

    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} = {text!r}: must be an integer >= {lo}") from None
        if n < lo:
            raise argparse.ArgumentTypeError(f"{name} = {n}: must be an integer >= {lo}")
        if ceiling is not None:
            from .limits import check_ceiling

            try:
                check_ceiling(ceiling, n, field=name)
            except ModelError as err:
                raise argparse.ArgumentTypeError(str(err)) from None
        return n

    return parse


def _hz(name: str, *, positive: bool = False):
    """An argparse type: a finite frequency in Hz, from 0 (above 0 when ``positive``) up to
    :data:`~flexshaft.validation.MAX_FREQUENCY_HZ`, the error naming the option."""

    def parse(text: str) -> float:
        from .validation import MAX_FREQUENCY_HZ, check_frequency

        try:
            return check_frequency(float(text), name, lo=0.0, lo_open=positive)
        except ModelError as err:
            raise argparse.ArgumentTypeError(str(err)) from None
        except ValueError:
            lo = "> 0" if positive else ">= 0"
            raise argparse.ArgumentTypeError(
                f"{name} = {text!r}: not a number; valid: a frequency {lo} and <= {MAX_FREQUENCY_HZ:g} Hz"
            ) from None

    return parse


def _rpm(name: str):
    """An argparse type: a finite shaft speed in rpm, at most
    :data:`~flexshaft.validation.MAX_SPEED_RPM` either way, the error naming the option."""

    def parse(text: str) -> float:
        from .validation import MAX_SPEED_RPM, check_real

        try:
            return check_real(float(text), name, "rpm", lo=-MAX_SPEED_RPM, hi=MAX_SPEED_RPM)
        except ModelError as err:
            raise argparse.ArgumentTypeError(str(err)) from None
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{name} = {text!r}: not a number; valid: a speed from {-MAX_SPEED_RPM:g} to "
                f"{MAX_SPEED_RPM:g} rpm"
            ) from None

    return parse


def _json_output_options(parser) -> None:
    """``--json``, ``-o PATH`` and ``--force``, as a command that prints a table or JSON takes them."""
    parser.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
    parser.add_argument(
        "-o", dest="output", metavar="PATH", help="write to this file: PATH.txt the table, PATH.json JSON"
    )
    parser.add_argument("--force", action="store_true", help="allow replacing an existing file")


def _unit_option(parser, prefix: str) -> None:
    """``--unit COLUMN=UNIT`` (repeatable): the unit of a signal-file column whose header has none."""
    parser.add_argument(
        "--unit",
        dest="units",
        action="append",
        metavar="COLUMN=UNIT",
        help=prefix + "the unit of a column whose header has none, e.g. torque=kNm or time=ms (repeatable)",
    )


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error on one line and exits 2."""

    def error(self, message: str):  # noqa: D102 - argparse hook
        self.exit(2, f"flexshaft: error: {message} (see `{self.prog} --help`)\n")


def _parser() -> argparse.ArgumentParser:
    from .version import __version__

    p = _Parser(
        prog="flexshaft",
        description="Drivetrain dynamics from model files: modes, twist test, sections, flexible bodies, "
        "state space, simulation, signals, calibration.",
    )
    p.add_argument("--version", action="version", version=f"flexshaft {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    m = sub.add_parser("modes", help="natural frequencies, damping and mode shapes of a model file")
    m.add_argument("model", help="TOML model file")
    m.add_argument(
        "--mesh-check",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="estimate each mode's distance from mesh convergence by re-solving at twice the elements "
        f"(default: on up to {MESH_CHECK_AUTO_DOFS} DOFs)",
    )
    m.add_argument(
        "--inertia",
        choices=("consistent", "lumped"),
        help="how shaft inertia is spread (overrides the model file)",
    )
    m.add_argument(
        "--count",
        type=_whole("--count", 1),
        help="how many of the lowest modes (default: all for small models, 10 otherwise)",
    )
    m.add_argument(
        "--max-hz", type=_hz("--max-hz", positive=True), metavar="F", help="list only the modes up to F Hz"
    )
    bo = sub.add_parser("body", help="check an exported flexible body (checksums, physics) and summarise it")
    bo.add_argument("file", help="PART.npz|.json|.mat|.op4|.pch, as `flexshaft reduce` writes it")
    bo.add_argument("--json", action="store_true", help="print one JSON document instead of a summary")
    bo.set_defaults(output=None, force=False)
    d = sub.add_parser("demo", help="modes of the built-in Customer 1 test bench")
    s = sub.add_parser(
        "sections",
        help="section table, torsional stiffness and inertia of CAD and "
        "dimensioned parts (a model file) or of one STEP/BREP/STL/OBJ/PLY file",
    )
    s.add_argument("source", help="TOML model file, or a part file")
    s.add_argument(
        "--material",
        default="steel",
        help="material of a part file (built-in: steel; for others use a model file)",
    )
    s.add_argument("--unit", help="length unit of a mesh file: m, mm, cm or in")
    s.add_argument("--merge", action="store_true", help="join neighbouring intervals with equal sections")
    t = sub.add_parser(
        "twist",
        help="applied-torque twist test: each part's torsional stiffness and the twist along the shaft",
    )
    t.add_argument("model", help="TOML model file")
    t.add_argument(
        "--torque", type=float, default=1000.0, help="torque at the load station, N·m (default 1000)"
    )
    t.add_argument("--clamp", help="station clamped (default: the driving end)")
    t.add_argument("--load", help="station the torque is applied at (default: the far end)")
    t.add_argument(
        "--target",
        action="append",
        default=[],
        metavar="PART=N·m/rad",
        help="also give the Young's modulus (or dimension scale) that makes PART this stiff; repeatable",
    )
    t.add_argument("--plot", metavar="FILE", help=f"write the twist-along-the-shaft plot to FILE ({PLOTS})")
    t.add_argument(
        "--view",
        metavar="FILE.png",
        help="write the twisted shaft in 3D, coloured by shear stress, to this PNG",
    )
    r = sub.add_parser(
        "reduce", help="Craig–Bampton flexible body of one part, written to .npz/.json/.mat/.op4/.pch"
    )
    r.add_argument("model", help="TOML model file")
    r.add_argument("--part", required=True, help="the part (a cad part or a shaft given by segments)")
    g = r.add_mutually_exclusive_group()
    g.add_argument(
        "--modes",
        type=_whole("--modes", 0),
        help="fixed-interface modes to keep (default: the part's reduce)",
    )
    g.add_argument(
        "--cutoff",
        type=_hz("--cutoff", positive=True),
        metavar="HZ",
        help="keep every fixed-interface mode below HZ",
    )
    r.add_argument(
        "--damping-ratio",
        type=float,
        help="ratio on every elastic mode (default: the part's damping in the model file, else 0.0053)",
    )
    r.add_argument(
        "--no-residual",
        action="store_true",
        help="textbook Craig–Bampton: no residual vectors after the modes",
    )
    ssp = sub.add_parser("statespace", help="state space A, B, C, D between named inputs and outputs")
    fr = sub.add_parser("frf", help="frequency response between named inputs and outputs")
    for q in (ssp, fr):
        q.add_argument("model", help="TOML model file")
        q.add_argument(
            "--input", dest="inputs", action="append", required=True, help="a station (torque there, N·m)"
        )
        q.add_argument(
            "--output",
            dest="outputs",
            action="append",
            required=True,
            help="angle:STATION, speed:STATION or torque:COMPONENT (repeatable)",
        )
        q.add_argument("--force", action="store_true", help="allow replacing an existing file")
        q.add_argument(
            "--max-hz",
            type=_hz("--max-hz", positive=True),
            metavar="F",
            help="keep only the modes up to F Hz",
        )
        q.add_argument(
            "--speed",
            type=_rpm("--speed"),
            default=0.0,
            metavar="RPM",
            help="the line spinning at RPM: a 6-DOF model's gyroscopic terms join the damping (0)",
        )
    ssp.add_argument(
        "-o", dest="output", metavar="FILE", required=True, help="FILE.npz, FILE.mat or FILE.json"
    )
    fr.add_argument(
        "--from", dest="f_from", type=_hz("--from"), default=0.1, help="first frequency, Hz (0.1)"
    )
    fr.add_argument(
        "--to",
        dest="f_to",
        type=_hz("--to", positive=True),
        help="last frequency, Hz (default: 1.5 × the highest mode kept, at most 1e9)",
    )
    fr.add_argument(
        "--points",
        type=_whole("--points", 2, "frf_points"),
        default=1000,
        help="evenly spaced frequencies (1000); 13 more are added around each resonance",
    )
    fr.add_argument("--plot", metavar="FILE", help=f"write the Bode plot to FILE ({PLOTS})")
    fr.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
    fr.add_argument(
        "-o",
        dest="output",
        metavar="FILE",
        help="write the response: FILE.csv, .json, .npz (complex H) or .txt (the peaks table)",
    )
    fo = sub.add_parser(
        "forced", help="steady torque amplitudes in every part under a sinusoidal torque at each mode"
    )
    fo.add_argument("model", help="TOML model file")
    fo.add_argument("--input", default="motor", help="the station the torque is applied at (motor)")
    fo.add_argument("--amplitude", type=float, default=1.0, help="torque amplitude, N·m (1)")
    fo.add_argument(
        "--at",
        dest="at_hz",
        type=float,
        action="append",
        metavar="HZ",
        help="excitation frequency, Hz (repeatable; default: each flexible mode's natural frequency)",
    )
    rp = sub.add_parser("report", help="one self-contained HTML report of a model: parts, modes, pictures")
    rp.add_argument("model", help="TOML model file")
    rp.add_argument("-o", "--output", metavar="DIR", required=True, help="the report's folder (index.html)")
    rp.add_argument("--force", action="store_true", help="allow replacing an existing report in DIR")
    v = sub.add_parser("view", help="one mode in 3D on the drivetrain's surface, as a PNG or an animated GIF")
    v.add_argument("model", help="TOML model file")
    v.add_argument(
        "--mode", type=_whole("--mode", 0), required=True, help="the mode, as `flexshaft modes` numbers it"
    )
    v.add_argument(
        "--color",
        choices=("twist", "stress", "energy"),
        default="twist",
        help="surface colour: twist (mrad), shear stress (MPa) or strain-energy density, at 1 mrad",
    )
    v.add_argument(
        "--scale", type=float, default=0.3, help="drawn twist of the largest station rotation (rad)"
    )
    v.add_argument(
        "--frames", type=_whole("--frames", 2, "frames"), default=30, help="GIF frames per period (30)"
    )
    v.add_argument("-o", "--output", metavar="FILE", required=True, help="FILE.png or FILE.gif")
    v.add_argument("--force", action="store_true", help="allow -o to replace an existing file")
    si = sub.add_parser(
        "simulate", help="time run of a scenario (step, speed ramp in closed loop, coast, ...)"
    )
    si.add_argument("model", help="TOML model file")
    si.add_argument("--scenario", required=True, choices=("step", "ramp", "coast", "sine", "csv"))
    si.add_argument(
        "--output",
        dest="outputs",
        action="append",
        required=True,
        help="angle:STATION, speed:STATION, torque:COMPONENT; with a ramp also control:torque, "
        "control:setpoint (repeatable)",
    )
    si.add_argument("--rate", type=float, default=1000.0, help="sample and controller rate, Hz (1000)")
    si.add_argument("--duration", type=float, help="run length, s (10; a ramp: its time + 10 %%)")
    si.add_argument("--torque", type=float, default=0.0, help="step or sine amplitude, coast preload, N·m")
    si.add_argument("--at", help="station of the drive (air-gap) torque (default: the driving end)")
    si.add_argument("--step-time", type=float, default=0.0, help="when the step comes, s (0)")
    si.add_argument("--frequency", type=float, default=0.0, help="sine frequency, Hz")
    si.add_argument(
        "--speed", type=float, default=0.0, help="start speed (ramp) or running speed (coast), rpm"
    )
    si.add_argument("--end-speed", type=float, help="ramp: final speed, rpm")
    si.add_argument("--ramp-time", type=float, help="ramp: its duration, s")
    si.add_argument("--load", type=float, default=0.0, help="constant load torque, N·m (a generator: < 0)")
    si.add_argument("--load-at", help="station of the load torque (default: the far end)")
    si.add_argument("--kp", type=float, help="PI gain, N·m per rad/s (default: tuned from the model)")
    si.add_argument("--ki", type=float, help="PI integral gain, N·m per rad (default: tuned from the model)")
    si.add_argument("--bandwidth", type=float, help="speed-loop bandwidth for the default gains, Hz")
    si.add_argument("--tau", type=float, default=0.0, help="low-pass to the air-gap torque, s (0: none)")
    si.add_argument("--torque-limit", type=float, help="|commanded torque| limit, N·m (anti-windup)")
    si.add_argument("--measure", help="the speed the loop controls, speed:STATION (default: the drive's)")
    si.add_argument("--series", metavar="CSV", help="csv scenario: the file with the torque history")
    si.add_argument("--column", help="csv scenario: the torque column (header, with or without its unit)")
    si.add_argument("--time-column", default="time", help="csv scenario: the time column (time)")
    _unit_option(si, "csv scenario: ")
    si.add_argument(
        "--max-hz", type=_hz("--max-hz", positive=True), metavar="F", help="keep only the modes up to F Hz"
    )
    si.add_argument("--plot", metavar="FILE", help=f"draw the outputs against time to FILE ({PLOTS})")
    si.add_argument("-o", dest="output", metavar="FILE.csv", help="write the samples: time [s], NAME [unit]…")
    si.add_argument("--force", action="store_true", help="allow replacing an existing file")
    ca = sub.add_parser("campbell", help="Campbell diagram: modes against speed, order lines and crossings")
    ca.add_argument("model", help="TOML model file")
    ca.add_argument("--speed", default="0:1800", help="speed range LO:HI, rpm (0:1800)")
    ca.add_argument("--orders", default="1,2,6", help="excitation orders, comma-separated (1,2,6)")
    ca.add_argument("--reference", help="the station whose speed the axis is (default: the driving end)")
    ca.add_argument("--plot", metavar="FILE", help=f"draw the diagram to FILE ({PLOTS})")
    sp = sub.add_parser(
        "spectrum", help="amplitude spectrum, peaks and damping of a signal (simulated or measured CSV)"
    )
    sp.add_argument("signals", help="CSV: a 'time [s]' column, then 'NAME [unit]' columns")
    sp.add_argument("--column", required=True, help="the signal (its header, with or without the unit)")
    sp.add_argument("--time-column", default="time", help="the time column (time)")
    _unit_option(sp, "")
    sp.add_argument(
        "--window",
        choices=("hann", "rect", "flattop", "exponential"),
        help="hann (default: stationary signals), rect, flattop; with --decay rect or exponential (default)",
    )
    sp.add_argument(
        "--segment",
        type=float,
        metavar="SECONDS",
        help="Welch averaging over segments this long, 50 %% overlap",
    )
    sp.add_argument(
        "--decay",
        action="store_true",
        help="the record is a free decay: damping by a window fit for a transient and by log decrement",
    )
    sp.add_argument(
        "--peaks", type=_whole("--peaks", 1, "peaks"), default=8, help="how many peaks to list (8)"
    )
    sp.add_argument("--speed-column", help="a shaft-speed column: peaks get their order, plots the orders")
    sp.add_argument("--orders", default="1,2,6", help="order lines of the spectrogram plot (1,2,6)")
    sp.add_argument("--model", help="a model file: peaks get the nearest eigenfrequency, plots mark them")
    sp.add_argument(
        "--plot",
        metavar="FILE",
        help="the spectrum; with --speed-column the spectrogram against speed, --spectrogram: against time",
    )
    sp.add_argument(
        "--spectrogram",
        action="store_true",
        help="--plot draws the spectrogram (against time without a speed)",
    )
    se = sub.add_parser("sensitivity", help="how every mode moves with every parameter (analytic)")
    se.add_argument("model", help="TOML model file")
    se.add_argument(
        "--param",
        dest="params",
        action="append",
        metavar="NAME",
        help="COMPONENT.FIELD or MATERIAL.FIELD (repeatable; default: every parameter)",
    )
    se.add_argument(
        "--modes",
        type=_whole("--modes", 1),
        help=f"the lowest N elastic modes (default: {DEFAULT_MODES}, or all the model has if fewer)",
    )
    se.add_argument("--plot", metavar="FILE", help=f"the normalised sensitivities as a heat map ({PLOTS})")
    cb = sub.add_parser("calibrate", help="tune parameters to target frequencies (bounded least squares)")
    cb.add_argument("model", help="TOML model file (the stages of a targets file may name others)")
    cb.add_argument("--targets", required=True, metavar="T.toml", help="targets and parameters (TOML)")
    cb.add_argument(
        "--starts", type=_whole("--starts", 1, "starts"), help="starting points (overrides the file's)"
    )
    cb.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
    cb.add_argument("-o", dest="output", metavar="TUNED.toml", help="write the tuned model file")
    cb.add_argument("--force", action="store_true", help="allow replacing an existing file")
    cb.add_argument("--scheduler", metavar="ADDRESS", help="run the starts on this Dask scheduler")
    sw = sub.add_parser("sweep", help="a parameter study: frequencies and damping over a grid or a hypercube")
    sw.add_argument("model", help="TOML model file")
    sw.add_argument(
        "--param",
        dest="params",
        action="append",
        required=True,
        metavar="NAME=LO:HI:N",
        help="a parameter and its values: LO:HI:N evenly spaced, or V1,V2,... (repeatable: a full grid)",
    )
    sw.add_argument(
        "--lhs",
        type=_whole("--lhs", 1, "sweep_points"),
        metavar="N",
        help="N Latin-hypercube points in LO:HI instead",
    )
    sw.add_argument("--seed", type=_whole("--seed", 0), default=0, help="seed of the hypercube (0)")
    sw.add_argument(
        "--modes",
        type=_whole("--modes", 1),
        help=f"elastic modes per point (default: {DEFAULT_MODES}, or all the model has if fewer)",
    )
    sw.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (tcp://host:8786)")
    sw.add_argument("--json", action="store_true", help="print one JSON document instead of a summary")
    sw.add_argument("-o", dest="output", metavar="SWEEP.csv", help="write every point as CSV")
    sw.add_argument("--force", action="store_true", help="allow replacing an existing file")
    for q in (fo, ca, sp, se):
        _json_output_options(q)
    for q in (m, s, t, r, v, rp, ssp, fr, fo, si, ca, sp, se, cb, sw):
        q.add_argument(
            "--no-cache",
            action="store_true",
            help="slice CAD parts anew instead of reading their section tables from the disk cache",
        )
        q.add_argument(
            "--allow-code",
            action="store_true",
            help="run part code the model file names beyond flexshaft's own part library "
            "(a .py file beside it or an installed package): only for files you trust",
        )
    for q in (m, d, s, t, r):
        q.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
        q.add_argument(
            "-o",
            "--output",
            metavar="PATH",
            help="the flexible-body file (reduce); else write the table to PATH instead of stdout - "
            "PATH.txt the table, PATH.json (or --json) JSON, PATH.csv CSV for `sections`",
        )
        q.add_argument("--force", action="store_true", help="allow -o to replace an existing file")
    for q in sub.choices.values():
        q.add_argument(
            "--threads",
            type=_whole("--threads", 1),
            metavar="N",
            help="BLAS/OpenMP threads (default: FLEXSHAFT_THREADS, else your OPENBLAS_NUM_THREADS/"
            "OMP_NUM_THREADS if set, else 1 - steady on a busy machine)",
        )
    return p


def _load(args, path):
    """The model file, with the command line's trust, cache and progress settings."""
    from .io.modelfile import load_model
    from .views.progress import ProgressBar

    return load_model(path, progress=ProgressBar, allow_code=args.allow_code, use_cache=not args.no_cache)


def _write_plot(path, fig, force: bool) -> Path:
    """A ``--plot`` figure, written atomically in the type its suffix names (.png, .svg or .pdf)."""
    from .atomic import atomic_write_bytes
    from .views.plots import picture

    return atomic_write_bytes(path, picture(fig, Path(path).suffix), overwrite=force)


# What each command writes, by option: the suffixes it accepts (any case) and what each gives. Checked
# by _check_output_paths before any work, so a wrong suffix costs nothing and never gets content of
# another type (a text table in a .npz, a PNG in a .txt).
_TABLE = {".txt": "the table", ".json": "the JSON document"}
_PLOT = {".png": "PNG", ".svg": "SVG", ".pdf": "PDF"}  # matplotlib's Agg, SVG and PDF backends
OUTPUT_SUFFIXES: dict[str, dict[str, dict[str, str]]] = {
    "modes": {"-o": _TABLE},
    "demo": {"-o": _TABLE},  # or a folder, DIR/: the report
    "sections": {"-o": _TABLE | {".csv": "the section tables as CSV"}},
    "twist": {"-o": _TABLE, "--plot": _PLOT, "--view": {".png": "PNG only: the 3D view is a raster picture"}},
    "reduce": {"-o": {s: "the flexible body" for s in (".npz", ".json", ".mat", ".op4", ".pch")}},
    "view": {"-o": {".png": "a picture", ".gif": "an animation"}},
    "statespace": {"-o": {s: "A, B, C, D and their names and units" for s in (".npz", ".mat", ".json")}},
    "frf": {
        "-o": {
            ".csv": "frequency and real, imaginary parts",
            ".json": "the JSON document",
            ".npz": "frequency_hz and complex H, units in metadata",
            ".txt": "the peaks table",
        },
        "--plot": _PLOT,
    },
    "forced": {"-o": _TABLE},
    "simulate": {"-o": {".csv": "the samples"}, "--plot": _PLOT},
    "campbell": {"-o": _TABLE, "--plot": _PLOT},
    "spectrum": {"-o": _TABLE, "--plot": _PLOT},
    "sensitivity": {"-o": _TABLE, "--plot": _PLOT},
    "calibrate": {"-o": {".toml": "the tuned model file"}},
    "sweep": {"-o": {".csv": "every point"}},
}
REPORT_FILES = ("index.html", "modes.json")  # what a report folder gets


def _to_folder(args) -> bool:
    """Whether ``-o`` names a folder: always for report; for demo an existing folder or a path ending in /."""
    if args.command == "report":
        return True
    out = getattr(args, "output", None)
    return args.command == "demo" and bool(out) and (out.endswith("/") or Path(out).is_dir())


def _check_output_paths(args) -> None:
    """Refuse an output path of the wrong type before any work: every -o, --plot and --view.

    A file's suffix (any case) must be one ``OUTPUT_SUFFIXES`` lists for the command and option;
    a report folder must be one flexshaft may write (:func:`flexshaft.atomic.check_output_folder`).
    """
    if _to_folder(args):
        from .atomic import check_output_folder

        if Path(args.output).suffix.lower() in (".html", ".htm"):
            raise ModelError(
                "is a folder for the report, not a page",
                field="-o",
                value=args.output,
                valid="a folder DIR (the report writes DIR/index.html and DIR/modes.json)",
            )
        inputs = [args.model] if args.command == "report" else []
        check_output_folder(args.output, force=args.force, inputs=inputs, files=REPORT_FILES, option="-o")
        return
    for option, kinds in OUTPUT_SUFFIXES.get(args.command, {}).items():
        path = getattr(args, {"-o": "output", "--plot": "plot", "--view": "view"}[option], None)
        if path is not None and Path(path).suffix.lower() not in kinds:  # "" too: it names no file
            valid = ", ".join(f"{s} ({what})" for s, what in kinds.items())
            if args.command == "demo":
                valid += ", or a folder DIR/ (the report)"
            raise ModelError("unknown file type", field=option, value=path, valid=valid)
    _check_output_files(args)


#: The options naming files a command reads: no output may be one of them.
INPUT_OPTIONS = ("model", "signals", "source", "targets", "series")


def _check_output_files(args) -> None:
    """Before any work: no output file is an input, two outputs or an existing file without --force.

    The atomic writer checks the same again when it writes (with the files a model brought in, such
    as its STEP parts); checking here too means a refused output costs no computation and leaves no
    other output (a plot) behind.
    """
    import os
    import stat

    named = {"-o": getattr(args, "output", None), "--plot": getattr(args, "plot", None)}
    named["--view"] = getattr(args, "view", None)
    inputs = []
    for attr in INPUT_OPTIONS:
        value = getattr(args, attr, None)
        if isinstance(value, str) and value:
            try:
                inputs.append((attr, os.stat(value)))
            except (OSError, ValueError):
                pass  # a missing input is its reader's error
    seen: dict[tuple[int, int] | str, str] = {}
    for option, path in named.items():
        if not path:
            continue
        key = os.path.abspath(path)
        if key in seen:
            raise ModelError(
                f"is also the {seen[key]} file", field=option, value=path, valid="a different path"
            )
        seen[key] = option
        try:
            st = os.stat(path)
        except FileNotFoundError:
            parent = os.path.dirname(os.path.abspath(path))
            if not os.path.isdir(parent):
                valid = "a path in an existing folder"
                raise ModelError("its folder does not exist", field=option, value=path, valid=valid) from None
            continue
        except (OSError, ValueError):
            continue  # the writer says why
        for attr, ist in inputs:
            if (st.st_dev, st.st_ino) == (ist.st_dev, ist.st_ino):
                raise ModelError(
                    f"is the input file {getattr(args, attr)!r} (links followed): an output never "
                    "replaces an input, --force or not",
                    field=option,
                    value=path,
                    valid="a path that is none of the command's input files",
                )
        if stat.S_ISDIR(st.st_mode):
            raise ModelError("is a folder", field=option, value=path, valid="a file path")
        if not args.force:
            raise ModelError(
                "file exists", field=option, value=path, valid="a new path, or --force to replace it"
            )


def _mesh_check(result, asked: bool | None):
    """The mesh-convergence estimate: when asked, or by default on models up to MESH_CHECK_AUTO_DOFS."""
    if asked is False or (asked is None and result.model.n_dof > MESH_CHECK_AUTO_DOFS):
        return None
    from .analysis.convergence import mesh_convergence

    try:
        return mesh_convergence(result)
    except ModelError:
        if asked:
            raise  # asked for explicitly: say why it cannot be done
        return None  # the doubled mesh is over a budget or a guard: the modes themselves stand


def _all_modes(model):
    """Every mode of a model up to 2000 DOFs (no truncation), the default count above."""
    from .analysis.modal import modal_analysis

    return modal_analysis(model, model.n_dof if model.n_dof <= 2000 else None)


def _modes(drivetrain, args) -> str:
    from .analysis.modal import modal_analysis
    from .validation import check_real
    from .views.tables import modes_document, modes_table

    count = getattr(args, "count", None)
    try:
        result = modal_analysis(drivetrain, count, inertia_model=getattr(args, "inertia", None))
    except ModelError as err:
        if count is None or err.field != "count":
            raise
        # named as the option (as sensitivity and sweep name --modes)
        raise ModelError(err.message, field="--count", value=err.value, valid=err.valid) from None
    max_hz = getattr(args, "max_hz", None)
    if max_hz is not None:
        max_hz = check_real(max_hz, "--max-hz", "Hz", lo=0.0, lo_open=True)
    mesh = _mesh_check(result, getattr(args, "mesh_check", None))
    if args.json:
        return json.dumps(modes_document(result, max_hz=max_hz, mesh=mesh), indent=1, ensure_ascii=False)
    return modes_table(result, max_hz=max_hz, mesh=mesh)


def _twist(args) -> str:
    from .analysis.twist import stiffness_target, twist_test
    from .views.tables import twist_document, twist_table

    drivetrain = _load(args, args.model)
    result = twist_test(drivetrain, args.torque, clamp=args.clamp, load=args.load)
    targets = []
    for spec in args.target:
        name, sep, value = spec.rpartition("=")
        try:
            k = float(value)
        except ValueError:
            k = None
        if not sep or not name or k is None:
            raise ModelError(
                "is not PART=STIFFNESS",
                field="--target",
                value=spec,
                valid="a component name, '=', a stiffness in N·m/rad",
            )
        targets.append((name, stiffness_target(drivetrain.component(name), k)))
    if args.plot:
        from .views.plots import twist_figure

        _write_plot(args.plot, twist_figure(result), args.force)
    if args.view:
        from .views.render import twist_png

        twist_png(drivetrain, result, args.view, overwrite=args.force)
    if args.json:
        doc = twist_document(result)
        doc["targets"] = [
            {
                "name": n,
                "target": t.target,
                "current": t.current,
                "E": t.youngs_modulus,
                "scale_all": t.scale_all,
                "scale_diameters": t.scale_diameters,
            }
            for n, t in targets
        ]
        return json.dumps(doc, indent=1, ensure_ascii=False)
    text = twist_table(result)
    for n, t in targets:
        text += (
            f"\n\n{n}: {t.current:.6e} -> {t.target:.6e} N·m/rad needs E = {t.youngs_modulus:.6e} Pa "
            f"(ν and geometry fixed), or every dimension ×{t.scale_all:.6f}, or the diameters "
            f"×{t.scale_diameters:.6f}"
        )
    return text


def _reduce(args) -> str:
    from .io.bodies import write_flexible_body
    from .model.assembly import shaft_part_model
    from .model.components import Shaft
    from .reduction import cb_check, craig_bampton

    if not args.output:
        raise ModelError(
            "needs an output file", field="-o", valid="-o PART.npz, PART.json, PART.mat, PART.op4 or PART.pch"
        )
    drivetrain = _load(args, args.model)
    comp = drivetrain.component(args.part)
    if not isinstance(comp, Shaft):
        raise ModelError(
            "has no elements to reduce",
            field="--part",
            value=args.part,
            valid="a shaft: a cad part, or a shaft given by segments or by numbers",
        )
    pm = shaft_part_model(comp, drivetrain.dofs, drivetrain.inertia_model)
    extra = comp.named_mesh_nodes(pm.x - pm.x[0])
    spec = comp.reduce
    modes, cutoff = args.modes, args.cutoff
    if modes is None and cutoff is None:
        if spec is None:
            raise ModelError(
                "how many modes?",
                field="--modes",
                valid="--modes N or --cutoff HZ, or reduce = {modes = n} on the part in the model file",
            )
        modes, cutoff = spec.modes, spec.cutoff_hz
    if args.damping_ratio is not None:
        ratio = args.damping_ratio
    elif spec is not None:
        ratio = spec.damping
    else:
        ratio = comp.damping_ratio or 0.0053
    body = craig_bampton(
        pm, modes=modes, cutoff_hz=cutoff, nodes=extra, damping_ratio=ratio, residual=not args.no_residual
    )
    check = cb_check(body, pm)
    n_fixed = body.n_modes - body.n_residual
    path = write_flexible_body(body, args.output, material=comp.material, overwrite=args.force)
    if args.json:
        doc = {
            "units": {"x": "m", "frequency": "Hz", "damping_ratio": "fraction"},
            "part": comp.name,
            "dofs": drivetrain.dofs,
            "part_dofs": pm.n_dofs,
            "boundary_dofs": body.n_boundary,
            # A shaft given by numbers has no length: its interface positions are not metres.
            "boundary_x": (body.boundary_x - pm.x[0]).tolist() if comp.sections is not None else None,
            "modes": n_fixed,
            "residual_vectors": body.n_residual,
            "fixed_interface_hz": body.fixed_interface_hz[:n_fixed].tolist(),
            "free_hz": body.free_hz.tolist(),
            "damping_ratios": body.damping_ratios.tolist(),
            "check": {"rigid_mass_error": check.rigid_mass_error, "static_error": check.static_error},
            "written": str(path),
        }
        return json.dumps(doc, indent=1, ensure_ascii=False)
    lines = [
        f"{comp.name}: {pm.n_dofs} DOFs ({drivetrain.dofs}) -> {body.n_boundary} boundary DOFs at x = "
        + ", ".join(f"{x:.4g}" for x in body.boundary_x)
        + f" m + {n_fixed} fixed-interface modes + {body.n_residual} residual vectors",
        "fixed-interface modes, Hz: "
        + (" ".join(f"{f:.2f}" for f in body.fixed_interface_hz[:n_fixed]) or "none (no interior nodes)"),
        "free-free modes of the reduced part, Hz: " + " ".join(f"{f:.2f}" for f in body.free_hz),
        "damping ratio per free-free mode, %: "
        + " ".join(f"{100 * z:.3f}" for z in body.damping_ratios[body.free_hz > 0]),
        f"check: rigid-body mass {check.rigid_mass_error:.1e}, interface stiffness vs static condensation "
        f"{check.static_error:.1e} (relative)",
        f"written: {path}",
    ]
    return "\n".join(lines)


def _report(args) -> str:
    return _write_report(_load(args, args.model), args.output, args.force, inputs=(args.model,))


def _write_report(drivetrain, out, force: bool, inputs=()) -> str:
    from .analysis.modal import modal_analysis
    from .analysis.twist import twist_test
    from .views.progress import ProgressBar
    from .views.report import write_report
    from .views.tables import modes_document

    result = modal_analysis(drivetrain)
    mesh = _mesh_check(result, None)
    path = write_report(
        result,
        out,
        twist=twist_test(drivetrain, 1000.0),
        document=modes_document(result, mesh=mesh),
        overwrite=force,
        progress=ProgressBar("rendering"),
        mesh=mesh,
        inputs=inputs,
        option="-o",
    )
    return f"report: {path}"


def _demo_model(source: str):
    from .io.modelfile import loads_model

    text = resources.files("flexshaft.data").joinpath(DEMO_MODEL).read_text(encoding="utf-8")
    return loads_model(text, source=source)


def _system(args):
    from .analysis.statespace import state_space
    from .model.assembly import assemble

    result = _all_modes(assemble(_load(args, args.model)))
    return result, state_space(result, args.inputs, args.outputs, max_hz=args.max_hz, speed_rpm=args.speed)


def _statespace(args) -> str:
    import io

    import numpy as np

    from .atomic import atomic_write_bytes, atomic_write_text

    _, ss = _system(args)
    meta = {
        "format": "flexshaft-state-space",
        "units": {"input": "N·m", "time": "s"},
        "inputs": list(ss.inputs),
        "outputs": list(ss.outputs),
        "input_units": list(ss.input_units),
        "output_units": list(ss.output_units),
        "states": list(ss.states),
        "modes": ss.modes.tolist(),
        "frequencies_hz": ss.frequencies_hz.tolist(),
    }
    out = args.output
    if out.lower().endswith(".npz"):
        buf = io.BytesIO()
        np.savez(buf, A=ss.A, B=ss.B, C=ss.C, D=ss.D, metadata=np.array(json.dumps(meta, ensure_ascii=False)))
        path = atomic_write_bytes(out, buf.getvalue(), overwrite=args.force)
    elif out.lower().endswith(".mat"):
        from scipy.io import savemat

        buf = io.BytesIO()
        savemat(
            buf,
            {
                "A": ss.A,
                "B": ss.B,
                "C": ss.C,
                "D": ss.D,
                "flexshaft_metadata": json.dumps(meta, ensure_ascii=False),
            },
        )
        path = atomic_write_bytes(out, buf.getvalue(), overwrite=args.force)
    elif out.lower().endswith(".json"):
        doc = meta | {k: getattr(ss, k).tolist() for k in ("A", "B", "C", "D")}
        path = atomic_write_text(out, json.dumps(doc, ensure_ascii=False), overwrite=args.force)
    else:
        raise ModelError("unknown file type", field="-o", value=out, valid="FILE.npz, FILE.mat or FILE.json")
    return (
        f"state space: {ss.A.shape[0]} states ({len(ss.modes)} modes), {len(ss.inputs)} inputs, "
        f"{len(ss.outputs)} outputs: {path}"
    )


def _frf(args) -> str:

    from .analysis.statespace import frequency_grid, frequency_response

    if len(args.inputs) != 1:
        raise ModelError(
            "frf takes one input (its outputs are repeatable)",
            field="--input",
            value=", ".join(args.inputs),
            valid="one station; run frf once per input, or use statespace for several",
        )
    _, ss = _system(args)
    from .validation import MAX_FREQUENCY_HZ

    # the default's ceiling is the option's: a mode above 1e9 Hz (a micrometre disc) is past the range
    top = 1.5 * max(float(ss.frequencies_hz.max()), 1.0)
    f_to = args.f_to if args.f_to is not None else min(top, MAX_FREQUENCY_HZ)
    if not (0 <= args.f_from < f_to):
        raise ModelError(
            "must be below --to",
            field="--from",
            value=args.f_from,
            unit="Hz",
            valid=f"0 <= --from < --to = {f_to:g} Hz",
        )
    resp = frequency_response(ss, frequency_grid(ss, args.f_from, f_to, args.points))
    H = resp.H[:, :, 0] if resp.H.shape[2] == 1 else resp.H
    one = H.ndim == 2 and H.shape[1] == 1
    doc = {
        "inputs": list(resp.inputs),
        "outputs": list(resp.outputs),
        "units": {"frequency": "Hz", "input": list(resp.input_units), "output": list(resp.output_units)},
        "frequency_hz": resp.frequencies_hz.tolist(),
        "real": (H[:, 0].real if one else H.real).tolist(),
        "imag": (H[:, 0].imag if one else H.imag).tolist(),
        "peaks": resp.peaks(),
    }
    if args.plot:
        from .views.plots import bode_figure

        _write_plot(args.plot, bode_figure(resp), args.force)
    kind = Path(args.output).suffix.lower() if args.output else None
    if kind == ".npz":
        return _frf_written(resp, args, _frf_npz(resp, doc))
    if kind == ".csv":
        lines = [
            "frequency_hz,"
            + ",".join(
                f"{o} real ({u}/N·m),{o} imag ({u}/N·m)" for o, u in zip(resp.outputs, resp.output_units)
            )
        ]
        for k, fk in enumerate(resp.frequencies_hz):
            lines.append(
                f"{fk:.9g},"
                + ",".join(
                    f"{resp.H[k, j, 0].real:.9g},{resp.H[k, j, 0].imag:.9g}" for j in range(len(resp.outputs))
                )
            )
        text = "\n".join(lines)
    elif args.json or kind == ".json":
        text = json.dumps(doc, ensure_ascii=False)
    else:
        rows = [f"frequency response {resp.inputs[0]} -> {', '.join(resp.outputs)}; peaks:"]
        rows += [
            f"  {p['frequency_hz']:10.4f} Hz  |H| {p['magnitude']:.4g}  half-power damping "
            f"{100 * p['damping_ratio']:.4f} %"
            for p in doc["peaks"]
        ]
        text = "\n".join(rows)
    return _frf_written(resp, args, (text + "\n").encode("utf-8")) if args.output else text


def _frf_npz(resp, doc: dict) -> bytes:
    """The response as an .npz: ``frequency_hz`` (Hz), complex ``H`` [frequency, output, input], ``metadata``.

    ``metadata`` is a JSON string (as in ``statespace -o FILE.npz``): the input and output names,
    their units (H is in output unit per input unit) and the peaks; ``np.load(path)`` reads it all
    without pickles.
    """
    import io

    import numpy as np

    meta = {
        "format": "flexshaft-frequency-response",
        "inputs": doc["inputs"],
        "outputs": doc["outputs"],
        "units": doc["units"] | {"H": "output unit per input unit, e.g. rad/s per N·m"},
        "shape": "H[frequency, output, input]",
        "peaks": doc["peaks"],
    }
    buf = io.BytesIO()
    np.savez(
        buf,
        frequency_hz=np.asarray(resp.frequencies_hz, dtype=float),
        H=np.asarray(resp.H, dtype=complex),
        metadata=np.array(json.dumps(meta, ensure_ascii=False)),
    )
    return buf.getvalue()


def _frf_written(resp, args, data: bytes) -> str:
    """Write frf's -o file (its type checked before the work) and say what went where."""
    from .atomic import atomic_write_bytes

    path = atomic_write_bytes(args.output, data, overwrite=args.force)
    return (
        f"frequency response {resp.inputs[0]} -> {', '.join(resp.outputs)}, "
        f"{resp.frequencies_hz.size} frequencies: {path}"
    )


def _forced(args) -> str:
    from .analysis.forced import forced_response
    from .model.assembly import assemble

    result = _all_modes(assemble(_load(args, args.model)))
    try:
        fr = forced_response(result, args.input, amplitude=args.amplitude, frequencies_hz=args.at_hz)
    except ModelError as err:
        if err.field in ("amplitude", "input"):  # the library names its argument, the CLI its option
            err = ModelError(
                err.message, field=f"--{err.field}", value=err.value, unit=err.unit, valid=err.valid
            )
        raise err from None
    if args.json:
        return json.dumps(fr.to_dict(), ensure_ascii=False)
    parts = [k for k, s in enumerate(fr.signals) if s.startswith("torque:")]
    width = max(10, *(len(fr.signals[k]) - 7 for k in parts))
    head = "mode  frequency Hz  " + "  ".join(f"{fr.signals[k][7:]:>{width}}" for k in parts) + "  largest"
    rows = [
        f"forced response to {fr.amplitude:g} N·m at {fr.input}: peak dynamic torque per part, N·m",
        "",
        head,
        "-" * len(head),
    ]
    for i, (f, m) in enumerate(zip(fr.frequencies_hz, fr.modes)):
        cells = "  ".join(f"{fr.amplitudes[i, k]:>{width}.4g}" for k in parts)
        rows.append(f"{m if m >= 0 else '-':>4}  {f:12.4f}  {cells}  {fr.largest_torque(i)}")
    return "\n".join(rows)


def _is_station(model, name: str) -> bool:
    try:
        model.station(name, "station")
    except ModelError:
        return False
    return True


def _simulate(args) -> str:
    import math

    from .analysis.simulate import Scenario, SpeedControl, simulate
    from .model.assembly import assemble
    from .views.progress import ProgressBar

    if args.output and not args.output.lower().endswith(".csv"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="FILE.csv")
    kind = args.scenario
    if kind != "ramp":  # refused before any work
        for name in ("kp", "ki", "bandwidth", "torque_limit", "measure", "end_speed", "ramp_time"):
            if getattr(args, name) is not None:
                raise ModelError(
                    "belongs to the ramp scenario (the closed speed loop)",
                    field="--" + name.replace("_", "-"),
                    valid="--scenario ramp, or leave it out",
                )
    if kind == "csv" and args.column:
        from .signals.checks import check_not_time

        check_not_time(args.column, args.time_column, "--column")
    result = _all_modes(assemble(_load(args, args.model)))
    # The library names its arguments; the command line names the options that set them.
    option_of = {
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
        "measure": "--measure",
        "rate": "--rate",
        "duration": "--duration",
        "max_hz": "--max-hz",
        "series": "--series",
        "output": "--output",
    }
    common = {"load": args.load, "load_at": args.load_at}
    try:
        if kind == "step":
            sc = Scenario.step(args.torque, at=args.at, time=args.step_time, **common)
        elif kind == "sine":
            sc = Scenario.sine(args.torque, args.frequency, at=args.at, **common)
        elif kind == "coast":
            sc = Scenario.coast(args.torque, speed_rpm=args.speed, at=args.at, load_at=args.load_at)
        elif kind == "csv":
            from .io.signalfile import read_signals

            if not args.series or not args.column:
                raise ModelError(
                    "the csv scenario reads a torque history",
                    field="--series",
                    valid="--series FILE.csv --column NAME",
                )
            table = read_signals(
                args.series, columns=[args.column], units=_units(args.units), time_column=args.time_column
            )
            (torque,) = table.columns.values()
            (unit,) = table.units.values()
            if unit != "N·m":
                raise ModelError(
                    "the drive torque history must be a torque",
                    field="--column",
                    value=args.column,
                    unit=unit,
                    valid="a column in N·m or kN·m",
                )
            sc = Scenario.from_series(table.time, torque, at=args.at, **common)
        else:
            if args.end_speed is None or args.ramp_time is None:
                raise ModelError(
                    "a ramp needs its final speed and duration",
                    field="--end-speed" if args.end_speed is None else "--ramp-time",
                    valid="--end-speed RPM --ramp-time S",
                )
            limit = math.inf if args.torque_limit is None else args.torque_limit
            if not limit > 0:  # NaN too
                raise ModelError(
                    "must be > 0", field="--torque-limit", value=limit, unit="N·m", valid="> 0 N·m"
                )
            loop = {"tau": args.tau, "torque_min": -limit, "torque_max": limit, "measure": args.measure}
            if (args.kp is None) != (args.ki is None):
                raise ModelError("give both gains or neither", field="--kp" if args.kp is None else "--ki")
            if args.kp is None:
                control = SpeedControl.tuned(result, bandwidth_hz=args.bandwidth, **loop)
            else:
                control = SpeedControl(args.kp, args.ki, **loop)
            sc = Scenario.ramp(args.end_speed, args.ramp_time, control, start_rpm=args.speed, **common)
        # The stations by their options (the state space would call either of them "input").
        for option, station in (("--at", args.at), ("--load-at", args.load_at)):
            if station is not None and not _is_station(result.model, station):
                from .analysis.statespace import signal_names

                stations = ", ".join(signal_names(result.model)["inputs"])
                raise ModelError("no such station", field=option, value=station, valid=stations)
        # every result is checked in there: a stable loop, inputs below Nyquist, enough samples,
        # finite outputs - so nothing below prints or writes a number that is not one
        run = simulate(
            result,
            sc,
            args.outputs,
            rate=args.rate,
            duration=args.duration,
            max_hz=args.max_hz,
            progress=ProgressBar("simulating"),
        )
    except ModelError as err:
        if err.file is not None or err.field not in option_of:
            raise
        raise ModelError(
            err.message,
            component=err.component,
            field=option_of[err.field],
            value=err.value,
            unit=err.unit,
            valid=err.valid.replace("max_hz", "--max-hz") if err.valid else err.valid,
            has_value=err.has_value,
        ) from None
    lines = [
        f"{kind} run: {run.time[-1]:g} s at {run.rate_hz:g} Hz ({run.time.size} samples, "
        f"{run.states} states, {run.method})"
    ]
    if sc.control is not None:
        c = sc.control
        lines.append(
            f"speed loop on {c.measure or 'speed:' + (sc.at or result.model.stations[0].name)}: "
            f"kp {c.kp:.6g} N·m·s/rad, ki {c.ki:.6g} N·m/rad, tau {c.tau:g} s, "
            f"limits {c.torque_min:g} … {c.torque_max:g} N·m"
        )
    lines.append(f"{'output':<32} {'unit':>6} {'min':>12} {'max':>12} {'final':>12}")
    for name, y in run.outputs.items():
        lines.append(f"{name:<32} {run.units[name]:>6} {y.min():12.5g} {y.max():12.5g} {y[-1]:12.5g}")
    if args.plot:
        from .views.plots import simulation_figure

        _write_plot(args.plot, simulation_figure(run), args.force)
        lines.append(f"plot: {args.plot}")
    if args.output:
        from .io.signalfile import write_signals

        cols = {name: (y, run.units[name]) for name, y in run.outputs.items()}
        path = write_signals(args.output, run.time, cols, overwrite=args.force)
        lines.append(f"samples: {path}")
    return "\n".join(lines)


def _campbell(args) -> str:
    from .analysis.campbell import campbell
    from .limits import check_ceiling
    from .model.assembly import assemble
    from .signals.checks import parse_orders

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
    result = _all_modes(assemble(_load(args, args.model)))
    try:
        diagram = campbell(result, speeds, orders, reference=args.reference)
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
        from .views.plots import campbell_figure

        _write_plot(args.plot, campbell_figure(diagram), args.force)
    if args.json:
        return json.dumps(diagram.to_dict(), ensure_ascii=False)
    rows = [
        f"Campbell diagram: {speeds[0]:g} … {speeds[1]:g} rpm at {diagram.reference!r}, orders "
        + ", ".join(f"{k:g}" for k in diagram.orders)
        + (
            " (gyroscopic: the whirl frequencies move with speed)"
            if diagram.speed_dependent
            else " (no speed-dependent terms: every mode is a horizontal line)"
        ),
        "",
        f"{'speed rpm':>10}  {'order':>5}  {'mode':>4}  {'frequency Hz':>12}  {'damping %':>9}",
    ]
    for c in diagram.crossings:
        rows.append(
            f"{c.speed_rpm:10.2f}  {c.order:5g}  {c.mode:4d}  {c.frequency_hz:12.4f}  "
            f"{100 * c.damping_ratio:9.4f}"
        )
    if not diagram.crossings:
        rows.append("  (no order line crosses a mode in this speed range)")
    return "\n".join(rows)


def _calibrate(args) -> str:
    from datetime import date

    from .analysis.calibrate import calibrate, check_problem
    from .analysis.sensitivity import parameters, with_parameters
    from .io.tunedfile import carried, read_targets, write_tuned_model

    if args.output and not args.output.lower().endswith(".toml"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="TUNED.toml")
    tf = read_targets(args.targets)
    starts = args.starts or tf.starts

    def in_stage(err: ModelError, stage) -> ModelError:
        """The error located in the targets file, its entry named as the file has it."""
        component = err.component
        if stage.where and component and component.startswith("[["):
            component = stage.where + component
        return ModelError(
            err.message,
            file=err.file or tf.source,
            component=component,
            field=err.field,
            value=err.value,
            unit=err.unit,
            valid=err.valid,
            has_value=err.has_value,
        )

    # Every stage's targets and parameters checked against its model before the first one runs.
    models, earlier = [], {}  # earlier: stage name -> the parameters it tunes
    for stage in tf.stages:
        path = stage.model or Path(args.model)
        d = _load(args, str(path))
        try:
            check_problem(d, stage.targets, stage.parameters)
        except ModelError as err:
            raise in_stage(err, stage) from None
        has = {p.name for p in parameters(d)}
        for name in stage.carry_from if stage.carry_from is not None else earlier:
            for k, b in enumerate(stage.parameters):
                if b.name in earlier[name] and b.name in has:
                    raise ModelError(
                        f"was tuned in the earlier stage {name!r} and is carried into {stage.name!r}, fixed",
                        file=tf.source,
                        component=f"{stage.where}[[parameter]] #{k + 1}",
                        field="parameter",
                        value=b.name,
                        valid="leave it out of the later stage",
                    )
        earlier[stage.name] = {b.name for b in stage.parameters if b.fixed is None}
        models.append((path, d))
    executor = None
    if args.scheduler:
        from .analysis.sweep import dask_executor

        executor = dask_executor(args.scheduler)
    tuned: dict = {}  # stage name -> its tuned values
    reports = []
    last = None
    for stage, (path, d) in zip(tf.stages, models):
        pool: dict = {}
        for name in stage.carry_from if stage.carry_from is not None else tuned:
            pool |= tuned[name]
        fixed = carried(d, pool)
        try:
            res = calibrate(
                with_parameters(d, fixed) if fixed else d,
                stage.targets,
                stage.parameters,
                starts=starts,
                seed=tf.seed,
                executor=executor,
            )
        except ModelError as err:
            raise in_stage(err, stage) from None
        tuned[stage.name] = dict(zip(res.names, res.tuned))
        reports.append((stage, path, fixed, res))
        last = (path, d, fixed | res.fixed | dict(zip(res.names, res.tuned)))
    lines = []
    if args.output:
        path, d, values = last
        header = (
            f"{d.name}, tuned by flexshaft calibrate on {date.today().isoformat()} "
            f"against {Path(tf.source).name}\n"
            f"from {path}; tuned values (SI): " + ", ".join(f"{k} = {v:.9g}" for k, v in values.items())
        )
        out = write_tuned_model(args.output, path, d, values, header=header, overwrite=args.force)
        lines.append(f"tuned model: {out}")
    if args.json:
        doc = {
            "stages": [
                {"name": st.name, "model": str(p), "carried": {k: float(v) for k, v in fx.items()}}
                | res.to_dict()
                for st, p, fx, res in reports
            ]
        }
        if args.output:
            doc["tuned_model"] = lines[0].split(": ", 1)[1]
        return json.dumps(doc, ensure_ascii=False)
    body = []
    for st, p, fx, res in reports:
        body += [f"stage {st.name!r} ({p}): {res.starts} start(s), cost {res.cost:.4g}; {res.message}"]
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
            body.append(
                f"  {n:<{width}} {res.initial[k]:12.6g} {res.tuned[k]:12.6g} {res.lower[k]:12.6g} "
                f"{res.upper[k]:12.6g} {res.change_percent[k]:9.3f}  {note}"
            )
        body.append(
            f"  {'target':<16} {'mode':>4} {'initial':>10} {'tuned':>10} {'error %':>8} {'tol %':>6}  met"
        )
        for t, mo, a, v, e, ok in zip(
            res.targets, res.modes, res.initial_values, res.values, res.errors, res.met
        ):
            body.append(
                f"  {t.label:<16} {mo:>4} {a:10.5g} {v:10.5g} {100 * e:8.3f} {100 * t.tolerance:6.2f}  "
                f"{'yes' if ok else 'NO'}"
            )
        for u in res.unmet:
            need = "; ".join(f"{e['parameter']} {e['change_percent']:+.1f} %" for e in u["alone_would_need"])
            body.append(f"  {u['target']} is missed by {100 * u['error']:+.2f} %: alone it would need {need}")
        body.append("")
    return "\n".join(body + lines).rstrip()


def _sweep(args) -> str:
    import numpy as np

    from .analysis.sensitivity import find_parameter, lowest_elastic
    from .analysis.sweep import check_values, dask_executor, grid_points, lhs_points, parse_range, sweep
    from .atomic import atomic_write_text
    from .model.assembly import assemble
    from .views.progress import ProgressBar

    if args.output and not args.output.lower().endswith(".csv"):
        raise ModelError("unknown file type", field="-o", value=args.output, valid="SWEEP.csv")
    ranges = dict(parse_range(p) for p in args.params)
    if len(ranges) != len(args.params):
        raise ModelError("a parameter is given twice", field="--param", value=", ".join(args.params))
    d = _load(args, args.model)
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
    failed = sum(1 for e in res.errors if e)
    if args.json:
        doc = {
            "parameters": [{"name": n, "unit": u} for n, u in zip(res.names, res.units)],
            "points": res.values.tolist(),
            "frequencies_hz": [
                [None if np.isnan(v) else float(v) for v in row] for row in res.frequencies_hz
            ],
            "damping_ratios": [
                [None if np.isnan(v) else float(v) for v in row] for row in res.damping_ratios
            ],
            "errors": list(res.errors),
        }
        return json.dumps(doc, ensure_ascii=False)
    lines.insert(
        0,
        f"{len(res.errors)} models ({'Latin hypercube' if args.lhs else 'grid'} over "
        + ", ".join(res.names)
        + f"), {failed} refused"
        + (f" on {args.scheduler}" if args.scheduler else ""),
    )
    lines.append(f"{'mode':>4}  {'min Hz':>12}  {'max Hz':>12}")
    for k in range(res.frequencies_hz.shape[1]):
        col = res.frequencies_hz[:, k]
        if np.all(np.isnan(col)):
            continue
        lines.append(f"{k + 1:>4}  {np.nanmin(col):12.5g}  {np.nanmax(col):12.5g}")
    return "\n".join(lines)


def _sensitivity(args) -> str:
    from .analysis.sensitivity import lowest_elastic, sensitivities
    from .model.assembly import assemble

    d = _load(args, args.model)
    # --modes N: the lowest N elastic modes, refused beyond the model's (as `modes --count` is);
    # without it, up to DEFAULT_MODES
    model = assemble(d, reduce=False, damping=False)
    elastic = model.n_dof - model.rigid_basis.shape[1]
    count = args.modes if args.modes is not None else max(1, min(DEFAULT_MODES, elastic))
    sens = sensitivities(d, args.params, modes=lowest_elastic(model, count, "--modes"))
    if args.plot:
        from .views.plots import sensitivity_figure

        _write_plot(args.plot, sensitivity_figure(sens), args.force)
    if args.json:
        return json.dumps(sens.to_dict(), ensure_ascii=False)
    width = max(16, *(len(p.name) for p in sens.parameters))
    rows = [
        f"{d.name}: frequency sensitivities, % per % (p/f·∂f/∂p); Hz per unit with --json",
        "",
        f"{'parameter':<{width}} {'value':>12} {'unit':>9}  "
        + "  ".join(f"{f'mode {m}':>9}" for m in sens.modes),
        f"{'':<{width}} {'':>12} {'':>9}  " + "  ".join(f"{f'{f:.4g} Hz':>9}" for f in sens.frequencies_hz),
    ]
    for k, p in enumerate(sens.parameters):
        cells = "  ".join(f"{v:9.4f}" for v in sens.normalised[:, k])
        rows.append(f"{p.name:<{width}} {sens.values[k]:12.6g} {p.unit:>9}  {cells}")
    return "\n".join(rows)


def _units(pairs) -> dict | None:
    """``--unit COLUMN=UNIT`` options as the ``units`` of :func:`read_signals`."""
    if not pairs:
        return None
    out = {}
    for pair in pairs:
        name, sep, unit = pair.rpartition("=")
        if not sep or not name.strip() or not unit.strip():
            raise ModelError(
                "not COLUMN=UNIT", field="--unit", value=pair, valid="e.g. torque=kNm or time=ms"
            )
        out[name.strip()] = unit.strip()
    return out


def _spectrum(args) -> str:
    import numpy as np

    from .io.signalfile import read_signals
    from .signals import decay_damping, log_decrement, spectrogram, spectrum
    from .signals.checks import as_signal, bare_name, check_not_time, parse_orders

    # options first, before the file is read: an order list of positive numbers, signals that are
    # neither the time nor each other
    orders = parse_orders(args.orders, "--orders")
    check_not_time(args.column, args.time_column, "--column")
    if args.speed_column:
        check_not_time(args.speed_column, args.time_column, "--speed-column")
        if bare_name(args.speed_column) == bare_name(args.column):
            raise ModelError(
                "is the signal itself",
                field="--speed-column",
                value=args.speed_column,
                valid="a shaft-speed column other than --column",
            )
    wanted = [args.column] + ([args.speed_column] if args.speed_column else [])
    table = read_signals(args.signals, columns=wanted, units=_units(args.units), time_column=args.time_column)
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
    rate = table.rate_hz
    eigen = None
    if args.model:
        from .analysis.modal import modal_analysis

        res = modal_analysis(_load(args, args.model))
        eigen = [(int(i), float(f)) for i, f in enumerate(res.frequencies_hz) if not res.rigid[i]]
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
        spec = spectrum(x, rate, window="rect")
        method = f"free decay: {window} window on the whole record (no averaging), and log decrement"
    else:
        window = args.window or "hann"
        if window == "exponential":
            raise ModelError(
                "the exponential window is for a free decay",
                field="--window",
                valid="--decay --window exponential",
            )
        spec = spectrum(x, rate, window=window, segment=args.segment)
        method = f"stationary: {window} window" + (
            f", Welch averaging of {spec.averages} segments of {spec.segment_s:g} s"
            if spec.averages > 1
            else ""
        )
    found = spec.peaks(count=args.peaks)
    peaks = []
    for k, p in enumerate(found):
        # a peak keeps its frequency and amplitude (always numbers); a damping that cannot be read is
        # None, and damping_missing says why
        entry = {
            "frequency_hz": p.frequency_hz,
            "amplitude": p.amplitude,
            "damping_ratio": None if not np.isfinite(p.damping_ratio) else p.damping_ratio,
            "damping_missing": p.damping_missing,
            "notes": list(p.notes),
        }
        if args.decay:
            # a band around the peak, reaching half-way to its neighbours, isolates its mode
            others = sorted(q.frequency_hz for j, q in enumerate(found) if j != k)
            lo = max(
                [0.5 * p.frequency_hz] + [(p.frequency_hz + f) / 2 for f in others if f < p.frequency_hz]
            )
            hi = min(
                [1.5 * p.frequency_hz, 0.49 * rate]
                + [(p.frequency_hz + f) / 2 for f in others if f > p.frequency_hz]
            )
            try:
                dd = decay_damping(table.time, x, band=(lo, hi), window=window)
                entry |= {
                    "frequency_hz": dd.frequency_hz,
                    "damping_ratio": None if not np.isfinite(dd.damping_ratio) else dd.damping_ratio,
                    "damping_missing": dd.damping_missing,
                    "window": dd.window,
                    "notes": list(dd.notes),
                }
            except ModelError as err:  # one peak that cannot be analysed does not cost the others
                entry |= {
                    "damping_ratio": None,
                    "damping_missing": f"half-power: {err}",
                    "window": window,
                    "notes": [],
                }
            try:
                ld = log_decrement(table.time, x, band=(lo, hi))
                entry["log_decrement_damping_ratio"] = ld.damping_ratio
                entry["notes"] += list(ld.notes)
            except ModelError as err:
                entry["notes"].append(f"log decrement: {err}")
        if speed_rpm is not None:
            n = float(np.mean(speed_rpm))
            entry["order"] = entry["frequency_hz"] / (n / 60.0) if n > 0 else None
        if eigen:
            i, f = min(eigen, key=lambda e: abs(e[1] - entry["frequency_hz"]))
            # a match within two bins (or 1 % for a coarse spectrum): the peak is that mode
            if abs(f - entry["frequency_hz"]) <= max(2 * spec.resolution_hz, 0.01 * f):
                entry["mode"], entry["mode_frequency_hz"] = i, f
        peaks.append(entry)
    if args.plot:
        from .views.plots import spectrogram_figure, spectrum_figure

        marks = [f for _, f in eigen] if eigen else []
        if speed_rpm is not None or args.spectrogram:
            sg = spectrogram(x, rate, segment=args.segment or 1.0, window="hann", speed=speed_rpm)
            fig = spectrogram_figure(sg, orders=orders, eigenfrequencies=marks, title=f"{names[0]} [{unit}]")
        else:
            fig = spectrum_figure(spec, title=f"{names[0]}: {method}", unit=unit, marks=marks)
        _write_plot(args.plot, fig, args.force)
    doc = {
        "signal": names[0],
        "unit": unit,
        "source": table.source,
        "rate_hz": rate,
        "samples": int(table.time.size),
        "method": method,
        "window": window,
        "segment_s": spec.segment_s,
        "averages": spec.averages,
        "resolution_hz": spec.resolution_hz,
        "units": {"frequency": "Hz", "amplitude": f"{unit} (single-sided peak)", "damping_ratio": "fraction"},
        "peaks": peaks,
    }
    if speed_rpm is not None:
        doc["mean_speed_rpm"] = float(np.mean(speed_rpm))
    if args.json:
        return json.dumps(doc, ensure_ascii=False)
    rows = [
        f"{names[0]} [{unit}]: {table.time.size} samples at {rate:g} Hz; {method}; resolution "
        f"{spec.resolution_hz:.4g} Hz",
        "",
        f"{'frequency Hz':>12}  {'amplitude':>11}  {'damping %':>9}"
        + ("  log dec. %" if args.decay else "")
        + ("  order" if speed_rpm is not None else "")
        + ("  mode" if eigen else ""),
    ]
    notes = []
    for e in peaks:
        z = e["damping_ratio"]
        row = (
            f"{e['frequency_hz']:12.4f}  {e['amplitude']:11.4g}  {'-' if z is None else f'{100 * z:9.4f}':>9}"
        )
        if args.decay:
            ld = e.get("log_decrement_damping_ratio")
            row += f"  {'-' if ld is None else f'{100 * ld:10.4f}':>10}"
        if speed_rpm is not None:
            row += f"  {e['order']:5.2f}" if e.get("order") is not None else "      -"
        if eigen:
            row += f"  {e['mode']:4d}" if "mode" in e else "     -"
        rows.append(row)
        missing = e.get("damping_missing")
        if missing:  # the reason once, as why the damping column holds '-'
            notes.append(f"  {e['frequency_hz']:.4g} Hz: damping missing: {missing}")
        notes += [f"  {e['frequency_hz']:.4g} Hz: {n}" for n in e["notes"] if not (missing and n in missing)]
    if notes:
        rows += ["", "notes:"] + notes
    return "\n".join(rows)


def _view(args) -> str:
    from .analysis.modal import default_count, modal_analysis
    from .model.assembly import assemble
    from .views import render

    model = assemble(_load(args, args.model))
    if args.mode >= model.n_dof:
        raise ModelError("no such mode", field="--mode", value=args.mode, valid=f"0 … {model.n_dof - 1}")
    result = modal_analysis(model, min(max(args.mode + 1, default_count(model)), model.n_dof))
    out = args.output
    if out.lower().endswith(".gif"):
        path = render.mode_gif(
            result,
            args.mode,
            out,
            frames=args.frames,
            colour=args.color,
            scale=args.scale,
            overwrite=args.force,
        )
    elif out.lower().endswith(".png"):
        path = render.mode_png(
            result, args.mode, out, colour=args.color, scale=args.scale, overwrite=args.force
        )
    else:
        raise ModelError("unknown picture type", field="-o", value=out, valid="FILE.png or FILE.gif")
    f = result.frequencies_hz[args.mode]
    return f"mode {args.mode} ({f:.4g} Hz), coloured by {args.color}: {path}"


def _section_parts(args) -> list:
    """The shafts with section tables named by ``flexshaft sections SOURCE``."""
    from pathlib import Path

    from .materials import BUILTIN_MATERIALS
    from .model.components import Shaft
    from .views.progress import ProgressBar

    source = Path(args.source)
    if source.suffix.lower() == ".toml":
        if args.unit is not None:
            raise ModelError(
                "a model file gives each mesh part its own unit",
                field="--unit",
                value=args.unit,
                valid="unit = ... on the [[chain]] entry",
            )
        drivetrain = _load(args, source)
        parts = [c for c in drivetrain.components if isinstance(c, Shaft) and c.sections is not None]
        if not parts:
            raise ModelError(
                "no part is given by its geometry",
                file=str(source),
                field="chain",
                valid="a model with type = 'cad' parts or shafts given by segments",
            )
        return parts
    if args.material not in BUILTIN_MATERIALS:
        raise ModelError(
            "unknown material",
            field="--material",
            value=args.material,
            valid=", ".join(BUILTIN_MATERIALS) + " (define others in a model file)",
        )
    from .io.cad import cad_sections

    material = BUILTIN_MATERIALS[args.material]
    table = cad_sections(
        str(source),
        use_cache=not args.no_cache,
        unit=args.unit,
        nu=material.nu,
        name=source.stem,
        progress=ProgressBar(f"slicing {source.name}"),
    )
    return [Shaft.from_sections(source.stem, table, material, geometry=str(source))]


def _sections(args) -> str:
    from dataclasses import replace

    from .sections.table import tables_to_csv
    from .views.tables import sections_document, sections_table

    parts = _section_parts(args)
    if args.merge:
        parts = [replace(p, sections=replace(p.sections.merged(), meta=p.sections.meta)) for p in parts]
    if args.output and args.output.lower().endswith(".csv"):
        return tables_to_csv([p.sections for p in parts]).rstrip("\n")
    if args.json:
        return json.dumps(sections_document(parts), indent=1, ensure_ascii=False)
    return sections_table(parts)


def _emit(text: str) -> None:
    """Print to stdout; a reader that stops early (``| head``) is not an error."""
    import os

    try:
        print(text, flush=True)
    except BrokenPipeError:
        # Point stdout at devnull so the interpreter's final flush does not raise again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code.

    Without ``argv`` (the ``flexshaft`` command, ``python -m flexshaft``) the work runs under the
    watchdog of :mod:`flexshaft.watchdog`: SIGINT or SIGTERM ends it within seconds, native calls
    included. With ``argv`` (from Python) it runs in this process, stopped at the next bytecode.
    """
    import threading

    from .watchdog import Terminated, stopping, supervise

    if threading.current_thread() is not threading.main_thread():
        return _main(argv)
    if argv is None:
        code = supervise()
        if code is not None:
            return code  # the watchdog: the work has ended
    with stopping(ending=argv is None):
        try:
            return _main(argv)
        except KeyboardInterrupt:
            print("flexshaft: interrupted", file=sys.stderr)
            return 130
        except Terminated:
            print("flexshaft: terminated", file=sys.stderr)
            return 143


def _main(argv: list[str] | None) -> int:
    from .inputs import recording

    with recording():  # each command's outputs are checked against its own inputs
        return _command(argv)


def _command(argv: list[str] | None) -> int:
    try:
        args = _parser().parse_args(argv)
    except SystemExit as stop:  # usage errors (2) and --help (0), already printed
        return int(stop.code or 0)

    if args.force and not (args.output or getattr(args, "plot", None) or getattr(args, "view", None)):
        print(
            "flexshaft: error: --force: replaces a file only with -o PATH; valid: -o PATH --force, "
            "or leave --force out",
            file=sys.stderr,
        )
        return 2
    from .threads import cli_threads, thread_policy

    try:
        threads = cli_threads(args.threads)  # before numpy loads: this process and its workers
    except ModelError as err:
        print(f"flexshaft: error: {err}", file=sys.stderr)
        return 2
    with thread_policy(threads):
        return _dispatch(args)


def _body(args) -> str:
    """``flexshaft body FILE``: read an exported body with every check the reader makes; what it holds."""
    import json

    from .io.bodies import read_flexible_body

    got = read_flexible_body(args.file)
    b, meta = got.body, got.metadata
    doc = {
        "file": str(got.path),
        "format": meta.get("format"),
        "version": meta.get("version"),
        "name": b.name,
        "dofs": b.dofs,
        "boundary_x_m": [float(x) for x in b.boundary_x],
        "coordinates": int(b.K.shape[0]),
        "fixed_interface_modes": int(b.fixed_interface_hz.size - b.n_residual),
        "residual_vectors": int(b.n_residual),
        "free_hz": [float(f) for f in b.free_hz],
        "damping_ratios": [float(z) for z in b.damping_ratios],
        "material": got.material,
        "checks": "checksums match; K, M, C symmetric; M positive definite; K and C positive "
        "semidefinite with the body's rigid-body modes; free_hz those of K and M",
    }
    if args.json:
        return json.dumps(doc, indent=2)
    material = got.material["name"] if got.material else "not recorded"
    return "\n".join(
        [
            f"{got.path}: flexible body {b.name!r} ({b.dofs}), format version {meta.get('version')}",
            f"boundary nodes at x = {', '.join(f'{x:g}' for x in b.boundary_x)} m; "
            f"{doc['coordinates']} coordinates: {doc['fixed_interface_modes']} fixed-interface modes, "
            f"{b.n_residual} residual vectors; material {material}",
            "free-free modes, Hz: " + " ".join(f"{f:.2f}" for f in b.free_hz),
            "damping ratio per free-free mode, %: " + " ".join(f"{100 * z:.3f}" for z in b.damping_ratios),
            f"checks: {doc['checks']}",
        ]
    )


def _dispatch(args) -> int:
    """Run the parsed command; returns the exit code (one line on stderr for any failure)."""
    own = ("reduce", "view", "report", "statespace", "frf", "simulate", "calibrate", "sweep")
    writes_own = args.command in own
    if not writes_own and args.output and args.output.lower().endswith(".json"):
        args.json = True  # a .json file gets the JSON document, never the table
    source = {
        "modes": getattr(args, "model", None),
        "twist": getattr(args, "model", None),
        "reduce": getattr(args, "model", None),
        "view": getattr(args, "model", None),
        "report": getattr(args, "model", None),
        "statespace": getattr(args, "model", None),
        "frf": getattr(args, "model", None),
        "forced": getattr(args, "model", None),
        "simulate": getattr(args, "model", None),
        "campbell": getattr(args, "model", None),
        "spectrum": getattr(args, "signals", None),
        "sensitivity": getattr(args, "model", None),
        "calibrate": getattr(args, "model", None),
        "sweep": getattr(args, "model", None),
        "sections": getattr(args, "source", None),
    }.get(args.command) or f"<built-in {DEMO_MODEL}>"
    try:
        _check_output_paths(args)  # every output's type, and a report's folder, before any work
        if args.command == "demo" and _to_folder(args):
            # demo -o DIR/: the report of the built-in test bench (a file path gets the table, as before)
            try:
                _emit(_write_report(_demo_model(source), args.output, args.force))
            except ModelError as err:
                raise err.located(file=source) from None
            return 0
        if writes_own:
            handlers = {
                "frf": _frf,
                "calibrate": _calibrate,
                "sweep": _sweep,
                "reduce": _reduce,
                "view": _view,
                "report": _report,
                "statespace": _statespace,
                "simulate": _simulate,
            }
            try:
                _emit(handlers[args.command](args))  # they write their own files
            except ModelError as err:
                raise err.located(file=source) from None
            return 0
        if args.command == "sections":
            out = _sections(args)  # its errors name the part file themselves
        elif args.command == "body":
            out = _body(args)  # the reader's errors name the body file (or its sidecar)
        else:
            try:
                if args.command == "twist":
                    out = _twist(args)
                elif args.command == "forced":
                    out = _forced(args)
                elif args.command == "campbell":
                    out = _campbell(args)
                elif args.command == "spectrum":
                    out = _spectrum(args)
                elif args.command == "sensitivity":
                    out = _sensitivity(args)
                else:
                    if args.command == "modes":
                        drivetrain = _load(args, args.model)
                    else:
                        drivetrain = _demo_model(source)
                    out = _modes(drivetrain, args)
            except ModelError as err:
                raise err.located(file=source) from None
        if args.output:
            from .atomic import atomic_write_text

            atomic_write_text(args.output, out + "\n", overwrite=args.force)
        else:
            _emit(out)
    except ModelError as err:
        print(f"flexshaft: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("flexshaft: interrupted", file=sys.stderr)
        return 130
    except OSError as err:  # the environment (disk full, permissions), not the input
        where = f"{err.filename}: " if getattr(err, "filename", None) else ""
        print(f"flexshaft: error: {where}{err.strerror or err}", file=sys.stderr)
        return 1
    except Exception as err:  # noqa: BLE001 - a defect still gets one line, never a traceback
        detail = str(err).splitlines()[0] if str(err) else ""
        print(
            f"flexshaft: error: unexpected {type(err).__name__}{': ' + detail if detail else ''} "
            "(a flexshaft defect: please report it with the input that caused it)",
            file=sys.stderr,
        )
        return 2
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
