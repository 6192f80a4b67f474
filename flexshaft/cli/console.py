"""What a command puts out: its result on stdout, its one error line on stderr, a ``--plot`` file."""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["emit", "complain", "write_plot"]


def write_plot(path, fig, force: bool) -> Path:
    """A ``--plot`` figure, written atomically in the type its suffix names (.png, .svg or .pdf)."""
    from ..system.atomic import atomic_write_bytes
    from ..views.plots import picture

    return atomic_write_bytes(path, picture(fig, Path(path).suffix), overwrite=force)


def _stdout_to_devnull() -> None:
    """Point stdout at devnull, so the interpreter's final flush of what is left does not fail again."""
    import os

    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError):  # no stdout file descriptor (a test's captured stream)
        pass


def emit(text: str) -> None:
    """Print to stdout, with every control character of a name escaped (:func:`flexshaft.errors.shown`:
    a JSON document stays valid and means the same); a reader that stops early (``| head``) is not an
    error, a full disk behind a redirection (``> file``) is one :class:`ModelError`."""
    from ..errors import shown

    try:
        print(shown(text, keep="\n\t"), flush=True)
    except BrokenPipeError:
        _stdout_to_devnull()
    except OSError as err:  # ENOSPC, EFBIG, EDQUOT behind `> file`: what was printed is lost either way
        from ..system.atomic import output_error

        _stdout_to_devnull()
        raise output_error(err, "<standard output>") from None


def complain(text: str) -> None:
    """One line on stderr, ``flexshaft: error: TEXT``, its control characters escaped."""
    from ..errors import shown

    try:
        print(f"flexshaft: error: {shown(text)}", file=sys.stderr, flush=True)
    except OSError:  # stderr gone or full: the exit status still tells
        pass
