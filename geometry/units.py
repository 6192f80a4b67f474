"""The one place lengths cross between SI (flexshaft) and millimetres (build123d).

build123d and OCCT work in millimetres; every function of :mod:`geometry` takes
and returns SI metres. Nothing else in the package multiplies by 1000.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "LENGTH_UNITS",
    "metres_per",
    "MM_PER_M",
    "to_cad",
    "from_cad",
    "area_from_cad",
    "moment_from_cad",
    "volume_from_cad",
    "volume_moment_from_cad",
]

#: build123d's length unit is the millimetre.
MM_PER_M = 1000.0


#: Length units accepted for files that carry none of their own (STL, OBJ, PLY), in metres.
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254}


def metres_per(unit: str, *, field: str = "unit") -> float:
    """Metres per one ``unit`` of a mesh file, or a ModelError listing the valid units."""
    from flexshaft.errors import ModelError

    if unit not in LENGTH_UNITS:
        raise ModelError("unknown length unit", field=field, value=unit, valid=", ".join(LENGTH_UNITS))
    return LENGTH_UNITS[unit]


def to_cad(length_m):
    """A length (or array of lengths) in metres as build123d millimetres."""
    return np.multiply(length_m, MM_PER_M) if isinstance(length_m, np.ndarray) else length_m * MM_PER_M


def from_cad(length_mm):
    """A build123d length in millimetres (scalar or array) as metres."""
    return np.divide(length_mm, MM_PER_M) if isinstance(length_mm, np.ndarray) else length_mm / MM_PER_M


def area_from_cad(area_mm2):
    """An area in mm² as m²."""
    return area_mm2 / MM_PER_M**2


def volume_from_cad(volume_mm3):
    """A volume in mm³ as m³."""
    return volume_mm3 / MM_PER_M**3


def moment_from_cad(moment_mm4):
    """A second moment of area in mm⁴ as m⁴."""
    return moment_mm4 / MM_PER_M**4


def volume_moment_from_cad(moment_mm5):
    """A second moment of volume (∫ r² dV, the mass moment per unit density) in mm⁵ as m⁵."""
    return moment_mm5 / MM_PER_M**5
