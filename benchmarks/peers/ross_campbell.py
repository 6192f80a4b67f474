"""ROSS peer run: whirl frequencies of a spinning uniform shaft on two bearings at given speeds.

Run with the peers virtualenv (benchmarks/setup_peers.sh), never flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/ross_campbell.py < rotor.json

Input (stdin, JSON): {"L": m, "D": m, "n": elements, "k_bearing": N/m, "count": modes,
"E": Pa, "nu": -, "rho": kg/m³, "speeds": [rad/s, ...], optional "disk": {"node": i, "m": kg,
"Id": kg·m², "Ip": kg·m²}}. Builds n equal ``ShaftElement``
(Timoshenko: shear effects, rotary inertia, gyroscopic) and two isotropic undamped
``BearingElement`` at the ends, and for each speed runs ``run_modal(speed)``. Prints one JSON line
{"frequencies_hz": [[the lowest `count` non-zero natural frequencies wn/2π at speed 1], ...]}.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import ross as rs


def main() -> None:
    d = json.load(sys.stdin)
    steel = rs.Material(name="steel_peer", rho=d["rho"], E=d["E"], Poisson=d["nu"])
    le = d["L"] / d["n"]
    shaft = [
        rs.ShaftElement(
            L=le,
            idl=0.0,
            odl=d["D"],
            material=steel,
            shear_effects=True,
            rotary_inertia=True,
            gyroscopic=True,
        )
        for _ in range(d["n"])
    ]
    k = d["k_bearing"]
    bearings = [rs.BearingElement(n=0, kxx=k, cxx=0.0), rs.BearingElement(n=d["n"], kxx=k, cxx=0.0)]
    disks = []
    if d.get("disk"):
        k_ = d["disk"]
        disks = [rs.DiskElement(n=int(k_["node"]), m=k_["m"], Id=k_["Id"], Ip=k_["Ip"])]
    rotor = rs.Rotor(shaft, disks, bearings)
    out = []
    for speed in d["speeds"]:
        modal = rotor.run_modal(speed=float(speed), num_modes=2 * d["count"] + 8)
        wn = np.sort(np.asarray(modal.wn)) / (2 * np.pi)
        out.append(wn[wn > 1e-3][: d["count"]].tolist())
    print(json.dumps({"frequencies_hz": out}))


if __name__ == "__main__":
    main()
