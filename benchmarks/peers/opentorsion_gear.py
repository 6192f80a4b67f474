"""openTorsion peer run: undamped frequencies of a geared torsional chain described in JSON.

Run it with the peers virtualenv (see benchmarks/setup_peers.sh), never with flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/opentorsion_gear.py < model.json

The JSON names openTorsion's own elements, node numbers and all:

    {"shafts": [[nl, nr, k, I], ...],          # ot.Shaft(nl, nr, k=k, I=I)
     "disks": [[node, I], ...],                # ot.Disk(node, I=I)
     "gears": [[node, I, R, parent], ...],     # ot.Gear; parent: index into "gears" or null
     "elastic_gears": [[node, I, R, k, parent], ...]}   # ot.ElasticGear (k: mesh stiffness)

openTorsion conventions to mind when describing a flexshaft model: its shaft mass matrix is
``I * [[2, 1], [1, 2]]`` (a consistent element of inertia j takes I = j/6); a gear pair ties
``R_parent·θ_parent + R_child·θ_child = 0`` (the child turns the other way, R_child/R_parent
times slower), eliminated by openTorsion's constraint transformation; an elastic gear's mesh
stiffness k acts on θ_parent + (R_child/R_parent)·θ_child.

It prints one JSON line: {"frequencies_hz": [...]} - the square roots of the generalised
eigenvalues of openTorsion's assembled (and, with gears, transformed) K and M, ascending,
the rigid-body mode as round-off near 0.
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import opentorsion as ot
import scipy.linalg as sla


def build(spec: dict):
    shafts = [ot.Shaft(int(nl), int(nr), k=float(k), I=float(i)) for nl, nr, k, i in spec.get("shafts", [])]
    disks = [ot.Disk(int(node), I=float(i)) for node, i in spec.get("disks", [])]
    gears: list = []
    for node, i, r, parent in spec.get("gears", []):
        gears.append(ot.Gear(int(node), float(i), float(r), parent=None if parent is None else gears[parent]))
    elastic: list = []
    for node, i, r, k, parent in spec.get("elastic_gears", []):
        elastic.append(
            ot.ElasticGear(
                int(node), float(i), float(r), k=k, c=0.0, parent=None if parent is None else elastic[parent]
            )
        )
    return ot.Assembly(
        shaft_elements=shafts or None,
        disk_elements=disks or None,
        gear_elements=gears or None,
        elastic_gear_elements=elastic or None,
    )


def main() -> None:
    spec = json.load(sys.stdin)
    assembly = build(spec)
    lam = sla.eigh(
        np.asarray(assembly.K, dtype=float), np.asarray(assembly.M, dtype=float), eigvals_only=True
    )
    freqs = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * math.pi)
    print(json.dumps({"frequencies_hz": [float(f) for f in np.sort(freqs)]}))


if __name__ == "__main__":
    main()
