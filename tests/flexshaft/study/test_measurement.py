"""A study from the bench's own recordings: ``[[measurement]]`` identifies the runs, writes the targets
file, calibrates the set-up to it and lists the tuned model's modes - checked against a bench whose
truth is known exactly (``recorded_bench``: its own exact simulation, not flexshaft's).

Tolerances, from what the estimators guarantee on these records (three 60 s runs at 2 kHz, ζ = 1 %):
SSI's random frequency error on one 60 s run is about √(ζ/(π·f·T)) relative, 1.5e-3 at mode 1 (22.5
Hz) and less above; the mean of three runs ~9e-4 - inside 0.3 % with over three standard deviations
to spare. The damping ratio's, 1/√(π·ζ·f·T), is 15 % per run at mode 1 (9 % for three): within 30 %.
Two stiffnesses from three frequencies: the Jacobian of the frequencies in (k2, k3) has singular
values of about 0.3 (relative to relative), so 0.1 % in the frequencies is at most ~0.5 % in them -
within 1 %.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.study.runner import run_study
from flexshaft.study.studyfile import loads_study
from flexshaft.study.tunedfile import read_targets

from . import recorded_bench as bench

STUDY = """
[study]
name = "recorded bench"
max_hz = 300.0

[[setup]]
name = "bench"
model = "bench.toml"

[views]
setups = []

[[frf]]
outputs = ["torque:part 2"]
from_hz = 1.0
to_hz = 200.0

[[measurement]]
setup = "bench"
files = ["runs/run*.*"]
channels = ["torque flange", "speed motor", "speed generator"]
stations = { "speed motor" = "motor", "speed generator" = "generator" }
parameters = [
  { name = "part 2.stiffness", percent = 30 },
  { name = "part 3.stiffness", percent = 30 },
]
"""


@pytest.fixture(scope="module")
def studied(tmp_path_factory):
    d = tmp_path_factory.mktemp("recorded")
    (d / "bench.toml").write_text(bench.model_text())
    (d / "runs").mkdir()
    bench.write_runs(d / "runs")
    (d / "study.toml").write_text(STUDY)
    run = run_study(d / "study.toml", d / "out")
    return d, run


def test_the_study_identifies_every_mode_and_recovers_the_stiffnesses(studied):
    d, run = studied
    assert run.exit_code == 0, [r.error for r in run.failed]
    doc = json.loads((d / "out" / "results.json").read_text())["measurement"]["bench"]
    assert set(doc) >= {"runs", "identified", "calibration", "tuned_modes", "targets_file"}
    assert [r["file"].rsplit(".", 1)[1] for r in doc["runs"]] == ["tdms", "mf4", "csv"]
    assert all(
        r["duration_s"] == pytest.approx(60.0, abs=1e-3) and r["rate_hz"] == 2000.0 for r in doc["runs"]
    )

    truth = bench.bench_modes()
    trusted = [m for m in doc["identified"] if m["frequency_target"]]
    f = np.array([m["frequency_hz"] for m in trusted])
    np.testing.assert_allclose(f, truth, rtol=3e-3)  # every elastic mode below max_hz, within 0.3 %
    np.testing.assert_allclose([m["damping_ratio"] for m in trusted], bench.ZETA, rtol=0.3)
    for m in trusted:
        assert set(m) >= {"frequency_std_hz", "damping_std", "mpc", "paired_mode", "mac"}
        assert m["mac"] > 0.9 and len(m["run_frequencies_hz"]) == 3
    assert [m["paired_mode"] for m in trusted] == [1, 2, 3]

    tuned = {p["name"]: p for p in doc["calibration"]["parameters"]}
    for part in ("part 2", "part 3"):
        p = tuned[f"{part}.stiffness"]
        assert p["initial"] == pytest.approx(bench.MODEL_STIFFNESS[part])
        assert p["tuned"] == pytest.approx(bench.BENCH_STIFFNESS[part], rel=0.01)
        assert p["lower"] == pytest.approx(0.7 * p["initial"]) and p["upper"] == pytest.approx(
            1.3 * p["initial"]
        )
    assert all(t["met"] for t in doc["calibration"]["targets"])
    np.testing.assert_allclose([m["frequency_hz"] for m in doc["tuned_modes"]][:3], truth, rtol=3e-3)
    # the study's FRF again on the tuned model: its largest resonance moved onto one of the bench's
    (out,) = doc["responses"][0]["outputs"]
    model_hz = [m["model_frequency_hz"] for m in trusted]
    assert min(abs(out["before"]["frequency_hz"] / f - 1) for f in model_hz) < 3e-3
    assert min(abs(out["after"]["frequency_hz"] / f - 1) for f in truth) < 3e-3

    # the files a user takes further: the targets calibrate reads, the tuned model
    tf = read_targets(d / "out" / doc["targets_file"])
    assert [t.mode for t in tf.stages[0].targets] == [1, 2, 3] and len(tf.stages[0].parameters) == 2
    assert (d / "out" / doc["tuned_model"]).is_file()
    page = (d / "out" / "index.html").read_text()
    assert "Measurement" in page and "3 trusted as targets; calibrated: 3 of 3 frequency targets met" in page


def test_an_unchanged_recording_redoes_nothing_a_changed_one_the_measurement(studied):
    d, _ = studied
    again = run_study(d / "study.toml", d / "out")
    assert {r.status for r in again.stages} == {"cached"} and not again.written
    shutil.copy(d / "runs" / "run2.mf4", d / "run2.keep")
    try:
        time, columns = bench.record(7, 60.0)  # another run recorded in its place
        import flexshaft as fs

        fs.write_measured(d / "runs" / "run2.mf4", time, columns, overwrite=True)
        changed = run_study(d / "study.toml", d / "out")
        ran = {r.id for r in changed.stages if r.status == "ran"}
        assert ran == {"measurement/bench"}, [(r.id, r.status) for r in changed.stages]
    finally:
        shutil.copy(d / "run2.keep", d / "runs" / "run2.mf4")


ENTRY = 'setup = "bench"\nfiles = ["bench.toml"]\nchannels = ["a"]\n'


def _study(tmp_path, entry: str):
    (tmp_path / "bench.toml").write_text(bench.model_text())
    text = '[[setup]]\nname = "bench"\nmodel = "bench.toml"\n\n[[measurement]]\n' + entry
    return loads_study(text, "s.toml", folder=tmp_path)


@pytest.mark.parametrize(
    ("entry", "field", "says"),
    [
        ('setup = "bench"\nfiles = ["runs/*.tdms"]\nchannels = ["a"]\n', "files", "matches no file"),
        ('setup = "other"\nfiles = ["bench.toml"]\nchannels = ["a"]\n', "setups", "no such set-up"),
        ('setup = "bench"\nfiles = ["bench.toml"]\nchannels = ["a"]\ncolour = 1\n', "colour", "unknown"),
        (ENTRY + 'parameters = [{ nme = "x" }]\n', "nme", ""),
        (ENTRY + 'parameters = [{ name = "part 2.stiffness", percent = -5 }]\n', "percent", "-5"),
    ],
)
def test_a_wrong_entry_is_one_error_naming_it(tmp_path, entry, field, says):
    with pytest.raises(ModelError) as err:
        _study(tmp_path, entry)
    text = str(err.value)
    assert field in text and says in text and "\n" not in text


def test_one_entry_per_set_up(tmp_path):
    entry = 'setup = "bench"\nfiles = ["bench.toml"]\nchannels = ["a"]\n'
    with pytest.raises(ModelError, match="measured set-up"):
        _study(tmp_path, entry + "\n[[measurement]]\n" + entry)


def test_identify_parameters_does_the_same_in_one_command(studied, tmp_path, capsys):
    """`flexshaft identify --model --parameters --tuned`: the study's [[measurement]] as one command."""
    from flexshaft.cli import main
    from flexshaft.input.modelfile import load_model

    d, _ = studied
    (tmp_path / "p.toml").write_text(
        '[[parameter]]\nname = "part 2.stiffness"\npercent = 30\n\n'
        '[[parameter]]\nname = "part 3.stiffness"\npercent = 30\n'
    )
    runs = [str(p) for p in sorted((d / "runs").glob("run*.*"))]
    channels = [a for c in ("torque flange", "speed motor", "speed generator") for a in ("--channel", c)]
    argv = [
        "identify",
        *runs,
        *channels,
        "--model",
        str(d / "bench.toml"),
        "--parameters",
        str(tmp_path / "p.toml"),
    ]
    argv += [
        "--station",
        "speed motor=motor",
        "--tuned",
        str(tmp_path / "tuned.toml"),
        "-o",
        str(tmp_path / "t.toml"),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "calibrated to the trusted targets" in out and "tuned model: " in out
    tuned = load_model(tmp_path / "tuned.toml")
    k = {c.name: c.stiffness for c in tuned.components if c.name.startswith("part")}
    for part in ("part 2", "part 3"):
        assert k[part] == pytest.approx(bench.BENCH_STIFFNESS[part], rel=0.01)
    # the targets file written is the one the study writes: calibrate runs it again
    assert read_targets(tmp_path / "t.toml").stages[0].parameters


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (["--tuned", "x.toml"], "--tuned with --parameters"),
        (["--parameters", "p.toml"], "--parameters with --model"),
    ],
)
def test_identify_parameters_needs_its_partners(tmp_path, capsys, extra, says, monkeypatch):
    from flexshaft.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.toml").write_text('[[parameter]]\nname = "part 2.stiffness"\npercent = 30\n')
    (tmp_path / "r.csv").write_text("time [s],a [N·m]\n0,1\n0.001,2\n")
    model = ["--model", "m.toml"] if "--tuned" in extra else []
    assert main(["identify", "r.csv", "--channel", "a", *model, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err


@pytest.mark.slow
def test_the_example_study_finds_the_benchs_stiffnesses_again(tmp_path):
    """examples/bench_study.toml on examples/bench_recordings.py's recordings (made here): every mode
    below 250 Hz within 0.3 % of the bench's exact ones, the damping within 30 % of its 0.53 %, every
    stiffness within 1 % of the bench's - the README's table."""
    import runpy

    from tests.conftest import EXAMPLES

    shutil.copytree(
        EXAMPLES, tmp_path / "examples", ignore=shutil.ignore_patterns("recordings", "__pycache__")
    )
    make = runpy.run_path(str(EXAMPLES / "bench_recordings.py"))["ensure_recordings"]
    manifest = make(tmp_path / "examples" / "recordings", progress=lambda line: None)
    run = run_study(tmp_path / "examples" / "bench_study.toml", tmp_path / "out")
    assert run.exit_code == 0, [r.error for r in run.failed]
    results = json.loads((tmp_path / "out" / "results.json").read_text())["measurement"]
    for setup, truth in manifest["setups"].items():
        doc = results[setup]
        exact = [f for f in truth["exact_modes_hz"] if f <= 250.0]
        found = [m for m in doc["identified"] if m["frequency_target"]]
        np.testing.assert_allclose([m["frequency_hz"] for m in found], exact, rtol=3e-3)
        np.testing.assert_allclose([m["damping_ratio"] for m in found], 0.0053, rtol=0.3)
        tuned = {p["name"]: p["tuned"] for p in doc["calibration"]["parameters"]}
        assert tuned == pytest.approx(truth["true"], rel=0.01)
