"""ROSS peer run: whirl frequencies of a spinning uniform shaft on two bearings at given speeds.

Run with the peers virtualenv (benchmarks/setup_peers.sh), never flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/ross_campbell.py < rotor.json

Input (stdin, JSON): {"L": m, "D": m, "n": elements, "k_bearing": N/m, "count": modes,
"E": Pa, "nu": -, "rho": kg/m³, "speeds": [rad/s, ...], optional "disk": {"node": i, "m": kg,
"Id": kg·m², "Ip": kg·m²}}. Builds n equal ``ShaftElement``
(Timoshenko: shear effects, rotary inertia, gyroscopic) and two isotropic undamped
``BearingElement`` at the ends, and for each speed runs ``run_modal(speed)``. Prints one JSON line
{"frequencies_hz": [[the lowest `count` non-zero natural frequencies wn/2π at speed 1], ...]}.
A JSON list of such rotors gives a list of such results on one line (one ROSS import for all: it
takes seconds). The rotor is ross_rotor.py's ``build``.
"""

from __future__ import annotations

import json
import sys

import numpy as np
from ross_rotor import build  # the same rotor as the bench: this folder is on sys.path


def whirl(d: dict) -> dict:
    rotor = build(d)
    out = []
    for speed in d["speeds"]:
        modal = rotor.run_modal(speed=float(speed), num_modes=2 * d["count"] + 8)
        wn = np.sort(np.asarray(modal.wn)) / (2 * np.pi)
        out.append(wn[wn > 1e-3][: d["count"]].tolist())
    return {"frequencies_hz": out}


def main() -> None:
    d = json.load(sys.stdin)
    print(json.dumps([whirl(r) for r in d] if isinstance(d, list) else whirl(d)))


if __name__ == "__main__":
    main()
