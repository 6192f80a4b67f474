"""The command ``identify``: modes from measured runs, paired with a model's, as calibration targets."""

from __future__ import annotations

from ...errors import ModelError
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

__all__ = ["COMMANDS", "identify", "identify_table"]


def identify(args) -> str:
    from ...analysis.identification import identify as identify_runs

    stations = option_pairs(args.stations, "--station", "CHANNEL=STATION", "'speed 1=motor'")
    if args.output and not args.model:
        raise ModelError(
            "a targets file numbers modes as the model does",
            field="-o",
            value=args.output,
            valid="-o with --model",
        )
    if stations and not args.model:
        raise ModelError(
            "pairs channels with a model's stations", field="--station", valid="--station with --model"
        )
    out = identify_runs(
        list(args.runs),
        list(args.channels),
        model=load(args, args.model) if args.model else None,
        stations=stations,
        max_hz=args.max_hz,
        min_hz=args.min_hz,
        units=signal_units(args.units),
        time_column=args.time_column,
        group=args.group,
        rate=args.rate,
    )
    if args.plot:
        from ...views.stabilisation import stabilisation_figure

        write_plot(args.plot, stabilisation_figure(out.identification), args.force)
    if args.output:
        out.write_targets(args.output, overwrite=args.force)
    if args.json:
        return out.to_json()
    return identify_table(out.identification, out.pairing) + (
        f"\n\ntargets written to {args.output}" if args.output else ""
    )


def identify_table(found, pairing=None) -> str:
    """The identified modes as text: frequency, damping, their spread, and the model mode paired."""
    rows = [found.method, ""]
    head = f"{'frequency Hz':>12}  {'± Hz':>8}  {'damping %':>9}  {'± %':>6}  {'runs':>4}  {'MPC':>5}"
    if pairing is not None:
        head += f"  {'mode':>4}  {'model Hz':>9}  {'MAC':>5}"
    rows.append(head)
    pairs = pairing.pairs if pairing is not None else [None] * len(found.modes)
    notes = list(found.notes)
    for m, p in zip(found.modes, pairs):
        f_std = m.frequency_std_hz if m.frequency_std_hz == m.frequency_std_hz else m.segment_frequency_std_hz
        z_std = m.damping_std if m.damping_std == m.damping_std else m.segment_damping_std
        # no spread from one estimate (one run of one segment): "-", as --json says null
        f_spread = f"{f_std:8.4f}" if f_std == f_std else f"{'-':>8}"
        z_spread = f"{100 * z_std:6.3f}" if z_std == z_std else f"{'-':>6}"
        row = (
            f"{m.frequency_hz:12.4f}  {f_spread}  {100 * m.damping_ratio:9.4f}  {z_spread}"
            f"  {m.found_in_runs:4d}  {m.mpc:5.3f}"
        )
        if p is not None:
            if p.mode is None:
                row += f"  {'-':>4}  {'-':>9}  {'-':>5}"
                notes.append(f"{m.frequency_hz:.4g} Hz unpaired: {p.reason}")
            else:
                mac = f"{p.mac:5.3f}" if p.mac == p.mac else "    -"
                row += f"  {p.mode:4d}  {p.model_frequency_hz:9.4f}  {mac}"
        rows.append(row)
    rows.append("")
    rows.append("± : one standard deviation across runs (one run: across its segments; - : one estimate)")
    if notes:
        rows += ["", "notes:"] + [f"  {n}" for n in notes]
    return "\n".join(rows)


def _identify_options(p) -> None:
    p.add_argument("runs", nargs="+", help="one or more runs: .csv .tdms .mf4 .mdf .dat .h5 .hdf5 .mat")
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
        help="the highest frequency of interest (default: 1.5 x the model's highest mode, else 0.2 x rate)",
    )
    p.add_argument(
        "--min-hz", type=hz("--min-hz", positive=True), metavar="HZ", help="the lowest (max-hz/50)"
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
    plot_option(p, "the first run's stabilisation diagram")
    json_option(p)
    output_option(p, "TARGETS.toml", "write the targets file calibrate reads (needs --model)")
    force_option(p)


COMMANDS = (
    Command(
        "identify",
        "natural frequencies, damping and shapes from measured runs (SSI-COV), targets for calibrate",
        _identify_options,
        identify,
        files={"-o": {".toml": "the targets file for calibrate"}, "--plot": PLOT},
        source="runs",
    ),
)
