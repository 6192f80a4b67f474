"""Nonlinear time runs against an independent reference: a four-inertia chain's equations of motion
written here in physical coordinates (J·θ'' = the torques of the neighbouring couplings + the drive),
integrated by scipy's Radau with event functions, one regime of the middle coupling's law at a time.

Nothing of flexshaft's matrices, modes or event code is used by the reference: it knows only the
element laws as :mod:`flexshaft.analysis.hybrid`'s docstring defines them (friction slip with its
slip angle as a state, centred free play whose contact never pulls, a piecewise-linear torque curve).
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexshaft.analysis.modal import modal_analysis
from flexshaft.analysis.simulate import Scenario, simulate
from flexshaft.model.assembly import assemble
from flexshaft.model.components import Coupling, Drivetrain, Rigid

RATE = 1000.0
DT = 1.0 / RATE
STATIONS = ("a", "b", "c", "d")
INERTIA = np.array([2.0, 1.0, 3.0, 1.5])  # kg·m²
K1, K3 = 2e4, 3e4  # the linear couplings a-b and c-d, N·m/rad
K_MID = 1e4  # the nonlinear coupling b-c (slip, backlash), N·m/rad
# Elastic modes 10.4, 27.6 and 31.5 Hz (stuck / in contact): 30-100 samples a period at 1 kHz.

# Radau is asked for rtol 1e-10 with atol 1e-12 (rad, rad/s): its local error per step is held to
# ~1e-10 of the state, and its dense output (the collocation polynomial, order 3: what the samples
# and the event states are read from) to ~1e-9 of it. Over the ~10⁴ steps and ~20 restarts of a run
# those add up to at most ~1e-7 of a signal's peak; flexshaft's expm steps are exact to round-off.
# So the two must agree to 1e-6 of each signal's peak, a tenth of which is the integrator's budget.
RTOL, ATOL = 1e-10, 1e-12
AGREE = 1e-6
# An event's time: the state's error over the guard's rate of change, ~1e-9 of the state over a rate
# of the state's size per period (~0.03 s): ~1e-10 s. 1e-8 s (1e-5 of the step) leaves room for a
# guard that crosses slowly.
EVENT_TIME = 1e-8


# --- the reference: the chain's equations of motion and the laws -------------------------------
class SlipLaw:
    """Friction face in series with the spring k and damper c (hybrid.py's docstring).

    Regimes: 0 stuck, ±1 slipping forward / backward. The slip angle s is a state.

    Parameters
    ----------
    k, c : float
        Spring (N·m/rad) and parallel damper (N·m·s/rad).
    static, kinetic, damping : float
        Slip torque, kinetic torque (N·m) and the slip face's viscous damping (N·m·s/rad).
    """

    def __init__(self, k, c, static, kinetic, damping=0.0):
        self.k, self.c, self.static, self.kinetic, self.damping = k, c, static, kinetic, damping

    start = 0

    def label(self, regime):
        return {0: "stuck", 1: "slipping +", -1: "slipping -"}[regime]

    def torque(self, d, w, s, regime):
        """Transmitted torque and slip rate ṡ at relative rotation d, speed w, slip angle s."""
        k, c, cs = self.k, self.c, self.damping
        if regime == 0:
            return k * (d - s) + c * w, 0.0
        if c + cs == 0.0:
            # massless hub, no damper: the spring stays at the kinetic torque and the face slips at Δω
            return regime * self.kinetic, w
        rate = (k * (d - s) + c * w - regime * self.kinetic) / (c + cs)
        return regime * self.kinetic + cs * rate, rate

    def guards(self, regime):
        """``[(g(d, w, s), next regime), ...]``, each g positive inside ``regime``."""
        if regime == 0:
            stuck = lambda d, w, s: self.torque(d, w, s, 0)[0]  # noqa: E731
            return [
                (lambda d, w, s: self.static - stuck(d, w, s), 1),
                (lambda d, w, s: self.static + stuck(d, w, s), -1),
            ]
        return [(lambda d, w, s: regime * self.torque(d, w, s, regime)[1], 0)]

    def enter(self, d, s, regime):
        """The slip angle just after switching into ``regime`` (from the stuck state, slip angle s)."""
        if regime != 0 and self.c + self.damping == 0.0:
            # without a damper the spring's torque drops from the static to the kinetic torque at once
            return d - regime * self.kinetic / self.k
        return s


class BacklashLaw:
    """Centred free play b; contact through k and c while the contact pushes.

    Regimes: 0 apart (inside the play), ±1 in contact, ±2 apart though past ±b/2 (the damper would
    have pulled: the sides separate with zero torque and touch again when the contact would push).

    Parameters
    ----------
    k, c, gap : float
        Contact stiffness (N·m/rad), damper (N·m·s/rad), total free play (rad).
    """

    def __init__(self, k, c, gap):
        self.k, self.c, self.gap = k, c, gap

    start = 0

    def label(self, regime):
        return {0: "apart", 1: "contact +", -1: "contact -", 2: "apart", -2: "apart"}[regime]

    def push(self, d, w, side):
        """The torque contact on ``side`` (±1) would carry, signed positive when it pushes."""
        return side * (self.k * (d - side * 0.5 * self.gap) + self.c * w)

    def torque(self, d, w, s, regime):
        if regime in (1, -1):
            return self.k * (d - regime * 0.5 * self.gap) + self.c * w, 0.0
        return 0.0, 0.0

    def guards(self, regime):
        half = 0.5 * self.gap
        if regime == 0:
            return [(lambda d, w, s: half - d, 1), (lambda d, w, s: d + half, -1)]
        side = 1 if regime > 0 else -1
        if regime in (1, -1):
            return [(lambda d, w, s: self.push(d, w, side), 2 * side if self.c > 0 else 0)]
        return [
            (lambda d, w, s: side * d - half, 0),  # back inside the play
            (lambda d, w, s: -self.push(d, w, side), side),  # the contact pushes again
        ]

    def enter(self, d, s, regime):
        return s


class CurveLaw:
    """Torque against relative rotation, piecewise linear through the given points and on with the
    end slopes; the damper c in parallel.

    Regime j: between points j − 1 and j (0: below the first point, n: above the last).

    Parameters
    ----------
    points : array (n, 2)
        [angle (rad), torque (N·m)], increasing, through (0, 0).
    c : float
    """

    def __init__(self, points, c=0.0):
        self.angle, self.value = np.asarray(points, dtype=float).T
        self.c = c
        slopes = np.diff(self.value) / np.diff(self.angle)
        self.slopes = np.concatenate([slopes[:1], slopes, slopes[-1:]])
        self.start = int(np.searchsorted(self.angle, 0.0, side="right"))

    def label(self, regime):
        return f"segment {regime}"

    def torque(self, d, w, s, regime):
        base = min(max(regime - 1, 0), self.angle.size - 1)
        return self.value[base] + self.slopes[regime] * (d - self.angle[base]) + self.c * w, 0.0

    def guards(self, regime):
        out = []
        if regime > 0:
            out.append((lambda d, w, s: d - self.angle[regime - 1], regime - 1))
        if regime < self.angle.size:
            out.append((lambda d, w, s: self.angle[regime] - d, regime + 1))
        return out

    def enter(self, d, s, regime):
        return s


def chain_rates(y, drive, law, regime):
    """The chain's state rates: y = [θ_a..θ_d, ω_a..ω_d, s], the held drive torque at a (N·m).

    J_a·θ_a'' = T − T₁,  J_b·θ_b'' = T₁ − T_nl,  J_c·θ_c'' = T_nl − T₃,  J_d·θ_d'' = T₃.
    """
    th, om, s = y[:4], y[4:8], y[8]
    t1 = K1 * (th[0] - th[1])
    t_nl, s_rate = law.torque(th[1] - th[2], om[1] - om[2], s, regime)
    t3 = K3 * (th[2] - th[3])
    acc = np.array([drive - t1, t1 - t_nl, t_nl - t3, t3]) / INERTIA
    return np.concatenate([om, acc, [s_rate]])


def reference(law, torque, samples):
    """The chain from rest under a drive torque held over each step, by Radau with terminal events.

    Parameters
    ----------
    law : SlipLaw, BacklashLaw or CurveLaw
        The middle coupling's.
    torque : ndarray
        The drive torque held over [k·dt, (k+1)·dt), N·m, one per sample.
    samples : int

    Returns
    -------
    y : ndarray (samples, 9)
        The state at the sample times.
    element : ndarray (samples,)
        The middle coupling's torque there, N·m.
    events : list of (time, before, after)
    """
    t_s = np.arange(samples) * DT
    y_out = np.full((samples, 9), np.nan)
    regime_at = np.zeros(samples, dtype=int)
    y = np.zeros(9)
    regime = law.start
    events = []
    # the drive changes only where the held torque does: integrate across the pieces between
    changes = np.flatnonzero(np.diff(torque[: samples - 1]) != 0.0) + 1
    bounds = np.concatenate([[0], changes, [samples - 1]])
    t = 0.0
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        drive, t_end = torque[lo], t_s[hi]
        while True:
            guards = law.guards(regime)

            def rates(_, x, drive=drive, regime=regime):
                return chain_rates(x, drive, law, regime)

            # each regime is affine in the state: its Jacobian is exact from unit differences
            f0 = rates(0.0, np.zeros(9))
            jac = np.column_stack([rates(0.0, e) - f0 for e in np.eye(9)])
            funcs = []
            for g, _ in guards:

                def event(_, x, g=g):
                    return g(x[1] - x[2], x[5] - x[6], x[8])

                event.terminal, event.direction = True, -1
                funcs.append(event)
            inside = (t_s >= t - 1e-15) & (t_s <= t_end + 1e-15)
            sol = solve_ivp(
                rates,
                (t, t_end),
                y,
                method="Radau",
                rtol=RTOL,
                atol=ATOL,
                jac=jac,
                t_eval=np.clip(t_s[inside], t, t_end),
                events=funcs,
            )
            assert sol.success, sol.message
            idx = np.flatnonzero(inside)[: len(sol.t)]
            y_out[idx] = np.asarray(sol.y).reshape(9, -1).T
            regime_at[idx] = regime
            if sol.status != 1:
                y, t = sol.y[:, -1], t_end
                break
            fired = min((te[0], i) for i, te in enumerate(sol.t_events) if te.size)[1]
            t = float(sol.t_events[fired][0])
            y = sol.y_events[fired][0].copy()
            after = guards[fired][1]
            y[8] = law.enter(y[1] - y[2], y[8], after)
            events.append((t, law.label(regime), law.label(after)))
            regime = after
        # the sample at a piece's end is the next piece's start: read it there (same state)
    element = np.array(
        [law.torque(v[1] - v[2], v[5] - v[6], v[8], r)[0] for v, r in zip(y_out, regime_at)]
    )
    return y_out, element, events


# --- flexshaft's run of the same chain -----------------------------------------------------------
OUTPUTS = [f"angle:{s}" for s in STATIONS] + [f"speed:{s}" for s in STATIONS]
OUTPUTS += ["torque:k1", "torque:nl", "torque:k3"]


def flexshaft_run(middle, torque, samples):
    """flexshaft's run of the chain with ``middle`` as the b-c coupling, every mode kept.

    Parameters
    ----------
    middle : Coupling
    torque : ndarray
        The drive torque at each sample time, held over the step after it.
    samples : int
    """
    chain = Drivetrain(
        "chain",
        (
            Rigid("a", INERTIA[0]),
            Coupling("k1", K1),
            Rigid("b", INERTIA[1]),
            middle,
            Rigid("c", INERTIA[2]),
            Coupling("k3", K3),
            Rigid("d", INERTIA[3]),
        ),
    )
    res = modal_analysis(assemble(chain))
    times = np.arange(samples) * DT
    if np.all(torque == torque[0]):
        scenario = Scenario.step(float(torque[0]), at="a")
    else:
        scenario = Scenario.from_series(times, torque, at="a")
    return simulate(
        res, scenario, OUTPUTS, rate=RATE, duration=(samples - 1) * DT, max_hz=float("inf")
    )


def square(amplitude, half_period, samples):
    """±amplitude, reversing every ``half_period`` s, at the sample times (held over each step)."""
    t = np.arange(samples) * DT
    return amplitude * np.where(np.floor(t / half_period + 1e-9) % 2 == 0, 1.0, -1.0)


# A held step cannot keep a friction face slipping and sticking: once it sticks with the line's mean
# torque below the kinetic torque it stays stuck (two events in all). A drive that reverses every
# 0.1 s slips it forward and back, ~19 events a second. The other laws take a held step.
T_S, T_K, GAP = 60.0, 45.0, 0.01
C_MID, C_SLIP = 5.0, 2.0  # the damped cases' coupling damper and slip-face damping, N·m·s/rad
CURVE = [[0.0, 0.0], [0.004, 40.0], [0.008, 120.0], [0.012, 240.0]]  # stiffening: 1e4, 2e4, 3e4 N·m/rad
SAMPLES = 601  # 0.6 s
CASES = {
    "slip": (
        SlipLaw(K_MID, 0.0, T_S, T_K),
        Coupling("nl", K_MID, slip_torque=T_S, slip_kinetic_torque=T_K),
        square(100.0, 0.1, SAMPLES),
    ),
    "slip damped": (
        SlipLaw(K_MID, C_MID, T_S, T_K, C_SLIP),
        Coupling("nl", K_MID, damping=C_MID, slip_torque=T_S, slip_kinetic_torque=T_K, slip_damping=C_SLIP),
        square(100.0, 0.1, SAMPLES),
    ),
    "backlash": (
        BacklashLaw(K_MID, 0.0, GAP),
        Coupling("nl", K_MID, backlash=GAP),
        np.full(SAMPLES, 70.0),
    ),
    "backlash damped": (
        BacklashLaw(K_MID, C_MID, GAP),
        Coupling("nl", K_MID, damping=C_MID, backlash=GAP),
        np.full(SAMPLES, 70.0),
    ),
    "curve": (
        CurveLaw(CURVE),
        Coupling("nl", torque_curve=CURVE),
        np.full(SAMPLES, 150.0),
    ),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    law, middle, torque = CASES[request.param]
    run = flexshaft_run(middle, torque, SAMPLES)
    y, element, events = reference(law, torque, SAMPLES)
    return request.param, run, y, element, events


def test_states_and_element_torque_agree(case):
    name, run, y, element, events = case
    assert len(events) >= 5  # the law is exercised: several regime changes in the run
    for i, s in enumerate(STATIONS):
        for what, ref in (("angle", y[:, i]), ("speed", y[:, 4 + i])):
            got = run.outputs[f"{what}:{s}"]
            err = np.abs(got - ref).max() / np.abs(ref).max()
            assert err < AGREE, (name, what, s, err)
    got = run.outputs["torque:nl"]
    err = np.abs(got - element).max() / np.abs(element).max()
    assert err < AGREE, (name, "torque", err)


def test_event_times_agree(case):
    name, run, y, element, events = case
    mine = events[:8]
    theirs = run.nonlinear.events[: len(mine)]
    assert [(e.before, e.after) for e in theirs] == [(b, a) for _, b, a in mine]
    np.testing.assert_allclose([e.time for e in theirs], [t for t, _, _ in mine], rtol=0, atol=EVENT_TIME)
