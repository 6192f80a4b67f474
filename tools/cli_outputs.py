"""Run every ``flexshaft`` command line of the README and record what it gives; compare two records.

    python tools/cli_outputs.py run FLEXSHAFT README.md OUT      # record one checkout's outputs
    python tools/cli_outputs.py compare OUT_A OUT_B             # what differs between two records

``run`` takes the command lines of the README's examples - the lines of its ```sh blocks and its
``$ flexshaft ...`` lines, and the inline `` `flexshaft ...` `` commands whose arguments are concrete
(``MODEL`` taken as ``examples/customer1.toml``, ``DIR`` as a folder, ``N`` as 1) - and runs each, in
the README's order, with ``FLEXSHAFT`` (a checkout's ``.venv/bin/flexshaft``) in one scratch folder
at a fixed path, :data:`SCRATCH`, holding a copy of the checkout's examples (so every path printed or
recorded is the same whichever checkout runs, and a command may read what an earlier one wrote);
the folder is moved to ``OUT/work`` afterwards. Each run's exit code, stdout, stderr and the
SHA-256 of every file it wrote or changed (raw, and with what changes from run to run left out)
are kept in ``OUT/record.json``; the cache is a fresh folder, so every checkout starts cold.

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
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

# The placeholders of the README's inline commands and what stands for them here.
PLACEHOLDERS = {"MODEL": "examples/customer1.toml", "DIR": "report_dir", "DIR/": "demo_dir/", "N": "1"}
TIMEOUT_S = 900  # the study and a cold CAD model take a few minutes on a busy machine
SCRATCH = Path(tempfile.gettempdir()) / "flexshaft-cli-outputs"
# What changes from run to run in what a command prints or writes: durations, dates and times, a
# lock's process id. (A MAT file's 128-byte header holds its date: only what follows is compared.)
VOLATILE = [
    (re.compile(r"\b\d+(\.\d+)? s\b"), "<t> s"),
    (re.compile(r"\d{4}-\d\d-\d\d([T ]\d\d:\d\d(:\d\d(\.\d+)?)?([+-]\d\d:?\d\d|Z)?)?"), "<date>"),
    (re.compile(r'"(\w*(seconds|_s|elapsed|pid|started|finished)\w*)": [-\d.e+]+'), r'"\1": <n>'),
]
TEXT = (".json", ".html", ".txt", ".csv", ".toml", ".flexshaft-output", "lock")


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


def _steady(text: str) -> str:
    for pattern, mark in VOLATILE:
        text = pattern.sub(mark, text)
    return text


def _hashes(path: Path) -> list[str]:
    """The SHA-256 of a file, and of what of it does not change from run to run."""
    data = path.read_bytes()
    steady = data
    if path.suffix == ".mat":
        steady = data[128:]
    elif path.name.endswith(TEXT):
        steady = _steady(data.decode("utf-8", "replace")).encode("utf-8")
    return [hashlib.sha256(data).hexdigest(), hashlib.sha256(steady).hexdigest()]


def _files(folder: Path) -> dict[str, list[str]]:
    """Every file under ``folder`` but the examples, and its hashes (:func:`_hashes`)."""
    out = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file() and "examples" not in path.relative_to(folder).parts[:1]:
            out[str(path.relative_to(folder))] = _hashes(path)
    return out


def run(flexshaft: str, readme: Path, out: Path) -> None:
    """Run the README's commands with ``flexshaft``, one after the other in ``out/work``."""
    work, cache = SCRATCH, out / "cache"
    shutil.rmtree(work, ignore_errors=True)
    cache.mkdir(parents=True)
    shutil.copytree(Path(flexshaft).resolve().parents[2] / "examples", work / "examples")
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
    shutil.move(work, out / "work")


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
            steady = [
                n
                for n in changed
                if n in x["files"] and n in y["files"] and x["files"][n][1] == y["files"][n][1]
            ]
            if steady:
                notes.append("  files (volatile only): " + ", ".join(steady))
            if len(steady) < len(changed):
                notes.append("  files differ: " + ", ".join(n for n in changed if n not in steady))
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
