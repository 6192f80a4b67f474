"""
The one-command study and its report
====================================

:download:`testbench_study.toml <../../examples/testbench_study.toml>` is the whole test-bench study
in one file: the three set-ups (:download:`without_dut_cad.toml <../../examples/without_dut_cad.toml>`,
:download:`customer1_cad.toml <../../examples/customer1_cad.toml>`,
:download:`customer2_cad.toml <../../examples/customer2_cad.toml>`), their modes under both damping
assumptions, responses, time runs and their spectra, the Campbell diagram, the staged calibration to
the measured frequency ratios (:download:`calibration/testbench_cad.toml
<../../examples/calibration/testbench_cad.toml>`), mode views and flexible-body exports.
``flexshaft study examples/testbench_study.toml -o bench`` runs it into ``bench/``, with an HTML
report (``bench/index.html``); so does :func:`flexshaft.run_study`, here, into a temporary folder
(~20 s on a 2-core machine).

Shown are three of the report's figures, all of Customer 1 under per-part damping - the flange
torque's FRF, the spectrogram of the speed ramp with its order lines, and the Campbell diagram - and,
where a Chromium is installed (Debian's chromium package), the report itself as the browser shows
it: the top of Customer 1's section. These are the documentation's pictures of the study:

.. code-block:: text

    python examples/study_pictures.py docs      # regenerate docs/testbench_study_*.png
    python examples/study_pictures.py           # into a temporary folder, removed at the end
"""

import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import flexshaft as fs

# The model files beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
# The pictures go to the folder given, or to a temporary one removed when the script ends.
scratch = None if len(sys.argv) > 1 else tempfile.TemporaryDirectory(prefix="flexshaft-pictures-")
OUT = Path(sys.argv[1]) if scratch is None else Path(scratch.name)
OUT.mkdir(parents=True, exist_ok=True)

# %%
# The study
# ---------
# Every stage of the study file, in order; a stage that fails is reported and the others go on (the
# exit code says whether any failed). The study's folder is temporary here: removed when the script
# ends.

bench = tempfile.TemporaryDirectory(prefix="flexshaft-study-")
run = fs.run_study(HERE / "testbench_study.toml", Path(bench.name) / "bench")
if run.exit_code:
    raise SystemExit(f"the study failed: {[s.error for s in run.failed]}")

# %%
# Three of the report's figures
# -----------------------------
# ``run.figures`` holds every figure of the report as PNG bytes, by stage and name.

#: The pictures: file name -> (stage, figure) in ``run.figures``.
PICTURES = {
    "testbench_study_frf.png": ("frf/Customer 1", "frf 1 parts"),
    "testbench_study_spectrogram.png": (
        "simulate/Customer 1/speed ramp",
        "spectrogram torque:part 2: torque flange parts",
    ),
    "testbench_study_campbell.png": ("campbell/Customer 1", "campbell"),
}


def picture(name: str) -> Path:
    """Write the report's figure of that file name (:data:`PICTURES`) into ``OUT``."""
    stage, figure = PICTURES[name]
    path = OUT / name
    path.write_bytes(run.figures[stage][figure])
    return path


# sphinx_gallery_thumbnail_number = 1
frf = picture("testbench_study_frf.png")
spectrogram = picture("testbench_study_spectrogram.png")
campbell = picture("testbench_study_campbell.png")

# %%
# The report in the browser
# -------------------------
# Headless Chromium draws the report page from the top of Customer 1's section.


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


view = report_view(run.folder / "index.html", OUT / "testbench_study_report.png")
if view is None:
    print("no chromium on this machine: the report's view is not drawn", file=sys.stderr)

# %%
# The files written:

written = [view, frf, spectrogram, campbell]
print("\n".join(str(p) for p in written if p is not None))
