"""FRF benchmark: flexshaft's ``frequency_response`` against one stacked solve and python-control.

What it measures
----------------
H(f) = C (i2πf − A)⁻¹ B + D of a modal state space (``state_space``: input the motor torque,
outputs the generator speed and the coupling torque), three ways on the same system and the
same frequencies, the calls interleaved (a, b, c, a, b, c, ...: every contender sees the same
drift in machine load), best of several, all on one BLAS thread (``threadpool_limits(1)``):

- flexshaft: ``frequency_response(system, f)``;
- stacked: one ``np.linalg.solve`` of the whole stack of modal matrices Ω² − ω²I + iω·Dm (one
  m × m matrix per frequency) written out here, and y = (Cq + iω·Cv) η + D - what the modal form
  costs with nothing but numpy;
- python-control 0.10: ``control.frequency_response(system.to_control(), 2πf)`` (without slycot it
  solves the 2m × 2m first-order system once per frequency).

Systems: Customer 1 (examples/customer1.toml, 5 modes) at 10 000 frequencies, 0.1 - 1000 Hz;
the 6-DOF bench line of ``bench_statespace.py`` (two Craig–Bampton shafts from ~50 000 DOFs,
all 83 modes kept) at 2 000 frequencies, 0.5 - 2000 Hz. Both have a full modal damping block
(shaft modal damping, a coupling dashpot), so flexshaft takes its stacked-solve path; Customer 1
once more with its damping written per mode (Dm = diag(2ξω), the model's own ratios) times the
path without a solve. ``--ptss N`` adds the 6-DOF examples/ptss_full.toml (1 159 modes) at N
frequencies: its matrices take 21 MB per frequency, flexshaft solves them 3 at a time (64 MB
chunks), python-control takes about 1 s per frequency.

Targets from the issue: flexshaft at most 1.0x the stacked solve and at most 0.5x python-control,
equal to 1e-12. "Equal" is read relative to each response's peak: far above the last mode |H|
falls to 1e-9 of its peak, where no double-precision evaluation keeps 1e-12 of |H| itself (on
Customer 1, against a 40-digit solve of the same A, B, C: flexshaft within 1.8e-12 of |H| at every
frequency checked, python-control's 2m × 2m first-order solve within 2.5e-10); the pointwise
relative difference is printed too.
Run: ``.venv/bin/python benchmarks/bench_frf.py`` (about 30 s; ``--ptss 16`` a minute more).
Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import flexshaft as fs

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def interleaved(fns: dict, repeats: int) -> tuple[dict, dict]:
    """Best wall time (s) of each of ``fns`` and its last result, the calls interleaved."""
    best = dict.fromkeys(fns, math.inf)
    out = {}
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            out[name] = fn()
            best[name] = min(best[name], time.perf_counter() - t0)
    return best, out


def stacked(ss: fs.StateSpace, f: np.ndarray) -> np.ndarray:
    """H by one stacked solve of the modal matrices Ω² + s·Dm + s²I, s = i2πf: (f, outputs, inputs)."""
    m = ss.A.shape[0] // 2
    s = 2j * np.pi * f
    M = -ss.A[m:, :m] - s[:, None, None] * ss.A[m:, m:] + (s * s)[:, None, None] * np.eye(m)
    Bq = ss.B[m:]
    eta = np.linalg.solve(M, np.broadcast_to(Bq, (f.size, *Bq.shape)))
    return (ss.C[:, :m] + s[:, None, None] * ss.C[:, m:]) @ eta + ss.D


def compare(label: str, ss: fs.StateSpace, f: np.ndarray, repeats: int) -> None:
    import control

    sys = ss.to_control()
    m = ss.A.shape[0] // 2
    Dm = -ss.A[m:, m:]
    kind = "diagonal" if np.count_nonzero(Dm) == np.count_nonzero(np.diag(Dm)) else "full"
    fns = {
        "flexshaft": lambda: fs.frequency_response(ss, f).H,
        "stacked": lambda: stacked(ss, f),
        "python-control": lambda: np.moveaxis(
            np.asarray(control.frequency_response(sys, 2 * np.pi * f).complex).reshape(
                ss.C.shape[0], ss.B.shape[1], f.size
            ),
            -1,
            0,
        ),
    }
    with threadpool_limits(limits=1):
        t, H = interleaved(fns, repeats)
    print(
        f"\n{label}: {m} modes ({2 * m} states, damping block {kind}), "
        f"{ss.C.shape[0]} outputs x {ss.B.shape[1]} input, {f.size} frequencies, best of {repeats}"
    )
    ours = H["flexshaft"]
    peak = np.max(np.abs(ours), axis=0)  # each output's peak over the frequencies
    for name in fns:
        line = f"  {name:15s} {t[name] * 1e3:10.2f} ms"
        if name != "flexshaft":
            d = np.abs(ours - H[name])
            line += (
                f"   flexshaft/{name} {t['flexshaft'] / t[name]:5.2f}x"
                f"   max diff / peak {np.max(d / peak):.1e}"
                f"   max pointwise rel {np.max(d / np.abs(H[name])):.1e}"
            )
        print(line)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=7, help="runs to take the best of (Customer 1: 3x)")
    ap.add_argument("--ptss", type=int, default=0, metavar="N", help="add ptss_full.toml at N frequencies")
    args = ap.parse_args(argv)
    try:
        import control
    except ImportError:
        raise SystemExit("needs python-control: .venv/bin/pip install -e '.[test]'") from None
    print(
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; numpy {np.__version__}, "
        f"python-control {control.__version__}; one BLAS thread for everyone"
    )
    outputs = ["speed:generator", "torque:part 3"]

    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    compare(
        "Customer 1",
        fs.state_space(r, ["motor"], outputs),
        np.linspace(0.1, 1000.0, 10_000),
        3 * args.repeats,
    )

    # The same line with its modal damping written per mode, 2ξω on the diagonal (the model's own
    # damping ratios): the path without a solve.
    ss = fs.state_space(r, ["motor"], outputs)
    m = ss.A.shape[0] // 2
    A = ss.A.copy()
    A[m:, m:] = -np.diag(2 * r.damping_ratios * r.omega)
    compare(
        "Customer 1, modal damping diagonal",
        replace(ss, A=A),
        np.linspace(0.1, 1000.0, 10_000),
        3 * args.repeats,
    )

    from bench_statespace import bench_line

    model = fs.assemble(bench_line())
    r = fs.modal_analysis(model, count=model.n_dof)
    compare(
        f"6-DOF bench line ({model.n_dof} coordinates, reduced)",
        fs.state_space(r, ["motor"], ["speed:gen", "torque:c"]),
        np.linspace(0.5, 2000.0, 2000),
        args.repeats,
    )

    if args.ptss:
        model = fs.assemble(fs.load_model(EXAMPLES / "ptss_full.toml"))
        r = fs.modal_analysis(model, count=model.n_dof)
        compare(
            "PTSS full 6-DOF (examples/ptss_full.toml)",
            fs.state_space(r, ["motor"], outputs),
            np.linspace(0.5, 2000.0, args.ptss),
            2,
        )


if __name__ == "__main__":
    main()
