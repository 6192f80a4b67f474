"""What every signal reader returns: :class:`SignalTable`, and the unit spellings read (:data:`UNITS`).

The seam between the readers (the CSV signal file, :mod:`flexshaft.measurement.signalfile`; measured
test-bench files, :mod:`flexshaft.measurement.files`) and their consumers (``flexshaft spectrum``, the
csv scenario of ``simulate``, a study's torque history): one table type, one set of units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..validation import check_name

__all__ = ["UNITS", "VALID_UNITS", "SignalTable", "signal_entries", "stated_units"]

_PER_MINUTE = math.pi / 30.0  # one revolution per minute, rad/s
_DEGREE = math.pi / 180.0

#: Every unit spelling read: spelling -> (SI unit, factor to SI). The spellings test benches write:
#: ``Nm``/``N m`` (NI, HBM), ``1/min`` and ``U/min`` (revolutions per minute: DIN 1301, German
#: benches), ``rpm``.
UNITS: dict[str, tuple[str, float]] = {
    "s": ("s", 1.0),
    "ms": ("s", 1e-3),
    "rad": ("rad", 1.0),
    "deg": ("rad", _DEGREE),
    "°": ("rad", _DEGREE),
    "rad/s": ("rad/s", 1.0),
    "rpm": ("rad/s", _PER_MINUTE),
    "1/min": ("rad/s", _PER_MINUTE),
    "U/min": ("rad/s", _PER_MINUTE),
    "rev/min": ("rad/s", _PER_MINUTE),
    "N·m": ("N·m", 1.0),
    "N⋅m": ("N·m", 1.0),
    "N*m": ("N·m", 1.0),
    "Nm": ("N·m", 1.0),
    "N m": ("N·m", 1.0),
    "kN·m": ("N·m", 1e3),
    "kN⋅m": ("N·m", 1e3),
    "kN*m": ("N·m", 1e3),
    "kNm": ("N·m", 1e3),
    "kN m": ("N·m", 1e3),
}
#: The spellings, as an error's "valid" lists them.
VALID_UNITS = ", ".join(UNITS)


@dataclass(frozen=True)
class SignalTable:
    """Sampled signals on one uniform time base, in SI.

    Attributes
    ----------
    time : ndarray, shape (n,)
        Sample times, s (uniformly spaced, increasing).
    columns : dict of str to ndarray
        Each signal by its name (the header without its unit; a measured file's channel name), in SI.
    units : dict of str to str
        Each signal's SI unit: ``s``, ``rad``, ``rad/s`` or ``N·m``.
    rate_hz : float
        The sampling rate, Hz.
    source : str
        The file read.
    notes : tuple of str
        What reading did to the samples that a user should know: signals of different rates brought
        to one time base (:mod:`flexshaft.measurement.files`). Empty when every value is as the file has it.
    """

    time: np.ndarray
    columns: dict
    units: dict
    rate_hz: float
    source: str
    notes: tuple = ()


def stated_units(units, noun: str) -> dict[str, str]:
    """A reader's ``units`` argument checked: name -> unit string (stripped); ``noun`` is what the
    names name (``column``, ``channel``) for the error."""
    out = {}
    for key, unit in (units or {}).items():
        if not isinstance(key, str) or not isinstance(unit, str):
            raise ModelError(
                f"must map {noun} names to unit strings",
                field="units",
                value=units,
                valid="a dict such as {'torque': 'kNm'}",
            )
        out[key] = unit.strip()
    return out


def signal_entries(columns) -> list[tuple[str, str, object, str]]:
    """A writer's ``columns`` checked: ``{name: (values, unit)}``, non-empty, each unit one of
    :data:`UNITS`; returns (key, name, values, unit) per column (the values for the writer to check)."""
    if not isinstance(columns, dict) or not columns:
        raise ModelError("is not a non-empty dict", field="columns", valid="{name: (values, unit)}")
    out = []
    for key, entry in columns.items():
        name = check_name(key, "columns")
        try:
            values, unit = entry
        except (TypeError, ValueError):
            raise ModelError("is not a (values, unit) pair", field=name, valid="(array, unit)") from None
        if unit not in UNITS:
            raise ModelError("unknown unit", field=name, value=unit, valid=f"one of {VALID_UNITS}")
        out.append((key, name, values, unit))
    return out
