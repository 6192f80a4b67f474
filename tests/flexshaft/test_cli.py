"""The flexshaft command: output, JSON contract, exit codes."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.cli import main
from tests.conftest import EXAMPLES

C1 = str(EXAMPLES / "customer1.toml")


def _run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_demo_prints_the_customer1_table(capsys):
    code, out, err = _run(capsys, "demo")
    assert code == 0 and err == ""
    assert out.startswith("Customer 1: 6 components")
    ref = fs.modal_analysis(fs.load_model(C1))
    # Each mode's frequency appears in the table, as the library computes it.
    for f in ref.frequencies_hz[1:]:
        assert f"{f:.4f}" in out
    assert "rigid-body mode" in out and "part 3" in out


def test_modes_json_contract(capsys):
    code, out, err = _run(capsys, "modes", C1, "--json")
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["model"] == "Customer 1"
    assert doc["components"][0] == {"name": "motor", "type": "rigid", "inertia": 58.1}
    assert doc["components"][1]["stiffness"] == 307933.18 and doc["components"][1]["inertia"] == 0.44
    assert doc["stations"] == ["motor", "part 1/part 2", "part 2/part 3", "part 3/part 4", "generator"]
    modes = doc["modes"]
    # the rigid-body mode's 0 Hz is set, not solved for: exactly 0
    assert modes[0]["index"] == 0 and modes[0]["rigid"] is True and modes[0]["frequency_hz"] == 0.0
    assert modes[1]["rigid"] is False and modes[1]["dominant_component"] == "part 3"
    for m in modes:
        assert len(m["shape"]) == len(doc["stations"])  # shapes only at stations
        assert {"frequency_hz", "damping_ratio", "rigid", "strain_energy", "kinetic_energy"} <= set(m)
    ref = fs.modal_analysis(fs.load_model(C1))
    # The same model and solve in this process, through JSON (which keeps every digit): equal to the bit.
    assert [m["frequency_hz"] for m in modes] == pytest.approx(list(ref.frequencies_hz), rel=1e-12)
    assert doc["units"]["frequency"] == "Hz" and doc["units"]["stiffness"] == "N·m/rad"


def test_inertia_and_count_options(capsys):
    code, out, _ = _run(capsys, "modes", C1, "--inertia", "lumped", "--modes", "3", "--json")
    doc = json.loads(out)
    assert code == 0 and doc["inertia_model"] == "lumped" and len(doc["modes"]) == 3
    ref = fs.modal_analysis(fs.load_model(C1), 3, inertia_model="lumped")
    assert [m["frequency_hz"] for m in doc["modes"]] == pytest.approx(list(ref.frequencies_hz))


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["modes", "nope.toml"],
            "flexshaft: error: nope.toml: file not found; valid: an existing model file\n",
        ),
        (
            ["modes", C1, "--modes", "0"],
            "flexshaft: error: argument --modes: --modes = 0: must be an integer >= 1 "
            "(see `flexshaft modes --help`)\n",
        ),
        (
            ["modes", C1, "--inertia", "foo"],
            "flexshaft: error: argument --inertia: invalid choice: 'foo' "
            "(choose from 'consistent', 'lumped') (see `flexshaft modes --help`)\n",
        ),
    ],
)
def test_bad_arguments_exit_2_with_one_line(capsys, argv, message):
    code, out, err = _run(capsys, *argv)
    assert code == 2 and out == "" and err == message


def test_bad_model_file_exits_2_with_file_component_field_value(tmp_path: Path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = -58.1\n')
    code, out, err = _run(capsys, "modes", str(bad))
    assert code == 2 and out == ""
    assert err == (
        f"flexshaft: error: {bad}: [[chain]] #1 'motor': inertia = -58.1 kg·m²: out of range; "
        "valid: a finite number > 0 (kg·m²)\n"
    )


def test_assembly_error_names_the_file(tmp_path: Path, capsys):
    bad = tmp_path / "massless.toml"
    bad.write_text(
        '[[chain]]\nname = "m"\ntype = "rigid"\ninertia = 1\n'
        '[[chain]]\nname = "s"\ntype = "shaft"\nstiffness = 1e5\ninertia = 0\n'
    )
    code, out, err = _run(capsys, "modes", str(bad))
    assert code == 2 and out == "" and err.startswith(f"flexshaft: error: {bad}: 's': inertia = 0.0 kg·m²")
    assert err.count("\n") == 1


def test_installed_entry_point_runs_as_a_process():
    exe = Path(sys.executable).with_name("flexshaft")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "flexshaft.cli"]
    ok = subprocess.run(cmd + ["modes", C1], capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0 and "part 3" in ok.stdout and ok.stderr == ""
    bad = subprocess.run(cmd + ["modes", "missing.toml"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr == "flexshaft: error: missing.toml: file not found; valid: an existing model file\n"


def test_output_file_is_never_overwritten_without_force(tmp_path: Path, capsys):
    target = tmp_path / "modes.json"
    code, out, err = _run(capsys, "modes", C1, "--json", "-o", str(target))
    assert code == 0 and out == "" and err == ""
    assert json.loads(target.read_text())["model"] == "Customer 1"
    target.write_text("keep me")
    code, out, err = _run(capsys, "demo", "-o", str(target))
    assert code == 2 and out == ""
    assert err == (
        f"flexshaft: error: -o = {str(target)!r}: file exists; valid: a new path, or --force to replace it\n"
    )
    assert target.read_text() == "keep me"
    assert _run(capsys, "demo", "-o", str(target), "--force")[0] == 0
    # Replaced by the demo's output; a .json path gets the JSON document, never the table.
    assert json.loads(target.read_text())["model"] == "Customer 1"
    assert [p.name for p in tmp_path.iterdir()] == ["modes.json"]  # no temporary left behind


def test_failed_run_writes_nothing(tmp_path: Path, capsys):
    target = tmp_path / "out.txt"
    code, _, _ = _run(capsys, "modes", str(tmp_path / "missing.toml"), "-o", str(target))
    assert code == 2 and not target.exists()


def test_reduce_takes_the_model_files_reduce_and_damping(tmp_path, capsys):
    from flexshaft.exports.bodies import read_flexible_body

    flex = str(EXAMPLES / "customer1_flex.toml")
    out = tmp_path / "p2.pch"
    assert main(["reduce", flex, "--part", "part 2", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    # The file's reduce = {cutoff_hz = 6000} with named node torque_flange: 3 interface nodes (θx) and
    # 3 residual vectors. Fixed at the flange, part 2 is two like 1.1 m halves, each a fixed-fixed tube
    # at about n·c/(2·1.1 m) = n·1.5 kHz (c = √(G/ρ) = 3.2 km/s), in pairs: three pairs below 6 kHz.
    assert "3 boundary DOFs at x = 0, 1.1, 2.2 m + 6 fixed-interface modes + 3 residual vectors" in text
    _read = read_flexible_body(out)
    body, meta = _read.body, _read.metadata
    assert body.n_modes == 9 and body.n_residual == 3 and meta["residual_vectors"] == 3
    assert np.all(body.fixed_interface_hz[:6] < 6000) and np.all(body.damping_ratios[1:] == 0.0053)
    assert main(["reduce", flex, "--part", "part 2", "--modes", "2", "--no-residual", "-o", str(out)]) == 2
    assert "file exists" in capsys.readouterr().err
    out2 = tmp_path / "p2.npz"
    assert main(["reduce", flex, "--part", "part 2", "--modes", "2", "--no-residual", "-o", str(out2)]) == 0
    _read = read_flexible_body(out2)
    body = _read.body
    assert body.n_modes == 2 and body.n_residual == 0
    # Without reduce in the model file the number of modes must be given.
    cad = str(EXAMPLES / "customer1_cad.toml")
    assert main(["reduce", cad, "--part", "part 4", "-o", str(out2), "--force"]) == 2
    assert "--modes: how many modes?" in capsys.readouterr().err


def test_reduce_a_shaft_given_by_numbers(tmp_path, capsys):
    # A shaft of given stiffness and inertia in 10 equal elements reduces like any other: Craig–Bampton
    # keeps the static condensation, so the body's interface stiffness is the shaft's k·[[1, −1], [−1, 1]].
    model = tmp_path / "m.toml"
    model.write_text(
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n[[chain]]\nname = "s"\n'
        'type = "shaft"\nstiffness = 3.0e5\ninertia = 0.44\nelements = 10\n'
    )
    out = tmp_path / "s.npz"
    assert main(["reduce", str(model), "--part", "s", "--modes", "3", "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["part"] == "s" and doc["modes"] == 3 and doc["boundary_x"] is None  # no length: no x
    from flexshaft.exports.bodies import read_flexible_body

    body = read_flexible_body(out).body
    # Round-off of the condensation: the 10-element chain's K_ii has condition ~50 and the element
    # stiffness 10k cancels to k: ~eps·500 ≈ 1e-13 (2e-16 seen); 1e-10 is loose.
    np.testing.assert_allclose(body.K[:2, :2], 3.0e5 * np.array([[1, -1], [-1, 1]]), rtol=1e-10)
    assert main(["reduce", str(model), "--part", "motor", "--modes", "3", "-o", str(out), "--force"]) == 2
    assert "--part = 'motor': has no elements to reduce" in capsys.readouterr().err


def test_cli_contract_details(tmp_path, capsys):
    from flexshaft import __version__

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"flexshaft {__version__}"
    # The one version string is the installed distribution's (pyproject.toml).
    from importlib.metadata import version

    assert version("flexshaft") == __version__
    # --force without -o is a mistake, said on one line; a .json output gets the JSON document.
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--force"]) == 2
    err = capsys.readouterr()
    assert err.out == "" and "--force: replaces a file only with -o PATH" in err.err
    target = tmp_path / "modes.json"
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "-o", str(target)]) == 0
    assert json.loads(target.read_text())["model"] == "Customer 1"


@pytest.mark.parametrize(
    "raised, code, text",
    [
        (TypeError("bad thing\nsecond line"), 2, "unexpected TypeError: bad thing (a flexshaft defect"),
        # the environment refusing an output: named, with the system's reason and its code (exit 2)
        (
            PermissionError(13, "Permission denied", "/x/out.txt"),
            2,
            "output = '/x/out.txt': cannot be written: Permission denied (EACCES)",
        ),
        # the environment refusing something that is no output (a fork): said as the system says it
        (
            BlockingIOError(11, "Resource temporarily unavailable"),
            2,
            "error: Resource temporarily unavailable (EAGAIN)",
        ),
        (KeyboardInterrupt(), 130, "flexshaft: interrupted"),
    ],
)
def test_anything_else_is_one_line_and_no_traceback(monkeypatch, capsys, raised, code, text):
    # The error contract beyond ModelError: a defect (exit 2), the environment (2), an interrupt (130).
    from flexshaft.cli.commands import modelling

    def boom(*args, **kwargs):
        raise raised

    monkeypatch.setattr(modelling, "modes", boom)
    assert main(["modes", str(EXAMPLES / "customer1.toml")]) == code
    out = capsys.readouterr()
    assert out.out == "" and text in out.err and len(out.err.strip().splitlines()) == 1
    if isinstance(raised, OSError) and raised.filename is None:
        assert "cannot be written" not in out.err  # no output named: not told as one


def test_a_warning_inside_a_command_is_one_note_without_a_source_path(monkeypatch, capsys):
    # Python prints a warning as "/path/to/module.py:LINE: Category: message" and the source line; a
    # command tells each distinct one once as a note of its own, escaped, after its result
    import warnings

    from flexshaft.cli.commands import modelling

    real = modelling.modes

    def warned(*args, **kwargs):
        for _ in range(2):  # the same warning twice (from one place): one note
            np.float64(1.0) / np.float64(0.0)  # numpy's own RuntimeWarning, from numpy's code
        warnings.warn("a library's remark \x1b[2J", UserWarning, stacklevel=1)
        return real(*args, **kwargs)

    monkeypatch.setattr(modelling, "modes", warned)
    assert main(["modes", C1]) == 0
    captured = capsys.readouterr()
    assert "Customer 1" in captured.out
    assert captured.err.splitlines() == [
        "flexshaft: note: RuntimeWarning: divide by zero encountered in scalar divide",
        "flexshaft: note: UserWarning: a library's remark \\u001b[2J",
    ]
    assert ".py" not in captured.err

    def warned_then_refused(*args, **kwargs):
        warnings.warn("never shown", UserWarning, stacklevel=1)
        raise fs.ModelError("refused", field="x")

    monkeypatch.setattr(modelling, "modes", warned_then_refused)
    assert main(["modes", C1]) == 2
    assert capsys.readouterr().err.splitlines() == ["flexshaft: error: " + C1 + ": x: refused"]


@pytest.mark.parametrize(
    "text, message",
    [
        (
            '[[chain]]\nname = "a"\ntype = ["rigid"]\ninertia = 1.0\n',
            "type = ['rigid']: unknown component type",
        ),
        (
            '[[chain]]\nname = "a"\ntype = "shaft"\nstiffness = 1.0\ninertia = 1.0\nstations = {j = 0.5}\n',
            "stations = {'j': 0.5}: belongs to a shaft made from sections",
        ),
        ("a = " + "[" * 3000 + "]" * 3000 + "\n", "nests arrays or tables 65 deep (line 1)"),
    ],
)
def test_model_files_that_were_tracebacks(tmp_path, capsys, text, message):
    model = tmp_path / "m.toml"
    model.write_text(text)
    assert main(["modes", str(model)]) == 2
    out = capsys.readouterr()
    assert out.out == "" and message in out.err and len(out.err.strip().splitlines()) == 1


def test_max_hz_lists_only_the_modes_up_to_it(capsys):
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--max-hz", "100", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [m["index"] for m in doc["modes"]] == [0, 1, 2]  # 0, 11.6 and 91.1 Hz; 242.8 Hz is above
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--max-hz", "100"]) == 0
    assert "modes up to 100 Hz: 3 of the 5 computed" in capsys.readouterr().out
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--max-hz", "-1"]) == 2
    assert "--max-hz = -1.0 Hz: out of range" in capsys.readouterr().err


def test_every_output_option_has_its_suffixes_in_the_one_table():
    # The central check (_check_output_paths) knows every file option of every command (-o, --plot ...): a new
    # command or option cannot write a file whose suffix nobody checked. report and study write a folder.
    from flexshaft import cli
    from flexshaft.views.plots import PICTURE_SUFFIXES

    parser = cli._parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    from flexshaft.cli.outputs import OUTPUT_OPTIONS

    flags = {attr: option for option, attr in OUTPUT_OPTIONS.items()}
    for name, command in sub.choices.items():
        options = {flags[a.dest] for a in command._actions if a.dest in flags}
        if name in ("report", "study"):
            assert options == {"-o"}
            continue
        assert options == set(cli.output_suffixes().get(name, {})), name
        for option, kinds in cli.output_suffixes().get(name, {}).items():
            assert all(s == s.lower() and s.startswith(".") for s in kinds), (name, option)
            if option == "--plot":
                assert tuple(kinds) == PICTURE_SUFFIXES  # what views.plots.picture writes
