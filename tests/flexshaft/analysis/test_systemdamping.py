"""System damping (Rayleigh fitted to the first two system modes) against per-part damping.

References: the Rayleigh closed form ξ = α/(2ω) + βω/2, a single mode's resonant amplitude 1/(2ξω²),
the study's finding (0.53 % on the parts' own modes gives system modes far below 0.53 %).
"""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.statespace import frequency_response, state_space
from flexshaft.analysis.systemdamping import (
    DAMPING_CHOICES,
    DAMPING_DESCRIPTIONS,
    SYSTEM_DAMPING_RATIO,
    system_damped,
    system_rayleigh,
    undamped_parts,
)
from flexshaft.model.components import Coupling, Drivetrain, Rayleigh, Rigid, Shaft
from tests.conftest import EXAMPLES


@pytest.fixture(scope="module")
def customer1():
    return fs.load_model(EXAMPLES / "customer1.toml")


def test_choices_and_their_descriptions():
    assert DAMPING_CHOICES == ("parts", "system", "both")
    assert set(DAMPING_DESCRIPTIONS) == set(DAMPING_CHOICES)
    assert all("\n" not in text and text for text in DAMPING_DESCRIPTIONS.values())
    assert SYSTEM_DAMPING_RATIO == 0.0053


@pytest.mark.parametrize("name", ["customer1", "without_dut", "customer2"])
def test_the_first_two_elastic_modes_carry_the_ratio(name):
    d = fs.load_model(EXAMPLES / f"{name}.toml")
    s = system_damped(d, 0.0053)
    r = fs.modal_analysis(s)
    e = ~r.rigid
    # Proportional damping keeps the undamped modes, so the damped eigen-solve gives every mode exactly the
    # closed form ξ = α/(2ω) + βω/2 - 0.0053 on modes 1 and 2 by construction. The damped solve's round-off
    # (eps times the spread of the model, ~1e-12 relative) is far inside 1e-9.
    omega = r.omega[e]
    closed = s.rayleigh.alpha / (2 * omega) + s.rayleigh.beta * omega / 2
    np.testing.assert_allclose(r.damping_ratios[e], closed, rtol=1e-9)
    np.testing.assert_allclose(r.damping_ratios[e][:2], 0.0053, rtol=1e-9)
    # the undamped frequencies are the per-part model's (damping does not move them)
    np.testing.assert_allclose(omega, fs.modal_analysis(d).omega[e], rtol=1e-12)


def test_every_components_own_damping_is_removed():
    d = Drivetrain(
        "damped",
        (
            Rigid("m", 10.0),
            Shaft("s", 1e5, 0.5, elements=3, damping_ratio=0.01, damping=20.0),
            Coupling("c", 2e4, 0.1, damping=5.0),
            Rigid("g", 2.0),
        ),
        rayleigh=Rayleigh(alpha=1.0, beta=1e-4),
    )
    u = undamped_parts(d)
    assert u.rayleigh is None
    assert (u.component("s").damping_ratio, u.component("s").damping, u.component("c").damping) == (0, 0, 0)
    assert fs.assemble(u).C is None  # nothing left to damp
    # meshes, stiffness and inertia as they were
    assert u.component("s").elements == 3 and u.component("s").stiffness == 1e5
    s = system_damped(d, 0.02)
    r = fs.modal_analysis(s)
    np.testing.assert_allclose(r.damping_ratios[~r.rigid][:2], 0.02, rtol=1e-9)


def test_a_flexible_bodys_modal_damping_is_removed_too():
    d = fs.load_model(EXAMPLES / "customer1_flex.toml")
    u = undamped_parts(d)
    assert all(
        c.reduce is None or np.all(np.asarray(c.reduce.damping) == 0)
        for c in u.components
        if c.type == "shaft"
    )
    r = fs.modal_analysis(system_damped(d))
    np.testing.assert_allclose(r.damping_ratios[~r.rigid][:2], 0.0053, rtol=1e-8)


def test_one_elastic_mode_gets_stiffness_proportional_damping():
    # Two inertias on a massless spring: one elastic mode, ω² = k (J1 + J2)/(J1 J2); β = 2ξ/ω, α = 0.
    k, j1, j2 = 4e4, 3.0, 1.0
    d = Drivetrain("two", (Rigid("a", j1), Shaft("s", k, 0.0), Rigid("b", j2)))
    ray, f = system_rayleigh(d, 0.05)
    w = np.sqrt(k * (j1 + j2) / (j1 * j2))
    assert f == pytest.approx([w / (2 * np.pi)], rel=1e-12)
    assert ray.alpha == 0.0 and ray.beta == pytest.approx(2 * 0.05 / w, rel=1e-12)
    r = fs.modal_analysis(system_damped(d, 0.05))
    assert r.damping_ratios[1] == pytest.approx(0.05, rel=1e-9)


def test_per_part_damping_leaves_system_mode_1_far_below_the_ratio(customer1):
    # The study's finding: 0.53 % on each flexible part's own modes reaches Customer 1's first mode (which
    # lives in the undamped coupling) only through the parts' share of its strain energy - far below.
    parts = fs.modal_analysis(customer1)
    system = fs.modal_analysis(system_damped(customer1))
    zp, zs = parts.damping_ratios[1], system.damping_ratios[1]
    assert zs == pytest.approx(0.0053, rel=1e-9)
    assert zp < zs / 20
    # A lightly damped mode's resonant amplitude is 1/(2ξω²) (single-DOF closed form): at mode 1's natural
    # frequency the two FRFs differ by the ratio of the damping ratios. The other modes add a quasi-static
    # background of a few 1e-3 of the system peak (mode 2 is 8x higher): within 3 %.
    f1 = parts.frequencies_hz[1]
    h = []
    for result in (parts, system):
        sys_ = state_space(fs.modal_analysis(result.model), ["motor"], ["torque:part 3"])
        h.append(abs(frequency_response(sys_, [f1]).H[0, 0, 0]))
    assert h[0] / h[1] == pytest.approx(zs / zp, rel=0.03)


def test_bad_arguments(customer1):
    with pytest.raises(fs.ModelError, match="system_damping_ratio"):
        system_damped(customer1, 1.2)
    with pytest.raises(fs.ModelError, match="system_damping_ratio"):
        system_damped(customer1, float("nan"))
    with pytest.raises(fs.ModelError, match="drivetrain"):
        system_damped("customer1.toml")
    with pytest.raises(fs.ModelError, match="no elastic mode"):
        system_damped(Drivetrain("one", (Rigid("m", 1.0),)))


def _free_pair(alpha, beta=0.0):
    # Two inertias on a massless spring, free at both ends: one rigid-body mode, one elastic mode
    # ω² = k (J1 + J2)/(J1 J2).
    k, j1, j2 = 4e4, 3.0, 1.0
    chain = (Rigid("a", j1), Shaft("s", k, 0.0), Rigid("b", j2))
    d = Drivetrain("two", chain, rayleigh=Rayleigh(alpha, beta))
    return d, k, j1, j2


def test_rayleigh_damps_the_deformation_not_the_rigid_rotation():
    # Rayleigh's αJ would put a drag α·J·ω to ground on a free chain's rigid rotation (at the bench's
    # α ≈ 3.7 1/s the closed-loop ramp never reached speed). Taken on the deformation only, the rigid-body
    # mode stays undamped and the elastic mode keeps the closed form ξ = α/(2ω) + βω/2.
    alpha, beta = 5.0, 2e-4
    d, k, j1, j2 = _free_pair(alpha, beta)
    r = fs.modal_analysis(d)
    w = np.sqrt(k * (j1 + j2) / (j1 * j2))
    assert r.rigid[0] and not r.rigid[1]
    # the damped eigenvalue of the rigid-body mode is 0 (a real -α with the drag): no decay of its speed
    assert abs(r.damped.eigenvalues[0]) < 1e-9 * w
    # eps-level arithmetic in a 4x4 eigen-solve: 1e-9 is far outside round-off, far inside any mistake
    assert r.damping_ratios[1] == pytest.approx(alpha / (2 * w) + beta * w / 2, rel=1e-9)
    # Speed per torque on the free pair far below its mode: a pure integrator 1/(jω(J1 + J2)) without
    # drag; with the drag it would be 1/((α + jω)(J1 + J2)), 12 % lower in magnitude at 0.4 Hz. The
    # elastic mode's quasi-static share is (f/f1)² ~ 1e-5 there; 1e-4 is the bound.
    f = 0.4
    ss = state_space(r, ["a"], ["speed:a"])
    h = frequency_response(ss, [f]).H[0, 0, 0]
    assert abs(h) * 2 * np.pi * f * (j1 + j2) == pytest.approx(1.0, rel=1e-4)


def test_a_constant_torque_accelerates_a_rayleigh_damped_free_chain_freely():
    # Newton on the rigid body: a torque T on the free pair, from rest, gives speed T·t/(J1 + J2)
    # whatever its Rayleigh damping (the deformation rings down; the mean speed feels no drag).
    d, k, j1, j2 = _free_pair(5.0)
    ss = state_space(fs.modal_analysis(d), ["a"], ["speed:b"])
    T, t_end = 100.0, 4.0
    t = np.linspace(0.0, t_end, 4001)
    from scipy.signal import lsim

    _, y, _ = lsim((ss.A, ss.B, ss.C, ss.D), np.full(t.size, T), t)
    # by 4 s the elastic mode (ξ = α/(2ω) ≈ 2 %, ω ≈ 231 rad/s) has decayed by e^-18: its swing is the
    # static twist's speed change, far below 1e-3 of T·t/J
    assert y[-1] == pytest.approx(T * t_end / (j1 + j2), rel=1e-3)
