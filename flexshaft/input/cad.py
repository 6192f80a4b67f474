"""Section tables for ``type = "cad"`` parts: the one place flexshaft reaches into :mod:`geometry`.

The geometry package (and build123d behind it) is imported only here and only
when a model has a CAD part, so models without one load fast.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import re
import sys
import types
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..sections.table import SectionTable
from ..system.inputs import CAD, CODE, MESH, check_path, note_input
from .cache import load_table, store_table

__all__ = [
    "cad_sections",
    "solid_mesh",
    "resolve_function",
    "clear_cache",
    "FILE_SUFFIXES",
    "TRUSTED_MODULES",
]

FILE_SUFFIXES = (".step", ".stp", ".brep", ".brp", ".stl", ".obj", ".ply")

# Slicing the same part twice (two set-ups, or a CLI run per set-up) is the
# slow part of loading: keep each distinct (source, parameters, axis, nu) once.
_CACHE: dict[tuple, SectionTable] = {}


def clear_cache() -> None:
    """Forget every section table sliced so far in this process."""
    _CACHE.clear()


def _freeze(value):
    if isinstance(value, Mapping):
        return tuple(sorted((k, _freeze(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return tuple(_freeze(v) for v in value)
    return value


#: The project's own part libraries: a model file may always name their public functions.
TRUSTED_MODULES = (
    "geometry.parts",
    "geometry.parts.testbench",
    "geometry.parts.primitives",
    "geometry.parts.prismatic",
    "geometry.parts.features",
)
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_DOTTED = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*")
_TRUST_HINT = (
    "a function of geometry.parts or geometry.parts.testbench, a STEP/STL file, or - only for code you "
    "trust - flexshaft --allow-code (load_model(..., allow_code=True))"
)


def _installed_top_levels() -> set[str]:
    """Top-level import names of the installed distributions (not the standard library)."""
    from importlib.metadata import packages_distributions

    try:
        return set(packages_distributions())
    except Exception:  # a broken distribution's metadata must not break loading  # noqa: BLE001
        return set()


def _user_code_failed(spec: str, what: str, err: BaseException) -> ModelError:
    """A ModelError for an error, exit or interrupt inside a user's part module.

    A SIGINT or SIGTERM that reached the command meanwhile is not the code's doing: it is raised
    again, and stops the command as anywhere else (exit 130 or 143).
    """
    from ..system.watchdog import is_stop

    if is_stop(err):
        raise err
    detail = str(err).splitlines()[0] if str(err) else ""
    kind = type(err).__name__
    return ModelError(
        f"the part code {what} ({kind}{': ' + detail if detail else ''})",
        field="geometry",
        value=spec,
        valid="part code that returns a build123d solid",
    )


def _import_user_module(module_name: str, spec: str, base_dir: Path | None):
    """The module of a trusted ``module:function``: a ``.py`` beside the model, or an installed package."""
    if base_dir is not None and _IDENTIFIER.fullmatch(module_name):
        folder = Path(base_dir).resolve()
        local = (folder / f"{module_name}.py").resolve()
        if local.parent == folder and local.is_file():
            check_path(local, CODE, field="geometry")  # a regular file within the part module's ceiling
            # compiled from the source read now, never from a cached .pyc: what runs is the file as it
            # is (a .pyc is trusted by the source's mtime and size, and an edit within the same second
            # that keeps the size ran the old code), and nothing is written beside the user's model
            source = local.read_bytes()
            module = types.ModuleType(f"flexshaft_user_parts.{module_name}")
            module.__file__ = str(local)
            try:
                exec(compile(source, str(local), "exec", dont_inherit=True), module.__dict__)  # noqa: S102 - trusted
            except BaseException as err:  # user code: errors, exits and interrupts alike  # noqa: BLE001
                raise _user_code_failed(spec, f"in {local.name} failed while loading", err) from None
            return module
    top = module_name.split(".")[0]
    if top in sys.stdlib_module_names or top in sys.builtin_module_names:
        raise ModelError(
            "names a standard-library module, which is never run from a model file",
            field="geometry",
            value=spec,
            valid="a .py file beside the model file or an installed package's part function",
        )
    if top not in _installed_top_levels():
        raise ModelError(
            f"cannot import module {module_name!r} (neither a .py file beside the model file nor an "
            "installed package)",
            field="geometry",
            value=spec,
            valid="a .py file beside the model file or an installed package",
        )
    try:
        return importlib.import_module(module_name)
    except BaseException as err:  # noqa: BLE001 - an installed package's import may fail any way
        raise _user_code_failed(spec, f"module {module_name!r} failed to import", err) from None


def resolve_function(spec: str, base_dir: Path | None = None, *, allow_code: bool = False) -> Callable:
    """The part function named by ``"module:function"``, if the model may run it.

    A function of the project's own part libraries (:data:`TRUSTED_MODULES`,
    e.g. ``geometry.parts.testbench:ptss_part2``) is always allowed. Any other
    code runs only with ``allow_code``: a model file from someone else is code
    when it names code. It is then a ``.py`` file beside the model file
    (``my_parts:flange`` for ``my_parts.py``, never a path) or a module of an
    installed package - never a standard-library module.
    """
    module_name, _, func_name = spec.partition(":")
    if not _DOTTED.fullmatch(module_name) or not _IDENTIFIER.fullmatch(func_name):
        raise ModelError(
            "is not 'module:function' or a file",
            field="geometry",
            value=spec,
            valid="'module:function' (e.g. 'geometry.parts.testbench:ptss_part2') or a path to a "
            + "/".join(FILE_SUFFIXES)
            + " file",
        )
    if module_name in TRUSTED_MODULES:
        module = importlib.import_module(module_name)
        if func_name not in getattr(module, "__all__", ()):
            raise ModelError(
                f"module {module_name!r} has no part function {func_name!r}",
                field="geometry",
                value=spec,
                valid=", ".join(sorted(getattr(module, "__all__", ()))),
            )
    elif not allow_code:
        raise ModelError(
            "runs code that is not flexshaft's own part library, and code from a model file runs only "
            "when you trust it",
            field="geometry",
            value=spec,
            valid=_TRUST_HINT,
        )
    else:
        module = _import_user_module(module_name, spec, base_dir)
    func = getattr(module, func_name, None)
    if func_name.startswith("_") or not callable(func):
        raise ModelError(
            f"module {module_name!r} has no function {func_name!r}",
            field="geometry",
            value=spec,
            valid="a part function of that module",
        )
    return func


def _is_geometry_file(geometry: str, params: dict) -> bool:
    """Whether ``geometry`` names a file (by its suffix) rather than a part function; a file takes no
    ``params``."""
    is_file = Path(geometry).suffix.lower() in FILE_SUFFIXES
    if is_file and params:
        raise ModelError(
            "a geometry file takes no parameters",
            field="params",
            value=params,
            valid="leave params out (it is for part functions)",
        )
    return is_file


def cad_sections(
    geometry: str,
    *,
    name: str,
    nu: float,
    params: Mapping | None = None,
    unit: str | None = None,
    axis=None,
    base_dir: Path | None = None,
    progress=None,
    allow_code: bool = False,
    use_cache: bool = True,
) -> SectionTable:
    """The section table of a CAD part given as a part function or a file.

    Parameters
    ----------
    geometry : str
        ``"module:function"`` (a build123d part function taking SI keyword
        parameters) or a path to a STEP/BREP/STL/OBJ/PLY file, relative to
        ``base_dir``.
    name : str
        The component's name, for the table and messages.
    nu : float
        Poisson's ratio of the material (shear areas).
    params : mapping, optional
        Keyword parameters of the part function, SI units.
    unit : str, optional
        Length unit of a mesh file (``m, mm, cm, in``).
    axis : optional
        The shaft axis, see :func:`geometry.slicing.sections`.
    base_dir : Path, optional
        Directory relative paths are read from (the model file's).
    progress : callable, optional
        ``progress(done, total)`` per slice.
    allow_code : bool
        Run a part function that is not flexshaft's own part library (see
        :func:`resolve_function`); off by default.
    use_cache : bool
        Read and keep the table in the disk cache (:mod:`flexshaft.input.cache`):
        a part costs its slicing once, not on every run.
    """
    params = dict(params or {})
    is_file = _is_geometry_file(geometry, params)
    is_mesh = Path(geometry).suffix.lower() in (".stl", ".obj", ".ply")
    if not is_mesh and unit is not None:
        # A STEP file records its unit and OCCT converts it; BREP and part functions are millimetres
        # and metres by definition: a unit here would silently disagree with them.
        raise ModelError(
            "only a mesh file (STL/OBJ/PLY) takes a length unit",
            field="unit",
            value=unit,
            valid="leave unit out for a part function or STEP/BREP file (they carry their unit)",
        )
    path = (base_dir / geometry if base_dir is not None else Path(geometry)) if is_file else None
    key = (str(path.resolve()) if path else geometry, _freeze(params), unit, _freeze(axis), nu, allow_code)
    if path is not None and path.is_file():
        key += (path.stat().st_mtime_ns,)
    if key in _CACHE:
        if path is not None:
            note_input(path)  # read by an earlier call: still this command's input, never its output
        return _CACHE[key]
    disk_key = None
    if use_cache:
        disk_key = _disk_key(geometry, path, base_dir, params, unit, axis, nu, allow_code, name)
    if disk_key is not None:
        table = load_table(disk_key)
        if table is not None:
            table = _with_checks(table)
            _CACHE[key] = table
            return table
    shape = _shape(geometry, path, params, unit, base_dir, allow_code)
    from geometry.slicing import sections  # build123d: only now

    table = sections(shape, axis=axis, nu=nu, name=name, progress=progress)
    table = _with_surface(table, shape)
    _CACHE[key] = table
    if disk_key is not None:
        points, triangles = table.meta["surface"]
        store_table(disk_key, table, _checks_as_json(table), {"points": points, "triangles": triangles})
    return table


def solid_mesh(
    *,
    name: str,
    geometry: str | None = None,
    segments=None,
    params: Mapping | None = None,
    axis=None,
    base_dir: Path | None = None,
    size: float | None = None,
    progress=None,
    allow_code: bool = False,
    use_cache: bool = True,
):
    """A part's solid mesh (curved 10-node tetrahedra, :func:`geometry.meshing.mesh_solid`).

    The part is a CAD ``geometry`` (as for :func:`cad_sections`: a part function with ``params`` or
    a STEP/BREP file) or a turned shaft of ``segments`` (``{length, od, id}`` in m, from its driving
    end). ``size`` is the global element size, m (default: the mesher's V/S). The mesh is kept in the
    disk cache (:mod:`flexshaft.input.cache`) keyed by the geometry's content and the size: a part is
    meshed once. ``progress(stage, fraction)`` reports the meshing.
    """
    from .cache import entry_key, geometry_digest, load_mesh, store_mesh

    params = dict(params or {})
    path = None
    if geometry is not None:
        is_file = _is_geometry_file(geometry, params)
        path = (base_dir / geometry if base_dir is not None else Path(geometry)) if is_file else None
    key = None
    if use_cache:
        if geometry is None:
            what = {"segments": segments}
            key = entry_key(solid=what, geometry=geometry_digest(), size=size, name=name)
        else:
            part_key = _disk_key(geometry, path, base_dir, params, None, axis, 0.0, allow_code, name)
            key = None if part_key is None else entry_key(solid=part_key, size=size)
    if key is not None:
        mesh = load_mesh(key)
        if mesh is not None:
            return mesh
    if geometry is None:
        from geometry.parts.primitives import stepped_shaft

        shape = stepped_shaft(segments)
    elif path is not None:
        check_path(path, _kind(path), field="geometry")
        shape = path  # read by the mesher, which refuses a triangulated (STL) surface with the reason
    else:
        shape = _shape(geometry, path, params, None, base_dir, allow_code)
    from geometry.meshing import mesh_solid

    mesh = mesh_solid(shape, name=name, axis=axis, size=size, progress=progress, field="mesh_size")
    if key is not None:
        store_mesh(key, mesh)
    return mesh


def _shape(geometry: str, path: Path | None, params: dict, unit, base_dir, allow_code: bool):
    """The part's build123d shape: read from its file, or built by its part function."""
    if path is not None:
        check_path(path, _kind(path), field="geometry")  # a FIFO, a 2 GB file: refused before build123d loads
        from geometry.cadio import read_cad

        return read_cad(path, unit=unit)
    func = resolve_function(geometry, base_dir, allow_code=allow_code)
    try:
        inspect.signature(func).bind(**params)
    except TypeError as err:
        raise ModelError(
            f"parameters do not fit {geometry} ({err})",
            field="params",
            value=params,
            valid=f"keyword parameters of {func.__name__}{inspect.signature(func)}",
        ) from None
    try:
        return func(**params)
    except ModelError:
        raise
    except BaseException as err:  # the part code's own errors, exits and interrupts  # noqa: BLE001
        raise _user_code_failed(geometry, f"{func.__name__}(...) failed", err) from None


def _kind(path: Path):
    """The kind of input a part file is (:mod:`flexshaft.system.inputs`): its size ceiling and name."""
    return MESH if path.suffix.lower() in (".stl", ".obj", ".ply") else CAD


def _with_surface(table: SectionTable, shape) -> SectionTable:
    """The table with its part's own surface (triangles in the shaft frame, m) for pictures."""
    from dataclasses import replace

    from geometry.slicing.surface import surface_in_frame

    points, triangles = surface_in_frame(shape, table.meta["axis"], float(table.x[0]))
    return replace(table, meta=dict(table.meta) | {"surface": (points, triangles)})


def _disk_key(geometry, path, base_dir, params, unit, axis, nu, allow_code, name) -> str | None:
    """The disk-cache key of a part, from its content - or None where the content cannot be read.

    Nothing is imported or run: a part function is named by its module's source (a trusted
    library's is the geometry package's own; a user's .py is read as bytes, and only when
    ``allow_code`` trusts it, which the run checks again before any code runs).
    """
    from .cache import entry_key, geometry_digest, source_digest

    try:
        if path is not None:
            what = {"file": source_digest(path, _kind(path), field="geometry")}
        else:
            module_name, _, func_name = geometry.partition(":")
            what = {"function": geometry}
            if module_name not in TRUSTED_MODULES:
                if not allow_code or base_dir is None or not _IDENTIFIER.fullmatch(module_name):
                    return None  # refused (or an installed package's): resolve_function says why
                local = (Path(base_dir) / f"{module_name}.py").resolve()
                if local.parent != Path(base_dir).resolve() or not local.is_file():
                    return None
                what["module_source"] = source_digest(local, CODE, field="geometry")
        what |= {"geometry": geometry_digest(), "params": params, "unit": unit, "axis": axis, "nu": nu}
        what["name"] = name
        return entry_key(**what)
    except OSError:
        return None


def _checks_as_json(table: SectionTable) -> dict:
    """The table's mass check and axis as plain values, to keep with it in the cache."""
    out = {}
    check, axis = table.meta.get("mass_check"), table.meta.get("axis")
    if check is not None:
        out["mass_check"] = {
            k: float(getattr(check, k))
            for k in ("volume_table", "volume_solid", "axial_moment_table", "axial_moment_solid")
        }
    if axis is not None:
        out["axis"] = {"origin": list(axis.origin), "direction": list(axis.direction), "found": axis.found}
    if "source" in table.meta:
        out["source"] = str(table.meta["source"])
    return out


def _with_checks(table: SectionTable) -> SectionTable:
    """A cached table with its mass check and axis as the objects the slicer makes."""
    from dataclasses import replace

    from geometry.slicing.common import AxisSpec, MassCheck

    raw, meta = table.meta, {}
    if "mass_check" in raw:
        meta["mass_check"] = MassCheck(**raw["mass_check"])
    if "axis" in raw:
        a = raw["axis"]
        meta["axis"] = AxisSpec(tuple(a["origin"]), tuple(a["direction"]), bool(a["found"]))
    if "source" in raw:
        meta["source"] = raw["source"]
    arrays = raw.get("arrays", {})
    if "points" in arrays and "triangles" in arrays:
        points, triangles = np.asarray(arrays["points"], float), np.asarray(arrays["triangles"], np.int64)
        if (
            points.ndim == 2
            and points.shape[1] == 3
            and triangles.ndim == 2
            and triangles.shape[1] == 3
            and (triangles.size == 0 or (triangles.min() >= 0 and triangles.max() < points.shape[0]))
        ):
            meta["surface"] = (points, triangles)
    return replace(table, meta=meta)
