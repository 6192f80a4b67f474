"""The README's pictures of the test-bench study's report, drawn by the study itself.

    python examples/study_pictures.py docs      # regenerate docs/testbench_study_*.png (the README shows)
    python examples/study_pictures.py           # into a temporary folder (what the tests run)

runs examples/testbench_study.toml (into a temporary folder, ~20 s) and writes three of its
report's figures into the folder given: the flange torque's FRF, the spectrogram of the speed
ramp with its order lines, and the Campbell diagram, all of Customer 1 under per-part damping -
and, where a Chromium is installed (Debian's chromium package), a view of the report itself as
the browser shows it: the top of Customer 1's section (testbench_study_report.png).
"""

from __future__ import annotations

import re
import shutil
import subprocess
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


#: The report's view: which set-up's section (its anchor), the browser window's width and height, px.
REPORT_VIEW = ("setup-2", 1000, 1300)


def report_view(page: Path, path: Path) -> Path | None:
    """The report as headless Chromium draws it, from the top of a set-up's section; None without one."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        return None
    anchor, width, height = REPORT_VIEW
    flags = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    # Where the section starts: a copy of the page with a script that puts it in the title.
    probe = page.with_name("probe.html")
    probe.write_text(
        page.read_text().replace(
            "</body>",
            "<script>window.addEventListener('load', () => { document.title = 'top:' + Math.round("
            f"document.getElementById('{anchor}').getBoundingClientRect().top); }});</script></body>",
        )
    )
    dom = subprocess.run(
        [*flags, f"--window-size={width},{height}", "--dump-dom", probe.as_uri()],
        capture_output=True,
        text=True,
        timeout=180,
    ).stdout
    probe.unlink()
    top = int(re.search(r"<title>top:(\d+)</title>", dom).group(1))
    # A window tall enough to hold the view (a fragment URL left headless Chromium's capture blank).
    shot = page.with_name("shot.png")
    subprocess.run(
        [*flags, f"--window-size={width},{top + height}", f"--screenshot={shot}", page.as_uri()],
        capture_output=True,
        timeout=180,
        check=True,
    )
    import matplotlib.image as mpimg
    import numpy as np

    image = mpimg.imread(shot)[max(top - 16, 0) : top - 16 + height]
    image = np.pad(image, ((0, 0), (16, 0), (0, 0)), constant_values=1.0)  # the page's left margin
    mpimg.imsave(path, image)
    return path


def main(folder: str) -> list[Path]:
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with tempfile.TemporaryDirectory() as tmp:
        run = fs.run_study(HERE / "testbench_study.toml", Path(tmp) / "bench")
        if run.exit_code:
            raise SystemExit(f"the study failed: {[s.error for s in run.failed]}")
        view = report_view(run.folder / "index.html", out / "testbench_study_report.png")
        if view is None:
            print("no chromium on this machine: the report's view is not drawn", file=sys.stderr)
        else:
            written.append(view)
    for name, (stage, figure) in PICTURES.items():
        path = out / name
        path.write_bytes(run.figures[stage][figure])
        written.append(path)
    return written


if __name__ == "__main__":
    for p in main(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="flexshaft-pictures-")):
        print(p)
