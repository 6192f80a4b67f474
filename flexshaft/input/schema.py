"""One declarative schema for flexshaft's TOML files: model files, study files, targets files.

A :class:`Field` says what one key holds - its kind, its unit (a string with a unit such as
``"307.9 kN*m/rad"`` is converted to SI by :func:`flexshaft.input.quantities.si_value`), the values it
may take (a :class:`~flexshaft.validation.Domain`, an integer range or choices), its default and its
help text. A :class:`Table` lists a table's fields; tables nest (a field of kind ``"table"`` holds an
inline table, one of kind ``"tables"`` an array of tables, each read by its own :class:`Table`).

:func:`toml_file` parses a file with its nesting refused before the parser recurses
(:mod:`flexshaft.system.nesting`), and :func:`read` checks one table: that it is a table, its unknown
keys, its missing keys, then each value's type, unit and range - in this one place, every problem the
project's one-line :class:`~flexshaft.ModelError` naming the file, the table, the key, the value with
its unit and what is valid. What depends on several keys at once (a ramp needs its end speed, a shaft
its stiffness or its segments) stays with the reader of that file.

:func:`markdown` renders a table as the documentation's key reference (``tools/schema_docs.py`` writes
the site's file-format pages from it, and a test holds them equal), so the documentation is the schema.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from dataclasses import dataclass

from ..errors import ModelError
from ..validation import Domain, check_choice, check_int, check_name, check_real
from .quantities import si_value

__all__ = [
    "Field",
    "Table",
    "REQUIRED",
    "read",
    "read_entries",
    "toml_file",
    "markdown",
    "one_of",
    "top_level",
]


class _Required:
    """The default of a key that must be given."""

    def __repr__(self) -> str:
        return "REQUIRED"


#: The default of a key the table must have.
REQUIRED = _Required()

#: The kinds of value a field holds (see :class:`Field`).
KINDS = ("number", "quantity", "integer", "name", "string", "bool", "choice", "table", "tables", "any")


@dataclass(frozen=True)
class Field:
    """One key of a table.

    Parameters
    ----------
    key : str
        The key as the file writes it.
    kind : str
        ``"number"``: a finite number in ``domain`` (its unit converted); ``"quantity"``: a number with
        its unit converted to SI, its range checked by what it builds; ``"integer"``: a whole number in
        ``count``; ``"name"``: a non-empty string on one line; ``"string"``: any string; ``"bool"``;
        ``"choice"``: one of ``choices``; ``"table"``: an inline table (read by ``table`` when given);
        ``"tables"``: an array of tables (each read by ``table``); ``"any"``: checked by ``check``
        alone.
    help : str
        What it means, for the documentation's file reference (markdown).
    domain : Domain, optional
        For ``"number"``: its bounds and SI unit.
    unit : str
        For ``"quantity"`` (and ``"number"`` without a domain): its SI unit as the reference writes it
        (``"N·m/rad"``), ``""`` if none.
    count : (int, int or None)
        For ``"integer"``: the smallest and largest value.
    choices : tuple of str
        For ``"choice"``.
    default : object
        Its value when absent; :data:`REQUIRED` when it must be given; None: absent means not set.
    missing : str
        The message when a required key is absent.
    expects : str
        What is valid when it is absent (a required key's error) and, for the reference, how it is
        written when its kind does not say (``{modes = n} or {cutoff_hz = f}``).
    table : Table, optional
        For ``"table"`` and ``"tables"``: the schema of the nested table(s).
    check : callable, optional
        ``check(value, key) -> value``: what the kind does not say (a list of names, a fraction
        ``"1/97"``); runs after the kind's own check, on the converted value.
    shown_default : str
        The default as the reference shows it, when ``repr(default)`` is not it (``"file stem"``).
    shown_type : str
        How the reference writes the value, when its kind and ``expects`` do not say it.
    """

    key: str
    kind: str = "number"
    help: str = ""
    domain: Domain | None = None
    unit: str = ""
    count: tuple = (1, None)
    choices: tuple = ()
    default: object = None
    missing: str = "missing key"
    expects: str = ""
    table: Table | None = None
    check: Callable | None = None
    shown_default: str = ""
    shown_type: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"{self.key}: kind {self.kind!r} is not one of {KINDS}")

    @property
    def si_unit(self) -> str:
        """The unit a string value is converted to (``""``: none)."""
        return self.domain.unit if self.domain is not None else self.unit

    @property
    def absent(self) -> str | None:
        """What is valid, for the error when the key is required and absent."""
        if self.expects or self.kind not in ("number", "quantity"):
            return self.expects or None
        return f"a number in {self.si_unit}" if self.si_unit else "a number"

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def value(self, value: object, key: str) -> object:
        """``value`` checked by this field's kind (and ``check``), its unit converted; ``key`` is the
        name messages give it (``"segments[2].od"`` inside a nested table)."""
        kind = self.kind
        if kind in ("number", "quantity"):
            value = si_value(value, key, self.si_unit)
            if kind == "number":
                value = self.domain.check(value, key) if self.domain else check_real(value, key, self.unit)
        elif kind == "integer":
            value = check_int(value, key, lo=self.count[0], hi=self.count[1])
        elif kind == "name":
            value = check_name(value, key)
        elif kind == "string" and not isinstance(value, str):
            raise ModelError("must be a string", field=key, value=value, has_value=True, valid=self.expects)
        elif kind == "bool" and not isinstance(value, bool):
            raise ModelError(
                "is not true or false", field=key, value=value, has_value=True, valid="true or false"
            )
        elif kind == "choice":
            value = check_choice(value, key, self.choices)
        elif kind == "table":
            if self.table is not None:
                value = read(value, self.table, field=key, prefix=f"{key}.")
            elif not isinstance(value, dict):
                raise _not_table(key, value, self.expects)
        elif kind == "tables":
            value = read_entries(value, key)
            if self.table is not None:
                value = [read(v, self.table, field=key, prefix=f"{key}[{i}].") for i, v in enumerate(value)]
        return self.check(value, key) if self.check is not None else value

    @property
    def written(self) -> str:
        """How the value is written, for the reference: ``"N·m/rad, > 0"``, ``"`"a"` \\| `"b"`"``."""
        if self.shown_type:
            return self.shown_type
        if self.expects:
            return f"`{self.expects}`" if self.expects[:1] in "{[" else self.expects
        if self.kind == "number":
            bounds = self.domain.bounds if self.domain else ""
            return ", ".join(p for p in (self.si_unit or "number", bounds) if p)
        if self.kind == "quantity":
            return self.unit or "number"
        if self.kind == "integer":
            lo, hi = self.count
            return f"integer >= {lo}" + (f" and <= {hi}" if hi is not None else "")
        if self.kind == "choice":
            return " \\| ".join(f'`"{c}"`' for c in self.choices)
        return {"name": "string", "bool": "`true` \\| `false`", "tables": "array of tables"}.get(
            self.kind, self.kind
        )

    @property
    def shown(self) -> str:
        """The default, for the reference."""
        if self.shown_default:
            return self.shown_default
        if self.required:
            return "required"
        if self.default is None:
            return "none"
        if isinstance(self.default, bool):
            return f"`{str(self.default).lower()}`"
        if isinstance(self.default, str):
            return f'`"{self.default}"`'
        if isinstance(self.default, tuple):
            return "`[" + ", ".join(_number(v) for v in self.default) + "]`"
        return f"`{_number(self.default)}`"


def _number(v) -> str:
    return f'"{v}"' if isinstance(v, str) else f"{v:g}" if isinstance(v, float) else str(v)


@dataclass(frozen=True)
class Table:
    """The keys of one table.

    Parameters
    ----------
    name : str
        How messages and the reference name it: ``"[model]"``, ``"[[chain]]"``, ``"[materials.NAME]"``.
    fields : tuple of Field
    help : str
        What it is, for the reference.
    forms : str
        What is valid for an unknown key or a value that is no table, when "one of" its keys does not
        say it (``{modes = n} or {cutoff_hz = f} (Hz)``).
    unknown : str
        The message for a key it does not have (``"unknown table"`` at a file's top).
    """

    name: str
    fields: tuple[Field, ...]
    help: str = ""
    forms: str = ""
    unknown: str = "unknown key"

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(f.key for f in self.fields)

    def field(self, key: str) -> Field:
        for f in self.fields:
            if f.key == key:
                return f
        raise KeyError(key)

    @property
    def valid_keys(self) -> str:
        return self.forms or one_of(self.keys)

    def defaults(self) -> dict:
        """Every key with a default (not required, not None), and that default."""
        return {f.key: f.default for f in self.fields if f.default is not None and not f.required}


def top_level(name: str, kinds: dict[str, str], **table) -> Table:
    """A file's top level: each of its tables (key -> kind: ``"table"``, ``"tables"``, or ``"any"`` for
    what its reader checks), read one by one by their own :class:`Table`."""
    return Table(name, tuple(Field(key, kind=kind) for key, kind in kinds.items()), **table)


def one_of(keys) -> str:
    """``"one of a, b, c"``: what an unknown key's error says is valid."""
    return "one of " + ", ".join(keys)


def _not_table(field: str, value, valid: str = "") -> ModelError:
    return ModelError("must be a table", field=field, value=value, has_value=True, valid=valid or None)


def read(
    data,
    table: Table,
    *,
    file: str | None = None,
    where: str | None = None,
    field: str | None = None,
    prefix: str = "",
    fill: bool = False,
) -> dict:
    """One table of a file, checked: its keys' values (units converted to SI), in the table's order.

    Parameters
    ----------
    data : object
        The table as parsed.
    table : Table
        Its schema.
    file, where : str, optional
        The file and the table's place in it (``"[[chain]] #2 'part 1'"``), put on every error.
    field : str, optional
        The key the table is the value of (``"reduce"``), for the error when it is no table.
    prefix : str
        Put before each key in messages (``"reduce."``, ``"segments[2]."``): an inline table's keys.
    fill : bool
        Also give the absent keys' defaults (not those of default None).

    Returns
    -------
    dict
        The given keys' checked values (and with ``fill`` the defaults of the others).

    Raises
    ------
    ModelError
        It is not a table, has a key the schema does not know (the first, in the file's order) or
        lacks a required one (the first, in the schema's order), or a value is not what its field
        says - naming ``file``, ``where``, the key, the value and what is valid.
    """
    try:
        if not isinstance(data, dict):
            raise _not_table(field or table.name, data, table.forms)
        for key in data:
            if key not in table.keys:
                raise ModelError(table.unknown, field=prefix + key, valid=table.valid_keys)
        for f in table.fields:
            if f.required and f.key not in data:
                raise ModelError(f.missing, field=prefix + f.key, valid=f.absent)
        out = {f.key: f.value(data[f.key], prefix + f.key) for f in table.fields if f.key in data}
    except ModelError as err:
        raise err.located(file=file, component=where) from None
    if fill:
        out = table.defaults() | out
        out = {k: out[k] for k in table.keys if k in out}
    return out


def read_entries(value, key: str, *, file: str | None = None, most: int | None = None) -> list:
    """The entries of an array of tables ``[[key]]`` as parsed (absent: none), each to be read by
    :func:`read`; refused when it is not an array or has more than ``most`` entries."""
    if value is None:
        return []
    if not isinstance(value, list) or (most is not None and len(value) > most):
        raise ModelError(
            f"must be an array of tables ([[{key}]])",
            file=file,
            field=key,
            value=value,
            has_value=True,
            valid=f"at most {most} [[{key}]] tables" if most is not None else None,
        )
    return value


def toml_file(text: str, source: str, what: str) -> dict:
    """A TOML file's document, its nesting refused before the parser recurses
    (:func:`flexshaft.system.nesting.toml_document`); bad TOML is one ModelError naming ``source``.

    ``what`` says what the file should be (``"a TOML study file"``)."""
    from ..system.nesting import toml_document

    try:
        return toml_document(text, source)
    except tomllib.TOMLDecodeError as err:
        raise ModelError(f"not valid TOML ({err})", file=source, valid=what) from None


def markdown(table: Table, *, skip: tuple[str, ...] = ()) -> str:
    """``table``'s reference: a markdown table of key, how it is written (type / unit, range), default
    and meaning, one row a key (those in ``skip`` left out)."""
    rows = ["| key | type / unit | default | meaning |", "|---|---|---|---|"]
    for f in table.fields:
        if f.key in skip:
            continue
        rows.append(f"| `{f.key}` | {f.written} | {f.shown} | {f.help} |")
    return "\n".join(rows)
