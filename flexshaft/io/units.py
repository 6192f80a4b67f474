"""Numbers with units in model files: ``stiffness = "307.9 kN*m/rad"``, converted to SI once, here.

A bare number is SI, as always. A string is read by pint (imported only when a model file has
one) and must have the dimension of the key's SI unit; anything else names both. Angles are
radians, which pint treats as dimensionless, so ``"86 kN*m"`` is accepted for a torsional
stiffness in N·m/rad as well as ``"86 kN*m/rad"``; degrees are converted (``"1 N*m/deg"``).
"""

from __future__ import annotations

import math

from ..errors import ModelError

__all__ = ["si_value", "PINT_UNITS"]

#: The SI unit of each model-file unit, as pint spells it.
PINT_UNITS = {
    "N·m/rad": "N*m/rad",
    "kg·m²": "kg*m**2",
    "N·m·s/rad": "N*m*s/rad",
    "m": "m",
    "Hz": "Hz",
    "N/m": "N/m",
    "kg": "kg",
    "Pa": "Pa",
    "kg/m³": "kg/m**3",
    "1/s": "1/s",
    "s": "s",
}

_REGISTRY = None


def _registry():
    global _REGISTRY
    if _REGISTRY is None:
        import pint

        _REGISTRY = pint.UnitRegistry()
    return _REGISTRY


def si_value(value, field: str, unit: str):
    """``value`` as a number in ``unit`` (SI): a number as it is, a string with a unit converted.

    Parameters
    ----------
    value : object
        From the model file.
    field : str
        Its key, for messages.
    unit : str
        The key's SI unit as the model-file reference writes it (``"N·m/rad"``).

    Raises
    ------
    ModelError
        A string that is not a number with a unit, or whose unit has another dimension.
    """
    if not isinstance(value, str) or unit not in PINT_UNITS:
        return value
    ureg = _registry()
    try:
        q = ureg.Quantity(value)
    except Exception as err:  # noqa: BLE001 - pint's parser raises many kinds for a bad string
        raise ModelError(
            f"is not a number with a unit ({type(err).__name__})",
            field=field,
            value=value,
            has_value=True,
            valid=f"a number in {unit}, or a string such as '1.5 {PINT_UNITS[unit]}'",
        ) from None
    target = ureg.Quantity(1.0, PINT_UNITS[unit])
    if not isinstance(q, ureg.Quantity) or q.dimensionality != target.dimensionality:
        got = q.units if isinstance(q, ureg.Quantity) else "no unit"
        raise ModelError(
            f"has the unit {got}, which is not a {unit}",
            field=field,
            value=value,
            has_value=True,
            valid=f"a quantity in {unit} or a unit of the same dimension",
        )
    si = float(q.to(PINT_UNITS[unit]).magnitude)
    if not math.isfinite(si):
        valid = f"a finite number in {unit}"
        raise ModelError("is not finite", field=field, value=value, has_value=True, valid=valid)
    return si
