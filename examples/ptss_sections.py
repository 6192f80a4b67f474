"""
From parameters to stiffness: CAD parts sliced into section tables
==================================================================

The test bench's PTSS parts 1, 2 and 4 of ``geometry.parts.testbench`` (plausible dimensions, not
the bench's drawings) as build123d solids, each sliced into a section table: its torsional
stiffness (Σ L/(G·J) in series), axial inertia (ρ·Σ Ip·L) and the check of the table against the
solid's own volume. Part 4 then goes through STEP and STL files and is sliced again; the three
tables become shafts in a chain with the published motor and generator.

The parts are Python functions, so there is no model file to download (the model file that names
them is :download:`customer1_cad.toml <../../examples/customer1_cad.toml>`). Needs the CAD kernel
(build123d, installed with flexshaft).

.. code-block:: text

    python examples/ptss_sections.py              # the files into a temporary folder, removed at the end
    python examples/ptss_sections.py OUT_DIR      # ptss_part4.step and .stl kept in OUT_DIR
"""

import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import flexshaft as fs
from geometry.cadio import read_cad, write_step, write_stl
from geometry.parts import testbench
from geometry.slicing import sections

# The files go to the folder given, or to a temporary one removed when the script ends.
scratch = None if len(sys.argv) > 1 else tempfile.TemporaryDirectory(prefix="flexshaft-ptss-")
OUT = Path(sys.argv[1]) if scratch is None else Path(scratch.name)

# %%
# Each part sliced
# ----------------
# ``sections`` cuts the solid across its axis where its section changes and computes each interval's
# properties (closed forms for circles and rings, a warping solution elsewhere). The volume error is
# the table's volume against the solid's own: how well the slices hold the part.

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

# %%
# What the 1D model sees of each part: its torsion constant J along the axis (G·J is the
# torsional rigidity of each interval; the flanges and bolt circles show as the steps).

profile, axes = plt.subplots(len(tables), 1, figsize=(7.5, 6.0), sharey=True, layout="constrained")
for ax, (name, t) in zip(axes, tables.items()):
    ax.stairs(t.j, t.x, baseline=None)
    ax.set_yscale("log")
    ax.set_title(name, fontsize=10)
    ax.set_ylabel("J, m⁴")
axes[-1].set_xlabel("x along the part, m")

# %%
# Through files
# -------------
# Part 4 as STEP (the exact B-rep) and STL (faceted: 50 µm chords, 0.1 rad), each read back and
# sliced again; the stiffness against the parametric part's says what each format keeps.

step = write_step(parts["part 4"], OUT / "ptss_part4.step", overwrite=True)
stl = write_stl(
    parts["part 4"], OUT / "ptss_part4.stl", tolerance=5e-5, angular_tolerance=0.1, overwrite=True
)
k_ref = tables["part 4"].torsional_stiffness(steel.G)
for path in (step, stl):
    t = sections(read_cad(path), name=path.name, nu=steel.nu)
    k = t.torsional_stiffness(steel.G)
    print(f"{path.name:<14} stiffness {k:.6e} N·m/rad ({k / k_ref - 1:+.1e} against the parametric part)")

# %%
# In a chain
# ----------
# The same tables as flexshaft shafts between the published motor and generator, and the chain's
# lowest torsional frequencies (the first is the rigid spin).

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
shapes = modes.plot(modes=[1, 2, 3])
# sphinx_gallery_thumbnail_number = 1
