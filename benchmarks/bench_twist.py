"""Twist-test and section-mesh benchmark: flexshaft against a plain scipy solve and openTorsion.

What it measures
----------------
A stepped, partly hollow steel shaft (PTSS part 4-like: 0.17 m of Ø0.34, 0.66 m of
Ø0.26 / 0.08 bore, 0.17 m of Ø0.34) given by its segments, meshed from its section table.

1. Twist test, 10 000 elements (max element length 0.1 mm): flexshaft ``twist_test``
   (assembly, static solve, per-part stiffness, a 5-torque ramp) against the same
   tridiagonal solve written by hand in scipy (``sparse.diags`` + ``spsolve``, one
   torque). Target from the issue: under 0.2 s. Both are checked against the exact
   series stiffness.
2. Torsional frequencies of the free shaft at 200 elements: flexshaft against openTorsion
   0.3.2 on the same element chain (same k and j per element, consistent inertia), in its
   own virtualenv; agreement should be round-off, and both within 0.5 % of a 20 000-
   element flexshaft reference.

Run: ``.venv/bin/python benchmarks/bench_twist.py`` (openTorsion columns need
``benchmarks/setup_peers.sh`` first). Timings are printed, never asserted.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import flexshaft as fs
from flexshaft.analysis.twist import twist_test
from flexshaft.sections import table_from_segments

HERE = Path(__file__).resolve().parent
PEER_PY = HERE / ".venv-peers" / "bin" / "python"
SEGMENTS = [
    {"length": 0.17, "od": 0.34},
    {"length": 0.66, "od": 0.26, "id": 0.08},
    {"length": 0.17, "od": 0.34},
]


def shaft(max_len):
    table = table_from_segments(SEGMENTS)
    return fs.Shaft.from_sections("part 4", table, fs.STEEL, max_element_length=max_len)


def best(fn, repeat=5):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    exact = 1.0 / sum(
        s["length"] / (fs.STEEL.G * math.pi * (s["od"] ** 4 - s.get("id", 0.0) ** 4) / 32) for s in SEGMENTS
    )
    s = shaft(1e-4)
    chain = fs.Drivetrain("bench", [fs.Rigid("motor", 58.1), s])
    n_el = s.torsion_mesh().n_elements
    t_fs, r = best(lambda: twist_test(chain, 86e3))
    k_el = s.element_properties()[0]

    def by_hand():
        n = k_el.size + 1
        main_d = np.zeros(n)
        main_d[:-1] += k_el
        main_d[1:] += k_el
        K = sp.diags([main_d, -k_el, -k_el], [0, 1, -1], format="csc")[1:, 1:]
        f = np.zeros(n - 1)
        f[-1] = 86e3
        theta = spla.spsolve(K, f)
        return 86e3 / theta[-1]

    t_sp, k_sp = best(by_hand)
    print(f"\ntwist test, {n_el} elements:")
    print(
        f"  flexshaft twist_test (assembly + solve + 5-torque ramp) {t_fs:.4f} s, stiffness error "
        f"{r.parts[0].stiffness / exact - 1:+.1e}   target < 0.2 s: {'met' if t_fs < 0.2 else 'NOT met'}"
    )
    print(
        f"  plain scipy spsolve (one torque)                       {t_sp:.4f} s, stiffness error "
        f"{k_sp / exact - 1:+.1e}"
    )
    print(f"  flexshaft / scipy = {t_fs / t_sp:.2f}")

    ref = fs.modal_analysis(fs.Drivetrain("r", [shaft(1.0 / 20000)]), count=6, damped=False).frequencies_hz[
        1:
    ]
    s200 = shaft(1.0 / 200)
    t_m, res = best(lambda: fs.modal_analysis(fs.Drivetrain("b", [s200]), count=6, damped=False), repeat=3)
    f_fs = res.frequencies_hz[1:]
    print(f"\nfree shaft, {s200.torsion_mesh().n_elements} elements, modes 1-5 (Hz):")
    print("  flexshaft   ", " ".join(f"{f:9.3f}" for f in f_fs), f"  ({t_m:.4f} s)")
    print("  reference   ", " ".join(f"{f:9.3f}" for f in ref), "  (flexshaft, 20 000 elements)")
    if PEER_PY.exists():
        k, j, _ = s200.element_properties()
        payload = json.dumps({"k": k.tolist(), "j": j.tolist(), "count": 6})
        out = subprocess.run(
            [str(PEER_PY), str(HERE / "peers" / "opentorsion_chain.py")],
            input=payload,
            capture_output=True,
            text=True,
            check=True,
        )
        peer = json.loads(out.stdout)
        f_ot = np.asarray(peer["frequencies_hz"][1:6])
        print("  openTorsion ", " ".join(f"{f:9.3f}" for f in f_ot), f"  ({peer['seconds']:.4f} s)")
        print(
            f"  flexshaft vs openTorsion: max |rel diff| {np.max(np.abs(f_fs / f_ot - 1)):.1e}; "
            f"both vs reference: {np.max(np.abs(f_fs / ref - 1)):.1e}, {np.max(np.abs(f_ot / ref - 1)):.1e} "
            "(target 0.5 %)"
        )
        print(f"  time flexshaft / openTorsion = {t_m / peer['seconds']:.3f}")
    else:
        print("  (openTorsion skipped: run benchmarks/setup_peers.sh)")


if __name__ == "__main__":
    main()
