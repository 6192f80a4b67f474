"""The whole study in one run: every stage into one report, redone only where its inputs changed.

The study here is the test bench's numbers-only set-ups (fast), with one of everything: FRF,
forced response, two time runs with spectra, Campbell, the staged calibration, an export in all
five formats and the mode views. The references are other entry points of flexshaft that the
study must agree with (``flexshaft modes --json`` on the same set-up, ``read_flexible_body`` on
the exports, ``load_model`` on the tuned models) and the behaviour the issue asks for (a re-run
does nothing, a change redoes what depends on it, a failure costs only its dependants).
"""

from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.study import SECTIONS, run_study
from tests.browser import NO_BROWSER, page_errors
from tests.conftest import ROOT

EXAMPLES = ROOT / "examples"

STUDY = """
[study]
name = "bench"
damping = "both"

[[setup]]
name = "Customer 1"
model = "c1.toml"

[[setup]]
name = "Without DUT"
model = "wd.toml"

[[frf]]
setups = ["Customer 1"]
input = "motor"
outputs = ["speed:motor", "torque:part 3"]

[[forced]]
setups = ["Customer 1"]
amplitude = 1000

[[simulate]]
name = "ramp"
setups = ["Customer 1"]
end_speed_rpm = 1000
ramp_time_s = 4
duration_s = 5
outputs = ["torque:part 3", "speed:motor"]
spectra = ["torque:part 3"]

[[simulate]]
name = "coast"
setups = ["Customer 1"]
scenario = "coast"
speed_rpm = 1000
torque = 10000
duration_s = 4
outputs = ["torque:part 3"]

[views]
modes = [1]

[campbell]
speed_rpm = [0, 1800]
orders = [1, 2, 6]

[calibration]
targets = "calibration/study.toml"
model = "c1.toml"

[[export]]
setups = ["Customer 1"]
part = "part 2"
"""


def _with_max_hz(src: Path, dst: Path, max_hz: float) -> None:
    """A copy of an example model file with ``[model] max_hz`` set: the study and the CLI mesh alike."""
    text = src.read_text()
    dst.write_text(text.replace("[model]\n", f"[model]\nmax_hz = {max_hz}\n", 1))


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """A study folder (model files copied in) and one cold run of it."""
    d = tmp_path_factory.mktemp("study")
    _with_max_hz(EXAMPLES / "customer1.toml", d / "c1.toml", 400.0)
    _with_max_hz(EXAMPLES / "without_dut.toml", d / "wd.toml", 400.0)
    (d / "calibration").mkdir()
    targets = (EXAMPLES / "calibration" / "study.toml").read_text()
    targets = targets.replace("../without_dut.toml", "../wd.toml").replace("../customer1.toml", "../c1.toml")
    targets = targets.replace("../customer2.toml", "../c2.toml")
    (d / "calibration" / "study.toml").write_text(targets)
    _with_max_hz(EXAMPLES / "customer2.toml", d / "c2.toml", 400.0)
    (d / "study.toml").write_text(STUDY)
    run = run_study(d / "study.toml", d / "out")
    return d, run


def test_every_stage_runs_into_one_report(bench):
    d, run = bench
    assert run.exit_code == 0, [s for s in run.stages if s.status != "ran"]
    assert {s.status for s in run.stages} == {"ran"}
    results = json.loads((d / "out" / "results.json").read_text())
    required = {"provenance", "modes", "frf", "simulation", "spectra", "campbell", "calibration"}
    assert required | {"exports", "views"} <= set(results) == set(SECTIONS)
    assert set(results["modes"]) == {"Customer 1", "Without DUT"}
    assert set(results["modes"]["Customer 1"]) == {"parts", "system"}  # damping = "both": side by side
    prov = results["provenance"]
    assert prov["flexshaft"] and prov["date"] and prov["machine"]["cpus"]
    assert str(d / "c1.toml") in prov["inputs"]  # the set-ups' files, with their SHA-256
    assert all(len(h) == 64 for h in prov["inputs"].values())


def test_the_report_is_self_contained(bench):
    d, _ = bench
    page = (d / "out" / "index.html").read_text()
    images = re.findall(r'<img [^>]*src="([^"]*)"', page)
    # at least the figures every set-up has (twist, energy, shapes) and its one 3D still ([views])
    assert len(images) >= 2 * (3 + 1)
    for src in images:
        assert src.startswith("data:image/png;base64,")
        png = base64.b64decode(src.split(",", 1)[1], validate=True)
        assert png[:8] == b"\x89PNG\r\n\x1a\n"  # a PNG signature (the file format's, not ours)
    # nothing is fetched: no URL in any src/href, no script file, no stylesheet link; the mode viewer's
    # scripts are inline and the page's Content-Security-Policy forbids any request
    assert not re.search(r'(src|href)="(https?:)?//', page)
    assert not re.search(r"<script[^>]*\bsrc=", page) and "<link" not in page
    assert "default-src 'none'" in page
    # the viewer of each set-up, with the modes the modes stage lists
    blobs = re.findall(r'<script type="application/json" id="(fs-viewer-\d+)-data">', page)
    assert len(blobs) == 2
    # every in-page link has its target; HTML ids hold no whitespace (set-up names may)
    ids = re.findall(r' id="([^"]*)"', page)
    assert ids and not any(re.search(r"\s", i) for i in ids)
    assert set(re.findall(r'href="#([^"]*)"', page)) <= set(ids)


def _sections(page: str) -> list[tuple[str, str]]:
    """The page's section headings (h2, h3) in order, as (id, text)."""
    return re.findall(r'<h[23] id="([^"]+)">([^<]*)</h[23]>', page)


def test_the_report_opens_on_a_summary_and_contents_linking_every_section(bench):
    d, _ = bench
    page = (d / "out" / "index.html").read_text()
    results = json.loads((d / "out" / "results.json").read_text())
    sections = _sections(page)
    ids = [i for i, _ in sections]
    # the summary first, then the contents; the provenance and the stages' times at the end
    assert ids[0] == "summary"
    assert page.index('id="summary"') < page.index('<nav class="toc">') < page.index('id="setup-1"')
    assert ids.index("calibration") < ids.index("provenance") < ids.index("provenance-stages")
    assert "<h3" not in page[page.index('id="provenance-input-files"') :]  # nothing after it
    # the contents link every section and subsection, Calibration included, and nothing else
    nav = page[page.index('<nav class="toc">') : page.index("</nav>")]
    assert set(re.findall(r'href="#([^"]+)"', nav)) == set(ids)
    assert "calibration" in ids and len(ids) == len(set(ids))
    summary = page[page.index('id="summary"') : page.index('<nav class="toc">')]
    for setup in results["setups"]:
        assert f"<td>{setup}</td>" in summary
    # every measured target against the model as built and tuned, with its verdict
    stages = results["calibration"]["stages"]
    assert stages
    for st in stages:
        for t in st["targets"]:
            before = t["initial"] / t["value"] - 1
            ok = abs(before) <= t["tolerance"]
            said = f"within ±{100 * t['tolerance']:.3g} %" if ok else f"off by {100 * before:+.2f} %"
            assert f"<td>{t['value']:.5g}</td><td>{t['initial']:.5g}</td><td>{said}</td>" in summary, t
            if not t["met"]:
                assert "missed by" in summary


def test_every_flexible_body_mode_past_its_accuracy_is_flagged(bench):
    d, _ = bench
    page = (d / "out" / "index.html").read_text()
    results = json.loads((d / "out" / "results.json").read_text())
    flagged = 0
    for doc in results["exports"].values():
        for e in doc.values():
            body = [f for f in e["free_hz"] if f > 0]  # the elastic ones, as the full part's list
            err = [abs(b - f) / f for b, f in zip(body, e["full_part_free_hz"])]
            assert err == pytest.approx(e["free_hz_error"], rel=1e-9, abs=1e-15)
            flagged += sum(x > e["free_hz_tolerance"] for x in err)
    assert page.count("<td>⚠ past 1 %</td>") == flagged


def test_an_empty_peak_table_says_why(bench):
    d, _ = bench
    page = (d / "out" / "index.html").read_text()
    results = json.loads((d / "out" / "results.json").read_text())
    empty = 0
    for runs in results["spectra"].values():
        for variants in runs.values():
            for doc in variants.values():
                for a in doc["signals"].values():
                    t = a["peak_threshold"]
                    # the threshold the peaks passed: 1e-3 of the largest amplitude above 0 Hz
                    assert t["relative"] == 1e-3 and t["amplitude"] > 0
                    assert all(p["amplitude"] >= t["amplitude"] for p in a["peaks"])
                    empty += not a["peaks"]
    assert page.count("<p>No peak listed: none reaches the threshold") == empty


def test_modes_equal_the_modes_command(bench, capsys):
    from flexshaft.cli import main

    d, _ = bench
    results = json.loads((d / "out" / "results.json").read_text())
    for setup, model in (("Customer 1", "c1.toml"), ("Without DUT", "wd.toml")):
        assert main(["modes", str(d / model), "--json"]) == 0
        cli = json.loads(capsys.readouterr().out)
        ours = results["modes"][setup]["parts"]
        assert [m["index"] for m in ours["modes"]] == [m["index"] for m in cli["modes"]]
        for a, b in zip(ours["modes"], cli["modes"]):
            # the same model, mesh and solver: equal to round-off of the eigen-solve (1e-9 relative)
            assert a["frequency_hz"] == pytest.approx(b["frequency_hz"], rel=1e-9, abs=1e-9)
            assert a["damping_ratio"] == pytest.approx(b["damping_ratio"], rel=1e-9, abs=1e-12)


def test_the_files_it_writes_load(bench):
    from flexshaft.exports.bodies import read_flexible_body
    from flexshaft.input.modelfile import load_model

    d, _ = bench
    out = d / "out"
    results = json.loads((out / "results.json").read_text())
    tuned = sorted(out.glob("*tuned*.toml"))
    assert [p.name for p in tuned] == [
        "customer-1-tuned.toml",
        "customer-2-tuned.toml",
        "shared-parts-tuned.toml",
    ]
    for p in tuned:
        assert load_model(p).components  # a tuned model is a model file
    files = results["exports"]["Customer 1"]["part 2"]["files"]
    bodies = [f for f in files if not f.endswith(".json") or f.count(".") == 1]
    assert {Path(f).suffix for f in bodies} == {".npz", ".json", ".mat", ".op4", ".pch"}
    for f in bodies:
        body = read_flexible_body(out / f).body
        assert body.n_boundary == 2  # the part's two interface stations (torsion)


def test_an_unchanged_study_is_not_run_again(bench):
    d, _ = bench
    lines = []
    again = run_study(d / "study.toml", d / "out", progress=lines.append)
    assert {s.status for s in again.stages} == {"cached"}
    assert not again.written and again.exit_code == 0
    # one line, not one per stage
    assert lines == [
        f"study unchanged: {len(again.stages)} stages read from the store ({d / 'out'}/): nothing to do"
    ]


SMALL = STUDY[: STUDY.index("[[frf]]")] + STUDY[STUDY.index("[campbell]") :] + "[views]\nsetups = []\n"


@pytest.mark.slow  # two runs of a study after the fixture's: 4-5 s
def test_a_change_redoes_only_what_depends_on_it(bench, tmp_path):
    d, _ = bench
    work = tmp_path / "work"
    shutil.copytree(d, work, ignore=shutil.ignore_patterns("out"))
    study = work / "study.toml"
    study.write_text(SMALL)
    assert run_study(study, work / "out").exit_code == 0
    study.write_text(SMALL.replace("orders = [1, 2, 6]", "orders = [1, 3]"))
    run = run_study(study, work / "out")
    ran = {s.id for s in run.stages if s.status == "ran"}
    assert ran == {"campbell/Customer 1", "campbell/Without DUT"}
    # a model file read by a set-up (and by the calibration's stages) redoes those, nothing else
    wd = work / "wd.toml"
    wd.write_text(wd.read_text().replace("58.10", "58.2"))
    run = run_study(study, work / "out")
    ran = {s.id for s in run.stages if s.status == "ran"}
    assert ran == {
        "setup/Without DUT",
        "twist/Without DUT",
        "modes/Without DUT",
        "campbell/Without DUT",
        "calibration",
    }
    # a file the study wrote and the user deleted is written again by its stage
    (work / "out" / "exports" / "customer-1" / "part-2.mat").unlink()
    run = run_study(study, work / "out")
    assert {s.id for s in run.stages if s.status == "ran"} == {"export/Customer 1/part 2"}
    assert (work / "out" / "exports" / "customer-1" / "part-2.mat").is_file()
    # a stage dropped from the study takes its files with it
    study.write_text(SMALL.replace('[[export]]\nsetups = ["Customer 1"]\npart = "part 2"\n', ""))
    run = run_study(study, work / "out")
    assert not (work / "out" / "exports" / "customer-1" / "part-2.mat").exists()
    assert (
        "exports" not in json.loads((work / "out" / "results.json").read_text())
        or not json.loads((work / "out" / "results.json").read_text())["exports"]
    )


@pytest.mark.slow  # two runs of a study: 4-5 s
def test_a_failing_stage_costs_only_its_dependants(bench, tmp_path):
    d, _ = bench
    work = tmp_path / "work"
    shutil.copytree(d, work, ignore=shutil.ignore_patterns("out"))
    bad = STUDY.replace('outputs = ["speed:motor", "torque:part 3"]', 'outputs = ["speed:nowhere"]')
    (work / "study.toml").write_text(bad)
    lines = []
    run = run_study(work / "study.toml", work / "out", progress=lines.append)
    assert run.exit_code == 2
    (failed,) = run.failed
    assert failed.id == "frf/Customer 1" and "nowhere" in failed.error
    assert sum(s.status == "ran" for s in run.stages) == len(run.stages) - 1
    assert any("failed" in line and "nowhere" in line for line in lines)
    page = (work / "out" / "index.html").read_text()
    assert "nowhere" in page  # the report says why, in place of the section
    again = run_study(work / "study.toml", work / "out")
    assert [s.id for s in again.stages if s.status != "cached"] == ["frf/Customer 1"]  # a failure is not kept


def test_only_a_new_folder_or_this_studys_own_is_written(bench, tmp_path):
    d, _ = bench
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(ModelError, match="not empty"):
        run_study(d / "study.toml", foreign)
    assert (foreign / "notes.txt").read_text() == "mine" and len(list(foreign.iterdir())) == 1
    other = tmp_path / "other.toml"
    other.write_text('[[setup]]\nmodel = "%s"\n' % (d / "c1.toml"))
    with pytest.raises(ModelError, match="holds the run of the study"):
        run_study(other, d / "out")


def test_the_report_opens_in_a_browser_with_every_image_decoded(bench, tmp_path):
    d, _ = bench
    page = tmp_path / "index.html"
    shutil.copy(d / "out" / "index.html", page)
    # one page load: every image decoded, and the mode viewer runs (no script error, no console error,
    # no refused request; its clock ran)
    ran = page_errors(page, 1500)
    if ran is None:
        pytest.skip(NO_BROWSER)
    assert ran.startswith("errors:0 ") and "frames:-1" not in ran, ran
    assert re.search(r" broken:0 of [1-9]\d* remote:0 ", ran), ran  # and no request off the machine


def test_the_cli_prints_a_line_per_stage_and_exits_2_on_a_failure(bench, tmp_path, capsys):
    from flexshaft.cli import main

    d, _ = bench
    study = tmp_path / "s.toml"
    study.write_text(
        f'[[setup]]\nmodel = "{d / "c1.toml"}"\n[[frf]]\noutputs = ["speed:nowhere"]\n[views]\nsetups = []\n'
    )
    assert main(["study", str(study), "-o", str(tmp_path / "out")]) == 2
    out, err = capsys.readouterr()
    assert "[1/4] set-up 'c1'" in out and "study: 4 stages (3 ran, 1 failed)" in out
    (line,) = err.splitlines()  # one line per failed stage
    assert line.startswith("flexshaft: error: study stage FRF 'c1':") and "nowhere" in line
    assert main(["study", str(tmp_path / "missing.toml"), "-o", str(tmp_path / "o2")]) == 2
    assert "study file" in capsys.readouterr().err


@pytest.mark.slow
def test_the_test_bench_study_example(tmp_path):
    """examples/testbench_study.toml end to end, as the README's quick start runs it (~25 s)."""
    import subprocess
    import sys

    from flexshaft.exports.bodies import read_flexible_body

    out = tmp_path / "bench"
    cmd = [sys.executable, "-m", "flexshaft", "study", str(EXAMPLES / "testbench_study.toml"), "-o", str(out)]
    first = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    results = json.loads((out / "results.json").read_text())
    for key in (
        "provenance",
        "modes",
        "frf",
        "simulation",
        "spectra",
        "campbell",
        "calibration",
        "exports",
        "views",
    ):
        assert results[key], key
    assert set(results["modes"]) == {"Customer 1", "Without DUT", "Customer 2"}
    for setup in results["modes"]:  # every mode below the study's max_hz converged by its own check
        doc = results["modes"][setup]["parts"]
        assert doc["mesh_check"]["flagged_modes"] == [], setup

    # Damping acts on deformation only, so the line's mean speed - rigid-body motion under the same PI
    # loop - is the same under either damping assumption (a drag to ground, Rayleigh's αJ taken on the
    # rigid rotation, held the system-damped line near 18 rad/s of the 188.5 asked). The motor's mean
    # over the last 0.5 s: the elastic ringing (±0.3 rad/s there) averages out to well below 0.2 %;
    # near the set-point 1800 rpm = 188.50 rad/s within the PI loop's overshoot after the ramp, at most
    # its ramp-tracking lag J·a/kp (about 2 % at Customer 2's slower loop): 5 %.
    def late_motor_speed(run):
        data = np.loadtxt(out / run["samples_file"], delimiter=",", skiprows=1)
        head = (out / run["samples_file"]).read_text().splitlines()[0].split(",")
        late = data[:, 0] >= data[-1, 0] - 0.5
        return data[late, head.index("speed:motor [rad/s]")].mean()

    for setup, runs in results["simulation"].items():
        speeds = {v: late_motor_speed(run) for v, run in runs["speed ramp"].items()}
        assert speeds["system"] == pytest.approx(speeds["parts"], rel=2e-3), setup
        assert speeds["system"] == pytest.approx(1800 * 2 * np.pi / 60, rel=0.05), setup
    # Every CAD part's section table is in the report, row for row as in results.json.
    page = (out / "index.html").read_text()
    for setup, doc in results["parts"].items():
        for part in doc["parts"]:
            t, name = part["table"], part["name"]
            assert f"Section table of {name} ({len(t['area'])} intervals" in page, (setup, name)
            assert all(f"<td>{a:.5e}</td>" in page for a in t["area"])
    tuned = sorted(out.glob("*tuned*.toml"))
    assert tuned
    for p in tuned:
        r = subprocess.run(
            [sys.executable, "-m", "flexshaft", "modes", str(p)], capture_output=True, timeout=300
        )
        assert r.returncode == 0, r.stderr
    exported = [f for e in results["exports"]["Customer 1"].values() for f in e["files"]]
    for f in exported:
        if not f.endswith((".op4.json", ".pch.json")):
            read_flexible_body(out / f)
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0 and "nothing to do" in again.stdout
    told = page_errors(out / "index.html", 1500)  # the whole study's page: images and the viewers
    assert told is None or (told.startswith("errors:0 ") and re.search(r" broken:0 of [1-9]", told)), told
