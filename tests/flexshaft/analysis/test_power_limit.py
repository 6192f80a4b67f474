"""The drive's power limit in the speed loop: above its base speed the motor gives at most P/|ω|."""

import numpy as np
import pytest

from flexshaft import ModelError
from flexshaft.analysis.modal import modal_analysis
from flexshaft.analysis.simulate import Scenario, SpeedControl, simulate
from flexshaft.model.assembly import assemble
from flexshaft.model.components import Coupling, Drivetrain, Rigid

P, T_MAX = 50e3, 2000.0  # W, N·m: base speed P/T_MAX = 25 rad/s (239 rpm)
OUTS = ["speed:motor", "control:torque", "torque:c"]


def _line(**kw):
    chain = (Rigid("motor", 50.0), Coupling("c", 4e4, damping=20.0, **kw), Rigid("g", 30.0))
    return modal_analysis(assemble(Drivetrain("two", chain)))


def _run(result, **kw):
    ctl = SpeedControl.tuned(result, torque_min=-T_MAX, torque_max=T_MAX, power_limit=P)
    return simulate(result, Scenario.ramp(1500.0, 5.0, ctl), OUTS, rate=1000.0, duration=8.0, **kw)


def test_the_drive_gives_at_most_its_power_and_its_torque():
    run = _run(_line())
    torque, speed = run.outputs["control:torque"], run.outputs["speed:motor"]
    power = torque * speed
    # the clamp is P/|ω_k| at the sample's own speed, so T·ω is P to round-off where it holds
    assert power.max() == pytest.approx(P, rel=1e-12)
    held = np.abs(power - P) < 1e-9 * P
    assert held.sum() > 1000 and np.all(speed[held] >= P / T_MAX * (1 - 1e-12))
    assert torque.max() == T_MAX  # below the base speed the torque limit holds
    assert np.all(np.abs(torque) <= np.minimum(T_MAX, P / np.maximum(np.abs(speed), 1e-300)) * (1 + 1e-12))
    assert "power limit" in run.method


def test_a_coupling_that_never_slips_runs_the_same_loop():
    """The nonlinear run's clamp (per sample, on its own forms) against the linear stepped law."""
    linear, sticking = _run(_line()), _run(_line(slip_torque=1e9))
    assert sticking.nonlinear.event_count == 0
    for name in OUTS:
        ref = linear.outputs[name]
        # two arithmetic routes (Schur recursion vs the plant's own matrices) over 8000 steps
        np.testing.assert_allclose(sticking.outputs[name], ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_bad_power_limit():
    with pytest.raises(ModelError) as err:
        SpeedControl(1.0, 1.0, power_limit=-5.0)
    assert err.value.field == "power_limit"
    with pytest.raises(ModelError) as err:
        Scenario.of("step", {"power_limit": 1e3}, _line())
    assert err.value.field == "power_limit"
