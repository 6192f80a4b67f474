"""Run every ``flexshaft`` command line of the README and record what it gives; compare two records.

    python tools/cli_outputs.py run FLEXSHAFT README.md OUT      # record one checkout's outputs
    python tools/cli_outputs.py compare OUT_A OUT_B             # what differs between two records

``run`` takes the command lines of the README's examples - the lines of its ```sh blocks and its
``$ flexshaft ...`` lines, and the inline `` `flexshaft ...` `` commands whose arguments are concrete
(``MODEL`` taken as ``examples/customer1.toml``, ``DIR`` as a folder, ``N`` as 1) - and runs each, in
the README's order, with ``FLEXSHAFT`` (a checkout's ``.venv/bin/flexshaft``) in one scratch folder
``OUT/work`` (where ``examples`` links to the checkout's examples, so the paths printed are the same
for every checkout, and a command may read what an earlier one wrote). Each run's exit code, stdout,
stderr and the SHA-256 of every file it wrote or changed are kept in ``OUT/record.json``; the cache
is a fresh folder, so every checkout starts cold.

``compare`` pairs the two records' runs in order (a README whose options were renamed has the same
commands in the same order) and prints, for each pair, ``same`` or what differs: the command lines
(where an option was renamed), the exit code, the stdout, the stderr, the files. Times printed by a
command (``in 3.2 s``) and the study folder's provenance (dates, machine, durations) are told apart
as volatile, not as a difference.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

# The placeholders of the README's inline commands and what stands for them here.
PLACEHOLDERS = {"MODEL": "examples/customer1.toml", "DIR": "report_dir", "DIR/": "demo_dir/", "N": "1"}
TIMEOUT_S = 900  # the study and a cold CAD model take a few minutes on a busy machine
# What a command prints that changes from run to run: durations.
VOLATILE = [(re.compile(r"\bin \d+(\.\d+)? s\b"), "in <t> s")]


def _commands(readme: str) -> list[str]:
    """The README's command lines, in order, each once."""
    lines = readme.split("\n")
    found, block, i = [], False, 0
    while i < len(lines):
        text = lines[i].strip()
        if text.startswith("```"):
            block = not block and text in ("```sh", "```console", "```bash", "```shell")
            i += 1
            continue
        line = text[2:] if text.startswith("$ ") else text if block else None
        while line is not None and line.endswith("\\") and i + 1 < len(lines):
            i += 1
            line = line[:-1] + " " + lines[i].strip()
        for part in (line or "").split("&&"):
            part = part.split("  #")[0].strip()
            if re.match(r"((\w+=\S+ )*)(\S*/)?flexshaft ", part):
                found.append(part)
        for inline in re.findall(r"`((?:\w+=\S+ )*flexshaft [^`]+)`", lines[i]):
            words = inline.split()
            if any(c in inline for c in "[|…") or "..." in inline:
                continue  # a synopsis, not a command line
            words = [PLACEHOLDERS.get(w, w) for w in words]
            if not any(re.fullmatch(r"[A-Z][A-Z_]*(\.\w+)?", w) for w in words[2:]):
                found.append(" ".join(shlex.quote(w) if " " in w else w for w in words))
        i += 1
    return [c for c in dict.fromkeys(found) if _runnable(c)]


def _runnable(line: str) -> bool:
    """A command line, not a name in prose: a command and, but for demo and --help, an argument."""
    words = shlex.split(line)
    while "=" in words[0]:
        words.pop(0)
    if len(words) < 2 or not re.fullmatch(r"[a-z]+|--version", words[1]):
        return False
    return (
        words[1] in ("demo", "--version")
        or "--help" in words
        or any(not w.startswith("-") for w in words[2:])
    )


def _files(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` (links not followed) and its SHA-256."""
    out = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file() and not path.is_symlink() and "examples" not in path.relative_to(folder).parts[:1]:
            out[str(path.relative_to(folder))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def run(flexshaft: str, readme: Path, out: Path) -> None:
    """Run the README's commands with ``flexshaft``, one after the other in ``out/work``."""
    work, cache = out / "work", out / "cache"
    work.mkdir(parents=True)
    cache.mkdir()
    (work / "examples").symlink_to(Path(flexshaft).resolve().parents[2] / "examples")
    env = os.environ | {"FLEXSHAFT_CACHE_DIR": str(cache), "COLUMNS": "100"}
    records = []
    for line in _commands(readme.read_text(encoding="utf-8")):
        words = shlex.split(line)
        while "=" in words[0]:  # FLEXSHAFT_X=... before the command
            key, _, value = words.pop(0).partition("=")
            env = env | {key: value}
        before = _files(work)
        try:
            proc = subprocess.run(
                [flexshaft, *words[1:]], cwd=work, env=env, capture_output=True, timeout=TIMEOUT_S
            )
            code, stdout, stderr = proc.returncode, proc.stdout, proc.stderr
        except subprocess.TimeoutExpired as err:
            code, stdout, stderr = "timeout", err.stdout or b"", err.stderr or b""
        after = _files(work)
        written = {k: v for k, v in after.items() if before.get(k) != v}
        records.append(
            {
                "line": line,
                "exit": code,
                "stdout": stdout.decode("utf-8", "replace"),
                "stderr": stderr.decode("utf-8", "replace"),
                "files": written,
            }
        )
        print(f"{code!s:>7}  {line}", flush=True)
    (out / "record.json").write_text(json.dumps(records, indent=1, ensure_ascii=False), encoding="utf-8")


def _steady(text: str) -> str:
    for pattern, mark in VOLATILE:
        text = pattern.sub(mark, text)
    return text


def compare(a: Path, b: Path) -> int:
    """Print what differs between two records; the number of runs that differ."""
    ra = json.loads((a / "record.json").read_text(encoding="utf-8"))
    rb = json.loads((b / "record.json").read_text(encoding="utf-8"))
    if len(ra) != len(rb):
        print(f"{len(ra)} runs against {len(rb)}: the READMEs have different commands")
    differ = 0
    for x, y in zip(ra, rb):
        notes = []
        if x["line"] != y["line"]:
            notes.append(f"  command line: {x['line']}\n            ->  {y['line']}")
        if x["exit"] != y["exit"]:
            notes.append(f"  exit {x['exit']} -> {y['exit']}")
        for stream in ("stdout", "stderr"):
            if x[stream] != y[stream]:
                steady = _steady(x[stream]) == _steady(y[stream])
                diff = difflib.unified_diff(x[stream].splitlines(), y[stream].splitlines(), lineterm="", n=0)
                notes.append(f"  {stream} {'(volatile only)' if steady else ''}\n    " + "\n    ".join(diff))
        if x["files"] != y["files"]:
            names = sorted(set(x["files"]) | set(y["files"]))
            changed = [n for n in names if x["files"].get(n) != y["files"].get(n)]
            notes.append("  files differ: " + ", ".join(changed))
        real = [n for n in notes if not n.startswith("  command line") and "(volatile only)" not in n]
        differ += bool(real)
        print(("same" if not notes else "differs" if real else "same but") + f": {y['line']}")
        for note in notes:
            print(note)
    return differ


def main(argv: list[str]) -> int:
    if len(argv) == 4 and argv[0] == "run":
        run(argv[1], Path(argv[2]), Path(argv[3]))
        return 0
    if len(argv) == 3 and argv[0] == "compare":
        return 1 if compare(Path(argv[1]), Path(argv[2])) else 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
