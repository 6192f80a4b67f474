"""Reading a part file in an isolated child (issue 33) against build123d's and trimesh's in-process reading.

What it measures
----------------
The test bench's PTSS parts 1, 2 and 4 (``geometry.parts.testbench``) and the whole bench as one
STEP (seven solids), written as STEP files, each read

- the way it was read before issue 33 (the peer): ``build123d.import_step`` in this process;
- by :func:`geometry.cadio.read_step`: OCCT translates it in a forked child, which writes the shape
  as OCCT's binary BREP; the parent reads those bytes back.

Interleaved (peer, ours, peer, ours, ...), best of 7 each: on a shared machine every disturbance
only adds time. The difference is the isolation's cost; it is split into its parts: an empty fork
and join of :func:`flexshaft.system.isolate.run_isolated`, and OCCT's binary BREP written and read in one
process (with its size). For comparison, pickling the build123d shape (build123d registers
``copyreg`` reducers that write the same binary BREP, plus its Python attributes).

PTSS part 2 as a binary STL (0.1 mm chord) is read the same two ways: trimesh in this process
(load, merge, the watertight and winding checks, orientation, scale - what ``read_mesh`` did before)
against :func:`geometry.cadio.read_mesh` (the same in the child, vertices and triangles back).

Both readings of each file are checked equal (vertices bit for bit) before anything is timed.

Run: ``.venv/bin/python benchmarks/bench_cadread.py`` (~30 s). Timings are printed, never asserted.
"""

from __future__ import annotations

import io
import pickle
import sys
import tempfile
from pathlib import Path

import numpy as np
from timing import best as _best
from timing import interleaved as _interleaved

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

REPEAT = 7


def interleaved(a, b, repeat: int = REPEAT) -> tuple[float, float]:
    """Best wall time of ``a()`` and of ``b()``, run in turns (s)."""
    t = _interleaved({"a": a, "b": b}, repeat)
    return t["a"], t["b"]


def best(fn, repeat: int = REPEAT) -> float:
    return _best(fn, repeat)[0]


def vertices(shape) -> np.ndarray:
    return np.array(sorted((v.X, v.Y, v.Z) for v in shape.vertices()))


def main() -> None:
    import build123d as bd

    from flexshaft.system.isolate import run_isolated
    from geometry.cadio import _from_bytes, _to_bytes, read_mesh, read_step, write_step, write_stl
    from geometry.parts import testbench

    def failed(failure):
        raise RuntimeError(failure.reason)

    fork = best(lambda: run_isolated(lambda send: None, timeout=60.0, error=failed))
    print(f"empty run_isolated (fork, pipe, join) with build123d loaded: {fork * 1e3:.1f} ms")
    print()
    print(
        f"{'part':<22} {'STEP kB':>8} {'faces':>6} {'in-process ms':>14} {'isolated ms':>12} {'ratio':>6} "
        f"{'cost ms':>8} | {'BREP kB':>8} {'write+read ms':>14} | {'pickle kB':>9} {'dumps+loads ms':>15}"
    )
    with tempfile.TemporaryDirectory(prefix="bench-cadread-") as tmp:
        parts = {name: getattr(testbench, name)() for name in ("ptss_part1", "ptss_part2", "ptss_part4")}
        parts["whole bench (7 solids)"] = bd.Compound(list(testbench.ptss().values()))
        for name, part in parts.items():
            path = write_step(part, Path(tmp) / f"{name.split()[0]}.step")
            ours, theirs = read_step(path), bd.import_step(path)
            assert np.array_equal(vertices(ours), vertices(theirs)), name
            t_peer, t_ours = interleaved(lambda p=path: bd.import_step(p), lambda p=path: read_step(p))

            def brep_round_trip(shape=theirs):
                data = _to_bytes(shape)  # what the child sends and the caller reads back
                _from_bytes(data)
                return len(data)

            size = brep_round_trip()
            t_brep = best(brep_round_trip)
            blob = pickle.dumps(theirs, protocol=5)
            t_pickle = best(lambda s=theirs: pickle.loads(pickle.dumps(s, protocol=5)))
            print(
                f"{name:<22} {path.stat().st_size / 1e3:8.0f} {len(theirs.faces()):6d} {t_peer * 1e3:14.1f} "
                f"{t_ours * 1e3:12.1f} {t_ours / t_peer:6.2f} {(t_ours - t_peer) * 1e3:8.1f} | "
                f"{size / 1e3:8.0f} {t_brep * 1e3:14.2f} | {len(blob) / 1e3:9.0f} {t_pickle * 1e3:15.2f}"
            )

        import trimesh

        stl = write_stl(parts["ptss_part2"], Path(tmp) / "p2.stl", tolerance=1e-4, angular_tolerance=0.1)

        def in_process():
            mesh = trimesh.load(io.BytesIO(stl.read_bytes()), file_type="stl", force="mesh", process=True)
            mesh.merge_vertices()
            assert mesh.is_watertight and mesh.is_winding_consistent
            if mesh.volume < 0:
                mesh.invert()
            mesh.apply_scale(1e-3)
            return mesh

        mine, peer = read_mesh(stl), in_process()
        assert np.array_equal(mine.vertices, peer.vertices) and np.array_equal(mine.faces, peer.faces)
        t_peer, t_ours = interleaved(in_process, lambda: read_mesh(stl))
        print()
        print(
            f"PTSS part 2 as binary STL ({stl.stat().st_size / 1e6:.1f} MB, {len(peer.faces)} triangles): "
            f"trimesh in-process {t_peer * 1e3:.1f} ms, read_mesh isolated {t_ours * 1e3:.1f} ms, "
            f"ratio {t_ours / t_peer:.2f}, cost {(t_ours - t_peer) * 1e3:.1f} ms"
        )


if __name__ == "__main__":
    main()
