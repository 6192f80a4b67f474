"""The test bench with its PTSS parts as solids, against its 1D model: each mode's shift, part by part.

``customer1_solid.toml`` is ``customer1_cad.toml`` with ``fe = "solid"`` on parts 1, 2 and 4: each
part's solid, meshed into curved 10-node tetrahedra, enters the chain as a Craig-Bampton body of
the solid instead of 1D torsion elements on its section table. This script

1. runs the twist test on both models: each part's torsional stiffness, 1D (its sections in
   series) and solid (its mesh, end faces tied rigidly) - the solid is softer where the stress
   spreads past a diameter step, a hub or a flange;
2. computes both models' modes and explains each mode's shift by the parts' stiffness changes and
   their shares of the mode's strain energy: to first order
   δf/f = ½ Σ_p E_p·(k_p,solid / k_p,1D − 1), E_p the part's share in the 1D mode (the parts'
   inertias agree to ~1e-4, the solid's curved mesh against the table's ρ·Ip).

Run: ``python examples/solid_testbench.py`` (needs ``pip install 'flexshaft[solid]'``; the first run
meshes the three parts and reduces them - about 1.5 minutes from cold; the meshes and the
reductions are cached, so the next runs take seconds).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import flexshaft as fs
from flexshaft.analysis.convergence import meshed_for_own_range

HERE = Path(__file__).parent
MODES = 3  # the measured ones: the first three elastic modes


def main() -> None:
    one_d = meshed_for_own_range(fs.load_model(HERE / "customer1_cad.toml"))
    solid = meshed_for_own_range(fs.load_model(HERE / "customer1_solid.toml"))

    k1 = {p.name: p.stiffness for p in fs.twist_test(one_d).parts}
    twist = fs.twist_test(solid)
    ks = {p.name: p.stiffness for p in twist.parts}
    print("twist test: each part's torsional stiffness, N·m/rad")
    print(f"{'part':<8} {'1D':>13} {'solid':>13} {'solid/1D':>9}  elements")
    for p in twist.parts:
        print(
            f"{p.name:<8} {k1[p.name]:13.6e} {ks[p.name]:13.6e} {ks[p.name] / k1[p.name]:9.5f}  {p.elements}"
        )

    r1, rs = fs.modal_analysis(one_d), fs.modal_analysis(solid)
    names = r1.model.component_names
    change = np.array([ks.get(n, k1.get(n, 1.0)) / k1.get(n, 1.0) - 1.0 for n in names])
    energy = r1.strain_energy_fractions()
    e1, es = np.flatnonzero(~r1.rigid)[:MODES], np.flatnonzero(~rs.rigid)[:MODES]
    print()
    print("modes: the solid model against the 1D, and the shift the parts' stiffness explains")
    print(f"{'mode':<5} {'1D Hz':>9} {'solid Hz':>9} {'δf/f':>9} {'explained':>9}  by part (½·E_p·δk_p/k_p)")
    for k, (i, j) in enumerate(zip(e1, es), start=1):
        f1, fs_ = r1.frequencies_hz[i], rs.frequencies_hz[j]
        parts = 0.5 * energy[i] * change
        by = ", ".join(f"{n} {100 * v:+.2f} %" for n, v in zip(names, parts) if abs(v) > 5e-5)
        print(f"{k:<5} {f1:9.3f} {fs_:9.3f} {100 * (fs_ / f1 - 1):+8.3f}% {100 * parts.sum():+8.3f}%  {by}")


if __name__ == "__main__":
    main()
