"""
Your own shaft from CAD
=======================

A stepped shaft with a keyway drawn in a few lines of Python (``geometry.parts``, build123d),
sliced into its section table, written as STEP and STL, and used through a model file that names the
STEP file - the way a part drawn in any CAD system enters a flexshaft model.

Every dimension is in metres. The files go into the folder given, or into a temporary folder
removed when the script ends; they are written with ``overwrite=True``, so the script runs again and
again (without it, flexshaft never replaces a file). The model file is written by the script itself
(below), beside the STEP file it names.

.. code-block:: text

    python examples/cad_shaft.py            # into a temporary folder
    python examples/cad_shaft.py OUT_DIR    # my_shaft.step, my_shaft.stl and my_shaft.toml kept in OUT_DIR
"""

import sys
import tempfile
from pathlib import Path

import flexshaft as fs
from flexshaft.sections import table_from_segments
from geometry import parts
from geometry.cadio import write_step, write_stl
from geometry.slicing import sections

# The files go to the folder given, or to a temporary one removed when the script ends.
scratch = None if len(sys.argv) > 1 else tempfile.TemporaryDirectory(prefix="flexshaft-cad-")
OUT = Path(sys.argv[1]) if scratch is None else Path(scratch.name)
OUT.mkdir(parents=True, exist_ok=True)

# %%
# The part
# --------
# 300 mm at 160 mm diameter, then 400 mm at 120 mm bored to 40 mm, a 5 mm fillet at the shoulder,
# and a 36 mm wide, 10 mm deep keyway 200 mm long in the larger diameter.

segments = [parts.Segment(0.3, 0.16), parts.Segment(0.4, 0.12, id=0.04)]
my = parts.stepped_shaft(segments, fillet=0.005)
my = parts.keyway(my, width=0.036, depth=0.01, length=0.2, x_start=0.05, diameter=0.16)

# %%
# Its section table
# -----------------
# Sliced where its section changes: the torsional stiffness of its intervals in series and its
# axial inertia, beside the same shaft without keyway and fillet from closed forms (the keyway
# takes a little of the stiffness; the fillet adds a little). The volume error checks the table
# against the solid's own volume.

steel = fs.STEEL
table = sections(my, name="my shaft", nu=steel.nu)
plain = table_from_segments([{"length": 0.3, "od": 0.16}, {"length": 0.4, "od": 0.12, "id": 0.04}])
k, k_plain = table.torsional_stiffness(steel.G), plain.torsional_stiffness(steel.G)
print(f"torsional stiffness {k:.5e} N·m/rad (plain stepped shaft: {k_plain:.5e}, {k / k_plain - 1:+.2%})")
print(f"axial inertia       {table.axial_inertia(steel.rho):.5f} kg·m²")
print(f"volume error        {table.meta['mass_check'].volume_error:+.1e}")

# %%
# As files
# --------
# STEP keeps the exact geometry; STL is faceted (here 50 µm chords). Either can be a model's part.

step = write_step(my, OUT / "my_shaft.step", overwrite=True)
stl = write_stl(my, OUT / "my_shaft.stl", tolerance=5e-5, overwrite=True)
print("written:", step.name, stl.name)

# %%
# In a model file
# ---------------
# A ``cad`` part names its geometry - here the STEP file beside the model file - and its material;
# a motor and a load on either side make the chain. ``flexshaft modes my_shaft.toml`` reads the same
# file.

model = OUT / "my_shaft.toml"
model.write_text(
    """[model]
name = "my shaft"

[[chain]]
name = "motor"
type = "rigid"
inertia = 1.2          # kg·m²

[[chain]]
name = "my shaft"
type = "cad"
geometry = "my_shaft.step"     # its unit is in the file; an STL would need unit = "mm"
material = "steel"
damping_ratio = 0.005

[[chain]]
name = "load"
type = "rigid"
inertia = 0.8          # kg·m²
""",
    encoding="utf-8",
)
result = fs.modal_analysis(fs.load_model(model))
for i in range(1, 3):
    print(f"mode {i}: {result.frequencies_hz[i]:9.2f} Hz")

# %%
# The first elastic mode along the chain, and in 3D on the part's own surface, coloured by the
# shear stress.

# sphinx_gallery_thumbnail_number = 2
shapes = result.plot(modes=[1, 2])
still = result.view(1, OUT / "my_shaft_mode1.png", colour="stress", overwrite=True)
