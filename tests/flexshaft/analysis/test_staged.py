"""calibrate_stages, the staged calibration ``flexshaft calibrate`` and the study both run: on the
study's targets file it gives the command's --json document, and the tuned model gets the last stage's
values."""

from __future__ import annotations

import json

import pytest

import flexshaft as fs
from flexshaft.analysis.staged import calibrate_stages
from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.study.tunedfile import read_targets
from tests.conftest import EXAMPLES

TARGETS = EXAMPLES / "calibration" / "study.toml"
MODEL = EXAMPLES / "customer1.toml"


@pytest.fixture(scope="module")
def staged():
    return calibrate_stages(read_targets(TARGETS), fs.load_model, model=MODEL)


def test_the_document_is_the_command_s(staged, capsys):
    assert main(["calibrate", str(MODEL), "--targets", str(TARGETS), "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    assert json.loads(json.dumps(staged.to_dict())) == cli


def test_later_stages_carry_what_earlier_ones_tuned(staged):
    first, *later = staged.stages
    assert first.carried == {}
    shared = dict(zip(first.result.names, first.result.tuned))
    for stage in later:  # every later stage takes the shared parts' tuned values, fixed
        assert stage.carried and all(stage.carried[k] == shared[k] for k in stage.carried)
    last = staged.last
    tuned = dict(zip(last.result.names, last.result.tuned))
    assert staged.tuned_values() == last.carried | last.result.fixed | tuned


def test_an_error_is_located_in_the_targets_file(tmp_path):
    # the stages name their models relative to the targets file: the same layout, in tmp_path
    for name in ("without_dut.toml", "customer1.toml", "customer2.toml"):
        (tmp_path / name).write_text((EXAMPLES / name).read_text())
    (tmp_path / "calibration").mkdir()
    bad = tmp_path / "calibration" / "t.toml"
    bad.write_text(TARGETS.read_text().replace('name = "part 1.stiffness"', 'name = "part 9.stiffness"', 1))
    with pytest.raises(ModelError) as err:
        calibrate_stages(read_targets(bad), fs.load_model, model=MODEL)
    assert err.value.file == str(bad) and err.value.component.startswith("[[stage]] #1 [[parameter]]")
