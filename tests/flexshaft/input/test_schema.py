"""The one schema layer of the TOML files: what a field declares is what is checked, in one place, and
the documentation's file references are the schemas rendered (they never drift)."""

from __future__ import annotations

import importlib.util

import pytest

from flexshaft.errors import ModelError
from flexshaft.input.schema import REQUIRED, Field, Table, markdown, read
from flexshaft.validation import STIFFNESS
from tests.conftest import ROOT

INNER = Table("inner", (Field("cutoff_hz", kind="quantity", unit="Hz"),), forms="{cutoff_hz = f}")
T = Table(
    "[t]",
    (
        Field("k", domain=STIFFNESS, default=REQUIRED, help="a spring"),
        Field("n", kind="integer", count=(1, 10), default=3),
        Field("kind", kind="choice", choices=("a", "b")),
        Field("inner", kind="table", table=INNER),
    ),
)


def _error(data) -> str:
    with pytest.raises(ModelError) as err:
        read(data, T, file="f.toml", where="[t]")
    return str(err.value)


def test_values_are_read_in_si_with_their_defaults():
    got = read({"k": "307.9 kN*m/rad", "inner": {"cutoff_hz": "2 kHz"}}, T, fill=True)
    assert got == {"k": pytest.approx(307_900.0), "n": 3, "inner": {"cutoff_hz": pytest.approx(2000.0)}}
    assert read({"k": 1.0}, T) == {"k": 1.0}  # without fill, the keys given


@pytest.mark.parametrize(
    "data, message",
    [
        ({"k": 1.0, "colour": 1}, "f.toml: [t]: colour: unknown key; valid: one of k, n, kind, inner"),
        ({"n": 2}, "f.toml: [t]: k: missing key; valid: a number in N·m/rad"),
        ({"k": -1.0}, "f.toml: [t]: k = -1.0 N·m/rad: out of range; valid: a finite number > 0 (N·m/rad)"),
        ({"k": "1 kg"}, "f.toml: [t]: k = '1 kg': has the unit kilogram, which is not a N·m/rad; "),
        ({"k": 1.0, "n": 2.0}, "f.toml: [t]: n = 2.0: not an integer; valid: an integer >= 1 and <= 10"),
        ({"k": 1.0, "kind": "c"}, "f.toml: [t]: kind = 'c': unknown option; valid: one of 'a', 'b'"),
        ({"k": 1.0, "inner": 3}, "f.toml: [t]: inner = 3: must be a table; valid: {cutoff_hz = f}"),
        ({"k": 1.0, "inner": {"x": 1}}, "f.toml: [t]: inner.x: unknown key; valid: {cutoff_hz = f}"),
        ([1], "f.toml: [t]: [t] = [1]: must be a table"),
    ],
)
def test_each_problem_is_one_line_naming_file_table_key_value_and_what_is_valid(data, message):
    assert _error(data).startswith(message)


def test_the_reference_renders_unit_range_default_and_help():
    rows = markdown(T).splitlines()
    assert rows[2] == "| `k` | N·m/rad, > 0 | required | a spring |"
    assert rows[3] == "| `n` | integer >= 1 and <= 10 | `3` |  |"


def _schema_docs():
    spec = importlib.util.spec_from_file_location("schema_docs", ROOT / "tools" / "schema_docs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_file_references_of_the_docs_are_the_schemas():
    """docs/reference/{model,study,targets}-file.md are what tools/schema_docs.py renders now."""
    docs = _schema_docs()
    for path, text in docs.pages().items():
        assert path.read_text(encoding="utf-8") == text, (
            f"{path.name} differs from the schemas: run python tools/schema_docs.py --write"
        )


def test_every_key_a_reader_knows_is_documented():
    """Each component type's keys, the model file's tables and the study's scenario options are in the
    model-file reference as the readers accept them (the reference lists keys, the readers take them
    from the same tables)."""
    from flexshaft.input.modelschema import COMPONENTS
    from flexshaft.study.studyschema import SCENARIO_KEYS, SIMULATE

    text = (ROOT / "docs" / "reference" / "model-file.md").read_text(encoding="utf-8")
    for table in COMPONENTS.values():
        for key in table.keys:
            if key not in ("name", "type"):
                assert f"| `{key}` |" in text, key
    assert set(SCENARIO_KEYS) <= set(SIMULATE.keys)
