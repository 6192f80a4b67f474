"""The Campbell (interference) diagram: eigenfrequencies against shaft speed, with order lines.

An excitation of order k at shaft speed n (rpm) has the frequency k·n/60 Hz; where that line
crosses a mode's frequency the mode is driven in resonance. A torsion model has no
speed-dependent terms, so every eigenfrequency is a horizontal line and each crossing is exact:
n = 60·f/k. A 6-DOF model spins: its shafts' gyroscopic matrix G (forces −Ω·G·q̇) splits each
bending pair into a forward and a backward whirl whose frequencies move with speed; at each
speed the whirl frequencies are the imaginary parts of the roots of M s² + (C + Ω G) s + K,
solved in the model's own lowest modes (at least :data:`BASIS_MODES`, and all up to ten times the
band: a modal basis, exact when it holds every mode; a rigid component's polar inertia turns its
node's tilts as a disc's does), and a crossing is found by bisection on the speed to
1e-9. The speed axis is one station's shaft speed (the driving end by default); past a gear stage
its orders are that shaft's, and the speeds of the others follow by their ratios.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..linalg.damping import modal_damping_block
from ..linalg.firstorder import damped_eigen
from ..measurement.checks import check_orders
from ..system.threads import follows_policy
from ..validation import MAX_FREQUENCY_HZ, check_frequency, check_int, check_real
from .modal import ModalResult, rayleigh_alpha

__all__ = ["Crossing", "CampbellDiagram", "campbell", "BASIS_MODES"]

#: A spinning model's whirl frequencies are solved in its lowest modes, at least this many (a dense
#: eigen-solve of twice this size per speed).
BASIS_MODES = 150


@dataclass(frozen=True)
class Crossing:
    """An order line crossing a mode's frequency: resonance at that speed.

    Attributes
    ----------
    speed_rpm : float
        The reference shaft's speed at the crossing, rpm.
    order : float
        Excitation order (per revolution of the reference shaft).
    mode : int
        The mode, as ``flexshaft modes`` numbers it.
    frequency_hz : float
        Its frequency (the crossing's), Hz.
    damping_ratio : float
        The mode's damping ratio (fraction; 0 for an undamped model).
    """

    speed_rpm: float
    order: float
    mode: int
    frequency_hz: float
    damping_ratio: float


@dataclass(frozen=True)
class CampbellDiagram:
    """Eigenfrequencies against speed, the order lines and their crossings.

    Attributes
    ----------
    speeds_rpm : ndarray, shape (s,)
        Speeds of the reference station, rpm.
    modes : ndarray of int
        The elastic modes drawn (numbered as ``flexshaft modes`` does).
    frequencies_hz : ndarray, shape (s, len(modes))
        Each mode's frequency at each speed, Hz (constant: see the module docstring).
    damping_ratios : ndarray, shape (len(modes),)
    orders : tuple of float
    crossings : tuple of Crossing
        In order of speed.
    reference : str
        The station whose speed the axis is.
    speed_dependent : bool
        True for a spinning 6-DOF model (gyroscopic terms); False for a torsion model.
    """

    speeds_rpm: np.ndarray
    modes: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    orders: tuple
    crossings: tuple
    reference: str
    speed_dependent: bool

    def order_line(self, order: float) -> np.ndarray:
        """Frequency of an order over the speed axis, Hz: order·n/60."""
        return order * self.speeds_rpm / 60.0

    def to_dict(self) -> dict:
        """The ``flexshaft campbell --json`` document."""
        return {
            "units": {"speed": "rpm", "frequency": "Hz", "damping_ratio": "fraction"},
            "reference": self.reference,
            "speed_dependent": self.speed_dependent,
            "speeds_rpm": self.speeds_rpm.tolist(),
            "orders": list(self.orders),
            "modes": [
                {
                    "mode": int(m),
                    "frequency_hz": float(self.frequencies_hz[0, i]),
                    "damping_ratio": float(self.damping_ratios[i]),
                    **(
                        {"frequency_hz_over_speed": [float(v) for v in self.frequencies_hz[:, i]]}
                        if self.speed_dependent
                        else {}
                    ),
                }
                for i, m in enumerate(self.modes)
            ],
            "crossings": [
                {
                    "speed_rpm": c.speed_rpm,
                    "order": c.order,
                    "mode": c.mode,
                    "frequency_hz": c.frequency_hz,
                    "damping_ratio": c.damping_ratio,
                }
                for c in self.crossings
            ],
        }

    def plot(self):
        """The diagram as a matplotlib Figure (never shown; ``fig.savefig("campbell.png")``)."""
        from ..views.plots import campbell_figure

        return campbell_figure(self)

    def table(self, speed_range=None) -> str:
        """The ``flexshaft campbell`` table: the crossings (speed rpm, order, mode, frequency Hz, damping %);
        ``speed_range`` (rpm) as asked for, default the diagram's first and last speed."""
        lo, hi = speed_range if speed_range is not None else (self.speeds_rpm[0], self.speeds_rpm[-1])
        rows = [
            f"Campbell diagram: {lo:g} … {hi:g} rpm at {self.reference!r}, orders "
            + ", ".join(f"{k:g}" for k in self.orders)
            + (
                " (gyroscopic: the whirl frequencies move with speed)"
                if self.speed_dependent
                else " (no speed-dependent terms: every mode is a horizontal line)"
            ),
            "",
            f"{'speed rpm':>10}  {'order':>5}  {'mode':>4}  {'frequency Hz':>12}  {'damping %':>9}",
        ]
        for c in self.crossings:
            rows.append(
                f"{c.speed_rpm:10.2f}  {c.order:5g}  {c.mode:4d}  {c.frequency_hz:12.4f}  "
                f"{100 * c.damping_ratio:9.4f}"
            )
        if not self.crossings:
            rows.append("  (no order line crosses a mode in this speed range)")
        return "\n".join(rows)


@follows_policy
def campbell(
    result: ModalResult,
    speeds_rpm=(0.0, 1800.0),
    orders=(1.0, 2.0, 6.0),
    *,
    points: int = 181,
    reference: str | None = None,
    max_hz: float | None = None,
) -> CampbellDiagram:
    """The Campbell diagram of a drivetrain over a speed range.

    Parameters
    ----------
    result : ModalResult
    speeds_rpm : (float, float)
        Lowest and highest speed of the reference station, rpm, 0 <= lo < hi.
    orders : sequence of float
        Excitation orders per revolution, > 0 and at most
        :data:`~flexshaft.measurement.checks.MAX_ORDER` (a million).
    points : int
        Speeds on the axis (for drawing; crossings are exact, not read off the grid).
    reference : str, optional
        The station whose speed the axis is; default the driving end.
    max_hz : float, optional
        Modes up to this frequency, Hz; default: up to 1.25 × the highest order line's end.
    """
    try:
        lo, hi = (float(v) for v in speeds_rpm)
    except (TypeError, ValueError):
        raise ModelError(
            "needs two speeds", field="speed", value=speeds_rpm, unit="rpm", valid="LO:HI in rpm"
        ) from None
    lo = check_real(lo, "speed (low)", "rpm", lo=0.0)
    hi = check_real(hi, "speed (high)", "rpm", lo=lo, lo_open=True)
    orders = check_orders(orders)  # finite, > 0 and <= MAX_ORDER: the order lines stay finite
    points = check_int(points, "points", lo=2, hi=100_000)
    model = result.model
    ref = model.stations[0] if reference is None else model.station(reference, "reference")
    top = max(orders) * (hi / 60.0)  # inf only far beyond MAX_FREQUENCY_HZ, refused just below
    if top > MAX_FREQUENCY_HZ:  # an order line beyond any mode, and soon beyond floating point
        raise ModelError(
            f"takes order {max(orders):g} above {MAX_FREQUENCY_HZ:g} Hz",
            field="speed (high)",
            value=hi,
            unit="rpm",
            valid=f"order lines up to {MAX_FREQUENCY_HZ:g} Hz: a top speed up to"
            f" {60.0 * MAX_FREQUENCY_HZ / max(orders):g} rpm for these orders",
        )
    max_hz = 1.25 * top if max_hz is None else check_frequency(max_hz, "max_hz", lo_open=True)
    modes = np.flatnonzero(~result.rigid & (result.frequencies_hz <= max_hz))
    f = result.frequencies_hz[modes]
    zeta = result.damping_ratios[modes]
    speeds = np.linspace(lo, hi, points)
    G = model.G
    if G is not None and G.nnz and np.any(G.data):
        return _spinning(result, speeds, orders, modes, max_hz, ref.name, model.speed_ratio[ref.node])
    crossings = []
    for k in orders:
        for m, fm, z in zip(modes, f, zeta):
            n = 60.0 * fm / k
            if lo <= n <= hi:
                crossings.append(Crossing(float(n), k, int(m), float(fm), float(z)))
    crossings.sort(key=lambda c: (c.speed_rpm, c.order))
    return CampbellDiagram(
        speeds_rpm=speeds,
        modes=modes,
        frequencies_hz=np.tile(f, (points, 1)),
        damping_ratios=np.asarray(zeta, dtype=float),
        orders=orders,
        crossings=tuple(crossings),
        reference=ref.name,
        speed_dependent=False,
    )


#: Eigen-solves a crossing costs in :func:`_spinning`: the bracketing root finder's steps and the
#: last one (5.8 measured on examples/ptss_full.toml at 1 800 and 6 000 rpm).
SOLVES_PER_CROSSING = 6


def _check_tracking_work(f_hz, speeds, orders, basis: int) -> None:
    """Refuse a speed range whose whirl tracking would run for hours (the ``dense_work`` ceiling).

    Every speed on the axis, and every step of the search for a crossing, is a dense eigen-solve
    of order 2·basis. The crossings are estimated from the modes at standstill (order k meets
    mode f at 60·f/k rpm); ptss_full at 0:20 000 rpm took 440 s.
    """
    from ..system.limits import check_ceiling, dense_work

    lo, hi = float(speeds[0]), float(speeds[-1])
    crossings = sum(int(np.sum((60.0 * f_hz / k >= lo) & (60.0 * f_hz / k <= hi))) for k in orders)
    solves = speeds.size + SOLVES_PER_CROSSING * crossings
    work = dense_work(solves, 2 * basis)
    check_ceiling(
        "dense_work",
        work,
        field="speed (high)",
        value=hi,
        unit="rpm",
        detail=f"about {crossings} crossings to find among {f_hz.size} modes, {solves} eigen-solves of "
        f"order {2 * basis}, the work of {work:.3g} solves of order 1000",
        hint="a lower top speed, fewer orders, or fewer modes in the band, max_hz",
    )


def _spinning(result, speeds, orders, modes, max_hz, reference, ref_ratio) -> CampbellDiagram:
    """The speed-dependent diagram of a 6-DOF model (see the module docstring)."""
    from scipy.optimize import brentq

    model = result.model
    # The basis: every computed mode up to BASIS_MODES (exact then: ROSS's whirl frequencies to 4e-11
    # in a test), else the modes up to ten times the band (modal truncation, ~1e-6 at high speed).
    order = np.argsort(result.frequencies_hz, kind="stable")
    basis = np.zeros(result.count, dtype=bool)
    basis[order[: max(BASIS_MODES, int(np.sum(result.frequencies_hz <= 10.0 * max_hz)))]] = True
    basis |= result.rigid
    Phi = result.shapes[:, basis]
    w = result.omega[basis]
    Gm = Phi.T @ (model.G @ Phi)
    Cm = modal_damping_block(model.C, Phi, result.rigid[basis], rayleigh_alpha(model))
    Gm = 0.5 * (Gm - Gm.T)
    n_branch = modes.size
    line = 2 * np.pi / 60.0 / ref_ratio  # rad/s of line speed per rpm of the reference station

    def roots(rpm: float) -> np.ndarray:
        lam = damped_eigen(omega=w, damping=Cm + rpm * line * Gm)
        scale = max(float(np.max(np.abs(lam))), 1.0)
        lam = lam[lam.imag > 1e-9 * scale]
        return lam[np.argsort(lam.imag, kind="stable")][:n_branch]

    _check_tracking_work(result.frequencies_hz[modes], speeds, orders, w.size)
    lam = np.array([roots(n) for n in speeds])
    f = lam.imag / (2 * np.pi)
    crossings = []
    for k in orders:
        for b in range(n_branch):
            g = f[:, b] - k * speeds / 60.0
            for i in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0):
                if g[i] == g[i + 1] == 0:
                    continue

                def miss(n, b=b, k=k):
                    return roots(n)[b].imag / (2 * np.pi) - k * n / 60.0

                n = speeds[i] if g[i] == 0 else brentq(miss, speeds[i], speeds[i + 1], xtol=1e-9, rtol=1e-12)
                r = roots(n)[b]
                crossings.append(
                    Crossing(float(n), k, int(modes[b]), float(r.imag / (2 * np.pi)), float(-r.real / abs(r)))
                )
    crossings.sort(key=lambda c: (c.speed_rpm, c.order))
    unique = []
    for c in crossings:  # a grid speed exactly on a crossing is found from both sides
        if (
            not unique
            or (c.order, c.mode) != (unique[-1].order, unique[-1].mode)
            or abs(c.speed_rpm - unique[-1].speed_rpm) > 1e-6
        ):
            unique.append(c)
    return CampbellDiagram(
        speeds_rpm=speeds,
        modes=modes,
        frequencies_hz=f,
        damping_ratios=np.asarray(-lam[0].real / np.abs(lam[0]), dtype=float),
        orders=orders,
        crossings=tuple(unique),
        reference=reference,
        speed_dependent=True,
    )
