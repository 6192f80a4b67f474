"""openTorsion peer run for benchmarks/bench_modes.py: modes of the uniform benchmark shaft.

Run it with the peers virtualenv (see benchmarks/setup_peers.sh), never with flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/opentorsion_modes.py N COUNT [--repeat R]

It builds the free-free steel shaft of bench_modes.py (G = 81 GPa, rho = 7850 kg/m3,
D = 0.2 m, L = 4 m) as N equal openTorsion ``Shaft`` elements, times the build
(``Assembly``) plus ``Assembly.modal_analysis()`` with ``time.perf_counter`` (best of R
runs), and prints one JSON line:

    {"elements": N, "seconds": t, "frequencies_hz": [rigid, f1, ..., f_{COUNT-1}]}

Inertia convention: openTorsion's shaft mass matrix is ``I * [[2, 1], [1, 2]]``, so the
consistent-inertia element of inertia j_e (j_e * [[1/3, 1/6], [1/6, 1/3]], as flexshaft
uses) takes ``I = j_e / 6``; passing ``I = j_e`` would give six times the inertia.

``modal_analysis`` solves the dense 2N x 2N first-order (state-space) eigenproblem, so
every mode comes back twice (the pair +-i*omega); this script keeps one of each pair. The
rigid-body mode is a double zero eigenvalue there and comes back as round-off, not 0.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np
import opentorsion as ot

G = 81e9  # shear modulus, Pa
RHO = 7850.0  # density, kg/m3
DIAMETER = 0.2  # m
LENGTH = 4.0  # m


def shaft_properties() -> tuple[float, float]:
    """End-to-end stiffness (N·m/rad) and inertia (kg·m²) of the benchmark shaft."""
    ip = math.pi * DIAMETER**4 / 32.0
    return G * ip / LENGTH, RHO * ip * LENGTH


def modes(n: int, count: int) -> np.ndarray:
    """The ``count`` lowest undamped frequencies (Hz) of the shaft cut into ``n`` elements."""
    k, j = shaft_properties()
    k_e, j_e = k * n, j / n
    shafts = [ot.Shaft(i, i + 1, k=k_e, I=j_e / 6.0) for i in range(n)]
    assembly = ot.Assembly(shafts)
    wn, _wd, _zeta = assembly.modal_analysis()
    # wn is |eigenvalue| sorted ascending; the two members of each conjugate pair
    # (and the two round-off roots of the rigid mode) are adjacent: keep one of each.
    wn = np.sort(np.asarray(wn, dtype=float))[: 2 * count].reshape(-1, 2)
    elastic = wn[1:]
    if np.any(np.abs(elastic[:, 1] - elastic[:, 0]) > 1e-6 * elastic[:, 1]):
        raise SystemExit("opentorsion_modes: eigenvalues do not come in conjugate pairs")
    return wn[:, 0] / (2.0 * math.pi)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("elements", type=int, help="number of shaft elements")
    p.add_argument("count", type=int, help="how many of the lowest modes, rigid included")
    p.add_argument("--repeat", type=int, default=1, help="time the best of this many runs")
    args = p.parse_args()
    best = math.inf
    freqs = np.zeros(0)
    for _ in range(max(1, args.repeat)):
        t0 = time.perf_counter()
        freqs = modes(args.elements, args.count)
        best = min(best, time.perf_counter() - t0)
    print(
        json.dumps({"elements": args.elements, "seconds": best, "frequencies_hz": [float(f) for f in freqs]})
    )


if __name__ == "__main__":
    main()
