"""Every code block of the getting-started pages (and the README's quick starts) runs as written.

The pages are read the way a newcomer follows them, one page in a fresh folder holding a copy of
``examples/``; their fenced blocks are, in order:

- ```` ```{code-block} LANG```` with ``:caption: NAME`` - a file the page writes: saved as NAME;
- ```` ```bash```` - commands, run one after the other: ``flexshaft ...`` through the CLI's ``main`` in
  this process, ``python ...`` in a subprocess; each must exit 0;
- ```` ```python```` - run in a subprocess; it must exit 0;
- ```` ```text```` - what the block before it prints (the last command of a bash block): each of its
  lines must appear in that output, in order, numbers equal to the last digit shown (so a table that
  goes stale fails here);
- ```` ```sh```` - the set-up commands, not run here (they install): each line must be one of the
  README's, so the two never disagree.

A block of any other kind fails the test (nothing on these pages goes unrun). Commands that take
tens of seconds (the test bench's whole study, the demo's report) run in the slow step.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES

ROOT = EXAMPLES.parent
# the numbered pages (index.md is the section's contents: a toctree, nothing to run)
PAGES = sorted((ROOT / "docs" / "getting-started").glob("[0-9][0-9]-*.md"))
README = ROOT / "README.md"
# The commands of the pages that take tens of seconds: run by CI's slow step, `pytest -m slow`.
SLOW = {
    "flexshaft demo -o demo-report/",
    "flexshaft study examples/testbench_study.toml -o bench",
    "python examples/bench_recordings.py",
    "flexshaft study examples/bench_study.toml -o bench-recorded",
}
#: What a page's copy of examples/ leaves out: recordings a run of bench_recordings.py left behind
#: (tens of MB; a page that needs them makes them).
NOT_EXAMPLES = shutil.ignore_patterns("recordings", "__pycache__")
PREFIXES = {"flexshaft": "flexshaft", ".venv/bin/flexshaft": "flexshaft", "python": "python"}
PREFIXES[".venv/bin/python"] = "python"


@dataclass(frozen=True)
class Block:
    """One fenced block of a page: its language, the file it names (a caption) and its text."""

    lang: str
    caption: str | None
    text: str
    line: int


_FENCE = re.compile(r"^```(\{code-block\}\s*)?([\w-]*)\s*$")


def blocks(path: Path) -> list[Block]:
    """The fenced blocks of a Markdown page, in order (directive options read off their first lines)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    found, i = [], 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start, i, caption, body = i + 1, i + 1, None, []
        while m.group(1) and i < len(lines) and lines[i].startswith(":"):
            key, _, value = lines[i][1:].partition(":")
            caption = value.strip() if key == "caption" else caption
            i += 1
        while i < len(lines) and lines[i].strip() != "```":
            body.append(lines[i])
            i += 1
        i += 1
        text = "\n".join(body).strip("\n") + "\n"
        found.append(Block(m.group(2), caption, text, start))
    return found


def commands(text: str) -> list[str]:
    """The command lines of a shell block: continuations joined, comments and blanks left out."""
    joined = re.sub(r"\\\n\s*", " ", text)
    return [c.strip() for c in joined.splitlines() if c.strip() and not c.strip().startswith("#")]


def is_slow(command: str) -> bool:
    """One of the long commands, with or without the README's ``.venv/bin/``."""
    return command.removeprefix(".venv/bin/") in SLOW


def _ulp(token: str) -> float:
    """One unit in the last digit of a printed number ('11.6073' -> 1e-4, '7.6e+06' -> 1e5); a whole
    number (a mode, a count, a part's name) must be the same."""
    if not re.search(r"[.eE]", token):
        return 0.0
    mantissa, _, exponent = token.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def _number(token: str) -> float | None:
    try:
        return float(token.strip("()[],;:%"))
    except ValueError:
        return None


def _same_line(shown: str, got: str) -> bool:
    a, b = shown.split(), got.split()
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if x == y:
            continue
        nx, ny = _number(x), _number(y)
        if nx is None or ny is None or abs(nx - ny) > _ulp(x.strip("()[],;:%")):
            return False
    return True


def check_output(shown: str, got: str, where: str) -> None:
    """Each line the page shows appears in what the command printed, in the same order."""
    got_lines = got.splitlines()
    at = 0
    for line in (s for s in shown.splitlines() if s.strip()):
        for k in range(at, len(got_lines)):
            if _same_line(line, got_lines[k]):
                at = k + 1
                break
        else:
            raise AssertionError(f"{where}: the page shows\n  {line}\nwhich the output lacks:\n{got}")


def _run_command(command: str, cwd: Path, capsys) -> str:
    from flexshaft.cli import main

    argv = shlex.split(command)
    program = PREFIXES.get(argv[0])
    assert program, f"{command!r}: neither flexshaft nor python"
    if program == "python":
        proc = subprocess.run(
            [sys.executable, *argv[1:]], cwd=cwd, capture_output=True, text=True, timeout=300
        )
        assert proc.returncode == 0, f"{command}: {proc.stderr}"
        return proc.stdout
    capsys.readouterr()
    code = main(argv[1:])
    out, err = capsys.readouterr()
    assert code == 0, f"{command}: exit {code}: {err}"
    return out


def run_page(path: Path, folder: Path, capsys, monkeypatch, *, slow: bool) -> int:
    """Follow one page in ``folder``; return how many commands and programs ran.

    ``slow``: every command, the long ones included; else all but those (and their outputs).
    """
    shutil.copytree(
        EXAMPLES, folder / "examples", ignore=NOT_EXAMPLES
    )  # links followed: the files themselves
    monkeypatch.chdir(folder)
    readme = README.read_text(encoding="utf-8")
    ran, output, skipped = 0, None, False
    for block in blocks(path):
        where = f"{path.name}:{block.line}"
        if block.caption:
            (folder / block.caption).write_text(block.text, encoding="utf-8")
        elif block.lang == "bash":
            for command in commands(block.text):
                skipped = is_slow(command) and not slow
                if not skipped:
                    output = _run_command(command, folder, capsys)
                    ran += 1
        elif block.lang == "python":
            (folder / "block.py").write_text(block.text, encoding="utf-8")
            proc = subprocess.run(
                [sys.executable, "block.py"], cwd=folder, capture_output=True, text=True, timeout=300
            )
            assert proc.returncode == 0, f"{where}: {proc.stderr}"
            output, skipped = proc.stdout, False
            ran += 1
        elif block.lang == "text":
            assert output is not None, f"{where}: an output block with nothing run before it"
            if not skipped:
                check_output(block.text, output, where)
        elif block.lang == "sh":
            for command in commands(block.text):
                assert command in readme, f"{where}: {command!r} is not the README's"
        else:
            raise AssertionError(f"{where}: a ```{block.lang} block that no test runs")
    return ran


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_getting_started_page_runs_as_written(page, tmp_path, capsys, monkeypatch):
    run_page(page, tmp_path, capsys, monkeypatch, slow=False)


def _has_slow(path: Path) -> bool:
    return any(is_slow(c) for b in blocks(path) if b.lang == "bash" for c in commands(b.text))


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if _has_slow(p)], ids=lambda p: p.name)
def test_getting_started_page_with_its_long_commands(page, tmp_path, capsys, monkeypatch):
    run_page(page, tmp_path, capsys, monkeypatch, slow=True)


def test_the_readme_quick_starts_run_as_written(tmp_path, capsys, monkeypatch):
    assert run_page(README, tmp_path, capsys, monkeypatch, slow=False) >= 2


@pytest.mark.slow
@pytest.mark.skipif(not _has_slow(README), reason="the README has no long command")
def test_the_readme_with_its_long_commands(tmp_path, capsys, monkeypatch):
    run_page(README, tmp_path, capsys, monkeypatch, slow=True)


GUIDE = sorted((ROOT / "docs" / "guide").glob("*.md"))


def shown_runs(path: Path) -> list[tuple[int, list[str], str]]:
    """The guide's shown runs: ``text`` blocks opening with ``$ flexshaft ...``, as (line, commands,
    the output shown after them), where every file a command names is in ``examples/`` or written
    by a command before it (the others need files the page describes, such as a solid part)."""
    runs = []
    for block in blocks(path):
        lines = block.text.replace("\\\n", " ").splitlines()
        if block.lang != "text" or not lines[0].startswith("$ flexshaft "):
            continue
        cmds = [line[2:].split("  #")[0].strip() for line in lines if line.startswith("$ ")]
        written, runnable = set(), True
        for command in cmds:
            argv = shlex.split(command)
            for arg, nxt in zip(argv, [*argv[1:], ""]):
                if arg in ("-o", "--plot"):
                    written.add(nxt)
                elif re.search(r"\.(toml|csv)$", arg) and arg not in written:
                    runnable &= arg.startswith("examples/") and (EXAMPLES.parent / arg).exists()
        shown = "\n".join(line for line in lines if not line.startswith("$ ") and "..." not in line)
        if runnable:
            runs.append((block.line, cmds, shown))
    return runs


@pytest.mark.parametrize("page", [p for p in GUIDE if shown_runs(p)], ids=lambda p: p.name)
def test_the_guides_shown_outputs_are_what_the_commands_print(page, tmp_path, capsys, monkeypatch):
    """A table the user guide shows is what the command prints today (numbers to the last digit
    shown), for every run on the page that needs only the examples."""
    shutil.copytree(EXAMPLES, tmp_path / "examples", ignore=NOT_EXAMPLES)
    monkeypatch.chdir(tmp_path)
    for line, cmds, shown in shown_runs(page):
        for command in cmds:
            output = _run_command(command, tmp_path, capsys)
        check_output(shown, output, f"{page.name}:{line}")


@pytest.mark.parametrize(
    "page", [p for p in GUIDE if any(b.lang == "python" for b in blocks(p))], ids=lambda p: p.name
)
def test_the_guides_python_runs_as_written(page, tmp_path):
    """Every Python block of the user guide runs as it stands, from a folder holding ``examples/``."""
    shutil.copytree(
        EXAMPLES, tmp_path / "examples", ignore=NOT_EXAMPLES
    )  # links followed: the files themselves
    for block in blocks(page):
        if block.lang == "python":
            (tmp_path / "block.py").write_text(block.text, encoding="utf-8")
            proc = subprocess.run(
                [sys.executable, "block.py"], cwd=tmp_path, capture_output=True, text=True, timeout=300
            )
            assert proc.returncode == 0, f"{page.name}:{block.line}: {proc.stderr}"


def test_every_slow_command_is_on_a_page():
    """The list of slow commands names only commands the pages hold (none left over after an edit)."""
    held = [c for p in [*PAGES, README] for b in blocks(p) if b.lang == "bash" for c in commands(b.text)]
    assert SLOW <= {c.removeprefix(".venv/bin/") for c in held}


def test_the_pages_are_in_order_and_the_readme_is_short():
    assert [p.name[:3] for p in PAGES] == [f"{i:02d}-" for i in range(1, len(PAGES) + 1)]
    # no page is left out of the run: every page but the section's contents is numbered
    every = {p.name for p in (ROOT / "docs" / "getting-started").glob("*.md")}
    assert every == {p.name for p in PAGES} | {"index.md"}
    assert len(README.read_text(encoding="utf-8").splitlines()) <= 150


def test_the_comparison_takes_the_shown_digits_and_nothing_else():
    got = "mode  frequency Hz\n   1       11.1520     0.0000  part 3 (100 %)\npart 1  1.482719e+07\n"
    check_output("   1       11.1520     0.0000  part 3 (100 %)\npart 1 1.48272e+07", got, "same")
    for stale in (
        "   1       11.1470     0.0000  part 3 (100 %)",
        "part 1  1.482729e+07",
        "part 2  1.482719e+07",
    ):
        with pytest.raises(AssertionError, match="which the output lacks"):
            check_output(stale, got, "stale")
    with pytest.raises(AssertionError):  # in order
        check_output("part 1  1.482719e+07\n   1       11.1520     0.0000  part 3 (100 %)", got, "order")
