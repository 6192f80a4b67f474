"""Fuzzing model files: any document is a model whose modes pass the numerical guards, or one ModelError.

Hypothesis builds model files from the model-file vocabulary with wrong types, extreme and
non-finite numbers, unknown keys, code references and missing parts mixed in. The only outcomes
allowed are a ModalResult whose every mode is finite (the guards inside modal_analysis check the
residuals) or a ModelError of one line. The seed is fixed (derandomize); the README's test
command runs FLEXSHAFT_FUZZ cases (default 300), CI's slow step runs 3000, and a longer run is
``FLEXSHAFT_FUZZ=50000 .venv/bin/python -m pytest tests/test_fuzz.py -m slow``.
"""

from __future__ import annotations

import json
import math
import os
import string

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import flexshaft as fs
from flexshaft.analysis.modal import default_count

CASES = int(os.environ.get("FLEXSHAFT_FUZZ", "300"))

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=1e-3, max_value=1e7),  # mostly plausible values, so that models get built
    st.floats(min_value=1e-3, max_value=1e7),
    st.integers(min_value=-5, max_value=10**6),
    st.sampled_from([0.0, -1.0, 1e-30, 1e308, 1e-320]),
)
words = st.text(alphabet=string.ascii_letters + string.digits + " _-:./", max_size=8)
junk = st.one_of(words, st.booleans(), st.lists(st.integers(), max_size=3))
value = st.one_of(numbers, numbers, numbers, numbers, junk)


def mostly(good, bad):
    """``good`` six times in seven: enough valid models reach the solver, enough bad ones the checks."""
    return st.one_of(*([good] * 6), bad)


component = st.fixed_dictionaries(
    {
        "name": mostly(st.sampled_from(["motor", "p", "c", "gen"]), junk),
        "type": mostly(
            st.sampled_from(["rigid", "shaft", "shaft", "coupling", "gear"]), st.one_of(junk, st.just("cad"))
        ),
    },
    optional={
        "inertia": value,
        "stiffness": value,
        "damping": value,
        "damping_ratio": st.one_of(st.floats(min_value=0, max_value=0.2), value),
        "elements": st.one_of(st.integers(min_value=-1, max_value=40), junk),
        "material": mostly(st.just("steel"), junk),
        "segments": st.one_of(
            st.lists(
                st.fixed_dictionaries({"length": numbers, "od": numbers}, optional={"id": numbers}),
                min_size=0,
                max_size=3,
            ),
            junk,
        ),
        "reduce": mostly(st.fixed_dictionaries({"modes": st.integers(-1, 6)}), junk),
        "geometry": st.sampled_from(["os:system", "evil:part", "missing.step", "no:"]),  # never runs
        "stations": st.one_of(st.dictionaries(st.sampled_from(["j", "k"]), numbers, max_size=2), junk),
        "ratio": st.one_of(numbers, st.sampled_from(["1/97", "3/0", "x/y", "2"])),
        "mass": value,
        "diametral_inertia": value,
        "inertia_in": value,
        "inertia_out": value,
        "mesh_stiffness": value,
        "mesh_damping": value,
        "bogus_key": value,
    },
)
model_table = st.fixed_dictionaries(
    {},
    optional={
        "name": st.one_of(words, junk),
        "inertia_model": mostly(st.sampled_from(["consistent", "lumped"]), junk),
        "dofs": mostly(st.sampled_from(["torsion", "torsion", "full"]), junk),
        "rayleigh": st.one_of(st.fixed_dictionaries({"alpha": numbers, "beta": numbers}), junk),
    },
)
document = st.fixed_dictionaries(
    {"chain": st.lists(component, min_size=0, max_size=5)},
    optional={
        "model": model_table,
        "bearings": st.lists(st.fixed_dictionaries({"station": words, "stiffness": numbers}), max_size=2),
    },
)


# Well-formed chains of any numbers (extreme, tiny, huge): these reach the assembly and the solver.
plausible = st.floats(min_value=1e-6, max_value=1e9)
sizes = st.one_of(plausible, plausible, plausible, numbers)
chain_of_numbers = st.lists(
    st.one_of(
        st.builds(lambda j: {"type": "rigid", "inertia": j}, sizes),
        st.builds(
            lambda k, j, c, z, n: {
                "type": "shaft",
                "stiffness": k,
                "inertia": j,
                "damping": c,
                "damping_ratio": z,
                "elements": n,
            },
            sizes,
            sizes,
            st.one_of(st.just(0.0), sizes),
            st.one_of(st.just(0.0), st.floats(min_value=0.0, max_value=0.5)),
            st.integers(min_value=1, max_value=30),
        ),
        st.builds(lambda k, j: {"type": "coupling", "stiffness": k, "inertia": j}, sizes, sizes),
        st.builds(
            lambda n, a, b, k: (
                {"type": "gear", "ratio": n, "inertia_in": a, "inertia_out": b}
                | ({} if k is None else {"mesh_stiffness": k})
            ),
            st.one_of(st.floats(min_value=1e-3, max_value=1e3), numbers),
            st.one_of(st.just(0.0), sizes),
            st.one_of(st.just(0.0), sizes),
            st.one_of(st.none(), sizes),
        ),
    ),
    min_size=1,
    max_size=6,
)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string accepts JSON's escapes
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(doc: dict) -> str:
    """The document as TOML; the chain's plausible names made distinct (duplicates are tested elsewhere)."""
    for i, entry in enumerate(doc.get("chain", [])):
        if entry.get("name") in ("motor", "p", "c", "gen"):
            entry["name"] = f"{entry['name']} {i}"
    lines = []
    if "model" in doc:
        lines.append("[model]")
        lines += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in doc["model"].items()]
    for table in ("chain", "bearings"):
        for entry in doc.get(table, []):
            lines.append(f"[[{table}]]")
            lines += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in entry.items()]
    return "\n".join(lines) + "\n"


def _outcome(text: str) -> None:
    try:
        d = fs.loads_model(text, source="fuzz.toml")
        r = fs.modal_analysis(d)
    except fs.ModelError as err:
        assert "\n" not in str(err)
        return
    assert np.all(np.isfinite(r.frequencies_hz)) and np.all(np.isfinite(r.damping_ratios))
    assert r.count == default_count(r.model)  # the modes asked for (by default), none missing


@settings(
    max_examples=CASES,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(document)
def test_any_model_file_is_a_result_or_one_error(doc):
    _outcome(to_toml(doc))


@settings(
    max_examples=CASES,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(chain_of_numbers, st.sampled_from(["consistent", "lumped"]))
def test_any_numbers_give_guarded_modes_or_one_error(chain, inertia_model):
    entries = [{"name": f"c{i}", **e} for i, e in enumerate(chain)]
    _outcome(to_toml({"model": {"inertia_model": inertia_model}, "chain": entries}))


@pytest.mark.slow
def test_a_long_fuzz_run():
    # CI's slow step: ten times the default budget (or FLEXSHAFT_FUZZ's), same guarantees.
    @settings(
        max_examples=max(CASES, 3000),
        derandomize=True,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(document, chain_of_numbers)
    def run(doc, chain):
        _outcome(to_toml(doc))
        _outcome(to_toml({"chain": [{"name": f"c{i}", **e} for i, e in enumerate(chain)]}))

    run()


# --- section-table CSVs and command lines --------------------------------------------------------


def _csv_text() -> str:
    from flexshaft.sections import table_from_segments, tables_to_csv

    return tables_to_csv([table_from_segments([(0.3, 0.1, 0.04), (0.4, 0.16)], name="p")])


@settings(max_examples=CASES, derandomize=True, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 10_000), st.sampled_from(list(',\n#x-1.e9 "nan'))), max_size=6))
def test_a_damaged_section_csv_is_tables_or_one_error(edits):
    from flexshaft.sections import tables_from_csv

    text = list(_csv_text())
    for pos, ch in edits:
        text[pos % len(text)] = ch
    try:
        tables = tables_from_csv("".join(text))
    except fs.ModelError as err:
        assert "\n" not in str(err)
        return
    for t in tables:  # what is accepted is a valid table (its constructor checks every column)
        assert np.all(np.isfinite(t.x)) and np.all(np.diff(t.x) > 0)


ARGS = st.lists(
    st.sampled_from(
        [
            "modes",
            "twist",
            "reduce",
            "sections",
            "demo",
            "--json",
            "--count",
            "0",
            "3",
            "-5",
            "--force",
            "--torque",
            "1e308",
            "nan",
            "--part",
            "part 1",
            "motor",
            "--modes",
            "--cutoff",
            "--clamp",
            "--load",
            "--target",
            "part 1=1e6",
            "--inertia",
            "lumped",
            "--merge",
            "--unit",
            "mm",
            "--allow-code",
            "examples/customer1.toml",
            "examples/customer1_flex.toml",
            "missing.toml",
            "-o",
            "out.json",
            "out.npz",
            "out.txt",
            "--no-residual",
            "--damping-ratio",
            "2",
        ]
    ),
    max_size=7,
)


@settings(max_examples=CASES, derandomize=True, deadline=None)
@given(ARGS)
def test_any_command_line_exits_0_1_or_2_with_no_traceback(tmp_path_factory, args):
    import contextlib
    import io
    from pathlib import Path

    from flexshaft.cli import main
    from tests.conftest import ROOT

    work = tmp_path_factory.mktemp("cli")

    def where(a: str) -> str:
        return str(ROOT / a) if a.startswith("examples/") else str(work / a) if a.startswith("out") else a

    argv = [where(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    assert code in (0, 1, 2), (argv, code)
    if code != 0:
        assert out.getvalue() == "" and len(err.getvalue().strip().splitlines()) <= 2, (argv, err.getvalue())
    assert "Traceback" not in err.getvalue()
    assert not list(Path(work).glob(".*.tmp"))


# --- calibration targets files ---------------------------------------------------------------------


def _damaged(good, damage):
    """``good`` with, one time in seven, keys from ``damage`` mixed in: most documents stay valid enough to
    reach the optimiser, the rest exercise the reader's checks."""
    return st.builds(lambda g, extra: {**g, **extra}, good, mostly(st.just({}), damage))


target_entry = _damaged(
    st.fixed_dictionaries(
        {
            "mode": mostly(st.integers(1, 4), st.one_of(st.integers(-2, 8), junk)),
            "frequency_hz": mostly(st.floats(min_value=1.0, max_value=600.0), value),
        },
        optional={"tolerance": st.floats(min_value=1e-4, max_value=0.2)},
    ),
    st.fixed_dictionaries(
        {},
        optional={
            "ratio_to": st.one_of(st.integers(-1, 6), junk),
            "ratio": value,
            "tolerance": value,
            "shape": st.one_of(st.lists(numbers, max_size=6), junk),
            "bogus": value,
        },
    ),
)
parameter_entry = _damaged(
    st.fixed_dictionaries(
        {
            "name": mostly(
                st.sampled_from(["part 3.stiffness", "motor.inertia", "generator.inertia", "part 1.damping"]),
                st.one_of(junk, st.just("x.y")),
            ),
            "percent": mostly(st.floats(min_value=0.5, max_value=50.0), value),
        }
    ),
    st.fixed_dictionaries(
        {},
        optional={"bounds": st.one_of(st.lists(numbers, max_size=3), junk), "fixed": value, "bogus": value},
    ),
)
targets_document = _damaged(
    st.fixed_dictionaries(
        {
            "target": mostly(
                st.lists(target_entry, min_size=1, max_size=3), st.lists(target_entry, max_size=0)
            ),
            "parameter": mostly(
                st.lists(parameter_entry, min_size=1, max_size=3), st.lists(parameter_entry, max_size=0)
            ),
        }
    ),
    st.fixed_dictionaries({"options": st.fixed_dictionaries({}, optional={"starts": value, "seed": value})}),
)


@settings(
    max_examples=max(CASES // 3, 50),
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(targets_document)
def test_any_targets_file_is_a_calibration_or_one_error(tmp_path_factory, doc):
    # Read, then calibrate Customer 1 with a few evaluations: a result, or one ModelError line.
    try:
        res = _calibrated(doc, tmp_path_factory.mktemp("t") / "t.toml")
    except fs.ModelError as err:
        assert "\n" not in str(err)
        return
    assert np.all(np.isfinite(res.tuned)) and np.all(np.isfinite(res.values))


CUSTOMER1 = fs.load_model(__import__("pathlib").Path(__file__).parent.parent / "examples" / "customer1.toml")


def _calibrated(doc: dict, path):
    """Write ``doc`` as a targets file, read it and calibrate Customer 1 with a few evaluations."""
    from flexshaft.analysis.calibrate import calibrate
    from flexshaft.io.tunedfile import read_targets

    lines = []
    if "options" in doc:
        lines += ["[options]"] + [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in doc["options"].items()]
    for key in ("target", "parameter"):
        for entry in doc.get(key, []):
            lines += [f"[[{key}]]"] + [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in entry.items()]
    path.write_text("\n".join(lines) + "\n")
    stage = read_targets(path).stages[0]
    return calibrate(CUSTOMER1, stage.targets, stage.parameters, starts=1, max_evaluations=3)


EDGES = [
    # Valid files at the edges of every accepted range reach the optimiser and give finite numbers.
    # (Hypothesis explores the refusals; it does not sample the valid core often enough to rely on.)
    {
        "target": [{"mode": 1, "frequency_hz": 1e-6}],
        "parameter": [{"name": "part 3.stiffness", "percent": 1e-6}],
    },
    {
        "target": [{"mode": 2, "frequency_hz": 1e9, "tolerance": 1e-9}],
        "parameter": [{"name": "motor.inertia", "percent": 99.0}],
    },
    {
        "target": [{"mode": 2, "ratio_to": 1, "ratio": 1e-6}],
        "parameter": [{"name": "generator.inertia", "bounds": [1.0, 1e6]}],
    },
    {
        "target": [{"mode": 1, "frequency_hz": 11.0}, {"mode": 1, "frequency_hz": 12.0, "tolerance": 1.0}],
        "parameter": [
            {"name": "part 3.stiffness", "percent": 50.0},
            {"name": "motor.inertia", "fixed": 1e-3},
        ],
        "options": {"starts": 2, "seed": 0},
    },
]


@pytest.mark.parametrize("doc", EDGES, ids=[f"edge {i}" for i in range(len(EDGES))])
def test_valid_targets_files_at_the_range_edges_reach_the_optimiser(tmp_path, doc):
    res = _calibrated(doc, tmp_path / "t.toml")
    assert np.all(np.isfinite(res.tuned)) and np.all(np.isfinite(res.values)) and np.isfinite(res.cost)
