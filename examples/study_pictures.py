"""The README's pictures of the test-bench study's report, drawn by the study itself.

    python examples/study_pictures.py docs      # regenerate docs/testbench_study_*.png (the README shows)
    python examples/study_pictures.py           # into a temporary folder (what the tests run)

runs examples/testbench_study.toml (into a temporary folder, ~25 s) and writes three of its
report's figures into the folder given: the flange torque's FRF, the spectrogram of the speed
ramp with its order lines, and the Campbell diagram, all of Customer 1 under per-part damping.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import flexshaft as fs

HERE = Path(__file__).resolve().parent
PICTURES = {
    "testbench_study_frf.png": ("frf/Customer 1", "frf 1 parts"),
    "testbench_study_spectrogram.png": (
        "simulate/Customer 1/speed ramp",
        "spectrogram torque:part 2: torque flange parts",
    ),
    "testbench_study_campbell.png": ("campbell/Customer 1", "campbell"),
}


def main(folder: str) -> list[Path]:
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        run = fs.run_study(HERE / "testbench_study.toml", Path(tmp) / "bench")
    if run.exit_code:
        raise SystemExit(f"the study failed: {[s.error for s in run.failed]}")
    written = []
    for name, (stage, figure) in PICTURES.items():
        path = out / name
        path.write_bytes(run.figures[stage][figure])
        written.append(path)
    return written


if __name__ == "__main__":
    for p in main(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="flexshaft-pictures-")):
        print(p)
