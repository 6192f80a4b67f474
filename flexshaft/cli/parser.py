"""The ``flexshaft`` command line's parser: its commands, options and their types.

The option types check a value where argparse reads it, so a wrong one is a usage error naming the
option (exit 2, one line) before any work starts.
"""

from __future__ import annotations

import argparse

from ..errors import ModelError
from .common import DEFAULT_MODES, MESH_CHECK_AUTO_DOFS, PLOTS

__all__ = ["build_parser", "Parser", "whole", "hz", "rpm"]


def whole(name: str, lo: int, ceiling: str | None = None):
    """An argparse type: a whole number >= ``lo`` (and within the ceiling of that name in
    :data:`flexshaft.system.limits.CEILINGS`), the error naming the option."""

    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} = {text!r}: must be an integer >= {lo}") from None
        if n < lo:
            raise argparse.ArgumentTypeError(f"{name} = {n}: must be an integer >= {lo}")
        if ceiling is not None:
            from ..system.limits import check_ceiling

            try:
                check_ceiling(ceiling, n, field=name)
            except ModelError as err:
                raise argparse.ArgumentTypeError(str(err)) from None
        return n

    return parse


def hz(name: str, *, positive: bool = False):
    """An argparse type: a finite frequency in Hz, from 0 (above 0 when ``positive``) up to
    :data:`~flexshaft.validation.MAX_FREQUENCY_HZ`, the error naming the option."""

    def parse(text: str) -> float:
        from ..validation import MAX_FREQUENCY_HZ, check_frequency

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


def rpm(name: str):
    """An argparse type: a finite shaft speed in rpm, at most
    :data:`~flexshaft.validation.MAX_SPEED_RPM` either way, the error naming the option."""

    def parse(text: str) -> float:
        from ..validation import MAX_SPEED_RPM, check_real

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


def json_output_options(parser) -> None:
    """``--json``, ``-o PATH`` and ``--force``, as a command that prints a table or JSON takes them."""
    parser.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
    parser.add_argument(
        "-o", dest="output", metavar="PATH", help="write to this file: PATH.txt the table, PATH.json JSON"
    )
    parser.add_argument("--force", action="store_true", help="allow replacing an existing file")


def signal_file_options(parser, prefix: str, *, rate: bool) -> None:
    """How a signal file is read (:func:`flexshaft.read_signals`): ``--time-column``, ``--group``,
    ``--unit COLUMN=UNIT`` (repeatable) and, where the command has no ``--rate`` of its own, the
    sampling rate of a measured file without time."""
    parser.add_argument(
        "--time-column",
        help=prefix + "the time column (CSV: time; a measured file: the channel's own timing)",
    )
    parser.add_argument(
        "--group", help=prefix + "a measured file's group of the channels (or name them GROUP/NAME)"
    )
    if rate:
        parser.add_argument(
            "--rate",
            type=hz("--rate", positive=True),
            metavar="HZ",
            help="the sampling rate of a measured file that has no time (a MAT file without a time variable)",
        )
    parser.add_argument(
        "--unit",
        dest="units",
        action="append",
        metavar="COLUMN=UNIT",
        help=prefix + "the unit of a column whose header has none, e.g. torque=kNm or time=ms (repeatable)",
    )


class Parser(argparse.ArgumentParser):
    """argparse that reports a usage error on one line and exits 2."""

    def error(self, message: str):  # noqa: D102 - argparse hook
        from ..errors import shown  # an option's value as typed: no control character reaches the terminal

        self.exit(2, f"flexshaft: error: {shown(message)} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    from ..version import __version__

    p = Parser(
        prog="flexshaft",
        description="Drivetrain dynamics from model files: modes, twist test, sections, flexible bodies, "
        "state space, simulation, signals, calibration.",
    )
    p.add_argument("--version", action="version", version=f"flexshaft {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

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
        type=whole("--count", 1),
        help="how many of the lowest modes (default: all for small models, 10 otherwise)",
    )
    m.add_argument(
        "--max-hz", type=hz("--max-hz", positive=True), metavar="F", help="list only the modes up to F Hz"
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
    s.add_argument(
        "--compare-solid",
        action="store_true",
        help="each part's 1D model against its solid mesh: stiffness, free-free modes, the extra length "
        "each diameter step implies (the solid extra); -o FILE.csv writes the tables corrected to the "
        "solids' torsional stiffness",
    )
    s.add_argument(
        "--solid-modes",
        type=whole("--solid-modes", 0),
        default=4,
        help="free-free modes compared with --compare-solid (default 4; 0: stiffness only)",
    )
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
        type=whole("--modes", 0),
        help="fixed-interface modes to keep (default: the part's reduce)",
    )
    g.add_argument(
        "--cutoff",
        type=hz("--cutoff", positive=True),
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
            type=hz("--max-hz", positive=True),
            metavar="F",
            help="keep only the modes up to F Hz",
        )
        q.add_argument(
            "--speed",
            type=rpm("--speed"),
            default=0.0,
            metavar="RPM",
            help="the line spinning at RPM: a 6-DOF model's gyroscopic terms join the damping (0)",
        )
    ssp.add_argument(
        "-o", dest="output", metavar="FILE", required=True, help="FILE.npz, FILE.mat or FILE.json"
    )
    fr.add_argument("--from", dest="f_from", type=hz("--from"), default=0.1, help="first frequency, Hz (0.1)")
    fr.add_argument(
        "--to",
        dest="f_to",
        type=hz("--to", positive=True),
        help="last frequency, Hz (default: 1.5 × the highest mode kept, at most 1e9)",
    )
    fr.add_argument(
        "--points",
        type=whole("--points", 2, "frf_points"),
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
    st = sub.add_parser(
        "study",
        help="the whole study in one command: set-ups, modes, responses, runs, calibration, exports, "
        "one HTML report (re-runs redo only what changed)",
    )
    st.add_argument("study", help="TOML study file (its [[setup]] tables name the model files)")
    st.add_argument(
        "-o",
        "--output",
        metavar="DIR",
        required=True,
        help="the study's folder: index.html, results.json, exports/, *-tuned.toml (new, empty, or this "
        "study's earlier run, which is updated)",
    )
    st.set_defaults(force=False, json=False)  # a study's folder is updated in place: there is no --force
    v = sub.add_parser(
        "view",
        help="one mode in 3D on the drivetrain's surface: a PNG, an animated GIF, or an HTML page to turn "
        "in a browser",
    )
    v.add_argument("model", help="TOML model file")
    v.add_argument(
        "--mode", type=whole("--mode", 0), required=True, help="the mode, as `flexshaft modes` numbers it"
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
        "--frames", type=whole("--frames", 2, "frames"), default=30, help="GIF frames per period (30)"
    )
    v.add_argument(
        "-o", "--output", metavar="FILE", required=True, help="FILE.png, FILE.gif or FILE.html (interactive)"
    )
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
    si.add_argument(
        "--series",
        metavar="FILE",
        help="csv scenario: the file with the torque history (CSV, or measured: "
        ".tdms .mf4 .mdf .dat .h5 .hdf5 .mat)",
    )
    si.add_argument("--column", help="csv scenario: the torque column (header, with or without its unit)")
    signal_file_options(si, "csv scenario: ", rate=False)  # its --rate is the simulation's
    si.add_argument(
        "--max-hz", type=hz("--max-hz", positive=True), metavar="F", help="keep only the modes up to F Hz"
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
        "spectrum", help="amplitude spectrum, peaks and damping of a signal (simulated or measured)"
    )
    sp.add_argument(
        "signals",
        help="CSV: a 'time [s]' column, then 'NAME [unit]' columns; or a measured file: "
        ".tdms .mf4 .mdf .dat .h5 .hdf5 .mat",
    )
    sp.add_argument("--column", required=True, help="the signal (its header, with or without the unit)")
    signal_file_options(sp, "", rate=True)
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
        "--peaks", type=whole("--peaks", 1, "peaks"), default=8, help="how many peaks to list (8)"
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
    ident = sub.add_parser(
        "identify",
        help="natural frequencies, damping and shapes from measured runs (SSI-COV), targets for calibrate",
    )
    ident.add_argument("runs", nargs="+", help="one or more runs: .csv .tdms .mf4 .mdf .dat .h5 .hdf5 .mat")
    ident.add_argument(
        "--channel",
        dest="channels",
        action="append",
        required=True,
        metavar="NAME",
        help="a channel to use (repeatable; every run must have them)",
    )
    signal_file_options(ident, "", rate=True)
    ident.add_argument(
        "--max-hz",
        type=hz("--max-hz", positive=True),
        metavar="HZ",
        help="the highest frequency of interest (default: 1.5 x the model's highest mode, else 0.2 x rate)",
    )
    ident.add_argument(
        "--min-hz", type=hz("--min-hz", positive=True), metavar="HZ", help="the lowest (max-hz/50)"
    )
    ident.add_argument(
        "--model", help="a model file: each mode is paired with the model's and numbered as `modes`"
    )
    ident.add_argument(
        "--station",
        dest="stations",
        action="append",
        metavar="CHANNEL=STATION",
        help="a speed or angle channel measures this station's rotation: pairing by MAC too (repeatable)",
    )
    ident.add_argument("--plot", metavar="FILE", help=f"the first run's stabilisation diagram ({PLOTS})")
    ident.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
    ident.add_argument(
        "-o",
        dest="output",
        metavar="TARGETS.toml",
        help="write the targets file calibrate reads (needs --model)",
    )
    ident.add_argument("--force", action="store_true", help="allow replacing an existing file")
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
        type=whole("--modes", 1),
        help=f"the lowest N elastic modes (default: {DEFAULT_MODES}, or all the model has if fewer)",
    )
    se.add_argument("--plot", metavar="FILE", help=f"the normalised sensitivities as a heat map ({PLOTS})")
    cb = sub.add_parser(
        "calibrate", help="tune parameters to target frequencies and damping ratios (bounded least squares)"
    )
    cb.add_argument("model", help="TOML model file (the stages of a targets file may name others)")
    cb.add_argument("--targets", required=True, metavar="T.toml", help="targets and parameters (TOML)")
    cb.add_argument(
        "--starts", type=whole("--starts", 1, "starts"), help="starting points (overrides the file's)"
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
        type=whole("--lhs", 1, "sweep_points"),
        metavar="N",
        help="N Latin-hypercube points in LO:HI instead",
    )
    sw.add_argument("--seed", type=whole("--seed", 0), default=0, help="seed of the hypercube (0)")
    sw.add_argument(
        "--modes",
        type=whole("--modes", 1),
        help=f"elastic modes per point (default: {DEFAULT_MODES}, or all the model has if fewer)",
    )
    sw.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (tcp://host:8786)")
    sw.add_argument("--json", action="store_true", help="print one JSON document instead of a summary")
    sw.add_argument("-o", dest="output", metavar="SWEEP.csv", help="write every point as CSV")
    sw.add_argument("--force", action="store_true", help="allow replacing an existing file")
    for q in (fo, ca, sp, se):
        json_output_options(q)
    for q in (m, s, t, r, v, rp, ssp, fr, fo, si, ca, sp, se, cb, sw, st, ident):
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
            type=whole("--threads", 1),
            metavar="N",
            help="BLAS/OpenMP threads (default: FLEXSHAFT_THREADS, else your OPENBLAS_NUM_THREADS/"
            "OMP_NUM_THREADS if set, else 1 - steady on a busy machine)",
        )
    return p
