"""The README's pictures: the test bench's modes along the shaft, in 3D, and in the browser viewer.

    python examples/mode_pictures.py docs      # regenerate docs/*.png (the README shows them)
    python examples/mode_pictures.py           # into a temporary folder (what the tests run)

Customer 1 with parts 1, 2 and 4 from geometry (examples/customer1_cad.toml), meshed for its
range of interest (``[model] max_hz``, as every command does): its second mode (the first one
with flexibility in the steel shafts) in 3D, coloured by shear stress; the first four elastic
modes as twist along the shaft; the twist test; and, where a Chromium is installed (Debian's
chromium package), the browser viewer of the same modes as headless Chromium draws it (software
WebGL), held a quarter period into its animation (the largest deflection, as the still).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import flexshaft as fs
from flexshaft.analysis.convergence import mesh_for_range

HERE = Path(__file__).resolve().parent


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


def main(out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    d = fs.load_model(HERE / "customer1_cad.toml")
    modes = fs.modal_analysis(mesh_for_range(d, d.max_hz).drivetrain, 8)
    written = [
        modes.view(2, out / "customer1_cad_mode2.png", colour="stress", overwrite=True),
    ]
    shapes = out / "customer1_cad_shapes.png"
    modes.plot(modes=[1, 2, 3, 4]).savefig(shapes)
    twist = out / "customer1_cad_twist.png"
    fs.twist_test(d, 1000.0).plot().savefig(twist)
    written += [shapes, twist]
    view = viewer_picture(modes, out / "customer1_cad_viewer.png")
    if view is None:
        print("no chromium on this machine: the viewer's picture is not drawn", file=sys.stderr)
    else:
        written.append(view)
    return written


if __name__ == "__main__":
    for p in main(
        Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="flexshaft-pictures-"))
    ):
        print(p)
