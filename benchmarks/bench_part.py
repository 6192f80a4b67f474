"""Full 6-DOF part benchmark: flexshaft Timoshenko part models against ROSS on the same rotor.

What it measures
----------------
A uniform steel shaft (E 210 GPa, ν 0.29, ρ 7850 kg/m³), L = 1 m, D = 0.1 m (L/D = 10),
on two isotropic bearings of 1e9 N/m at its ends (a stiff journal bearing), in equal
Timoshenko elements with Cowper's shear factor and rotary inertia, consistent mass:

1. the same rotor in ROSS 2.3.0 (``ShaftElement`` + ``BearingElement``, ``run_modal`` at
   speed 0, its own virtualenv) and in flexshaft (``part_model`` + ``part_modes``), 50 and
   200 elements: time (build + modal) and the lowest 10 non-zero frequencies of each
   (bending pairs, torsion, axial), with their largest relative difference (target 0.5 %);
2. flexshaft alone at 10 000 elements (60 006 DOFs), lowest 20 modes: target under 2 s.
   ROSS is not run there: it builds dense matrices (minutes and several GB at 1 000).

Run: ``.venv/bin/python benchmarks/bench_part.py`` (ROSS needs ``benchmarks/setup_peers.sh``).
Timings are printed, never asserted.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path

import numpy as np

import flexshaft as fs
from flexshaft.analysis.modal import part_modes
from flexshaft.parts.model import part_model
from flexshaft.sections import table_from_segments

HERE = Path(__file__).resolve().parent
PEER_PY = HERE / ".venv-peers" / "bin" / "python"
L, D, KB = 1.0, 0.1, 1e9


def flexshaft_run(n, count):
    t0 = time.perf_counter()
    part = part_model(
        table_from_segments([{"length": L, "od": D}]), fs.STEEL, dofs="full", max_element_length=L / n
    )
    modes = part_modes(part, count + 2, bearings={0: KB, part.n_nodes - 1: KB})
    seconds = time.perf_counter() - t0
    return seconds, modes.frequencies_hz[~modes.rigid][:count]


def ross_run(n, count):
    payload = json.dumps(
        {
            "L": L,
            "D": D,
            "n": n,
            "k_bearing": KB,
            "count": count,
            "E": fs.STEEL.E,
            "nu": fs.STEEL.nu,
            "rho": fs.STEEL.rho,
        }
    )
    out = subprocess.run(
        [str(PEER_PY), str(HERE / "peers" / "ross_rotor.py")],
        input=payload,
        capture_output=True,
        text=True,
        check=True,
        timeout=900,
    )
    doc = json.loads(out.stdout.strip().splitlines()[-1])
    return doc["seconds"], np.asarray(doc["frequencies_hz"])


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    count = 10
    for n in (50, 200):
        t_fs, f_fs = min((flexshaft_run(n, count) for _ in range(3)), key=lambda r: r[0])
        print(f"\n{n} elements ({6 * (n + 1)} DOFs), lowest {count} non-zero frequencies, Hz:")
        print("  flexshaft", " ".join(f"{f:8.2f}" for f in f_fs), f"  {t_fs:.3f} s")
        if PEER_PY.exists():
            t_ro, f_ro = ross_run(n, count)
            print("  ROSS     ", " ".join(f"{f:8.2f}" for f in f_ro), f"  {t_ro:.3f} s")
            print(
                f"  max |relative difference| {np.max(np.abs(f_fs / f_ro - 1)):.1e} (target 0.5 %); "
                f"time flexshaft / ROSS = {t_fs / t_ro:.4f}"
            )
        else:
            print("  (ROSS skipped: run benchmarks/setup_peers.sh)")
    t_big, f_big = min((flexshaft_run(10_000, 20) for _ in range(3)), key=lambda r: r[0])
    print(
        f"\n10 000 elements (60 006 DOFs), lowest 20 modes: {t_big:.2f} s   target < 2 s: "
        f"{'met' if t_big < 2 else 'NOT met'}; first {f_big[0]:.4f} Hz"
    )


if __name__ == "__main__":
    main()
