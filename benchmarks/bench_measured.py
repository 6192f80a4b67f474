"""Measured-file benchmark: an 8-channel x 5 M-sample record read by flexshaft and by each format's library.

What it measures
----------------
A test-bench record - 8 channels of float64 (N·m), 5 000 000 samples each at 10 kHz (500 s) - written
into a temporary folder as HDF5 (h5py: one contiguous dataset per channel, ``rate_hz`` and ``units``
attributes), TDMS (npTDMS: one segment, waveform properties) and MDF 4 (asammdf: one channel group,
its time master). Each file is 320-360 MB; the page cache holds them after writing, so every reading
below reads memory, not a disk.

1. In-process, interleaved (a, b, a, b, ...: both see the same drift in machine load), best of
   ``--repeats``:

   - the library's own read of the 8 channels into float64 arrays, as its documentation does it:
     h5py ``f[name][()]``; npTDMS ``TdmsFile.read(path)`` and ``channel[:]``; asammdf
     ``MDF(path).select(names)`` (one pass over the group's records for every channel);
   - the same and the time vector the record implies (``np.arange(n) / rate_hz``, npTDMS's
     ``time_track()``; asammdf's ``select`` gives the time stamps already), as flexshaft's table has;
   - ``flexshaft.measurement.files.read_measured(path, names)``: the library parses the file in a forked
     child (a crash or a hang of its native code is one error), the samples are read by the caller
     from where the library says they lie, checked finite, put on the time base (a time array made).

   Printed: each time and the ratios (target: at most 1.5x).
2. Whole process: ``python -c`` doing each of the two (imports included), each started from a small
   launcher process whose ``os.wait4`` gives the child's peak resident memory (``ru_maxrss``: the
   larger of the process and its forked reading child; Linux carries a forking parent's memory into
   a child's peak, hence the launcher). Printed: time and memory, and their ratios (targets: at most
   1.5x each).

Run: ``.venv/bin/python benchmarks/bench_measured.py`` (about 2 min; ``--samples 500000`` for a quick
look; ``--keep DIR`` writes the files there and keeps them). Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from timing import interleaved

CHANNELS = [f"ch{i}" for i in range(8)]
RATE = 10_000.0  # Hz
GROUP = "bench"


def write_files(folder: Path, n: int) -> dict[str, Path]:
    """The record in each format, written by its own library."""
    import h5py
    from asammdf import MDF, Signal
    from nptdms import ChannelObject, TdmsWriter

    k = np.arange(n)
    cols = {c: (i + 1) * np.sin(2 * np.pi * (10 + i) * k / RATE) for i, c in enumerate(CHANNELS)}
    files = {"HDF5": folder / "rec.h5", "TDMS": folder / "rec.tdms", "MDF 4": folder / "rec.mf4"}
    with h5py.File(files["HDF5"], "w") as f:
        g = f.create_group(GROUP)
        for c, v in cols.items():
            d = g.create_dataset(c, data=v)
            d.attrs["units"] = "Nm"
            d.attrs["rate_hz"] = RATE
    wf = {"unit_string": "Nm", "wf_increment": 1 / RATE, "wf_start_offset": 0.0}
    with TdmsWriter(str(files["TDMS"])) as w:
        w.write_segment([ChannelObject(GROUP, c, v, properties=wf) for c, v in cols.items()])
    mdf = MDF(version="4.10")
    mdf.append([Signal(v, k / RATE, name=c, unit="Nm") for c, v in cols.items()], acq_name=GROUP)
    mdf.save(files["MDF 4"], overwrite=True)
    mdf.close()
    return files


# --- the libraries' own reads (the same code runs in-process and as `python -c`) ------------------

LIBRARY_READS = {
    "HDF5": """
import h5py, numpy as np
def read(path, names):
    with h5py.File(path, "r") as f:
        return {n: f["bench"][n][()].astype(np.float64, copy=False) for n in names}
""",
    "TDMS": """
import numpy as np
from nptdms import TdmsFile
def read(path, names):
    g = TdmsFile.read(path)["bench"]
    return {n: g[n][:].astype(np.float64, copy=False) for n in names}
""",
    "MDF 4": """
import numpy as np
from asammdf import MDF
def read(path, names):
    with MDF(path) as m:
        return {s.name: s.samples.astype(np.float64, copy=False) for s in m.select(names)}
""",
}
# The same and the time vector the record implies (flexshaft's table has one): what a user of the library
# computes next. asammdf's select gives each channel's time stamps already.
WITH_TIME = {
    "HDF5": """
import h5py, numpy as np
def read(path, names):
    with h5py.File(path, "r") as f:
        cols = {n: f["bench"][n][()].astype(np.float64, copy=False) for n in names}
        cols["time"] = np.arange(cols[names[0]].size) / f["bench"][names[0]].attrs["rate_hz"]
        return cols
""",
    "TDMS": """
import numpy as np
from nptdms import TdmsFile
def read(path, names):
    g = TdmsFile.read(path)["bench"]
    cols = {n: g[n][:].astype(np.float64, copy=False) for n in names}
    cols["time"] = g[names[0]].time_track()
    return cols
""",
    "MDF 4": LIBRARY_READS["MDF 4"],
}
FLEXSHAFT_READ = """
from flexshaft.measurement.files import read_measured
def read(path, names):
    return read_measured(path, names).columns
"""
WHOLE = """
import sys
{code}
cols = read(sys.argv[1], sys.argv[2:])
assert len(cols) == len(sys.argv) - 2
"""
LAUNCHER = """
import os, subprocess, sys, time
t0 = time.perf_counter()
proc = subprocess.Popen(sys.argv[1:])
_, status, usage = os.wait4(proc.pid, 0)
print(os.waitstatus_to_exitcode(status), usage.ru_maxrss, time.perf_counter() - t0)
"""


def reader(code: str):
    space: dict = {}
    exec(code, space)  # noqa: S102 - this file's own snippets, run as they are in `python -c`
    return space["read"]


def whole_process(code: str, path: Path) -> tuple[float, float]:
    """(wall time s, peak resident MB) of ``python -c`` reading the file, from a small launcher."""
    argv = [sys.executable, "-c", WHOLE.format(code=code), str(path), *CHANNELS]
    out = subprocess.run(
        [sys.executable, "-c", LAUNCHER, *argv], capture_output=True, text=True, check=True
    ).stdout.split()
    if int(out[0]):
        raise RuntimeError(f"{argv[:3]} failed")
    return float(out[2]), int(out[1]) / 1024.0


def same_numbers(files: dict) -> None:
    from flexshaft.measurement.files import read_measured

    for fmt, path in files.items():
        lib = reader(LIBRARY_READS[fmt])(path, CHANNELS)
        ours = read_measured(path, CHANNELS)
        assert all(np.array_equal(lib[c], ours.columns[c]) for c in CHANNELS), fmt
        assert abs(ours.rate_hz / RATE - 1) < 1e-9, (fmt, ours.rate_hz)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=5_000_000, help="per channel (5 000 000)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved rounds, best taken (5)")
    parser.add_argument("--keep", type=Path, help="write the files into this folder and keep them")
    args = parser.parse_args()
    import asammdf
    import h5py
    import nptdms

    print(
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; numpy {np.__version__}, "
        f"h5py {h5py.__version__}, npTDMS {nptdms.__version__}, asammdf {asammdf.__version__}"
    )
    with tempfile.TemporaryDirectory(prefix="bench-measured-") as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        files = write_files(folder, args.samples)
        sizes = ", ".join(f"{k} {p.stat().st_size / 1e6:.0f} MB" for k, p in files.items())
        took = time.perf_counter() - t0
        print(f"{len(CHANNELS)} channels x {args.samples:,} samples, written in {took:.1f} s: {sizes}")
        same_numbers(files)
        print("flexshaft gives each library's numbers bit for bit: True")

        ours = reader(FLEXSHAFT_READ)
        print(f"\n1. in-process, best of {args.repeats} interleaved")
        print(
            f"  {'format':6s} {'library s':>10s} {'+ time s':>9s} {'flexshaft s':>12s} {'ratio':>6s}"
            f" {'to + time':>10s}   (target <= 1.5)"
        )
        for fmt, path in files.items():
            lib, timed = reader(LIBRARY_READS[fmt]), reader(WITH_TIME[fmt])
            t = interleaved(
                {
                    "lib": lambda p=path, f=lib: f(p, CHANNELS),
                    "timed": lambda p=path, f=timed: f(p, CHANNELS),
                    "ours": lambda p=path: ours(p, CHANNELS),
                },
                args.repeats,
            )
            print(
                f"  {fmt:6s} {t['lib']:10.3f} {t['timed']:9.3f} {t['ours']:12.3f} {t['ours'] / t['lib']:6.2f}"
                f" {t['ours'] / t['timed']:10.2f}"
            )

        rounds = max(2, args.repeats // 2)
        print(f"\n2. whole process (python -c, imports included), best of {rounds} interleaved")
        print(
            f"  {'format':6s} {'library s':>10s} {'flexshaft s':>12s} {'ratio':>6s}"
            f" {'library MB':>11s} {'flexshaft MB':>13s} {'ratio':>6s}   (targets <= 1.5)"
        )
        for fmt, path in files.items():
            best = {k: [math.inf, math.inf] for k in ("lib", "ours")}
            for _ in range(rounds):
                for key, code in (("lib", LIBRARY_READS[fmt]), ("ours", FLEXSHAFT_READ)):
                    s, mb = whole_process(code, path)
                    best[key] = [min(best[key][0], s), min(best[key][1], mb)]
            (ls, lm), (fs_, fm) = best["lib"], best["ours"]
            print(f"  {fmt:6s} {ls:10.3f} {fs_:12.3f} {fs_ / ls:6.2f} {lm:11.0f} {fm:13.0f} {fm / lm:6.2f}")


if __name__ == "__main__":
    main()
