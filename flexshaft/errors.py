"""The one exception users see for bad input.

Every check on user input raises :class:`ModelError`. Its message is a single
line naming where the problem is (file, component), the field, the value with
its unit, and what would be valid, so the CLI can print it as is.
"""

from __future__ import annotations

import math

__all__ = ["ModelError", "format_value"]


def format_value(value: object) -> str:
    """Render a user-supplied value for an error message (repr for strings)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return repr(value)
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
        return " ".join(text.split("\n"))

    def located(self, *, file: str | None = None, component: str | None = None) -> ModelError:
        """A copy of this error with its location filled in where it was missing."""
        return ModelError(
            self.message,
            file=self.file or file,
            component=self.component or component,
            field=self.field,
            value=self.value,
            unit=self.unit,
            valid=self.valid,
            has_value=self.has_value,
        )
