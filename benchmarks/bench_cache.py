"""Disk cache of section tables: `flexshaft modes` on a CAD model, cold (empty cache) and warm.

What it measures: the whole process (interpreter start, imports, model file, slicing or the cache,
modal analysis) for examples/customer1_cad.toml and examples/ptss_full.toml, best of 3 warm runs
against one cold run in a fresh cache folder. Target (issue 12): warm under a quarter of cold.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(model: Path, cache: str) -> float:
    env = {**os.environ, "FLEXSHAFT_CACHE_DIR": cache}
    t = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "flexshaft.cli", "modes", str(model)],
        check=True,
        env=env,
        stdout=subprocess.DEVNULL,
    )
    return time.perf_counter() - t


def main() -> None:
    for name in ("customer1_cad.toml", "ptss_full.toml"):
        with tempfile.TemporaryDirectory() as cache:
            cold = run(ROOT / "examples" / name, cache)
            warm = min(run(ROOT / "examples" / name, cache) for _ in range(3))
        verdict = "met" if warm < cold / 4 else "NOT met"
        print(
            f"{name:<20} cold {cold:6.2f} s   warm {warm:6.2f} s   warm/cold {warm / cold:.3f}   "
            f"target < 0.25: {verdict}"
        )


if __name__ == "__main__":
    main()
