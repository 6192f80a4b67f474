"""Numbers with units in model files: ``stiffness = "307.9 kN*m/rad"``, converted to SI once, here.

A bare number is SI, as always. A string is one number and a unit expression, read by a small
grammar of its own - nothing in it is evaluated::

    quantity := number ["/"] unit      (at most MAX_LENGTH characters; "0.1/s" is 0.1 1/s)
    number   := [+-] digits [. digits] [e [+-] digits]        (no inf, no nan)
    unit     := term (("*" | "·" | "×" | "/" | " ") term)*
    term     := ("1" | NAME | "(" unit ")") [("**" | "^") [+-] digits | superscript digits]

A NAME is a unit pint knows (``kN``, ``mm``, ``t``, ``us``, ``deg`` or ``°``, ``rad``, ``GPa``...);
pint is used only to look names up and to convert (imported only when a model file has a unit).
Exponents are whole numbers from -MAX_EXPONENT to MAX_EXPONENT, brackets nest at most MAX_DEPTH
deep, and every unit of the expression ends with a power in the same range - so ``"9**9**9 kg"``,
``"1 m**99"`` and a unit with no number (``"kg*m^2"``) are errors naming the field, found before
any arithmetic.

The unit must have the dimension of the key's SI unit; anything else names both. Angles are
radians, which pint treats as dimensionless, so ``"86 kN*m"`` is accepted for a torsional
stiffness in N·m/rad as well as ``"86 kN*m/rad"``; degrees are converted (``"1 N*m/deg"``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..errors import ModelError

__all__ = [
    "si_value",
    "parse_quantity",
    "Quantity",
    "PINT_UNITS",
    "MAX_LENGTH",
    "MAX_EXPONENT",
    "MAX_DEPTH",
]

#: The SI unit of each model-file unit, as the grammar below spells it.
PINT_UNITS = {
    "N·m/rad": "N*m/rad",
    "N·m": "N*m",
    "rad": "rad",
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

#: Longest unit string read, characters: "307.93318 kN*m/rad" is 18; a string longer than this is
#: not a number with a unit someone typed.
MAX_LENGTH = 200
#: Largest exponent, literal or after brackets multiply out: m⁴ (a second moment of area) is the
#: highest power a drivetrain quantity needs.
MAX_EXPONENT = 4
#: Deepest nesting of brackets: "(kN*m)/(rad)" is one level.
MAX_DEPTH = 3

_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
_SUPERSCRIPT = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺", "0123456789-+")
# One token: a unit name, a run of digits, a superscript exponent, an operator, a bracket, spaces.
_TOKEN = re.compile(
    r"(?P<name>[A-Za-z_µμ]+|°)|(?P<int>\d+)|(?P<sup>[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)"
    r"|(?P<op>\*\*|\^|[*·⋅×/()+-])|(?P<space>\s+)"
)
_MULTIPLY = ("*", "·", "⋅", "×")


class _Refused(ValueError):
    """A unit string the grammar does not accept; the reason, for the message."""


@dataclass(frozen=True)
class Quantity:
    """A parsed quantity: the number as written and its unit as {pint name: power}.

    Parameters
    ----------
    magnitude : float
        The number, in the unit below.
    powers : tuple of (str, int)
        Each unit's canonical pint name and power (nonzero, at most MAX_EXPONENT in size).
    """

    magnitude: float
    powers: tuple[tuple[str, int], ...]


_REGISTRY = None


def _registry():
    global _REGISTRY
    if _REGISTRY is None:
        import pint

        _REGISTRY = pint.UnitRegistry()
    return _REGISTRY


def _tokens(text: str) -> list[tuple[str, str]]:
    """``[(kind, text)]`` of a unit expression, spaces kept (they multiply between two terms)."""
    out, at = [], 0
    while at < len(text):
        m = _TOKEN.match(text, at)
        if m is None:
            raise _Refused(f"the character {text[at]!r} is not part of a unit")
        out.append((m.lastgroup, m.group()))
        at = m.end()
    return out


class _Parser:
    """Recursive descent over the tokens of one unit expression into {name: power}; no arithmetic
    beyond adding small integer powers, so its work is linear in the (bounded) string."""

    def __init__(self, text: str, lookup) -> None:
        self.tokens = _tokens(text)
        self.at = 0
        self.lookup = lookup

    def _peek(self) -> tuple[str, str] | None:
        """The next token that is not a space (``at`` moves past the spaces), or None at the end."""
        while self.at < len(self.tokens) and self.tokens[self.at][0] == "space":
            self.at += 1
        return self.tokens[self.at] if self.at < len(self.tokens) else None

    def _take(self) -> tuple[str, str]:
        tok = self._peek()
        if tok is None:
            raise _Refused("it ends where a unit is expected")
        self.at += 1
        return tok

    def parse(self) -> dict[str, int]:
        powers = self._unit(0)
        tok = self._peek()
        if tok is not None:
            raise _Refused(f"{tok[1]!r} is not expected there")
        return powers

    def _unit(self, depth: int) -> dict[str, int]:
        powers = self._term(depth)
        while True:
            spaced = self.at < len(self.tokens) and self.tokens[self.at][0] == "space"
            tok = self._peek()
            if tok is None or tok[1] == ")":
                return powers
            if tok[1] in _MULTIPLY or tok[1] == "/":
                self.at += 1
                sign = -1 if tok[1] == "/" else 1
            elif spaced and (tok[0] == "name" or tok[1] == "("):
                sign = 1  # "N m" is N·m, as pint reads it
            else:
                raise _Refused(f"{tok[1]!r} is not expected there")
            for name, p in self._term(depth).items():
                powers[name] = powers.get(name, 0) + sign * p

    def _term(self, depth: int) -> dict[str, int]:
        kind, text = self._take()
        if kind == "name":
            base = {self.lookup(text): 1}
        elif kind == "int" and text == "1":
            base = {}  # "1/s"
        elif text == "(":
            if depth >= MAX_DEPTH:
                raise _Refused(f"brackets nest deeper than {MAX_DEPTH}")
            base = self._unit(depth + 1)
            if self._take()[1] != ")":
                raise _Refused("a bracket is not closed")
        else:
            raise _Refused(f"{text!r} is not a unit")
        n = self._exponent()
        return {name: p * n for name, p in base.items()}

    def _exponent(self) -> int:
        start = self.at
        tok = self._peek()
        if tok is not None and tok[0] == "sup" and self.at == start:
            self.at += 1
            written = tok[1].translate(_SUPERSCRIPT)
        elif tok is not None and tok[1] in ("**", "^"):
            self.at += 1
            sign = ""
            if self._peek() is not None and self._peek()[1] in ("+", "-"):
                sign = self._take()[1]
            tok = self._take()
            if tok[0] != "int":
                raise _Refused(f"the exponent {tok[1]!r} is not a whole number")
            written = sign + tok[1]
        else:
            self.at = start  # no exponent: a space before the next term still multiplies
            return 1
        if len(written.lstrip("+-")) > 2 or abs(int(written)) > MAX_EXPONENT:
            raise _Refused(f"the exponent {written} is beyond ±{MAX_EXPONENT}")
        return int(written)


def _lookup(name: str) -> str:
    """pint's canonical name of one unit name (``"kN"`` -> ``"kilonewton"``), nothing evaluated."""
    import pint

    if name == "°":
        return "degree"
    try:
        return _registry().get_name(name)
    except pint.errors.PintError:
        raise _Refused(f"{name!r} is not a unit") from None


def _powers(text: str) -> tuple[tuple[str, int], ...]:
    powers = _Parser(text, _lookup).parse()
    for name, p in powers.items():
        if abs(p) > MAX_EXPONENT:
            raise _Refused(f"{name} ends with the power {p}, beyond ±{MAX_EXPONENT}")
    return tuple((name, p) for name, p in powers.items() if p != 0)


def parse_quantity(text: str) -> Quantity:
    """A number with a unit, by the grammar in the module docstring; nothing is evaluated.

    Parameters
    ----------
    text : str
        ``"307.9 kN*m/rad"``, ``"58.1 kg·m²"``, ``"1 N*m/deg"``.

    Returns
    -------
    Quantity
        The number as written and the unit's canonical pint names with their powers (empty when
        the string holds only a number).

    Raises
    ------
    ValueError
        The string is too long, has no number in front, or its unit is not in the grammar (the
        message says which; :func:`si_value` turns it into a ModelError naming the field).
    """
    if len(text) > MAX_LENGTH:
        raise _Refused(f"it is {len(text)} characters long, more than {MAX_LENGTH}")
    text = text.strip()
    m = _NUMBER.match(text)
    if m is None:
        raise _Refused("it has no number in front")
    magnitude = float(m.group())  # the pattern has no inf or nan; "1e999" is inf, refused later
    rest = text[m.end() :].lstrip()
    if rest[:1] in ("*", "^", "·", "⋅", "×", "+", "-"):
        raise _Refused(f"{rest[:2]!r} follows the number: one number, then a unit (nothing is computed)")
    if rest.startswith("/"):
        rest = "1" + rest  # "0.1/s" is 0.1 1/s, as pint reads it; "2/3 m" stays refused ("3" is no unit)
    return Quantity(magnitude, _powers(rest) if rest else ())


def _unit(powers):
    from pint.util import UnitsContainer

    return _registry().Unit(UnitsContainer(dict(powers)))


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
        A string that is not a number with a unit (by the grammar of the module docstring), a
        unit of another dimension, or a value that is not finite in SI.
    """
    if not isinstance(value, str) or unit not in PINT_UNITS:
        return value
    import pint

    spelled = PINT_UNITS[unit]
    try:
        q = parse_quantity(value)
    except _Refused as why:
        raise ModelError(
            f"is not a number with a unit: {why}",
            field=field,
            value=value,  # a long one is cut by the message
            has_value=True,
            valid=f"a number in {unit}, or a number and a unit such as '1.5 {spelled}' (names pint knows, "
            f"* / · and brackets, whole exponents up to ±{MAX_EXPONENT}, at most {MAX_LENGTH} characters)",
        ) from None
    ureg = _registry()
    given = _unit(q.powers)
    target = _unit(_powers(spelled))
    if not q.powers:
        raise ModelError(
            "is a number in a string, with no unit",
            field=field,
            value=value,
            has_value=True,
            valid=f"a bare number (SI: {unit}), or a number and a unit such as '1.5 {spelled}'",
        )
    if given.dimensionality != target.dimensionality:
        raise ModelError(
            f"has the unit {given}, which is not a {unit}",
            field=field,
            value=value,
            has_value=True,
            valid=f"a quantity in {unit} or a unit of the same dimension",
        )
    valid = f"a finite number in {unit}"
    try:
        si = float(ureg.Quantity(q.magnitude, given).to(target).magnitude)
    except OverflowError:
        raise ModelError("is beyond floating point in SI", field=field, value=value, valid=valid) from None
    except pint.errors.PintError as err:  # an offset unit (degC) multiplied: no plain factor to SI
        raise ModelError(f"cannot be converted ({err})", field=field, value=value, valid=valid) from None
    if not math.isfinite(si):
        raise ModelError("is not finite", field=field, value=value, has_value=True, valid=valid)
    return si
