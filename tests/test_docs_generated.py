"""The documentation's generated pages are up to date: regenerating them changes nothing.

``docs/reference/cli.md`` is rendered from the ``flexshaft`` parser by ``tools/cli_docs.py`` (the file
references, from the schemas, are held by tests/flexshaft/input/test_schema.py)."""

from __future__ import annotations

import argparse
import importlib.util

from tests.conftest import ROOT


def _tool(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_cli_reference_is_the_parser():
    cli_docs = _tool("cli_docs")
    assert cli_docs.PAGE.read_text(encoding="utf-8") == cli_docs.page(), (
        "docs/reference/cli.md differs from the parser: run python tools/cli_docs.py --write"
    )


def test_the_cli_reference_has_every_command_and_every_shown_option_but_no_hidden_one():
    """Independent of the renderer's layout: each command a heading, each option --help shows named
    under it (but -h), each old spelling argparse hides (help=SUPPRESS) absent from it."""
    from flexshaft.cli.registry import build_parser

    text = _tool("cli_docs").page()
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    for name, parser in sub.choices.items():
        start = text.index(f"## `flexshaft {name}`")
        end = text.find("\n## ", start + 1)
        section = text[start : end if end > 0 else len(text)]
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue  # -h: every command has it
            for spelling in action.option_strings:
                if action.help == argparse.SUPPRESS:
                    assert f"`{spelling} " not in section and f"`{spelling}`" not in section, (name, spelling)
                else:
                    assert spelling in section, (name, spelling)
