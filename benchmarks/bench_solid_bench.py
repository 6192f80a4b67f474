"""The solid test bench (examples/solid_testbench.py) cold, with its meshes cached, and warm.

What it measures
----------------
``examples/solid_testbench.py`` with ``customer1_solid.toml``: PTSS parts 1 and 2 and the stepped
part 4 as solids (curved 10-node tetrahedra, 132 000 + 309 000 + 48 000 DOFs), each reduced to a
Craig-Bampton body of its twist modes, then the twist test and the modes of both the 1D and the
solid model. The same script three times, each in a fresh process with one cache folder
(``FLEXSHAFT_CACHE_DIR``, new and empty at the start):

1. **cold**: an empty cache - the parts are sliced (the 1D model's section tables), meshed (gmsh)
   and solved (assembly, multigrid, constraint modes, twist modes, residual vectors);
2. **meshes cached**: the solid results removed from the cache, the section tables and meshes kept -
   the solving alone; cold minus this is what slicing and meshing cost;
3. **warm**: everything cached - the solid results read back (:mod:`flexshaft.input.solidcache`).

Each run's wall time, its CPU time (user + system, its children's included: gmsh meshes in a forked
child) and its peak memory (``ru_maxrss`` of the largest process, read by a small launcher, since
Linux carries a parent's ``ru_maxrss`` into a forked child); the load average before each run, as
the machine may be shared. Printed: the warm/cold ratio, the cold time against the 180 s target and
whether the three runs print the same tables (they must: a cache changes no number).

Run (from the repository root):

    .venv/bin/python benchmarks/bench_solid_bench.py          # ~3-4 min on the 2-core machine
    .venv/bin/python benchmarks/bench_solid_bench.py --twist  # also `flexshaft twist` cold and warm

Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
EXAMPLE = ROOT / "examples" / "solid_testbench.py"
MODEL = ROOT / "examples" / "customer1_solid.toml"
#: The issue's target for the cold run, s.
TARGET_S = 180.0
TIMEOUT_S = 3600
#: Runs the command as its child and reports the child's wall time, CPU time and peak memory (the
#: largest ru_maxrss among the processes it waited for, gmsh's included) as one JSON line on stderr.
LAUNCHER = r"""
import json, resource, subprocess, sys, time
t0 = time.perf_counter()
proc = subprocess.run(sys.argv[1:], capture_output=True, text=True)
wall = time.perf_counter() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
sys.stdout.write(proc.stdout)
sys.stderr.write(proc.stderr)
sys.stderr.write("\n" + json.dumps({"wall": wall, "cpu": ru.ru_utime + ru.ru_stime,
                                    "peak_mib": ru.ru_maxrss / 1024.0, "code": proc.returncode}) + "\n")
"""


def measured(cmd: list[str], cache: Path) -> tuple[dict, str]:
    """One run of ``cmd`` in a fresh process with ``cache`` as its cache folder: (record, stdout)."""
    env = dict(os.environ, FLEXSHAFT_CACHE_DIR=str(cache))
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    load = os.getloadavg()[0]
    proc = subprocess.run(
        [sys.executable, "-c", LAUNCHER, *cmd], capture_output=True, text=True, timeout=TIMEOUT_S, env=env
    )
    record = json.loads(proc.stderr.strip().splitlines()[-1])
    if record["code"] != 0:
        raise RuntimeError(f"{' '.join(cmd[1:])} failed:\n{proc.stderr[-3000:]}")
    record["load"] = load
    return record, proc.stdout


def cache_mib(cache: Path, folder: str) -> float:
    """The size of the cache's ``folder`` (``solids``, ``meshes``), MB."""
    return sum(p.stat().st_size for p in (cache / folder).glob("*.npz")) / 2**20


def show(label: str, r: dict) -> None:
    print(
        f"{label:34s} {r['wall']:7.1f} s wall  {r['cpu']:7.1f} s CPU  peak {r['peak_mib'] / 1024:5.2f} GiB  "
        f"(load {r['load']:.2f} before)"
    )


def series(label: str, cmd: list[str], cache: Path) -> dict:
    """Cold, meshes cached, warm: the three runs of ``cmd`` on one cache folder."""
    rows, outputs = {}, {}
    rows["cold"], outputs["cold"] = measured(cmd, cache)
    show(f"{label}: cold (empty cache)", rows["cold"])
    kept = cache_mib(cache, "solids")
    shutil.rmtree(cache / "solids", ignore_errors=True)
    rows["meshed"], outputs["meshed"] = measured(cmd, cache)
    show(f"{label}: meshes cached, solved", rows["meshed"])
    rows["warm"], outputs["warm"] = measured(cmd, cache)
    show(f"{label}: warm (results cached)", rows["warm"])
    cold, meshed, warm = (rows[k]["wall"] for k in ("cold", "meshed", "warm"))
    same = outputs["cold"] == outputs["meshed"] == outputs["warm"]
    print(
        f"{'':34s} warm/cold {warm / cold:.3f} ({cold / warm:.0f}x faster warm); cold {cold:.1f} s against "
        f"the {TARGET_S:.0f} s target: {'met' if cold < TARGET_S else 'NOT met'}"
    )
    share = 100 * (cold - meshed) / cold
    print(
        f"{'':34s} slicing + meshing ~{cold - meshed:.1f} s of the cold run ({share:.0f} %), "
        f"solving {meshed - warm:.1f} s, the rest {warm:.1f} s; cache: {kept:.0f} MB of solid results, "
        f"{cache_mib(cache, 'meshes'):.0f} MB of meshes"
    )
    print(f"{'':34s} the three runs print {'the same tables' if same else 'DIFFERENT tables'}")
    return {"rows": rows, "same_output": same}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--twist", action="store_true", help="also `flexshaft twist customer1_solid.toml`")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    results = {}
    with tempfile.TemporaryDirectory(prefix="bench-solid-bench-") as tmp:
        results["example"] = series("solid_testbench.py", [sys.executable, str(EXAMPLE)], Path(tmp) / "a")
        if args.twist:
            cmd = [sys.executable, "-m", "flexshaft", "twist", str(MODEL)]
            results["twist"] = series("flexshaft twist", cmd, Path(tmp) / "b")
    print(json.dumps(results))


if __name__ == "__main__":
    main()
