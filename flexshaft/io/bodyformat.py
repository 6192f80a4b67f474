"""What every flexible-body file carries: format, version, units, DOF order, material.

Shared by the writers and readers of every format (:mod:`flexshaft.io.bodies`,
:mod:`flexshaft.io.dmig`), so that each checks the same things.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..parts.model import DOF_NAMES
from ..reduction.craig_bampton import FlexibleBody

__all__ = [
    "FORMAT",
    "VERSION",
    "UNITS",
    "MAX_ENTRIES",
    "dof_order",
    "metadata",
    "check_metadata",
    "check_body",
]

FORMAT = "flexshaft-flexible-body"
VERSION = 1
#: The unit of every quantity in an exported flexible body.
UNITS = {
    "length": "m",
    "angle": "rad",
    "mass": "kg",
    "time": "s",
    "frequency": "Hz",
    "K": "N/m, N/rad, N·m/m, N·m/rad (by DOF pair)",
    "M": "kg, kg·m, kg·m² (by DOF pair)",
    "C": "N·s/m, N·m·s/rad (by DOF pair)",
    "damping_ratios": "fraction",
}


def dof_order(body: FlexibleBody) -> list[str]:
    """Names of the reduced coordinates: boundary DOFs (node-major), then the modal coordinates."""
    names = [f"node {n} {d}" for n in body.boundary_nodes for d in DOF_NAMES[body.dofs]]
    n_fixed = body.n_modes - body.n_residual
    return (
        names
        + [f"mode {k + 1}" for k in range(n_fixed)]
        + [f"residual {k + 1}" for k in range(body.n_residual)]
    )


def metadata(body: FlexibleBody, material) -> dict:
    """The metadata every export carries: format, version, units, name, DOFs, material."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": UNITS,
        "name": body.name,
        "dofs": body.dofs,
        "dof_order": dof_order(body),
        "residual_vectors": body.n_residual,
        "material": None
        if material is None
        else {"name": material.name, "E": material.E, "nu": material.nu, "rho": material.rho},
    }


def check_metadata(meta: dict, source: str) -> None:
    """Refuse metadata that is not a flexshaft flexible body of this version in SI units, naming both."""
    if meta.get("format") != FORMAT:
        raise ModelError(
            "is not a flexshaft flexible body",
            file=source,
            field="format",
            value=meta.get("format"),
            has_value=True,
            valid=repr(FORMAT),
        )
    if meta.get("version") != VERSION:
        raise ModelError(
            "unsupported version",
            file=source,
            field="version",
            value=meta.get("version"),
            has_value=True,
            valid=str(VERSION),
        )
    units = meta.get("units", {})
    for key, unit in UNITS.items():
        if units.get(key) != unit:
            raise ModelError(
                f"the file's {key} unit is {units.get(key)!r}, flexshaft's is {unit!r}",
                file=source,
                field=f"units.{key}",
                value=units.get(key),
                has_value=True,
                valid=repr(unit),
            )


#: Most entries one matrix of a body file may claim (T of a 20 000-element 6-DOF part reduced to 34
#: coordinates has 4e6; 5e7 doubles are 400 MB). A header claiming more is refused before anything
#: is allocated.
MAX_ENTRIES = 50_000_000


def _bad(source: str, field: str, what: str, valid: str, value=None) -> ModelError:
    return ModelError(what, file=source, field=field, value=value, has_value=value is not None, valid=valid)


def check_body(arrays: dict, meta: dict, source: str) -> None:
    """Refuse a body whose metadata or arrays do not fit together, before it is used.

    Types and sizes of the metadata; every array finite and of the shape the
    DOF order implies; K, M, C symmetric (to the 9 digits a DMIG field keeps)
    and M positive definite; frequencies >= 0; damping ratios in [0, 1).
    """
    if not isinstance(meta.get("name"), str):
        raise _bad(source, "name", "must be a string", "the part's name", meta.get("name"))
    if meta.get("dofs") not in DOF_NAMES:
        raise _bad(source, "dofs", "unknown DOF set", "'torsion' or 'full'", meta.get("dofs"))
    order = meta.get("dof_order")
    if not isinstance(order, list) or not all(isinstance(x, str) for x in order):
        raise _bad(source, "dof_order", "must be a list of names", "one name per reduced coordinate")
    n_res = meta.get("residual_vectors", 0)
    if isinstance(n_res, bool) or not isinstance(n_res, int) or n_res < 0:
        raise _bad(source, "residual_vectors", "must be a whole number >= 0", "an integer >= 0", n_res)
    mat = meta.get("material")
    if mat is not None and not (
        isinstance(mat, dict)
        and isinstance(mat.get("name"), str)
        and all(isinstance(mat.get(k), int | float) and np.isfinite(mat.get(k)) for k in ("E", "nu", "rho"))
    ):
        raise _bad(source, "material", "must be {name, E, nu, rho}", "null or a material with finite numbers")
    d = len(DOF_NAMES[meta["dofs"]])
    n = len(order)
    for key, a in arrays.items():
        if not isinstance(a, np.ndarray) or a.dtype.kind not in "fiu":
            raise _bad(source, key, "is not a numeric array", "numbers")
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise _bad(source, key, "has non-finite values", "finite numbers")
    nodes = arrays["boundary_nodes"]
    nb = nodes.size * d
    shapes = {
        "boundary_nodes": (nodes.size,),
        "boundary_x": (nodes.size,),
        "K": (n, n),
        "M": (n, n),
        "C": (n, n),
        "fixed_interface_hz": (n - nb,),
        "free_hz": (n,),
        "free_modes": (n, n),
        "damping_ratios": (n,),
    }
    for key, shape in shapes.items():
        if arrays[key].shape != shape:
            raise _bad(source, key, f"has shape {arrays[key].shape}", f"{shape} for {n} coordinates", None)
    T = arrays["T"]
    if T.ndim != 2 or T.shape[1] != n or T.shape[0] % d or T.shape[0] < nb:
        raise _bad(source, "T", f"has shape {T.shape}", f"(a multiple of {d} rows, {n} columns)")
    if n_res > n - nb:
        raise _bad(source, "residual_vectors", f"is more than the {n - nb} modal coordinates", "fewer", n_res)
    if np.any(nodes < 0) or np.any(nodes >= T.shape[0] // d) or np.unique(nodes).size != nodes.size:
        valid = f"distinct nodes 0 … {T.shape[0] // d - 1}"
        raise _bad(source, "boundary_nodes", "are not distinct nodes of the mesh", valid)
    for key in ("K", "M", "C"):
        A = arrays[key]
        if np.max(np.abs(A - A.T), initial=0.0) > 1e-8 * max(float(np.max(np.abs(A), initial=0.0)), 1e-300):
            raise _bad(source, key, "is not symmetric", "a symmetric matrix (K, M and C of a body are)")
    try:
        np.linalg.cholesky(arrays["M"])
    except np.linalg.LinAlgError:
        raise _bad(source, "M", "is not positive definite", "the mass matrix of a body") from None
    for key in ("fixed_interface_hz", "free_hz"):
        if np.any(arrays[key] < 0):
            raise _bad(source, key, "has negative frequencies", "frequencies >= 0 (Hz)")
    z = arrays["damping_ratios"]
    if np.any((z < 0) | (z >= 1)):
        raise _bad(source, "damping_ratios", "has ratios outside [0, 1)", "fractions in [0, 1)")
