"""
The test bench's modes in pictures
==================================

Customer 1 with parts 1, 2 and 4 from geometry
(:download:`customer1_cad.toml <../../examples/customer1_cad.toml>`), meshed for its range of
interest (``[model] max_hz``, as every command does): its second mode (the first one with
flexibility in the steel shafts) in 3D, coloured by shear stress; the first four elastic modes as
twist along the shaft; the twist test; and, where a Chromium is installed (Debian's chromium
package), the browser viewer of the same mode as headless Chromium draws it (software WebGL), held
a quarter period into its animation (the largest deflection, as the still).

These are the documentation's pictures of the modes:

.. code-block:: text

    python examples/mode_pictures.py docs      # regenerate docs/customer1_cad_*.png
    python examples/mode_pictures.py           # into a temporary folder, removed at the end
"""

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import flexshaft as fs
from flexshaft.analysis.convergence import mesh_for_range

# The model files beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
# The pictures go to the folder given, or to a temporary one removed when the script ends.
scratch = None if len(sys.argv) > 1 else tempfile.TemporaryDirectory(prefix="flexshaft-pictures-")
OUT = Path(sys.argv[1]) if scratch is None else Path(scratch.name)
OUT.mkdir(parents=True, exist_ok=True)

# %%
# The modes
# ---------
# The model file's CAD parts are sliced into section tables (kept in the disk cache: the first run
# builds and slices the parts), then meshed so that every mode below ``max_hz`` is within 1 %.

d = fs.load_model(HERE / "customer1_cad.toml")
modes = fs.modal_analysis(mesh_for_range(d, d.max_hz).drivetrain, 8)
print(modes.table(max_hz=d.max_hz))

# %%
# Mode 2 in 3D
# ------------
# The parts' own surfaces (from their CAD solids) turned by the mode, coloured by the shear stress
# at 1 mrad peak station rotation (pyvista, off-screen).

# sphinx_gallery_thumbnail_number = 1
still = modes.view(2, OUT / "customer1_cad_mode2.png", colour="stress", overwrite=True)

# %%
# Along the shaft
# ---------------
# The first four elastic modes' twist against the position along the shaft, the components
# shaded; then the twist test: the bench clamped at the motor and turned by 1000 N·m at the
# generator, each part's twist and stiffness.

shapes = modes.plot(modes=[1, 2, 3, 4])
shapes.savefig(OUT / "customer1_cad_shapes.png")
twist = fs.twist_test(d, 1000.0).plot()
twist.savefig(OUT / "customer1_cad_twist.png")

# %%
# In the browser viewer
# ---------------------
# ``flexshaft view MODEL --mode 2 -o m2.html`` writes a page that turns the mode in the browser
# (self-contained, nothing fetched). Headless Chromium draws it here, a quarter period in.


def viewer_picture(modes, path: Path) -> Path | None:
    """The browser viewer (``flexshaft view ... -o x.html``) as headless Chromium shows it, or None."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        page = modes.view(2, Path(tmp) / "m2.html", colour="stress")
        subprocess.run(
            [
                browser,
                "--headless",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--hide-scrollbars",
                "--window-size=1120,720",
                "--virtual-time-budget=200",
                f"--screenshot={path}",
                page.as_uri() + "#t=0.5&paused",
            ],
            capture_output=True,
            timeout=180,
            check=True,
        )
    return path


view = viewer_picture(modes, OUT / "customer1_cad_viewer.png")
if view is None:
    print("no chromium on this machine: the viewer's picture is not drawn", file=sys.stderr)

# %%
# The files written:

written = [still, OUT / "customer1_cad_shapes.png", OUT / "customer1_cad_twist.png", view]
print("\n".join(str(p) for p in written if p is not None))
