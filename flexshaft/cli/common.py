"""What every command of the ``flexshaft`` command line shares: its defaults, loading a model file
with the command line's settings, writing a ``--plot``, reading ``--unit`` and printing."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import ModelError

__all__ = [
    "DEMO_MODEL",
    "MESH_CHECK_AUTO_DOFS",
    "PLOTS",
    "DEFAULT_MODES",
    "load",
    "write_plot",
    "signal_units",
    "emit",
    "complain",
]

DEMO_MODEL = "customer1.toml"
MESH_CHECK_AUTO_DOFS = 20_000  # the check doubles the solve; above this it runs only when asked
PLOTS = ".png, .svg or .pdf"  # what --plot writes (the suffix picks)
DEFAULT_MODES = 6  # sensitivity and sweep: the lowest elastic modes reported without --modes


def load(args, path, *, mesh_solids: bool = False):
    """The model file, with the command line's trust, cache and progress settings (a solid part's
    reduction shows its progress through the bar the loader hands it).

    A model with ``[model] max_hz`` comes meshed for it (:func:`flexshaft.mesh_for_range`): each
    shaft's and CAD part's elements chosen so every mode below max_hz is within 1 %.
    """
    from ..analysis.convergence import meshed_for_own_range
    from ..input.modelfile import load_model
    from ..views.progress import ProgressBar

    # [model] max_hz: every command works on the mesh that range needs
    return meshed_for_own_range(
        load_model(
            path,
            progress=ProgressBar,
            allow_code=args.allow_code,
            use_cache=not args.no_cache,
            mesh_solids=mesh_solids,
        )
    )


def write_plot(path, fig, force: bool) -> Path:
    """A ``--plot`` figure, written atomically in the type its suffix names (.png, .svg or .pdf)."""
    from ..system.atomic import atomic_write_bytes
    from ..views.plots import picture

    return atomic_write_bytes(path, picture(fig, Path(path).suffix), overwrite=force)


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
