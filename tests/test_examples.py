"""Every example runs, as a script and as the documentation's gallery runs it; the Python example builds the
same chain as the model file; every example is run by the gallery or named as not run, with why."""

import ast
import importlib.util
import math
import re
import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import flexshaft as fs
from tests.conftest import EXAMPLES, ROOT, exudyn_loads, gmsh_loads

# Study files (examples/*_study.toml) name model files; every other .toml beside them is a model file.
STUDIES = sorted(EXAMPLES.glob("*_study.toml"))
MODELS = sorted(set(EXAMPLES.glob("*.toml")) - set(STUDIES))
# Slow (run by CI's second step, `pytest -m slow`): ptss_sections.py builds and slices every PTSS part
# from its solid, then round-trips part 4 through STEP and STL, all in a fresh interpreter where no
# cache helps - 10-14 s on the 2-core machine, the longest CAD run of the suite; cad_shaft.py builds,
# slices and writes one part and reads it back from STEP (~10 s).
# study_pictures.py runs the whole test-bench study (~20 s); tests/flexshaft/study covers the same
# stages on the numbers-only set-ups in the fast suite. mode_pictures.py (~6 s) meshes the CAD bench
# for its max_hz and draws through pyvista and headless Chromium; tests/flexshaft/views covers each
# picture in the fast suite. customer2_slip.py runs some 400 stepped-sine runs with a slipping coupling
# (~50 s); tests/flexshaft/analysis/test_amplitude.py covers the stepped sine in the fast suite.
# solid_testbench.py meshes the bench's PTSS parts into solids (~490 000 DOFs in all), reduces them
# and solves customer1_solid.toml's modes (~1.5 min cold; the solid extra): slow, and skipped where gmsh
# does not import. It runs the model's modal analysis itself, so test_example_model_solves leaves that
# model out rather than reduce the three solids a second time in its own process. tube.toml is one
# solid part (meshed and reduced: ~8 s cold).
SLOW_SCRIPTS = {
    "customer2_slip.py",
    "ptss_sections.py",
    "study_pictures.py",
    "mode_pictures.py",
    "solid_testbench.py",
    "cad_shaft.py",
}
SOLID = {"customer1_solid.toml", "solid_testbench.py", "tube.toml"}
SOLVED_BY_A_SCRIPT = {"customer1_solid.toml"}
# customer1_exudyn.py builds the bench in Exudyn (the multibody extra, ~5 s): skipped where that does not
# import.
MULTIBODY = {"customer1_exudyn.py"}
SCRIPT_TIMEOUT_S = {"solid_testbench.py": 1800}


def _gallery_conf():
    """docs/gallery_conf.py, the gallery's configuration (it imports nothing of Sphinx at import)."""
    spec = importlib.util.spec_from_file_location("gallery_conf", ROOT / "docs" / "gallery_conf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _files(folder) -> set:
    """Every file under ``folder`` but compiled bytecode and the recordings bench_recordings.py makes on
    first use (git-ignored: made for examples/bench_study.toml, never committed)."""
    return {p for p in folder.rglob("*") if p.is_file() and not {"__pycache__", "recordings"} & set(p.parts)}


def _marks(name: str) -> list:
    marks = [pytest.mark.slow] if name in SLOW_SCRIPTS or name in SOLID else []
    if name in SOLID:
        marks.append(pytest.mark.skipif(not gmsh_loads(), reason="gmsh does not import (the solid extra)"))
    if name in MULTIBODY:
        why = "exudyn does not import (the multibody extra)"
        marks.append(pytest.mark.skipif(not exudyn_loads(), reason=why))
    return marks


SCRIPTS = [pytest.param(s, id=s.name, marks=_marks(s.name)) for s in sorted(EXAMPLES.glob("*.py"))]


@pytest.mark.parametrize("script", SCRIPTS)
def test_example_script_runs(script, tmp_path):
    # from another folder, as `python examples/x.py` from a clone: it finds its model files beside it
    # and writes nothing into the repository (its files go to a temporary folder or the one given)
    before = _files(EXAMPLES)
    timeout = SCRIPT_TIMEOUT_S.get(script.name, 120)
    proc = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=timeout, cwd=tmp_path
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip()
    assert _files(EXAMPLES) == before
    assert not list(tmp_path.iterdir())


# The short ones (the others are the slow scripts above; the gallery's build runs them all this way).
@pytest.mark.parametrize("name", ["customer1_python.py", "run_up.py"])
def test_example_runs_as_the_gallery_runs_it(name, monkeypatch, capsys):
    # sphinx-gallery runs an example's code as __main__ without __file__ (and a notebook has none),
    # in the example's folder, with no arguments
    before = _files(EXAMPLES)
    script = EXAMPLES / name
    monkeypatch.chdir(EXAMPLES)
    monkeypatch.setattr(sys, "argv", [str(script)])
    exec(compile(script.read_text(encoding="utf-8"), str(script), "exec"), {"__name__": "__main__"})
    assert capsys.readouterr().out.strip()
    assert _files(EXAMPLES) == before


@pytest.mark.parametrize(
    "model",
    [pytest.param(m, id=m.name, marks=_marks(m.name)) for m in MODELS if m.name not in SOLVED_BY_A_SCRIPT],
)
def test_example_model_solves(model):
    # The rigid-body modes the supports allow come first at 0 Hz (a free torsion chain: its spin; the
    # 6-DOF example on three bearings: axial motion and spin), every other mode above.
    r = fs.modal_analysis(fs.load_model(model))
    n_rigid = r.model.rigid_basis.shape[1]
    assert n_rigid == (2 if r.model.dofs == "full" else 1)
    assert np.all(r.rigid[:n_rigid]) and np.all(r.frequencies_hz[:n_rigid] == 0.0)  # set, not solved for
    assert np.all(r.frequencies_hz[n_rigid:] > 0)


def test_python_example_equals_the_model_file():
    ns = runpy.run_path(str(EXAMPLES / "customer1_python.py"))
    py = fs.modal_analysis(ns["build"]())
    toml = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    # The two build the same matrices to the bit, so the same solve gives the same numbers. (Were they an
    # ulp apart, the solves' round-off - eps·λ_max/λ₁/2 = 3e-13 on f, 2e-10 on ξ₁ = 7e-5 - would need
    # tolerances to match.)
    assert py.frequencies_hz == pytest.approx(toml.frequencies_hz, rel=1e-14)
    assert py.damping_ratios == pytest.approx(toml.damping_ratios, rel=1e-12)


@pytest.mark.parametrize("study", STUDIES, ids=[s.name for s in STUDIES])
def test_example_study_reads_and_names_files_that_exist(study):
    from flexshaft.study.studyfile import read_study

    if "[[measurement]]" in study.read_text(encoding="utf-8"):  # its recordings are made on first use
        runpy.run_path(str(EXAMPLES / "bench_recordings.py"))["ensure_recordings"](progress=lambda line: None)
    s = read_study(study)
    assert all(Path(f).is_file() for m in s.measurements for f in m.files)
    assert s.setups and all(setup.model.is_file() for setup in s.setups)
    assert s.calibration is None or s.calibration.targets.is_file()


# --- the model files the docs use -----------------------------------------------------------------------


def test_the_stepped_shaft_is_its_two_sections_in_series():
    # closed form: 1/k = Σ L/(G·J), J = π d⁴/32 of each solid section (250 mm at 200 mm, 250 mm at
    # 120 mm); linear torsion elements on uniform intervals are exact in statics, so to the solve's
    # round-off
    g = fs.STEEL.G
    k = 1.0 / sum(length / (g * math.pi * d**4 / 32) for length, d in ((0.25, 0.2), (0.25, 0.12)))
    (part,) = fs.twist_test(fs.load_model(EXAMPLES / "step.toml")).parts
    assert part.stiffness == pytest.approx(k, rel=1e-9)


@pytest.mark.slow
@pytest.mark.skipif(not gmsh_loads(), reason="gmsh does not import (the solid extra)")
def test_the_solid_tube_meets_its_closed_form():
    # G·J/L of the tube (OD 200, ID 80, 500 mm): the solid's mesh is stiffer than the solid it meshes
    # (conforming elements), so from above, within the 0.5 % the README quotes (+1.1e-4)
    g, (od, bore, length) = fs.STEEL.G, (0.2, 0.08, 0.5)
    gj_l = g * math.pi * (od**4 - bore**4) / 32 / length
    (part,) = fs.twist_test(fs.load_model(EXAMPLES / "tube.toml")).parts
    assert gj_l <= part.stiffness <= 1.005 * gj_l


@pytest.mark.slow
def test_the_cad_example_runs_again_into_the_same_folder(tmp_path):
    # it writes its STEP, STL and model file with overwrite=True: a second run into the same folder works
    for _ in range(2):
        proc = subprocess.run(
            [sys.executable, str(EXAMPLES / "cad_shaft.py"), str(tmp_path)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert proc.returncode == 0, proc.stderr
    assert {p.name for p in tmp_path.iterdir()} == {
        "my_shaft.step",
        "my_shaft.stl",
        "my_shaft.toml",
        "my_shaft_mode1.png",
    }


# --- the gallery ------------------------------------------------------------------------------------------

GALLERY_SCRIPTS = sorted(EXAMPLES.glob("*.py"))


def test_every_example_is_run_by_the_gallery_or_named_as_not_run():
    conf = _gallery_conf()
    pattern = conf.sphinx_gallery_conf["filename_pattern"]
    names = {s.name for s in GALLERY_SCRIPTS}
    assert set(conf.NOT_EXECUTED) <= names, "NOT_EXECUTED names an example that is not there"
    for script in GALLERY_SCRIPTS:
        run = re.search(pattern, str(script)) is not None  # as sphinx-gallery matches: the full path
        assert run != (script.name in conf.NOT_EXECUTED), script.name
    assert all(len(why) > 20 for why in conf.NOT_EXECUTED.values())


@pytest.mark.parametrize("script", GALLERY_SCRIPTS, ids=[s.name for s in GALLERY_SCRIPTS])
def test_example_is_a_gallery_page(script):
    text = script.read_text(encoding="utf-8")
    doc = ast.get_docstring(ast.parse(text), clean=False)
    assert doc is not None and text.lstrip().startswith('"""'), "the module docstring comes first"
    title, underline = doc.strip().splitlines()[:2]
    assert underline == "=" * len(underline) and len(underline) >= len(title), "an RST title first"
    assert "\n# %%\n" in text, "cells: text between the code"
    if script.name in _gallery_conf().NOT_EXECUTED:
        assert "Not run when these pages are built" in doc, "says why it is not run, and how long it takes"
    else:
        assert "# sphinx_gallery_thumbnail_number = " in text
    # every model file of examples/ the code names is downloadable from its page
    named = set(re.findall(r'"([\w/]+\.toml)"', text.replace(doc, "")))
    downloads = set(re.findall(r":download:`[^<`]*<\.\./\.\./examples/([\w/]+\.toml)>`", doc))
    assert {n for n in named if (EXAMPLES / n).is_file()} <= downloads
    assert all((EXAMPLES / d).is_file() for d in downloads)
