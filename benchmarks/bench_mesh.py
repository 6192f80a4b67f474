"""Meshing a solid part over sizes: DOFs and seconds per size, and whether a coarser mesh is ever slower.

What it measures
----------------
PTSS part 1 of the test bench (``geometry.parts.testbench.ptss_part1``: a 3 m steel tube with a hub
and a 12-hole bolted flange at each end, 10 mm shoulder fillets; ``--part 2`` or ``--part 4`` for the
others) meshed by :func:`geometry.meshing.mesh_solid` into curved 10-node tetrahedra at each of
``--sizes`` (default 0.16, 0.12, 0.08, 0.06, 0.04 and 0.03 m). For each size:

- the mesh's DOFs and elements, and the estimate made before meshing
  (:func:`geometry.meshing.estimate_mesh`) with the ratio mesh / estimate;
- the wall time of ``mesh_solid`` (best of ``--repeat``; the part is built once, outside the
  timing), and where it goes: gmsh's surfaces, its volume, the second order (mid-side nodes on the
  geometry), the high-order optimiser mending the curved elements that came out inverted, and the
  rest (reading the part, finding its axis, the forked child, converting the mesh), from the
  mesher's progress reports.

Then it says whether the time is monotone in the DOFs: no mesh with fewer DOFs took longer than one
with more (strictly, and within 20 % for a shared machine's noise). The comparison is with ourselves
at other sizes: the issue was a coarse mesh (0.12 m, 161 000 DOFs) taking 26-110 s, 85 s of it in
gmsh's high-order optimiser, against 5.8 s at a million DOFs.

Run (from the repository root):

    .venv/bin/python benchmarks/bench_mesh.py                 # ~1 min
    .venv/bin/python benchmarks/bench_mesh.py --part 4 --sizes 0.2 0.1 0.05 0.03 0.02
    .venv/bin/python benchmarks/bench_mesh.py --repeat 1      # one run per size

Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import sys
import time

STAGES = {  # the mesher's progress stages, and the column each one's time goes to
    "meshing the surfaces": "surfaces",
    "meshing the volume": "volume",
    "placing the mid-side nodes on the geometry": "order 2",
    "checking the elements": "order 2",
    "moving the nodes of curved elements that came out inverted": "optimiser",
}
COLUMNS = ("surfaces", "volume", "order 2", "optimiser")


def timed_mesh(shape, name: str, size: float):
    """One ``mesh_solid`` call: (mesh, wall seconds, {column: seconds})."""
    from geometry.meshing import mesh_solid

    marks = []
    t0 = time.perf_counter()
    mesh = mesh_solid(
        shape, name=name, size=size, progress=lambda stage, f: marks.append((stage, time.perf_counter()))
    )
    total = time.perf_counter() - t0
    spent = dict.fromkeys(COLUMNS, 0.0)
    for (stage, t), (_, t_next) in zip(marks, marks[1:]):
        if stage in STAGES:
            spent[STAGES[stage]] += t_next - t
    return mesh, total, spent


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", type=int, choices=(1, 2, 4), default=1, help="PTSS part (default 1)")
    parser.add_argument("--sizes", type=float, nargs="+", default=[0.16, 0.12, 0.08, 0.06, 0.04, 0.03])
    parser.add_argument("--repeat", type=int, default=3, help="runs per size, the best kept (default 3)")
    args = parser.parse_args(argv)

    from geometry.meshing import estimate_mesh
    from geometry.parts import testbench

    name = f"PTSS part {args.part}"
    t0 = time.perf_counter()
    shape = getattr(testbench, f"ptss_part{args.part}")()
    print(f"{name}: built in {time.perf_counter() - t0:.1f} s (not timed below); best of {args.repeat}")
    print()
    head = (
        f"{'size m':>7} {'DOFs':>9} {'elements':>8} {'estimate':>9} {'mesh/est':>8} {'estimate s':>10} "
        f"{'mesh s':>7}  " + " ".join(f"{c:>9}" for c in COLUMNS) + f" {'other':>6}"
    )
    print(head)
    rows = []
    for size in args.sizes:
        t = time.perf_counter()
        guess = estimate_mesh(shape, name=name, size=size)
        t_est = time.perf_counter() - t
        best = None
        for _ in range(args.repeat):
            mesh, total, spent = timed_mesh(shape, name, size)
            if best is None or total < best[1]:
                best = (mesh, total, spent)
        mesh, total, spent = best
        dofs = 3 * mesh.n_nodes
        rows.append((size, dofs, total))
        other = total - sum(spent.values())
        print(
            f"{size:7.3f} {dofs:9d} {mesh.n_elements:8d} {guess.dofs:9.0f} {dofs / guess.dofs:8.2f} "
            f"{t_est:10.2f} {total:7.2f}  "
            + " ".join(f"{spent[c]:9.2f}" for c in COLUMNS)
            + f" {other:6.2f}",
            flush=True,
        )
    print()
    by_dofs = sorted(rows, key=lambda r: r[1])
    worst = max(
        ((a, b) for i, a in enumerate(by_dofs) for b in by_dofs[i + 1 :]),
        key=lambda ab: ab[0][2] / ab[1][2],
        default=None,
    )
    if worst is None:
        print("one size: nothing to compare")
        return 0
    (sa, da, ta), (sb, db, tb) = worst
    strict = ta <= tb
    print(
        f"time monotone in DOFs: {'yes' if strict else 'no'} (strictly); "
        f"{'yes' if ta <= 1.2 * tb else 'no'} within 20 % - the worst pair: {sa:g} m ({da} DOFs) "
        f"{ta:.2f} s against {sb:g} m ({db} DOFs) {tb:.2f} s, ratio {ta / tb:.2f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
