"""The asymptotic mesh-error estimate against a fine-mesh reference, and meshes chosen from max_hz."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.convergence import mesh_convergence, mesh_for_range
from flexshaft.analysis.modal import modal_analysis
from flexshaft.model.assembly import assemble
from flexshaft.sections.table import table_from_segments
from tests.conftest import EXAMPLES

SETUPS = ("customer1", "without_dut", "customer2")
#: Elements per shaft of the reference solve. Linear elements converge as h², so its own error is
#: about (1/256)² = 1.5e-5 of a one-element shaft's (the worst, Customer 1 mode 4 at 53 %, is off
#: by under 1e-5 relative): negligible beside the 20 % the estimate is held to.
REFERENCE_ELEMENTS = 256


def _uniform(d: fs.Drivetrain, n: int) -> fs.Drivetrain:
    comps = tuple(dataclasses.replace(c, elements=n) if c.type == "shaft" else c for c in d.components)
    return dataclasses.replace(d, components=comps)


def _reference(d: fs.Drivetrain, count: int) -> np.ndarray:
    mdl = assemble(_uniform(d, REFERENCE_ELEMENTS), damping=False)
    return modal_analysis(mdl, count, damped=False).frequencies_hz


@pytest.mark.parametrize("name", SETUPS)
def test_estimate_matches_the_true_error_within_a_fifth(name):
    # The three set-ups as the study gives them, one element per shaft: the old one-step estimate
    # told 4.5 % for Customer 1 mode 3 (true 9.7 %), 4.9 % for Without DUT mode 2 (10.4 %), 2.6 %
    # for Customer 2 mode 4 (5.4 %). The two-refinement estimate must be within 20 % of the truth.
    d = fs.load_model(EXAMPLES / f"{name}.toml")
    r = fs.modal_analysis(d)
    mc = mesh_convergence(r)
    assert mc.asymptotic and mc.levels == (1, 2, 4)
    ref = _reference(d, r.count)
    elastic = ~r.rigid
    true = np.abs(r.frequencies_hz[elastic] - ref[elastic]) / ref[elastic]
    est = mc.error[elastic]
    big = true > 0.005
    assert big.any()
    assert np.all(np.abs(est[big] - true[big]) <= 0.2 * true[big]), (est[big], true[big])
    # the modes of the numbers
    worst = {"customer1": 3, "without_dut": 2, "customer2": 4}[name]
    k = worst - int(np.count_nonzero(r.rigid[:worst]))
    assert true[k] > 0.05 and mc.error[worst] > 0.05


def test_estimate_falls_back_honestly_over_a_ceiling(monkeypatch):
    # The h/4 mesh over the elements ceiling: one Richardson step, and the result says so.
    monkeypatch.setenv("FLEXSHAFT_MAX_ELEMENTS", "3")
    d = fs.load_model(EXAMPLES / "customer1.toml")
    mc = mesh_convergence(fs.modal_analysis(d))
    assert not mc.asymptotic and mc.levels == (1, 2) and mc.finest_hz is None
    assert "ceiling" in mc.note and "ceiling" in mc.method


def test_no_max_hz_leaves_the_drivetrain_as_it_is():
    d = fs.load_model(EXAMPLES / "customer1.toml")
    assert d.max_hz is None
    choice = mesh_for_range(d)
    assert choice.drivetrain is d and choice.convergence is None and choice.converged


@pytest.mark.parametrize("name", SETUPS)
def test_max_hz_meshes_every_mode_below_it_within_one_percent(name):
    d = fs.load_model(EXAMPLES / f"{name}.toml")
    max_hz = 400.0
    choice = mesh_for_range(d, max_hz)
    assert choice.converged, choice.message
    assert choice.drivetrain.max_hz == max_hz
    r = fs.modal_analysis(choice.drivetrain)
    below = (r.frequencies_hz <= max_hz) & ~r.rigid
    assert below.sum() >= 2
    ref = _reference(d, r.count)
    err = np.abs(r.frequencies_hz[below] - ref[below]) / ref[below]
    assert np.all(err <= 0.01), err
    assert np.all(choice.convergence.error <= 0.01)  # by its own check as well


def _steel_rod(length: float, od: float, **kw) -> fs.Shaft:
    table = table_from_segments([{"length": length, "od": od}], nu=fs.STEEL.nu, name="rod")
    return fs.Shaft.from_sections("rod", table, fs.STEEL, **kw)


def test_segments_shaft_torsion_against_the_closed_form():
    # A uniform free-free shaft: f_n = n·c/(2L), c = √(G/ρ) (Timoshenko & Goodier; any vibration text).
    L = 2.0
    rod = _steel_rod(L, 0.1)
    max_hz = 5000.0
    choice = mesh_for_range(fs.Drivetrain("rod", [rod]), max_hz)
    assert choice.converged and choice.fixed == ()
    r = fs.modal_analysis(choice.drivetrain, 12)
    c = np.sqrt(fs.STEEL.G / fs.STEEL.rho)
    f = r.frequencies_hz[~r.rigid]
    exact = np.arange(1, f.size + 1) * c / (2 * L)
    below = exact <= max_hz
    assert below.sum() == 6
    assert np.all(np.abs(f[below] - exact[below]) / exact[below] <= 0.01)


def test_segments_shaft_bending_against_euler_bernoulli():
    # A slender free-free round shaft, dofs = "full": bending f_n = (β_nL)²/(2πL²)·√(EI/(ρA)) with
    # cos βL·cosh βL = 1 (Blevins, Formulas for Natural Frequency and Mode Shape, table 8-1). Shear
    # and rotary inertia (Timoshenko) lower mode n by about ½(r_g·β_n)²(1 + E/(k·G)) relative, r_g the
    # radius of gyration: allowed on top of the 1 %.
    L, d = 4.0, 0.02
    rod = _steel_rod(L, d)
    max_hz = 110.0
    choice = mesh_for_range(fs.Drivetrain("rod", [rod], dofs="full"), max_hz)
    assert choice.converged, choice.message
    r = fs.modal_analysis(choice.drivetrain, 24)
    beta_l = np.array([4.730040745, 7.853204624, 10.995607838, 14.137165491, 17.278759657, 20.420352245])
    E, rho = fs.STEEL.E, fs.STEEL.rho
    area, inertia = np.pi * d**2 / 4, np.pi * d**4 / 64
    exact = beta_l**2 / (2 * np.pi * L**2) * np.sqrt(E * inertia / (rho * area))
    lateral = np.array([k == "lateral" for k in r.kinds]) & ~r.rigid
    f = r.frequencies_hz[lateral]
    f = f[f <= max_hz]
    assert f.size == 2 * exact.size  # each in two planes
    rg2 = inertia / area
    shear = 0.5 * rg2 * (beta_l / L) ** 2 * (1 + E / (0.9 * fs.STEEL.G))
    assert np.all(np.abs(f[::2] - exact) / exact <= 0.01 + shear)
    assert np.all(np.abs(f[1::2] - exact) / exact <= 0.01 + shear)


def test_a_mesh_the_file_fixes_is_left_as_given():
    text = (
        (EXAMPLES / "customer1.toml")
        .read_text()
        .replace('name = "part 2"\ntype = "shaft"', 'name = "part 2"\ntype = "shaft"\nelements = 1')
    )
    d = fs.loads_model(text)
    assert d.component("part 2").fixed_mesh and not d.component("part 1").fixed_mesh
    choice = mesh_for_range(d, 400.0)
    assert choice.drivetrain.component("part 2").elements == 1 and choice.fixed == ("part 2",)
    assert not choice.converged and "fixes" in choice.message and "part 2" in choice.message


def test_max_hz_in_the_model_file():
    text = (
        (EXAMPLES / "without_dut.toml")
        .read_text()
        .replace('inertia_model = "consistent"', 'inertia_model = "consistent"\nmax_hz = "0.3 kHz"')
    )
    d = fs.loads_model(text)
    assert d.max_hz == pytest.approx(300.0)
    assert mesh_for_range(d).converged
    with pytest.raises(fs.ModelError, match="max_hz"):
        fs.loads_model(text.replace('"0.3 kHz"', "-1"))


def test_cad_example_converged_by_its_own_check():
    # The flagship CAD example: every mode below 400 Hz within 1 % by its own (two-refinement) check.
    d = fs.load_model(EXAMPLES / "customer1_cad.toml")
    choice = mesh_for_range(d, 400.0)
    assert choice.converged, choice.message
    assert choice.convergence.asymptotic and choice.convergence.flagged.size == 0
    # the check covered every mode up to 400 Hz, and only those
    r = fs.modal_analysis(assemble(choice.drivetrain, damping=False), 12, damped=False)
    n_below = int(np.count_nonzero(r.frequencies_hz <= 400.0))
    assert choice.convergence.error.size == n_below >= 4
