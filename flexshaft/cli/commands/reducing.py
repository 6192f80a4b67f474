"""``flexshaft reduce``: one part as a Craig–Bampton flexible body, written to a file."""

from __future__ import annotations

import json

from ...errors import ModelError
from ..loadmodel import load
from ..options import force_option, hz, json_option, output_option, renamed, whole
from ..registry import Command

__all__ = ["COMMANDS", "reduce"]


def reduce(args) -> str:
    from ...exports.bodies import write_flexible_body
    from ...model.components import Shaft
    from ...model.reduce import reduce_part

    if not args.output:
        raise ModelError(
            "needs an output file",
            field="-o",
            valid="-o PART.npz, PART.json, PART.mat, PART.op4, PART.pch or PART.uff",
        )
    drivetrain = load(args, args.model)
    comp = drivetrain.component(args.part)
    if isinstance(comp, Shaft) and args.modes is None and args.max_hz is None and comp.reduce is None:
        # the library names its arguments; the command line its options
        raise ModelError(
            "how many modes?",
            field="--modes",
            valid="--modes N or --max-hz HZ, or reduce = {modes = n} on the part in the model file",
        )
    try:
        reduction = reduce_part(
            drivetrain,
            args.part,
            modes=args.modes,
            cutoff_hz=args.max_hz,
            damping_ratio=args.damping_ratio,
            residual=not args.no_residual,
        )
    except ModelError as err:
        if err.field != "part" or err.file is not None:
            raise
        raise ModelError(err.message, field="--part", value=err.value, valid=err.valid) from None
    if args.output.lower().endswith((".uff", ".unv")):
        from ...exports.universalfile import write_body_uff

        try:
            path = write_body_uff(reduction, args.output, overwrite=args.force)
        except ModelError as err:
            if err.field != "path":
                raise
            raise err.replaced(field="-o") from None
    else:
        path = write_flexible_body(reduction.body, args.output, material=comp.material, overwrite=args.force)
    if args.json:
        return json.dumps(reduction.to_dict(path), indent=1, ensure_ascii=False)
    return reduction.table(path)


def _reduce_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument("--part", required=True, help="the part (a cad part or a shaft given by segments)")
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--modes",
        type=whole("--modes", 0),
        metavar="N",
        help="fixed-interface modes to keep (default: the part's reduce)",
    )
    g.add_argument(
        "--max-hz",
        type=hz("--max-hz", positive=True),
        metavar="HZ",
        help="keep every fixed-interface mode below HZ",
    )
    renamed(p, "--cutoff", "--max-hz", "max_hz", type=hz("--cutoff", positive=True), group=g)
    p.add_argument(
        "--damping-ratio",
        type=float,
        help="ratio on every elastic mode (default: the part's damping in the model file, else 0.0053)",
    )
    p.add_argument(
        "--no-residual",
        action="store_true",
        help="textbook Craig–Bampton: no residual vectors after the modes",
    )
    json_option(p)
    output_option(
        p,
        "PART.npz",
        "the flexible-body file: PART.npz, .json, .mat, .op4 or .pch; or PART.uff/.unv, its free-free "
        "modes for the test lab",
    )
    force_option(p, "allow -o to replace an existing file")


COMMANDS = (
    Command(
        "reduce",
        "Craig–Bampton flexible body of one part, written to .npz/.json/.mat/.op4/.pch",
        _reduce_options,
        reduce,
        files={
            "-o": {s: "the flexible body" for s in (".npz", ".json", ".mat", ".op4", ".pch")}
            | {s: "the body's free-free modes as a universal file (2411, 55)" for s in (".uff", ".unv")}
        },
    ),
)
