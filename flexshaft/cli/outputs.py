"""Where the ``flexshaft`` commands write, checked before any work: each option's file types, and no
output that is an input, another output, or an existing file without ``--force``."""

from __future__ import annotations

from pathlib import Path

from ..errors import ModelError

__all__ = [
    "output_suffixes",
    "REPORT_FILES",
    "INPUT_OPTIONS",
    "to_folder",
    "check_output_paths",
    "check_output_files",
]


def output_suffixes() -> dict[str, dict[str, dict[str, str]]]:
    """What each command writes, by option: the suffixes it accepts (any case) and what each gives
    (each command's ``files``). Checked by :func:`check_output_paths` before any work, so a wrong
    suffix costs nothing and never gets content of another type (a text table in a .npz, a PNG in a
    .txt)."""
    from .registry import commands

    return {c.name: dict(c.files) for c in commands() if c.files}


REPORT_FILES = ("index.html", "results.json")  # what a report folder gets (a study's report)
#: Every option that names a file a command writes, and its attribute on the parsed arguments.
OUTPUT_OPTIONS = {"-o": "output", "--plot": "plot", "--view": "view", "--tuned": "tuned", "--uff": "uff"}


def to_folder(args) -> bool:
    """Whether ``-o`` names a folder: always for report; for demo an existing folder or a path ending in /."""
    if args.command == "report":
        return True
    out = getattr(args, "output", None)
    return args.command == "demo" and bool(out) and (out.endswith("/") or Path(out).is_dir())


def check_output_paths(args) -> None:
    """Refuse an output path of the wrong type before any work: every -o, --plot, --view and --tuned.

    A file's suffix (any case) must be one the command's ``files`` list for the option;
    a report folder must be one flexshaft may write (:func:`flexshaft.system.atomic.check_output_folder`).
    """
    if to_folder(args):
        from ..system.atomic import check_output_folder

        if Path(args.output).suffix.lower() in (".html", ".htm"):
            raise ModelError(
                "is a folder for the report, not a page",
                field="-o",
                value=args.output,
                valid="a folder DIR (the report writes DIR/index.html and DIR/results.json)",
            )
        inputs = [args.model] if args.command == "report" else []
        check_output_folder(args.output, force=args.force, inputs=inputs, files=REPORT_FILES, option="-o")
        return
    from .registry import command

    for option, kinds in command(args.command).files.items():
        path = getattr(args, OUTPUT_OPTIONS[option], None)
        if path is not None and Path(path).suffix.lower() not in kinds:  # "" too: it names no file
            valid = ", ".join(f"{s} ({what})" for s, what in kinds.items())
            if args.command == "demo":
                valid += ", or a folder DIR/ (the report)"
            raise ModelError("unknown file type", field=option, value=path, valid=valid)
    check_output_files(args)


#: The options naming files a command reads: no output may be one of them.
INPUT_OPTIONS = ("model", "signals", "source", "targets", "series", "runs", "parameters")


def check_output_files(args) -> None:
    """Before any work: no output file is an input, two outputs or an existing file without --force.

    The atomic writer checks the same again when it writes (with the files a model brought in, such
    as its STEP parts); checking here too means a refused output costs no computation and leaves no
    other output (a plot) behind.
    """
    import os
    import stat

    named = {option: getattr(args, attr, None) for option, attr in OUTPUT_OPTIONS.items()}
    inputs = []
    for attr in INPUT_OPTIONS:
        value = getattr(args, attr, None)
        for one in value if isinstance(value, list) else [value]:
            if isinstance(one, str) and one:
                try:
                    inputs.append((attr, os.stat(one)))
                except (OSError, ValueError):
                    pass  # a missing input is its reader's error
    seen: dict[tuple[int, int] | str, str] = {}
    for option, path in named.items():
        if not path:
            continue
        key = os.path.abspath(path)
        if key in seen:
            raise ModelError(
                f"is also the {seen[key]} file", field=option, value=path, valid="a different path"
            )
        seen[key] = option
        try:
            st = os.stat(path)
        except FileNotFoundError:
            parent = os.path.dirname(os.path.abspath(path))
            if not os.path.isdir(parent):
                valid = "a path in an existing folder"
                raise ModelError("its folder does not exist", field=option, value=path, valid=valid) from None
            continue
        except (OSError, ValueError):
            continue  # the writer says why
        for attr, ist in inputs:
            if (st.st_dev, st.st_ino) == (ist.st_dev, ist.st_ino):
                raise ModelError(
                    f"is the input file {getattr(args, attr)!r} (links followed): an output never "
                    "replaces an input, --force or not",
                    field=option,
                    value=path,
                    valid="a path that is none of the command's input files",
                )
        if stat.S_ISDIR(st.st_mode):
            raise ModelError("is a folder", field=option, value=path, valid="a file path")
        if not args.force:
            raise ModelError(
                "file exists", field=option, value=path, valid="a new path, or --force to replace it"
            )
