"""The CLI's one vocabulary and the old spellings kept for one release (issue 34): each old spelling
gives what its new spelling gives, says so in one note on stderr, and is hidden from --help."""

from __future__ import annotations

import contextlib
import io
import re

import pytest

from flexshaft.cli import _parser, main
from tests.conftest import EXAMPLES

C1 = str(EXAMPLES / "customer1.toml")
C2 = str(EXAMPLES / "customer2.toml")
SIM = ["simulate", C1, "--duration", "0.5"]
# a ramp whose loop is stable on the generator's speed too (the table names the speed it controls)
SINE = [*SIM, "--scenario", "sine", "--torque", "10", "--frequency", "5"]
FEEDBACK = "--measure as the loop's speed is deprecated; use --feedback"
RAMP = [*SIM, "--scenario", "ramp", "--end-speed", "300", "--ramp-time", "0.4", "--kp", "0.5", "--ki", "0.1"]

# (old command line, the same in the new words, the notes the old one gives)
RENAMED = [
    (["modes", C1, "--count", "3"], ["modes", C1, "--modes", "3"], ["--count", "--modes"]),
    (
        ["reduce", C1, "--part", "part 3", "--cutoff", "900", "-o", "b.npz"],
        ["reduce", C1, "--part", "part 3", "--max-hz", "900", "-o", "b.npz"],
        ["--cutoff", "--max-hz"],
    ),
    (["twist", C1, "--load", "generator"], ["twist", C1, "--at", "generator"], ["--load", "--at"]),
    (
        ["sections", C1, "--compare-solid", "--solid-modes", "2"],
        ["sections", C1, "--compare-solid", "--modes", "2"],
        ["--solid-modes", "--modes"],
    ),
    (
        ["frf", C1, "--input", "motor", "--output", "speed:generator", "--output", "torque:part 3"],
        ["frf", C1, "--at", "motor", "--measure", "speed:generator", "--measure", "torque:part 3"],
        ["--input", "--at", "--output", "--measure", "--output", "--measure"],
    ),
    (
        [
            "statespace",
            C1,
            "--input",
            "motor",
            "--input",
            "generator",
            "--output",
            "angle:motor",
            "-o",
            "s.mat",
        ],
        ["statespace", C1, "--at", "motor", "--at", "generator", "--measure", "angle:motor", "-o", "s.mat"],
        ["--input", "--at", "--input", "--at", "--output", "--measure"],
    ),
    (
        [*SIM, "--scenario", "step", "--torque", "10", "--load", "-5", "--measure", "speed:motor"],
        [*SIM, "--scenario", "step", "--torque", "10", "--load-torque", "-5", "--measure", "speed:motor"],
        ["--load", "--load-torque"],
    ),
    (
        ["forced", C2, "--input", "motor", "--amplitude", "100"],
        ["forced", C2, "--at", "motor", "--torque", "100"],
        ["--input", "--at", "--amplitude", "--torque"],
    ),
]


def _parsed(argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        args = _parser().parse_args(argv)
    return args, err.getvalue()


def _note(old: str, new: str) -> str:
    return f"flexshaft: note: {old} is deprecated; use {new}"


@pytest.mark.parametrize("old, new, renames", RENAMED, ids=[" ".join(r[2][:2]) for r in RENAMED])
def test_an_old_spelling_reads_as_its_new_one_with_a_note(old, new, renames):
    got, notes = _parsed(old)
    want, quiet = _parsed(new)
    assert vars(got) == vars(want) and quiet == ""
    pairs = zip(renames[::2], renames[1::2])
    assert notes.splitlines() == [_note(o, n) for o, n in pairs]


def _run(capsys, argv):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize(
    "old, new, notes",
    [
        (
            ["modes", C1, "--count", "3", "--json"],
            ["modes", C1, "--modes", "3", "--json"],
            [_note("--count", "--modes")],
        ),
        (
            ["twist", C1, "--load", "generator", "--torque", "500"],
            ["twist", C1, "--at", "generator", "--torque", "500"],
            [_note("--load", "--at")],
        ),
        (
            ["frf", C1, "--input", "motor", "--output", "speed:generator", "--to", "300", "--points", "50"],
            ["frf", C1, "--at", "motor", "--measure", "speed:generator", "--to", "300", "--points", "50"],
            [_note("--input", "--at"), _note("--output", "--measure")],
        ),
        (
            ["forced", C2, "--amplitude", "100", "--input", "motor", "--json"],
            ["forced", C2, "--torque", "100", "--at", "motor", "--json"],
            [_note("--amplitude", "--torque"), _note("--input", "--at")],
        ),
        (  # --at was forced's excitation frequency: a number that is no station is still one
            ["forced", C1, "--at", "11.6", "--at", "50"],
            ["forced", C1, "--frequency", "11.6", "--frequency", "50"],
            ["flexshaft: note: --at HZ is deprecated (--at names the station); use --frequency HZ"],
        ),
        (
            [*SINE, "--load", "-5", "--output", "speed:motor"],
            [*SINE, "--load-torque", "-5", "--measure", "speed:motor"],
            [_note("--load", "--load-torque"), _note("--output", "--measure")],
        ),
        (  # with --output SIGNAL, --measure is still the loop's speed
            [*RAMP, "--output", "torque:part 3", "--measure", "speed:generator"],
            [*RAMP, "--measure", "torque:part 3", "--feedback", "speed:generator"],
            [_note("--output", "--measure"), f"flexshaft: note: {FEEDBACK}"],
        ),
    ],
)  # fmt: skip
def test_an_old_spelling_gives_the_same_output_and_a_note(capsys, old, new, notes):
    code, out, err = _run(capsys, new)
    assert (code, err) == (0, "")
    assert _run(capsys, old) == (0, out, "\n".join(notes) + "\n")


def test_the_loop_s_old_measure_is_one_speed(capsys):
    argv = [*RAMP, "--output", "torque:part 3", "--measure", "speed:motor", "--measure", "speed:generator"]
    code, out, err = _run(capsys, argv)
    assert code == 2 and out == ""
    assert ": --measure = 'speed:motor, speed:generator': " in err.splitlines()[-1]


@pytest.mark.parametrize(
    "command, old",
    [
        ("modes", ["--count"]),
        ("reduce", ["--cutoff"]),
        ("twist", ["--load"]),
        ("sections", ["--solid-modes"]),
        ("frf", ["--input", "--output"]),
        ("statespace", ["--input", "--output"]),
        ("simulate", ["--output", "--load"]),
        ("forced", ["--input", "--amplitude"]),
    ],
)
def test_help_lists_no_old_spelling(command, old):
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        _parser().parse_args([command, "--help"])
    text = out.getvalue()
    assert "usage: flexshaft " + command in text
    for spelling in old:
        assert not re.search(rf"(?<![\w-]){spelling}(?![\w-])", text), spelling


def test_one_word_one_meaning():
    # the words the issue settled: -o/--output the output file, --measure the outputs of a linear system
    # or a run, --modes a mode count, --max-hz an upper frequency, --at the station a torque acts at
    sub = next(a for a in _parser()._actions if a.dest == "command")
    meaning = {}
    for parser in sub.choices.values():
        for action in parser._actions:
            if action.help == "==SUPPRESS==":
                continue
            for option in action.option_strings:
                meaning.setdefault(option, set()).add(action.dest)
    assert meaning["--output"] == {"output"} and meaning["-o"] == {"output"}
    assert meaning["--measure"] == {"outputs"}
    assert meaning["--modes"] <= {"count", "modes", "solid_modes"}  # a count of modes, by each command's name
    assert meaning["--max-hz"] == {"max_hz"}
    assert meaning["--at"] <= {"at", "inputs"}  # forced, twist, simulate; frf and statespace (repeatable)
    for word in ("--count", "--cutoff", "--input", "--load", "--amplitude", "--solid-modes"):
        assert word not in meaning, word


def test_modes_and_demo_plot_the_mode_shapes(tmp_path, capsys):
    for argv in (["modes", C1], ["demo"]):
        plot = tmp_path / f"{argv[0]}.png"
        code, out, err = _run(capsys, [*argv, "--plot", str(plot)])
        assert (code, err) == (0, "") and "Customer 1" in out
        assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, err = _run(capsys, ["modes", C1, "--plot", str(tmp_path / "m.txt")])
    assert code == 2 and "--plot = " in err and "unknown file type" in err


def test_simulate_json_is_the_run_s_summary(tmp_path, capsys):
    import json

    import numpy as np

    csv = tmp_path / "run.csv"
    argv = [*SINE, "--measure", "speed:motor", "--measure", "torque:part 3", "--json", "-o", str(csv)]
    code, out, err = _run(capsys, argv)
    assert (code, err) == (0, "")
    text, written = out.rstrip("\n").rsplit("\n", 1)
    doc = json.loads(text)
    assert written == f"samples: {csv}"
    samples = np.loadtxt(csv, delimiter=",", skiprows=1)  # time [s], then one column per output
    assert doc["samples"] == samples.shape[0] == 501 and doc["duration_s"] == 0.5 and doc["rate_hz"] == 1000
    for k, name in enumerate(("speed:motor", "torque:part 3"), start=1):
        got = doc["outputs"][name]
        assert [got["min"], got["max"], got["final"]] == [
            samples[:, k].min(),
            samples[:, k].max(),
            samples[-1, k],
        ]
    assert doc["outputs"]["speed:motor"]["unit"] == "rad/s" and "speed_loop" not in doc
