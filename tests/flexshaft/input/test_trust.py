"""A model file runs no code it names unless the user trusts it, and user code fails as one error line.

The sentinel tests are the security contract: a model file from someone else naming ``os:system``,
``shutil:rmtree``, ``subprocess:check_output`` or a ``.py`` outside its folder runs nothing, with or
without ``--allow-code``.
"""

from __future__ import annotations

import pytest

import flexshaft as fs
from flexshaft.cli import main

MOTOR = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n'


def cad_model(folder, geometry, params=""):
    model = folder / "m.toml"
    entry = f'[[chain]]\nname = "tube"\ntype = "cad"\ngeometry = "{geometry}"\nmaterial = "steel"\n'
    model.write_text(MOTOR + entry + params)
    return model


@pytest.mark.parametrize("allow_code", [False, True])
@pytest.mark.parametrize(
    "geometry, params",
    [
        ("os:system", 'params = {command = "touch SENTINEL"}'),
        ("subprocess:check_output", 'params = {args = ["touch", "SENTINEL"]}'),
        ("shutil:rmtree", 'params = {path = "VICTIM"}'),
        ("os.path:exists", 'params = {path = "SENTINEL"}'),
    ],
)
def test_a_model_file_never_runs_the_standard_library(tmp_path, monkeypatch, geometry, params, allow_code):
    monkeypatch.chdir(tmp_path)
    victim = tmp_path / "VICTIM"
    victim.mkdir()
    model = cad_model(tmp_path, geometry, params.replace("VICTIM", str(victim)) + "\n")
    with pytest.raises(fs.ModelError) as err:
        fs.load_model(model, allow_code=allow_code)
    text = str(err.value)
    assert "\n" not in text and f"geometry = '{geometry}'" in text
    if allow_code:
        assert "names a standard-library module, which is never run from a model file" in text
    else:
        assert "code from a model file runs only when you trust it" in text and "--allow-code" in text
    assert not (tmp_path / "SENTINEL").exists() and victim.is_dir()


EVIL = """
from pathlib import Path
Path(__file__).with_name("SENTINEL").write_text("ran")


def part(**kw):
    return None
"""


def test_a_module_outside_the_model_files_folder_runs_nothing(tmp_path, monkeypatch):
    (tmp_path / "evil.py").write_text(EVIL)
    sub = tmp_path / "models"
    sub.mkdir()
    monkeypatch.chdir(tmp_path)  # even where the working directory would find it
    monkeypatch.syspath_prepend(str(tmp_path))
    (sub / "link.py").symlink_to(tmp_path / "evil.py")
    for geometry in ("evil:part", "../evil:part", "link:part", "/abs/evil:part", "models.evil:part"):
        model = cad_model(sub, geometry)
        for allow_code in (False, True):
            with pytest.raises(fs.ModelError):
                fs.load_model(model, allow_code=allow_code)
    assert not (tmp_path / "SENTINEL").exists()


def test_without_trust_a_user_module_beside_the_model_does_not_run(tmp_path, capsys):
    (tmp_path / "my_parts.py").write_text(EVIL)
    model = cad_model(tmp_path, "my_parts:part")
    assert main(["modes", str(model)]) == 2
    err = capsys.readouterr()
    assert err.out == "" and len(err.err.strip().splitlines()) == 1
    assert "geometry = 'my_parts:part'" in err.err and "--allow-code" in err.err
    assert not (tmp_path / "SENTINEL").exists()


BAD_PARTS = """
import sys


def raises(**kw):
    raise ValueError("no such flange")


def exits(**kw):
    sys.exit(0)


def interrupted(**kw):
    raise KeyboardInterrupt


def recursive(**kw):
    return recursive(**kw)
"""


@pytest.mark.parametrize(
    "function, kind",
    [
        ("raises", "ValueError: no such flange"),
        ("exits", "SystemExit"),
        ("interrupted", "KeyboardInterrupt"),
        ("recursive", "RecursionError"),
    ],
)
def test_trusted_user_code_that_fails_is_one_error_naming_part_and_function(tmp_path, capsys, function, kind):
    (tmp_path / "bad_parts.py").write_text(BAD_PARTS)
    model = cad_model(tmp_path, f"bad_parts:{function}")
    with pytest.raises(fs.ModelError) as err:
        fs.load_model(model, allow_code=True)
    text = str(err.value)
    assert "\n" not in text and "'tube'" in text and f"geometry = 'bad_parts:{function}'" in text
    assert f"{function}(...) failed ({kind}" in text
    # The CLI: exit 2 and one line, nothing on stdout - an exit or interrupt in part code ends nothing else.
    assert main(["modes", str(model), "--allow-code"]) == 2
    out = capsys.readouterr()
    assert out.out == "" and len(out.err.strip().splitlines()) == 1


def test_a_user_module_that_does_not_import_is_one_error(tmp_path):
    (tmp_path / "broken.py").write_text("def part(:\n")
    with pytest.raises(fs.ModelError, match=r"broken.py failed while loading \(SyntaxError"):
        fs.load_model(cad_model(tmp_path, "broken:part"), allow_code=True)


def test_the_projects_own_part_library_needs_no_trust(tmp_path):
    pytest.importorskip("build123d")
    d = fs.load_model(cad_model(tmp_path, "geometry.parts.testbench:coupling_hub"))
    assert d.component("tube").stiffness > 0
    # Only its public part functions, not whatever else the module holds.
    for name in ("_flanged_tube", "bd", "math"):
        with pytest.raises(fs.ModelError, match="has no part function"):
            fs.load_model(cad_model(tmp_path, f"geometry.parts.testbench:{name}"))
