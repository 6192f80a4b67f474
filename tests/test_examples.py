"""Every example runs, and the Python example builds the same chain as the model file."""

import runpy
import subprocess
import sys

import numpy as np
import pytest

import flexshaft as fs
from tests.conftest import EXAMPLES, gmsh_loads

# Study files (examples/*_study.toml) name model files; every other .toml beside them is a model file.
STUDIES = sorted(EXAMPLES.glob("*_study.toml"))
MODELS = sorted(set(EXAMPLES.glob("*.toml")) - set(STUDIES))
# Slow (run by CI's second step, `pytest -m slow`): ptss_sections.py builds and slices every PTSS part
# from its solid, then round-trips part 4 through STEP and STL, all in a fresh interpreter where no
# cache helps - 10-14 s on the 2-core machine, the longest CAD run of the suite.
# study_pictures.py runs the whole test-bench study (~20 s); tests/flexshaft/study covers the same
# stages on the numbers-only set-ups in the fast suite. mode_pictures.py (~6 s) meshes the CAD bench
# for its max_hz and draws through pyvista and headless Chromium; tests/flexshaft/views covers each
# picture in the fast suite.
# solid_testbench.py meshes the bench's PTSS parts into solids (~490 000 DOFs in all), reduces them
# and solves customer1_solid.toml's modes (~1.5 min cold; the solid extra): slow, and skipped where gmsh
# does not import. It runs the model's modal analysis itself, so test_example_model_solves leaves that
# model out rather than reduce the three solids a second time in its own process.
SLOW_SCRIPTS = {"ptss_sections.py", "study_pictures.py", "mode_pictures.py", "solid_testbench.py"}
SOLID = {"customer1_solid.toml", "solid_testbench.py"}
SOLVED_BY_A_SCRIPT = {"customer1_solid.toml"}
SCRIPT_TIMEOUT_S = {"solid_testbench.py": 1800}


def _marks(name: str) -> list:
    marks = [pytest.mark.slow] if name in SLOW_SCRIPTS or name in SOLID else []
    if name in SOLID:
        marks.append(pytest.mark.skipif(not gmsh_loads(), reason="gmsh does not import (the solid extra)"))
    return marks


SCRIPTS = [pytest.param(s, id=s.name, marks=_marks(s.name)) for s in sorted(EXAMPLES.glob("*.py"))]


@pytest.mark.parametrize("script", SCRIPTS)
def test_example_script_runs(script):
    timeout = SCRIPT_TIMEOUT_S.get(script.name, 120)
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip()


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

    s = read_study(study)
    assert s.setups and all(setup.model.is_file() for setup in s.setups)
    assert s.calibration is None or s.calibration.targets.is_file()
