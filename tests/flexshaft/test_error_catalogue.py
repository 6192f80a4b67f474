"""The CLI's error catalogue: every refusal is one stderr line naming file, field, value and what is valid.

Each case is a bad model file or a bad command line a user can write; the test runs the CLI on it and
checks the line's shape. The lines themselves are the catalogue (``pytest -s`` prints it).
"""

from __future__ import annotations

import pytest

from flexshaft.cli import main
from tests.conftest import EXAMPLES

M = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n'
S = '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = 1e5\ninertia = 1.0\n'
SEG = '[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\nsegments = [{length = 1.0, od = 0.1}]\n'
FULL = '[model]\ndofs = "full"\n'
CAD = '[[chain]]\nname = "c"\ntype = "cad"\nmaterial = "steel"\ngeometry = '
C1 = str(EXAMPLES / "customer1.toml")

MODEL_FILES = {
    "negative inertia": M.replace("58.1", "-58.1") + S,
    "NaN stiffness": M + S.replace("1e5", "nan"),
    "unknown key": M + S + "colour = 1\n",
    "unknown type": M + '[[chain]]\nname = "x"\ntype = "spring"\n',
    "duplicate name": M + M,
    "missing key": M + '[[chain]]\nname = "p"\ntype = "shaft"\ninertia = 1.0\n',
    "wrong unit": M + S.replace("1e5", '"1e5 kg"'),
    "bad unit text": M + S.replace("1e5", '"lots"'),
    "damping ratio above one": M + S + "damping_ratio = 1.5\n",
    "elements zero": M + S + "elements = 0\n",
    "unknown material": M + SEG.replace('"steel"', '"unobtainium"'),
    "bore above diameter": M + SEG.replace("od = 0.1}", "od = 0.1, id = 0.2}"),
    "station outside the part": M + SEG + "stations = {j = 2.0}\n",
    "stations on a numbers shaft": M + S + "stations = {j = 0.5}\n",
    "tiny element length": M + SEG + "max_element_length = 1e-12\n",
    "bearing in a torsion model": M + SEG + '[[bearings]]\nstation = "motor"\nstiffness = 1e9\n',
    "bearing at no station": FULL + M + SEG + '[[bearings]]\nstation = "x"\nstiffness = 1e9\n',
    "full model shaft without sections": FULL + M + S,
    "unknown inertia model": '[model]\ninertia_model = "heavy"\n' + M + S,
    "rayleigh unknown key": "[model]\nrayleigh = {gamma = 1.0}\n" + M + S,
    "reduce both": M + S + "reduce = {modes = 2, cutoff_hz = 100.0}\n",
    "flex damping without reduce": M + S + "damping_bands = [[0, 10, 0.01]]\n",
    "code not trusted": M + CAD + '"my:part"\n',
    "standard library": M + CAD + '"os:system"\n',
    "inertia out of scale": (
        M.replace("58.1", "1e-30") + S.replace("inertia = 1.0", "inertia = 0.0") + M.replace("motor", "g")
    ),
    "massless free end": M + S.replace("inertia = 1.0", "inertia = 0.0"),
    "empty chain": "[model]\nname = 'x'\n",
    "not TOML": "[[chain\n",
}


def _line(capsys, argv) -> str:
    code = main(argv)
    out = capsys.readouterr()
    assert code == 2 and out.out == "", (argv, out)
    lines = out.err.strip().splitlines()
    assert len(lines) == 1, out.err
    return lines[0]


@pytest.mark.parametrize("case", list(MODEL_FILES))
def test_model_file_errors_are_one_complete_line(tmp_path, capsys, case):
    model = tmp_path / "m.toml"
    model.write_text(MODEL_FILES[case])
    line = _line(capsys, ["modes", str(model)])
    print(f"{case:>34}: {line}")
    assert line.startswith(f"flexshaft: error: {model}: ")
    # What is valid, always; the field and the value where there is one (a missing key has no value).
    assert "; valid: " in line or case == "not TOML", line


CLI_CASES = {
    "missing file": ["modes", "nowhere.toml"],
    "count zero": ["modes", C1, "--count", "0"],
    "too many modes": ["modes", C1, "--count", "99"],
    "force without output": ["modes", C1, "--force"],
    "twist unknown station": ["twist", C1, "--clamp", "nowhere"],
    "twist tiny torque": ["twist", C1, "--torque", "1e-320"],
    "twist bad target": ["twist", C1, "--target", "part 1"],
    "reduce without output": ["reduce", C1, "--part", "part 1", "--modes", "2"],
    "reduce a rigid": ["reduce", C1, "--part", "motor", "--modes", "2", "-o", "x.npz"],
    "reduce unknown part": ["reduce", C1, "--part", "p9", "--modes", "2", "-o", "x.npz"],
    "unknown option": ["modes", C1, "--colour"],
}


@pytest.mark.parametrize("case", list(CLI_CASES))
def test_command_line_errors_are_one_line(tmp_path, capsys, monkeypatch, case):
    monkeypatch.chdir(tmp_path)
    line = _line(capsys, CLI_CASES[case])
    print(f"{case:>34}: {line}")
    assert line.startswith("flexshaft: error: ")
