"""``import flexshaft`` time, warm, against its 0.3 s target.

What it measures
----------------
``python -X importtime -c "import flexshaft"`` in a fresh interpreter, best of 5 runs after
one warm-up run (so the byte-code and the OS file cache are warm). Reported:

- the cumulative import time of ``flexshaft`` itself (the ``-X importtime`` line for the
  top-level package: everything ``import flexshaft`` pulls in), against the 0.3 s target;
- the whole process (interpreter start-up included), for context;
- the slowest modules it imported, so a regression names its cause.

The tests do not time anything (tests/test_layout.py checks the structural cause instead:
``import flexshaft`` loads none of its submodules and no numpy or scipy).

Run: ``.venv/bin/python benchmarks/bench_import.py`` (``--runs N`` to change the count).
Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 0.3
LINE = re.compile(r"^import time:\s+(\d+)\s+\|\s+(\d+)\s+\|(\s*)(\S+)\s*$")


def one_run(module: str) -> tuple[float, float, list[tuple[int, int, str]]]:
    """(cumulative import seconds of `module`, process wall seconds, [(self us, cumulative us, name)])."""
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", f"import {module}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    wall = time.perf_counter() - t0
    rows = []  # (self us, cumulative us, depth, name), children printed before their parent
    for line in proc.stderr.splitlines():
        m = LINE.match(line)
        if m:
            rows.append((int(m.group(1)), int(m.group(2)), len(m.group(3)), m.group(4)))
    tops = [i for i, r in enumerate(rows) if r[3] == module]
    if not tops:
        raise SystemExit(f"no -X importtime line for {module!r}:\n{proc.stderr}")
    i = tops[-1]
    j = i
    while j > 0 and rows[j - 1][2] > rows[i][2]:
        j -= 1  # the modules `module` imported
    return rows[i][1] / 1e6, wall, [(s, c, n) for s, c, _, n in rows[j : i + 1]]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--module", default="flexshaft")
    args = ap.parse_args(argv)

    one_run(args.module)  # warm-up: byte-code written, files cached
    runs = [one_run(args.module) for _ in range(args.runs)]
    best_import, _, rows = min(runs, key=lambda r: r[0])
    best_wall = min(r[1] for r in runs)

    print(f"python {sys.version.split()[0]}, {sys.executable}")
    print(
        f"import {args.module} (warm, best of {args.runs}, -X importtime cumulative): "
        f"{best_import * 1e3:.1f} ms"
    )
    verdict = "met" if best_import < TARGET_S else "MISSED"
    print(f"  target < {TARGET_S:.1f} s: {verdict}")
    print(f"  whole process (interpreter start-up included): {best_wall * 1e3:.1f} ms")
    print(f"  modules it imported (not there before), slowest first: {len(rows)}")
    for self_us, cum_us, name in sorted(rows, reverse=True)[:8]:
        print(f"    {self_us / 1e3:8.2f} ms self {cum_us / 1e3:8.2f} ms cumulative  {name}")
    heavy = sorted({n.split(".")[0] for _, _, n in rows} & {"numpy", "scipy", "matplotlib", "build123d"})
    print(f"  heavy packages loaded: {', '.join(heavy) or 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
