"""openTorsion peer run for benchmarks/bench_twist.py: modes of a given element chain.

Run with the peers virtualenv (benchmarks/setup_peers.sh), never flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/opentorsion_chain.py < chain.json

Input (stdin, JSON): {"k": [N·m/rad per element], "j": [kg·m² per element], "count": n}.
Each element becomes an openTorsion ``Shaft`` with ``I = j/6`` (its mass matrix is
I·[[2, 1], [1, 2]], so this is the consistent j·[[1/3, 1/6], [1/6, 1/3]]). Prints one JSON
line {"seconds": t, "frequencies_hz": [...]} with one frequency per conjugate pair.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
import opentorsion as ot


def main() -> None:
    data = json.load(sys.stdin)
    k, j, count = data["k"], data["j"], data["count"]
    t0 = time.perf_counter()
    assembly = ot.Assembly([ot.Shaft(i, i + 1, k=k[i], I=j[i] / 6.0) for i in range(len(k))])
    omegas, _, _ = assembly.modal_analysis()
    seconds = time.perf_counter() - t0
    w = np.sort(np.abs(np.asarray(omegas)))
    f = w[::2][:count] / (2 * np.pi)  # conjugate pairs: keep one of each
    print(json.dumps({"seconds": seconds, "frequencies_hz": f.tolist()}))


if __name__ == "__main__":
    main()
