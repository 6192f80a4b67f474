"""Craig–Bampton benchmark: a 20 000-element 6-DOF part reduced to its 2 end nodes + 20 modes.

What it measures
----------------
A uniform steel shaft (L = 2 m, D = 0.2 m) in 20 000 Timoshenko elements (120 006 DOFs):
``part_model`` (assembly) and ``craig_bampton(modes=20)`` (sparse LU for the 12 constraint
modes, banded shift-invert Lanczos for the fixed-interface modes, the 12 residual vectors,
reduced K/M/C, the orthonormalised basis), best of 3; also without residual vectors.
Target from the issue: under 2 s for the reduction.
Peer: the same reduction written by hand with plain scipy (``splu`` + ``eigsh`` in
shift-invert mode with its default shift 0), timed the same way; the fixed-interface
frequencies of both are compared.

Run: ``.venv/bin/python benchmarks/bench_reduce.py``. Timings are printed, never asserted.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse.linalg as spla
from timing import best

import flexshaft as fs
from flexshaft.parts.model import part_model
from flexshaft.reduction import cb_check, craig_bampton
from flexshaft.sections import table_from_segments


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    table = table_from_segments([{"length": 2.0, "od": 0.2}])
    t_asm, pm = best(lambda: part_model(table, fs.STEEL, dofs="full", max_element_length=2.0 / 20000))
    t_cb, body = best(lambda: craig_bampton(pm, modes=20))
    t_plain, _ = best(lambda: craig_bampton(pm, modes=20, residual=False))
    check = cb_check(body, pm)

    def by_hand():
        b = np.r_[pm.node_dofs(0), pm.node_dofs(pm.n_nodes - 1)]
        i = np.setdiff1d(np.arange(pm.n_dofs), b)
        K, M = pm.K.tocsr(), pm.M.tocsr()
        Kii = K[i][:, i].tocsc()
        psi = -spla.splu(Kii).solve(K[i][:, b].toarray())
        lam, phi = spla.eigsh(Kii, k=20, M=M[i][:, i], sigma=0.0, which="LM")
        return psi, np.sqrt(np.sort(lam)) / (2 * np.pi)

    t_hand, (_, f_hand) = best(by_hand)
    print(f"\npart model: {pm.n_dofs} DOFs, assembly {t_asm:.2f} s")
    print(
        f"flexshaft craig_bampton(modes=20): {t_cb:.2f} s   target < 2 s: {'met' if t_cb < 2 else 'NOT met'}"
    )
    print(f"  of which residual vectors: {t_cb - t_plain:.2f} s ({body.n_residual} of them)")
    print(
        f"plain scipy (splu + eigsh sigma=0, no reduced matrices): {t_hand:.2f} s   ratio {t_cb / t_hand:.2f}"
    )
    kept = body.fixed_interface_hz[: body.n_modes - body.n_residual]
    print(f"fixed-interface frequencies agree to {np.max(np.abs(kept / f_hand - 1)):.1e}")
    print(
        f"check: rigid-body mass {check.rigid_mass_error:.1e}, static condensation {check.static_error:.1e}"
    )


if __name__ == "__main__":
    main()
