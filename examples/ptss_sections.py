"""From parameters to stiffness: the test-bench PTSS parts as build123d solids, sliced into section tables.

Builds PTSS parts 1, 2 and 4 of ``geometry.parts.testbench`` (plausible dimensions, not the
bench's drawings), slices each into a section table, prints its torsional stiffness
(Σ L/(G·J) in series), axial inertia (ρ·Σ Ip·L) and the check of the table against the
solid's own volume and inertia, then writes part 4 as STEP and STL, reads both back and
slices them again. Run: ``python examples/ptss_sections.py [OUTPUT_DIR]`` (default: a
temporary directory).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import flexshaft as fs
from geometry.cadio import read_cad, write_step, write_stl
from geometry.parts import testbench
from geometry.slicing import sections


def main(out_dir: Path) -> None:
    steel = fs.STEEL
    parts = testbench.ptss()
    print(
        f"{'part':<14} {'length m':>9} {'stiffness N·m/rad':>18} {'inertia kg·m²':>14} {'mass kg':>9} "
        f"{'volume err':>11}"
    )
    tables = {}
    for name, part in parts.items():
        t = sections(part, name=name, nu=steel.nu)
        tables[name] = t
        check = t.meta["mass_check"]
        print(
            f"{name:<14} {t.length:9.3f} {t.torsional_stiffness(steel.G):18.6e} "
            f"{t.axial_inertia(steel.rho):14.4f} {t.mass(steel.rho):9.1f} {check.volume_error:+11.1e}"
        )

    # Part 4 through files: STEP keeps the exact B-rep, STL is faceted (50 µm chords, 0.1 rad).
    step = write_step(parts["part 4"], out_dir / "ptss_part4.step", overwrite=True)
    stl = write_stl(
        parts["part 4"], out_dir / "ptss_part4.stl", tolerance=5e-5, angular_tolerance=0.1, overwrite=True
    )
    k_ref = tables["part 4"].torsional_stiffness(steel.G)
    for path in (step, stl):
        t = sections(read_cad(path), name=path.name, nu=steel.nu)
        k = t.torsional_stiffness(steel.G)
        print(f"{path.name:<14} stiffness {k:.6e} N·m/rad ({k / k_ref - 1:+.1e} against the parametric part)")

    # The same parts as flexshaft shafts in a chain with the published motor and generator.
    chain = fs.Drivetrain(
        "PTSS from geometry",
        [
            fs.Rigid("motor", inertia=58.10),
            *(fs.Shaft.from_sections(n, t, steel, damping_ratio=0.0053) for n, t in tables.items()),
            fs.Rigid("generator", inertia=6.67),
        ],
    )
    modes = fs.modal_analysis(chain)
    print("lowest torsional frequencies, Hz:", " ".join(f"{f:.2f}" for f in modes.frequencies_hz[:4]))


if __name__ == "__main__":
    if len(sys.argv) > 1:
        main(Path(sys.argv[1]))
    else:
        with tempfile.TemporaryDirectory() as tmp:
            main(Path(tmp))
