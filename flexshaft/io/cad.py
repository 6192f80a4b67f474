"""Section tables for ``type = "cad"`` parts: the one place flexshaft reaches into :mod:`geometry`.

The geometry package (and build123d behind it) is imported only here and only
when a model has a CAD part, so models without one load fast.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from collections.abc import Callable, Mapping
from pathlib import Path

from ..errors import ModelError
from ..sections.table import SectionTable

__all__ = ["cad_sections", "resolve_function", "clear_cache", "FILE_SUFFIXES"]

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


def resolve_function(spec: str, base_dir: Path | None = None) -> Callable:
    """The part function named by ``"module:function"``.

    ``module`` is a dotted module on the Python path (``geometry.parts.testbench``)
    or a ``.py`` file next to the model file (``my_parts:flange`` for
    ``my_parts.py``).
    """
    module_name, _, func_name = spec.partition(":")
    if not module_name or not func_name:
        raise ModelError(
            "is not 'module:function' or a file",
            field="geometry",
            value=spec,
            valid="'module:function' (e.g. 'geometry.parts.testbench:ptss_part2') or a path to a "
            + "/".join(FILE_SUFFIXES)
            + " file",
        )
    local = (base_dir / f"{module_name}.py") if base_dir is not None else None
    try:
        if local is not None and local.is_file():
            mod_spec = importlib.util.spec_from_file_location(f"flexshaft_user_parts.{module_name}", local)
            module = importlib.util.module_from_spec(mod_spec)
            sys.modules[mod_spec.name] = module
            mod_spec.loader.exec_module(module)
        else:
            module = importlib.import_module(module_name)
    except ImportError as err:
        raise ModelError(
            f"cannot import module {module_name!r} ({err})",
            field="geometry",
            value=spec,
            valid="an importable module or a .py file beside the model file",
        ) from None
    func = getattr(module, func_name, None)
    if not callable(func):
        raise ModelError(
            f"module {module_name!r} has no function {func_name!r}",
            field="geometry",
            value=spec,
            valid="a part function of that module",
        )
    return func


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
    """
    params = dict(params or {})
    is_file = Path(geometry).suffix.lower() in FILE_SUFFIXES
    if is_file and params:
        raise ModelError(
            "a geometry file takes no parameters",
            field="params",
            value=params,
            valid="leave params out (it is for part functions)",
        )
    if not is_file and unit is not None:
        raise ModelError(
            "only a mesh file (STL/OBJ/PLY) takes a length unit",
            field="unit",
            value=unit,
            valid="leave unit out for a part function or STEP/BREP file",
        )
    path = (base_dir / geometry if base_dir is not None else Path(geometry)) if is_file else None
    key = (str(path.resolve()) if path else geometry, _freeze(params), unit, _freeze(axis), nu)
    if path is not None and path.is_file():
        key += (path.stat().st_mtime_ns,)
    if key in _CACHE:
        return _CACHE[key]
    from geometry.slicing import sections  # build123d: only now

    if path is not None:
        from geometry.cadio import read_cad

        shape = read_cad(path, unit=unit)
    else:
        func = resolve_function(geometry, base_dir)
        try:
            inspect.signature(func).bind(**params)
        except TypeError as err:
            raise ModelError(
                f"parameters do not fit {geometry} ({err})",
                field="params",
                value=params,
                valid=f"keyword parameters of {func.__name__}{inspect.signature(func)}",
            ) from None
        shape = func(**params)
    table = sections(shape, axis=axis, nu=nu, name=name, progress=progress)
    _CACHE[key] = table
    return table
