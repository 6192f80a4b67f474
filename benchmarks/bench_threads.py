"""Does a second BLAS thread pay for the kinds of work flexshaft does? Idle and busy, one thread and two.

What it measures
----------------
Each kind of linear algebra flexshaft's analyses spend their time in, at the sizes they meet, timed
with OpenBLAS limited to 1 thread and to 2 (``threadpoolctl``), on an idle machine and with every
core kept busy by spinning processes (benchmarks/busy.py starts and stops them):

- dense symmetric eigen-solve (``scipy.linalg.eigh``, K and M): a part's modal damping, a small
  model's modes, a reduced body - 300, 1 000 and 2 000 DOFs (flexshaft's dense limit is a few
  thousand);
- dense non-symmetric eigenvalues (``scipy.linalg.eig``) of a 210 × 210 state matrix: damped modes,
  closed-loop poles, the simulation's eigenbasis;
- a stacked complex solve (``np.linalg.solve``, 500 systems of 60 × 60): the frequency response;
- a dense matrix product 2 000 × 2 000: a Craig–Bampton projection;
- sparse: the LU factorisation of a 6-DOF Timoshenko part of 20 000 elements (``splu``) and the
  lowest 20 modes of a 100 000-element torsion chain (shift-invert ``eigsh``).

For each it prints the best of ``--repeat`` runs (s) the four ways and the gain of the second thread
idle (1-thread / 2-thread time, > 1: two are faster) and busy. flexshaft's thread policy
(flexshaft/system/threads.py) takes a second thread only where it gains idle and does not lose busy.

Run: ``.venv/bin/python benchmarks/bench_threads.py`` (about a minute).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from busy import busy
from scipy.sparse.linalg import eigsh, splu
from threadpoolctl import threadpool_limits

import flexshaft as fs


def spd_pair(n: int, seed: int = 0):
    """A symmetric positive definite pair (K, M) of size n, well conditioned."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    B = rng.standard_normal((n, n))
    M = B @ B.T / n + np.eye(n)
    return K, M


def work() -> dict:
    """name -> a function doing one unit of that work."""
    jobs = {}
    for n in (300, 1000, 2000):
        K, M = spd_pair(n)
        jobs[f"dense eigh {n}"] = lambda K=K, M=M: sla.eigh(K, M)
    A = np.random.default_rng(1).standard_normal((210, 210))
    jobs["dense eig 210 (state matrix)"] = lambda: sla.eig(A)
    rng = np.random.default_rng(2)
    Z = rng.standard_normal((500, 60, 60)) + 1j * rng.standard_normal((500, 60, 60)) + 60 * np.eye(60)
    R = rng.standard_normal((500, 60, 2)) + 0j
    jobs["stacked solve 500 x 60 (FRF)"] = lambda: np.linalg.solve(Z, R)
    P = rng.standard_normal((2000, 2000))
    jobs["matmul 2000 (projection)"] = lambda: P @ P
    # a 6-DOF part and a torsion chain, built by flexshaft itself
    from flexshaft.sections import table_from_segments

    table = table_from_segments([{"length": 2.0, "od": 0.2}], name="bench")
    part = fs.part_model(table, fs.STEEL, max_element_length=2.0 / 20_000)
    Kp = sp.csc_matrix(part.K + 1e3 * part.M)  # shifted: nonsingular, as a shift-invert factorises it
    jobs["sparse LU 6-DOF part, 120 k DOFs"] = lambda: splu(Kp)
    n = 100_000
    k, j = 1e7 * n, 1.0 / n
    k_main = np.r_[k, np.full(n - 1, 2 * k), k]
    Kc = sp.diags([np.full(n, -k), k_main, np.full(n, -k)], [-1, 0, 1], format="csc")
    m_main = np.r_[j / 3, np.full(n - 1, 2 * j / 3), j / 3]
    Mc = sp.diags([np.full(n, j / 6), m_main, np.full(n, j / 6)], [-1, 0, 1], format="csc")
    v0 = np.random.default_rng(0).standard_normal(n + 1)
    # shift: a tenth of λ1 = π²·1e7 (rad/s)² below 0 (K itself is singular: the rigid-body mode)
    jobs["sparse eigsh 20 modes, 100 k chain"] = lambda: eigsh(Kc, k=20, M=Mc, sigma=-1e7, v0=v0)
    return jobs


def timed(fn, threads: int, repeat: int) -> float:
    best = float("inf")
    with threadpool_limits(limits=threads):
        for _ in range(repeat):
            t0 = time.perf_counter()
            fn()
            best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    jobs = work()
    print(f"{os.cpu_count()} cores; best of {args.repeat}; seconds; gain = 1-thread time / 2-thread time")
    print(f"{'work':<36} {'idle 1':>8} {'idle 2':>8} {'gain':>6} {'busy 1':>8} {'busy 2':>8} {'gain':>6}")
    for name, fn in jobs.items():
        fn()  # warm-up: first-call costs (page faults, library loading) belong to nobody
        idle = [timed(fn, t, args.repeat) for t in (1, 2)]
        with busy():
            loaded = [timed(fn, t, args.repeat) for t in (1, 2)]
        print(
            f"{name:<36} {idle[0]:8.3f} {idle[1]:8.3f} {idle[0] / idle[1]:6.2f} "
            f"{loaded[0]:8.3f} {loaded[1]:8.3f} {loaded[0] / loaded[1]:6.2f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
