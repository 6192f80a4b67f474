"""The ``flexshaft`` command: a thin shell over the library.

Exit codes: 0 success, 2 bad input (one line on stderr, nothing on stdout).
"""

from __future__ import annotations

import argparse
import json
import sys
from importlib import resources

from .errors import ModelError

__all__ = ["main"]

DEMO_MODEL = "customer1.toml"


def _count(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--count = {text!r}: must be an integer >= 1") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"--count = {n}: must be an integer >= 1")
    return n


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error on one line and exits 2."""

    def error(self, message: str):  # noqa: D102 - argparse hook
        self.exit(2, f"flexshaft: error: {message} (see `{self.prog} --help`)\n")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="flexshaft", description="Torsional drivetrain models from model files.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    m = sub.add_parser("modes", help="natural frequencies, damping and mode shapes of a model file")
    m.add_argument("model", help="TOML model file")
    m.add_argument("--inertia", choices=("consistent", "lumped"),
                   help="how shaft inertia is spread (overrides the model file)")
    m.add_argument("--count", type=_count,
                   help="how many of the lowest modes (default: all for small models, 10 otherwise)")
    d = sub.add_parser("demo", help="modes of the built-in Customer 1 test bench")
    for q in (m, d):
        q.add_argument("--json", action="store_true", help="print one JSON document instead of a table")
        q.add_argument("-o", "--output", metavar="PATH",
                       help="write the table (or JSON) to PATH instead of stdout")
        q.add_argument("--force", action="store_true", help="allow -o to replace an existing file")
    return p


def _modes(drivetrain, args) -> str:
    from .modal import modal_analysis
    from .report import modes_document, modes_table

    result = modal_analysis(drivetrain, getattr(args, "count", None),
                            inertia_model=getattr(args, "inertia", None))
    if args.json:
        return json.dumps(modes_document(result), indent=1, ensure_ascii=False)
    return modes_table(result)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    try:
        args = _parser().parse_args(argv)
    except SystemExit as stop:  # usage errors (2) and --help (0), already printed
        return int(stop.code or 0)
    from .modelfile import load_model, loads_model

    source = args.model if args.command == "modes" else f"<built-in {DEMO_MODEL}>"
    try:
        if args.command == "modes":
            drivetrain = load_model(args.model)
        else:
            text = resources.files("flexshaft.data").joinpath(DEMO_MODEL).read_text(encoding="utf-8")
            drivetrain = loads_model(text, source=source)
        try:
            out = _modes(drivetrain, args)
        except ModelError as err:
            raise err.located(file=source) from None
        if args.output:
            from .fileio import atomic_write_text

            atomic_write_text(args.output, out + "\n", overwrite=args.force)
        else:
            print(out)
    except ModelError as err:
        print(f"flexshaft: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
