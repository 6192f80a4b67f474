"""The Campbell (interference) diagram: eigenfrequencies against shaft speed, with order lines.

An excitation of order k at shaft speed n (rpm) has the frequency k·n/60 Hz; where that line
crosses a mode's frequency the mode is driven in resonance. flexshaft's models have no
speed-dependent terms (torsion has none; the 6-DOF Timoshenko model leaves out the gyroscopic
matrix), so every eigenfrequency is a horizontal line and each crossing is exact:
n = 60·f/k. The speed axis is one station's shaft speed (the driving end by default); past a
gear stage its orders are that shaft's, and the speeds of the others follow by their ratios.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..validation import check_int, check_real
from .modal import ModalResult

__all__ = ["Crossing", "CampbellDiagram", "campbell"]


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
        False: no gyroscopic or other speed-dependent terms in the model.
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
        Excitation orders per revolution, > 0.
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
    try:
        orders = tuple(float(o) for o in orders)
    except (TypeError, ValueError):
        raise ModelError(
            "not a list of numbers", field="orders", value=orders, valid="orders > 0, e.g. 1,2,6"
        ) from None
    if not orders:
        raise ModelError("needs at least one order", field="orders", valid="orders > 0, e.g. 1,2,6")
    orders = tuple(check_real(o, "orders", "", lo=0.0, lo_open=True) for o in orders)
    points = check_int(points, "points", lo=2, hi=100_000)
    model = result.model
    ref = model.stations[0] if reference is None else model.station(reference, "reference")
    top = max(orders) * hi / 60.0
    max_hz = 1.25 * top if max_hz is None else check_real(max_hz, "max_hz", "Hz", lo=0.0, lo_open=True)
    modes = np.flatnonzero(~result.rigid & (result.frequencies_hz <= max_hz))
    f = result.frequencies_hz[modes]
    zeta = result.damping_ratios[modes]
    speeds = np.linspace(lo, hi, points)
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
