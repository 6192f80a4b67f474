"""Signal-file benchmark: the CSV of a 900 s run at 1.6 kHz (1 440 001 rows), written, read, analysed.

What it measures
----------------
The run of ``bench_simulate.py`` (Customer 1, PI speed loop, ramp 0 -> 1800 rpm in 900 s, 6th-order
torque ripple) sampled at 1.6 kHz: time, coupling torque, motor speed - 1 440 001 rows of 3 columns,
written to a temporary folder. Everything runs on one BLAS thread (threadpoolctl in-process, the
variables in the child processes); timings are interleaved (a, b, c, a, b, c, ...: each contender
sees the same drift in machine load), best of ``--repeats``.

1. Writing. ``simulate()`` and ``write_signals`` of its outputs, interleaved; printed: the share of
   the writing in simulate + write (the issue's target: at most 25 %; ``np.savetxt`` made it 58 % of
   ``flexshaft simulate -o``). The formatters weighed for it, once each on the same table:
   ``np.savetxt(fmt="%.17g")`` (the writer before), Python's ``%r`` over blocks of rows (the fastest
   pure-Python way found), orjson on blocks of rows (what ``write_signals`` uses), and pyarrow's CSV
   writer if pyarrow is installed (it is not a dependency). Then the share of ``write_signals`` in
   the whole ``flexshaft simulate ... -o run.csv`` command (a process of its own; the writing timed
   from inside it), as the issue measured it.
2. Reading, two files of the same numbers: as ``write_signals`` writes them (shortest round-trip
   decimals) and with 17 significant digits (``%.17g``, 79 MB: the issue's file, as the writer before
   made it and as other tools write doubles). Contenders: ``read_signals`` (every column; one
   column, as ``flexshaft spectrum`` asks), its text path alone (pandas disabled: numpy's
   ``loadtxt`` on each piece's lines, then cell by cell - what a reader on numpy's C parser gets),
   ``pandas.read_csv`` (its default: a parse thread per core, two here; and one thread, as
   flexshaft's thread policy runs everything), ``np.loadtxt`` on the file, ``np.fromstring`` after
   turning line ends into commas, and ``pyarrow.csv.read_csv`` if installed. Printed: each time and
   read_signals / pandas.read_csv (the issue's target: at most 1.5x).
3. Memory: the peak resident memory (``os.wait4``'s ``ru_maxrss``) of ``flexshaft spectrum FILE
   --column "torque:part 3" --segment 1`` as a whole process, against a process doing
   ``pandas.read_csv`` + ``scipy.signal.welch`` (Hann, the same 1 s segments, 50 % overlap) on the
   same column; each also with its imports alone, for the floor. Printed: the ratio (target: at most
   1.3x).

Run: ``.venv/bin/python benchmarks/bench_signalfile.py`` (about 2 min; ``--repeats 1`` for a quick
look). pyarrow, not a dependency, is timed when importable, e.g. installed apart with ``pip install
--target DIR pyarrow`` and ``PYTHONPATH=DIR``, then with ``--no-memory`` (pandas loads pyarrow when it
can, which changes its processes' memory). Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import io
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import orjson
import pandas as pd
from threadpoolctl import threadpool_limits
from timing import interleaved

import flexshaft as fs
from flexshaft.analysis.simulate import Scenario, SpeedControl, simulate
from flexshaft.measurement import signalfile
from flexshaft.measurement.signalfile import read_signals, write_signals

ROOT = Path(__file__).resolve().parents[1]
RATE, RAMP, END_RPM, RIPPLE, ORDER = 1600.0, 900.0, 1800.0, 20.0, 6.0
OUTPUTS = ["torque:part 3", "speed:motor"]
SEGMENT_S = 1.0
FLEXSHAFT = Path(sys.executable).with_name("flexshaft")
# Child processes on one BLAS thread too (flexshaft's CLI would choose one itself; scipy's welch not).
ONE_THREAD = os.environ | dict.fromkeys(
    ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS"), "1"
)

try:
    import pyarrow as pa
    import pyarrow.csv as pacsv
except ImportError:  # not a dependency: weighed when present
    pa = pacsv = None


def once(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


# --- writing ---------------------------------------------------------------------------------------


def python_blocks(table: np.ndarray) -> bytes:
    """Python's %r (shortest round-trip) over blocks of rows: one % formatting per block."""
    out, row = [], ",".join(["%r"] * table.shape[1]) + "\n"
    for first in range(0, table.shape[0], 1 << 16):
        block = table[first : first + (1 << 16)]
        out.append((row * len(block) % tuple(block.ravel().tolist())).encode())
    return b"".join(out)


def savetxt(table: np.ndarray) -> bytes:
    buf = io.StringIO()
    np.savetxt(buf, table, fmt="%.17g", delimiter=",")
    return buf.getvalue().encode()


def pyarrow_csv(table: np.ndarray) -> bytes:
    sink = io.BytesIO()
    tbl = pa.table({f"c{i}": table[:, i] for i in range(table.shape[1])})
    pacsv.write_csv(tbl, sink, pacsv.WriteOptions(include_header=False))
    return sink.getvalue()


# The whole `flexshaft simulate ... -o FILE` command in a process of its own, its write_signals timed
# from inside (the command imports it when it writes): (whole process, writing), s.
CLI_SIMULATE = """
import sys, time
t0 = time.perf_counter()
import flexshaft.measurement.signalfile as sf
write, spent = sf.write_signals, [0.0]
def timed(*args, **kwargs):
    t = time.perf_counter()
    try:
        return write(*args, **kwargs)
    finally:
        spent[0] += time.perf_counter() - t
sf.write_signals = timed
from flexshaft.cli import main
code = main(sys.argv[1:])
print(time.perf_counter() - t0, spent[0], code)
"""


def cli_simulate(out: Path) -> tuple[float, float]:
    """(whole process, its write_signals) wall times (s) of ``flexshaft simulate ... -o out``."""
    args = [
        "simulate",
        str(ROOT / "examples" / "customer1.toml"),
        "--scenario",
        "ramp",
        "--end-speed",
        "1800",
    ]
    args += ["--ramp-time", "900", "--duration", "900", "--rate", "1600", "--measure", OUTPUTS[0]]
    args += ["--measure", OUTPUTS[1], "-o", str(out), "--force"]
    run = subprocess.run(
        [sys.executable, "-c", CLI_SIMULATE, *args], capture_output=True, text=True, env=ONE_THREAD
    )
    whole, write, code = run.stdout.split()[-3:]
    if int(code):
        raise RuntimeError(f"flexshaft simulate failed: {run.stderr[-400:]}")
    return float(whole), float(write)


def bench_writing(folder: Path, repeats: int):
    result = fs.modal_analysis(fs.load_model(ROOT / "examples" / "customer1.toml"))
    ctl = SpeedControl.tuned(result, tau=0.002)
    sc = Scenario.ramp(END_RPM, RAMP, ctl, ripple=RIPPLE, ripple_order=ORDER)
    run = simulate(result, sc, OUTPUTS, rate=RATE, duration=RAMP)
    cols = {name: (y, run.units[name]) for name, y in run.outputs.items()}
    path = folder / "run.csv"
    t = interleaved(
        {
            "simulate()": lambda: simulate(result, sc, OUTPUTS, rate=RATE, duration=RAMP),
            "write_signals": lambda: write_signals(path, run.time, cols, overwrite=True),
        },
        repeats,
    )
    share = t["write_signals"] / (t["simulate()"] + t["write_signals"])
    print(f"\n1. writing {run.time.size} rows x {1 + len(cols)} columns ({path.stat().st_size / 1e6:.1f} MB)")
    print(f"  simulate()            {t['simulate()']:8.3f} s")
    print(f"  write_signals         {t['write_signals']:8.3f} s   (format, encode, write, fsync)")
    print(f"  share of the writing  {100 * share:7.1f} %   of simulate + write (target: at most 25 %)")

    table = np.column_stack([run.time, *run.outputs.values()])
    print("  formatting the table alone (once each; same numbers back from each):")
    formatters = {
        "np.savetxt %.17g (before)": savetxt,
        "Python %r over blocks": python_blocks,
        "orjson over blocks (used)": lambda tb: signalfile._csv_bytes([], tb),  # an empty header line
    }
    if pa is not None:
        formatters["pyarrow.csv.write_csv"] = pyarrow_csv
    else:
        print("    pyarrow.csv.write_csv        not installed (not a dependency): skipped")
    for name, fn in formatters.items():
        t0 = time.perf_counter()
        text = fn(table)
        dt = time.perf_counter() - t0
        back = pd.read_csv(io.BytesIO(text), header=None).to_numpy()
        exact = np.array_equal(back, table)
        print(f"    {name:28s} {dt:7.3f} s  {len(text) / 1e6:6.1f} MB  {'exact' if exact else 'NOT EXACT'}")
    seventeen = folder / "run17.csv"
    header = ",".join(["time [s]"] + [f"{n} [{u}]" for n, (_, u) in cols.items()]) + "\n"
    seventeen.write_bytes(header.encode() + savetxt(table))

    cli = [cli_simulate(folder / "cli.csv") for _ in range(max(repeats, 2))]
    whole, write = min(w[0] for w in cli), min(w[1] for w in cli)  # each its best, as every timing here
    print(
        f"  flexshaft simulate -o (the whole process, its best of {len(cli)}): {whole:.2f} s, of which "
        f"write_signals {write:.2f} s: {100 * write / whole:.0f} % (np.savetxt: 58 % in the issue)"
    )
    return path, seventeen


# --- reading ---------------------------------------------------------------------------------------


def text_path_only(path: Path):
    """read_signals with pandas disabled: numpy's loadtxt on every piece (then cell by cell)."""
    saved = signalfile._PANDAS_MIN_BYTES
    signalfile._PANDAS_MIN_BYTES = math.inf
    try:
        return read_signals(path)
    finally:
        signalfile._PANDAS_MIN_BYTES = saved


def pandas_one_thread(path: Path):
    with pd.option_context("mode.max_threads", 1):
        return pd.read_csv(path)


def fromstring(path: Path) -> np.ndarray:
    data = path.read_bytes()
    body = data[data.index(b"\n") + 1 :].replace(b"\n", b",")
    return np.fromstring(body, sep=",")  # noqa: NPY201 - text mode of fromstring is not deprecated


def bench_reading(files: dict, repeats: int) -> None:
    for label, path in files.items():
        ref = pd.read_csv(path).to_numpy()
        table = read_signals(path)
        same = np.array_equal(table.time, ref[:, 0]) and all(
            np.array_equal(v, ref[:, 1 + k]) for k, v in enumerate(table.columns.values())
        )
        fns = {
            "read_signals, every column": lambda p=path: read_signals(p),
            "read_signals, one column": lambda p=path: read_signals(p, columns=[OUTPUTS[0]]),
            "pandas.read_csv (default)": lambda p=path: pd.read_csv(p),
            "pandas.read_csv, 1 thread": lambda p=path: pandas_one_thread(p),
            "read_signals, text path": lambda p=path: text_path_only(p),
            "np.loadtxt": lambda p=path: np.loadtxt(p, delimiter=",", skiprows=1),
            "np.fromstring": lambda p=path: fromstring(p),
        }
        if pacsv is not None:
            fns["pyarrow.csv.read_csv"] = lambda p=path: pacsv.read_csv(p)
        t = interleaved(fns, repeats)
        threads = pd.get_option("mode.max_threads") or len(os.sched_getaffinity(0))
        print(f"\n2. reading {label}: {path.stat().st_size / 1e6:.1f} MB, best of {repeats}")
        print(
            f"  (read_signals gives pandas' numbers bit for bit: {same}; pandas' default: {threads} threads)"
        )
        for name, s in t.items():
            print(f"  {name:28s} {s:8.3f} s   {s / t['pandas.read_csv (default)']:6.2f}x pandas")
        if pacsv is None:
            print("  pyarrow.csv.read_csv         not installed (not a dependency): skipped")
        ours = t["read_signals, every column"]
        print(
            f"  read_signals / pandas.read_csv: {ours / t['pandas.read_csv (default)']:.2f}x its default, "
            f"{ours / t['pandas.read_csv, 1 thread']:.2f}x on one thread (target: at most 1.5x)"
        )


# --- memory ----------------------------------------------------------------------------------------

PANDAS_WELCH = """
import sys
import pandas as pd
import scipy.signal
path, column, segment = sys.argv[1], sys.argv[2], float(sys.argv[3])
df = pd.read_csv(path)
t = df["time [s]"].to_numpy()
rate = (t.size - 1) / (t[-1] - t[0])
n = int(round(segment * rate))
f, p = scipy.signal.welch(df[column].to_numpy(), rate, window="hann", nperseg=n, noverlap=n // 2)
print(f[1:][p[1:].argmax()])
"""
IMPORTS_PANDAS = "import pandas, scipy.signal"
IMPORTS_FLEXSHAFT = (
    "import pandas, scipy.signal, flexshaft.cli, flexshaft.measurement.signalfile, flexshaft.measurement"
)


# Started from a small process of its own: a child inherits its parent's resident memory in its peak
# (the kernel counts the forked image), and this benchmark's own holds the tables.
LAUNCHER = """
import os, subprocess, sys, time
t0 = time.perf_counter()
proc = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL)
_, status, usage = os.wait4(proc.pid, 0)
print(usage.ru_maxrss, time.perf_counter() - t0, os.waitstatus_to_exitcode(status))
"""


def peak_rss(args: list[str]) -> tuple[float, float]:
    """Peak resident memory (MB) of the process ``args``, from the kernel's account of that child, and
    its wall time (s)."""
    run = subprocess.run(
        [sys.executable, "-c", LAUNCHER, *args], capture_output=True, text=True, env=ONE_THREAD
    )
    kb, wall, code = run.stdout.split()
    if int(code):
        raise RuntimeError(f"{args[:3]} failed: {run.stderr[-400:]}")
    return int(kb) / 1024.0, float(wall)  # ru_maxrss: kB on Linux


def bench_memory(path: Path, repeats: int) -> None:
    runs = {
        "flexshaft spectrum": [str(FLEXSHAFT), "spectrum", str(path), "--column", OUTPUTS[0]]
        + ["--segment", str(SEGMENT_S)],
        "pandas.read_csv + welch": [sys.executable, "-c", PANDAS_WELCH, str(path), OUTPUTS[0] + " [N·m]"]
        + [str(SEGMENT_S)],
        "  its imports alone": [sys.executable, "-c", IMPORTS_FLEXSHAFT],
        "  their imports alone": [sys.executable, "-c", IMPORTS_PANDAS],
    }
    peak, wall = dict.fromkeys(runs, math.inf), dict.fromkeys(runs, math.inf)
    for _ in range(max(repeats, 2)):
        for name, args in runs.items():
            mb, s = peak_rss(args)
            peak[name], wall[name] = min(peak[name], mb), min(wall[name], s)
    print(
        f"\n3. peak memory, each a process of its own ({path.stat().st_size / 1e6:.0f} MB file, 1 s segments)"
    )
    for name, floor in (
        ("flexshaft spectrum", "  its imports alone"),
        ("pandas.read_csv + welch", "  their imports alone"),
    ):
        print(
            f"  {name:26s} {peak[name]:7.0f} MB, {wall[name]:5.2f} s   (its imports alone: "
            f"{peak[floor]:.0f} MB, {wall[floor]:.2f} s)"
        )
    ratio = peak["flexshaft spectrum"] / peak["pandas.read_csv + welch"]
    print(f"  flexshaft / pandas + welch  {ratio:7.2f}x   (target: at most 1.3x)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="interleaved rounds, best taken (3)")
    parser.add_argument(
        "--no-memory", action="store_true", help="skip the memory section (e.g. with pyarrow on the path)"
    )
    args = parser.parse_args()
    print(
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; numpy {np.__version__}, "
        f"pandas {pd.__version__}, orjson {orjson.__version__}, pyarrow {pa.__version__ if pa else '-'}"
    )
    with tempfile.TemporaryDirectory(prefix="bench-signalfile-") as tmp, threadpool_limits(1):
        written, seventeen = bench_writing(Path(tmp), args.repeats)
        bench_reading(
            {"as write_signals writes it": written, "with 17 digits (%.17g)": seventeen}, args.repeats
        )
        if not args.no_memory:  # pandas loads pyarrow when it can: its processes would not be comparable
            bench_memory(seventeen, args.repeats)


if __name__ == "__main__":
    main()
