"""ROSS peer run for benchmarks/bench_part.py: lateral modes of a uniform shaft on two bearings.

Run with the peers virtualenv (benchmarks/setup_peers.sh), never flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/ross_rotor.py < rotor.json

Input (stdin, JSON): {"L": m, "D": m, "n": elements, "k_bearing": N/m, "count": modes,
"E": Pa, "nu": -, "rho": kg/m³}. Builds n equal ``ShaftElement`` (Timoshenko: shear effects
with Cowper's factor, rotary inertia; gyroscopics irrelevant at speed 0) and two isotropic
``BearingElement`` at the ends, times ``Rotor`` + ``run_modal(speed=0)`` and prints one
JSON line {"seconds": t, "frequencies_hz": [...]} (ROSS's undamped natural frequencies wn).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
import ross as rs


def build(d: dict):
    """The ROSS rotor of the input: n equal Timoshenko shaft elements, two isotropic undamped bearings
    at the ends and, if ``d["disk"]`` = {"node", "m", "Id", "Ip"}, a disc (ross_campbell.py uses it too)."""
    steel = rs.Material(name="steel_bench", rho=d["rho"], E=d["E"], Poisson=d["nu"])
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
    disk = d.get("disk")
    disks = [rs.DiskElement(n=int(disk["node"]), m=disk["m"], Id=disk["Id"], Ip=disk["Ip"])] if disk else []
    return rs.Rotor(shaft, disks, bearings)


def main() -> None:
    d = json.load(sys.stdin)
    t0 = time.perf_counter()
    rotor = build(d)
    modal = rotor.run_modal(speed=0.0, num_modes=2 * d["count"])
    seconds = time.perf_counter() - t0
    wn = np.sort(np.asarray(modal.wn)) / (2 * np.pi)
    print(json.dumps({"seconds": seconds, "frequencies_hz": wn[: d["count"]].tolist()}))


if __name__ == "__main__":
    main()
