"""Solid-part matrices: flexshaft's 10-node tetrahedra against scikit-fem's P2 assembly.

What it measures
----------------
Stiffness K and consistent mass M of a steel box (E 210 GPa, ν 0.29, ρ 7850 kg/m³) of
0.4 x 0.3 x 0.3 m cut into n x n x n cells, each into the 6 Kuhn tetrahedra of its main
diagonal, quadratic (10-node) elements with mid-side nodes at the edges' midpoints:

1. agreement - on a small mesh (4 x 3 x 3 cells, interior corners moved at random, so the
   elements differ), flexshaft's K and M against scikit-fem 12's (``ElementVector(ElementTetP2())``,
   ``linear_elasticity`` and ρ u·v, the DOFs mapped through scikit-fem's vertex and edge numbering):
   both integrate straight P2 elements exactly, so they agree to round-off;
2. time and peak memory at n = 34 (235 824 elements, 328 509 nodes, 985 527 DOFs), each tool in
   a fresh process (started through a small launcher: Linux carries a parent's ru_maxrss into a
   forked child) - flexshaft's :func:`~flexshaft.elements.tet10.solid_matrices`, and scikit-fem's
   bases plus its two ``asm`` calls (K with a 4-point rule, exact here, M with its default
   order 4) in the peers' virtualenv;
3. flexshaft again with the node numbering shuffled at random (the widest bandwidth there is),
   which takes the assembly's touched-rows path instead of the span path.

Peak memory is ``getrusage(RUSAGE_SELF).ru_maxrss`` of the process; "before" is the same figure
just before the timed work (imports and the mesh), so peak − before is what the assembly added.

Run: ``.venv/bin/python benchmarks/bench_tet10.py [--cells 34] [--no-peer]`` (scikit-fem needs
``benchmarks/setup_peers.sh``). Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from itertools import permutations
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
PEER_PY = HERE / ".venv-peers" / "bin" / "python"
SIZE = (0.4, 0.3, 0.3)
E, NU, RHO = 210e9, 0.29, 7850.0
EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))  # VTK QUADRATIC_TETRA's mid-side nodes
#: Starts a child from a small interpreter, so that its ru_maxrss is its own (see bench_modes.py).
LAUNCHER = "import subprocess, sys; sys.exit(subprocess.call(sys.argv[1:]))"
TIMEOUT_S = 3600


def box_mesh(cells, size=SIZE):
    """Nodes (n, 3) and 10-node tetrahedra (m, 10) of a box cut into Kuhn tetrahedra (as the
    tests' generator: nodes on the doubled grid, x slowest)."""
    cells = np.asarray(cells)
    shape = 2 * cells + 1
    grid = np.stack(np.meshgrid(*(np.arange(s) for s in shape), indexing="ij"), -1).reshape(-1, 3)
    nodes = grid * (np.asarray(size, float) / (2 * cells))
    eye = np.eye(3, dtype=int)
    kuhn = []
    for p in permutations(range(3)):
        path = np.array([[0, 0, 0], eye[p[0]], eye[p[0]] + eye[p[1]], [1, 1, 1]])
        if np.linalg.det(path[1:] - path[0]) < 0:
            path = path[[0, 2, 1, 3]]
        kuhn.append(path)
    origins = np.stack(np.meshgrid(*(np.arange(c) for c in cells), indexing="ij"), -1).reshape(-1, 3)
    corners = 2 * origins[:, None, None, :] + 2 * np.array(kuhn)[None]
    mids = np.stack([(corners[:, :, a] + corners[:, :, b]) // 2 for a, b in EDGES], axis=2)
    at = np.concatenate([corners, mids], axis=2).reshape(-1, 10, 3)
    return nodes, (at[..., 0] * shape[1] + at[..., 1]) * shape[2] + at[..., 2]


def shuffled(nodes, tets, seed=0):
    """The same mesh with its nodes renumbered at random."""
    perm = np.random.default_rng(seed).permutation(len(nodes))  # node k becomes perm[k]
    moved = np.empty_like(nodes)
    moved[perm] = nodes
    return moved, perm[tets]


def peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def flexshaft_matrices(nodes, tets):
    from flexshaft.elements.materials import Material
    from flexshaft.elements.tet10 import solid_matrices
    from flexshaft.elements.tetmesh import TetMesh

    return solid_matrices(TetMesh("box", nodes, tets), Material(E=E, nu=NU, rho=RHO))


def child(cells: int, shuffle: bool) -> None:
    """flexshaft's assembly in this (fresh) process: one JSON line of time and memory."""
    nodes, tets = box_mesh((cells,) * 3)
    if shuffle:
        nodes, tets = shuffled(nodes, tets)
    flexshaft_matrices(*box_mesh((1, 1, 1)))  # imports and first calls, outside the timing
    before = peak_mib()
    t0 = time.perf_counter()
    r = flexshaft_matrices(nodes, tets)
    seconds = time.perf_counter() - t0
    print(
        json.dumps(
            {
                "seconds": seconds,
                "peak_mib": peak_mib(),
                "before_mib": before,
                "n_dofs": r.n_dofs,
                "nnz_K": int(r.K.nnz),
                "nnz_M": int(r.M.nnz),
            }
        )
    )


def run(cmd: list[str]) -> dict:
    proc = subprocess.run(
        [sys.executable, "-c", LAUNCHER, *cmd], capture_output=True, text=True, timeout=TIMEOUT_S
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{cmd[1]} failed: {proc.stderr.strip()[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def flexshaft_run(cells: int, shuffle: bool = False) -> dict:
    env_cmd = [sys.executable, str(Path(__file__).resolve()), "--child", str(cells)]
    return run(env_cmd + (["--shuffle"] if shuffle else []))


def peer_mesh(nodes, tets, path: Path) -> np.ndarray:
    """Write the mesh's corners for scikit-fem; return the corner nodes' flexshaft indices."""
    corners = np.unique(tets[:, :4])
    local = np.searchsorted(corners, tets[:, :4])
    np.savez(path, p=nodes[corners].T, t=local.T, E=E, nu=NU, rho=RHO)
    return corners


def peer_run(path: Path, matrices: Path | None = None) -> dict:
    cmd = [str(PEER_PY), str(HERE / "peers" / "skfem_tet10.py"), str(path)]
    return run(cmd + (["--matrices", str(matrices)] if matrices else []))


def agreement(tmp: Path) -> None:
    import scipy.sparse as sp

    nodes, tets = box_mesh((4, 3, 3))
    rng = np.random.default_rng(1)
    h = min(s / c for s, c in zip(SIZE, (4, 3, 3), strict=True))
    inner = ~np.any(np.isclose(nodes, 0.0) | np.isclose(nodes, SIZE), axis=1)
    is_corner = np.zeros(len(nodes), bool)
    is_corner[tets[:, :4]] = True
    move = inner & is_corner
    nodes[move] += rng.uniform(-0.08 * h, 0.08 * h, (move.sum(), 3))
    for k, (a, b) in enumerate(EDGES):  # straight elements: mid-side nodes at the midpoints
        nodes[tets[:, 4 + k]] = 0.5 * (nodes[tets[:, a]] + nodes[tets[:, b]])
    ours = flexshaft_matrices(nodes, tets)
    corners = peer_mesh(nodes, tets, tmp / "small.npz")
    peer_run(tmp / "small.npz", tmp / "small_out.npz")
    d = np.load(tmp / "small_out.npz")
    n = 3 * len(nodes)
    K = sp.csr_array((d["K_data"], d["K_indices"], d["K_indptr"]), shape=(n, n)).toarray()
    M = sp.csr_array((d["M_data"], d["M_indices"], d["M_indptr"]), shape=(n, n)).toarray()
    # scikit-fem's DOF -> flexshaft's: vertex v is corner node corners[v]; edge e (vertices
    # edges[:, e]) is the mid-side node between those corners.
    mid = {}
    for k, (a, b) in enumerate(EDGES):
        for ca, cb, m in zip(tets[:, a], tets[:, b], tets[:, 4 + k], strict=True):
            mid[(min(ca, cb), max(ca, cb))] = m
    ours_of = np.empty(n, dtype=np.int64)
    for c in range(3):
        ours_of[d["nodal_dofs"][c]] = 3 * corners + c
        ends = corners[d["edges"]]
        ours_of[d["edge_dofs"][c]] = 3 * np.array([mid[(min(a, b), max(a, b))] for a, b in ends.T]) + c
    Ko = ours.K.toarray()[np.ix_(ours_of, ours_of)]
    Mo = ours.M.toarray()[np.ix_(ours_of, ours_of)]
    dk = np.abs(Ko - K).max() / np.abs(K).max()
    dm = np.abs(Mo - M).max() / np.abs(M).max()
    print(
        f"agreement, 4 x 3 x 3 cells ({len(tets)} elements, {n} DOFs, interior corners moved): "
        f"max |K - K_skfem| / max |K| = {dk:.1e}, max |M - M_skfem| / max |M| = {dm:.1e}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=34, help="cells per side (34: 985 527 DOFs)")
    parser.add_argument("--no-peer", action="store_true", help="flexshaft only")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--shuffle", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        child(args.child, args.shuffle)
        return
    peer = not args.no_peer and PEER_PY.exists()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if peer:
            agreement(tmp)
        n = args.cells
        nodes, tets = box_mesh((n,) * 3)
        print(f"\n{n}³ cells: {len(tets)} elements, {len(nodes)} nodes, {3 * len(nodes)} DOFs")
        rows = [("flexshaft", flexshaft_run(n)), ("flexshaft, nodes shuffled", flexshaft_run(n, True))]
        if peer:
            peer_mesh(nodes, tets, tmp / "big.npz")
            rows.append(("scikit-fem 12.0.2", peer_run(tmp / "big.npz")))
        elif not args.no_peer:
            print("(scikit-fem skipped: run benchmarks/setup_peers.sh)")
        print(f"{'':28s} {'time s':>8s} {'peak MiB':>9s} {'added MiB':>9s} {'nnz K':>11s} {'nnz M':>11s}")
        for name, r in rows:
            print(
                f"{name:28s} {r['seconds']:8.2f} {r['peak_mib']:9.0f} {r['peak_mib'] - r['before_mib']:9.0f} "
                f"{r['nnz_K']:11d} {r['nnz_M']:11d}"
            )
        if peer:
            ours, theirs = rows[0][1], rows[-1][1]
            added = (ours["peak_mib"] - ours["before_mib"]) / (theirs["peak_mib"] - theirs["before_mib"])
            print(
                f"flexshaft / scikit-fem: time {ours['seconds'] / theirs['seconds']:.2f}, peak memory "
                f"{ours['peak_mib'] / theirs['peak_mib']:.2f}, memory added {added:.2f} "
                f"(scikit-fem: bases {theirs['seconds_basis']:.1f} s, K {theirs['seconds_K']:.1f} s, "
                f"M {theirs['seconds_M']:.1f} s)"
            )


if __name__ == "__main__":
    main()
