"""reduce_part, the part export ``flexshaft reduce`` and the study both call: the command's --json
document, a body that reproduces the part's rigid-body mass and static stiffness, and errors that
name the argument."""

from __future__ import annotations

import json

import pytest

import flexshaft as fs
from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.model.reduce import reduce_part
from tests.conftest import EXAMPLES

MODEL = EXAMPLES / "customer1_flex.toml"  # part 1 carries reduce = {modes = 4}


def test_the_document_is_the_command_s(tmp_path, capsys):
    out = tmp_path / "part2.npz"
    assert main(["reduce", str(MODEL), "--part", "part 2", "-o", str(out), "--json", "--modes", "3"]) == 0
    cli = json.loads(capsys.readouterr().out)
    r = reduce_part(fs.load_model(MODEL), "part 2", modes=3)
    assert json.loads(json.dumps(r.to_dict(out))) == cli
    assert r.to_dict()["written"] is None and r.fixed_modes == 3


def test_the_model_file_s_reduce_and_the_check():
    r = reduce_part(fs.load_model(MODEL), "part 1")
    assert r.fixed_modes == 4  # reduce = {modes = 4} on the part
    # Craig–Bampton keeps the rigid-body mass and the static condensation exactly: round-off only
    assert r.check.rigid_mass_error < 1e-9 and r.check.static_error < 1e-9


@pytest.mark.parametrize("part, options, field", [("motor", {}, "part"), ("part 3", {}, "part")])
def test_a_part_without_elements_is_refused(part, options, field):
    with pytest.raises(ModelError) as err:
        reduce_part(fs.load_model(MODEL), part, **options)
    assert err.value.field == field


def test_how_many_modes_when_nothing_says():
    from flexshaft.input.modelfile import loads_model

    text = MODEL.read_text().replace("reduce = {modes = 4}\n", "", 1)
    with pytest.raises(ModelError) as err:
        reduce_part(loads_model(text, source="plain.toml"), "part 1")
    assert err.value.field == "modes"
    assert reduce_part(loads_model(text, source="plain.toml"), "part 1", modes=2).fixed_modes == 2
