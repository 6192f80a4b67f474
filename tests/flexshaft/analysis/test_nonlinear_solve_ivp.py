"""Nonlinear time runs against an independent reference: a four-inertia chain's equations of motion,
written here in physical coordinates, integrated by scipy's Radau with terminal event functions and
restarted in the new regime after each event.

The reference uses nothing of flexshaft's matrices, modes or event code: only the element laws as
:mod:`flexshaft.analysis.hybrid`'s docstring defines them (a friction face whose slip angle is a
state, a centred free play whose contact never pulls, a piecewise-linear torque curve), each on the
chain's middle coupling in turn. The energy balance of an undamped slipping run closes the file.
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
INERTIA = np.array([2.0, 1.0, 3.0, 1.5])  # kg·m², a to d
K1, K3 = 2e4, 3e4  # the linear couplings a-b and c-d, N·m/rad
K_MID = 1e4  # the nonlinear coupling b-c (slip, backlash), N·m/rad
# Elastic modes 10.4, 27.6 and 31.5 Hz with the middle coupling stuck or in contact (14 to 40 Hz on the
# torque curve's stiffest segment): 25-100 samples a period at 1 kHz.

# Tolerances. Radau holds each step's local error estimate below rtol = 1e-10 of each state (atol
# 1e-12 rad, rad/s matters only near zero). A run here takes 4 000-7 000 steps and up to ~45
# restarts from an event state read off the dense output; those errors, added with no cancellation
# at all, stay below 7e-7 of a state's peak: hence 1e-6. The element torque is k·Δθ (+ c·Δω), Δθ a
# difference of angles ~100 times larger than it, but the step is set by the speeds (their rigid
# part only ~5 times their elastic part), so an angle's elastic error per step is ~rtol·|ω|/ω_n and
# the torque stays within ~1e-6 of its peak too. flexshaft's exact (expm) steps add only round-off.
# Measured: 1e-10 to 2e-9, the errors of successive steps far from all adding up.
RTOL, ATOL = 1e-10, 1e-12
AGREE = 1e-6
# An event's time: a guard's error over its rate of change. The slowest-crossing guard here is the
# slip speed coming back to zero: its error, 1e-6 of the speeds' peak (~2.4 rad/s), over the slip's
# deceleration (50-140 rad/s²): < 5e-8 s; 1e-7 s is 1e-4 of the step. (Measured: < 1e-10 s.)
EVENT_TIME = 1e-7
N_EVENTS = 10  # events compared one by one, from the first


# --- the reference: the chain's equations of motion and the laws -------------------------------
class SlipLaw:
    """Friction face in series with the spring k and damper c (hybrid.py's docstring).

    Regimes: 0 stuck, ±1 slipping forward / backward. The slip angle s is a state: stuck,
    ``T = k(Δθ − s) + cΔω`` and ṡ = 0; slipping (σ = ±1), ``ṡ = (k(Δθ − s) + cΔω − σT_k)/(c + c_s)``
    and ``T = σT_k + c_s·ṡ`` (with c + c_s = 0: ṡ = Δω, the spring held at σT_k).

    Parameters
    ----------
    k, c : float
        Spring (N·m/rad) and parallel damper (N·m·s/rad).
    static, kinetic : float
        Slip torque and kinetic torque, N·m.
    damping : float
        The slip face's viscous damping c_s, N·m·s/rad.
    """

    start = 0

    def __init__(self, k, c, static, kinetic, damping=0.0):
        self.k, self.c, self.static, self.kinetic, self.damping = k, c, static, kinetic, damping

    @staticmethod
    def label(regime):
        return {0: "stuck", 1: "slipping +", -1: "slipping -"}[regime]

    def torque(self, d, w, s, regime):
        """Transmitted torque (N·m) and slip rate ṡ at relative rotation d, speed w, slip angle s."""
        k, c, cs = self.k, self.c, self.damping
        if regime == 0:
            return k * (d - s) + c * w, 0.0
        if c + cs == 0.0:
            return regime * self.kinetic, w
        rate = (k * (d - s) + c * w - regime * self.kinetic) / (c + cs)
        return regime * self.kinetic + cs * rate, rate

    def guards(self, regime):
        """``[(g(d, w, s), next regime), ...]``, each g positive inside ``regime``."""
        if regime == 0:
            # the stuck torque reaches the slip torque, forwards or backwards
            return [
                (lambda d, w, s: self.static - self.torque(d, w, s, 0)[0], 1),
                (lambda d, w, s: self.static + self.torque(d, w, s, 0)[0], -1),
            ]
        # the slip speed comes back to zero
        return [(lambda d, w, s: regime * self.torque(d, w, s, regime)[1], 0)]

    def enter(self, d, s, regime):
        """The slip angle just after switching into ``regime`` at relative rotation d (slip angle s)."""
        if regime != 0 and self.c + self.damping == 0.0:
            # no damper: the spring lets go from the static to the kinetic torque at once
            return d - regime * self.kinetic / self.k
        return s


class BacklashLaw:
    """Centred free play b; contact through k and c while the contact pushes.

    Regimes: 0 apart inside the play, ±1 in contact (``T = k(Δθ ∓ b/2) + cΔω``), ±2 apart though
    past ±b/2 (the damper would have pulled: the sides part at zero torque, and touch again where
    the contact would push, or go back inside the play).

    Parameters
    ----------
    k, c, gap : float
        Contact stiffness (N·m/rad), damper (N·m·s/rad), total free play (rad).
    """

    start = 0

    def __init__(self, k, c, gap):
        self.k, self.c, self.gap = k, c, gap

    @staticmethod
    def label(regime):
        return {0: "apart", 1: "contact +", -1: "contact -", 2: "apart", -2: "apart"}[regime]

    def push(self, d, w, side):
        """The torque a contact on ``side`` (±1) would carry, positive when it pushes, N·m."""
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
            # without a damper the contact torque reaches zero exactly at the edge of the play
            return [(lambda d, w, s: self.push(d, w, side), 2 * side if self.c > 0 else 0)]
        return [
            (lambda d, w, s: side * d - half, 0),
            (lambda d, w, s: -self.push(d, w, side), side),
        ]

    @staticmethod
    def enter(d, s, regime):
        return s


class CurveLaw:
    """Torque against relative rotation, piecewise linear through the given points and on with the
    end slopes, a damper c in parallel.

    Regime j: between points j − 1 and j (0: below the first point, n: above the last), so each
    listed point is an event where the rotation crosses it.

    Parameters
    ----------
    points : array_like (n, 2)
        [angle (rad), torque (N·m)], both increasing, through (0, 0).
    c : float
    """

    def __init__(self, points, c=0.0):
        self.angle, self.value = np.asarray(points, dtype=float).T
        self.c = c
        slopes = np.diff(self.value) / np.diff(self.angle)
        self.slopes = np.concatenate([slopes[:1], slopes, slopes[-1:]])
        self.start = int(np.searchsorted(self.angle, 0.0, side="right"))

    @staticmethod
    def label(regime):
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

    @staticmethod
    def enter(d, s, regime):
        return s


def chain_rates(y, drive, law, regime):
    """The chain's state rates, y = [θ_a..θ_d, ω_a..ω_d, s], under the drive torque at a (N·m).

    J_a·θ_a'' = T − T₁,  J_b·θ_b'' = T₁ − T_nl,  J_c·θ_c'' = T_nl − T₃,  J_d·θ_d'' = T₃,
    with T₁ = K1·(θ_a − θ_b), T₃ = K3·(θ_c − θ_d) and T_nl the middle coupling's law.
    """
    th, om, s = y[:4], y[4:8], y[8]
    t1 = K1 * (th[0] - th[1])
    t_nl, s_rate = law.torque(th[1] - th[2], om[1] - om[2], s, regime)
    t3 = K3 * (th[2] - th[3])
    acc = np.array([drive - t1, t1 - t_nl, t_nl - t3, t3]) / INERTIA
    return np.concatenate([om, acc, [s_rate]])


def reference(law, torque):
    """The chain from rest under a drive torque held over each step, by Radau with terminal events.

    Parameters
    ----------
    law : SlipLaw, BacklashLaw or CurveLaw
        The middle coupling's.
    torque : ndarray
        The drive torque held over [k·dt, (k+1)·dt), N·m, one per sample.

    Returns
    -------
    y : ndarray (samples, 9)
        The state at the sample times.
    element : ndarray (samples,)
        The middle coupling's torque there, N·m.
    events : list of (time, before, after)
    """
    samples = torque.size
    t_s = np.arange(samples) * DT
    y_out = np.full((samples, 9), np.nan)
    regime_at = np.zeros(samples, dtype=int)
    y, t, regime, events = np.zeros(9), 0.0, law.start, []
    # integrate over each piece where the held torque is constant (the drive's jumps are no events)
    changes = np.flatnonzero(np.diff(torque[: samples - 1]) != 0.0) + 1
    bounds = np.concatenate([[0], changes, [samples - 1]])
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        drive, t_end = torque[lo], t_s[hi]
        while t < t_end:
            guards = law.guards(regime)

            def rates(_, x, drive=drive, regime=regime):
                return chain_rates(x, drive, law, regime)

            # each regime is affine in the state: unit differences give its Jacobian exactly
            f0 = rates(0.0, np.zeros(9))
            jac = np.column_stack([rates(0.0, e) - f0 for e in np.eye(9)])
            funcs = []
            for g, _ in guards:

                def event(_, x, g=g):
                    return g(x[1] - x[2], x[5] - x[6], x[8])

                event.terminal, event.direction = True, -1  # a guard falling through zero
                funcs.append(event)
            inside = np.flatnonzero((t_s >= t) & (t_s <= t_end))
            sol = solve_ivp(
                rates,
                (t, t_end),
                y,
                method="Radau",
                rtol=RTOL,
                atol=ATOL,
                jac=jac,
                t_eval=t_s[inside],
                events=funcs,
            )
            assert sol.success, sol.message
            # a piece's last sample is the next piece's first: the same state, read twice
            got = inside[: len(sol.t)]
            y_out[got] = np.reshape(sol.y, (9, -1)).T
            regime_at[got] = regime
            if sol.status != 1:
                y, t = sol.y[:, -1], t_end
                continue
            fired = min((te[0], i) for i, te in enumerate(sol.t_events) if te.size)[1]
            t, y = float(sol.t_events[fired][0]), sol.y_events[fired][0].copy()
            after = guards[fired][1]
            y[8] = law.enter(y[1] - y[2], y[8], after)
            events.append((t, law.label(regime), law.label(after)))
            regime = after
    element = np.array([law.torque(v[1] - v[2], v[5] - v[6], v[8], r)[0] for v, r in zip(y_out, regime_at)])
    return y_out, element, events


# --- flexshaft's run of the same chain -----------------------------------------------------------
OUTPUTS = [f"angle:{s}" for s in STATIONS] + [f"speed:{s}" for s in STATIONS]
OUTPUTS += ["torque:k1", "torque:nl", "torque:k3"]


def flexshaft_run(middle, torque):
    """flexshaft's run of the chain with ``middle`` as its b-c coupling, every mode kept.

    Parameters
    ----------
    middle : Coupling
        Named ``"nl"``.
    torque : ndarray
        The drive torque at each sample time, held over the step after it, N·m.
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
    if np.all(torque == torque[0]):
        scenario = Scenario.step(float(torque[0]), at="a")
    else:
        scenario = Scenario.from_series(np.arange(torque.size) * DT, torque, at="a")
    duration = (torque.size - 1) * DT
    return simulate(res, scenario, OUTPUTS, rate=RATE, duration=duration, max_hz=float("inf"))


def square(amplitude, half_period, samples):
    """±amplitude (N·m) at the sample times, reversing every ``half_period`` s."""
    k = np.arange(samples)
    return amplitude * np.where((k // round(half_period * RATE)) % 2 == 0, 1.0, -1.0)


# A held step cannot keep a friction face slipping and sticking: once it sticks with the line's mean
# torque below the kinetic torque it stays stuck (two events in all, whatever the step's size). A
# drive reversing every 0.1 s slips it forwards and back, ~2 events per reversal. The other laws take
# a held step: the free play's contacts bounce and the curve's segments are crossed many times.
T_S, T_K, GAP = 60.0, 45.0, 0.01
C_MID, C_SLIP = 5.0, 2.0  # the damped cases' coupling damper and slip-face damping, N·m·s/rad
CURVE = [[0.0, 0.0], [0.004, 40.0], [0.008, 120.0], [0.012, 240.0]]  # 1e4, 2e4, 3e4 N·m/rad
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
    "backlash": (BacklashLaw(K_MID, 0.0, GAP), Coupling("nl", K_MID, backlash=GAP), np.full(SAMPLES, 70.0)),
    "backlash damped": (
        BacklashLaw(K_MID, C_MID, GAP),
        Coupling("nl", K_MID, damping=C_MID, backlash=GAP),
        np.full(SAMPLES, 70.0),
    ),
    "curve": (CurveLaw(CURVE), Coupling("nl", torque_curve=CURVE), np.full(SAMPLES, 150.0)),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    law, middle, torque = CASES[request.param]
    return flexshaft_run(middle, torque), *reference(law, torque)


def test_states_and_element_torque_agree_with_radau(case):
    run, y, element, events = case
    # the law is exercised: it changes regime many times in the run
    assert len(events) >= N_EVENTS
    for i, s in enumerate(STATIONS):
        for what, ref in (("angle", y[:, i]), ("speed", y[:, 4 + i])):
            np.testing.assert_allclose(
                run.outputs[f"{what}:{s}"], ref, rtol=0, atol=AGREE * np.abs(ref).max(), err_msg=f"{what}:{s}"
            )
    np.testing.assert_allclose(run.outputs["torque:nl"], element, rtol=0, atol=AGREE * np.abs(element).max())


def test_event_times_agree_with_radau(case):
    run, _, _, events = case
    assert run.nonlinear.event_count == len(events)
    theirs = run.nonlinear.events[:N_EVENTS]
    mine = events[:N_EVENTS]
    assert [(e.before, e.after) for e in theirs] == [(before, after) for _, before, after in mine]
    np.testing.assert_allclose([e.time for e in theirs], [t for t, _, _ in mine], rtol=0, atol=EVENT_TIME)


# --- energy balance -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    "samples",
    [
        541,  # the run ends stuck (last event, sticking, at 0.516 s)
        SAMPLES,  # the run ends slipping (since 0.548 s): the account stops at the last sample
    ],
)
def test_energy_balance_undamped_slip(samples):
    """Input work = kinetic + spring energies + what the slip face dissipated, at the last sample.

    The work of a torque held over a step is exactly T·(θ_a(k+1) − θ_a(k)); each spring holds
    T²/(2k) (the slipping coupling's spring carries its transmitted torque: no damper); the face
    dissipates T_k per radian of slip plus the spring energy released at each slip onset.
    """
    _, middle, _ = CASES["slip"]
    torque = square(100.0, 0.1, samples)
    run = flexshaft_run(middle, torque)
    o = run.outputs
    work = np.sum(torque[:-1] * np.diff(o["angle:a"]))
    kinetic = 0.5 * sum(j * o[f"speed:{s}"][-1] ** 2 for j, s in zip(INERTIA, STATIONS))
    springs = sum(0.5 * o[f"torque:{n}"][-1] ** 2 / k for n, k in (("k1", K1), ("nl", K_MID), ("k3", K3)))
    assert run.nonlinear.elements[0].events >= 8  # several slipping phases dissipated
    assert kinetic + springs + run.nonlinear.elements[0].dissipated == pytest.approx(work, rel=1e-6)
