"""simulate checks its results before anyone reads them: a speed loop stable at its sample rate (proved
against the Jury criterion of a rigid inertia under the discrete PI), inputs below the Nyquist
frequency, enough samples, amplitudes whose response stays in floating point, finite outputs."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.discreteloop import loop_form as _loop_form
from flexshaft.analysis.discreteloop import zoh as _zoh
from flexshaft.analysis.simulate import (
    MAX_TORQUE,
    MIN_SAMPLES,
    STABILITY_TOLERANCE,
    Scenario,
    SpeedControl,
    _check_finite,
    _loop_growth,
    simulate,
)
from flexshaft.analysis.statespace import state_space
from flexshaft.cli import main
from flexshaft.model.components import Drivetrain, Rigid, Shaft
from tests.conftest import EXAMPLES

J1, J2 = 2.0, 1.0
J = J1 + J2  # the line's inertia, as its rigid-body mode sees it
RATE = 1000.0
DT = 1.0 / RATE


@pytest.fixture(scope="module")
def rigid():
    """Two inertias on a shaft so stiff (6.2 kHz) that a 1 kHz run drops its mode (the default cut at
    the rate): the plant is the rigid inertia J = J1 + J2 alone, exactly (zero-order hold of 1/(J s))."""
    d = Drivetrain("stiff", (Rigid("a", J1), Shaft("s", stiffness=1e9, inertia=0.0), Rigid("b", J2)))
    return fs.modal_analysis(d)


@pytest.fixture(scope="module")
def plant(rigid):
    ss = state_space(rigid, ["a", "b"], ["speed:a"], max_hz=RATE)
    assert ss.A.shape == (2, 2)  # the rigid mode only: angle and speed
    Ad, Bd = _zoh(ss.A, ss.B, DT)
    return Ad, Bd, ss.C


# --- the discrete PI on a rigid inertia, by hand -------------------------------------------------------
# ω_{k+1} = ω_k + (dt/J)·u_k, u_k = −kp·ω_k + I_k, I_{k+1} = I_k − ki·dt·ω_k: with a = kp·dt/J and
# b = ki·dt²/J the loop's characteristic polynomial is z² − (2 − a)·z + (1 − a + b). Jury's criterion
# for a second-order polynomial z² + a1·z + a0 (|a0| < 1, 1 + a1 + a0 > 0, 1 − a1 + a0 > 0) gives
#   b > 0,  b < a  (ki·dt < kp),  a < 2 + b/2  (kp < 2J/dt + ki·dt/2);
# so without integral action kp < 2J/dt, with kp = J/dt the limit is ki < kp/dt, and the tuned gains
# kp = J·ω_c, ki = J·ω_c²/5 (x = ω_c·dt: a = x, b = x²/5) are stable while x²/10 − x + 2 > 0 and x < 5,
# i.e. x < 5 − √5: a bandwidth below (5 − √5)/(2π·dt), 0.44 times the rate.
KP_MAX = 2 * J / DT
BW_MAX = (5 - math.sqrt(5)) / (2 * math.pi * DT)


def _poles(kp, ki):
    a, b = kp * DT / J, ki * DT * DT / J
    return np.roots([1.0, -(2.0 - a), 1.0 - a + b])


def _control(kp, ki):
    return SpeedControl(kp, ki, measure="speed:a")


@pytest.mark.parametrize(
    "kp,ki", [(0.3 * KP_MAX, 100.0), (0.9 * KP_MAX, 1e5), (1.2 * KP_MAX, 10.0), (1e3, 2e6)]
)
def test_the_loop_matrix_has_the_closed_form_poles(plant, kp, ki):
    F = _loop_form(*plant, kp, ki, 0.0, DT, held=False)[0]
    lam = np.linalg.eigvals(F)
    # the angle (an accumulator, z = 1) and the unused low-pass state (z = 0) besides the loop's two
    expected = np.concatenate([_poles(kp, ki), [1.0, 0.0]])
    # a 4x4 eigenproblem of entries O(1) (a ≤ 2.4, b ≤ 2): round-off ~1e-15; 1e-9 leaves room for the
    # two poles meeting as a double root (√eps splitting)
    assert np.sort_complex(lam) == pytest.approx(np.sort_complex(expected), abs=1e-9)
    assert _loop_growth(*plant, _control(kp, ki), DT) == pytest.approx(
        np.max(np.abs(_poles(kp, ki))), abs=1e-9
    )


def test_the_stability_boundary_is_jury_s(plant):
    limit = 1.0 + STABILITY_TOLERANCE
    ctl = _control(1.0, 0.0)
    # 1e-4 either side of the boundary moves the critical pole by ~1e-4, far beyond the √eps tolerance
    assert _loop_growth(*plant, ctl, DT, kp=(1 - 1e-4) * KP_MAX, ki=0.0) <= limit
    assert _loop_growth(*plant, ctl, DT, kp=(1 + 1e-4) * KP_MAX, ki=0.0) > limit
    kp = J / DT
    assert _loop_growth(*plant, ctl, DT, kp=kp, ki=(1 - 1e-4) * kp / DT) <= limit
    assert _loop_growth(*plant, ctl, DT, kp=kp, ki=(1 + 1e-4) * kp / DT) > limit


def _limit(err) -> float:
    """The largest stable value an error reports ("up to X ...")."""
    return float(re.search(r"up to ([0-9.e+-]+)", err.valid).group(1))


def _refused(result, control, field):
    sc = Scenario.ramp(100.0, 0.05, control)
    with pytest.raises(fs.ModelError) as info:
        simulate(result, sc, ["speed:a"], rate=RATE, duration=0.1)
    assert info.value.field == field, str(info.value)
    assert "unstable" in info.value.message
    return info.value


def test_an_unstable_kp_is_refused_with_jury_s_limit(rigid):
    err = _refused(rigid, _control(3 * KP_MAX, 0.0), "kp")
    # the bisection's limit (to 1e-9) rounded down to 4 digits: at most 1e-3 below the exact one, never above
    assert KP_MAX * (1 - 1e-3) <= _limit(err) <= KP_MAX


def test_an_unstable_ki_is_refused_with_jury_s_limit(rigid):
    kp = J / DT
    err = _refused(rigid, _control(kp, 5 * kp / DT), "ki")
    assert kp / DT * (1 - 1e-3) <= _limit(err) <= kp / DT


def test_an_unstable_bandwidth_is_refused_with_jury_s_limit(rigid):
    err = _refused(rigid, SpeedControl.tuned(rigid, bandwidth_hz=2 * BW_MAX, measure="speed:a"), "bandwidth")
    assert BW_MAX * (1 - 1e-3) <= _limit(err) <= BW_MAX
    # just inside, the loop runs and settles on the set-point: every sample a number
    ok = SpeedControl.tuned(rigid, bandwidth_hz=0.99 * BW_MAX, measure="speed:a")
    run = simulate(rigid, Scenario.ramp(100.0, 0.05, ok), ["speed:a"], rate=RATE, duration=0.5)
    assert np.all(np.isfinite(run.outputs["speed:a"]))


def test_a_loop_unstable_only_through_an_aliased_undamped_mode_says_so():
    # Undamped two inertias with their mode at 700 Hz: above the 500 Hz Nyquist frequency of a 1 kHz loop
    # (kept by the default cut at the rate), which sees it aliased and late and drives it unstable; the
    # same loop on the modes below 500 Hz is stable, and the error says to drop the others.
    je = J1 * J2 / J
    k = (2 * math.pi * 700.0) ** 2 * je
    d = Drivetrain("undamped", (Rigid("a", J1), Shaft("s", stiffness=k, inertia=0.0), Rigid("b", J2)))
    r = fs.modal_analysis(d)
    ctl = SpeedControl.tuned(r, bandwidth_hz=5.0, measure="speed:a")
    err = _refused(r, ctl, "bandwidth")
    assert "max_hz below 500 Hz" in err.valid
    run = simulate(r, Scenario.ramp(100.0, 0.05, ctl), ["speed:a"], rate=RATE, duration=0.1, max_hz=400.0)
    assert np.all(np.isfinite(run.outputs["speed:a"]))


def test_nothing_is_written_for_an_unstable_loop(tmp_path, capsys):
    out = tmp_path / "run.csv"
    args = ["simulate", str(EXAMPLES / "customer1.toml"), "--scenario", "ramp", "--end-speed", "100"]
    args += ["--ramp-time", "0.2", "--duration", "0.3", "--measure", "speed:motor", "--bandwidth", "1e6"]
    assert main([*args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--bandwidth" in err and "unstable" in err and "valid: up to" in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


# --- inputs the samples can carry -----------------------------------------------------------------------


def test_a_sine_at_or_above_nyquist_is_refused(rigid):
    for f in (RATE / 2, 5 * RATE):
        with pytest.raises(fs.ModelError, match="Nyquist") as info:
            simulate(rigid, Scenario.sine(1.0, f), ["speed:a"], rate=RATE, duration=0.1)
        assert info.value.field == "frequency"
    run = simulate(rigid, Scenario.sine(1.0, 0.49 * RATE), ["speed:a"], rate=RATE, duration=0.1)
    assert np.all(np.isfinite(run.outputs["speed:a"]))


def test_a_ripple_above_nyquist_is_refused(rigid):
    # order 6 at 6000 rpm: 600 Hz, above the 500 Hz Nyquist frequency of a 1 kHz run
    sc = Scenario("coast", torque=10.0, speed_rpm=6000.0, ripple=1.0, ripple_order=6.0)
    with pytest.raises(fs.ModelError, match="Nyquist") as info:
        simulate(rigid, sc, ["speed:a"], rate=RATE, duration=0.1)
    assert info.value.field == "ripple_order"
    sc = Scenario("coast", torque=10.0, speed_rpm=4000.0, ripple=1.0, ripple_order=6.0)  # 400 Hz
    assert np.all(np.isfinite(simulate(rigid, sc, ["speed:a"], rate=RATE, duration=0.1).outputs["speed:a"]))


def test_a_torque_history_sampled_finer_than_the_step_is_refused(rigid):
    t = np.arange(1001) / 10_000.0
    with pytest.raises(fs.ModelError, match="finer than the run's step") as info:
        simulate(
            rigid, Scenario.from_series(t, np.sin(2 * np.pi * 3000 * t)), ["speed:a"], rate=RATE, duration=0.1
        )
    assert info.value.field == "series" and "10000 Hz" in info.value.valid
    # at the rate itself (decimal time stamps: steps within 1e-6 of it) and coarser: interpolated
    for step in (DT, 5 * DT):
        t = np.round(np.arange(0.0, 0.1, step), 6)
        run = simulate(rigid, Scenario.from_series(t, 10.0 + 0 * t), ["speed:a"], rate=RATE, duration=0.1)
        assert np.all(np.isfinite(run.outputs["speed:a"]))


# --- enough samples, amplitudes that stay numbers, finite outputs -----------------------------------------


def test_a_run_holds_at_least_min_samples(rigid):
    sc = Scenario.step(1.0)
    with pytest.raises(fs.ModelError, match="sample") as info:
        simulate(rigid, sc, ["speed:a"], rate=RATE, duration=(MIN_SAMPLES - 2) / RATE)
    assert info.value.field == "duration" and f"{(MIN_SAMPLES - 1) / RATE:g} s" in info.value.valid
    with pytest.raises(fs.ModelError) as info:
        simulate(rigid, sc, ["speed:a"], rate=0.001)  # the default 10 s: one sample
    assert info.value.field == "rate"
    run = simulate(rigid, sc, ["speed:a"], rate=RATE, duration=(MIN_SAMPLES - 1) / RATE)
    assert run.time.size == MIN_SAMPLES
    with pytest.raises(fs.ModelError, match="beyond count") as info:
        simulate(rigid, sc, ["speed:a"], rate=1e6, duration=1e305)
    assert info.value.field == "duration"


@pytest.mark.parametrize(
    "make,field",
    [
        (lambda: Scenario.step(1.01 * MAX_TORQUE), "torque"),
        (lambda: Scenario.sine(-1e308, 10.0), "torque"),
        (lambda: Scenario.step(1.0, load=-1e300), "load"),
        (lambda: Scenario.coast(1.0, speed_rpm=1e300), "speed"),
        (lambda: Scenario.from_series([0.0, 1.0], [0.0, 1e308]), "series"),
        (lambda: Scenario("coast", noise=1e300), "noise"),
    ],
)
def test_amplitudes_beyond_the_ceiling_are_refused(make, field):
    with pytest.raises(fs.ModelError) as info:
        make()
    assert info.value.field == field


def test_the_largest_torque_gives_finite_outputs(rigid):
    # 1e12 N·m for 10 s on 3 kg·m²: the angle T·t²/(2J) = 1.7e13 rad, far inside floating point
    run = simulate(rigid, Scenario.step(MAX_TORQUE), ["angle:a", "torque:s"], rate=RATE, duration=10.0)
    assert all(np.all(np.isfinite(y)) for y in run.outputs.values())
    assert run.outputs["angle:a"][-1] == pytest.approx(MAX_TORQUE * 10.0**2 / (2 * J), rel=1e-3)


def test_an_output_that_left_floating_point_is_named_with_its_time():
    t = np.arange(5) * 0.01
    _check_finite("speed:a", np.ones(5), t)
    with pytest.raises(fs.ModelError, match=r"from t = 0.03 s on \(sample 3\)") as info:
        _check_finite("speed:a", np.array([0.0, 1.0, 2.0, np.inf, np.nan]), t)
    assert info.value.field == "speed:a"
