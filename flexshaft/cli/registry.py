"""The commands of ``flexshaft``: each declares its options and its run function in one place.

Every module of :mod:`flexshaft.cli.commands` holds a tuple ``COMMANDS`` of :class:`Command`; the
parser is built from them (adding a command touches the one module it lives in). ``--threads``
belongs to every command, ``--no-cache`` and ``--allow-code`` to every command that reads a model.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cache

from .options import Parser, model_options, whole

__all__ = ["Command", "Written", "commands", "command", "build_parser", "TABLE", "PLOT"]

#: The files a command that prints a table writes with ``-o``, and ``--plot``'s (the suffix picks).
TABLE = {".txt": "the table", ".json": "the JSON document"}
PLOT = {".png": "PNG", ".svg": "SVG", ".pdf": "PDF"}  # matplotlib's Agg, SVG and PDF backends
UFF = {".uff": "a universal file", ".unv": "a universal file"}  # pyuff (the uff extra)


class Written(str):
    """What a table command returns when it wrote its own output (``demo -o DIR/``): a line to print."""


@dataclass(frozen=True)
class Command:
    """One ``flexshaft`` command.

    Attributes
    ----------
    name, help : str
        The command's name and its line in ``flexshaft --help``.
    options : callable
        ``options(parser)`` adds the command's own arguments.
    run : callable
        ``run(args)`` does the work: the text to print (a table command: or to write to ``-o``), or
        (``whole``) the exit status.
    files : mapping
        By option (``-o``, ``--plot``, ``--view``): the suffixes it accepts (lower case) and what
        each gives; checked before any work.
    source : str or None
        The argument naming the file its errors are located in (its first, if repeatable); None:
        the built-in test bench.
    locate : bool
        Whether a ModelError is located in ``source`` (False: its readers name their own files).
    table : bool
        What ``run`` returns goes to ``-o PATH`` if given (a ``.json`` path: the JSON document),
        else to stdout; otherwise the command writes its own files and its text is printed.
    reads_model : bool
        It takes ``--no-cache`` and ``--allow-code``.
    whole : bool
        It checks its outputs, writes and says its exit status itself (``study``).
    """

    name: str
    help: str
    options: Callable
    run: Callable
    files: Mapping = field(default_factory=dict)
    source: str | None = "model"
    locate: bool = True
    table: bool = False
    reads_model: bool = True
    whole: bool = False

    def source_of(self, args) -> str | None:
        """The file this run's errors are located in (None: the built-in test bench)."""
        value = getattr(args, self.source, None) if self.source else None
        return (value or [None])[0] if isinstance(value, list) else value


@cache
def commands() -> tuple[Command, ...]:
    """Every command, by name."""
    import importlib
    import pkgutil

    from . import commands as package

    found = []
    for info in pkgutil.iter_modules(package.__path__):
        found += importlib.import_module(f"{package.__name__}.{info.name}").COMMANDS
    return tuple(sorted(found, key=lambda c: c.name))


def command(name: str) -> Command:
    """The command of this name."""
    return next(c for c in commands() if c.name == name)


def build_parser() -> argparse.ArgumentParser:
    """The ``flexshaft`` parser: each command's options, then the ones they share."""
    from ..version import __version__

    p = Parser(
        prog="flexshaft",
        description="Drivetrain dynamics from model files: modes, twist test, sections, flexible bodies, "
        "state space, simulation, signals, calibration.",
    )
    p.add_argument("--version", action="version", version=f"flexshaft {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for c in commands():
        q = sub.add_parser(c.name, help=c.help)
        c.options(q)
        if c.reads_model:
            model_options(q)
        q.add_argument(
            "--threads",
            type=whole("--threads", 1),
            metavar="N",
            help="BLAS/OpenMP threads (default: FLEXSHAFT_THREADS, else your OPENBLAS_NUM_THREADS/"
            "OMP_NUM_THREADS if set, else 1 - steady on a busy machine)",
        )
    return p
