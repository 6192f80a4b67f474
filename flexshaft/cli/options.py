"""The ``flexshaft`` command line's words: option types, the options several commands share, and the
old spellings kept for one release.

The option types check a value where argparse reads it, so a wrong one is a usage error naming the
option (exit 2, one line) before any work starts. One word means one thing in every command
(``-o/--output`` the output file, ``--measure`` the system outputs, ``--modes`` a mode count,
``--max-hz`` an upper frequency, ``--at`` the station a torque acts at, ``--torque`` a torque);
:func:`renamed` keeps an old spelling working, hidden from ``--help``, with a note on stderr.
"""

from __future__ import annotations

import argparse
import sys

from ..errors import ModelError

__all__ = [
    "Parser",
    "whole",
    "hz",
    "rpm",
    "renamed",
    "note",
    "json_option",
    "output_option",
    "force_option",
    "plot_option",
    "model_options",
    "signal_file_options",
    "option_pairs",
    "signal_units",
    "PLOTS",
    "DEFAULT_MODES",
]

PLOTS = ".png, .svg or .pdf"  # what --plot writes (the suffix picks)
DEFAULT_MODES = 6  # sensitivity and sweep: the lowest elastic modes reported without --modes


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


class Parser(argparse.ArgumentParser):
    """argparse that reports a usage error on one line and exits 2.

    An option whose old spelling is still read (:func:`renamed`) cannot be ``required`` to argparse,
    which would refuse the old spelling alone; :meth:`require` checks it after parsing instead, with
    argparse's words.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._needed: list[tuple[str, tuple[str, ...]]] = []

    def require(self, label: str, *dests: str) -> None:
        """``label`` (the option's new spelling) is required: one of ``dests`` must be given."""
        self._needed.append((label, dests))

    def parse_known_args(self, args=None, namespace=None):  # noqa: D102 - argparse hook
        namespace, rest = super().parse_known_args(args, namespace)
        missing = [
            label for label, dests in self._needed if all(getattr(namespace, d, None) is None for d in dests)
        ]
        if missing:
            self.error(f"the following arguments are required: {', '.join(missing)}")
        return namespace, rest

    def error(self, message: str):  # noqa: D102 - argparse hook
        from ..errors import shown  # an option's value as typed: no control character reaches the terminal

        self.exit(2, f"flexshaft: error: {shown(message)} (see `{self.prog} --help`)\n")


def note(text: str) -> None:
    """One line on stderr, ``flexshaft: note: TEXT`` (a deprecated spelling, said where it is read)."""
    try:
        print(f"flexshaft: note: {text}", file=sys.stderr, flush=True)
    except OSError:  # stderr gone: the command goes on
        pass


class _Renamed(argparse.Action):
    """An old spelling: stores (or appends) as its new spelling does, and says it is deprecated."""

    def __init__(self, option_strings, dest, *, new: str, append: bool = False, **kwargs):
        super().__init__(option_strings, dest, **kwargs)
        self.new, self.append = new, append

    def __call__(self, parser, namespace, values, option_string=None):
        note(f"{option_string} is deprecated; use {self.new}")
        if self.append:
            values = [*(getattr(namespace, self.dest, None) or []), values]
        setattr(namespace, self.dest, values)


def renamed(parser, old: str, new: str, dest: str, *, append: bool = False, type=None, group=None) -> None:
    """Keep ``old`` working as ``new`` for one release: same ``dest`` and ``type``, hidden from --help,
    ``flexshaft: note: OLD is deprecated; use NEW`` on stderr each time it is read."""
    (group or parser).add_argument(
        old,
        dest=dest,
        action=_Renamed,
        new=new,
        append=append,
        type=type,
        default=argparse.SUPPRESS,  # the new spelling's default stands
        help=argparse.SUPPRESS,
    )


def json_option(parser, instead: str = "a table") -> None:
    """``--json``: the result as one JSON document on stdout."""
    parser.add_argument("--json", action="store_true", help=f"print one JSON document instead of {instead}")


def output_option(parser, metavar: str, text: str, *, long: bool = True, required: bool = False) -> None:
    """``-o/--output``: the command's output file (its help says what goes there)."""
    names = ("-o", "--output") if long else ("-o",)
    parser.add_argument(*names, dest="output", metavar=metavar, required=required, help=text)


def table_output_option(parser, what: str, extra: str = "") -> None:
    """``-o PATH`` of a command that prints a table: ``what`` names that table."""
    output_option(
        parser,
        "PATH",
        f"write {what} to PATH instead of stdout: PATH.txt the table, PATH.json (or --json) the JSON "
        f"document{extra}",
    )


def table_options(parser, what: str, extra: str = "") -> None:
    """``--json``, ``-o PATH`` and ``--force`` of a command that prints a table (``what``)."""
    json_option(parser)
    table_output_option(parser, what, extra)
    force_option(parser, "allow -o to replace an existing file")


def force_option(parser, text: str = "allow replacing an existing file") -> None:
    """``--force``: an existing output file may be replaced."""
    parser.add_argument("--force", action="store_true", help=text)


def plot_option(parser, text: str) -> None:
    """``--plot FILE``: the result drawn to FILE (.png, .svg or .pdf)."""
    parser.add_argument("--plot", metavar="FILE", help=f"{text} ({PLOTS})")


def model_options(parser) -> None:
    """``--no-cache`` and ``--allow-code``: how a command reads a model file."""
    parser.add_argument(
        "--no-cache",
        action="store_true",
        help="slice CAD parts anew instead of reading their section tables from the disk cache",
    )
    parser.add_argument(
        "--allow-code",
        action="store_true",
        help="run part code the model file names beyond flexshaft's own part library "
        "(a .py file beside it or an installed package): only for files you trust",
    )


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


def option_pairs(pairs, option: str, form: str, example: str) -> dict:
    """Repeated ``NAME=VALUE`` options as a dict (the last ``=`` splits: a name may hold one)."""
    out = {}
    for pair in pairs or ():
        name, sep, value = pair.rpartition("=")
        if not sep or not name.strip() or not value.strip():
            raise ModelError(f"not {form}", field=option, value=pair, valid=f"e.g. {example}")
        out[name.strip()] = value.strip()
    return out


def signal_units(pairs) -> dict | None:
    """``--unit COLUMN=UNIT`` options as the ``units`` of :func:`read_signals`."""
    return option_pairs(pairs, "--unit", "COLUMN=UNIT", "torque=kNm or time=ms") or None
