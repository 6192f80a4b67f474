"""``flexshaft reduce``: one part as a Craig–Bampton flexible body, written to a file."""

from __future__ import annotations

import json

from ..errors import ModelError
from .common import load

__all__ = ["reduce"]


def reduce(args) -> str:
    from ..exports.bodies import write_flexible_body
    from ..model.components import Shaft
    from ..model.reduce import reduce_part

    if not args.output:
        raise ModelError(
            "needs an output file", field="-o", valid="-o PART.npz, PART.json, PART.mat, PART.op4 or PART.pch"
        )
    drivetrain = load(args, args.model)
    comp = drivetrain.component(args.part)
    if isinstance(comp, Shaft) and args.modes is None and args.cutoff is None and comp.reduce is None:
        # the library names its arguments; the command line its options
        raise ModelError(
            "how many modes?",
            field="--modes",
            valid="--modes N or --cutoff HZ, or reduce = {modes = n} on the part in the model file",
        )
    try:
        reduction = reduce_part(
            drivetrain,
            args.part,
            modes=args.modes,
            cutoff_hz=args.cutoff,
            damping_ratio=args.damping_ratio,
            residual=not args.no_residual,
        )
    except ModelError as err:
        if err.field != "part" or err.file is not None:
            raise
        raise ModelError(err.message, field="--part", value=err.value, valid=err.valid) from None
    path = write_flexible_body(reduction.body, args.output, material=comp.material, overwrite=args.force)
    if args.json:
        return json.dumps(reduction.to_dict(path), indent=1, ensure_ascii=False)
    return reduction.table(path)
