"""
The test bench with solid parts, against its 1D model
=====================================================

.. note::

   Not run when these pages are built: the first run meshes the bench's three PTSS parts into
   solids (~490 000 DOFs in all) and reduces them - about 1.5 minutes from a cold cache on a 2-core
   machine (the meshes and the reductions are then cached, so the next runs take seconds). Run it
   yourself: ``python examples/solid_testbench.py`` (needs ``pip install 'flexshaft[solid]'``).

:download:`customer1_solid.toml <../../examples/customer1_solid.toml>` is
:download:`customer1_cad.toml <../../examples/customer1_cad.toml>` with ``fe = "solid"`` on parts 1,
2 and 4: each part's solid, meshed into curved 10-node tetrahedra, enters the chain as a
Craig-Bampton body of the solid instead of 1D torsion elements on its section table. This script

1. runs the twist test on both models: each part's torsional stiffness, 1D (its sections in
   series) and solid (its mesh, end faces tied rigidly) - the solid is softer where the stress
   spreads past a diameter step, a hub or a flange;
2. computes both models' modes and explains each mode's shift by the parts' stiffness changes and
   their shares of the mode's strain energy: to first order
   δf/f = ½ Σ_p E_p·(k_p,solid / k_p,1D − 1), E_p the part's share in the 1D mode (the parts'
   inertias agree to ~1e-4, the solid's curved mesh against the table's ρ·Ip).
"""

from pathlib import Path

import numpy as np

import flexshaft as fs
from flexshaft.analysis.convergence import meshed_for_own_range

# The model files beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
MODES = 3  # the measured ones: the first three elastic modes

# %%
# Both models
# -----------
# Each meshed for its own range of interest (``[model] max_hz``): the 1D parts by the wavelength
# rule and the mesh check, the solid parts at the sizes their model file gives.

one_d = meshed_for_own_range(fs.load_model(HERE / "customer1_cad.toml"))
solid = meshed_for_own_range(fs.load_model(HERE / "customer1_solid.toml"))

# %%
# The twist test, part by part
# ----------------------------
# Clamped at the motor, turned at the generator: each part's torsional stiffness in both models.

k1 = {p.name: p.stiffness for p in fs.twist_test(one_d).parts}
twist = fs.twist_test(solid)
ks = {p.name: p.stiffness for p in twist.parts}
print("twist test: each part's torsional stiffness, N·m/rad")
print(f"{'part':<8} {'1D':>13} {'solid':>13} {'solid/1D':>9}  elements")
for p in twist.parts:
    print(f"{p.name:<8} {k1[p.name]:13.6e} {ks[p.name]:13.6e} {ks[p.name] / k1[p.name]:9.5f}  {p.elements}")

# %%
# The modes, and what explains their shift
# ----------------------------------------
# Each mode's shift from the 1D model to the solid one, beside the first-order estimate from the
# parts' stiffness changes weighted by their shares of the 1D mode's strain energy.

r1, rs = fs.modal_analysis(one_d), fs.modal_analysis(solid)
names = r1.model.component_names
change = np.array([ks.get(n, k1.get(n, 1.0)) / k1.get(n, 1.0) - 1.0 for n in names])
energy = r1.strain_energy_fractions()
e1, es = np.flatnonzero(~r1.rigid)[:MODES], np.flatnonzero(~rs.rigid)[:MODES]
print("modes: the solid model against the 1D, and the shift the parts' stiffness explains")
print(f"{'mode':<5} {'1D Hz':>9} {'solid Hz':>9} {'δf/f':>9} {'explained':>9}  by part (½·E_p·δk_p/k_p)")
for k, (i, j) in enumerate(zip(e1, es), start=1):
    f1, fs_ = r1.frequencies_hz[i], rs.frequencies_hz[j]
    parts = 0.5 * energy[i] * change
    by = ", ".join(f"{n} {100 * v:+.2f} %" for n, v in zip(names, parts) if abs(v) > 5e-5)
    print(f"{k:<5} {f1:9.3f} {fs_:9.3f} {100 * (fs_ / f1 - 1):+8.3f}% {100 * parts.sum():+8.3f}%  {by}")
