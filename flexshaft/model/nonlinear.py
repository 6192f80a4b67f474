"""Nonlinear laws a coupling or a gear mesh carries in time runs: friction slip, free play, a
torque-angle curve.

Each law replaces the element's linear spring k·Δθ + c·Δω (Δθ = θ_in − n·θ_out, the element's
relative rotation in its driving-side frame) in :func:`flexshaft.analysis.simulate.simulate`; the
linear analyses (modes, FRF, forced response, state space, calibration) keep the linear element -
stuck, in contact, the tangent at zero torque - and say so. Every law is piecewise linear, so a
time run is a chain of linear systems joined at events (:mod:`flexshaft.analysis.hybrid`).

- :class:`Slip`: a friction face in series with the coupling's spring and damper. Stuck, the
  coupling is its linear self; once the torque reaches the static slip torque the face slips and
  transmits the kinetic torque (and a viscous part), until the slip speed comes back to zero.
- :class:`Backlash`: a total free play, centred: the spring and damper act only in contact, and
  the contact never pulls (a damper that would pull lets go instead, as Modelica's ElastoBacklash).
- :class:`TorqueCurve`: a stiffness that depends on the torque carried, as a piecewise-linear
  torque against angle curve through zero.

All quantities SI: N·m, rad, N·m/rad, N·m·s/rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from ..errors import ModelError
from ..validation import DAMPER, STIFFNESS, Domain, check_real

__all__ = ["Slip", "Backlash", "TorqueCurve", "law_of", "CURVE_TOLERANCE", "MAX_CURVE_POINTS"]

#: A slip or contact torque, N·m (> 0).
TORQUE = Domain(0.0, True, unit="N·m")
#: A free play, rad: > 0, and below a full turn.
GAP = Domain(0.0, True, 2 * math.pi, True, unit="rad")
#: How closely the chords of a curve given as tangent stiffness against torque follow the exact
#: curve (the integral of 1/k over the torque, k linear between the listed torques): the largest
#: angle error over an interval as a fraction of the interval's angle. The angles at the listed
#: torques themselves are exact.
CURVE_TOLERANCE = 1e-4
#: The most points a curve may list (a manufacturer's table has a handful).
MAX_CURVE_POINTS = 1000


@dataclass(frozen=True)
class Slip:
    """A friction face in series with the element's spring: it sticks below ``torque``.

    Attributes
    ----------
    torque : float
        Static slip torque, N·m, > 0: the stuck coupling slips once it carries this much.
    kinetic_torque : float
        Torque transmitted while slipping, N·m, in (0, torque].
    damping : float
        Viscous torque per slip speed while slipping, N·m·s/rad, >= 0.
    """

    torque: float
    kinetic_torque: float
    damping: float = 0.0
    kind: ClassVar[str] = "slip"


@dataclass(frozen=True)
class Backlash:
    """A total free play ``gap`` (rad), centred: the spring and damper act in contact only.

    Attributes
    ----------
    gap : float
        Total free play, rad, > 0 (±gap/2 about the centre).
    """

    gap: float
    kind: ClassVar[str] = "backlash"


@dataclass(frozen=True)
class TorqueCurve:
    """Transmitted torque against relative rotation, piecewise linear through (0, 0).

    Beyond its first and last points the curve goes on with its end slopes.

    Attributes
    ----------
    angle : ndarray
        Break points, rad, increasing (the slope changes at each).
    torque : ndarray
        The torque there, N·m, increasing; the curve passes through (0, 0).
    """

    angle: np.ndarray
    torque: np.ndarray
    kind: ClassVar[str] = "curve"

    @cached_property
    def slopes(self) -> np.ndarray:
        """Stiffness of each segment, N·m/rad: below the first point (segment 0), between points,
        above the last (segment ``angle.size``)."""
        k = np.diff(self.torque) / np.diff(self.angle)
        return np.concatenate([k[:1], k, k[-1:]])

    @cached_property
    def offsets(self) -> np.ndarray:
        """Each segment's line at zero angle, N·m: on segment j the torque is offsets[j] + slopes[j]·θ."""
        base = np.clip(np.arange(self.angle.size + 1) - 1, 0, self.angle.size - 1)
        return self.torque[base] - self.slopes * self.angle[base]

    def segment_of(self, angle):
        """The segment (index of :attr:`slopes`) holding each relative rotation ``angle`` (rad); a
        break point belongs to the segment above it."""
        return np.searchsorted(self.angle, angle, side="right")

    @property
    def tangent_at_zero(self) -> float:
        """The stiffness the linear analyses use, N·m/rad: the slope of the curve at zero torque (the
        mean of the two segments meeting there, when they differ)."""
        k = self.slopes
        j = int(self.segment_of(0.0))
        return float(0.5 * (k[j - 1] + k[j])) if j > 0 and self.angle[j - 1] == 0.0 else float(k[j])

    def torque_at(self, angle) -> np.ndarray:
        """The torque at relative rotations ``angle`` (rad), N·m."""
        angle = np.asarray(angle, dtype=float)
        j = self.segment_of(angle)
        return self.offsets[j] + self.slopes[j] * angle

    @classmethod
    def from_points(cls, points, field: str = "torque_curve") -> TorqueCurve:
        """A curve from ``[[angle, torque], ...]`` (rad, N·m), as a manufacturer gives it.

        Both columns strictly increasing; (0, 0) one of the points, or every point at a positive
        angle (the curve is then mirrored: T(−θ) = −T(θ), through (0, 0)).
        """
        a, t = _pairs(points, field, ("angle", "rad"), ("torque", "N·m"))
        _increasing(a, field, 0, "angle", "rad")
        _increasing(t, field, 1, "torque", "N·m")
        if a[0] > 0.0:
            a, t = np.concatenate([-a[::-1], [0.0], a]), np.concatenate([-t[::-1], [0.0], t])
        zero = np.flatnonzero(a == 0.0)
        if zero.size == 0 or t[zero[0]] != 0.0:
            raise ModelError(
                "does not pass through (0 rad, 0 N·m)",
                field=field,
                value=points,
                has_value=True,
                valid="[[angle, torque], ...] with [0, 0] among them, or every angle > 0 (mirrored)",
            )
        return cls(angle=a, torque=t).merged()

    @classmethod
    def from_stiffness(cls, points, field: str = "stiffness_curve") -> TorqueCurve:
        """A curve from ``[[torque, stiffness], ...]`` (N·m, N·m/rad): the tangent stiffness at each
        listed torque, linear in the torque between them and constant beyond the ends; every torque
        >= 0 mirrors the curve to negative torques.

        The angle at a torque is the integral of dT/k(T) (exact at the listed torques); between them
        the curve is cut into chords within :data:`CURVE_TOLERANCE` of it.
        """
        t, k = _pairs(points, field, ("torque", "N·m"), ("stiffness", "N·m/rad"))
        _increasing(t, field, 0, "torque", "N·m")
        for i, ki in enumerate(k):
            STIFFNESS.check(ki, f"{field}[{i}][1]")
        if t[0] >= 0.0:
            if t[0] > 0.0:
                t, k = np.concatenate([[0.0], t]), np.concatenate([[k[0]], k])
            t, k = np.concatenate([-t[:0:-1], t]), np.concatenate([k[:0:-1], k])
        elif not (t[0] < 0.0 < t[-1]) and 0.0 not in t:
            raise ModelError(
                "does not reach zero torque",
                field=field,
                value=points,
                has_value=True,
                valid="torques on both sides of 0, or every torque >= 0 (mirrored)",
            )
        if 0.0 not in t:
            j = int(np.searchsorted(t, 0.0))
            k0 = k[j - 1] + (k[j] - k[j - 1]) * (0.0 - t[j - 1]) / (t[j] - t[j - 1])
            t, k = np.insert(t, j, 0.0), np.insert(k, j, k0)
        # chords: n equal torque steps per interval, n from the chord error of 1/k's curvature
        torques = [t[:1]]
        for i in range(t.size - 1):
            spread = abs(k[i + 1] - k[i]) / min(k[i], k[i + 1])
            n = max(1, math.ceil(math.sqrt(spread / (8.0 * CURVE_TOLERANCE))))
            cut = np.linspace(t[i], t[i + 1], n + 1)
            if spread > 0.0 and 0.0 in (t[i], t[i + 1]):
                # chords halving towards zero torque: the first one's slope is the tangent at zero
                # within CURVE_TOLERANCE, so a small vibration sees what the linear analyses use
                step, first = (t[i + 1] - t[i]) / n, 2.0 * CURVE_TOLERANCE * (t[i + 1] - t[i]) / spread
                levels = step * 0.5 ** np.arange(1, max(1, math.ceil(math.log2(abs(step / first)))) + 1)
                cut = np.union1d(cut, t[i] + levels if t[i] == 0.0 else t[i + 1] - levels)
            torques.append(cut[1:])
        tt = np.concatenate(torques)
        kk = np.interp(tt, t, k)
        # the angle across each chord: ∫ dT / k, k linear in T (the log mean where k changes)
        k1, k2 = kk[:-1], kk[1:]
        with np.errstate(divide="ignore", invalid="ignore"):  # where k1 = k2 the mean is k1 itself
            mean = np.where(np.isclose(k1, k2, rtol=1e-12, atol=0.0), k1, (k2 - k1) / np.log(k2 / k1))
        a = np.concatenate([[0.0], np.cumsum(np.diff(tt) / mean)])
        a -= a[int(np.flatnonzero(tt == 0.0)[0])]
        # one more chord at each end, at the end's stiffness: the curve goes on with it
        span = t[-1] - t[0]
        a = np.concatenate([[a[0] - span / k[0]], a, [a[-1] + span / k[-1]]])
        tt = np.concatenate([[tt[0] - span], tt, [tt[-1] + span]])
        return cls(angle=a, torque=tt).merged()

    def merged(self) -> TorqueCurve:
        """The same curve without the break points where the slope does not change (a mirrored
        curve's zero, a constant stiffness): each break point is an event in a time run."""
        k = self.slopes
        keep = ~np.isclose(k[1:], k[:-1], rtol=1e-12, atol=0.0)
        keep[[0, -1]] = True  # the ends hold the slopes the curve goes on with
        return TorqueCurve(angle=self.angle[keep], torque=self.torque[keep])


def _pairs(points, field: str, first: tuple, second: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Two columns of finite numbers from a list of ``[a, b]`` pairs (at least two of them)."""
    valid = f"[[{first[0]} ({first[1]}), {second[0]} ({second[1]})], ...], at least two pairs"
    if not isinstance(points, (list, tuple, np.ndarray)) or len(points) < 2:
        raise ModelError("needs at least two points", field=field, value=points, has_value=True, valid=valid)
    if len(points) > MAX_CURVE_POINTS:
        raise ModelError(
            f"lists {len(points)} points", field=field, valid=f"at most {MAX_CURVE_POINTS} points"
        )
    cols = ([], [])
    for i, p in enumerate(points):
        if not isinstance(p, (list, tuple, np.ndarray)) or len(p) != 2:
            raise ModelError("is not a pair", field=f"{field}[{i}]", value=p, has_value=True, valid=valid)
        cols[0].append(check_real(p[0], f"{field}[{i}][0]", first[1]))
        cols[1].append(check_real(p[1], f"{field}[{i}][1]", second[1]))
    return np.array(cols[0]), np.array(cols[1])


def _increasing(x: np.ndarray, field: str, col: int, what: str, unit: str) -> None:
    bad = np.flatnonzero(np.diff(x) <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        raise ModelError(
            f"is not above the {what} before it ({x[i - 1]:g} {unit}): the curve must be monotone",
            field=f"{field}[{i}][{col}]",
            value=float(x[i]),
            unit=unit,
            valid=f"{what}s strictly increasing down the list",
        )


def law_of(
    *,
    stiffness: float | None,
    slip_torque=None,
    slip_kinetic_torque=None,
    slip_damping=0.0,
    backlash=None,
    stiffness_curve=None,
    torque_curve=None,
    spring: str = "stiffness",
):
    """The one nonlinear law an element's keys give (or None), each value checked.

    Parameters
    ----------
    stiffness : float or None
        The element's linear stiffness as given (N·m/rad; ``spring`` names its key); a curve gives
        it instead, a backlash needs it.
    slip_torque, slip_kinetic_torque, slip_damping, backlash, stiffness_curve, torque_curve
        The model file's keys of the same names (module docstring).

    Returns
    -------
    Slip, Backlash, TorqueCurve or None
    """
    given = [
        k
        for k, v in (
            ("slip_torque", slip_torque),
            ("backlash", backlash),
            ("stiffness_curve", stiffness_curve),
            ("torque_curve", torque_curve),
        )
        if v is not None
    ]
    for key, value in (("slip_kinetic_torque", slip_kinetic_torque), ("slip_damping", slip_damping or None)):
        if value is not None and slip_torque is None:
            raise ModelError(
                "belongs to a slipping coupling", field=key, value=value, valid="slip_torque (N·m) with it"
            )
    if len(given) > 1:
        raise ModelError(
            f"cannot be combined with {given[0]}: an element carries one nonlinear law",
            field=given[1],
            valid=f"one of {', '.join(given)}",
        )
    if not given:
        return None
    key = given[0]
    if key in ("stiffness_curve", "torque_curve") and stiffness is not None:
        raise ModelError(
            f"comes from the {key} (its tangent at zero torque)",
            field=spring,
            value=stiffness,
            unit="N·m/rad",
            valid=f"leave {spring} out with {key}",
        )
    if key in ("slip_torque", "backlash") and stiffness is None:
        raise ModelError(
            f"{key} needs the element's stiffness (the stuck coupling, the contact)",
            field=spring,
            valid=f"{spring} (N·m/rad) with {key}",
        )
    if key == "slip_torque":
        static = TORQUE.check(slip_torque, "slip_torque")
        kinetic = (
            static
            if slip_kinetic_torque is None
            else TORQUE.check(slip_kinetic_torque, "slip_kinetic_torque")
        )
        if kinetic > static:
            raise ModelError(
                "is above the static slip torque: a face that slips at less than it transmits while"
                " slipping would stick and break loose at once",
                field="slip_kinetic_torque",
                value=kinetic,
                unit="N·m",
                valid=f"> 0 and <= slip_torque = {static:g} N·m",
            )
        return Slip(static, kinetic, DAMPER.check(slip_damping, "slip_damping"))
    if key == "backlash":
        return Backlash(GAP.check(backlash, "backlash"))
    if key == "stiffness_curve":
        return TorqueCurve.from_stiffness(stiffness_curve)
    return TorqueCurve.from_points(torque_curve)
