"""Modal-analysis benchmark: flexshaft against a plain scipy solve and openTorsion.

What it measures
----------------
The lowest 10 modes (rigid-body mode included) of a uniform free-free steel shaft,
G = 81 GPa, rho = 7850 kg/m3, D = 0.2 m, L = 4 m, cut into 10, 1 000, 100 000 and
1 000 000 equal elements with consistent inertia. Per size, wall time with
``time.perf_counter`` (best of a few runs; one run at 1e6 elements) of

- flexshaft: ``Drivetrain`` + ``assemble`` + ``modal_analysis(count=10, damped=False)``;
- plain scipy: tridiagonal K and M from ``scipy.sparse.diags`` + ``eigsh`` in shift-invert
  mode with its default ``splu`` factorisation, the code a scipy user would write by hand;
- openTorsion 0.3.2 (dense state-space eigensolver), in its own virtualenv through a
  subprocess (benchmarks/peers/opentorsion_modes.py), up to ``--peer-max-elements``.

Accuracy: the largest relative error of modes 1..9 of each tool against the closed form
f_k = k/(2L)·sqrt(G/rho), and the agreement of flexshaft and openTorsion on the same
discrete model (same element, so they should agree to round-off, ~1e-9 or better).

It also times the whole ``flexshaft modes examples/customer1.toml`` process (best of 5)
and states the targets from the issue: 100 000 elements in under 1 s in-process and no
slower than the plain scipy solve; the CLI on the Customer 1 model in under 0.5 s.

Peak memory (``--memory-size``, default 1 000 000 elements): flexshaft and the plain scipy
solve, each in a fresh process of its own (this script again, ``--child``, started from a
small launcher: Linux carries a process's peak RSS into the children it forks), interleaved,
``--memory-runs`` times each. A child imports what the parent does (numpy, scipy, flexshaft)
and warms up the same way, so both start from the same footprint; it then solves once and
reports its wall and CPU time and its peak resident memory,
``resource.getrusage(RUSAGE_SELF).ru_maxrss``, a figure that covers everything the process
ever held - the interpreter and imports, the model or matrices, the factorisation and
ARPACK's workspace. Targets from the issue: peak memory at most 1.1x and time at most 1.0x
the plain scipy solve's. The time ratio uses the best wall time of each tool (CPU times are
printed beside it: on a busy machine they drift less).

How to run (from the repository root)
-------------------------------------
    benchmarks/setup_peers.sh              # once: openTorsion into benchmarks/.venv-peers
    .venv/bin/python benchmarks/bench_modes.py
    .venv/bin/python benchmarks/bench_modes.py --quick          # 10 and 1000 elements only
    .venv/bin/python benchmarks/bench_modes.py --sizes 10 5000 --peer-max-elements 5000
    .venv/bin/python benchmarks/bench_modes.py --memory-only              # the peak-memory part alone
    .venv/bin/python benchmarks/bench_modes.py --memory-size 1e5 --memory-runs 5

The default run takes about two minutes on two cores (the peak-memory part ~40 s of it;
``--quick`` leaves it out). Without the peers virtualenv the openTorsion columns are left
out. Timings and memory are printed, not asserted.

Run it on a quiet machine: ARPACK's dense steps go through multithreaded OpenBLAS, and
with another process busy on a two-core machine its threads stall each other, making
both the flexshaft and the scipy solve several times slower. On a shared machine
``OPENBLAS_NUM_THREADS=1`` gives steadier numbers (the header shows the load average
and the BLAS thread setting).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np
import scipy
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

import flexshaft as fs

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PEER_PYTHON = HERE / ".venv-peers" / "bin" / "python"
PEER_SCRIPT = HERE / "peers" / "opentorsion_modes.py"
CLI_MODEL = ROOT / "examples" / "customer1.toml"

G = 81e9  # shear modulus, Pa
RHO = 7850.0  # density, kg/m3
DIAMETER = 0.2  # m
LENGTH = 4.0  # m
IP = math.pi * DIAMETER**4 / 32.0  # polar second moment of area, m^4
STIFFNESS = G * IP / LENGTH  # end to end, N·m/rad
INERTIA = RHO * IP * LENGTH  # kg·m²

COUNT = 10  # modes asked for, rigid-body mode included
DEFAULT_SIZES = (10, 1_000, 100_000, 1_000_000)
QUICK_SIZES = (10, 1_000)
PEER_MAX_ELEMENTS = 1_000
PEER_TIMEOUT_S = 1800

TARGET_SIZE = 100_000
TARGET_SECONDS = 1.0
CLI_TARGET_SECONDS = 0.5
CLI_RUNS = 5
AGREE_TOL = 1e-9  # flexshaft vs openTorsion on the same discrete model

MEMORY_SIZE = 1_000_000  # elements of the peak-memory comparison
MEMORY_RUNS = 3  # fresh processes per tool (peak memory repeats to the MiB; time does not)
MEMORY_TARGET = 1.1  # peak memory, flexshaft / plain scipy, at most (the target)
TIME_TARGET = 1.0  # time, flexshaft / plain scipy, at most (the target)
CHILD_TIMEOUT_S = 600
TOOLS = {"flexshaft": "flexshaft", "scipy": "plain scipy"}

T = TypeVar("T")


def closed_form_hz(count: int) -> np.ndarray:
    """Elastic frequencies f_k = k/(2L)·sqrt(G/rho), k = 1..count, of the free-free shaft."""
    return np.arange(1, count + 1) / (2.0 * LENGTH) * math.sqrt(G / RHO)


def discretisation_estimate(n: int, mode: int) -> float:
    """Leading-order relative frequency error of linear consistent-inertia elements.

    omega_h / omega = 1 + (k·h)²/24 with k·h = mode·pi/n (asymptotic, so rough at n = 10).
    """
    return (mode * math.pi / n) ** 2 / 24.0


def repeats_for(n: int) -> int:
    """Runs to take the best of (1e6 elements: one run, a few seconds each)."""
    return 7 if n <= 100_000 else 1


def best_times(fns: list[Callable[[], T]], repeats: int) -> list[tuple[float, T]]:
    """Best wall time of each of ``fns`` and its last result, the calls interleaved.

    Interleaving (a, b, a, b, ...) exposes every tool to the same drift in machine
    load, which on a shared 2-core machine is larger than the difference measured.
    """
    best = [math.inf] * len(fns)
    out: list = [None] * len(fns)
    for _ in range(repeats):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            out[i] = fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return list(zip(best, out))


def flexshaft_modes(n: int) -> fs.ModalResult:
    """Lowest COUNT modes from flexshaft, model build included."""
    drivetrain = fs.Drivetrain(
        "bench shaft", [fs.Shaft("shaft", stiffness=STIFFNESS, inertia=INERTIA, elements=n)]
    )
    model = fs.assemble(drivetrain)
    return fs.modal_analysis(model, COUNT, damped=False)


def scipy_modes(n: int) -> np.ndarray:
    """Lowest COUNT frequencies (Hz) from a hand-written scipy solve, matrix build included."""
    k_e, j_e = STIFFNESS * n, INERTIA / n
    k_main = np.full(n + 1, 2.0 * k_e)
    k_main[[0, -1]] = k_e
    j_main = np.full(n + 1, 2.0 * j_e / 3.0)
    j_main[[0, -1]] = j_e / 3.0
    K = sp.diags([np.full(n, -k_e), k_main, np.full(n, -k_e)], [-1, 0, 1], format="csc")
    M = sp.diags([np.full(n, j_e / 6.0), j_main, np.full(n, j_e / 6.0)], [-1, 0, 1], format="csc")
    # A plain-scipy user must choose the shift: K is singular (rigid-body mode), so sigma = 0
    # is out, and a too small negative shift (e.g. -1) leaves K - sigma·M singular in floating
    # point, so splu fails with "Factor is exactly singular" (it does at 100 000 elements).
    # Take a tenth of the first elastic eigenvalue of the continuous shaft,
    # lambda1 = (pi/L)²·G/rho, below zero.
    lambda1 = (math.pi / LENGTH) ** 2 * G / RHO
    lam = eigsh(K, k=COUNT, M=M, sigma=-0.1 * lambda1, which="LM", return_eigenvectors=False)
    return np.sqrt(np.maximum(np.sort(lam), 0.0)) / (2.0 * math.pi)


def peak_rss_mib() -> float:
    """This process's peak resident memory so far, MiB (ru_maxrss: KiB on Linux, bytes on macOS)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10


def cpu_seconds() -> float:
    """User + system CPU time of this process so far, s."""
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime


def child(tool: str, n: int) -> int:
    """One solve in this (fresh) process; prints a JSON line with its time and peak memory.

    Warms up like :func:`main` (the first calls pay for lazy imports), so the
    flexshaft and the scipy child start from the same footprint, printed as
    ``before_mib``.
    """
    flexshaft_modes(10)
    scipy_modes(100)
    before = peak_rss_mib()
    c0, t0 = cpu_seconds(), time.perf_counter()
    out = flexshaft_modes(n).frequencies_hz if tool == "flexshaft" else scipy_modes(n)
    seconds, cpu = time.perf_counter() - t0, cpu_seconds() - c0
    peak = peak_rss_mib()
    record = dict(
        tool=tool,
        n=n,
        seconds=seconds,
        cpu_seconds=cpu,
        peak_mib=peak,
        before_mib=before,
        frequencies_hz=[float(f) for f in out],
    )
    print(json.dumps(record))
    return 0


@dataclass
class MemoryRun:
    """One fresh-process solve: wall and CPU time (s), peak and pre-solve resident memory (MiB)."""

    seconds: float
    cpu_seconds: float
    peak_mib: float
    before_mib: float


#: Starts the child from a small interpreter. Linux carries a process's peak RSS over into a child
#: it forks (ru_maxrss survives fork and exec), so a child of this script, once it has solved 1e6
#: elements itself, would report this script's peak; a grandchild of a small process reports its own.
LAUNCHER = "import subprocess, sys; sys.exit(subprocess.call([sys.executable] + sys.argv[1:]))"


def run_child(tool: str, n: int) -> MemoryRun:
    """Run :func:`child` in a fresh interpreter (this script, ``--child``) and read its record."""
    cmd = [sys.executable, "-c", LAUNCHER, str(Path(__file__).resolve()), "--child", tool, str(n)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=CHILD_TIMEOUT_S)
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1:] or ["(no output)"]
        raise RuntimeError(f"the {tool} child at {n} elements failed: {tail[0]}")
    rec = json.loads(proc.stdout.strip().splitlines()[-1])
    return MemoryRun(rec["seconds"], rec["cpu_seconds"], rec["peak_mib"], rec["before_mib"])


def memory_comparison(n: int, runs: int) -> dict[str, list[MemoryRun]]:
    """``runs`` fresh-process solves of each tool at ``n`` elements, interleaved (fs, scipy, fs, ...)."""
    out: dict[str, list[MemoryRun]] = {tool: [] for tool in TOOLS}
    for _ in range(runs):
        for tool in TOOLS:
            out[tool].append(run_child(tool, n))
    return out


def report_memory(n: int, runs: dict[str, list[MemoryRun]]) -> tuple[float, float, float]:
    """Print the peak-memory table; return the ratios (time, CPU time, peak memory), flexshaft / scipy.

    Time: the best run of each tool. Peak memory: the largest of each tool's
    runs (it repeats to within a MiB or two; the largest is the conservative
    figure).
    """
    count = len(runs["flexshaft"])
    print(
        f"Peak memory at {n} elements: each solve in a fresh process ({count} each, interleaved); "
        "peak RSS = getrusage(RUSAGE_SELF).ru_maxrss,"
    )
    blas_threads = os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS") or "default"
    print(
        "  the whole process: interpreter, numpy, scipy and flexshaft imported and warmed up in both;"
        f" BLAS threads {blas_threads} (flexshaft's Lanczos: one), load average {os.getloadavg()[0]:.2f}."
    )
    head = (
        f"  {'':<12} {'wall s (best)':>13} {'CPU s (best)':>12} {'peak MiB (max)':>14} "
        f"{'peak MiB (min)':>14} {'before solve MiB':>16}"
    )
    print(head)
    best = {}
    for tool, label in TOOLS.items():
        rs = runs[tool]
        best[tool] = (
            min(r.seconds for r in rs),
            min(r.cpu_seconds for r in rs),
            max(r.peak_mib for r in rs),
        )
        print(
            f"  {label:<12} {best[tool][0]:>13.3f} {best[tool][1]:>12.3f} {best[tool][2]:>14.0f} "
            f"{min(r.peak_mib for r in rs):>14.0f} {max(r.before_mib for r in rs):>16.0f}"
        )
    fs_, sp_ = best["flexshaft"], best["scipy"]
    ratios = (fs_[0] / sp_[0], fs_[1] / sp_[1], fs_[2] / sp_[2])
    print(
        f"  flexshaft / plain scipy: peak memory {ratios[2]:.2f} (target <= {MEMORY_TARGET:g}: "
        f"{verdict(ratios[2] <= MEMORY_TARGET)}), time {ratios[0]:.2f} (target <= {TIME_TARGET:g}: "
        f"{verdict(ratios[0] <= TIME_TARGET)}; CPU time {ratios[1]:.2f})"
    )
    return ratios


@dataclass
class PeerResult:
    """An openTorsion run, or why there is none."""

    seconds: float | None = None
    frequencies_hz: np.ndarray | None = None
    note: str = ""


def opentorsion_modes(n: int, max_elements: int) -> PeerResult:
    """Run the openTorsion peer script in the peers virtualenv."""
    if not PEER_PYTHON.exists():
        return PeerResult(note="n/a")
    if n > max_elements:
        return PeerResult(note="skipped")
    # Past ~100 elements a dense solve takes seconds: one run, timer noise is negligible.
    repeat = repeats_for(n) if n <= 100 else 1
    cmd = [str(PEER_PYTHON), str(PEER_SCRIPT), str(n), str(COUNT), "--repeat", str(repeat)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=PEER_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return PeerResult(note=f"timeout > {PEER_TIMEOUT_S} s")
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1:] or ["(no output)"]
        print(f"  openTorsion failed at {n} elements: {tail[0]}")
        return PeerResult(note="failed")
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return PeerResult(seconds=float(out["seconds"]), frequencies_hz=np.asarray(out["frequencies_hz"]))


def max_rel_error(freqs: np.ndarray | None, reference: np.ndarray) -> float | None:
    """Largest relative difference of the elastic modes (rigid-body mode left out)."""
    if freqs is None:
        return None
    return float(np.max(np.abs(freqs[1:] / reference[1:] - 1.0)))


def time_cli(runs: int) -> float | None:
    """Best wall time of ``flexshaft modes examples/customer1.toml`` as a whole process."""
    exe = Path(sys.executable).parent / "flexshaft"
    if not exe.exists():
        print(f"flexshaft CLI: {exe} not found (run this with the dev venv's python)")
        return None
    best = math.inf
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run([str(exe), "modes", str(CLI_MODEL)], check=True, capture_output=True)
        best = min(best, time.perf_counter() - t0)
    return best


def fmt(x: float | None, spec: str, missing: str = "-") -> str:
    """Format a number, or a placeholder when there is none."""
    return missing if x is None else format(x, spec)


def verdict(ok: bool) -> str:
    """'met' / 'NOT met'."""
    return "met" if ok else "NOT met"


def size_arg(text: str) -> int:
    """An element count: 100000, 100_000 or 1e5."""
    try:
        value = float(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of elements") from None
    if value < COUNT or value != int(value):
        raise argparse.ArgumentTypeError(
            f"{text!r}: the number of elements must be an integer >= {COUNT} ({COUNT} modes are asked for)"
        )
    return int(value)


def memory_size_arg(text: str) -> int:
    """An element count for the peak-memory part, or 0 to leave it out."""
    return 0 if text.strip() == "0" else size_arg(text)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line options."""
    p = argparse.ArgumentParser(description="Modal-analysis benchmark: flexshaft vs scipy vs openTorsion.")
    p.add_argument(
        "--sizes",
        type=size_arg,
        nargs="+",
        metavar="N",
        help=f"element counts (default: {' '.join(map(str, DEFAULT_SIZES))})",
    )
    p.add_argument(
        "--quick", action="store_true", help=f"only {' and '.join(map(str, QUICK_SIZES))} elements"
    )
    p.add_argument(
        "--peer-max-elements",
        type=int,
        default=PEER_MAX_ELEMENTS,
        metavar="N",
        help=f"run openTorsion up to this many elements (default {PEER_MAX_ELEMENTS}; "
        "its dense solver takes minutes past ~1000)",
    )
    p.add_argument(
        "--memory-size",
        type=memory_size_arg,
        metavar="N",
        help=f"elements of the fresh-process peak-memory comparison (default {MEMORY_SIZE}; "
        "0 leaves it out; --quick leaves it out unless given)",
    )
    p.add_argument(
        "--memory-runs",
        type=int,
        default=MEMORY_RUNS,
        metavar="R",
        help=f"fresh processes per tool in the peak-memory comparison (default {MEMORY_RUNS})",
    )
    p.add_argument("--memory-only", action="store_true", help="only the peak-memory comparison")
    p.add_argument("--child", nargs=2, metavar=("TOOL", "N"), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.memory_runs < 1:
        p.error("--memory-runs must be at least 1")
    return args


def print_header(exact: np.ndarray) -> None:
    """The problem, the versions and the machine."""
    print(
        f"Uniform free-free steel shaft: G = {G:.3g} Pa, rho = {RHO:g} kg/m3, D = {DIAMETER} m, "
        f"L = {LENGTH} m;"
    )
    print(
        f"k = {STIFFNESS:.6g} N·m/rad, J = {INERTIA:.6g} kg·m², closed-form f1 = {exact[0]:.4f} Hz; "
        f"lowest {COUNT} modes, rigid-body mode included."
    )
    blas_threads = os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS") or "default"
    print(
        f"numpy {np.__version__}, scipy {scipy.__version__}, python {sys.version.split()[0]}; "
        f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}, BLAS threads {blas_threads}; "
        "times: best of the runs shown."
    )
    if not PEER_PYTHON.exists():
        print(
            f"openTorsion: no peers virtualenv at {PEER_PYTHON.parent.parent}; run "
            "benchmarks/setup_peers.sh to include it (skipped)."
        )
    print()


def timed_rows(sizes, peer_max_elements: int, exact_with_rigid: np.ndarray) -> dict:
    """Each size timed (flexshaft, scipy, openTorsion) and printed as a row of the table: the rows."""
    # Warm up: the first call pays for lazy imports (scipy.sparse.linalg, ARPACK), not solving.
    flexshaft_modes(10)
    scipy_modes(100)

    head = (
        f"{'elements':>9} {'runs':>4} {'flexshaft s':>11} {'scipy s':>9} {'fs/scipy':>8} "
        f"{'openTorsion s':>13} {'fs/oT':>8} | {'err fs':>7} {'err scipy':>9} {'err oT':>7} "
        f"{'disc. est':>9} | {'fs~oT':>7}"
    )
    print(head)
    print("-" * len(head))
    rows = {}
    for n in sizes:
        runs = repeats_for(n)
        (t_fs, res), (t_sp, f_sp) = best_times(
            [lambda n=n: flexshaft_modes(n), lambda n=n: scipy_modes(n)], runs
        )
        f_fs = res.frequencies_hz
        peer = opentorsion_modes(n, peer_max_elements)
        agree = max_rel_error(peer.frequencies_hz, f_fs) if peer.frequencies_hz is not None else None
        rows[n] = dict(t_fs=t_fs, t_sp=t_sp, method=res.method, f_fs=f_fs, f_sp=f_sp, peer=peer, agree=agree)
        t_ot = fmt(peer.seconds, ".4f", peer.note or "-")
        r_ot = fmt(t_fs / peer.seconds if peer.seconds else None, ".2g")
        print(
            f"{n:>9} {runs:>4} {t_fs:>11.4f} {t_sp:>9.4f} {t_fs / t_sp:>8.2f} {t_ot:>13} {r_ot:>8} | "
            f"{fmt(max_rel_error(f_fs, exact_with_rigid), '.1e'):>7} "
            f"{fmt(max_rel_error(f_sp, exact_with_rigid), '.1e'):>9} "
            f"{fmt(max_rel_error(peer.frequencies_hz, exact_with_rigid), '.1e'):>7} "
            f"{discretisation_estimate(n, COUNT - 1):>9.1e} | {fmt(agree, '.1e'):>7}"
        )

    return rows


def print_notes(sizes, rows: dict) -> None:
    """What the columns mean, and the rigid-body mode as each tool reports it."""
    print()
    print("err *: max relative error of modes 1..9 against f_k = k/(2L)·sqrt(G/rho); disc. est: the")
    print("  leading-order discretisation error (9·pi/n)²/24 of mode 9 (asymptotic: rough at 10 elements).")
    print("  Past ~1e5 elements round-off (~eps·n², the conditioning of K) rather than discretisation")
    print("  sets the error floor of a plain Ritz value; flexshaft refines each eigenvalue by the")
    print("  Rayleigh quotient of its vector (error squared), so it stays on the discretisation error.")
    print("fs~oT: max relative difference of modes 1..9, flexshaft vs openTorsion on the same model.")
    for n in sizes:
        if rows[n]["peer"].note == "skipped":
            print(
                f"openTorsion, {n} elements: skipped: dense solver, minutes past ~1000 elements "
                f"(--peer-max-elements to change)"
            )

    print()
    print("Rigid-body mode as reported (Hz; exact value 0) and flexshaft's solver path:")
    for n in sizes:
        r = rows[n]
        f_ot = r["peer"].frequencies_hz
        print(
            f"  {n:>9}: flexshaft {r['f_fs'][0]:.3g}, scipy {r['f_sp'][0]:.3g}, "
            f"openTorsion {fmt(None if f_ot is None else f_ot[0], '.3g', r['peer'].note or '-')}"
            f"  [{r['method']}]"
        )


def print_checks(rows: dict, memory_size: int, mem_ratios) -> None:
    """The checks and targets, and the command line's own time."""
    print()
    print("Checks and targets:")
    compared = [(n, r["agree"]) for n, r in rows.items() if r["agree"] is not None]
    if compared:
        worst = max(a for _, a in compared)
        print(
            f"  flexshaft and openTorsion agree on the same model (<= {AGREE_TOL:g} relative): "
            f"{'yes' if worst <= AGREE_TOL else 'NO'} (worst {worst:.1e} over "
            f"{', '.join(str(n) for n, _ in compared)} elements)"
        )
    else:
        print("  flexshaft vs openTorsion: not compared (no openTorsion run)")
    if TARGET_SIZE in rows:
        r = rows[TARGET_SIZE]
        print(
            f"  {TARGET_SIZE} elements in under {TARGET_SECONDS:g} s in-process: "
            f"{verdict(r['t_fs'] < TARGET_SECONDS)} ({r['t_fs']:.3f} s)"
        )
        print(
            f"  {TARGET_SIZE} elements no slower than the plain scipy solve: "
            f"{verdict(r['t_fs'] <= r['t_sp'])} ({r['t_fs']:.3f} s vs {r['t_sp']:.3f} s, "
            f"ratio {r['t_fs'] / r['t_sp']:.2f})"
        )
    else:
        print(f"  {TARGET_SIZE}-element targets: not measured (size not in this run)")
    if mem_ratios is not None:
        print(
            f"  {memory_size} elements, fresh processes: peak memory at most {MEMORY_TARGET:g}x plain scipy: "
            f"{verdict(mem_ratios[2] <= MEMORY_TARGET)} ({mem_ratios[2]:.2f}); time at most "
            f"{TIME_TARGET:g}x: {verdict(mem_ratios[0] <= TIME_TARGET)} ({mem_ratios[0]:.2f})"
        )
    else:
        print("  peak-memory targets: not measured (--memory-size 0 or --quick)")
    t_cli = time_cli(CLI_RUNS)
    if t_cli is not None:
        print(
            f"  `flexshaft modes examples/customer1.toml`, whole process, best of {CLI_RUNS}: "
            f"{t_cli:.3f} s, target < {CLI_TARGET_SECONDS:g} s: {verdict(t_cli < CLI_TARGET_SECONDS)}"
        )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the tables."""
    args = parse_args(argv)
    if args.child:
        tool, n = args.child
        return child(tool, int(n))
    memory_size = args.memory_size if args.memory_size is not None else (0 if args.quick else MEMORY_SIZE)
    if args.memory_only:
        n = memory_size or MEMORY_SIZE
        report_memory(n, memory_comparison(n, args.memory_runs))
        return 0
    sizes = args.sizes or (QUICK_SIZES if args.quick else DEFAULT_SIZES)
    exact = closed_form_hz(COUNT - 1)

    print_header(exact)
    rows = timed_rows(sizes, args.peer_max_elements, np.concatenate([[0.0], exact]))
    print_notes(sizes, rows)
    mem_ratios = None
    if memory_size:
        print()
        mem_ratios = report_memory(memory_size, memory_comparison(memory_size, args.memory_runs))

    print_checks(rows, memory_size, mem_ratios)
    return 0


if __name__ == "__main__":
    sys.exit(main())
