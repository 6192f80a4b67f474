"""The ``flexshaft`` command: a thin shell over the library.

Each command declares its options and its run function in one place (:mod:`.registry`, the modules
of :mod:`.commands`), calls the library's stage functions - the same the study calls - and prints
what they return. The words mean one thing in every command (:mod:`.options`); :mod:`.outputs`
checks where they write before any work.

Exit codes: 0 success, 2 bad input (one line on stderr, nothing on stdout).
"""

from __future__ import annotations

import errno
import sys

from ..errors import ModelError
from .console import complain, emit
from .loadmodel import DEMO_MODEL
from .outputs import OUTPUT_OPTIONS, REPORT_FILES, check_output_paths, output_suffixes
from .registry import Written, command
from .registry import build_parser as _parser

__all__ = ["main", "last_warnings", "output_suffixes", "REPORT_FILES"]


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code.

    Without ``argv`` (the ``flexshaft`` command, ``python -m flexshaft``) the work runs under the
    watchdog of :mod:`flexshaft.system.watchdog`: SIGINT or SIGTERM ends it within seconds, native calls
    included. With ``argv`` (from Python) it runs in this process, stopped at the next bytecode.
    """
    import threading

    from ..system.watchdog import Terminated, stopping, supervise

    if threading.current_thread() is not threading.main_thread():
        return _main(argv)
    if argv is None:
        code = supervise()
        if code is not None:
            return code  # the watchdog: the work has ended
    with stopping(ending=argv is None):
        try:
            return _main(argv)
        except KeyboardInterrupt:
            print("flexshaft: interrupted", file=sys.stderr)
            return 130
        except Terminated:
            print("flexshaft: terminated", file=sys.stderr)
            return 143


def _main(argv: list[str] | None) -> int:
    import warnings

    from ..system.inputs import recording

    # A library's warning is no message of ours: Python would print it with the library's source
    # path and line, raw. Each distinct one becomes a note after a successful command (the result
    # stands: flexshaft checks its own numbers, and bad input is refused before the work); after a
    # failure the error line stays the only one.
    with recording(), warnings.catch_warnings(record=True) as caught:  # outputs checked against inputs
        warnings.simplefilter("default")  # once per place, whatever a library or PYTHONWARNINGS set
        try:
            code = _command(argv)
        finally:
            _HEARD[:] = [(w.category.__name__, str(w.message)) for w in caught]
    if code == 0:
        _notes(_HEARD)
    return code


_HEARD: list[tuple[str, str]] = []


def last_warnings() -> tuple[tuple[str, str], ...]:
    """The warnings (category name, message) the last command run in this process caught - told as
    notes after a success, not at all after an error - for tests that want none at all."""
    return tuple(_HEARD)


#: The most warnings told after a command: the rest are counted.
MAX_NOTES = 3


def _notes(heard) -> None:
    """One line on stderr per distinct warning (``heard``: category name, message): ``flexshaft:
    note: Category: message``, no path."""
    from ..errors import shown

    seen = list(dict.fromkeys((kind, text.strip()) for kind, text in heard))
    lines = [f"flexshaft: note: {kind}: {shown(' '.join(text.split()))[:300]}" for kind, text in seen]
    if len(lines) > MAX_NOTES:
        lines = lines[:MAX_NOTES] + [f"flexshaft: note: and {len(lines) - MAX_NOTES} more warnings"]
    for line in lines:
        try:
            print(line, file=sys.stderr, flush=True)
        except OSError:  # stderr gone: the result is out already
            return


def _command(argv: list[str] | None) -> int:
    try:
        args = _parser().parse_args(argv)
    except SystemExit as stop:  # usage errors (2) and --help (0), already printed
        return int(stop.code or 0)

    if args.force and not any(getattr(args, attr, None) for attr in OUTPUT_OPTIONS.values()):
        complain("--force: replaces a file only with -o PATH; valid: -o PATH --force, or leave --force out")
        return 2
    from ..system.threads import cli_threads, thread_policy

    try:
        threads = cli_threads(args.threads)  # before numpy loads: this process and its workers
    except ModelError as err:
        complain(str(err))
        return 2
    with thread_policy(threads):
        return _dispatch(args)


def _dispatch(args) -> int:
    """Run the parsed command; returns the exit code (one line on stderr for any failure)."""
    cmd = command(args.command)
    if cmd.table and args.output and args.output.lower().endswith(".json"):
        args.json = True  # a .json file gets the JSON document, never the table
    source = cmd.source_of(args) or f"<built-in {DEMO_MODEL}>"
    try:
        if cmd.whole:
            return cmd.run(args)
        check_output_paths(args)  # every output's type, and a report's folder, before any work
        try:
            out = cmd.run(args)
        except ModelError as err:
            if not cmd.locate:
                raise
            raise err.located(file=source) from None
        if cmd.table and args.output and not isinstance(out, Written):
            from ..system.atomic import atomic_write_text

            atomic_write_text(args.output, out + "\n", overwrite=args.force)
        else:
            emit(out)  # a table, or what the command wrote where
    except ModelError as err:
        complain(str(err))
        return 2
    except KeyboardInterrupt:
        print("flexshaft: interrupted", file=sys.stderr)
        return 130
    except OSError as err:  # the environment: the writers name their own outputs; this is the rest
        from ..system.atomic import output_error, refused_write

        if refused_write(err):  # a full disk, a read-only folder where a file was named
            complain(str(output_error(err)))
        else:  # not a write flexshaft knows of (a fork refused, a pipe closed): said as the system says it
            code = errno.errorcode.get(err.errno) if err.errno is not None else None
            where = f"{err.filename}: " if err.filename is not None else ""
            complain(f"{where}{err.strerror or err}{f' ({code})' if code else ''}")
        return 2
    except Exception as err:  # noqa: BLE001 - a defect still gets one line, never a traceback
        detail = str(err).splitlines()[0] if str(err) else ""
        complain(
            f"unexpected {type(err).__name__}{': ' + detail if detail else ''} "
            "(a flexshaft defect: please report it with the input that caused it)"
        )
        return 2
    return 0
