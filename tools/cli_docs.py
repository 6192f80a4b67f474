"""The site's command-line reference, ``docs/reference/cli.md``, rendered from the ``flexshaft`` parser.

Every command :func:`flexshaft.cli.registry.build_parser` builds, with its help line, a synopsis and
each argument's spelling, value, default and help, as ``flexshaft COMMAND --help`` gives them (the
old spellings it keeps working but hides from ``--help`` are left out here too). The page is
generated whole and committed; a test holds it equal to this rendering, so it never drifts from the
parser::

    python tools/cli_docs.py            # print the page
    python tools/cli_docs.py --write    # write docs/reference/cli.md
    python tools/cli_docs.py --check    # exit 1 when docs/reference/cli.md differs
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # this checkout's flexshaft, whichever one the interpreter has installed
    sys.path.insert(0, str(ROOT))
PAGE = ROOT / "docs" / "reference" / "cli.md"

INTRO = """\
# Command line

`flexshaft COMMAND [OPTIONS]`: one command per job, each reading a model file (or a study, a
recording, a body file) and printing a readable table, or one JSON document with `--json`. The
vocabulary is shared: `-o/--output` is always the file written (its suffix picks the format), and
nothing is replaced without `--force`; frequencies are in Hz, torques in N·m, stiffnesses in N·m/rad.
Every command takes `--threads N` and every command that reads a model `--no-cache` and
`--allow-code`. The exit status is 0 on success and 2 on bad input, with one line on stderr that
names the file, the field, the value and what would be valid.

`flexshaft COMMAND --help` prints the same as this page, which is generated from the parser by
`tools/cli_docs.py` (do not edit it by hand: run `python tools/cli_docs.py --write`)."""

# What a backslash protects in MyST Markdown text: emphasis, tables, math, links, HTML; an underscore
# only where it could start or end emphasis (not inside a word: FLEXSHAFT_THREADS).
_SPECIAL = re.compile(r"([\\`*|$<>\[\]]|(?<!\w)_|_(?!\w))")


def _text(text: str) -> str:
    """Help text as Markdown: argparse's whitespace folded, Markdown's special characters escaped, and
    `quoted` words (a command, an option) as code - unless a backtick stands alone."""
    pieces = " ".join(text.split()).split("`")
    if len(pieces) % 2 == 0:  # an odd number of backticks: no code, the backticks as they are
        pieces = ["`".join(pieces)]
    # Outside code, every special character escaped; inside, the table's | only (GFM tables split
    # cells before the code spans are read, and remove that backslash).
    return "`".join(
        _SPECIAL.sub(r"\\\1", p) if i % 2 == 0 else p.replace("|", "\\|") for i, p in enumerate(pieces)
    )


def _code(text: str) -> str:
    """Inline code (a backtick inside would end it: doubled delimiters then)."""
    text = text.replace("|", "\\|")  # (in a table cell)
    return f"`` {text} ``" if "`" in text else f"`{text}`"


def _metavar(action: argparse.Action) -> str:
    """The value an argument takes, as ``--help`` spells it (empty for a flag)."""
    if action.nargs == 0:
        return ""
    if action.metavar is not None:
        name = action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar)
    elif action.choices is not None:
        name = "{" + ",".join(map(str, action.choices)) + "}"
    else:
        name = action.dest if not action.option_strings else action.dest.upper()
    if action.nargs == "?":
        return f"[{name}]"
    if action.nargs == "*":
        return f"[{name} ...]"
    if action.nargs == "+":
        return f"{name} [{name} ...]"
    if isinstance(action.nargs, int):
        return " ".join([name] * action.nargs)
    return name


def _shown(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The arguments ``--help`` shows, but ``-h`` itself."""
    return [
        a for a in parser._actions if a.help != argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)
    ]


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The help text as ``--help`` prints it (``%(default)s`` and the like expanded)."""
    return parser._get_formatter()._expand_help(action) if action.help else ""


def _default(action: argparse.Action) -> str:
    if action.default in (None, False, argparse.SUPPRESS) or action.default == [] or action.nargs == 0:
        return ""
    return _code(str(action.default))


def _synopsis(name: str, parser: argparse.ArgumentParser) -> str:
    words = [f"flexshaft {name}"]
    for action in _shown(parser):
        if not action.option_strings:
            words.append(_metavar(action))
        elif action.required:
            words.append(f"{action.option_strings[-1]} {_metavar(action)}".strip())
    if any(a.option_strings and not a.required for a in _shown(parser)):
        words.append("[OPTIONS]")
    return " ".join(words)


def _command(name: str, parser: argparse.ArgumentParser, summary: str) -> str:
    rows = ["| argument | default | what it is |", "|---|---|---|"]
    for action in _shown(parser):
        head = f"{', '.join(action.option_strings)} {_metavar(action)}".strip()
        required = " (required)" if action.option_strings and action.required else ""
        rows.append(f"| {_code(head)}{required} | {_default(action)} | {_text(_help(parser, action))} |")
    return "\n\n".join(
        [
            f"## `flexshaft {name}`",
            f"{_text(summary[:1].upper() + summary[1:])}.",
            "```text\n" + _synopsis(name, parser) + "\n```",
            "\n".join(rows),
        ]
    )


def page() -> str:
    """The whole reference page, from the parser."""
    from flexshaft.cli.registry import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    summaries = {c.dest: c.help for c in sub._choices_actions}
    table = ["| command | what it does |", "|---|---|"]
    table += [f"| [`{n}`](#flexshaft-{n}) | {_text(summaries[n])} |" for n in sub.choices]
    parts = [INTRO, "## Commands", "\n".join(table)]
    parts += [_command(n, p, summaries[n]) for n, p in sub.choices.items()]
    return "\n\n".join(parts) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"write {PAGE.name}")
    parser.add_argument("--check", action="store_true", help=f"exit 1 when {PAGE.name} differs")
    args = parser.parse_args(argv)
    text = page()
    if args.write:
        PAGE.write_text(text, encoding="utf-8")
    elif args.check:
        if not PAGE.is_file() or PAGE.read_text(encoding="utf-8") != text:
            print(f"{PAGE} differs from the parser: run python tools/cli_docs.py --write")
            return 1
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
