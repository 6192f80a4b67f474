"""A solid part at a million DOFs: meshing, the twist test and Craig-Bampton, against scikit-fem + pyamg.

What it measures
----------------
PTSS part 1 of the test bench (``geometry.parts.testbench.ptss_part1``: a 3 m steel tube with a hub
and a 12-hole bolted flange at each end, shoulder fillets) meshed by :func:`geometry.meshing.mesh_solid`
into curved 10-node tetrahedra at ``--size`` (default 0.0145 m: 332 985 nodes, 998 955 DOFs; the
mesher before its graded size field of 2026-11-28 made 1 035 384 DOFs at 0.017 m), then

1. the twist test as a user runs it (``flexshaft twist MODEL``): a model file with the part as
   ``fe = "solid"`` at ``mesh_size`` = ``--size``, loaded with an empty mesh cache (so it meshes),
   then :func:`flexshaft.twist_test` - the part's static condensation onto its end faces' master
   nodes (RBE2; a torsion model: θx of each, two solves by multigrid-preconditioned block CG to a
   relative residual of 1e-8), the start clamped, a torque at the end; meshing + twist test is the
   issue's target (a): under 90 s and 8 GiB;
2. the end's whole 6 x 6 stiffness (``--only stiffness``, not in the default run):
   :func:`flexshaft.analysis.twist.part_stiffness` - the six unit loads at the end's master,
   the start clamped (torsion, axial and both bendings at once; each load costs about one torque's
   solve);
3. Craig-Bampton: :func:`flexshaft.reduction.solidbasis.solid_basis` with ``dofs="full"`` and
   ``modes=20`` - assembly, ties, 12 constraint modes, 20 fixed-interface modes (LOBPCG), 12
   residual vectors, the reduced matrices - the issue's target (b): under 5 minutes;
4. the peer: the same mesh's corners as a scikit-fem 12 ``MeshTet``, its quadratic vector element
   (``ElementVector(ElementTetP2())``, straight: mid-side nodes at the edges' midpoints) assembled
   with ``linear_elasticity``, the start face's DOFs clamped and the end face's nodes loaded by a
   torque, solved by pyamg's smoothed aggregation (its defaults, the rigid-body modes as near-null
   space) accelerating CG to the same relative residual: what a scikit-fem user writes for the twist
   test, with the same one load as the twist test (an averaging end rather than a rigid one: its
   stiffness is a little lower).

Each measurement runs in a fresh process (this script again, ``--child``, started through a small
launcher: Linux carries a parent's ``ru_maxrss`` into a forked child), whose peak memory is its
``getrusage(RUSAGE_SELF).ru_maxrss`` - numpy's and scipy's arrays included, which tracemalloc does
not see. The flexshaft runs are repeated with ``OPENBLAS_NUM_THREADS`` 1 and 2 (``--threads``), and
with ``--busy`` once more with every core kept busy by spinning processes (``benchmarks/busy.py``).
The stages inside the twist test come from its solver report, those of the reduction from its
``progress`` callback.

Run (from the repository root; the peer needs ``benchmarks/.venv-peers`` with scikit-fem and pyamg):

    .venv/bin/python benchmarks/bench_solid.py        # ~25 min: twist, CB, 1 and 2 threads, the peer
    .venv/bin/python benchmarks/bench_solid.py --only twist --threads 1 --no-peer
    .venv/bin/python benchmarks/bench_solid.py --size 0.06 --no-peer  # 142 000 DOFs, a few minutes
    .venv/bin/python benchmarks/bench_solid.py --busy               # and again with both cores busy

The C heap keeps the iterations' freed blocks for reuse while a child runs (``benchmarks/heap.py``:
20 modes of a million DOFs spent 76 s of 230 s in the kernel faulting in fresh mappings without it,
9 s of 156 s with it); flexshaft itself leaves the heap alone. A million-DOF reduction holds ~10 GB;
flexshaft's memory ceiling (2 GB by default) is raised for the
children (``FLEXSHAFT_MAX_MEMORY_MB``). Timings are printed, never asserted.
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
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PEER_PY = HERE / ".venv-peers" / "bin" / "python"
#: Starts a child from a small interpreter, so that its ru_maxrss is its own (see bench_modes.py).
LAUNCHER = "import subprocess, sys; sys.exit(subprocess.call(sys.argv[1:]))"
TIMEOUT_S = 3600
#: The relative residual both tools solve to (flexshaft's default, :data:`flexshaft.linalg.spd.RTOL`).
RTOL = 1e-8
#: The memory ceiling the children run under, MB (a million-DOF reduction holds ~10 GB).
MEMORY_MB = 22_000
E, NU, RHO = 210e9, 0.3, 7850.0

#: The peer's code, run by the peers' interpreter (scikit-fem and pyamg never enter flexshaft's).
PEER = r"""
import json, resource, sys, time
import numpy as np
import pyamg
from skfem import Basis, ElementTetP2, ElementVector, MeshTet, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0

data = np.load(sys.argv[1])
E, nu, rtol, length = float(data["E"]), float(data["nu"]), float(data["rtol"]), float(data["length"])
before = peak_mib()
t0 = time.perf_counter()
mesh = MeshTet(data["p"], data["t"])
basis = Basis(mesh, ElementVector(ElementTetP2()), intorder=2)
K = asm(linear_elasticity(*lame_parameters(E, nu)), basis).tocsr()
t1 = time.perf_counter()
x = basis.doflocs                      # (3, N): where each DOF sits
comp = np.empty(x.shape[1], dtype=int)  # and which displacement it is
for c in range(3):
    comp[basis.nodal_dofs[c]] = c
    comp[basis.edge_dofs[c]] = c
tol = 1e-6 * length
start = np.isclose(x[0], 0.0, atol=tol)
end = np.isclose(x[0], length, atol=tol)
# a torque about x on the end face: tangential forces r x e_x per DOF, scaled to 1 N.m
f = np.zeros(x.shape[1])
f[end & (comp == 1)] = -x[2, end & (comp == 1)]
f[end & (comp == 2)] = x[1, end & (comp == 2)]
f /= np.sum(f * np.where(comp == 1, -x[2], np.where(comp == 2, x[1], 0.0)))
free = ~start
A = K[free][:, free].tocsr()
b = f[free]
# the rigid-body modes as pyamg's near-null space
B = np.zeros((x.shape[1], 6))
for c in range(3):
    B[comp == c, c] = 1.0
rot = [(1, 2), (2, 0), (0, 1)]  # rotation about axis a moves component i by -x_j, j by +x_i
for a, (i, j) in enumerate(rot):
    B[comp == i, 3 + a] = -x[j, comp == i]
    B[comp == j, 3 + a] = x[i, comp == j]
B = B[free]
del K
t2 = time.perf_counter()
ml = pyamg.smoothed_aggregation_solver(A, B=B, symmetry="symmetric")
t3 = time.perf_counter()
residuals = []
u = ml.solve(b, tol=rtol, accel="cg", maxiter=2000, residuals=residuals)
t4 = time.perf_counter()
angle = float(np.sum(u * b))  # the end's mean twist per unit torque (the load's own work)
print(json.dumps({
    "seconds_assembly": t1 - t0, "seconds_setup": t3 - t2, "seconds_solve": t4 - t3,
    "seconds": t4 - t0, "iterations": len(residuals) - 1,
    "residual": float(np.linalg.norm(b - A @ u) / np.linalg.norm(b)),
    "dofs": int(A.shape[0]), "torsion": 1.0 / angle, "peak_mib": peak_mib(), "before_mib": before,
}))
"""


#: What --only may pick: the twist test, the end's 6 x 6 stiffness, Craig-Bampton.
CHOICES = ["twist", "stiffness", "cb"]
#: The twist test's model file: PTSS part 1 alone, a solid of the same material as the peer's.
MODEL = """
[model]
name = "PTSS part 1 as a solid"
dofs = "torsion"

[materials.bench]
E = {E}
nu = {nu}
rho = {rho}

[[chain]]
name = "part 1"
type = "cad"
geometry = "geometry.parts.testbench:ptss_part1"
material = "bench"
fe = "solid"
mesh_size = "{size_mm} mm"
"""


def peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _mesh(size: float):
    from geometry.meshing import mesh_solid
    from geometry.parts.testbench import ptss_part1

    return mesh_solid(ptss_part1(), name="PTSS part 1", size=size)


def child(what: str, size: float, modes: int, save: str | None) -> None:
    """One measurement in this (fresh) process: one JSON line."""
    import numpy as np

    from flexshaft.elements.materials import Material

    if what == "twist":  # the whole of it, as the command line does it: meshing included
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["FLEXSHAFT_CACHE_DIR"] = tmp  # an empty mesh cache: the part is meshed
            model = Path(tmp) / "ptss_part1.toml"
            model.write_text(MODEL.format(E=E, nu=NU, rho=RHO, size_mm=1000 * size))
            import flexshaft as fs

            t0 = time.perf_counter()
            drivetrain = fs.load_model(model)
            t1 = time.perf_counter()
            result = fs.twist_test(drivetrain, 1000.0)
            t2 = time.perf_counter()
            part = result.parts[0]
            mesh = drivetrain.components[0].solid_mesh
        record = {
            "dofs": 3 * mesh.n_nodes,
            "elements": int(mesh.n_elements),
            "seconds_mesh": t1 - t0,
            "seconds_twist": t2 - t1,
            "torsion": float(part.stiffness),
        }
    else:
        steel = Material(E=E, nu=NU, rho=RHO)
        t0 = time.perf_counter()
        mesh = _mesh(size)
        t1 = time.perf_counter()
        record = {"dofs": 3 * mesh.n_nodes, "elements": int(mesh.n_elements), "seconds_mesh": t1 - t0}
    if what == "stiffness":
        from flexshaft.analysis.twist import part_stiffness
        from flexshaft.parts.solidpart import solid_part_model

        result = part_stiffness(solid_part_model(mesh, steel))
        t2 = time.perf_counter()
        record.update(
            seconds_stiffness=t2 - t1,
            seconds_setup=result.solver.setup_s,
            seconds_solve=result.solver.solve_s,
            iterations=result.solver.iterations,
            residual=result.solver.residual,
            solver=result.solver.method,
            torsion=result.torsion,
        )
    elif what == "cb":
        from flexshaft.parts.solidpart import solid_part_model
        from flexshaft.reduction.solidbasis import solid_basis

        stages = []

        def mark(stage, fraction):
            stages.append((stage, time.perf_counter()))

        red = solid_basis(solid_part_model(mesh, steel, dofs="full"), modes=modes, progress=mark)
        t2 = time.perf_counter()
        marks = [(s, t) for s, t in stages] + [("end", t2)]
        record.update(
            seconds_cb=t2 - t1,
            stages={a: b_t - a_t for (a, a_t), (_, b_t) in zip(marks, marks[1:], strict=False)},
            frequencies_hz=(np.sqrt(np.clip(red.eigenvalues[:modes], 0, None)) / (2 * np.pi)).tolist(),
            reduced=int(red.K.shape[0]),
        )
    record["peak_mib"] = peak_mib()
    if save:  # the corners for the peer, outside the timing
        corners = np.unique(mesh.tets[:, :4])
        local = np.searchsorted(corners, mesh.tets[:, :4])
        np.savez(save, p=mesh.nodes[corners].T, t=local.T, E=E, nu=NU, rtol=RTOL, length=float(mesh.length))
    print(json.dumps(record))


def run(cmd: list[str], env: dict | None = None) -> dict:
    proc = subprocess.run(
        [sys.executable, "-c", LAUNCHER, *cmd], capture_output=True, text=True, timeout=TIMEOUT_S, env=env
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{cmd[1]} failed: {proc.stderr.strip()[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def flexshaft_run(what: str, size: float, modes: int, threads: int, save: Path | None = None) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env.update(OPENBLAS_NUM_THREADS=str(threads), FLEXSHAFT_MAX_MEMORY_MB=str(MEMORY_MB))
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", what, "--size", str(size)]
    cmd += ["--modes", str(modes)] + (["--save", str(save)] if save else [])
    return run(cmd, env)


def show(label: str, r: dict) -> None:
    if "seconds_twist" in r:
        print(
            f"{label:34s} {r['dofs']:>9d} DOFs  load + mesh {r['seconds_mesh']:6.1f} s  "
            f"twist test {r['seconds_twist']:6.1f} s  = {r['seconds_mesh'] + r['seconds_twist']:6.1f} s  "
            f"peak {r['peak_mib'] / 1024:5.2f} GiB  T/θ {r['torsion']:.6e} N·m/rad"
        )
    elif "seconds_stiffness" in r:
        total = r["seconds_mesh"] + r["seconds_stiffness"]
        rest = r["seconds_stiffness"] - r["seconds_setup"] - r["seconds_solve"]
        print(
            f"{label:34s} {r['dofs']:>9d} DOFs  mesh {r['seconds_mesh']:6.1f} s  "
            f"assembly+ties {rest:6.1f} s  "
            f"setup {r['seconds_setup']:5.1f} s  solve {r['seconds_solve']:6.1f} s ({r['iterations']} its)  "
            f"= {total:6.1f} s  peak {r['peak_mib'] / 1024:5.2f} GiB  T/θ {r['torsion']:.6e} N·m/rad"
        )
    else:
        stages = "  ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
        print(
            f"{label:34s} {r['dofs']:>9d} DOFs  mesh {r['seconds_mesh']:6.1f} s  CB {r['seconds_cb']:6.1f} s "
            f"(mesh + CB {r['seconds_mesh'] + r['seconds_cb']:6.1f} s)  "
            f"peak {r['peak_mib'] / 1024:5.2f} GiB\n"
            f"{'':34s} stages: {stages}\n"
            f"{'':34s} f (Hz): {', '.join(f'{f:.2f}' for f in r['frequencies_hz'])}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=float, default=0.0145, help="element size, m (0.0145: 998 955 DOFs)")
    parser.add_argument("--modes", type=int, default=20, help="fixed-interface modes of the reduction")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="OPENBLAS_NUM_THREADS values")
    parser.add_argument("--only", choices=CHOICES, help="one flexshaft measurement")
    parser.add_argument("--no-peer", action="store_true", help="flexshaft only")
    parser.add_argument("--busy", action="store_true", help="also with every core kept busy")
    parser.add_argument("--child", choices=CHOICES, help=argparse.SUPPRESS)
    parser.add_argument("--save", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        from heap import reused_blocks  # benchmarks/heap.py: the iterations' freed blocks reused

        with reused_blocks():
            child(args.child, args.size, args.modes, args.save)
        return
    sys.path.insert(0, str(HERE))
    from busy import busy  # benchmarks/busy.py: spinning processes on every core

    peer = not args.no_peer and args.only in (None, "twist")
    if peer and not PEER_PY.exists():
        print("(peer skipped: benchmarks/.venv-peers with scikit-fem and pyamg is missing)")
        peer = False
    what = [args.only] if args.only else ["twist", "cb"]
    load = os.getloadavg()[0]
    print(f"load average {load:.2f} on {os.cpu_count()} cores; PTSS part 1 at size {args.size} m")
    with tempfile.TemporaryDirectory() as tmp:
        mesh_file = Path(tmp) / "mesh.npz"
        rows = {}
        for loaded in [False, True] if args.busy else [False]:
            for threads in args.threads:
                for w in what:
                    label = f"{w}, {threads} BLAS thread{'s' if threads > 1 else ''}"
                    label += ", busy" if loaded else ""
                    save = mesh_file if peer and not mesh_file.exists() and w == "twist" else None
                    if loaded:
                        with busy():
                            r = flexshaft_run(w, args.size, args.modes, threads, save)
                    else:
                        r = flexshaft_run(w, args.size, args.modes, threads, save)
                    rows[label] = r
                    show(label, r)
        if peer:
            cmd = [str(PEER_PY), "-c", PEER, str(mesh_file)]
            theirs = run(cmd)
            print(
                f"{'scikit-fem 12 + pyamg (the torque)':34s} {theirs['dofs']:>9d} DOFs  assembly "
                f"{theirs['seconds_assembly']:6.1f} s  AMG setup {theirs['seconds_setup']:5.1f} s  "
                f"solve {theirs['seconds_solve']:6.1f} s ({theirs['iterations']} its)  "
                f"= {theirs['seconds']:6.1f} s  "
                f"peak {theirs['peak_mib'] / 1024:5.2f} GiB  T/θ {theirs['torsion']:.6e} N·m/rad"
            )
            for label, r in rows.items():
                if "seconds_twist" in r:
                    print(
                        f"flexshaft twist ({label}) / peer: "
                        f"time {r['seconds_twist'] / theirs['seconds']:.2f} "
                        f"(with meshing {(r['seconds_mesh'] + r['seconds_twist']) / theirs['seconds']:.2f}), "
                        f"peak memory {r['peak_mib'] / theirs['peak_mib']:.2f}"
                    )


if __name__ == "__main__":
    main()
