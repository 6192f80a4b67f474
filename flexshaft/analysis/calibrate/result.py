"""A calibration's outcome (:class:`CalibrationResult`), and what it reports beside the tuned values: the
tuned stiffness or inertia of a part back in physical terms, and how each measured shape matches its mode
before and after.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...linalg.mac import mac
from ...model.components import Drivetrain, Shaft
from ..parameters import find_parameter

__all__ = ["CalibrationResult", "physical_terms", "shape_macs", "shape_notes", "SHAPE_MAC_FALL", "PLAUSIBLE"]

#: A measured shape's MAC with its tracked mode that falls by more than this over the calibration is
#: reported: the frequencies are met by values whose mode looks less like the measurement than at the
#: start - often another solution (two frequencies can fix two stiffnesses in two ways). Measured
#: shapes match their true mode to 1 − MAC ~1e-4 (2 % noise); the wrong one of such a pair differs
#: by some 5e-2 (examples/operational_run.py's line).
SHAPE_MAC_FALL = 0.01
#: How far a tuned Young's modulus or density may move from the material's before it is flagged as
#: implausible (fraction): structural steels' E spread about ±5 % around 205-210 GPa and their
#: density far less; a change beyond these is a modelling error in disguise, not a material.
PLAUSIBLE = {"E": 0.10, "rho": 0.05}


@dataclass(frozen=True)
class CalibrationResult:
    """What a calibration did: the study's tables, made for you.

    Attributes
    ----------
    names : tuple of str
        The tuned parameters.
    initial, tuned, lower, upper : ndarray
        Their starting and tuned values and bounds, SI.
    targets : tuple of Target
        The targets with a frequency or ratio (the rows of ``initial_values`` …).
    initial_values, values : ndarray
        Each target's quantity (Hz or ratio) before and after.
    modes : ndarray of int
        The mode each target's mode has become in the tuned model (tracked by shape).
    active : tuple of str or None
        ``"lower"``/``"upper"`` where a parameter ends on a bound.
    widen : tuple of float
        For a parameter on a bound: the cost's decrease per % that bound is widened (first order;
        0 inside its bounds) - which bound to widen first.
    unmet : tuple of dict
        For each target missed: the parameters that would meet it alone, and by how much (%).
    physics : tuple of dict
        A tuned stiffness or inertia of a part from sections, or a tuned material, back in physical
        terms: the Young's modulus (at fixed ν) or density it means, the equivalent scale of every
        cross-section dimension (k, j ∝ s⁴), and whether that stays plausible (:data:`PLAUSIBLE`).
    drivetrain : Drivetrain
        The tuned model.
    fixed : dict
        Parameters fixed to a value.
    cost : float
        ½ Σ residual² at the end (residual = relative miss / tolerance), damping targets' included.
    starts : int
        Starting points tried.
    message : str
        The optimiser's (and the damping solve's).
    damping_targets : tuple of Target
        The targets with a damping ratio (a target with a frequency too is in ``targets`` as well).
    initial_damping, damping : ndarray
        Each one's damping ratio (fraction) before and after: the damped mode's ``ξ = −Re λ/|λ|`` of the
        model as ``flexshaft modes`` assembles it (flexible bodies reduced, with their own damping).
    damping_modes : ndarray of int
        The mode each damping target's mode has become in the tuned model (tracked by shape).
    initial_shape_mac, shape_mac : ndarray
        Per target (in ``targets``' order) the MAC of its measured ``shape`` with its mode at the
        stations before and after; NaN for a target without a shape. A fall of more than
        :data:`SHAPE_MAC_FALL` is noted in ``message``.
    """

    names: tuple
    initial: np.ndarray
    tuned: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    targets: tuple
    initial_values: np.ndarray
    values: np.ndarray
    modes: np.ndarray
    active: tuple
    widen: tuple
    unmet: tuple
    drivetrain: Drivetrain = field(repr=False)
    physics: tuple = ()
    fixed: dict = field(default_factory=dict)
    cost: float = 0.0
    starts: int = 1
    message: str = ""
    damping_targets: tuple = ()
    initial_damping: np.ndarray = field(default_factory=lambda: np.zeros(0))
    damping: np.ndarray = field(default_factory=lambda: np.zeros(0))
    damping_modes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    initial_shape_mac: np.ndarray = field(default_factory=lambda: np.zeros(0))  # one per target
    shape_mac: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def damping_errors(self) -> np.ndarray:
        """Each damping target's relative miss after tuning (ξ/ξ_target − 1)."""
        return self.damping / np.array([t.damping_ratio for t in self.damping_targets], dtype=float) - 1

    @property
    def damping_met(self) -> np.ndarray:
        """Which damping targets are within their damping tolerance."""
        tol = np.array([t.damping_tolerance for t in self.damping_targets], dtype=float)
        return np.abs(self.damping_errors) <= tol * (1 + 1e-9)

    @property
    def errors(self) -> np.ndarray:
        """Each target's relative miss after tuning (value/target − 1)."""
        return self.values / np.array([t.value for t in self.targets]) - 1

    @property
    def met(self) -> np.ndarray:
        """Which targets are within their tolerance."""
        tol = np.array([t.tolerance for t in self.targets])
        return np.abs(self.errors) <= tol * (1 + 1e-9)

    @property
    def change_percent(self) -> np.ndarray:
        """Each parameter's change, %; NaN for a damping parameter that started at 0."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.initial != 0, 100 * (self.tuned / self.initial - 1), np.nan)

    def to_dict(self) -> dict:
        """The ``flexshaft calibrate --json`` document."""
        return {
            "units": {
                "values": "SI",
                "change": "%",
                "frequency": "Hz",
                "error": "fraction",
                "damping_ratio": "fraction",
            },
            "parameters": [
                {
                    "name": n,
                    "initial": float(a),
                    "tuned": float(b),
                    "lower": float(lo),
                    "upper": float(hi),
                    "change_percent": float(c) if np.isfinite(c) else None,
                    "active_bound": act,
                    "widen_gain_per_percent": float(w),
                }
                for n, a, b, lo, hi, c, act, w in zip(
                    self.names,
                    self.initial,
                    self.tuned,
                    self.lower,
                    self.upper,
                    self.change_percent,
                    self.active,
                    self.widen,
                )
            ],
            "fixed": dict(self.fixed),
            "targets": [
                {
                    "target": t.label,
                    "mode": t.mode,
                    "tracked_mode": int(m),
                    "value": float(t.value),
                    "initial": float(a),
                    "tuned": float(v),
                    "error": float(e),
                    "tolerance": t.tolerance,
                    "met": bool(ok),
                    "shape_mac_initial": _finite_or_none(ma),
                    "shape_mac": _finite_or_none(mb),
                }
                for t, m, a, v, e, ok, ma, mb in zip(
                    self.targets,
                    self.modes,
                    self.initial_values,
                    self.values,
                    self.errors,
                    self.met,
                    self.initial_shape_mac,
                    self.shape_mac,
                )
            ],
            "damping_targets": [
                {
                    "target": t.damping_label,
                    "mode": t.mode,
                    "tracked_mode": int(m),
                    "value": float(t.damping_ratio),
                    "initial": float(a),
                    "tuned": float(v),
                    "error": float(e),
                    "tolerance": t.damping_tolerance,
                    "met": bool(ok),
                }
                for t, m, a, v, e, ok in zip(
                    self.damping_targets,
                    self.damping_modes,
                    self.initial_damping,
                    self.damping,
                    self.damping_errors,
                    self.damping_met,
                )
            ],
            "unmet": list(self.unmet),
            "physics": list(self.physics),
            "cost": self.cost,
            "starts": self.starts,
            "message": self.message,
        }


def _finite_or_none(v) -> float | None:
    return float(v) if np.isfinite(v) else None


def physical_terms(d: Drivetrain, names, x0, x) -> tuple:
    """Tuned stiffness/inertia of parts from sections, and tuned materials, as E, ρ and a scale."""
    out = []
    for n, a, b in zip(names, x0, x):
        p = find_parameter(d, n)
        if a == 0:  # a damping parameter that started at 0 (no damper yet): no physics to tell
            continue
        ratio = b / a
        if p.kind == "material" and p.field in PLAUSIBLE:
            key, material = (
                p.field,
                next(
                    c.material
                    for c in d.components
                    if isinstance(c, Shaft) and c.material and c.material.name == p.owner
                ),
            )
        elif p.kind == "component" and p.field in ("stiffness", "inertia"):
            c = d.component(p.owner)
            if not (isinstance(c, Shaft) and c.sections is not None):
                continue
            key, material = ("E" if p.field == "stiffness" else "rho"), c.material
        else:
            continue
        value = getattr(material, key) * ratio
        out.append(
            {
                "parameter": n,
                "material": material.name,
                key: float(value),
                "unit": "Pa" if key == "E" else "kg/m³",
                "change_percent": float(100 * (ratio - 1)),
                "scale_equivalent": float(ratio**0.25),
                "plausible": bool(abs(ratio - 1) <= PLAUSIBLE[key]),
            }
        )
    return tuple(out)


def shape_macs(result, modes_of: dict, targets) -> np.ndarray:
    """Each target's measured shape's MAC with its tracked mode at the stations (θx); NaN without one."""
    st = result.station_shapes() if any(t.shape is not None for t in targets) else None
    out = np.full(len(targets), np.nan)
    for k, t in enumerate(targets):
        if t.shape is not None:
            out[k] = mac(np.asarray(t.shape), st[:, modes_of[t.mode]])
    return out


def shape_notes(targets, before, after) -> list[str]:
    return [
        f"mode {t.mode}'s shape matches the measured one less than at the start (MAC {a:.3f} -> {b:.3f}): "
        "other values may meet the frequencies as well - narrow the bounds to what is known, or start nearer"
        for t, a, b in zip(targets, before, after)
        if b < a - SHAPE_MAC_FALL
    ]
