"""The linear-system commands: ``statespace`` (A, B, C, D to a file), ``frf`` (frequency response)
and ``forced`` (steady torque amplitudes under a sinusoidal torque)."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import ModelError
from .common import load, write_plot

__all__ = ["statespace", "frf", "forced"]


def _system(args):
    """The modes and the state space between the command's inputs and outputs."""
    from ..analysis.statespace import response_system

    return response_system(
        load(args, args.model), args.inputs, args.outputs, max_hz=args.max_hz, speed_rpm=args.speed
    )


def statespace(args) -> str:
    from ..exports.statespacefile import write_state_space

    _, ss = _system(args)
    try:
        path = write_state_space(ss, args.output, overwrite=args.force)
    except ModelError as err:
        if err.field != "path":
            raise
        raise ModelError(err.message, field="-o", value=err.value, valid=err.valid) from None
    return (
        f"state space: {ss.A.shape[0]} states ({len(ss.modes)} modes), {len(ss.inputs)} inputs, "
        f"{len(ss.outputs)} outputs: {path}"
    )


def frf(args) -> str:
    from ..analysis.statespace import default_frf_range, frequency_grid, frequency_response
    from ..exports.statespacefile import frf_npz

    if len(args.inputs) != 1:
        raise ModelError(
            "frf takes one input (its outputs are repeatable)",
            field="--input",
            value=", ".join(args.inputs),
            valid="one station; run frf once per input, or use statespace for several",
        )
    _, ss = _system(args)
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
    if args.plot:
        from ..views.plots import bode_figure

        write_plot(args.plot, bode_figure(resp), args.force)
    kind = Path(args.output).suffix.lower() if args.output else None
    if kind == ".npz":
        return _written(resp, args, frf_npz(resp, doc))
    if kind == ".csv":
        text = resp.csv()
    elif args.json or kind == ".json":
        text = json.dumps(doc, ensure_ascii=False)
    else:
        text = resp.table(doc["peaks"])
    return _written(resp, args, (text + "\n").encode("utf-8")) if args.output else text


def _written(resp, args, data: bytes) -> str:
    """Write frf's -o file (its type checked before the work) and say what went where."""
    from ..system.atomic import atomic_write_bytes

    path = atomic_write_bytes(args.output, data, overwrite=args.force)
    return (
        f"frequency response {resp.inputs[0]} -> {', '.join(resp.outputs)}, "
        f"{resp.frequencies_hz.size} frequencies: {path}"
    )


def forced(args) -> str:
    from ..analysis.forced import forced_response
    from ..analysis.modal import response_modes
    from ..model.assembly import assemble

    result = response_modes(assemble(load(args, args.model)))
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
    return fr.table()
