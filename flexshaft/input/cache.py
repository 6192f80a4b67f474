"""A disk cache of section tables, solid meshes and solid results, so that a part costs its slicing,
meshing or solving once.

An entry is keyed by what it depends on: for a table the geometry's content (a file's bytes, or the
part function's name, its module's source and the source of the whole ``geometry`` package,
since the function builds with it), the parameters, unit, axis and Poisson's ratio, and
flexshaft's version; for a solid part's results (:mod:`flexshaft.input.solidcache`) its mesh's arrays,
the material and the solver's settings. It lives in ``$FLEXSHAFT_CACHE_DIR``, else
``$XDG_CACHE_HOME/flexshaft``, else ``~/.cache/flexshaft``. Entries are plain ``.npz`` arrays and
one JSON string (no pickles), written atomically, read as any input is (a regular file under a
ceiling, :mod:`flexshaft.system.inputs`); one that cannot be read back whole and valid is ignored and
rebuilt, never trusted. Every entry - table, mesh or solid result - is one format
(:func:`store_entry`, :func:`load_entry`): it carries the SHA-256 of its arrays, checked on every
read, so a flipped byte, a truncated or an edited array is found.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..sections.table import SectionTable
from ..system.inputs import BODY, Kind, ceiling_bytes, open_input, open_seekable
from ..version import __version__

__all__ = [
    "cache_dir",
    "source_digest",
    "geometry_digest",
    "package_digest",
    "entry_key",
    "load_table",
    "store_table",
    "load_mesh",
    "store_mesh",
    "load_entry",
    "store_entry",
    "arrays_digest",
    "drop_entry",
]

#: Bumped when an entry's layout changes (old entries are then simply not found).
LAYOUT = 3  # 2: with the part's surface (points, triangles); 3: tables and meshes verified too
#: The ceiling an entry is read under (:mod:`flexshaft.system.inputs`: a regular file, at most this big): that
#: of a flexible-body file, 512 MB unless ``FLEXSHAFT_MAX_FILE_MB`` says otherwise - a solid part's
#: reduction holds every node's motion per reduced coordinate (1 000 000 DOFs x 44 columns: 350 MB).
ENTRY = BODY
_ARRAYS = ("x", "area", "ip", "iy", "iz", "iyz", "j", "shear_area_y", "shear_area_z", "yc", "zc")


@contextmanager
def _entry_arrays(path: Path):
    """The ``.npz`` entry at ``path`` opened for reading its arrays (``numpy.load``'s NpzFile).

    Opened as any input is (a regular file under :data:`ENTRY`'s ceiling), not noted as the
    command's input (the cache is flexshaft's own), and refused unless every member is stored
    uncompressed, as ``numpy.savez`` writes them: what is read is then at most the file's size (a
    compressed member could inflate to any size before anything is checked).
    """
    with open_seekable(path, ENTRY, noted=False) as fh:
        with zipfile.ZipFile(fh) as z:
            if any(i.compress_type != zipfile.ZIP_STORED for i in z.infolist()):
                raise ValueError("a compressed member: not an entry this cache wrote")
        fh.seek(0)
        with np.load(fh, allow_pickle=False) as data:
            yield data


def cache_dir() -> Path:
    """Where section tables are cached: ``$FLEXSHAFT_CACHE_DIR`` or the user's cache folder."""
    if os.environ.get("FLEXSHAFT_CACHE_DIR"):
        return Path(os.environ["FLEXSHAFT_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "flexshaft"


def source_digest(path: Path, kind: Kind, *, field: str | None = None) -> str:
    """SHA-256 of a user's file (a part file, a part module), read a piece at a time.

    The file is opened as every input is (:func:`flexshaft.system.inputs.open_input`): a regular file
    within the ceiling of its ``kind``, else a ModelError naming it (as ``field``'s value if given).
    """
    h = hashlib.sha256()
    with open_input(path, kind, field=field) as fh:
        while piece := fh.read(1 << 20):
            h.update(piece)
    return h.hexdigest()


@lru_cache(maxsize=4)
def package_digest(name: str) -> str:
    """SHA-256 over an installed package's sources (its ``.py`` and ``.js`` files, by relative path):
    what code made a result, where the version number does not say (an editable install)."""
    import importlib.util

    spec = importlib.util.find_spec(name)
    h = hashlib.sha256()
    for folder in spec.submodule_search_locations or ():
        paths = [*Path(folder).rglob("*.py"), *Path(folder).rglob("*.js")]
        for path in sorted(paths):
            h.update(str(path.relative_to(folder)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def geometry_digest() -> str:
    """SHA-256 over the ``geometry`` package's sources: a part function builds with all of them."""
    return package_digest("geometry")


def entry_key(**what) -> str:
    """The cache key of a table: a digest of everything it depends on, flexshaft's version included."""
    doc = json.dumps({"layout": LAYOUT, "flexshaft": __version__, **what}, sort_keys=True, default=repr)
    return hashlib.sha256(doc.encode()).hexdigest()


def load_table(key: str) -> SectionTable | None:
    """The cached table, or None when there is none, or it is damaged (then it is removed).

    Its ``meta`` holds what :func:`store_table` was given as ``extra``, as plain JSON values.
    """
    entry = load_entry("sections", key)
    if entry is None:
        return None
    arrays, meta = entry
    try:
        more = {k: np.array(arrays[f"extra_{k}"]) for k in meta.get("arrays", [])}
        return SectionTable(
            method=tuple(meta["method"]),
            nu=float(meta["nu"]),
            name=str(meta["name"]),
            meta=dict(meta.get("extra", {})) | ({"arrays": more} if more else {}),
            **{k: np.array(arrays[k], dtype=float) for k in _ARRAYS},
        )
    except Exception:  # noqa: BLE001 - an entry that is no table is rebuilt, whatever is wrong with it
        drop_entry("sections", key)
        return None


def store_table(key: str, table: SectionTable, extra: dict | None = None, arrays: dict | None = None) -> None:
    """Keep a table for the next run; a cache that cannot be written is simply not used.

    ``extra`` (plain JSON values) and ``arrays`` (numeric arrays, e.g. the part's surface) come
    back in the loaded table's ``meta`` (``meta["arrays"]``).
    """
    meta = {"method": list(table.method), "nu": table.nu, "name": table.name, "extra": extra or {}}
    meta["arrays"] = sorted(arrays or {})
    more = {f"extra_{k}": np.asarray(v) for k, v in (arrays or {}).items()}
    store_entry("sections", key, {k: getattr(table, k) for k in _ARRAYS} | more, meta)


def load_mesh(key: str):
    """The cached solid mesh (:class:`~flexshaft.elements.tetmesh.TetMesh`), or None when there is
    none or it is damaged (then it is removed). The mesh's own checks (indices in range, faces) run
    on what is read: an entry is data, never trusted."""
    from ..elements.tetmesh import TetMesh

    entry = load_entry("meshes", key)
    if entry is None:
        return None
    arrays, meta = entry
    try:
        return TetMesh(
            name=str(meta["name"]),
            nodes=np.array(arrays["nodes"], dtype=float),
            tets=np.array(arrays["tets"], dtype=np.int64),
            faces={name: np.array(arrays[f"face_{name}"], dtype=np.int64) for name in meta["faces"]},
            size=float(meta["size"]),
            source=str(meta["source"]),
        )
    except Exception:  # noqa: BLE001 - an entry that is no mesh is rebuilt, whatever is wrong with it
        drop_entry("meshes", key)
        return None


def store_mesh(key: str, mesh) -> None:
    """Keep a solid mesh for the next run; a cache that cannot be written is simply not used."""
    meta = {"name": mesh.name, "size": mesh.size, "source": mesh.source, "faces": sorted(mesh.faces)}
    faces = {f"face_{k}": v for k, v in mesh.faces.items()}
    store_entry("meshes", key, {"nodes": mesh.nodes, "tets": mesh.tets, **faces}, meta)


#: The kinds of array a verified entry holds: numbers and flags (never objects, which need pickles).
_NUMERIC = "biuf"


def arrays_digest(arrays: dict) -> str:
    """SHA-256 over named arrays: each one's name, dtype, shape and bytes, in the order of the names."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(json.dumps([name, a.dtype.str, list(a.shape)]).encode())
        h.update(a.data if a.size else b"")
    return h.hexdigest()


def _entry_path(folder: str, key: str) -> Path:
    return cache_dir() / folder / f"{key}.npz"


def store_entry(folder: str, key: str, arrays: dict, meta: dict) -> None:
    """Keep numeric ``arrays`` and ``meta`` (plain JSON values) under ``key`` in the cache's ``folder``.

    The entry holds, beside the arrays, one JSON string: the key, the meta, each array's dtype and
    shape, and the SHA-256 of them all (:func:`arrays_digest`), which :func:`load_entry` checks.
    Written atomically; a cache that cannot be written (read-only, full) is simply not used.
    """
    from ..system.atomic import atomic_write_bytes

    arrays = {name: np.ascontiguousarray(a) for name, a in arrays.items()}
    for name, a in arrays.items():
        if a.dtype.kind not in _NUMERIC:
            raise TypeError(f"cache entry array {name!r} is not numeric ({a.dtype})")
    doc = {
        "key": key,
        "meta": meta,
        "arrays": {name: [a.dtype.str, list(a.shape)] for name, a in arrays.items()},
        "sha256": arrays_digest(arrays),
    }
    buf = io.BytesIO()
    np.savez(buf, meta=np.array(json.dumps(doc)), **{f"a_{name}": a for name, a in arrays.items()})
    try:
        if buf.tell() > ceiling_bytes(ENTRY):
            return  # it would not be read back (above the ceiling): not written either
        path = _entry_path(folder, key)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, buf.getvalue(), overwrite=True)
    except Exception:  # noqa: BLE001 - read-only or full disk: run without the cache
        pass


def load_entry(folder: str, key: str) -> tuple[dict, dict] | None:
    """The arrays and meta :func:`store_entry` kept under ``key``, or None when there are none or
    the entry is not whole and valid (then it is removed, to be rebuilt).

    Valid: a regular file under the entries' ceiling (:data:`ENTRY`), its members stored
    uncompressed, written for this key, holding exactly the arrays it lists, each of the dtype
    (numeric) and shape listed, whose SHA-256 is the one stored. What the arrays mean (their shapes
    against the mesh, their values) is the caller's to check before use.
    """
    path = _entry_path(folder, key)
    if not path.is_file():
        return None
    try:
        with _entry_arrays(path) as data:
            doc = json.loads(str(data["meta"]))
            if not isinstance(doc, dict) or doc.get("key") != key:
                raise ValueError("entry written for another key")
            listed = doc["arrays"]
            if sorted(data.files) != sorted(["meta", *(f"a_{name}" for name in listed)]):
                raise ValueError("the entry's arrays are not the ones it lists")
            arrays = {}
            for name, (dtype, shape) in listed.items():
                a = data[f"a_{name}"]
                if a.dtype.str != dtype or list(a.shape) != list(shape) or a.dtype.kind not in _NUMERIC:
                    raise ValueError(f"array {name!r} is not as listed")
                arrays[name] = a
        if arrays_digest(arrays) != doc["sha256"]:
            raise ValueError("the arrays are not the ones stored")
        meta = doc["meta"]
        if not isinstance(meta, dict):
            raise ValueError("no meta")
        return arrays, meta
    except Exception:  # noqa: BLE001 - a damaged entry is rebuilt, whatever is wrong with it
        drop_entry(folder, key)
        return None


def drop_entry(folder: str, key: str) -> None:
    """Remove an entry whose content its reader found invalid (it is then rebuilt)."""
    _entry_path(folder, key).unlink(missing_ok=True)
