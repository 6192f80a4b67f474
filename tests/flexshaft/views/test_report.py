"""``flexshaft report MODEL``: the model's study with the default plan - self-contained, every picture a
decodable PNG, results.json (with the modes document) beside it."""

from __future__ import annotations

import base64
import json
import re

import pytest

import flexshaft as fs
from flexshaft.cli import main
from tests.browser import NO_BROWSER, page_errors
from tests.conftest import EXAMPLES

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    pytest.importorskip("pyvista")
    out = tmp_path_factory.mktemp("report")
    assert main(["report", str(EXAMPLES / "customer1.toml"), "-o", str(out / "r")]) == 0
    return out / "r"


def _modes(report) -> dict:
    """The report's modes document (results.json's, under the set-up and the parts' damping)."""
    return json.loads((report / "results.json").read_text())["modes"]["customer1"]["parts"]


def test_the_report_holds_everything_and_needs_no_network(report):
    text = (report / "index.html").read_text()
    # each section's heading (with its id: the table of contents links it)
    assert re.search(r"<h3 id=\"[^\"]+\">Modes</h3>", text) and "part 3" in text
    assert re.search(r"<h3 id=\"[^\"]+\">Twist test</h3>", text)
    # No link to anything outside the file: every picture is a data URI (links only to its own set-ups).
    assert not re.search(r'(src|href)="(?!data:|#)', text)
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', text)
    assert len(images) >= 5  # energy, shapes, three 3D pictures, twist
    assert all(base64.b64decode(i)[:8] == PNG for i in images)


def test_the_report_is_the_models_study_with_the_default_plan(report, tmp_path):
    # a study file naming only the set-up: every other table at its default - the same results
    study = tmp_path / "c1.toml"
    study.write_text(f"[[setup]]\nmodel = {json.dumps(str(EXAMPLES / 'customer1.toml'))}\n")
    assert main(["study", str(study), "-o", str(tmp_path / "s")]) == 0
    ours = json.loads((report / "results.json").read_text())
    theirs = json.loads((tmp_path / "s" / "results.json").read_text())
    assert [s["id"] for s in ours["provenance"]["stages"]] == [
        s["id"] for s in theirs["provenance"]["stages"]
    ]
    for section in ("setups", "parts", "twist", "modes", "views"):
        assert ours[section] == theirs[section], section


def test_the_modes_document_is_the_cli_one(report):
    doc = _modes(report)
    ref = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml")).to_dict()
    assert [m["frequency_hz"] for m in doc["modes"]] == [m["frequency_hz"] for m in ref["modes"]]


def test_the_report_shows_the_mesh_check_of_modes(report, capsys):
    # The report's mesh column is the one `flexshaft modes --json` computes: the same flagged modes.
    text = (report / "index.html").read_text()
    assert "mesh error %" in text
    assert main(["modes", str(EXAMPLES / "customer1.toml"), "--json"]) == 0
    flagged = json.loads(capsys.readouterr().out)["mesh_check"]["flagged_modes"]
    assert flagged and text.count("⚠</td>") == len(flagged)
    doc = _modes(report)
    assert doc["mesh_check"]["flagged_modes"] == flagged
    # and the summary the page opens on names them (the page's first section)
    summary = text[text.index('id="summary"') : text.index('<nav class="toc">')]
    assert f"modes {', '.join(map(str, flagged))} estimated more than 1 %" in summary


def test_a_report_is_not_replaced_without_force(report, capsys):
    # The folder is flexshaft's (its marker): the same report again replaces its files with --force only.
    assert "flexshaft report" in (report / ".flexshaft-output").read_text()
    assert main(["report", str(EXAMPLES / "customer1.toml"), "-o", str(report)]) == 2
    assert "file exists" in capsys.readouterr().err
    assert main(["report", str(EXAMPLES / "customer1.toml"), "-o", str(report), "--force"]) == 0


def test_the_report_opens_in_a_browser_with_every_image_decoded(report):
    # Headless Chromium loads the page and counts the images it could not decode.
    # one page load: every image decoded, and the mode viewer runs (no script error, no console error,
    # no refused request; its clock ran)
    ran = page_errors(report / "index.html", 1500)
    if ran is None:
        pytest.skip(NO_BROWSER)
    assert ran.startswith("errors:0 ") and "frames:-1" not in ran, ran
    assert re.search(r" broken:0 of [1-9]\d* remote:0 ", ran), ran  # and no request off the machine


def test_demo_writes_the_report_into_a_folder(tmp_path, capsys):
    pytest.importorskip("pyvista")
    # A folder (existing, or written with a trailing slash) gets the report; a file path the table.
    assert main(["demo", "-o", str(tmp_path / "rep") + "/"]) == 0
    assert (tmp_path / "rep" / "index.html").is_file() and (tmp_path / "rep" / "results.json").is_file()
    assert "report:" in capsys.readouterr().out
    assert main(["demo", "-o", str(tmp_path / "table.txt")]) == 0
    assert (tmp_path / "table.txt").read_text().startswith("Customer 1:")
