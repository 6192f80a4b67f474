"""The command ``identify``: modes from measured runs, paired with a model's, as calibration targets."""

from __future__ import annotations

import json

from ..errors import ModelError
from .common import load, option_pairs, signal_units, write_plot

__all__ = ["identify", "identify_table"]


def identify(args) -> str:
    from ..io.signalfile import read_signals
    from ..signals.identify import identify_modes

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
    units = signal_units(args.units)
    runs = [
        read_signals(
            path,
            columns=list(args.channels),
            units=units,
            time_column=args.time_column,
            group=args.group,
            rate=args.rate,
        )
        for path in args.runs
    ]
    result = None
    if args.model:
        from ..analysis.modal import modal_analysis

        result = modal_analysis(load(args, args.model))
    max_hz = args.max_hz
    if max_hz is None:
        nyquist = min(r.rate_hz for r in runs) / 2
        elastic = [f for f, rigid in zip(result.frequencies_hz, result.rigid) if not rigid] if result else []
        # the model's modes and half as much again (a model before calibration may be that far off),
        # within 80 % of the Nyquist frequency; without a model, 40 % of the Nyquist frequency
        max_hz = min(1.5 * max(elastic), 0.8 * nyquist) if elastic else 0.4 * nyquist
    found = identify_modes(runs, channels=list(args.channels), max_hz=max_hz, min_hz=args.min_hz)
    pairing = None
    if result is not None:
        from ..analysis.pairing import pair_modes

        pairing = pair_modes(found, result, stations)
    if args.plot:
        from ..views.stabilisation import stabilisation_figure

        write_plot(args.plot, stabilisation_figure(found), args.force)
    if args.output:
        from ..analysis.pairing import targets_toml
        from ..atomic import atomic_write_text

        atomic_write_text(args.output, targets_toml(pairing, found) + "\n", overwrite=args.force)
    if args.json:
        doc = found.to_dict(diagrams=False)
        if pairing is not None:
            doc["pairing"] = pairing.to_dict()
        return json.dumps(doc, ensure_ascii=False)
    return identify_table(found, pairing) + (f"\n\ntargets written to {args.output}" if args.output else "")


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
        row = (
            f"{m.frequency_hz:12.4f}  {f_std:8.4f}  {100 * m.damping_ratio:9.4f}  {100 * z_std:6.3f}"
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
    rows.append("± : one standard deviation across runs (one run: across its segments)")
    if notes:
        rows += ["", "notes:"] + [f"  {n}" for n in notes]
    return "\n".join(rows)
