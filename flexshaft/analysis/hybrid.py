"""Time runs with nonlinear couplings and gear meshes: linear systems joined at events.

The plant is the modal state space the linear run uses (:mod:`flexshaft.analysis.statespace`), in
which each nonlinear element (:mod:`flexshaft.model.nonlinear`) is its linear self: stuck, in
contact, at its tangent stiffness at zero torque, transmitting ``k·Δθ + c·Δω``. Its true torque T
differs from that by ΔT, applied as a torque pair at its two nodes (−ΔT on the driving side, n·ΔT
on the driven side, as the element's own torque acts). Every law is piecewise linear: in each of
its regimes ΔT is an affine function of the state,

- slip: stuck ``T = k(Δθ − s) + cΔω`` (s: the slip angle so far, a state); slipping forward or
  backward (σ = ±1) ``T = σT_k + c_s·ṡ``, the spring and damper carrying the same torque through a
  massless hub, so ``ṡ = (k(Δθ − s) + cΔω − σT_k)/(c + c_s)`` (with c + c_s = 0: ``ṡ = Δω`` and the
  spring stays at σT_k, the drop from the static to the kinetic torque released at once);
- backlash: apart ``T = 0``; in contact ``T = k(Δθ ∓ b/2) + cΔω`` while that pushes (a contact
  never pulls: where its damper would pull, the sides come apart with the torque at zero);
- curve: on segment j ``T = T_j + k_j(Δθ − θ_j) + cΔω``;

so between events the drivetrain is one linear system. The augmented state is ``[η, η̇, s, 1]``
(modal coordinates and rates, one slip angle per slipping coupling, a constant for the offsets).
Each regime's system is discretised exactly by zero-order hold and run in blocks through its Schur
form (:class:`~flexshaft.linalg.recursion.TriangularRecursion`); with the speed loop closed, the
loop's discrete forms (:mod:`flexshaft.analysis.discreteloop`) are built on it. Each regime has
guards, affine functions of the state that are positive inside it (the stuck torque below the slip
torque, the slip speed of the slip's sign, the relative rotation inside the gap, the contact torque
pushing). A guard found negative at a sample (below −10⁻⁹ of its scale) means an event inside the
step before: it is located by a safeguarded Newton iteration on the exact solution within the step
(``expm`` of the regime's matrix with the step's held input), to :data:`EVENT_TIME_TOLERANCE` of the
step; the regime switches there and the step goes on from that instant in the new one. So stick,
slip, contact and release happen at their times, not at samples, and the samples stay on their
grid. What happens and comes back within one step (a contact shorter than the step) is not seen:
the rate must resolve the element's own oscillation, which modes kept up to the rate do.

Energy dissipated by a slip face is counted exactly: the kinetic torque times the slip angle of
each slipping phase (the slip speed keeps its sign through it), plus the spring energy released
where the torque drops from the static to the kinetic slip torque; the viscous ``slip_damping`` part
is not counted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import ModelError
from ..linalg.recursion import TriangularRecursion
from .discreteloop import BLOCK_MAX, BLOCK_MIN, limit_crossed, limit_switched, loop_form, zoh
from .scenario import torque_limits
from .statespace import element_rows

__all__ = [
    "NonlinearElement",
    "ElementRun",
    "Event",
    "NonlinearRun",
    "HybridPlant",
    "nonlinear_elements",
    "EVENT_TIME_TOLERANCE",
    "GUARD_TOLERANCE",
    "MAX_EVENTS_PER_STEP",
    "MAX_EVENTS_KEPT",
    "ACTIVE_MEANS",
]

#: Events are located in time to this fraction of the step (Newton's method on the exact solution).
EVENT_TIME_TOLERANCE = 1e-12
#: A guard counts as crossed below −GUARD_TOLERANCE times its scale (the slip torque, the free play,
#: ...): round-off of a state just switched cannot set off an event of its own.
GUARD_TOLERANCE = 1e-9
#: The most events one step may hold; more means the element chatters between regimes.
MAX_EVENTS_PER_STEP = 64
#: The events listed in a result; beyond that they are counted only.
MAX_EVENTS_KEPT = 10_000
#: What an element's active time is, by law.
ACTIVE_MEANS = {"slip": "slipping", "backlash": "in contact", "curve": "off its zero segment"}


@dataclass(frozen=True)
class NonlinearElement:
    """A nonlinear coupling or gear mesh bound to the plant's augmented state (module docstring).

    Attributes
    ----------
    name : str
    law : Slip, Backlash or TorqueCurve
    angle, speed : ndarray
        Rows reading Δθ (rad) and Δω (rad/s) from the augmented state.
    stiffness, damping : float
        The linear element: k (N·m/rad) and c (N·m·s/rad).
    slot : int
        Index of its slip angle in the augmented state (−1 without one).
    """

    name: str
    law: object
    angle: np.ndarray
    speed: np.ndarray
    stiffness: float
    damping: float
    slot: int

    @property
    def force(self) -> np.ndarray:
        """The augmented state's rates per N·m of ΔT: the torque pair's generalised force, −φ on the
        modal rates - minus the speed row, the element's relative rotation read on the modes."""
        return -self.speed


@dataclass(frozen=True)
class Event:
    """One regime change: at ``time`` (s) ``element`` went from ``before`` to ``after``, carrying
    ``torque`` (N·m)."""

    time: float
    element: str
    before: str
    after: str
    torque: float


@dataclass(frozen=True)
class ElementRun:
    """What one nonlinear element did in a run.

    Attributes
    ----------
    name, law : str
        The component and its law (``"slip"``, ``"backlash"``, ``"curve"``).
    events : int
        Its regime changes.
    active_time : float
        Time slipping (slip), in contact (backlash) or off the curve's segment through zero, s.
    peak_torque : float
        Largest transmitted torque, N·m (at the samples and the events).
    dissipated : float
        Energy the slip face dissipated, J (module docstring); 0 for the other laws.
    """

    name: str
    law: str
    events: int
    active_time: float
    peak_torque: float
    dissipated: float

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "law": self.law,
            "events": self.events,
            "active_time_s": self.active_time,
            "peak_torque": self.peak_torque,
            "dissipated_J": self.dissipated,
        }


@dataclass(frozen=True)
class NonlinearRun:
    """The nonlinear part of a run: each element's account and the events.

    Attributes
    ----------
    elements : tuple of ElementRun
    events : tuple of Event
        The first :data:`MAX_EVENTS_KEPT`, in time order.
    event_count : int
        All of them.
    tolerance : str
        How the events were located.
    """

    elements: tuple
    events: tuple
    event_count: int
    tolerance: str

    def to_dict(self) -> dict:
        return {
            "tolerance": self.tolerance,
            "events": self.event_count,
            "elements": [e.to_dict() for e in self.elements],
            "first_events": [
                {"time_s": e.time, "element": e.element, "from": e.before, "to": e.after, "torque": e.torque}
                for e in self.events[:100]
            ],
        }

    def table(self) -> str:
        lines = [f"nonlinear elements ({self.event_count} events, {self.tolerance}):"]
        for e in self.elements:
            lines.append(
                f"  {e.name}: {e.law}, {e.events} events, {ACTIVE_MEANS[e.law]} {e.active_time:.6g} s, "
                f"peak torque {e.peak_torque:.6g} N·m"
                + (f", dissipated {e.dissipated:.6g} J" if e.law == "slip" else "")
            )
        return "\n".join(lines)


def nonlinear_elements(model) -> list:
    """The components of ``model`` (an AssembledModel) that carry a nonlinear law."""
    return [c for c in model.drivetrain.components if getattr(c, "law", None) is not None]


# Regimes. slip: 0 stuck, ±1 slipping; backlash: 0 apart, ±1 in contact, ±2 apart but overlapping
# (the damper would pull); curve: the segment index (the curve's slopes index).
_SLIP_LABELS = {0: "stuck", 1: "slipping +", -1: "slipping -"}
_BACKLASH_LABELS = {0: "apart", 1: "contact +", -1: "contact -", 2: "apart", -2: "apart"}


def _label(law, regime: int) -> str:
    if law.kind == "slip":
        return _SLIP_LABELS[regime]
    if law.kind == "backlash":
        return _BACKLASH_LABELS[regime]
    return f"segment {regime}"


class HybridPlant:
    """The drivetrain's regimes: each one's continuous and discrete system, guards and outputs.

    Parameters
    ----------
    result : ModalResult
    ss : StateSpace
        The linear plant (inputs: drive, load; outputs: the run's, the measured speed last).
    dt : float
        The step, s.
    """

    def __init__(self, result, ss, dt: float) -> None:
        model = result.model
        m = ss.A.shape[0] // 2
        Phi = result.shapes[:, ss.modes]
        rigid = result.rigid[ss.modes]
        comps = nonlinear_elements(model)
        slips = [c for c in comps if c.law.kind == "slip"]
        N = 2 * m + len(slips) + 1
        self.m, self.N, self.dt, self.const = m, N, dt, N - 1
        A0 = np.zeros((N, N))
        A0[: 2 * m, : 2 * m] = ss.A
        self.B = np.zeros((N, ss.B.shape[1]))
        self.B[: 2 * m] = ss.B
        self.A0 = A0
        elements = []
        for c in comps:
            diff, k, cd = element_rows(model, c.name)
            phi = diff @ Phi
            phi[rigid] = 0.0  # a rigid-body rotation strains no element (exactly; round-off aside)
            angle, speed = np.zeros(N), np.zeros(N)
            angle[:m], speed[m : 2 * m] = phi, phi
            slot = 2 * m + slips.index(c) if c in slips else -1
            elements.append(NonlinearElement(c.name, c.law, angle, speed, k, cd, slot))
        self.elements = tuple(elements)
        self.outputs = list(ss.outputs)
        self.C0 = np.zeros((len(self.outputs), N))
        self.C0[:, : 2 * m] = ss.C
        self._systems: dict = {}

    # -- one element's affine rows in a regime ---------------------------------------------------

    def _unit(self, i: int) -> np.ndarray:
        e = np.zeros(self.N)
        e[i] = 1.0
        return e

    def slip_rate(self, el: NonlinearElement, regime: int) -> np.ndarray:
        """ṡ of a slip element as a row on the augmented state (zero while stuck)."""
        if regime == 0:
            return np.zeros(self.N)
        law, k, c = el.law, el.stiffness, el.damping
        if c + law.damping == 0.0:
            return el.speed.copy()
        row = (
            k * (el.angle - self._unit(el.slot))
            + c * el.speed
            - regime * law.kinetic_torque * self._unit(self.const)
        )
        return row / (c + law.damping)

    def torque(self, el: NonlinearElement, regime: int) -> np.ndarray:
        """The element's transmitted torque in ``regime`` as a row on the augmented state, N·m."""
        law, k, c, one = el.law, el.stiffness, el.damping, self._unit(self.const)
        if law.kind == "slip":
            if regime == 0:
                return k * (el.angle - self._unit(el.slot)) + c * el.speed
            return regime * law.kinetic_torque * one + law.damping * self.slip_rate(el, regime)
        if law.kind == "backlash":
            if regime in (1, -1):
                return k * (el.angle - regime * 0.5 * law.gap * one) + c * el.speed
            return np.zeros(self.N)
        return law.offsets[regime] * one + law.slopes[regime] * el.angle + c * el.speed

    def guards(self, el: NonlinearElement, regime: int) -> list:
        """``[(row, scale, next regime), ...]``: each guard positive inside ``regime``."""
        law, one = el.law, self._unit(self.const)
        if law.kind == "slip":
            if regime == 0:
                t = self.torque(el, 0)
                return [(law.torque * one - t, law.torque, 1), (law.torque * one + t, law.torque, -1)]
            # the scale: the slip speed that winds the spring to the slip torque in one step
            return [(regime * self.slip_rate(el, regime), law.torque / (el.stiffness * self.dt), 0)]
        if law.kind == "backlash":
            b, kb = law.gap, el.stiffness * law.gap
            push = {s: el.stiffness * (el.angle - s * 0.5 * b * one) + el.damping * el.speed for s in (1, -1)}
            if regime == 0:
                return [(0.5 * b * one - el.angle, b, 1), (el.angle + 0.5 * b * one, b, -1)]
            s = 1 if regime > 0 else -1
            if regime in (1, -1):
                # contact ends where it would pull: apart, or overlapping while the damper holds on
                return [(s * push[s], kb, 2 * s if el.damping > 0 else 0)]
            return [(s * (el.angle - s * 0.5 * b * one), b, 0), (-s * push[s], kb, s)]
        out = []
        scale = float(np.ptp(law.angle)) if law.angle.size > 1 else 1.0
        if regime > 0:
            out.append((el.angle - law.angle[regime - 1] * one, scale, regime - 1))
        if regime < law.angle.size:
            out.append((law.angle[regime] * one - el.angle, scale, regime + 1))
        return out

    def initial_regime(self, el: NonlinearElement, X: np.ndarray) -> int:
        """The regime the element is in at state X (at rest: stuck, apart, the segment through zero)."""
        law = el.law
        if law.kind == "slip":
            return 0
        d = float(el.angle @ X)
        if law.kind == "backlash":
            return 0 if abs(d) <= 0.5 * law.gap else (1 if d > 0 else -1)
        return int(law.segment_of(d))

    # -- a regime's system -----------------------------------------------------------------------

    def system(self, regimes: tuple) -> dict:
        """The continuous matrix, discrete plant, outputs and guards of ``regimes`` (cached)."""
        got = self._systems.get(regimes)
        if got is not None:
            return got
        A = self.A0.copy()
        C = self.C0.copy()
        torques, guards, scales, targets = [], [], [], []
        for el, r in zip(self.elements, regimes):
            t = self.torque(el, r)
            linear = el.stiffness * el.angle + el.damping * el.speed
            A += np.outer(el.force, t - linear)
            if el.slot >= 0:
                A[el.slot] = self.slip_rate(el, r)
            if f"torque:{el.name}" in self.outputs:
                C[self.outputs.index(f"torque:{el.name}")] = t
            torques.append(t)
            g = self.guards(el, r)
            g += [(self._unit(self.const), 1.0, None)] * (2 - len(g))  # always positive: no guard
            for row, scale, nxt in g:
                guards.append(row)
                scales.append(scale)
                targets.append(nxt)
        Ad, Bd = zoh(A, self.B, self.dt)
        got = {
            "A": A,
            "Ad": Ad,
            "Bd": Bd,
            # the run's outputs, the element torques, the guards, then the measured speed again (last:
            # the speed loop reads the last row)
            "C": np.vstack([C, np.array(torques), np.array(guards), C[-1:]]),
            "guards": np.array(guards),
            "tolerance": GUARD_TOLERANCE * np.array(scales),
            "targets": targets,
            "forms": {},
        }
        self._systems[regimes] = got
        return got


def _crossing(row: np.ndarray, M: np.ndarray, X: np.ndarray, X_end: np.ndarray, h: float, dt: float) -> float:
    """When the guard ``row·X(τ)`` first goes from positive to zero in [0, h], given it is negative at
    h; X(τ) = expm(M·τ)·X is the exact motion (M: the regime's matrix with the step's input held).

    Newton's method on the exact guard and its exact rate row·M·X(τ), started from the cubic through
    the guard's values and rates at the step's ends and kept inside a bracket (a step out of it
    bisects): two or three matrix exponentials an event, to :data:`EVENT_TIME_TOLERANCE` of the step.
    A guard that starts at zero - within its tolerance, just switched to and rising - is followed over
    eight sub-steps to the last positive value before it falls; one that is nowhere positive crosses
    at once (τ = 0).
    """

    def at(tau):
        x = sla.expm(M * tau) @ X
        return float(row @ x), float(row @ (M @ x))

    tol = EVENT_TIME_TOLERANCE * dt
    lo, hi = 0.0, h
    g_lo, d_lo = float(row @ X), float(row @ (M @ X))
    g_hi, d_hi = float(row @ X_end), float(row @ (M @ X_end))
    if g_lo <= 0.0:
        points = h * np.arange(1, 9) / 8.0
        values = [at(p) for p in points]
        positive = [j for j, v in enumerate(values) if v[0] > 0.0]
        if not positive:
            return 0.0
        j = next(j for j in range(positive[0], 8) if values[j][0] <= 0.0)
        lo, hi = points[j - 1], points[j]
        (g_lo, d_lo), (g_hi, d_hi) = values[j - 1], values[j]
    # the cubic (Hermite) through both ends: its first sign change on a fine grid starts Newton
    s = np.linspace(0.0, 1.0, 65)
    width = hi - lo
    cubic = (
        (2 * s**3 - 3 * s**2 + 1) * g_lo
        + (s**3 - 2 * s**2 + s) * width * d_lo
        + (-2 * s**3 + 3 * s**2) * g_hi
        + (s**3 - s**2) * width * d_hi
    )
    change = np.flatnonzero((cubic[:-1] > 0.0) & (cubic[1:] <= 0.0))
    if change.size:
        c = int(change[0])
        tau = lo + width * (s[c] + (s[c + 1] - s[c]) * cubic[c] / (cubic[c] - cubic[c + 1]))
    else:
        tau = lo + width * g_lo / (g_lo - g_hi)
    for _ in range(60):
        g, d = at(tau)
        if g > 0.0:
            lo = tau
        else:
            hi = tau
        step = -g / d if d != 0.0 else math.inf
        nxt = tau + step
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - tau) <= tol or hi - lo <= tol:
            return nxt
        tau = nxt
    return 0.5 * (lo + hi)


def _held(A: np.ndarray, Bw: np.ndarray, const: int) -> np.ndarray:
    """The regime's matrix with the step's held input folded into the constant state's column: the
    motion over the step is X(τ) = expm(M·τ)·X, exactly."""
    M = A.copy()
    M[:, const] += Bw
    return M


class _Run:
    """One run's bookkeeping: the regimes, the events and each element's account."""

    def __init__(self, plant: HybridPlant, regimes: tuple) -> None:
        self.plant, self.regimes = plant, regimes
        n = len(plant.elements)
        self.events: list = []
        self.count = np.zeros(n, dtype=int)
        self.active = np.zeros(n)
        self.since = np.zeros(n)
        self.peak = np.zeros(n)
        self.dissipated = np.zeros(n)
        self.slip_from = np.zeros(n)

    def step(self, X: np.ndarray, w: np.ndarray, k: int) -> np.ndarray:
        """Step k from state X under the held plant input w, events and all: the state at k + 1."""
        plant = self.plant
        dt, t0 = plant.dt, 0.0
        Bw = plant.B @ w
        for _ in range(MAX_EVENTS_PER_STEP):
            sys = plant.system(self.regimes)
            M = _held(sys["A"], Bw, plant.const)
            X_end = sla.expm(M * (dt - t0)) @ X
            g_end = sys["guards"] @ X_end
            crossed = np.flatnonzero(g_end < -sys["tolerance"])
            if crossed.size == 0:
                return X_end
            first, at = None, dt - t0
            for i in crossed:
                tau = _crossing(sys["guards"][i], M, X, X_end, dt - t0, dt)
                if tau < at or first is None:
                    first, at = i, tau
            X = sla.expm(M * at) @ X
            t0 += at
            X = self.switch(int(first), X, (k * dt) + t0, sys)
            X = self.consistent(X, Bw, (k * dt) + t0)
        raise ModelError(
            f"changes regime more than {MAX_EVENTS_PER_STEP} times in the step at t = {k * dt:g} s: it"
            " chatters between stick and slip or contact and release",
            field="rate",
            value=1.0 / dt,
            unit="Hz",
            valid="a higher rate, some damping on the element, or a slip_kinetic_torque below slip_torque",
        )

    def consistent(self, X: np.ndarray, Bw: np.ndarray, time: float) -> np.ndarray:
        """Leave at once a regime just entered that the motion leaves at once: a guard at zero (within
        its tolerance) and falling - a stuck torque that touched the slip torque and turns back, a
        slip speed that would change sign as it starts. Its own transition is taken at the same
        instant (both events listed); a regime still inconsistent after that is a sliding motion
        the laws do not define, refused as chattering by the step."""
        plant = self.plant
        for _ in range(2 * len(plant.elements) + 2):
            sys = plant.system(self.regimes)
            M = _held(sys["A"], Bw, plant.const)
            g, rate = sys["guards"] @ X, sys["guards"] @ (M @ X)
            # falling: it would pass its tolerance within a step at this rate (a rate of round-off's
            # size, where the first derivative vanishes, decides nothing: the crossing is then found
            # as any other)
            leaving = np.flatnonzero((g <= sys["tolerance"]) & (rate * plant.dt < -sys["tolerance"]))
            if leaving.size == 0:
                return X
            X = self.switch(int(leaving[0]), X, time, sys)
        return X

    def switch(self, guard: int, X: np.ndarray, time: float, sys: dict) -> np.ndarray:
        """Apply the regime change of ``guard`` at ``time`` (state X there); the state after it."""
        plant = self.plant
        e = guard // 2
        el = plant.elements[e]
        before = self.regimes[e]
        after = sys["targets"][guard]
        torque = float(plant.torque(el, before) @ X)
        if el.law.kind == "slip":
            if after != 0:
                if el.stiffness and el.damping + el.law.damping == 0.0:
                    # massless hub, no damper: the spring drops to the kinetic torque at once
                    d_before = float((el.angle - plant._unit(el.slot)) @ X)
                    X = X.copy()
                    X[el.slot] = float(el.angle @ X) - after * el.law.kinetic_torque / el.stiffness
                    d_after = float((el.angle - plant._unit(el.slot)) @ X)
                    self.dissipated[e] += 0.5 * el.stiffness * (d_before**2 - d_after**2)
                self.slip_from[e] = X[el.slot]
            else:
                self.dissipated[e] += el.law.kinetic_torque * abs(X[el.slot] - self.slip_from[e])
        if self._active(el, before):
            self.active[e] += time - self.since[e]
        if self._active(el, after):
            self.since[e] = time
        regimes = list(self.regimes)
        regimes[e] = after
        self.regimes = tuple(regimes)
        self.count[e] += 1
        self.peak[e] = max(self.peak[e], abs(torque))
        if len(self.events) < MAX_EVENTS_KEPT:
            self.events.append(Event(time, el.name, _label(el.law, before), _label(el.law, after), torque))
        return X

    @staticmethod
    def _active(el: NonlinearElement, regime: int) -> bool:
        if el.law.kind == "curve":
            return regime != int(el.law.segment_of(0.0))
        return regime in (1, -1)

    def start(self, time: float) -> None:
        for e, el in enumerate(self.plant.elements):
            if self._active(el, self.regimes[e]):
                self.since[e] = time

    def finish(self, X: np.ndarray, time: float) -> NonlinearRun:
        for e, el in enumerate(self.plant.elements):
            if self._active(el, self.regimes[e]):
                self.active[e] += time - self.since[e]
            if el.law.kind == "slip" and self.regimes[e] != 0:
                self.dissipated[e] += el.law.kinetic_torque * abs(X[el.slot] - self.slip_from[e])
        elements = tuple(
            ElementRun(
                el.name,
                el.law.kind,
                int(self.count[e]),
                float(self.active[e]),
                float(self.peak[e]),
                float(self.dissipated[e]),
            )
            for e, el in enumerate(self.plant.elements)
        )
        tol = (
            f"events located to {EVENT_TIME_TOLERANCE:g} of the step on the exact solution; guards"
            f" crossed below {GUARD_TOLERANCE:g} of their scale"
        )
        return NonlinearRun(elements, tuple(self.events), int(self.count.sum()), tol)


def initial(plant: HybridPlant, X0: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, tuple]:
    """The augmented start state and regimes from the linear plant's start state ``X0`` (modal part)
    under the steady input ``w`` (drive, load torques): at rest as it is; preloaded, each elastic mode
    at its static deflection in the regimes the preload puts the elements in."""
    N, m = plant.N, plant.m
    X = np.zeros(N)
    X[: 2 * m] = X0
    X[plant.const] = 1.0
    regimes = tuple(plant.initial_regime(el, X) for el in plant.elements)
    if not np.any(w):
        return X, regimes
    for _ in range(len(plant.elements) + 2):
        sys = plant.system(regimes)
        A = sys["A"]
        elastic = np.flatnonzero(np.abs(np.diag(A[m : 2 * m, :m])) > 0)
        if elastic.size:
            rows = m + elastic
            rhs = -(A[rows] @ X - A[np.ix_(rows, elastic)] @ X[elastic]) - plant.B[rows] @ w
            X[elastic] = np.linalg.solve(A[np.ix_(rows, elastic)], rhs)
        new = tuple(plant.initial_regime(el, X) for el in plant.elements)
        for el in plant.elements:
            if el.law.kind == "slip" and abs(plant.torque(el, 0) @ X) > el.law.torque:
                raise ModelError(
                    f"carries {abs(plant.torque(el, 0) @ X):.6g} N·m at the start, above its slip torque:"
                    " the line cannot start steady",
                    field="slip_torque",
                    value=el.law.torque,
                    unit="N·m",
                    valid="a start torque (load, coast torque) below the slip torque",
                    component=repr(el.name),
                )
        if new == regimes:
            return X, regimes
        regimes = new
    return X, regimes


def run(
    plant: HybridPlant, X0: np.ndarray, regimes: tuple, W: np.ndarray, loop=None, progress=None, stepped=False
):
    """The run: plant outputs at every sample (and with the loop closed, the applied torque).

    Parameters
    ----------
    plant : HybridPlant
    X0 : ndarray
        Augmented start state (with the loop closed: then the integrator and low-pass states follow).
    regimes : tuple of int
    W : ndarray, shape (L, p)
        Open: [drive, load] per sample. Closed: [set-point, load, 0, disturbance].
    loop : (SpeedControl, float), optional
        The speed controller, and the torque the integrator and low-pass start at.
    progress : callable, optional
    stepped : bool
        Step one sample at a time (the reference) instead of running blocks.

    Returns
    -------
    Y : ndarray (L, outputs)
    T : ndarray (L,) or None
        The applied air-gap torque (closed loop).
    summary : NonlinearRun
    method : str
    """
    L = W.shape[0]
    n_out = len(plant.outputs)
    book = _Run(plant, regimes)
    book.start(0.0)
    Y = np.empty((L, n_out))
    Tq = np.empty(L) if loop is not None else None
    N = plant.N
    if loop is not None:
        control, hold = loop
        s = np.concatenate([X0, [hold, hold]])
        lo, hi = control.torque_min, control.torque_max
    else:
        s = X0.copy()
    held, limit = False, 0.0
    k, size, switches = 0, BLOCK_MIN, 0
    n_el = len(plant.elements)
    last = L - 1  # the steps run: from each sample to the next, none past the last sample
    power = loop is not None and math.isfinite(loop[0].power_limit)
    while k < last:
        sys = plant.system(book.regimes)
        if power:  # the limits move with the speed: each sample clamped by itself
            was = held
            held, limit = _power_clamp(sys, loop, s, W[k], n_out, plant.dt)
            switches += held != was
        form = _form(sys, held, loop, plant.dt)
        size_now = 1 if stepped or power else min(size, last - k)
        Wb = W[k : k + size_now].copy()
        if loop is not None:
            Wb[:, 2] = limit
        if size_now == 1:
            y_k, s_end = form.one(s, Wb[0])
            out = y_k[None]
        else:
            out, s_end = form.block(s, Wb)
        # guards after each step: the states at k+1 … k+L (the block's outputs read states k … k+L−1)
        g_rows = slice(n_out + n_el, n_out + 3 * n_el)
        g_next = np.vstack([out[1:, g_rows], (sys["C"][g_rows] @ s_end[:N])[None]])
        crossed = np.flatnonzero(np.any(g_next < -sys["tolerance"], axis=1))
        j_e = int(crossed[0]) if crossed.size else size_now  # the step an event lies in
        j_l = size_now
        if loop is not None and not power:
            bad = limit_crossed(out[:, -1], held, limit, lo, hi)
            j_l = int(bad[0]) if bad.size else size_now
        j = min(j_e, j_l)
        if j > 0:
            u_at = out[j, -1] if loop is not None and j < size_now else None
            if j < size_now:
                out, s_end = out[:j], form.state_at(j)
            _keep(book, out, Y, Tq, k, j, n_out, n_el)
            k, s = k + j, s_end
        else:
            u_at = out[0, -1] if loop is not None else None
        if j == size_now:
            size = min(2 * size, BLOCK_MAX)
        elif j_l <= j_e:  # a torque limit reached or left at sample k (the loop's own switch)
            switches += 1
            held, limit = limit_switched(held, limit, u_at, lo, hi)
            size = BLOCK_MIN
        else:  # an element event inside step k: that step by itself
            w_row = W[k].copy()
            if loop is not None:
                w_row[2] = limit
            y_k, s_next = form.one(s, w_row)
            one = y_k[None]
            _keep(book, one, Y, Tq, k, 1, n_out, n_el)
            applied = np.array([one[0, n_out + 3 * n_el + 1] if loop is not None else w_row[0], w_row[1]])
            X = book.step(s[:N], applied, k)
            s = np.concatenate([X, s_next[N:]]) if loop is not None else X
            k += 1
            size = BLOCK_MIN
        if progress is not None:
            progress(k, L)
    while True:  # the last sample: its outputs from the state reached, in the loop's form there
        if power:
            held, limit = _power_clamp(plant.system(book.regimes), loop, s, W[last], n_out, plant.dt)
        form = _form(plant.system(book.regimes), held, loop, plant.dt)
        w_row = W[last].copy()
        if loop is not None:
            w_row[2] = limit
        out = form.one(s, w_row)[0][None]
        if loop is None or power or limit_crossed(out[:, -1], held, limit, lo, hi).size == 0:
            break
        switches += 1
        held, limit = limit_switched(held, limit, out[0, -1], lo, hi)
    _keep(book, out, Y, Tq, last, 1, n_out, n_el)
    if progress is not None:
        progress(L, L)
    summary = book.finish(s[:N], last * plant.dt)
    how = "one step at a time" if stepped else "linear blocks between events"
    method = f"{how} ({summary.event_count} events" + (
        f", {switches} limit switches)" if loop is not None else ")"
    )
    return Y, Tq, summary, method


def _power_clamp(sys: dict, loop, s: np.ndarray, w: np.ndarray, n_out: int, dt: float) -> tuple[bool, float]:
    """With a power limit: whether the command at this sample is clamped, and to what (N·m) - the
    torque limits and ±power_limit/|ω| at the measured speed ω of this very sample, as the stepped
    control law clamps it."""
    free = _form(sys, False, loop, dt)
    y = free.H @ s + free.E @ np.concatenate([w[:2], [0.0], w[3:]])
    lo, hi = (float(v) for v in torque_limits(loop[0], y[n_out - 1]))
    u = y[-1]
    if u > hi:
        return True, hi
    if u < lo:
        return True, lo
    return False, 0.0


def _form(sys: dict, held: bool, loop, dt: float) -> TriangularRecursion:
    """The regime's discrete system, open or with the loop closed (free or held at a limit)."""
    key = held if loop is not None else None
    form = sys["forms"].get(key)
    if form is None:
        C = sys["C"]
        if loop is None:
            form = TriangularRecursion(sys["Ad"], sys["Bd"], C, np.zeros((C.shape[0], sys["Bd"].shape[1])))
        else:
            c = loop[0]
            form = TriangularRecursion(*loop_form(sys["Ad"], sys["Bd"], C, c.kp, c.ki, c.tau, dt, held))
        sys["forms"][key] = form
    return form


def _keep(book: _Run, out: np.ndarray, Y, Tq, k: int, j: int, n_out: int, n_el: int) -> None:
    """Store samples k … k+j−1 of a block (and each element's peak torque over them)."""
    Y[k : k + j] = out[:j, :n_out]
    if Tq is not None:
        Tq[k : k + j] = out[:j, n_out + 3 * n_el + 1]
    if n_el:
        book.peak = np.maximum(book.peak, np.abs(out[:j, n_out : n_out + n_el]).max(axis=0))


def respond(result, ss, x0: np.ndarray, preload, W: np.ndarray, control, dt: float, stepped: bool, progress):
    """:func:`flexshaft.analysis.simulate.simulate`'s run with nonlinear elements, on the inputs it
    built (``W``: open, [drive, load]; closed, [set-point, load, 0, disturbance]): the start state in
    the elements' regimes, then :func:`run`.

    Returns ``(Y, applied torque or None, NonlinearRun, method)``.
    """
    plant = HybridPlant(result, ss, dt)
    X0, regimes = initial(plant, x0, np.asarray(preload, dtype=float))
    loop = None if control is None else (control, float(preload[0]))
    return run(plant, X0, regimes, W, loop=loop, progress=progress, stepped=stepped)
