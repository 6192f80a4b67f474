"""Fuzzing model files: any document is a model whose modes pass the numerical guards, or one ModelError.

Hypothesis builds model files from the model-file vocabulary with wrong types, extreme and
non-finite numbers, unknown keys, code references and missing parts mixed in. The only outcomes
allowed are a ModalResult whose every mode is finite (the guards inside modal_analysis check the
residuals) or a ModelError of one line. The seed is fixed (derandomize); the test command
(docs/getting-started/01-install.md) runs FLEXSHAFT_FUZZ cases (default 300), CI's slow step runs
3000, and a longer run is
``FLEXSHAFT_FUZZ=50000 .venv/bin/python -m pytest tests/test_fuzz.py -m slow``.
"""

from __future__ import annotations

import json
import math
import os
import shlex
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
            "--max-hz",
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
            "--at",
            "--clamp",
            "--mesh-check",
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
    assert code in (0, 2), (argv, code)
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
    from flexshaft.study.tunedfile import read_targets

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
        # two targets on one mode's frequency are refused (one contradicts or repeats the other)
        "target": [{"mode": 1, "frequency_hz": 11.0}, {"mode": 2, "frequency_hz": 95.0, "tolerance": 1.0}],
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


# --- the analysis commands' options: frf, simulate, spectrum, campbell, sensitivity, calibrate ----------
#
# Each command's own options with values mostly valid (so that runs get through to the numerics) and
# otherwise hostile: non-finite, negative, zero, huge and subnormal numbers, huge counts, empty strings,
# power towers a unit parser could evaluate, wrong file suffixes, outputs naming an input. The model is
# small (a rigid motor, a 3-element shaft, a rigid generator: 4 DOFs) and the runs short, so a case costs
# tens of milliseconds. The only outcomes allowed: exit 0 with nothing on stderr, or exit 2 with one
# stderr line and nothing on stdout - never a traceback, never a warning, no file written beside a
# failed run, no input changed, no temporary file left. FLEXSHAFT_FUZZ // 6 cases per command in the
# test command (50 by default, ~12 s for the six), ten times as many in the slow step.
#
# A case is built from a seed hypothesis draws, with Python's random: hypothesis leans towards the ends
# of ranges and the first of a choice, which made nearly every option of every case both present and
# hostile; here each option is present and each value hostile with the probability its entry says.

SMALL_MODEL = """[model]
name = "small"

[[chain]]
name = "motor"
type = "rigid"
inertia = 2.0

[[chain]]
name = "shaft"
type = "shaft"
stiffness = 5e4
inertia = 0.05
damping_ratio = 0.01
elements = 3

[[chain]]
name = "gen"
type = "rigid"
inertia = 1.0
"""
#: The small model's parameters and modes (0 rigid-body; 43.4, 527, 1171 Hz).
SMALL_VALUES = {"shaft.stiffness": 5e4, "motor.inertia": 2.0, "gen.inertia": 1.0, "shaft.inertia": 0.05}
#: A case's wall-clock budget, s: the slowest valid run here (a ramp with its gains tuned, a plot) takes
#: ~1 s; anything that needs more than this on a 4-DOF model is a missing ceiling, and fails.
CASE_SECONDS = 20.0
OPTION_CASES = max(CASES // 6, 10)
#: How often an option that is present gets a hostile value: with 3-6 options a case, about a third
#: of the cases carry one.
HOSTILE = 0.08


def _signals_csv() -> str:
    """0.5 s at 1 kHz: a torque ringing at the model's first mode (43.4 Hz) and a speed ramp."""
    t = np.arange(500) / 1000.0
    torque = 100.0 * np.exp(-2.0 * t) * np.sin(2 * np.pi * 43.4 * t) + 5.0
    speed = 600.0 + 600.0 * t
    rows = ["time [s],torque [N·m],speed [rpm]"]
    rows += [f"{a!r},{b!r},{c!r}" for a, b, c in zip(t.tolist(), torque.tolist(), speed.tolist())]
    return "\n".join(rows) + "\n"


BAD_NUMBERS = ["nan", "inf", "-inf", "-1", "0", "-0", "1e308", "-1e308", "1e-320", "", " ", "9**9**9"]
BAD_NUMBERS += ["1e999", "x", "1,2", "0x10", "½", "1e3 Hz", "5e-324"]
BAD_COUNTS = ["0", "-1", "1000000000", "99999999999999999999", "2.5", "", "nan", "1e3", "9**9**9"]
BAD_WORDS = ["", " ", "nowhere", "motor\n", "9**9**9", "x" * 300, "m.toml"]
#: Outputs: the wrong suffix, none, an input, a missing folder, the folder itself.
BAD_FILES = ["out.npz", "out.txt", "out", "out.CSV.gz", "m.toml", "s.csv", "t.toml", "sub/out.csv", "."]
BAD_FILES.append("out/")


def _number(lo: float, hi: float):
    return (lambda r: f"{r.uniform(lo, hi):.6g}"), BAD_NUMBERS


def _count(lo: int, hi: int):
    return (lambda r: str(r.randint(lo, hi))), BAD_COUNTS


def _word(*good, bad=()):
    return (lambda r: r.choice(good)), [*BAD_WORDS, *bad]


def _file(*good, bad=()):
    return (lambda r: r.choice(good)), [*BAD_FILES, *bad]


def _pair(lo: tuple, hi: tuple, bad):
    return (lambda r: f"{r.uniform(*lo):.6g}:{r.uniform(*hi):.6g}"), bad


FLAG = (None, [])
SCENARIOS = ("step", "ramp", "coast", "sine", "csv")
PLOT = _file("p.png", "p.svg", "p.pdf", bad=["p.txt", "p.PNG.txt"])
STATIONS = ("motor", "gen")
ORDERS = _word("1,2,6", "1", "0.5,1.5,3", bad=["nan", "-1", "0", ",", "1,,2", "inf", "1e308", "1e-320"])
UNITS = _word(
    "torque=kNm",
    "time=ms",
    "speed=rpm",
    bad=["torque=9**9**9 N*m", "torque=", "=", "torque=kg", "time=1e308 s", "torque=N·m**99", "time=kg*m^2"],
)
COMMON = [("--threads", _word("1", bad=["0", "-1", "x", "2"]), 0.08), ("--no-cache", FLAG, 0.08)]

# Per command: its positional arguments, then (option, (make a good value, hostile values) or FLAG, how
# often it is present); a repeatable option appears twice.
COMMANDS = {
    "frf": (
        ["m.toml"],
        [
            ("--at", _word(*STATIONS, bad=["shaft", "speed:gen"]), 1.0),
            ("--measure", _word("speed:gen", "angle:motor", "torque:shaft", bad=["torque:motor"]), 1.0),
            ("--measure", _word("angle:gen", "speed:motor"), 0.15),
            ("--at", _word(*STATIONS), 0.02),
            ("--from", _number(0.0, 10.0), 0.3),
            ("--to", _number(20.0, 2000.0), 0.3),
            ("--points", _count(2, 300), 0.3),
            ("--max-hz", _number(50.0, 2000.0), 0.2),
            ("--speed", _number(0.0, 3000.0), 0.2),
            ("--json", FLAG, 0.2),
            ("-o", _file("out.csv", "out.json"), 0.25),
            ("--force", FLAG, 0.08),
            ("--plot", PLOT, 0.08),
        ],
    ),
    "simulate": (
        ["m.toml"],
        [  # the fourth entry: the scenarios an option belongs to (elsewhere it is present 1 time in 30)
            ("--measure", _word("speed:gen", "angle:motor", "torque:shaft"), 1.0),
            ("--measure", _word("speed:motor", "angle:gen"), 0.15),
            ("--measure", _word("control:torque", "control:setpoint"), 0.3, "ramp"),
            ("--rate", _number(200.0, 2000.0), 0.3),
            ("--duration", _number(0.01, 0.3), 0.9),
            ("--torque", _number(-100.0, 100.0), 0.6, "step sine coast"),
            ("--at", _word(*STATIONS), 0.15, "step sine coast csv"),
            ("--step-time", _number(0.0, 0.1), 0.3, "step"),
            ("--frequency", _number(1.0, 100.0), 1.0, "sine"),
            ("--speed", _number(0.0, 1000.0), 0.5, "coast ramp"),
            ("--end-speed", _number(0.0, 1500.0), 1.0, "ramp"),
            ("--ramp-time", _number(0.01, 0.2), 1.0, "ramp"),
            ("--load-torque", _number(-50.0, 50.0), 0.15, "step sine csv ramp"),
            ("--load-at", _word(*STATIONS), 0.1),
            ("--kp", _number(1.0, 500.0), 0.2, "ramp"),
            ("--ki", _number(1.0, 5000.0), 0.2, "ramp"),
            ("--bandwidth", _number(1.0, 20.0), 0.2, "ramp"),
            ("--tau", _number(0.0, 0.01), 0.2, "ramp"),
            ("--torque-limit", _number(10.0, 5000.0), 0.2, "ramp"),
            ("--feedback", _word("speed:motor", "speed:gen", bad=["angle:gen"]), 0.2, "ramp"),
            ("--series", _word("s.csv", bad=["nowhere.csv", "t.toml"]), 1.0, "csv"),
            ("--column", _word("torque", "torque [N·m]", bad=["speed", "time"]), 1.0, "csv"),
            ("--time-column", _word("time", bad=["torque"]), 0.2, "csv"),
            ("--unit", UNITS, 0.2, "csv"),
            ("--max-hz", _number(50.0, 2000.0), 0.15),
            ("-o", _file("out.csv"), 0.25),
            ("--force", FLAG, 0.08),
            ("--plot", PLOT, 0.05),
        ],
    ),
    "spectrum": (
        ["s.csv"],
        [
            ("--column", _word("torque", "speed", "torque [N·m]", bad=["time", "speed [rpm]x"]), 1.0),
            ("--time-column", _word("time", bad=["torque"]), 0.1),
            ("--unit", UNITS, 0.1),
            ("--window", _word("hann", "rect", "flattop", "exponential"), 0.3),
            ("--segment", _number(0.05, 0.5), 0.25),
            ("--decay", FLAG, 0.3),
            ("--peaks", _count(1, 20), 0.25),
            ("--speed-column", _word("speed", bad=["torque", "time"]), 0.25),
            ("--orders", ORDERS, 0.25),
            ("--model", _word("m.toml", bad=["s.csv", "nowhere.toml"]), 0.25),
            ("--json", FLAG, 0.2),
            ("-o", _file("out.csv", "out.json", "out.txt"), 0.2),
            ("--force", FLAG, 0.08),
            ("--plot", PLOT, 0.08),
            ("--spectrogram", FLAG, 0.1),
        ],
    ),
    "campbell": (
        ["m.toml"],
        [
            (
                "--speed",
                _pair(
                    (0.0, 1000.0),
                    (1000.0, 5000.0),
                    ["0:1e9", "nan:1", "5:1", "1", "", "0:inf", "-100:100", "0:0", "1e308:1e308", "9**9**9:1"]
                    + ["1e-320:1e-319", "0:1e-320"],
                ),
                0.5,
            ),
            ("--orders", ORDERS, 0.5),
            ("--reference", _word(*STATIONS, bad=["shaft"]), 0.25),
            ("--json", FLAG, 0.2),
            ("-o", _file("out.txt", "out.json"), 0.2),
            ("--force", FLAG, 0.08),
            ("--plot", PLOT, 0.08),
        ],
    ),
    "sensitivity": (
        ["m.toml"],
        [
            (
                "--param",
                _word(*SMALL_VALUES, "shaft.damping_ratio", bad=["x.y", "shaft.colour", "shaft.stiffness=1"]),
                0.5,
            ),
            ("--param", _word("shaft.damping", "gen.inertia", "shaft.stiffness"), 0.25),
            ("--modes", _word("1", "2", "3", bad=[*BAD_COUNTS, "4", "99"]), 0.5),
            ("--json", FLAG, 0.2),
            ("-o", _file("out.txt", "out.json"), 0.2),
            ("--force", FLAG, 0.08),
            ("--plot", PLOT, 0.08),
        ],
    ),
    "calibrate": (
        ["m.toml"],
        [
            ("--targets", _word("t.toml", bad=["s.csv", "nowhere.toml"]), 1.0),
            ("--starts", _count(1, 3), 0.25),
            ("--json", FLAG, 0.2),
            ("-o", _file("tuned.toml", bad=["tuned.json"]), 0.25),
            ("--force", FLAG, 0.08),
            ("--scheduler", _word("tcp://127.0.0.1:1"), 0.03),
        ],
    ),
}


def _value(r, make, bad) -> str:
    return r.choice(bad) if bad and r.random() < HOSTILE else make(r)


def _hostile_number(r):
    return r.choice([float("nan"), float("inf"), -1.0, 0.0, 1e308, 1e-320, -1e-320, 5e-324, 2.5])


def _small_targets(r) -> str:
    """A targets file for the small model (elastic modes 1 … 3: 43.4, 527, 1171 Hz): mostly a problem the
    optimiser solves in a few evaluations, sometimes a bad mode, ratio, shape, bound or name."""

    def odd(good, bad):
        return r.choice(bad) if r.random() < HOSTILE else good

    lines = []
    modes = r.sample([1, 2, 3], r.randint(1, 3))  # distinct: two targets on one mode are refused
    for mode in modes:
        lines.append("[[target]]")
        if r.random() < 0.6 or mode == 1:
            lines.append(f"mode = {_toml_value(odd(mode, [0, 4, 99, -1, 2.5, '1', True, 2**70]))}")
            lines.append(f"frequency_hz = {_toml_value(odd(r.uniform(30.0, 1500.0), [_hostile_number(r)]))}")
        else:
            lines.append(f"mode = {odd(mode, [0, 1, 99])}")
            lines.append(f"ratio_to = {odd(1, [0, 2, 3, 99, -1, 1.0])}")
            lines.append(f"ratio = {_toml_value(odd(r.uniform(5.0, 40.0), [_hostile_number(r)]))}")
        if r.random() < 0.3:
            lines.append(f"tolerance = {_toml_value(odd(r.uniform(1e-3, 0.2), [_hostile_number(r)]))}")
        if r.random() < 0.05:
            lines.append(f"shape = {_toml_value([r.uniform(-1, 1) for _ in range(r.choice([2, 2, 3, 5]))])}")
    for name in r.sample(list(SMALL_VALUES), r.randint(1, 2)):
        name = odd(name, ["shaft.damping", "shaft.damping_ratio", "x.y", "", "shaft.stiffness "])
        lines += ["[[parameter]]", f"name = {json.dumps(name)}"]
        kind = r.choice(["percent", "percent", "bounds", "fixed"])
        if kind == "percent":
            lines.append(f"percent = {_toml_value(odd(r.uniform(1.0, 50.0), [_hostile_number(r), 99.5]))}")
        elif kind == "bounds":
            x = SMALL_VALUES.get(name, 1.0)
            good = [r.uniform(0.1, 0.9) * x, r.uniform(1.1, 10.0) * x]
            bad = [[-1.0, x], [x, x], [2 * x, x], [0.0, 2 * x], [_hostile_number(r), x], [x]]
            lines.append(f"bounds = {_toml_value(odd(good, bad))}")
        else:
            fixed = odd(r.uniform(0.5, 2.0) * SMALL_VALUES.get(name, 1.0), [-1.0, 0.0])
            lines.append(f"fixed = {_toml_value(fixed)}")
    return "\n".join(lines) + "\n"


@st.composite
def command_lines(draw, command: str):
    """``(argv, targets file text)`` of one analysis command (see above)."""
    import random

    r = random.Random(draw(st.integers(0, 2**64 - 1)))
    positional, options = COMMANDS[command]
    argv = [command, *positional]
    scenario = None
    if command == "simulate":
        scenario = _value(r, lambda r: r.choice(SCENARIOS), ["", "walk", "STEP", "csv "])
        argv += ["--scenario", scenario]
    for option, (make, bad), present, *scenarios in options + COMMON:
        if scenarios and scenario not in scenarios[0].split():
            present /= 30  # an option of another scenario: refused, now and then
        if r.random() >= present:
            continue
        if make is None:
            argv.append(option)
            continue
        v = _value(r, make, bad)
        # "--to=-inf": a value that starts with "-" reaches the option, not argparse's guess at an option
        argv += [f"{option}={v}"] if v.startswith("-") and option.startswith("--") else [option, v]
    return argv, _small_targets(r) if command == "calibrate" else GOOD_SMALL_TARGETS


class _TooSlow(BaseException):
    """Raised in a case that outlives :data:`CASE_SECONDS` (a BaseException: the CLI's catch-all for
    defects must not turn it into an exit code)."""


def _option(argv: list[str], name: str) -> list[str]:
    """The values ``name`` has in ``argv`` (``--name value`` or ``--name=value``)."""
    out = [v for a, v in zip(argv, argv[1:]) if a == name]
    return out + [a.split("=", 1)[1] for a in argv if a.startswith(name + "=")]


def _snapshot(folder) -> dict:
    import hashlib

    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir() if p.is_file()}


def cli_problems(folder, argv: list[str], targets: str) -> list[str]:
    """Run ``flexshaft argv`` in ``folder`` (the small model, a signal file and a targets file laid out
    in it) and say what went wrong: the outcomes allowed are listed above this section."""
    import contextlib
    import io
    import signal
    import warnings

    from flexshaft.cli import main

    (folder / "m.toml").write_text(SMALL_MODEL)
    (folder / "s.csv").write_text(_signals_csv())
    (folder / "t.toml").write_text(targets)
    before = _snapshot(folder)
    out, err = io.StringIO(), io.StringIO()

    def too_slow(signum, frame):
        raise _TooSlow

    here = os.getcwd()
    previous = signal.signal(signal.SIGALRM, too_slow)
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    try:
        os.chdir(folder)
        with (
            warnings.catch_warnings(record=True) as heard,
            contextlib.redirect_stdout(out),
            contextlib.redirect_stderr(err),
        ):
            warnings.simplefilter("always")
            code = main(argv)
    except _TooSlow:
        return [f"still running after {CASE_SECONDS} s"]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        os.chdir(here)
    problems = []
    text, lines = err.getvalue(), err.getvalue().strip().splitlines()
    from flexshaft.cli import last_warnings

    # the command catches warnings itself (notes after a success, nothing after an error): it says which
    heard = [f"{w.category.__name__}: {w.message}" for w in heard] + [f"{k}: {m}" for k, m in last_warnings()]
    if heard:
        problems.append(f"warnings {heard}")
    if code not in (0, 2):
        problems.append(f"exit {code}")
    if "Traceback" in text or "defect" in text:
        problems.append(f"stderr {text[:500]!r}")
    after = _snapshot(folder)
    if {k: after.get(k) for k in before} != before:
        problems.append(f"an input changed: {[k for k in before if after.get(k) != before[k]]}")
    if code == 0:
        if text:
            problems.append(f"exit 0 with stderr {text[:300]!r}")
    else:
        if len(lines) != 1 or out.getvalue():
            problems.append(f"stderr {lines[:3]!r}, stdout {out.getvalue()[:200]!r}")
        if set(after) != set(before):
            problems.append(f"a failed run wrote {sorted(set(after) - set(before))}")
    left = [p.name for p in folder.rglob("*") if p.name.endswith(".tmp")]
    if left:
        problems.append(f"temporary files left: {left}")
    return problems


GOOD_SMALL_TARGETS = (
    "[[target]]\nmode = 1\nfrequency_hz = 44.0\n[[parameter]]\nname = 'shaft.stiffness'\npercent = 10\n"
)


def _check_command_line(tmp_path_factory, drawn) -> None:
    argv, targets = drawn
    problems = cli_problems(tmp_path_factory.mktemp("cli"), argv, targets)
    shown = f"\n{targets}" if argv[0] == "calibrate" else ""
    assert not problems, f"flexshaft {shlex.join(argv)}: {problems}{shown}"


def _option_test(command: str):
    @settings(
        max_examples=OPTION_CASES,
        derandomize=True,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
    )
    @given(command_lines(command))
    def test(tmp_path_factory, drawn):
        _check_command_line(tmp_path_factory, drawn)

    test.__name__ = f"test_{command}_options_exit_0_1_or_2_with_one_line_and_no_warning"
    return test


test_frf_options_exit_0_1_or_2_with_one_line_and_no_warning = _option_test("frf")
test_simulate_options_exit_0_1_or_2_with_one_line_and_no_warning = _option_test("simulate")
test_spectrum_options_exit_0_1_or_2_with_one_line_and_no_warning = _option_test("spectrum")
test_campbell_options_exit_0_1_or_2_with_one_line_and_no_warning = _option_test("campbell")
test_sensitivity_options_exit_0_1_or_2_with_one_line_and_no_warning = _option_test("sensitivity")
test_calibrate_options_exit_0_1_or_2_with_one_line_and_no_warning = _option_test("calibrate")


@pytest.mark.slow
@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_long_run_of_every_commands_options(tmp_path_factory, command):
    # CI's slow step: ten times the default run's cases per command.
    @settings(
        max_examples=10 * OPTION_CASES,
        derandomize=True,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
    )
    @given(command_lines(command))
    def run(drawn):
        _check_command_line(tmp_path_factory, drawn)

    run()
