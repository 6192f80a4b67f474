"""Numerical guards: no mode is returned that the arithmetic does not resolve, and none goes missing."""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import MAX_BACKWARD_ERROR, MAX_SPREAD


def test_an_inertia_far_out_of_scale_is_refused_naming_it():
    # 1e-30 kg·m² beside 1e6: K/M spans 1e36 > 1e14, the lowest modes would be round-off.
    d = fs.Drivetrain("a", [fs.Rigid("m", 1e6), fs.Shaft("s", 1e5, 0.0), fs.Rigid("g", 1e-30)])
    with pytest.raises(fs.ModelError, match=r"spans 1e\+36, from 's' on the inertia of 'g'"):
        fs.modal_analysis(d)


@pytest.mark.parametrize(
    "comp, field",
    [(fs.Shaft("s", 1e308, 1.0), "stiffness"), (fs.Shaft("s", 1e5, 1.0, damping=1e308), "damping")],
)
def test_numbers_that_overflow_are_refused_not_printed(comp, field):
    # A stiffness of 1e308 N·m/rad gives ω² beyond double precision; a damper of 1e308 overflows the
    # damped problem: either is an error, never a NaN or 1e153 Hz "mode".
    d = fs.Drivetrain("b", [fs.Rigid("m", 1.0), comp, fs.Rigid("g", 1.0)])
    with pytest.raises(fs.ModelError) as err:
        fs.modal_analysis(d)
    assert err.value.field == field


def test_every_returned_mode_passes_the_residual_check_and_none_goes_missing():
    d = fs.load_model("examples/customer1.toml")
    r = fs.modal_analysis(d)
    K, M = r.model.K, r.model.M
    lam = r.omega**2
    res = np.linalg.norm(K @ r.shapes - (M @ r.shapes) * lam, axis=0)
    scale = (abs(K).sum(axis=0).max() + lam * abs(M).sum(axis=0).max()) * np.linalg.norm(r.shapes, axis=0)
    assert np.all(res <= MAX_BACKWARD_ERROR * scale)
    assert np.all(np.isfinite(r.damping_ratios))
    with pytest.raises(fs.ModelError, match="count = 6: the model has only 5 DOFs"):
        fs.modal_analysis(d, 6)


def test_the_guards_leave_real_models_alone():
    # The spread of the shipped examples is 2e2 to 2e5, far inside 1e14.
    assert MAX_SPREAD >= 1e12
    for name in ("customer1", "customer2", "without_dut", "customer1_flex"):
        r = fs.modal_analysis(fs.load_model(f"examples/{name}.toml"))
        assert np.all(np.isfinite(r.frequencies_hz)) and np.all(np.isfinite(r.damping_ratios))
