"""A study's ``[[export]]`` without a part: the set-up's whole drivetrain as an FMU and its modes as a
universal file - the same files ``flexshaft fmu`` and ``flexshaft modes --uff`` write, read by the tools
they are for (FMPy, pyuff), not by flexshaft."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.errors import ModelError
from flexshaft.study import run_study
from flexshaft.study.studyfile import loads_study
from tests.conftest import EXAMPLES

STUDY = """
[study]
name = "exports"

[[setup]]
name = "Customer 1"
model = "c1.toml"

[[export]]
outputs = ["speed:generator", "torque:part 3"]
"""


def test_the_drivetrain_exported_by_a_study(tmp_path):
    pytest.importorskip("pyuff", reason="pyuff is not installed (the uff extra)")
    shutil.copy(EXAMPLES / "customer1.toml", tmp_path / "c1.toml")
    (tmp_path / "study.toml").write_text(STUDY)
    run = run_study(tmp_path / "study.toml", tmp_path / "out")
    assert run.exit_code == 0
    folder = tmp_path / "out" / "exports" / "customer-1"
    doc = json.loads((tmp_path / "out" / "results.json").read_text())["exports"]["Customer 1"]["drivetrain"]
    assert doc["fmu"]["inputs"] == ["motor", "generator"]  # the default: both ends
    assert doc["fmu"]["outputs"] == ["speed:generator", "torque:part 3"]
    import pyuff

    sets = pyuff.UFF(str(folder / "drivetrain.uff")).read_sets()
    result = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    freqs = [s["freq"] for s in sets if s["type"] == 55]
    # dataset 55 holds six significant digits (E13.5): the format's limit, not flexshaft's
    np.testing.assert_allclose(freqs, result.frequencies_hz[: len(freqs)], rtol=5e-6)
    assert (folder / "drivetrain.fmu").is_file()
    fmpy = pytest.importorskip("fmpy", reason="FMPy is not installed (the test extra)")
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(folder / "drivetrain.fmu")) == []
    names = {v.name for v in fmpy.read_model_description(str(folder / "drivetrain.fmu")).modelVariables}
    assert {"motor", "generator", "speed:generator", "torque:part 3", "damping_variant"} <= names


@pytest.mark.parametrize(
    ("entry", "field"),
    [
        ('formats = ["fmu", "mat"]', "formats"),  # a body format without a part
        ('part = "part 3"\nformats = ["fmu"]', "formats"),  # a drivetrain format with a part
        ('part = "part 3"\ninputs = ["motor"]', "inputs"),  # the FMU's signals on a part's export
        ("modes = 4", "modes"),  # a reduction's mode count on the drivetrain's export
        ('formats = ["step"]', "formats"),
    ],
)
def test_an_export_that_mixes_the_two_kinds_is_refused(tmp_path, entry, field):
    text = STUDY.replace('outputs = ["speed:generator", "torque:part 3"]', entry)
    with pytest.raises(ModelError) as err:
        loads_study(text, str(tmp_path / "study.toml"), folder=tmp_path)
    assert err.value.field.endswith(field)
