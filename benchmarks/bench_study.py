"""The whole test-bench study in one command: `flexshaft study`, cold and warm.

What it measures: the whole process (interpreter start, imports, the three CAD set-ups sliced
from geometry, every stage, the report) for examples/testbench_study.toml:

- cold: an empty section cache (a fresh FLEXSHAFT_CACHE_DIR) and a new output folder;
- warm: the same command again into the same folder (nothing changed: every stage's stored
  result stands), best of 3.

Targets (issue 21): cold under 30 s on a 2-core machine, warm under 5 s and at most 0.25x cold.
Run it idle, and with both cores loaded (`python benchmarks/busy.py -- python benchmarks/bench_study.py`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "examples" / "testbench_study.toml"


def run(out: Path, cache: str) -> float:
    env = {**os.environ, "FLEXSHAFT_CACHE_DIR": cache}
    t = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "flexshaft", "study", str(STUDY), "-o", str(out)],
        check=True,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - t


def main() -> None:
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "study"
        cold = run(out, cache)
        warm = min(run(out, cache) for _ in range(3))
    ok_cold = "met" if cold < 30 else "NOT met"
    ok_warm = "met" if warm < 5 and warm <= 0.25 * cold else "NOT met"
    print(f"flexshaft study {STUDY.name}: cold {cold:6.2f} s (target < 30 s: {ok_cold})")
    print(
        f"{'':>{len('flexshaft study ' + STUDY.name)}}  warm {warm:6.2f} s (target < 5 s and <= 0.25x cold: "
        f"{ok_warm}; warm/cold {warm / cold:.3f})"
    )


if __name__ == "__main__":
    main()
