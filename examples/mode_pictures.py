"""The README's pictures: the test bench's modes along the shaft and in 3D.

    python examples/mode_pictures.py docs      # regenerate docs/*.png (the README shows them)
    python examples/mode_pictures.py           # into a temporary folder (what the tests run)

Customer 1 with parts 1, 2 and 4 from geometry (examples/customer1_cad.toml): its second mode
(the first one with flexibility in the steel shafts) in 3D, coloured by shear stress, and the
first four elastic modes as twist along the shaft.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import flexshaft as fs

HERE = Path(__file__).resolve().parent


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    modes = fs.modal_analysis(fs.load_model(HERE / "customer1_cad.toml"), 8)
    modes.view(2, out / "customer1_cad_mode2.png", colour="stress", overwrite=True)
    modes.plot(modes=[1, 2, 3, 4]).savefig(out / "customer1_cad_shapes.png")
    for p in sorted(out.glob("customer1_cad_*.png")):
        print(p)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="flexshaft-pictures-")))
