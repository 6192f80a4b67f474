"""Reading and writing CAD parts: STEP and BREP through build123d, STL/OBJ/PLY through trimesh.

STEP carries its own length unit (OCCT converts it to millimetres on import).
BREP files are millimetres by build123d's convention. Mesh formats carry no
unit: the caller names it, and the STL files flexshaft writes record theirs
in the 80-byte header (``flexshaft STL unit=mm``), which the reader checks.
Every writer refuses to replace an existing file unless ``overwrite=True``
and never leaves half a file.

Every file is parsed in a forked child (:func:`flexshaft.system.isolate.run_isolated`): OCCT's STEP and
BREP parsers are C++ and a crafted file can crash them (200 000 nested parentheses in a 400 kB STEP
overflow the parser's stack: SIGSEGV) or keep them busy; trimesh's loaders are numpy, but their
time can grow faster than the file (an ASCII STL of 8 000 one-triangle solids, 0.84 MB, takes 7.6 s:
each solid's name is made unique against all before it). A crash, a run beyond :func:`timeout_s` or
an allocation beyond :func:`memory_bytes` is then one ModelError naming the file. What comes back:

- a STEP or BREP shape as OCCT's own binary BREP (``BinTools``), written by OCCT in the child from
  the shape it translated and read back by OCCT in the caller: the same topology and the same
  doubles (millimetres, as OCCT's STEP translation made them), without the STEP's names and
  colours, which nothing here uses. A part of a few hundred faces is ~70 kB and ~1 ms each way;
  the fork and the child's exit ~22 ms, 30-50 ms a file in all (``benchmarks/bench_cadread.py``);
- a mesh as its vertices (m) and triangles, checked closed and consistently oriented in the child;
  the caller makes a :class:`trimesh.Trimesh` of them without processing them again.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import struct
import sys
import tempfile
from pathlib import Path

import numpy as np

from flexshaft.errors import ModelError
from flexshaft.system.atomic import atomic_write_bytes
from flexshaft.system.inputs import CAD, MB, MESH, Kind, check_path, read_bytes
from flexshaft.validation import check_real

from .units import LENGTH_UNITS, metres_per

__all__ = [
    "CAD_SUFFIXES",
    "MESH_SUFFIXES",
    "TIMEOUT_S",
    "SECONDS_PER_MB",
    "EXTRA_MEMORY",
    "MEMORY_PER_BYTE",
    "timeout_s",
    "memory_bytes",
    "read_step",
    "read_brep",
    "read_mesh",
    "read_cad",
    "write_step",
    "write_brep",
    "write_stl",
]

CAD_SUFFIXES = (".step", ".stp", ".brep", ".brp")
MESH_SUFFIXES = (".stl", ".obj", ".ply")
_STL_TAG = b"flexshaft STL unit="
#: Seconds the reading of a part file may take at least before it counts as hung: the bench's parts
#: (0.1-0.3 MB of STEP) translate in ~0.05 s, and a hung parser never ends.
TIMEOUT_S = 60.0
#: And per MB of the file: OCCT translates the bench's STEP files at ~5 MB/s and trimesh reads an
#: ASCII STL of one solid at ~60 MB/s; 0.2 MB/s allows a B-spline-heavy file 25 times slower.
SECONDS_PER_MB = 5.0
#: Bytes of address space the reading's child may add to what it inherits, beyond
#: :data:`MEMORY_PER_BYTE` per byte of the file (the libraries' own tables and buffers).
EXTRA_MEMORY = 1 << 30
#: And per byte of the file: OCCT holds ~6 times a STEP file while it translates it
#: (:mod:`flexshaft.system.inputs`), trimesh ~12 times a binary STL while it merges vertices.
MEMORY_PER_BYTE = 16


def timeout_s(size: int) -> float:
    """Seconds the reading of a part file of ``size`` bytes may take, s."""
    return TIMEOUT_S + SECONDS_PER_MB * size / MB


def memory_bytes(size: int) -> int:
    """Bytes of address space the reading of a part file of ``size`` bytes may add, bytes."""
    return EXTRA_MEMORY + MEMORY_PER_BYTE * int(size)


def _existing(path, kind: Kind = CAD) -> Path:
    """``path`` when it is a regular file within the ceiling of its ``kind`` (:mod:`flexshaft.system.inputs`):
    OCCT's readers open the path themselves, and a FIFO or a device would block or never end."""
    return check_path(path, kind, field="geometry")


_ANSI = re.compile(r"\x1b\[[0-9;]*m")


@contextlib.contextmanager
def _captured_stdout(said: list):
    """Catch what C++ code (OCCT's STEP parser) prints on file descriptor 1 meanwhile.

    stdout is the program's result (a table, a JSON document) and stderr carries one error line:
    the parser's messages go into ``said`` (one line each, colour codes removed) for the error
    that names the file.
    """
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no file descriptor 1 (embedded interpreters): nothing to catch
        yield
        return
    with tempfile.TemporaryFile() as sink:
        try:
            os.dup2(sink.fileno(), 1)
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
            sink.seek(0)
            text = _ANSI.sub("", sink.read(65536).decode("utf-8", "replace"))
            said.extend(ln.strip(" *") for ln in text.splitlines() if ln.strip(" *"))


def _noise(said: list) -> str:
    return f"; the reader said: {said[0]}" if said else ""


def _too_big(p: Path, what: str, valid: str, size: int) -> ModelError:
    """The reading needed more memory than its child may take (:func:`memory_bytes`)."""
    return ModelError(
        f"cannot be read as {what}: its reader needed more than the {memory_bytes(size) / 2**30:.3g} GiB "
        "of memory allowed for a file of its size (a damaged or hostile file)",
        field="geometry",
        value=str(p),
        valid=valid,
    )


def _load(reader, p: Path, what: str, valid: str, said: list):
    """``reader(str(p))``, or a ModelError saying the file cannot be read as ``what``."""
    try:
        with _captured_stdout(said):
            return reader(str(p))
    except MemoryError:  # the child's cap: a file that makes its reader allocate without end
        raise _too_big(p, what, valid, p.stat().st_size) from None
    except Exception as err:  # OCCT and trimesh report a broken file through assorted exception types
        raise ModelError(
            f"cannot be read as {what} ({type(err).__name__}: {err}{_noise(said)})",
            field="geometry",
            value=str(p),
            valid=valid,
        ) from None


def _isolated(work, p: Path, what: str, valid: str, *, size: int, timeout: float | None):
    """``work()`` run in a forked child (:func:`flexshaft.system.isolate.run_isolated`): its result, its
    ModelError, or one ModelError naming the file for a crash, a run beyond ``timeout`` (default
    :func:`timeout_s` of the file's ``size`` in bytes) or an allocation beyond :func:`memory_bytes`."""
    from flexshaft.system.isolate import run_isolated

    limit = timeout_s(size) if timeout is None else check_real(timeout, "timeout", "s", lo=0.0, lo_open=True)

    def refused(failure) -> ModelError:
        if failure.kind == "timeout":
            how = f"reading it took more than {failure.limit:.3g} s, as on a damaged file that loops a reader"
        elif failure.detail.startswith("MemoryError"):  # outside the reader proper (trimesh's checks)
            return _too_big(p, what, valid, size)
        else:  # a crash, or a failure outside _load (which makes every Exception a ModelError)
            how = f"its reader {failure.reason}, as on a damaged or hostile file"
        return ModelError(f"cannot be read as {what}: {how}", field="geometry", value=str(p), valid=valid)

    return run_isolated(lambda send: work(), timeout=limit, error=refused, memory=memory_bytes(size))


def _to_bytes(shape) -> bytes:
    """A build123d shape as OCCT's binary BREP (topology, geometry and locations; no names, colours)."""
    from OCP.BinTools import BinTools

    buf = io.BytesIO()
    BinTools.Write_s(shape.wrapped, buf)
    return buf.getvalue()


def _from_bytes(data: bytes):
    """The build123d shape of :func:`_to_bytes`' bytes (a Solid for one solid, as build123d's import)."""
    import build123d as bd
    from OCP.BinTools import BinTools
    from OCP.TopoDS import TopoDS_Shape

    shape = TopoDS_Shape()
    BinTools.Read_s(shape, io.BytesIO(data))
    return bd.Compound.cast(shape)


_STEP_VALID = "a readable STEP (AP203/AP214/AP242) file"
_BREP_VALID = "a readable OCCT BREP file"
_MESH_VALID = "a readable STL/OBJ/PLY file"


def _step_work(p: Path) -> bytes:
    """In the child: the STEP file translated by OCCT, as BREP bytes."""
    import build123d as bd

    said: list[str] = []
    shape = _load(bd.import_step, p, "STEP", _STEP_VALID, said)
    if shape is None or not list(shape.faces()):
        raise ModelError(
            f"holds no shape{_noise(said)}", field="geometry", value=str(p), valid="a STEP file with a solid"
        )
    return _to_bytes(shape)


def _brep_work(p: Path) -> bytes:
    """In the child: the (text) BREP file read by OCCT, as binary BREP bytes."""
    import build123d as bd

    return _to_bytes(_load(bd.import_brep, p, "BREP", _BREP_VALID, []))


def read_step(path, *, timeout: float | None = None):
    """A STEP file as a build123d shape (millimetres; OCCT converts the file's own unit).

    OCCT parses it in a forked child (module docstring).

    Parameters
    ----------
    path : str or Path
        The STEP file (``.step``, ``.stp``).
    timeout : float, optional
        Seconds the reading may take, s; default :func:`timeout_s` of the file's size.

    Raises
    ------
    ModelError
        The file is missing, unreadable, or holds no shape; its reader crashed on it, ran out of
        time or needed more memory than :func:`memory_bytes` allows.
    """
    import build123d  # noqa: F401 - the caller needs it for the shape: imported once, before the fork

    p = _existing(path)
    size = p.stat().st_size
    return _from_bytes(_isolated(lambda: _step_work(p), p, "STEP", _STEP_VALID, size=size, timeout=timeout))


def read_brep(path, *, timeout: float | None = None):
    """An OCCT BREP file (millimetres) as a build123d shape, parsed in a forked child as
    :func:`read_step` is (its parameters and errors)."""
    import build123d  # noqa: F401 - as in read_step

    p = _existing(path)
    size = p.stat().st_size
    return _from_bytes(_isolated(lambda: _brep_work(p), p, "BREP", _BREP_VALID, size=size, timeout=timeout))


def _stl_header_unit(data: bytes) -> str | None:
    head = data[:80]
    if head.startswith(_STL_TAG):
        return head[len(_STL_TAG) :].split(b" ")[0].strip(b"\0 ").decode("ascii", "replace")
    return None


def _mesh_work(data: bytes, p: Path, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """In the child: the mesh file's bytes read by trimesh and checked closed; (vertices in m,
    triangles) as plain arrays."""
    import trimesh

    mesh = _load(
        lambda _: trimesh.load(io.BytesIO(data), file_type=p.suffix.lower()[1:], force="mesh", process=True),
        p,
        "a mesh",
        _MESH_VALID,
        [],
    )
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ModelError("holds no triangles", field="geometry", value=str(p), valid="a triangle mesh")
    mesh.merge_vertices()
    if not mesh.is_watertight:
        edges = trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)
        raise ModelError(
            f"is not watertight ({len(edges)} open edges): not the surface of a solid",
            field="geometry",
            value=str(p),
            valid="a closed, watertight triangle mesh",
        )
    if not mesh.is_winding_consistent:
        raise ModelError(
            "has inconsistently oriented triangles",
            field="geometry",
            value=str(p),
            valid="a closed mesh with consistent normals",
        )
    if mesh.volume < 0:
        mesh.invert()
    mesh.apply_scale(scale)
    # plain ndarrays (not trimesh's TrackedArray): their bytes travel apart from the pickle
    return np.array(mesh.vertices, dtype=np.float64), np.array(mesh.faces, dtype=np.int64)


def read_mesh(path, *, unit: str | None = None, timeout: float | None = None):
    """An STL, OBJ or PLY file as a watertight :class:`trimesh.Trimesh` in metres.

    trimesh reads and checks it in a forked child (module docstring).

    Parameters
    ----------
    path : str or Path
        The mesh file.
    unit : str, optional
        The file's length unit, one of ``m, mm, cm, in``. Required unless
        the file is an STL written by flexshaft, whose header records it; if
        both are given they must agree.
    timeout : float, optional
        Seconds the reading may take, s; default :func:`timeout_s` of the file's size.

    Raises
    ------
    ModelError
        Missing or unreadable file, no or conflicting unit, a mesh that is not
        a closed volume (open edges, inconsistent normals); trimesh failed on
        it, ran out of time or needed more memory than :func:`memory_bytes` allows.
    """
    import trimesh  # the caller's mesh is one: imported once, before the fork

    p = Path(path)
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise ModelError("is not a mesh file", field="geometry", value=str(p), valid=", ".join(MESH_SUFFIXES))
    data = read_bytes(p, MESH, field="geometry")  # trimesh reads these bytes, never the path
    recorded = _stl_header_unit(data) if p.suffix.lower() == ".stl" else None
    if unit is None and recorded is None:
        raise ModelError(
            "a mesh file carries no length unit",
            field="unit",
            value=str(p),
            valid=f"give unit = one of {', '.join(LENGTH_UNITS)}",
        )
    if unit is not None and recorded is not None and unit != recorded:
        raise ModelError(
            f"the file records unit {recorded!r}",
            field="unit",
            value=unit,
            valid=f"{recorded!r} (or leave it out)",
        )
    scale = metres_per(unit or recorded)
    vertices, faces = _isolated(
        lambda: _mesh_work(data, p, scale), p, "a mesh", _MESH_VALID, size=len(data), timeout=timeout
    )
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def read_cad(path, *, unit: str | None = None, timeout: float | None = None):
    """Read any supported part file: a build123d shape (STEP/BREP) or a trimesh (STL/OBJ/PLY, in m),
    parsed in a forked child (module docstring); ``timeout`` as for :func:`read_step`."""
    suffix = Path(path).suffix.lower()
    if suffix in (".step", ".stp"):
        return read_step(path, timeout=timeout)
    if suffix in (".brep", ".brp"):
        return read_brep(path, timeout=timeout)
    if suffix in MESH_SUFFIXES:
        return read_mesh(path, unit=unit, timeout=timeout)
    raise ModelError(
        "unknown file type", field="geometry", value=str(path), valid=", ".join(CAD_SUFFIXES + MESH_SUFFIXES)
    )


def write_step(shape, path, *, overwrite: bool = False) -> Path:
    """Write a build123d shape as STEP (AP214, unit recorded as millimetre in the file)."""
    import build123d as bd

    buf = io.BytesIO()
    bd.export_step(shape, buf, unit=bd.Unit.MM)
    return atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)


def write_brep(shape, path, *, overwrite: bool = False) -> Path:
    """Write a build123d shape as an OCCT BREP file (millimetres)."""
    import build123d as bd

    buf = io.BytesIO()
    bd.export_brep(shape, buf)
    return atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)


def write_stl(
    shape,
    path,
    *,
    tolerance: float = 1e-5,
    angular_tolerance: float = 0.05,
    unit: str = "mm",
    overwrite: bool = False,
) -> Path:
    """Triangulate a build123d shape and write a binary STL that records its unit.

    Parameters
    ----------
    shape : build123d Shape
        The part (millimetres).
    path : str or Path
        Target file.
    tolerance : float
        Largest chord deviation of the triangulation from the surface, m.
    angular_tolerance : float
        Largest angle between neighbouring facets of a curved face, rad.
    unit : str
        Length unit of the coordinates written (``m, mm, cm, in``); stored in
        the header as ``flexshaft STL unit=<unit>``.
    overwrite : bool
        Replace an existing file.
    """
    from OCP.BRepTools import BRepTools

    from .units import to_cad

    factor = 1e-3 / metres_per(unit)  # build123d mm → file unit
    # A shape triangulated once keeps that mesh; clean it so this tolerance is the one used.
    BRepTools.Clean_s(shape.wrapped)
    vertices, triangles = shape.tessellate(to_cad(tolerance), angular_tolerance)
    v = np.array([(p.X, p.Y, p.Z) for p in vertices]) * factor
    t = np.asarray(triangles, dtype=np.int64)
    tri = v[t]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, norm, out=np.zeros_like(normals), where=norm > 0)
    record = np.zeros(len(t), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    record["n"] = normals
    record["v"] = tri
    header = (_STL_TAG + unit.encode("ascii")).ljust(80, b" ")
    data = header + struct.pack("<I", len(t)) + record.tobytes()
    return atomic_write_bytes(path, data, overwrite=overwrite)
