"""Time simulation against scipy's dlsim, closed forms, the stepped control law and perturbation theory."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import dlsim

import flexshaft as fs
from flexshaft.analysis.simulate import (
    RPM,
    Scenario,
    SpeedControl,
    closed_loop_poles,
    simulate,
)
from flexshaft.analysis.statespace import state_space
from flexshaft.model.components import Drivetrain, Rigid, Shaft
from tests.conftest import EXAMPLES


@pytest.fixture(scope="module")
def customer1():
    return fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))


def _zoh(A, B, dt):
    # scipy's own zero-order hold (cont2discrete), not ours.
    from scipy.signal import cont2discrete

    Ad, Bd, *_ = cont2discrete((A, B, np.eye(A.shape[0]), 0), dt, method="zoh")
    return Ad, Bd


@pytest.mark.parametrize("kind", ["step", "sine"])
def test_open_loop_run_equals_scipy_dlsim(customer1, kind):
    # The same plant discretised by scipy (cont2discrete, zoh) and stepped by dlsim: our modal blocks
    # evaluate the same recursion through eigenvectors (cond ~ 1e2 here), so both agree to round-off
    # growing at most linearly over the 4 001 steps: 1e-9 of the output's range.
    rate, duration = 2000.0, 2.0
    sc = Scenario.step(100.0, time=0.2) if kind == "step" else Scenario.sine(50.0, 91.0)
    outputs = ["speed:motor", "torque:part 3", "angle:generator"]
    run = simulate(customer1, sc, outputs, rate=rate, duration=duration)
    assert run.method == "modal blocks"
    ss = state_space(customer1, ["motor", "generator"], outputs)
    Ad, Bd = _zoh(ss.A, ss.B, 1 / rate)
    t = run.time
    drive = np.where(t >= 0.2, 100.0, 0.0) if kind == "step" else 50.0 * np.sin(2 * np.pi * 91.0 * t)
    _, y, _ = dlsim((Ad, Bd, ss.C, ss.D, 1 / rate), np.column_stack([drive, np.zeros_like(t)]), t=t)
    for i, name in enumerate(outputs):
        scale = np.max(np.abs(y[:, i]))
        np.testing.assert_allclose(run.outputs[name], y[:, i], rtol=0, atol=1e-9 * scale)


def test_step_response_of_two_inertias_equals_the_closed_form():
    # J1 - (k, c) - J2, a torque step T at J1: the twist x = θ1 − θ2 obeys J_e·ẍ + c·ẋ + k·x = T·J2/(J1 + J2)
    # exactly (J_e = J1·J2/(J1 + J2)), a 1-DOF oscillator from rest; the shaft carries k·x + c·ẋ. A step
    # held from t = 0 is what zero-order hold assumes, so the samples are the continuous response itself:
    # round-off only (1e-9 of the peak: a 2-state expm and 5 000 steps).
    j1, j2, k, c, torque = 3.0, 1.5, 2e4, 4.0, 50.0
    d = Drivetrain("two", (Rigid("a", j1), Shaft("s", stiffness=k, inertia=0.0, damping=c), Rigid("b", j2)))
    r = fs.modal_analysis(d)
    run = simulate(r, Scenario.step(torque), ["torque:s", "speed:a"], rate=5000.0, duration=1.0)
    je = j1 * j2 / (j1 + j2)
    wn = math.sqrt(k / je)
    z = c / (2 * math.sqrt(k * je))
    wd = wn * math.sqrt(1 - z * z)
    t = run.time
    xs = torque * j2 / (j1 + j2) / k
    e = np.exp(-z * wn * t)
    x = xs * (1 - e * (np.cos(wd * t) + z / math.sqrt(1 - z * z) * np.sin(wd * t)))
    xdot = xs * e * (wn / math.sqrt(1 - z * z)) * np.sin(wd * t)
    expected = k * x + c * xdot
    np.testing.assert_allclose(
        run.outputs["torque:s"], expected, rtol=0, atol=1e-9 * np.max(np.abs(expected))
    )
    # and the line accelerates as a whole: the mean speed is T·t/(J1 + J2), the motor's oscillates about it
    mean = torque * t / (j1 + j2)
    assert np.max(np.abs(run.outputs["speed:a"] - mean)) < 0.05 * mean[-1]


@pytest.mark.parametrize(
    "ramp,limit,load,switches",
    [((0.0, 600.0, 4.0), 900.0, -300.0, 2), ((900.0, 0.0, 2.0), 500.0, 200.0, 1)],
    ids=["up: enters and leaves the upper limit", "down: held at the lower limit"],
)
def test_closed_loop_blocks_equal_the_stepped_control_law(customer1, ramp, limit, load, switches):
    # Ramps that hit a torque limit (and leave it), with the low-pass, ripple and noise: the vectorised
    # pieces must reproduce the stepped equations exactly, limit switches included (the switching step is
    # found exactly, so what remains is round-off).
    start, end, time = ramp
    ctl = SpeedControl.tuned(customer1, tau=0.003, torque_min=-limit, torque_max=limit)
    sc = Scenario.ramp(end, time, ctl, start_rpm=start, load=load, ripple=40.0, noise=20.0, seed=3)
    ends = ["angle:motor", "angle:part 2/part 3", "angle:part 3/part 4"]
    outputs = ["speed:motor", "torque:part 3", "control:torque", "angle:generator"]
    fast = simulate(customer1, sc, outputs + ends, rate=1000.0, duration=8.0)
    slow = simulate(customer1, sc, outputs + ends, rate=1000.0, duration=8.0, method="loop")
    assert fast.method.startswith("modal blocks") and slow.method == "loop"
    assert int(fast.method.split("(")[1].split()[0]) >= switches
    # How far round-off can take them apart. Each output is a sum of terms of the size S of the states
    # (angles and speeds), not of the output: the coupling torque is k3·(θa − θb) with θ ~ 1e2 rad
    # against a twist of ~1e-2 rad, the command is kp·(ω_set − ω) + ki·∫(ω_set − ω). Both methods round
    # the state to eps·S each step; the modal blocks go through the closed loop's eigenbasis, whose
    # condition number is 3.5e3 (held) and 6.5e3 (free) here, and the errors add up at most linearly over
    # the n steps: |Δy| <= n·eps·cond·S with cond = 1e4. (A wrong switching step or a lost sample would
    # show as a difference of the ripple's size, 1e-2 of the range and more.)
    o, n, eps = slow.outputs, slow.time.size, np.finfo(float).eps
    peak = {name: np.max(np.abs(o[name])) for name in o}
    k3 = customer1.model.drivetrain.components[3].stiffness  # N·m/rad, the coupling
    scale = {
        "speed:motor": peak["speed:motor"],
        "angle:generator": peak["angle:generator"],
        "torque:part 3": k3 * (peak["angle:part 2/part 3"] + peak["angle:part 3/part 4"]),
        "control:torque": 2 * ctl.kp * peak["speed:motor"] + 2 * ctl.ki * peak["angle:motor"],
    }
    for name in outputs:
        np.testing.assert_allclose(fast.outputs[name], o[name], rtol=0, atol=n * eps * 1e4 * scale[name])
    # the drive torque really is held at the limit (up to the ripple and noise added after it)
    held = fast.outputs["control:torque"]
    assert np.max(np.abs(held)) > limit - 1.0


def test_ramp_tracks_its_setpoint(customer1):
    # Without limits a PI loop on a ramp has a constant tracking lag; once the ramp ends the speed
    # settles on the set-point (integral action): within 0.1 % after 4 s of hold at ~1/10 of f1.
    ctl = SpeedControl.tuned(customer1)
    run = simulate(
        customer1, Scenario.ramp(1800.0, 5.0, ctl), ["speed:motor", "control:setpoint"], duration=9.0
    )
    final = run.outputs["speed:motor"][-1]
    assert final == pytest.approx(1800.0 * RPM, rel=1e-3)


def test_coast_starts_steady_and_rings_down(customer1):
    # Before t = 0 the line carries 1000 N·m at 600 rpm; at t = 0 the torques vanish: the coupling's
    # torque starts at exactly the transmitted torque (a static twist: every elastic mode at φᵀF/ω²) and the
    # mean speed stays (nothing brakes a free line).
    run = simulate(customer1, Scenario.coast(1000.0, speed_rpm=600.0), ["torque:part 3", "speed:generator"])
    assert run.outputs["torque:part 3"][0] == pytest.approx(1000.0, rel=1e-9)
    assert np.mean(run.outputs["speed:generator"]) == pytest.approx(600.0 * RPM, rel=1e-3)


def test_closing_the_loop_holds_the_motor_and_moves_the_first_mode_toward_its_clamped_value(customer1):
    # The PI on the motor speed is a damper kp and (its integrator) a spring ki from the motor to ground.
    # (1) The closed loop's oscillating poles equal those of (K + ki·e eᵀ, M, C + kp·e eᵀ) - an independent
    # dense quadratic eigen-solve (1e-8). (2) Why the study saw its frequencies shift slightly: the loop
    # holds the motor, so mode 1 (motor against generator) moves from its free-free value toward the
    # motor-clamped one (the chain without the motor's DOF, a separate dense solve); with the tuned gains
    # (2 Hz bandwidth) the damper dominates and the shift is small and downward, and with gains 1000 times
    # higher the mode is the clamped one (the residual is O(1/gain): 1e-3).
    ctl = SpeedControl.tuned(customer1, bandwidth_hz=2.0)
    poles = closed_loop_poles(customer1, ctl)
    m = customer1.model
    K, M = m.K.toarray(), m.M.toarray()
    C = m.C.toarray() if m.C is not None else np.zeros_like(K)
    e = np.asarray(m.T[m.node_dof([m.station("motor").node])[0]].toarray()).ravel()
    Kc, Cc = K + ctl.ki * np.outer(e, e), C + ctl.kp * np.outer(e, e)
    n = K.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, Kc), -np.linalg.solve(M, Cc)]])
    ref = np.linalg.eigvals(A)
    osc = np.sort_complex(poles[poles.imag > 1e-6])
    np.testing.assert_allclose(osc, np.sort_complex(ref[ref.imag > 1e-6]), rtol=1e-8)

    free = customer1.frequencies_hz[1]
    keep = np.flatnonzero(e == 0)  # every coordinate but the motor's
    clamped = np.sqrt(np.linalg.eigvals(np.linalg.solve(M[np.ix_(keep, keep)], K[np.ix_(keep, keep)])).real)
    clamped = np.sort(clamped)[0] / (2 * np.pi)

    def first(control):
        p = closed_loop_poles(customer1, control)
        return np.min(np.abs(p[p.imag > 1e-6])) / (2 * np.pi)

    closed = first(ctl)
    assert clamped < closed < free
    assert (free - closed) / free < 0.01  # "slightly": the tuned loop leaves the mode within 1 %
    stiff = SpeedControl(1000 * ctl.kp, 1000 * ctl.ki)
    assert first(stiff) == pytest.approx(clamped, rel=1e-3)


def test_tuned_gains_follow_the_line_inertia(customer1):
    # kp = J·ω_c, ki = kp·ω_c/5 with J the whole line's inertia (1/φ_rigid² at the motor).
    ctl = SpeedControl.tuned(customer1, bandwidth_hz=1.0)
    total = sum(c.inertia for c in customer1.model.drivetrain.components)
    assert ctl.kp == pytest.approx(total * 2 * math.pi, rel=1e-10)
    assert ctl.ki == pytest.approx(total * (2 * math.pi) ** 2 / 5, rel=1e-10)


BAD = [
    (lambda: SpeedControl(-1.0, 1.0), "kp"),
    (lambda: SpeedControl(1.0, 1.0, torque_min=5.0, torque_max=1.0), "torque_min"),
    (lambda: SpeedControl(1.0, 1.0, measure="angle:motor"), "measure"),
    (lambda: Scenario("jump"), "scenario"),
    (lambda: Scenario.sine(1.0, 0.0), "frequency"),
    (lambda: Scenario.step(1.0, ripple=2.0), "ripple"),
    (lambda: Scenario("ramp", end_rpm=100.0, ramp_time=1.0), "control"),
    (lambda: Scenario.from_series([0.0, 1.0], [1.0]), "series"),
    (lambda: Scenario.from_series([0.0, 0.0], [1.0, 2.0]), "series.time"),
    (lambda: Scenario.step(float("nan")), "torque"),
]


@pytest.mark.parametrize("make,field", BAD, ids=[b[1] + str(i) for i, b in enumerate(BAD)])
def test_bad_scenarios_name_the_field(make, field):
    with pytest.raises(fs.ModelError) as info:
        make()
    assert info.value.field == field


def test_bad_run_arguments(customer1):
    sc = Scenario.step(1.0)
    for kwargs, field in [
        ({"rate": 0.0}, "rate"),
        ({"duration": -1.0}, "duration"),
        ({"method": "euler"}, "method"),
    ]:
        with pytest.raises(fs.ModelError) as info:
            simulate(customer1, sc, ["speed:motor"], **kwargs)
        assert info.value.field == field
    with pytest.raises(fs.ModelError, match="no such signal"):
        simulate(customer1, sc, ["speed:nowhere"])
    with pytest.raises(fs.ModelError, match="speed loop closed"):
        simulate(customer1, sc, ["control:torque"])


def test_result_as_dataframe_and_plot(customer1):
    run = simulate(customer1, Scenario.step(10.0), ["speed:motor", "torque:part 3"], duration=0.5)
    fig = run.plot()
    assert len(fig.axes) == 2  # one panel per unit: rad/s and N·m
    pd = pytest.importorskip("pandas")
    frame = run.to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == ["speed:motor [rad/s]", "torque:part 3 [N·m]"]
    assert frame.index.name == "time [s]"
    np.testing.assert_array_equal(frame["torque:part 3 [N·m]"].to_numpy(), run.outputs["torque:part 3"])


def test_a_six_dof_line_simulates_like_its_torsion():
    # A 6-DOF line has two rigid-body modes (axial, spin); the speed loop and the start speed find the
    # spin. Its torsion response to a drive-torque step equals the torsion chain's own (the torsion modes
    # of a full model are the torsion chain's, and a torque excites nothing else): the modes kept differ
    # (the full model's default cut at the sample rate also drops torsion modes above it, as the chain's
    # does), so both are cut at the same frequency and agree to 1e-8 of the response's range.
    from flexshaft.model.components import Coupling
    from flexshaft.sections import table_from_segments

    def shaft(name, segs):
        return Shaft.from_sections(
            name, table_from_segments(segs, name=name), fs.STEEL, max_element_length=0.2
        )

    comps = (
        Rigid("motor", 2.0),
        shaft("s1", [{"length": 1.2, "od": 0.1}]),
        Coupling("c", stiffness=3e4, inertia=0.02),
        shaft("s2", [{"length": 0.8, "od": 0.09}]),
        Rigid("gen", 1.0),
    )
    full = fs.modal_analysis(
        Drivetrain("full", comps, dofs="full", bearings=(("motor", 1e8), ("s1/c", 1e8), ("gen", 1e8)))
    )
    torsion = fs.modal_analysis(Drivetrain("torsion", comps))
    out = ["torque:c", "speed:gen"]
    a = simulate(full, Scenario.step(50.0), out, rate=1000.0, duration=1.0, max_hz=400.0)
    b = simulate(torsion, Scenario.step(50.0), out, rate=1000.0, duration=1.0, max_hz=400.0)
    assert a.method == "modal blocks"
    for name in out:
        np.testing.assert_allclose(
            a.outputs[name], b.outputs[name], rtol=0, atol=1e-8 * np.ptp(b.outputs[name])
        )
    ctl = SpeedControl.tuned(full)
    assert ctl.kp == pytest.approx(SpeedControl.tuned(torsion).kp, rel=1e-9)  # the same spin inertia
    # Cut at 400 Hz as above: this line is undamped, and its torsion mode at 644 Hz, kept by the default
    # cut at the rate but above the 500 Hz Nyquist frequency, is seen by the 1 kHz loop aliased and late -
    # the loop drives it unstable (|z| = 1.0001 a step), which simulate refuses (test_stability_*).
    ramp = Scenario.ramp(300.0, 1.0, ctl, start_rpm=100.0)
    run = simulate(full, ramp, ["speed:motor"], duration=1.5, max_hz=400.0)
    assert run.outputs["speed:motor"][0] == pytest.approx(100.0 * RPM, rel=1e-9)
