"""What every flexible-body file carries: format, version, units, DOF order, material.

Shared by the writers and readers of every format (:mod:`flexshaft.io.bodies`,
:mod:`flexshaft.io.dmig`), so that each checks the same things.
"""

from __future__ import annotations

from ..errors import ModelError
from ..parts.model import DOF_NAMES
from ..reduction.craig_bampton import FlexibleBody

__all__ = ["FORMAT", "VERSION", "UNITS", "dof_order", "metadata", "check_metadata"]

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
