"""Calibrating damping: targets with a damping ratio met by damping parameters (Rayleigh α and β, the
ratios of the two-ratio form, a shaft's or a flexible body's modal damping ratio), beside or without
frequency targets; the checks before any solve; the targets file, the tuned model file, stages and the
command line.

References: the undamped frequencies of a free three-inertia chain (the quadratic in ω² of its
characteristic polynomial); Rayleigh damping's ratio ξ = α/(2ω) + βω/2 on classical (real) modes;
the damped eigenvalues of the first-order state-space form, solved by scipy.linalg.eig, ξ = −Re λ/|λ|.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import scipy.linalg as sla

import flexshaft as fs
from flexshaft.analysis import calibrate as cal
from flexshaft.analysis.calibrate import (
    DAMPING_TOLERANCE,
    SOLVER_FRACTION,
    Bound,
    Target,
    calibrate,
    frequencysolve,
)
from flexshaft.analysis.parameters import parameter_value, with_parameters
from flexshaft.analysis.sensitivity import sensitivities
from flexshaft.analysis.staged import calibrate_stages
from flexshaft.cli import main
from flexshaft.model.components import Drivetrain, Rayleigh, Rigid, Shaft
from flexshaft.study.tunedfile import read_targets
from tests.conftest import EXAMPLES

# The damping solve stops where the damped ratios agree with its prediction to SOLVER_FRACTION of the
# tightest damping tolerance (in units of a tolerance); its linear steps meet reachable targets to
# round-off. A reached ratio is then within SOLVER_FRACTION·tol of a tolerance tol of its target,
# relatively: SOLVER_FRACTION·tol² = 1e-6 at the default 10 %. Twice that leaves room for the round-off
# of the damped eigenvalues (~1e-13 of ξ).
REACHED = 2 * SOLVER_FRACTION * DAMPING_TOLERANCE**2

J1, J2, J3, K1, K2 = 2.0, 1.0, 0.5, 1.0e5, 5.0e4  # kg·m², N·m/rad


def _three(rayleigh=None):
    """A free chain of three inertias on two massless shafts."""
    return Drivetrain(
        "three",
        (
            Rigid("a", J1),
            Shaft("s1", stiffness=K1, inertia=0.0),
            Rigid("b", J2),
            Shaft("s2", stiffness=K2, inertia=0.0),
            Rigid("c", J3),
        ),
        rayleigh=rayleigh,
    )


def _three_omegas() -> np.ndarray:
    # det(K − ω²M) = 0 of the free chain: ω²·(ω⁴ − b·ω² + c) with b = k1/J1 + k1/J2 + k2/J2 + k2/J3 and
    # c = k1·k2·(J1 + J2 + J3)/(J1·J2·J3): the two elastic ω² are the roots of the quadratic.
    b = K1 / J1 + K1 / J2 + K2 / J2 + K2 / J3
    c = K1 * K2 * (J1 + J2 + J3) / (J1 * J2 * J3)
    disc = np.sqrt(b * b - 4 * c)
    return np.sqrt([(b - disc) / 2, (b + disc) / 2])


def _rayleigh_closed_form(omegas, ratios):
    # ξ_i = α/(2ω_i) + βω_i/2 at two modes: two linear equations in (α, β)
    A = np.array([[1 / (2 * w), w / 2] for w in omegas])
    return np.linalg.solve(A, ratios)


def test_rayleigh_alpha_and_beta_from_two_damping_targets_are_the_closed_form():
    # Two measured ratios on modes 1 and 2, α and β from 0: the linear problem in (α, β) the closed form
    # solves. Rayleigh damping keeps the modes real, so the damped ratio is the formula's exactly.
    targets = [Target(1, damping_ratio=0.0053), Target(2, damping_ratio=0.0081)]
    params = [Bound("rayleigh.alpha", lower=0.0, upper=50.0), Bound("rayleigh.beta", lower=0.0, upper=1e-3)]
    res = calibrate(_three(), targets, params)
    alpha, beta = _rayleigh_closed_form(_three_omegas(), [0.0053, 0.0081])
    assert alpha > 0 and beta > 0  # the closed form is inside the bounds: no bound holds it
    # The ratios are met to REACHED; the 2x2 map from (α, β) to the ratios, scaled to relative changes,
    # is inverted with its condition number κ: (α, β) within κ·REACHED of the closed form.
    A = (
        np.array([[1 / (2 * w), w / 2] for w in _three_omegas()])
        * np.array([alpha, beta])
        / [[0.0053], [0.0081]]
    )
    kappa = np.linalg.cond(A)
    np.testing.assert_allclose(res.tuned, [alpha, beta], rtol=kappa * REACHED)
    np.testing.assert_allclose(res.damping, [0.0053, 0.0081], rtol=REACHED)
    assert np.all(res.damping_met) and res.targets == () and res.active == (None, None)
    assert np.all(res.initial_damping == 0.0)  # no damping to start with
    # the tuned model reports those ratios as its damped modes
    r = fs.modal_analysis(res.drivetrain)
    np.testing.assert_allclose(r.damping_ratios[1:3], [0.0053, 0.0081], rtol=REACHED)
    np.testing.assert_allclose(2 * np.pi * r.frequencies_hz[1:3], _three_omegas(), rtol=1e-12)


def test_one_damping_target_moves_alpha_and_beta_least():
    # One ratio, two coefficients: the least relative change (the least-norm Gauss-Newton step, inside
    # the bounds) from a start with both nonzero: Δ(α/α0, β/β0) along g = ∂ξ/∂(x/x0) = (α0/(2ω), β0ω/2).
    w1 = _three_omegas()[0]
    a0, b0 = 1.0, 1e-5
    start = _three(Rayleigh(alpha=a0, beta=b0))
    xi0 = a0 / (2 * w1) + b0 * w1 / 2
    goal = 1.5 * xi0
    res = calibrate(
        start,
        [Target(1, damping_ratio=goal)],
        [Bound("rayleigh.alpha", percent=90), Bound("rayleigh.beta", percent=90)],
    )
    g = np.array([a0 / (2 * w1), b0 * w1 / 2])
    step = (goal - xi0) * g / (g @ g)
    # a miss of REACHED·goal moves the point along g by REACHED·goal/|g| of each start value, and
    # |g| >= ξ0/√2 (its components add up to ξ0): at most 1.5·√2·REACHED; 3·REACHED bounds it
    np.testing.assert_allclose(res.tuned, [a0 * (1 + step[0]), b0 * (1 + step[1])], rtol=3 * REACHED)


def _damped_ratio_by_state_space(d, omega):
    """ξ = −Re λ/|λ| of the damped root nearest ω (rad/s): the first-order form
    [[0, I], [−K, −C]] z = λ [[I, 0], [0, M]] z of the assembled K, M, C, solved by scipy.linalg.eig."""
    m = fs.assemble(d)
    K, M, C = (np.asarray(A.toarray()) for A in (m.K, m.M, m.C))
    n = K.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
    lam = sla.eigvals(A, B)
    lam = lam[np.isfinite(lam) & (lam.imag > 0)]
    root = lam[np.argmin(np.abs(np.abs(lam) - omega))]
    return -root.real / abs(root)


def _shaft_line(ratio=0.01):
    # a massive shaft of four elements between two inertias: its own modal damping is not proportional
    # (C is set on the shaft's own free-free modes), so the system's modes are complex
    return Drivetrain(
        "line",
        (
            Rigid("motor", 1.0),
            Shaft("s", stiffness=2.0e4, inertia=0.2, elements=4, damping_ratio=ratio),
            Rigid("gen", 0.5),
            Shaft("t", stiffness=8.0e3, inertia=0.05, elements=2),
            Rigid("load", 0.3),
        ),
    )


def test_a_shafts_damping_ratio_reaches_a_measured_system_ratio():
    d = _shaft_line()
    r0 = fs.modal_analysis(d)
    res = calibrate(d, [Target(1, damping_ratio=0.0053)], [Bound("s.damping_ratio", lower=1e-4, upper=0.5)])
    assert res.damping_met[0] and res.initial_damping[0] == pytest.approx(r0.damping_ratios[1], rel=1e-12)
    # independently: the damped eigenvalue of the tuned model's state space
    w1 = 2 * np.pi * r0.frequencies_hz[1]  # the undamped frequency: no damping parameter moves it
    assert _damped_ratio_by_state_space(res.drivetrain, w1) == pytest.approx(0.0053, rel=REACHED)
    assert res.damping[0] == pytest.approx(0.0053, rel=REACHED)
    # the shaft carries more than the system mode gets: only its share of the mode's strain energy
    assert res.tuned[0] > 0.0053


@pytest.fixture(scope="module")
def customer1_truth():
    """Customer 1 with two stiffnesses moved and its damping changed: part 2's ratio and Rayleigh α."""
    d = fs.load_model(EXAMPLES / "customer1.toml")
    truth = {
        "part 1.stiffness": 1.08 * parameter_value(d, "part 1.stiffness"),
        "part 3.stiffness": 0.9 * parameter_value(d, "part 3.stiffness"),
        "part 2.damping_ratio": 0.012,
        "rayleigh.alpha": 0.5,
    }
    return d, truth, fs.modal_analysis(with_parameters(d, truth))


def test_frequencies_and_damping_together_recover_a_true_model(customer1_truth):
    d, truth, rt = customer1_truth
    targets = [
        Target(1, frequency_hz=rt.frequencies_hz[1]),
        Target(2, frequency_hz=rt.frequencies_hz[2], damping_ratio=rt.damping_ratios[2]),
        Target(3, damping_ratio=rt.damping_ratios[3]),
    ]
    params = [
        Bound("part 1.stiffness", percent=20),
        Bound("part 3.stiffness", percent=20),
        Bound("part 2.damping_ratio", lower=0.0, upper=0.1),
        Bound("rayleigh.alpha", lower=0.0, upper=2.0),
    ]
    res = calibrate(d, targets, params)
    assert np.all(res.met) and np.all(res.damping_met)
    # the frequency parameters as the frequency-only calibration recovers them (test_calibrate: 1e-6)
    np.testing.assert_allclose(
        res.tuned[:2], [truth["part 1.stiffness"], truth["part 3.stiffness"]], rtol=1e-6
    )
    # The damping parameters: the ratios are met to REACHED, and the frequency parameters' 1e-6 moves
    # the shapes, so the ratios, by ~1e-6 (normalised sensitivities of order 1). The map from the two
    # parameters' relative changes to the two ratios' has condition number κ: within κ·(REACHED + 1e-6),
    # doubled for the second-order terms the first-order map leaves out.
    s = sensitivities(with_parameters(d, truth), ["part 2.damping_ratio", "rayleigh.alpha"], modes=[2, 3])
    kappa = np.linalg.cond(s.normalised_damping)
    assert kappa < 10  # the two are told apart by these two modes (κ ≈ 3)
    np.testing.assert_allclose(
        res.tuned[2:],
        [truth["part 2.damping_ratio"], truth["rayleigh.alpha"]],
        rtol=2 * kappa * (REACHED + 1e-6),
    )
    doc = res.to_dict()
    assert [t["target"] for t in doc["damping_targets"]] == [t.damping_label for t in targets[1:]]
    assert doc["damping_targets"][1]["tracked_mode"] == 3 and doc["targets"][1]["target"].startswith("f2")
    assert doc["parameters"][3]["change_percent"] is None  # α from 0: no % to give
    json.dumps(doc, allow_nan=False)  # strict JSON


def test_damping_ratios_beside_frequencies_are_compared_when_no_damping_parameter_is_tuned():
    # A targets file from `flexshaft identify` carries the measured damping with every frequency; tuning
    # a stiffness alone leaves the damping as the model has it, compared before and after. With Rayleigh
    # damping the modes stay real, and each ratio is α/(2ω) + βω/2 at the model's ω: the start's
    # (closed-form ω of the chain) and the end's (ω of the tuned chain, the frequencies it was tuned to).
    alpha, beta = 2.0, 2e-5
    w = _three_omegas()
    goal = w * 1.02 / (2 * np.pi)  # both modes 2 % up: both stiffnesses up 4 % (ω² ∝ k at fixed J)
    targets = [
        Target(1, frequency_hz=goal[0], damping_ratio=0.005),
        Target(2, frequency_hz=goal[1], damping_ratio=0.006),
    ]
    params = [Bound("s1.stiffness", percent=10), Bound("s2.stiffness", percent=10)]
    res = calibrate(_three(Rayleigh(alpha=alpha, beta=beta)), targets, params)
    assert "damping ratios compared, not tuned" in res.message
    assert [t.mode for t in res.damping_targets] == [1, 2]
    # the damped ratio is the Rayleigh formula's exactly (real modes); round-off of the damped
    # eigenvalues ~1e-13 relative, the tuned ω within the frequency solve's tolerance (1e-6 of ω, far
    # inside the 1e-4 allowed here, where ∂ξ/ξ ≤ ∂ω/ω)
    np.testing.assert_allclose(res.initial_damping, alpha / (2 * w) + beta * w / 2, rtol=1e-9)
    wt = 2 * np.pi * res.values
    np.testing.assert_allclose(res.damping, alpha / (2 * wt) + beta * wt / 2, rtol=1e-9)
    np.testing.assert_allclose(res.values, goal, rtol=1e-4)
    np.testing.assert_allclose(res.tuned, [K1 * 1.0404, K2 * 1.0404], rtol=1e-3)
    assert list(res.damping_met) == list(np.abs(res.damping / [0.005, 0.006] - 1) <= 0.1)


def test_a_missed_damping_target_says_what_each_parameter_alone_would_need():
    # Customer 1's first mode lives in the undamped coupling: part 1's own damping barely reaches it
    d = fs.load_model(EXAMPLES / "customer1.toml")
    res = calibrate(
        d,
        [Target(1, damping_ratio=0.0053), Target(3, damping_ratio=0.0053)],
        [Bound("part 1.damping_ratio", percent=50), Bound("rayleigh.alpha", lower=0.0, upper=0.1)],
    )
    assert not res.damping_met[0]
    unmet = {u["target"]: u for u in res.unmet}
    assert "ξ1 = 0.53 %" in unmet
    assert res.active[1] == "upper" and res.widen[1] > 0  # α holds on its upper bound


# --- the checks before any solve --------------------------------------------------------------------------


def _no_optimiser(monkeypatch):
    def refuse(*args, **kw):
        raise AssertionError("a solve started")

    monkeypatch.setattr(frequencysolve, "_solve_start", refuse)
    monkeypatch.setattr(cal, "damping_solve", refuse)


@pytest.mark.parametrize(
    "targets,params,component,field,says",
    [
        (
            [Target(1, frequency_hz=11.0), Target(2, damping_ratio=0.005)],
            [Bound("part 3.stiffness", percent=10)],
            "[[target]] #2",
            "target.damping_ratio",
            "needs a damping parameter",
        ),
        (
            [Target(1, frequency_hz=11.0)],
            [Bound("part 3.stiffness", percent=10), Bound("rayleigh.alpha", lower=0.0, upper=1.0)],
            "[[parameter]] #2",
            "parameter",
            "no target has a damping_ratio",
        ),
        (
            [Target(1, damping_ratio=0.005)],
            [Bound("part 3.stiffness", percent=10), Bound("rayleigh.beta", lower=0.0, upper=1e-4)],
            "[[parameter]] #1",
            "parameter",
            "no target has frequency_hz or ratio",
        ),
        (
            [Target(2, frequency_hz=91.0, damping_ratio=0.005)],
            [Bound("rayleigh.beta", lower=0.0, upper=1e-4)],
            "[[target]] #1",
            "target.frequency_hz",
            "no parameter moves the frequencies",
        ),
        (
            [Target(2, damping_ratio=0.005), Target(2, frequency_hz=91.0, damping_ratio=0.006)],
            [Bound("rayleigh.beta", lower=0.0, upper=1e-4), Bound("part 3.stiffness", percent=10)],
            "[[target]] #2",
            "target",
            "targets what [[target]] #1 targets already",
        ),
        (  # a damper at 0 has no % to move by
            [Target(2, damping_ratio=0.005)],
            [Bound("part 3.damping", percent=10)],
            "[[parameter]] #1",
            "part 3.damping",
            "is 0",
        ),
        (
            [Target(2, damping_ratio=0.005)],
            [Bound("rayleigh.alpha", lower=0.0, upper=2e6)],
            "[[parameter]] #1",
            "rayleigh.alpha.bounds",
            "<= 1e+06",
        ),
    ],
)
def test_damping_problems_are_refused_before_any_solve(monkeypatch, targets, params, component, field, says):
    _no_optimiser(monkeypatch)
    d = fs.load_model(EXAMPLES / "customer1.toml")
    with pytest.raises(fs.ModelError) as info:
        calibrate(d, targets, params)
    err = info.value
    assert err.component == component and err.field == field and says in str(err), str(err)


@pytest.mark.parametrize(
    "make,field",
    [
        (lambda: Target(1, damping_ratio=0.0), "target.damping_ratio"),
        (lambda: Target(1, damping_ratio=1.0), "target.damping_ratio"),
        (lambda: Target(1, damping_ratio=-0.01), "target.damping_ratio"),
        (lambda: Target(1, damping_ratio=float("nan")), "target.damping_ratio"),
        (lambda: Target(1, damping_ratio="0.5 %"), "target.damping_ratio"),
        (lambda: Target(1, damping_ratio=0.005, damping_tolerance=0.0), "target.damping_tolerance"),
        (lambda: Target(1, damping_ratio=0.005, damping_tolerance=2.0), "target.damping_tolerance"),
        (lambda: Target(1, frequency_hz=10.0, damping_tolerance=0.2), "target.damping_tolerance"),
        (lambda: Target(1, damping_ratio=0.005, tolerance=0.02), "target.tolerance"),
        (lambda: Target(1), "target"),
    ],
)
def test_a_damping_target_is_checked_when_made(make, field):
    with pytest.raises(fs.ModelError) as info:
        make()
    assert info.value.field == field


def test_defaults_and_labels():
    t = Target(2, frequency_hz=48.31, tolerance=0.004, damping_ratio=0.0051)
    assert t.damping_tolerance == DAMPING_TOLERANCE and t.tolerance == 0.004 and t.has_frequency
    assert t.label == "f2 = 48.31 Hz" and t.damping_label == "ξ2 = 0.51 %"
    z = Target(3, damping_ratio=0.0053)
    assert z.tolerance is None and not z.has_frequency and z.value is None and z.label == "ξ3 = 0.53 %"
    assert (
        Target(1, frequency_hz=10.0).tolerance == 0.01 and Target(1, frequency_hz=10.0).damping_label is None
    )


def test_rayleigh_coefficients_and_ratios_are_not_tuned_together(monkeypatch):
    _no_optimiser(monkeypatch)
    d = _three(Rayleigh(alpha=1.0, beta=1e-5, frequencies_hz=(40.0, 80.0)))
    with pytest.raises(fs.ModelError, match="a second way") as info:
        calibrate(
            d,
            [Target(1, damping_ratio=0.005)],
            [Bound("rayleigh.alpha", percent=10), Bound("rayleigh.damping_ratios[0]", percent=10)],
        )
    assert info.value.component == "[[parameter]] #2"
    with pytest.raises(fs.ModelError, match="not by two ratios"):  # the form the model does not have
        calibrate(
            _three(), [Target(1, damping_ratio=0.005)], [Bound("rayleigh.damping_ratios[0]", percent=10)]
        )


# --- files: targets, tuned models, stages, the command line ----------------------------------------------

TWO_RATIO_MODEL = """
[model]
name = "three, Rayleigh by two ratios"
rayleigh = {frequencies_hz = [30.0, 90.0], damping_ratios = [0.004, 0.004]}

[[chain]]
name = "a"
type = "rigid"
inertia = 2.0

[[chain]]
name = "s1"
type = "shaft"
stiffness = 1.0e5
inertia = 0.0

[[chain]]
name = "b"
type = "rigid"
inertia = 1.0

[[chain]]
name = "s2"
type = "shaft"
stiffness = 5.0e4
inertia = 0.0

[[chain]]
name = "c"
type = "rigid"
inertia = 0.5
"""

TWO_RATIO_TARGETS = """
[[target]]
mode = 1
damping_ratio = 0.0053

[[target]]
mode = 2
damping_ratio = 0.0081
damping_tolerance = 0.25

[[parameter]]
name = "rayleigh.damping_ratios[0]"
bounds = [0.001, 0.05]

[[parameter]]
name = "rayleigh.damping_ratios[1]"
bounds = [0.001, 0.05]
"""


def test_the_two_ratio_form_is_tuned_and_written_back(tmp_path, capsys):
    # The model states Rayleigh damping by its ratios at 30 and 90 Hz; the measured ratios of modes 1 and
    # 2 fix α and β (closed form), and with them the ratios at 30 and 90 Hz the tuned file must state.
    model, targets, out = tmp_path / "m.toml", tmp_path / "t.toml", tmp_path / "tuned.toml"
    model.write_text(TWO_RATIO_MODEL)
    targets.write_text(TWO_RATIO_TARGETS)
    assert main(["calibrate", str(model), "--targets", str(targets), "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)["stages"][0]
    assert [t["met"] for t in doc["damping_targets"]] == [True, True]
    assert doc["damping_targets"][1]["tolerance"] == 0.25
    alpha, beta = _rayleigh_closed_form(_three_omegas(), [0.0053, 0.0081])
    at = 2 * np.pi * np.array([30.0, 90.0])
    expect = alpha / (2 * at) + beta * at / 2
    # the ratios at the modes are a linear map of those at 30 and 90 Hz (through α and β); its condition
    # number, in relative changes, turns the ratios' misses (REACHED) into the parameters'
    R = np.array([[1 / (2 * w), w / 2] for w in _three_omegas()])
    S = np.array([[1 / (2 * w), w / 2] for w in at])
    kappa = np.linalg.cond(R @ np.linalg.inv(S) * expect / np.array([[0.0053], [0.0081]]))
    np.testing.assert_allclose([p["tuned"] for p in doc["parameters"]], expect, rtol=kappa * REACHED)
    tuned = fs.load_model(out)  # the file's own form, with the tuned ratios
    assert "damping_ratios = [" in out.read_text() and tuned.rayleigh.frequencies_hz == (30.0, 90.0)
    np.testing.assert_allclose(
        [tuned.rayleigh.alpha, tuned.rayleigh.beta], [alpha, beta], rtol=kappa * REACHED
    )
    r = fs.modal_analysis(tuned)  # the written model reproduces the damping
    np.testing.assert_allclose(
        r.damping_ratios[1:3], [t["tuned"] for t in doc["damping_targets"]], rtol=1e-12
    )


def test_the_command_line_prints_the_damping_rows_and_writes_the_tuned_damping(tmp_path, capsys):
    # A targets file as `flexshaft identify -o` will write it: frequency, tolerance, damping ratio and
    # its tolerance in one [[target]]; a stiffness and Rayleigh β tuned on Customer 1.
    d = fs.load_model(EXAMPLES / "customer1.toml")
    r0 = fs.modal_analysis(d)
    model, targets, out = tmp_path / "customer1.toml", tmp_path / "t.toml", tmp_path / "tuned.toml"
    model.write_text((EXAMPLES / "customer1.toml").read_text())
    targets.write_text(
        f"""
[[target]]
mode = 2
frequency_hz = {1.02 * r0.frequencies_hz[2]}
tolerance = 0.004
damping_ratio = 0.0051
damping_tolerance = 0.25

[[parameter]]
name = "part 2.stiffness"
percent = 10

[[parameter]]
name = "rayleigh.beta"
bounds = [0.0, 1e-4]
"""
    )
    assert main(["calibrate", str(model), "--targets", str(targets), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "damping target" in text and "ξ2 = 0.51 %" in text and "initial %" in text
    row = next(line for line in text.splitlines() if line.strip().startswith("ξ2"))
    assert row.split()[-1] == "yes" and row.split()[-2] == "25.00"  # the tolerance, %
    beta_row = next(line for line in text.splitlines() if line.strip().startswith("rayleigh.beta"))
    assert " - " in beta_row  # no change % from 0
    tuned = fs.load_model(out)
    r = fs.modal_analysis(tuned)
    assert r.damping_ratios[2] == pytest.approx(0.0051, rel=0.25) and tuned.rayleigh.beta > 0
    assert "rayleigh = {alpha = 0.0, beta = " in out.read_text()


@pytest.mark.parametrize(
    "entry,component,field",
    [
        ("mode = 1\ndamping_ratio = 0.0\n", "[[target]] #1", "target.damping_ratio"),
        ("mode = 1\ndamping_ratio = 1.2\n", "[[target]] #1", "target.damping_ratio"),
        ("mode = 1\ndamping_ratio = 0.005\ndamping = 0.1\n", "[[target]] #1", "damping"),  # unknown key
        ("mode = 1\ndamping_ratio = 0.005\ntolerance = 0.1\n", "[[target]] #1", "target.tolerance"),
        (
            "mode = 1\nfrequency_hz = 11.0\ndamping_tolerance = 0.1\n",
            "[[target]] #1",
            "target.damping_tolerance",
        ),
    ],
)
def test_targets_file_errors_name_the_entry_and_field(tmp_path, entry, component, field):
    path = tmp_path / "t.toml"
    path.write_text(f"[[target]]\n{entry}\n[[parameter]]\nname = 'rayleigh.beta'\nbounds = [0.0, 1e-4]\n")
    with pytest.raises(fs.ModelError) as info:
        read_targets(path)
    assert info.value.component == component and info.value.field == field and info.value.file == str(path)


def test_a_flexible_bodys_damping_ratio_is_tuned_and_written_back(tmp_path, capsys):
    # Customer 1 with parts 1, 2, 4 as flexible bodies: part 2's ratio of its own modes is a parameter,
    # evaluated on the reduced model (the one `flexshaft modes` reports), and the file's key gets it.
    model, targets, out = tmp_path / "flex.toml", tmp_path / "t.toml", tmp_path / "tuned.toml"
    model.write_text((EXAMPLES / "customer1_flex.toml").read_text())
    r0 = fs.modal_analysis(fs.load_model(model))
    goal = 1.5 * r0.damping_ratios[2]
    targets.write_text(
        f"[[target]]\nmode = 2\ndamping_ratio = {goal}\n"
        "[[parameter]]\nname = 'part 2.damping_ratio'\nbounds = [0.0, 0.1]\n"
    )
    assert main(["calibrate", str(model), "--targets", str(targets), "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)["stages"][0]
    z = doc["damping_targets"][0]
    assert z["met"] and z["initial"] == pytest.approx(r0.damping_ratios[2], rel=1e-12)
    assert z["tuned"] == pytest.approx(goal, rel=REACHED)
    tuned = fs.load_model(out)
    assert parameter_value(tuned, "part 2.damping_ratio") == pytest.approx(
        doc["parameters"][0]["tuned"], rel=1e-15
    )
    assert fs.modal_analysis(tuned).damping_ratios[2] == pytest.approx(z["tuned"], rel=1e-12)


def test_a_stage_calibrates_damping_and_later_stages_carry_it(tmp_path):
    for name in ("without_dut.toml", "customer1.toml"):
        (tmp_path / name).write_text((EXAMPLES / name).read_text())
    r1 = fs.modal_analysis(fs.load_model(tmp_path / "customer1.toml"))
    path = tmp_path / "t.toml"
    path.write_text(
        f"""
[[stage]]
name = "damping"
model = "customer1.toml"
[[stage.target]]
mode = 4
damping_ratio = {1.2 * r1.damping_ratios[4]}
[[stage.parameter]]
name = "part 4.damping_ratio"
percent = 60

[[stage]]
name = "stiffness"
model = "customer1.toml"
[[stage.target]]
mode = 2
frequency_hz = {1.01 * r1.frequencies_hz[2]}
[[stage.parameter]]
name = "part 2.stiffness"
percent = 10
"""
    )
    staged = calibrate_stages(read_targets(path), fs.load_model)
    first, second = staged.stages
    assert first.result.damping_met[0] and second.result.met[0]
    assert second.carried == {"part 4.damping_ratio": first.result.tuned[0]}
    assert staged.tuned_values()["part 4.damping_ratio"] == first.result.tuned[0]
    # a damping target in a later stage is checked with the others before the first stage runs: alone
    # (no frequency beside it, which it would be compared with) and with no damping parameter to tune
    path.write_text(
        path.read_text().replace(
            "mode = 2\nfrequency_hz",
            "mode = 3\ndamping_ratio = 0.005\n[[stage.target]]\nmode = 2\nfrequency_hz",
        )
    )
    with pytest.raises(fs.ModelError) as info:
        calibrate_stages(read_targets(path), fs.load_model)
    assert info.value.component == "[[stage]] #2 [[target]] #1" and info.value.field == "target.damping_ratio"


def test_the_system_damping_example_is_the_study_s_rayleigh_fit(capsys):
    # examples/calibration/system_damping.toml: the parts' own damping off, α and β tuned to 0.53 % on
    # modes 1 and 2 - the fit flexshaft.analysis.systemdamping makes in closed form (the study's eq. 41).
    from flexshaft.analysis.systemdamping import system_rayleigh

    model = EXAMPLES / "customer1.toml"
    args = ["calibrate", str(model), "--targets", str(EXAMPLES / "calibration" / "system_damping.toml")]
    assert main([*args, "--json"]) == 0
    (stage,) = json.loads(capsys.readouterr().out)["stages"]
    tuned = {p["name"]: p["tuned"] for p in stage["parameters"]}
    ray, f = system_rayleigh(fs.load_model(model), 0.0053)
    # the 2x2 map from relative changes of (α, β) to the two ratios, inverted (see the first test)
    w = 2 * np.pi * f
    A = np.array([[1 / (2 * x), x / 2] for x in w]) * np.array([ray.alpha, ray.beta]) / 0.0053
    kappa = np.linalg.cond(A)
    np.testing.assert_allclose(
        [tuned["rayleigh.alpha"], tuned["rayleigh.beta"]], [ray.alpha, ray.beta], rtol=kappa * REACHED
    )
    assert [t["met"] for t in stage["damping_targets"]] == [True, True]
    assert stage["fixed"] == {
        "part 1.damping_ratio": 0.0,
        "part 2.damping_ratio": 0.0,
        "part 4.damping_ratio": 0.0,
    }


def test_damping_parameters_of_flexible_bodies_and_the_model():
    from flexshaft.analysis.parameters import find_parameter, parameters
    from flexshaft.reduction.modaldamping import ModalDamping
    from flexshaft.sections import table_from_segments

    def body(damping):
        table = table_from_segments([{"length": 0.8, "od": 0.1}], name="s")
        s = Shaft.from_sections("s", table, fs.STEEL, max_element_length=0.1)
        return Drivetrain(
            "flex",
            (
                Rigid("a", 1.0),
                dataclasses.replace(s, reduce=fs.Reduce(modes=2, damping=damping)),
                Rigid("b", 1.0),
            ),
        )

    d = body(0.01)  # one ratio, as a number: the body's modes' ratio is the parameter
    assert parameter_value(d, "s.damping_ratio") == 0.01
    moved = with_parameters(d, {"s.damping_ratio": 0.02})
    assert moved.component("s").reduce.damping == ModalDamping(ratio=0.02)
    with pytest.raises(fs.ModelError, match="has no single damping_ratio"):
        find_parameter(body(ModalDamping(by_mode=(0.01, 0.02))), "s.damping_ratio")
    names = [p.name for p in parameters(d)]
    assert names[-2:] == ["rayleigh.alpha", "rayleigh.beta"] and "s.damping_ratio" in names
    two = dataclasses.replace(d, rayleigh=Rayleigh(1.0, 1e-5, frequencies_hz=(10.0, 50.0)))
    assert [p.name for p in parameters(two)][-2:] == [
        "rayleigh.damping_ratios[0]",
        "rayleigh.damping_ratios[1]",
    ]
    # the ratios at the two frequencies, and back: α, β unchanged
    z = [parameter_value(two, f"rayleigh.damping_ratios[{k}]") for k in (0, 1)]
    w = 2 * np.pi * np.array([10.0, 50.0])
    np.testing.assert_allclose(z, 1.0 / (2 * w) + 1e-5 * w / 2, rtol=1e-15)
    back = with_parameters(two, {"rayleigh.damping_ratios[0]": z[0], "rayleigh.damping_ratios[1]": z[1]})
    np.testing.assert_allclose([back.rayleigh.alpha, back.rayleigh.beta], [1.0, 1e-5], rtol=1e-12)
    with pytest.raises(fs.ModelError, match="negative Rayleigh coefficient"):
        with_parameters(two, {"rayleigh.damping_ratios[0]": 0.5})
    # the unreduced model the sensitivities differentiate has no body damping: NaN, not a false 0
    s = sensitivities(d, ["s.damping_ratio", "rayleigh.alpha"], modes=[1])
    assert np.isnan(s.ddamping[0, 0]) and s.dfrequency[0, 0] == 0.0
    # Rayleigh's α on an elastic mode: ∂ξ/∂α = 1/(2ω)
    assert s.ddamping[0, 1] == pytest.approx(1 / (4 * np.pi * s.frequencies_hz[0]), rel=1e-8)


def test_the_study_report_lists_the_damping_targets():
    from flexshaft.study import report as studyreport

    res = calibrate(
        _three(),
        [Target(1, damping_ratio=0.0053)],
        [Bound("rayleigh.beta", lower=0.0, upper=1e-3)],
    )
    page = studyreport._Page({}, {})
    page.failed = lambda stage_id: False
    doc = {"stages": [{"name": "damping", "model": "three.toml", "carried": {}} | res.to_dict()]}
    studyreport._calibration(page, {"calibration": json.loads(json.dumps(doc))}, "calibration")
    html = "".join(page.parts)
    assert "<th>damping target</th>" in html and "<td>ξ1 = 0.53 %</td>" in html and "<td>0.5300</td>" in html


def test_a_damper_held_at_zero_is_on_its_lower_bound():
    # The parts' own damping alone already exceeds the target: α stays at 0, pushed against it
    d = _shaft_line(ratio=0.05)
    r0 = fs.modal_analysis(d)
    res = calibrate(
        d,
        [Target(1, damping_ratio=0.5 * r0.damping_ratios[1])],
        [Bound("rayleigh.alpha", lower=0.0, upper=5.0)],
    )
    assert res.tuned[0] == 0.0 and res.active == ("lower",) and res.widen[0] > 0
    assert not res.damping_met[0] and res.unmet[0]["alone_would_need"] == []  # from 0: no % to give
