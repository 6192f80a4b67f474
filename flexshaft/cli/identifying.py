"""The command ``identify``: modes from measured runs, paired with a model's, as calibration targets."""

from __future__ import annotations

from ..errors import ModelError
from .common import load, option_pairs, signal_units, write_plot

__all__ = ["identify"]


def identify(args) -> str:
    from ..analysis.identification import identify as identify_runs

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
        write_plot(args.plot, out.plot(), args.force)
    if args.output:
        out.write_targets(args.output, overwrite=args.force)
    if args.json:
        return out.to_json()
    return out.table() + (f"\n\ntargets written to {args.output}" if args.output else "")
