"""A solid part's results in the disk cache: solved once, read back on every later run.

The costly results of a solid part - its Craig-Bampton basis (:func:`~flexshaft.reduction.solidbasis.
solid_basis`: the reduced K and M, the fixed-interface eigenvalues, every node's motion per reduced
coordinate, the check data), its end compliance (:func:`~flexshaft.parts.solidpart.end_compliance`,
6 x 6) and its free-free modes (:func:`~flexshaft.parts.solidpart.free_modes`: the eigenvalues and
shapes) - are minutes of multigrid solves for a part of a few hundred thousand DOFs.
:class:`SolidResults` keeps each in the disk cache of section tables and meshes
(:mod:`flexshaft.input.cache`: its root folder and :func:`~flexshaft.input.cache.entry_key`, in a
``solids/`` folder of its own, as verified entries - :func:`~flexshaft.input.cache.store_entry`), keyed by

- the mesh: a digest of its node, tetrahedron and face arrays' bytes and its element size
  (:func:`mesh_digest`);
- the settings the function states (its ``*_settings``): the material (E, ν, ρ), the interface ties
  and DOFs, the modes asked for, the solver and its tolerances;
- flexshaft's version (:func:`~flexshaft.input.cache.entry_key`) and the source of the modules that
  compute them (:func:`solver_digest`): a changed solver is a new entry, never an old result.

An entry is plain ``.npz`` arrays and one JSON string, written atomically, with the SHA-256 of its
arrays; on reading, the digest, every array's dtype and its shape against the mesh and the settings
are checked, and the values must be finite: anything else is ignored, removed and rebuilt. What is
derived from the mesh alone (a reduction's surface for views) is derived again, not stored.

The model-file loader hands :data:`SOLID_RESULTS` to each solid part (``use_cache``; the CLI's
``--no-cache`` leaves it out, and every result is computed afresh).
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

import numpy as np

from .cache import drop_entry, entry_key, load_entry, store_entry

__all__ = ["SolidResults", "SOLID_RESULTS", "mesh_digest", "solver_digest", "FOLDER"]

#: The cache's folder for solid results (beside ``sections`` and ``meshes``).
FOLDER = "solids"
#: Bumped when an entry's arrays or meta change meaning (old entries are then simply not found).
LAYOUT = 2  # 2: the free modes as eigenvalues (the solver's own result), not frequencies
#: The modules whose source a solid result depends on (relative to the flexshaft package): the
#: elements, the ties and the solves of a solid part, the solvers and the reduction.
SOLVER_SOURCES = ("elements", "linalg", "parts", "reduction")


def mesh_digest(mesh) -> str:
    """SHA-256 of a solid mesh: its nodes (m), tetrahedra, face sets and element size."""
    h = hashlib.sha256()
    nodes = np.ascontiguousarray(mesh.nodes, dtype=np.float64)
    tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
    h.update(repr((nodes.shape, tets.shape, float(mesh.size))).encode())
    h.update(nodes.data)
    h.update(tets.data)
    for name in sorted(mesh.faces):
        tri = np.ascontiguousarray(mesh.faces[name], dtype=np.int64)
        h.update(repr((name, tri.shape)).encode())
        h.update(tri.data)
    return h.hexdigest()


@lru_cache(maxsize=1)
def solver_digest() -> str:
    """SHA-256 over the source of :data:`SOLVER_SOURCES`: the code that computes a solid result."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for name in SOLVER_SOURCES:
        where = root / name
        files = sorted(where.rglob("*.py")) if where.is_dir() else [where]
        for path in files:
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def _key(mesh, settings: dict) -> str:
    return entry_key(
        solid_result=settings,
        mesh=mesh_digest(mesh),
        code=solver_digest(),
        layout_solid=LAYOUT,
    )


def _float(arrays: dict, name: str, shape: tuple) -> np.ndarray:
    """The array ``name``: float64 of ``shape`` with finite values, else ValueError."""
    a = arrays[name]
    if a.dtype != np.float64 or a.shape != shape or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: {a.dtype} {a.shape}, not finite float64 {shape}")
    return a


def _number(v, name: str, lo: float = -np.inf) -> float:
    """``v`` as a float when it is a finite JSON number of at least ``lo``, else ValueError."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v < lo:
        raise ValueError(f"{name}: {v!r}")
    return float(v)


# --- the results: each one's arrays and meta, and back with every array checked ----------------------


def _reduction_out(red) -> tuple[dict, dict]:
    arrays = {
        "K": red.K,
        "M": red.M,
        "eigenvalues": red.eigenvalues,
        "full": red.full,
        "rigid_boundary": red.rigid_boundary,
        "rigid_mass_full": red.rigid_mass_full,
    }
    meta = {
        "dofs": red.dofs,
        "n_residual": int(red.n_residual),
        "slab": float(red.slab),
        "static_residual": float(red.static_residual),
        "interface": red.shapes.interface,
    }
    return arrays, meta


def _reduction_in(mesh, settings: dict, arrays: dict, meta: dict):
    from ..reduction.axisline import solid_shapes
    from ..reduction.solidbasis import SolidReduction

    dofs = meta["dofs"]
    if dofs != settings["dofs"]:
        raise ValueError(f"dofs {dofs!r}")
    nb, r = (12, 6) if dofs == "full" else (2, 1)
    n = int(arrays["K"].shape[0]) if arrays["K"].ndim == 2 else -1
    if n < nb:
        raise ValueError("K smaller than the boundary")
    nm = n - nb
    n_residual = meta["n_residual"]
    if not isinstance(n_residual, int) or isinstance(n_residual, bool) or not 0 <= n_residual <= nm:
        raise ValueError(f"n_residual {n_residual!r}")
    interface = meta["interface"]
    if not isinstance(interface, str):
        raise ValueError("interface")
    full = _float(arrays, "full", (3 * mesh.n_nodes, n))
    return SolidReduction(
        mesh=mesh,
        dofs=dofs,
        K=_float(arrays, "K", (n, n)),
        M=_float(arrays, "M", (n, n)),
        eigenvalues=_float(arrays, "eigenvalues", (nm,)),
        n_residual=n_residual,
        full=full,
        shapes=solid_shapes(mesh, full, interface),
        slab=_number(meta["slab"], "slab", lo=np.finfo(float).tiny),
        rigid_boundary=_float(arrays, "rigid_boundary", (nb, r)),
        rigid_mass_full=_float(arrays, "rigid_mass_full", (r, r)),
        static_residual=_number(meta["static_residual"], "static_residual", lo=0.0),
    )


def _stiffness_out(result) -> tuple[dict, dict]:
    s = result.solver
    meta = {
        "dofs": int(result.unknowns),
        "solver": [s.method, int(s.iterations), float(s.residual), float(s.setup_s), float(s.solve_s)],
    }
    return {"compliance": result.compliance}, meta


def _stiffness_in(mesh, settings: dict, arrays: dict, meta: dict):
    from ..linalg.spd import SolveReport
    from ..parts.solidpart import EndCompliance

    method, iterations, residual, setup_s, solve_s = meta["solver"]
    if not isinstance(method, str) or not isinstance(iterations, int) or isinstance(iterations, bool):
        raise ValueError("solver")
    report = SolveReport(
        method,
        iterations,
        _number(residual, "residual", 0.0),
        _number(setup_s, "setup_s", 0.0),
        _number(solve_s, "solve_s", 0.0),
    )
    dofs = meta["dofs"]
    if not isinstance(dofs, int) or isinstance(dofs, bool) or dofs <= 0:
        raise ValueError("dofs")
    return EndCompliance(_float(arrays, "compliance", (6, 6)), dofs, report)


def _modes_out(solution) -> tuple[dict, dict]:
    arrays = {"eigenvalues": solution.eigenvalues, "vectors": solution.vectors, "rigid": solution.rigid}
    return arrays, {"method": solution.method}


def _modes_in(mesh, settings: dict, arrays: dict, meta: dict):
    from ..linalg.eigen import EigenSolution

    lam = arrays["eigenvalues"]
    m = int(lam.shape[0]) if lam.ndim == 1 else -1
    rigid = arrays["rigid"]
    if rigid.dtype != np.bool_ or rigid.shape != (m,):
        raise ValueError("rigid")
    method = meta["method"]
    if not isinstance(method, str):
        raise ValueError("method")
    return EigenSolution(
        _float(arrays, "eigenvalues", (m,)),
        _float(arrays, "vectors", (3 * mesh.n_nodes, m)),
        rigid,
        method,
    )


_CODECS = {
    "solid reduction": (_reduction_out, _reduction_in),
    "solid stiffness": (_stiffness_out, _stiffness_in),
    "solid modes": (_modes_out, _modes_in),
}


class SolidResults:
    """The disk cache's solid results (module docstring): what the solid stages are handed as ``cache``.

    ``settings`` is the plain-JSON dict a result's function states (its ``"result"`` names which:
    ``"solid reduction"``, ``"solid stiffness"``, ``"solid modes"``).
    """

    def load(self, mesh, settings: dict):
        """The result kept for ``mesh`` and ``settings``, or None (none kept, or not valid: removed)."""
        _, read = _CODECS[settings["result"]]
        key = _key(mesh, settings)
        got = load_entry(FOLDER, key)
        if got is None:
            return None
        arrays, meta = got
        try:
            return read(mesh, settings, arrays, meta)
        except Exception:  # noqa: BLE001 - an entry whose content does not fit is rebuilt, never trusted
            drop_entry(FOLDER, key)
            return None

    def store(self, mesh, settings: dict, result) -> None:
        """Keep ``result`` for ``mesh`` and ``settings`` (a cache that cannot be written is not used)."""
        write, _ = _CODECS[settings["result"]]
        arrays, meta = write(result)
        store_entry(FOLDER, _key(mesh, settings), arrays, meta)

    def kept(self, mesh, settings: dict, compute):
        """The result kept for ``mesh`` and ``settings``, else ``compute()``, then kept: ``(result,
        whether it was read from the cache)``. The one load-or-solve-and-store of every solid result."""
        got = self.load(mesh, settings)
        if got is not None:
            return got, True
        result = compute()
        self.store(mesh, settings, result)
        return result, False

    def __repr__(self) -> str:
        return "SolidResults()"

    def __reduce__(self):
        return (_the_results, ())


def _the_results() -> SolidResults:
    return SOLID_RESULTS


#: The one instance the model-file loader hands to solid parts.
SOLID_RESULTS = SolidResults()
