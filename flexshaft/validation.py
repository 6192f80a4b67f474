"""Checks for numbers and names at the public boundary.

Each check returns the cleaned value or raises :class:`~flexshaft.ModelError`
naming the field, the value, its unit and the valid range.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from .errors import ModelError

__all__ = [
    "check_real",
    "check_int",
    "check_name",
    "check_choice",
    "check_type",
    "check_positive",
    "check_frequency",
    "Domain",
    "STIFFNESS",
    "INERTIA",
    "POSITIVE_INERTIA",
    "MASS",
    "DAMPER",
    "FRACTION",
    "LENGTH",
    "GEAR_RATIO",
    "RAYLEIGH_ALPHA",
    "RAYLEIGH_BETA",
    "FREQUENCY",
    "POSITIVE_FREQUENCY",
    "RAYLEIGH_ALPHA_MAX",
    "RAYLEIGH_BETA_MAX",
    "FRACTION_VALID",
    "MAX_FREQUENCY_HZ",
    "MAX_SPEED_RPM",
]

#: What a damping ratio may be, for error messages.
FRACTION_VALID = "a fraction in [0, 1), e.g. 0.0053"

#: The highest frequency asked for or filtered by, Hz (``--to``, ``--max-hz``, ``cutoff_hz``): far
#: above every mode a drivetrain model has (torsional modes lie below 10 kHz; even millimetre
#: elements of a 6-DOF shaft stay in the MHz), and far below where ω² leaves floating point
#: (f ≈ 2e153 Hz): 1e300 Hz made the response's ω² overflow.
MAX_FREQUENCY_HZ = 1e9
#: The highest shaft speed, rpm (either sense): ten times a dental drill's 400 000 rpm. Gyroscopic
#: terms grow with it; 1e308 rpm made them overflow.
MAX_SPEED_RPM = 1e6


def _range_text(lo: float | None, lo_open: bool, hi: float | None, hi_open: bool) -> str:
    bounds = []
    if lo is not None:
        bounds.append(f"{'>' if lo_open else '>='} {lo:g}")
    if hi is not None:
        bounds.append(f"{'<' if hi_open else '<='} {hi:g}")
    return " and ".join(bounds)


def check_real(
    value: object,
    field: str,
    unit: str,
    *,
    lo: float | None = None,
    lo_open: bool = False,
    hi: float | None = None,
    hi_open: bool = False,
) -> float:
    """Return ``value`` as a finite float inside the given bounds.

    Parameters
    ----------
    value : object
        What the user gave.
    field : str
        Its name, for the message.
    unit : str
        Its unit, for the message (``""`` for dimensionless).
    lo, hi : float, optional
        Bounds; ``lo_open`` / ``hi_open`` make them strict.
    """
    bounds = _range_text(lo, lo_open, hi, hi_open)
    valid = "a finite number" + (f" {bounds}" if bounds else "") + (f" ({unit})" if unit else "")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        hint = "not a number"
        if isinstance(value, str) and unit:
            hint += f" (write a bare number: {field} is always in {unit})"
        raise ModelError(hint, field=field, value=value, valid=valid, has_value=True)
    x = float(value)
    if not math.isfinite(x):
        raise ModelError("not finite", field=field, value=x, unit=unit, valid=valid)
    too_low = lo is not None and (x <= lo if lo_open else x < lo)
    too_high = hi is not None and (x >= hi if hi_open else x > hi)
    if too_low or too_high:
        raise ModelError("out of range", field=field, value=x, unit=unit, valid=valid)
    return x


def check_int(value: object, field: str, *, lo: int = 1, hi: int | None = None) -> int:
    """Return ``value`` as an int in ``[lo, hi]``; floats such as ``2.0`` are refused."""
    valid = f"an integer >= {lo}" + (f" and <= {hi}" if hi is not None else "")
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ModelError("not an integer", field=field, value=value, valid=valid, has_value=True)
    n = int(value)
    if n < lo or (hi is not None and n > hi):
        raise ModelError("out of range", field=field, value=n, valid=valid)
    return n


def check_name(value: object, field: str = "name") -> str:
    """Return a non-empty, single-line, stripped name."""
    valid = "a non-empty string on one line"
    if not isinstance(value, str):
        raise ModelError("not a string", field=field, value=value, valid=valid, has_value=True)
    name = value.strip()
    if not name or "\n" in name or "\r" in name:
        raise ModelError("unusable name", field=field, value=value, valid=valid)
    return name


def check_choice(value: object, field: str, choices: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of ``choices``."""
    valid = "one of " + ", ".join(repr(c) for c in choices)
    if not isinstance(value, str) or value not in choices:
        raise ModelError("unknown option", field=field, value=value, valid=valid, has_value=True)
    return value


def check_type(value: object, kind: type, field: str, valid: str) -> None:
    """Refuse ``value`` unless it is a ``kind`` (the message names the type it is, not its value)."""
    if not isinstance(value, kind):
        raise ModelError(f"is a {type(value).__name__}", field=field, valid=valid, has_value=False)


def check_positive(value: float, field: str, unit: str, problem: str) -> None:
    """Refuse ``value`` unless it is finite and > 0; ``problem`` is the message (say what it must be)."""
    if not (np.isfinite(value) and value > 0):
        raise ModelError(problem, field=field, value=value, unit=unit, valid=f"a finite number > 0 ({unit})")


def check_frequency(value: object, field: str, *, lo: float = 0.0, lo_open: bool = False) -> float:
    """Return ``value`` as a finite frequency in Hz, ``lo`` (0) to :data:`MAX_FREQUENCY_HZ`."""
    return check_real(value, field, "Hz", lo=lo, lo_open=lo_open, hi=MAX_FREQUENCY_HZ)


#: The largest Rayleigh coefficients, α in 1/s and β in s. ξ = α/(2ω) + βω/2, so α = 1e6 1/s puts
#: every mode below 80 kHz past critical damping and β = 1 s every mode above 0.16 Hz: beyond any
#: drivetrain's damping, and αM, βK stay within a factor 1e6 of M and K. Larger coefficients only
#: reach floating point's end (1e300 overflowed the damped eigen-solve and the response).
RAYLEIGH_ALPHA_MAX = 1e6
RAYLEIGH_BETA_MAX = 1.0


@dataclass(frozen=True)
class Domain:
    """The values a physical quantity may take: finite, between bounds, in a unit.

    One of these is the one statement of a check that components, file readers, calibration bounds
    and sweeps all make (a stiffness > 0, a damping ratio in [0, 1), ...).

    Attributes
    ----------
    lo, hi : float or None
    lo_open, hi_open : bool
        Whether the bound itself is excluded.
    unit : str
    """

    lo: float | None = None
    lo_open: bool = False
    hi: float | None = None
    hi_open: bool = False
    unit: str = ""

    def contains(self, x: float) -> bool:
        """Whether ``x`` is a finite value inside the domain."""
        x = float(x)
        if not math.isfinite(x):
            return False
        if self.lo is not None and (x <= self.lo if self.lo_open else x < self.lo):
            return False
        return not (self.hi is not None and (x >= self.hi if self.hi_open else x > self.hi))

    def check(self, value: object, field: str) -> float:
        """``value`` as a float in the domain, or the one-line ModelError naming ``field``
        (:func:`check_real`)."""
        return check_real(
            value, field, self.unit, lo=self.lo, lo_open=self.lo_open, hi=self.hi, hi_open=self.hi_open
        )

    @property
    def bounds(self) -> str:
        """``"> 0"``, ``">= 0 and < 1"``; ``""`` when unbounded."""
        return _range_text(self.lo, self.lo_open, self.hi, self.hi_open)

    @property
    def text(self) -> str:
        """``"> 0 N·m/rad"``, ``">= 0 and < 1"``: the domain for an error message."""
        return (self.bounds or "finite") + (f" {self.unit}" if self.unit else "")


#: A spring's stiffness (a shaft's, a coupling's, a gear mesh's), N·m/rad.
STIFFNESS = Domain(0.0, True, unit="N·m/rad")
#: A flexible component's inertia, kg·m² (0: massless).
INERTIA = Domain(0.0, unit="kg·m²")
#: A rigid body's inertia, kg·m² (a rigid body without inertia is no body).
POSITIVE_INERTIA = Domain(0.0, True, unit="kg·m²")
#: A mass, kg.
MASS = Domain(0.0, unit="kg")
#: A discrete damper, N·m·s/rad.
DAMPER = Domain(0.0, unit="N·m·s/rad")
#: A damping ratio, a fraction (0.0053 for 0.53 %).
FRACTION = Domain(0.0, False, 1.0, True)
#: A length that must be > 0, m (an element's, a mesh size).
LENGTH = Domain(0.0, True, unit="m")
#: A gear ratio (driving-side speed / driven-side speed): beyond these the reflected stiffness (n²
#: apart) leaves too few digits of double precision for the shafts on the other side.
GEAR_RATIO = Domain(1e-3, False, 1e3, False)
#: Rayleigh's inertia-proportional coefficient α, 1/s.
RAYLEIGH_ALPHA = Domain(0.0, False, RAYLEIGH_ALPHA_MAX, False, "1/s")
#: Rayleigh's stiffness-proportional coefficient β, s.
RAYLEIGH_BETA = Domain(0.0, False, RAYLEIGH_BETA_MAX, False, "s")
#: A frequency, Hz, 0 to :data:`MAX_FREQUENCY_HZ` (:func:`check_frequency`) ...
FREQUENCY = Domain(0.0, False, MAX_FREQUENCY_HZ, False, "Hz")
#: ... and one that must be > 0 (a range's upper end, a cut-off).
POSITIVE_FREQUENCY = Domain(0.0, True, MAX_FREQUENCY_HZ, False, "Hz")
