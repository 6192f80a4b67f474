"""The command ``identify``: modes from measured runs, paired with a model's, as calibration targets."""

from __future__ import annotations

import json

from ...errors import ModelError
from ...system.atomic import atomic_write_text
from ..console import write_plot
from ..loadmodel import load
from ..options import (
    force_option,
    hz,
    json_option,
    option_pairs,
    output_option,
    plot_option,
    signal_file_options,
    signal_units,
)
from ..registry import PLOT, Command

__all__ = ["COMMANDS", "identify"]


def identify(args) -> str:
    from ...analysis.identification import identify as identify_runs
    from ...study.measured import read_parameters, tune_to_measured

    stations = option_pairs(args.stations, "--station", "CHANNEL=STATION", "'speed 1=motor'")
    for flag, given in (("-o", args.output), ("--parameters", args.parameters), ("--tuned", args.tuned)):
        if given and not args.model:
            raise ModelError(
                "a targets file numbers modes as the model does",
                field=flag,
                value=given,
                valid=f"{flag} with --model",
            )
    if args.tuned and not args.parameters:
        raise ModelError(
            "a tuned model needs parameters to tune",
            field="--tuned",
            value=args.tuned,
            valid="--tuned with --parameters",
        )
    if args.tuned and not args.tuned.lower().endswith(".toml"):
        raise ModelError("unknown file type", field="--tuned", value=args.tuned, valid="TUNED.toml")
    if stations and not args.model:
        raise ModelError(
            "pairs channels with a model's stations", field="--station", valid="--station with --model"
        )
    parameters = read_parameters(args.parameters) if args.parameters else []  # checked before any work
    drivetrain = load(args, args.model) if args.model else None
    out = identify_runs(
        list(args.runs),
        list(args.channels),
        model=drivetrain,
        stations=stations,
        max_hz=args.max_hz,
        min_hz=args.min_hz,
        units=signal_units(args.units),
        time_column=args.time_column,
        group=args.group,
        rate=args.rate,
    )
    if args.plot:
        write_plot(args.plot, out.plot(), args.force)
    if not args.model:
        return out.to_json() if args.json else out.table(verbose=args.verbose)
    # the one way from runs to a tuned model, as a study's [[measurement]] takes it
    tuning = tune_to_measured(
        out, parameters, model=args.model, load=lambda _: drivetrain, source=args.output or "<targets>"
    )
    written = []
    if args.output:
        atomic_write_text(args.output, tuning.targets_text, overwrite=args.force)
        written.append(f"targets written to {args.output}")
    if args.tuned:
        tuning.write_tuned(args.tuned, overwrite=args.force)
        written.append(f"tuned model: {args.tuned}")
    if args.json:
        doc = tuning.to_dict()
        if args.tuned:
            doc["tuned_model"] = args.tuned
        return json.dumps(doc, ensure_ascii=False)
    return tuning.table(verbose=args.verbose) + "".join(f"\n\n{w}" for w in written)


def _identify_options(p) -> None:
    p.add_argument(
        "runs", nargs="+", help="one or more runs: .csv .tdms .mf4 .mdf .dat .h5 .hdf5 .mat .uff .unv"
    )
    p.add_argument(
        "--channel",
        dest="channels",
        action="append",
        required=True,
        metavar="NAME",
        help="a channel to use (repeatable; every run must have them)",
    )
    signal_file_options(p, "", rate=True)
    p.add_argument(
        "--max-hz",
        type=hz("--max-hz", positive=True),
        metavar="HZ",
        # analysis.identification's MODEL_MARGIN, NYQUIST_WITH_MODEL / 2, NYQUIST_ALONE / 2 (held equal by
        # tests/flexshaft/test_cli_help.py): the parser is built without numpy
        help="the highest frequency of interest (default: 1.5 x the model's highest elastic mode, at most "
        "0.4 x rate; else 0.2 x rate)",
    )
    p.add_argument(
        "--min-hz",
        type=hz("--min-hz", positive=True),
        metavar="HZ",
        help="the lowest frequency of interest (default: half the model's first elastic mode, else "
        "max-hz/50; never below 20 periods of the shortest run; the output's first line says which)",
    )
    p.add_argument(
        "--model", help="a model file: each mode is paired with the model's and numbered as `modes`"
    )
    p.add_argument(
        "--station",
        dest="stations",
        action="append",
        metavar="CHANNEL=STATION",
        help="a speed or angle channel measures this station's rotation: pairing by MAC too (repeatable)",
    )
    p.add_argument(
        "--verbose", action="store_true", help="print the method in full (preprocessing, SSI, clustering)"
    )
    plot_option(p, "the first run's stabilisation diagram")
    json_option(p)
    output_option(p, "TARGETS.toml", "write the targets file calibrate reads (needs --model)")
    p.add_argument(
        "--parameters",
        metavar="P.toml",
        help="[[parameter]] tables (as in a targets file): calibrate the model to the trusted targets",
    )
    p.add_argument("--tuned", metavar="TUNED.toml", help="write the tuned model file (needs --parameters)")
    force_option(p)


COMMANDS = (
    Command(
        "identify",
        "natural frequencies, damping and shapes from measured runs (SSI-COV), targets for calibrate",
        _identify_options,
        identify,
        files={
            "-o": {".toml": "the targets file for calibrate"},
            "--tuned": {".toml": "the tuned model file"},
            "--plot": PLOT,
        },
        source="runs",
    ),
)
