"""Nonlinear time runs against closed forms nobody here wrote: Coulomb friction's linear amplitude
decay, stick-slip of two inertias under a constant drive, the free-play oscillator's period, a
static ramp along a stiffness curve, and the energy balance; the vectorised run against the same
equations stepped one sample at a time."""

import math

import numpy as np
import pytest

from flexshaft import ModelError as fs_error
from flexshaft.analysis.modal import modal_analysis
from flexshaft.analysis.simulate import Scenario, SpeedControl, simulate
from flexshaft.model.assembly import assemble
from flexshaft.model.components import Coupling, Drivetrain, Rigid

RATE = 1000.0
DT = 1.0 / RATE


def _modes(*components):
    return modal_analysis(assemble(Drivetrain("nonlinear", components)))


def _pulse(speed: float, inertia: float, at: str) -> Scenario:
    """A torque held over the first step only: the inertia leaves at ``speed`` (rad/s)."""
    return Scenario.from_series([0.0, DT], [speed * inertia / DT, 0.0], at=at)


# --- Coulomb friction, one DOF ------------------------------------------------------------------
# An inertia J on a spring k to ground, with a friction torque T_f to ground: each half cycle loses
# 2·T_f/k of amplitude (4·T_f/k a cycle) and the motion stops inside |θ| <= T_f/k (den Hartog).
# Ground is an inertia 10⁵ J on each side (its motion is 1e-5 of J's); the friction face is a
# slipping coupling to it whose own spring is 10⁴ k (stuck, J barely moves while the spring turns).
J, K, T_F = 1.0, 100.0, 0.5
GROUND = 1e5 * J
K_FACE = 1e4 * K


@pytest.fixture(scope="module")
def coulomb():
    res = _modes(
        Rigid("ground 1", GROUND),
        Coupling("spring", K),
        Rigid("mass", J),
        Coupling("face", K_FACE, slip_torque=T_F),
        Rigid("ground 2", GROUND),
    )
    outs = [
        "angle:mass",
        "angle:ground 1",
        "angle:ground 2",
        "speed:mass",
        "speed:ground 1",
        "speed:ground 2",
    ]
    outs += ["torque:face", "torque:spring"]
    return simulate(res, _pulse(1.0, J, "mass"), outs, rate=RATE, duration=12.0)


def test_coulomb_friction_loses_2_tf_over_k_per_half_cycle(coulomb):
    theta = coulomb.outputs["angle:mass"] - coulomb.outputs["angle:ground 1"]
    turning = np.flatnonzero(np.diff(np.sign(np.diff(theta))) != 0) + 1
    amplitude = np.abs(theta[turning])
    moving = amplitude > T_F / K  # turning points before it stops
    loss = -np.diff(amplitude[moving])
    assert loss.size >= 6
    # 0.5 %: the bound; the peaks are read at samples, (2π·1.6 Hz·1 ms)²/2 = 5e-5 of the
    # amplitude off the true turning point
    np.testing.assert_allclose(loss, 2 * T_F / K, rtol=5e-3)


def test_coulomb_friction_stops_inside_tf_over_k(coulomb):
    theta = coulomb.outputs["angle:mass"] - coulomb.outputs["angle:ground 1"]
    last = coulomb.time > 10.0
    assert np.all(np.abs(theta[last]) <= T_F / K)
    # at rest on the face: stuck for good, its relative rotation still but for its stiff spring's give
    # (the two grounds keep swinging against each other, 10⁵ times slower than the mass did)
    assert max(e.time for e in coulomb.nonlinear.events) < 10.0
    face = coulomb.outputs["angle:mass"] - coulomb.outputs["angle:ground 2"]
    assert np.ptp(face[last]) < 1e-3 * T_F / K
    # the face's torque is k_face·(Δθ − s), a difference of angles 10⁶ times its compliance T_f/k_face:
    # their round-off (1e-13 of the swing, from expm) shows at 1e-7 of T_f
    assert coulomb.nonlinear.elements[0].peak_torque == pytest.approx(T_F, rel=1e-6)


def test_energy_balance_with_friction(coulomb):
    """Input work = kinetic + strain + dissipated by the face, every term exact: the work of a torque
    held over a step is T·Δθ; the dissipation T_f·|slip| per slipping phase."""
    o = coulomb.outputs
    work = (o["angle:mass"][1] - o["angle:mass"][0]) * J / DT  # the pulse, over the first step
    kinetic = 0.5 * (
        J * o["speed:mass"] ** 2 + GROUND * (o["speed:ground 1"] ** 2 + o["speed:ground 2"] ** 2)
    )
    strain = 0.5 * o["torque:spring"] ** 2 / K + 0.5 * o["torque:face"] ** 2 / K_FACE
    dissipated = coulomb.nonlinear.elements[0].dissipated
    assert kinetic[-1] + strain[-1] + dissipated == pytest.approx(work, rel=1e-6)


# --- Slip under a constant drive --------------------------------------------------------------
# J1 driven by T, joined to J2 by a coupling k that slips at T_s (static) and T_k (kinetic).
# Stuck from rest, the coupling torque is T·J2/(J1+J2)·(1 − cos ωt), ω² = k(J1+J2)/(J1·J2); it slips
# when that reaches T_s. Slipping, d(ω1 − ω2)/dt = (T − T_k)/J1 − T_k/J2 exactly.
J1, J2, K_C, T_S, T_K, T_DRIVE = 2.0, 3.0, 1e4, 60.0, 45.0, 100.0


@pytest.fixture(scope="module")
def slipping():
    res = _modes(Rigid("a", J1), Coupling("c", K_C, slip_torque=T_S, slip_kinetic_torque=T_K), Rigid("b", J2))
    return simulate(
        res, Scenario.step(T_DRIVE, at="a"), ["speed:a", "speed:b", "torque:c"], rate=RATE, duration=1.0
    )


def test_slip_starts_when_the_stuck_torque_reaches_the_slip_torque(slipping):
    omega = math.sqrt(K_C * (J1 + J2) / (J1 * J2))
    onset = math.acos(1 - T_S * (J1 + J2) / (T_DRIVE * J2)) / omega
    first = slipping.nonlinear.events[0]
    assert (first.before, first.after) == ("stuck", "slipping +")
    assert first.time == pytest.approx(onset, rel=1e-3)  # the bound (measured: 1e-15)
    # located to 1e-12 of the step where the torque rises at ~1e5 N·m/s: 1e-10 N·m of 60
    assert first.torque == pytest.approx(T_S, rel=1e-6)


def test_relative_acceleration_while_slipping(slipping):
    after = slipping.time > slipping.nonlinear.events[0].time + DT
    rel = (slipping.outputs["speed:a"] - slipping.outputs["speed:b"])[after]
    slope = np.diff(rel) / DT
    np.testing.assert_allclose(slope, (T_DRIVE - T_K) / J1 - T_K / J2, rtol=1e-3)  # the bound
    # slipping, the coupling transmits T_k itself (the constant state times T_k): round-off only
    np.testing.assert_allclose(slipping.outputs["torque:c"][after], T_K, rtol=1e-9)
    # it never sticks again: the drive keeps the slip speed growing
    assert slipping.nonlinear.event_count == 1
    assert slipping.nonlinear.elements[0].active_time == pytest.approx(
        1.0 - slipping.nonlinear.events[0].time
    )


# --- Free play ----------------------------------------------------------------------------------
# Two inertias, free play b, contact stiffness k, relative speed v0 inside the gap: the relative
# motion crosses the gap (b/v0) and bounces off each side for half a period of the contact
# oscillator (π·sqrt(J_r/k)): the period is 2·(b/v0 + π·sqrt(J_r/k)), J_r = J1·J2/(J1 + J2).
B, K_B, V0 = 0.01, 1e4, 0.5
JB1, JB2 = 1.0, 2.0


@pytest.fixture(scope="module")
def free_play():
    res = _modes(Rigid("a", JB1), Coupling("c", K_B, backlash=B), Rigid("b", JB2))
    outs = ["speed:a", "speed:b", "torque:c", "angle:a", "angle:b"]
    return res, outs, simulate(res, _pulse(V0, JB1, "a"), outs, rate=RATE, duration=2.0)


def test_free_play_period(free_play):
    *_, run = free_play
    contacts = np.array([e.time for e in run.nonlinear.events if e.after == "contact +"])
    jr = JB1 * JB2 / (JB1 + JB2)
    period = 2 * (B / V0 + math.pi * math.sqrt(jr / K_B))
    assert contacts.size >= 10
    np.testing.assert_allclose(np.diff(contacts), period, rtol=1e-3)  # the bound (measured: 1e-8)


def test_free_play_contact_pushes_and_never_pulls(free_play):
    *_, run = free_play
    torque = run.outputs["torque:c"]
    rel = run.outputs["angle:a"] - run.outputs["angle:b"]
    inside = np.abs(rel) < B / 2
    assert np.all(torque[inside] == 0.0)
    assert np.all(torque * np.sign(rel) >= 0.0)
    # peak contact torque of an undamped bounce: the closing speed times sqrt(k·J_r). The account reads
    # it at the samples (and the events, where it is 0): within half a step of the crest of a sine of
    # ω = sqrt(k/J_r), so between cos(ω·dt/2) of it and it
    jr = JB1 * JB2 / (JB1 + JB2)
    crest = V0 * math.sqrt(K_B * jr)
    peak = run.nonlinear.elements[0].peak_torque
    assert crest * math.cos(math.sqrt(K_B / jr) * DT / 2) <= peak <= crest * (1 + 1e-12)


def test_blocks_equal_the_stepped_equations(free_play):
    """The vectorised run (blocks between events) and the same events stepped one sample at a time."""
    res, outs, run = free_play
    stepped = simulate(res, _pulse(V0, JB1, "a"), outs, rate=RATE, duration=0.5, method="loop")
    for name in outs:
        ref = stepped.outputs[name]
        # each block's Schur recursion and each step's expm: a few hundred roundings of the largest value
        np.testing.assert_allclose(run.outputs[name][: ref.size], ref, rtol=0, atol=1e-8 * np.abs(ref).max())


# --- Stiffness curve ----------------------------------------------------------------------------
def test_static_ramp_follows_the_torque_curve():
    """A torque raised slowly through a coupling between a light inertia and a heavy one: the twist
    follows the curve's angle-torque relation (quasi-static: the ramp 1000 times slower than the
    line's period, the residual oscillation damped)."""
    curve = [[0.0, 0.0], [0.01, 1000.0], [0.015, 2500.0], [0.02, 5000.0]]
    res = _modes(Rigid("a", 1.0), Coupling("c", torque_curve=curve, damping=40.0), Rigid("b", 1e4))
    t_end, top = 20.0, 4500.0
    times = np.arange(0.0, t_end + DT / 2, DT)
    run = simulate(
        res,
        Scenario.from_series(times, top * times / t_end, at="a"),
        ["angle:a", "angle:b", "torque:c", "speed:a", "speed:b"],
        rate=RATE,
        duration=t_end,
    )
    twist = run.outputs["angle:a"] - run.outputs["angle:b"]
    spring = run.outputs["torque:c"] - 40.0 * (run.outputs["speed:a"] - run.outputs["speed:b"])
    a, t = np.array(curve).T
    # the spring torque at each twist lies on the curve (the damper's share taken off): exact in
    # every regime, to round-off of the torque's size
    np.testing.assert_allclose(spring, np.interp(twist, a, t), rtol=0, atol=1e-6 * top)
    # the largest twist against the curve at the largest torque, the damper's share c·Δω aside: Δω is
    # the ramp's 225 N·m/s over the stiffness (at most 2.3e-3 rad/s), 0.09 N·m at 40 N·m·s/rad of 4500
    # N·m, and the light inertia's ringing as small: 1e-3 bounds both
    assert twist.max() == pytest.approx(np.interp(run.outputs["torque:c"].max(), t, a), rel=1e-3)


def test_closed_loop_ramp_with_a_slipping_coupling_equals_the_stepped_loop():
    """The PI loop and its limit switches on top of the events: blocks against one step at a time."""
    res = _modes(
        Rigid("motor", 50.0),
        Coupling("c", 4e4, slip_torque=500.0, slip_kinetic_torque=400.0),
        Rigid("g", 30.0),
    )
    ctl = SpeedControl.tuned(res, bandwidth_hz=3.0, torque_min=-2000.0, torque_max=2000.0)
    scenario = Scenario.ramp(600.0, 2.0, ctl)
    outs = ["speed:motor", "speed:g", "torque:c", "control:torque"]
    fast = simulate(res, scenario, outs, rate=RATE, duration=3.0)
    ref = simulate(res, scenario, outs, rate=RATE, duration=3.0, method="loop")
    assert fast.nonlinear.event_count > 0 and "limit switches" in fast.method
    assert fast.nonlinear.event_count == ref.nonlinear.event_count
    for name in outs:
        scale = np.abs(ref.outputs[name]).max()
        # the same events by two arithmetic routes (Schur blocks, each step's matrices) over 3000 steps
        np.testing.assert_allclose(fast.outputs[name], ref.outputs[name], rtol=0, atol=1e-8 * scale)


def test_free_play_in_a_gear_mesh_reflects_the_driven_side():
    """A mesh of ratio n with free play b and stiffness k on the driving side: the driven wheel's
    inertia J2 acts as J2/n² there, so the oscillator has J_r = J1·(J2/n²)/(J1 + J2/n²) and the
    driving-side relative speed v0 after a pulse on J1: the period is 2·(b/v0 + π·sqrt(J_r/k))."""
    from flexshaft.model.components import Gear

    n, j1, j2 = 3.0, 1.0, 18.0
    res = _modes(Rigid("a", j1), Gear("mesh", n, mesh_stiffness=K_B, backlash=B), Rigid("b", j2))
    run = simulate(res, _pulse(V0, j1, "a"), ["speed:a", "torque:mesh"], rate=RATE, duration=2.0)
    contacts = np.array([e.time for e in run.nonlinear.events if e.after == "contact +"])
    j2r = j2 / n**2
    period = 2 * (B / V0 + math.pi * math.sqrt(j1 * j2r / (j1 + j2r) / K_B))
    assert contacts.size >= 10
    np.testing.assert_allclose(np.diff(contacts), period, rtol=1e-3)  # the bound


def test_the_study_report_lists_what_each_element_did(free_play):
    """The time run's section of the study report: each element's events, time active, peak torque."""
    from flexshaft.study.report import _nonlinear_run

    *_, run = free_play
    html = "".join(str(part) for part in _nonlinear_run(run.to_dict()["nonlinear"]))
    element = run.nonlinear.elements[0]
    assert f"{run.nonlinear.event_count} events" in html and "backlash" in html and "in contact" in html
    assert f"{element.peak_torque:.6g}" in html


@pytest.mark.parametrize(
    "law, twist",
    [
        ({"stiffness": 4e4, "slip_torque": 600.0}, 500.0 / 4e4),  # stuck: the spring alone
        ({"stiffness": 4e4, "backlash": 0.01}, 500.0 / 4e4 + 0.005),  # in contact, past half the play
        ({"torque_curve": [[0, 0], [0.01, 300.0], [0.02, 900.0]]}, 0.01 + 200.0 / 6e4),  # on the curve
    ],
)
def test_a_preloaded_start_sits_on_the_law(law, twist):
    """A coast from 500 N·m through the coupling starts from the law's own static twist at that torque."""
    res = _modes(Rigid("motor", 50.0), Coupling("c", damping=20.0, **law), Rigid("g", 30.0))
    run = simulate(
        res, Scenario.coast(500.0, speed_rpm=600.0), ["torque:c", "angle:motor", "angle:g"], rate=RATE
    )
    # a static solve of a few modal equations, read back through the law: round-off
    assert run.outputs["torque:c"][0] == pytest.approx(500.0, rel=1e-9)
    assert run.outputs["angle:motor"][0] - run.outputs["angle:g"][0] == pytest.approx(twist, rel=1e-9)


def test_a_preload_above_the_slip_torque_is_refused():
    res = _modes(Rigid("motor", 50.0), Coupling("c", 4e4, slip_torque=100.0), Rigid("g", 30.0))
    with pytest.raises(fs_error) as err:
        simulate(res, Scenario.coast(500.0, speed_rpm=600.0), ["torque:c"], rate=RATE)
    assert err.value.field == "slip_torque" and "cannot start steady" in str(err.value)
