"""Reading and writing CAD parts: STEP and BREP through build123d, STL/OBJ/PLY through trimesh.

STEP carries its own length unit (OCCT converts it to millimetres on import).
BREP files are millimetres by build123d's convention. Mesh formats carry no
unit: the caller names it, and the STL files flexshaft writes record theirs
in the 80-byte header (``flexshaft STL unit=mm``), which the reader checks.
Every writer refuses to replace an existing file unless ``overwrite=True``
and never leaves half a file.
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

from flexshaft.atomic import atomic_write_bytes
from flexshaft.errors import ModelError
from flexshaft.inputs import CAD, MESH, Kind, check_path, read_bytes

from .units import LENGTH_UNITS, metres_per

__all__ = [
    "CAD_SUFFIXES",
    "MESH_SUFFIXES",
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


def _existing(path, kind: Kind = CAD) -> Path:
    """``path`` when it is a regular file within the ceiling of its ``kind`` (:mod:`flexshaft.inputs`):
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


def _load(reader, p: Path, what: str, valid: str, said: list):
    """``reader(str(p))``, or a ModelError saying the file cannot be read as ``what``."""
    try:
        with _captured_stdout(said):
            return reader(str(p))
    except Exception as err:  # OCCT and trimesh report a broken file through assorted exception types
        raise ModelError(
            f"cannot be read as {what} ({type(err).__name__}: {err}{_noise(said)})",
            field="geometry",
            value=str(p),
            valid=valid,
        ) from None


def read_step(path):
    """A STEP file as a build123d shape (millimetres; OCCT converts the file's own unit).

    Raises
    ------
    ModelError
        The file is missing, unreadable, or holds no shape.
    """
    import build123d as bd

    p = _existing(path)
    said: list[str] = []
    shape = _load(bd.import_step, p, "STEP", "a readable STEP (AP203/AP214/AP242) file", said)
    if shape is None or not list(shape.faces()):
        raise ModelError(
            f"holds no shape{_noise(said)}", field="geometry", value=str(p), valid="a STEP file with a solid"
        )
    return shape


def read_brep(path):
    """An OCCT BREP file (millimetres) as a build123d shape."""
    import build123d as bd

    return _load(bd.import_brep, _existing(path), "BREP", "a readable OCCT BREP file", [])


def _stl_header_unit(data: bytes) -> str | None:
    head = data[:80]
    if head.startswith(_STL_TAG):
        return head[len(_STL_TAG) :].split(b" ")[0].strip(b"\0 ").decode("ascii", "replace")
    return None


def read_mesh(path, *, unit: str | None = None):
    """An STL, OBJ or PLY file as a watertight :class:`trimesh.Trimesh` in metres.

    Parameters
    ----------
    path : str or Path
        The mesh file.
    unit : str, optional
        The file's length unit, one of ``m, mm, cm, in``. Required unless
        the file is an STL written by flexshaft, whose header records it; if
        both are given they must agree.

    Raises
    ------
    ModelError
        Missing or unreadable file, no or conflicting unit, a mesh that is not
        a closed volume (open edges, inconsistent normals).
    """
    import trimesh

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
    mesh = _load(
        lambda _: trimesh.load(io.BytesIO(data), file_type=p.suffix.lower()[1:], force="mesh", process=True),
        p,
        "a mesh",
        "a readable STL/OBJ/PLY file",
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
    return mesh


def read_cad(path, *, unit: str | None = None):
    """Read any supported part file: a build123d shape (STEP/BREP) or a trimesh (STL/OBJ/PLY, in m)."""
    suffix = Path(path).suffix.lower()
    if suffix in (".step", ".stp"):
        return read_step(path)
    if suffix in (".brep", ".brp"):
        return read_brep(path)
    if suffix in MESH_SUFFIXES:
        return read_mesh(path, unit=unit)
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
