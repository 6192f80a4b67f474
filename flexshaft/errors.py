"""The one exception users see for bad input.

Every check on user input raises :class:`ModelError`. Its message is a single
line naming where the problem is (file, component), the field, the value with
its unit, and what would be valid, so the CLI can print it as is.
"""

from __future__ import annotations

import math

__all__ = ["ModelError", "format_value", "shown", "CONTROLS"]

#: The characters never written raw to a terminal: C0 controls (ESC starts a terminal's escape
#: sequences, BEL rings, CR overwrites the line), DEL, C1 controls (U+009B is a one-byte CSI), the
#: bidirectional controls that reorder what follows them (U+202A-202E, U+2066-2069, the marks U+200E,
#: U+200F, U+061C: a name could show one text and hold another) and the line and paragraph separators
#: U+2028/U+2029. Names from files may hold any of them; they stay true in files and JSON values.
CONTROLS = frozenset(
    [*range(0x20), 0x7F, *range(0x80, 0xA0), 0x061C, 0x200E, 0x200F, *range(0x202A, 0x202F)]
    + [*range(0x2066, 0x206A), 0x2028, 0x2029]
)
_ESCAPED = {c: f"\\u{c:04x}" for c in CONTROLS}


def shown(text: object, keep: str = "") -> str:
    """``text`` safe to print on a terminal: each of :data:`CONTROLS` (except those in ``keep``, e.g.
    ``"\\n"`` for a table's line ends) written as its escape ``\\u001b``, ``\\u202e``.

    The escape is JSON's own: a JSON document stays valid and means the same (raw controls can only
    stand inside its strings), so ``--json`` on a terminal keeps the true names. Everything else,
    ``·``, ``²`` and any script, is left as it is.
    """
    text = str(text)
    if text.isascii() and text.isprintable():  # the common case, without the table
        return text
    table = _ESCAPED if not keep else {c: e for c, e in _ESCAPED.items() if chr(c) not in keep}
    return text.translate(table)


def _plain(value: object) -> object:
    """A numpy scalar or 0-d array as the Python number it holds (``np.float64(0.742)`` -> 0.742), an
    array as a list of them, inside lists and tuples too, so a message shows ``0.742`` and not
    numpy's repr; anything else as it is. numpy is not imported here: a value from numpy has its
    module's name on its type."""
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        # a scalar or 0-d array gives its number, an array a (nested) list of numbers
        return value.tolist()
    if type(value) in (list, tuple):
        return type(value)(_plain(v) for v in value)
    return value


#: Longest rendering of a value in a message, characters: a list of a million numbers from a file
#: is cut, so the error stays a line one can read.
MAX_VALUE_CHARS = 200


def format_value(value: object) -> str:
    """Render a user-supplied value for an error message (repr for strings; numbers as numbers,
    numpy's scalars included; cut after :data:`MAX_VALUE_CHARS` characters)."""
    if type(value).__module__ == "numpy" and getattr(value, "size", 1) > 20:
        return f"an array of {value.size} values"
    text = _format(_plain(value))
    if len(text) > MAX_VALUE_CHARS:
        text = f"{text[: MAX_VALUE_CHARS - 40]}... ({len(text)} characters)"
    return text


def _format(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return repr(value)


class ModelError(ValueError):
    """Bad input to flexshaft: a model, a file, an option.

    Parameters
    ----------
    message : str
        What is wrong, when the structured fields below do not say it all.
    file : str, optional
        The model file the value came from.
    component : str, optional
        The chain component (or table) it belongs to, e.g. ``'chain[2] "part 3"'``.
    field : str, optional
        The key or argument name.
    value : object, optional
        The offending value as given.
    unit : str, optional
        The unit the value is read in, e.g. ``"N·m/rad"``.
    valid : str, optional
        What would be accepted, e.g. ``"a finite number > 0"``.

    Notes
    -----
    ``str(err)`` is one line: ``file: component: field = value unit: message;
    valid: ...``. The attributes stay available for programs.
    """

    def __init__(
        self,
        message: str = "",
        *,
        file: str | None = None,
        component: str | None = None,
        field: str | None = None,
        value: object = None,
        unit: str | None = None,
        valid: str | None = None,
        has_value: bool | None = None,
    ) -> None:
        self.message = message
        self.file = file
        self.component = component
        self.field = field
        self.value = value
        self.unit = unit
        self.valid = valid
        # A value of None is a legitimate thing to report only when asked.
        self.has_value = (value is not None) if has_value is None else has_value
        super().__init__(self._render())

    def _render(self) -> str:
        where = [p for p in (self.file, self.component) if p]
        what = ""
        if self.field:
            what = self.field
            if self.has_value:
                what += f" = {format_value(self.value)}"
                if self.unit:
                    what += f" {self.unit}"
        parts = [": ".join(where + ([what] if what else []))] if (where or what) else []
        text = ": ".join(p for p in parts + ([self.message] if self.message else []) if p)
        if self.valid:
            text += f"; valid: {self.valid}"
        # one line, and no name from a file can move the cursor, ring or reorder the line it is in
        return shown(" ".join(text.split("\n")))

    def replaced(self, **changes) -> ModelError:
        """A copy of this error with some of its fields changed (``field="--speed"``, ``component=...``):
        the message is rendered when an error is made, so a changed error is a new one."""
        fields = ("message", "file", "component", "field", "value", "unit", "valid", "has_value")
        return ModelError(**({k: getattr(self, k) for k in fields} | changes))

    def located(self, *, file: str | None = None, component: str | None = None) -> ModelError:
        """A copy of this error with its location filled in where it was missing."""
        return self.replaced(file=self.file or file, component=self.component or component)
