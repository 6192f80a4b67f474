"""Tune a model to measured frequencies and damping ratios: bounded least squares, modes tracked by
their shape.

Targets are frequencies (Hz) or ratios to another mode (published and measured data is often
normalised to f1), each with a relative tolerance; parameters (see
:mod:`flexshaft.analysis.sensitivity`) move inside bounds. The residual of a target is its
relative miss over its tolerance, ``(value/target − 1)/tolerance``, so a target is met where
|residual| <= 1 and the tolerances weigh the targets against each other. It is solved by
``scipy.optimize.least_squares`` (trust-region reflective, bounds) on parameters scaled by their
starting values, with the analytic Jacobian ∂λ = φᵀ(∂K − λ∂M)φ, to the targets' own resolution
(:data:`SOLVER_FRACTION`); parameters the cost pushes against a bound are then put onto it.

The model is a :class:`~flexshaft.analysis.sensitivity.ParametrisedModel`: ∂K and ∂M of every
parameter are taken once per calibration, and where K and M are affine in all the parameters
(stiffnesses, inertias, E, ρ: checked at a point inside the bounds) an evaluation forms
K0 + Σ Δx_k ∂K_k and assembles nothing; a ``scale``, gear ``ratio`` or ``nu`` is assembled at each
point and differenced afresh.

Modes are followed by their shape, never by their number: the modes a target names are those
of the starting model, and at every evaluation each is found again as the mode whose shape
matches it best (MAC) along the straight path from the last evaluated point - halving the step
until every tracked mode has a clear match - so two modes crossing on the way keep their
targets. ``starts > 1`` adds Latin-hypercube starting points inside the bounds (each reached
along such a tracked path) and keeps the best.

Damping ratios (a target's ``damping_ratio``, with its own relative ``damping_tolerance``) are met
by the damping parameters alone, in a second solve on the frequency-tuned model: a damping
parameter (a shaft's or flexible body's ``damping_ratio``, a damper, ``rayleigh.alpha``/``beta`` or
the two ``rayleigh.damping_ratios``) enters C alone and leaves the undamped modes - the frequency
solve's - where they are. The ratio compared is the damped mode's, ξ = −Re λ/|λ|, of the model as
``flexshaft modes`` assembles it; the solve is linear to first order in the damping
(:func:`_damping_solve`). Each kind of target needs a parameter of its kind and each tuned
parameter a target (:func:`_check_pairing`), checked before any solve - except that a damping ratio
beside a frequency, with no damping parameter tuned, is compared and not met (the model's damped
ratio before and after, and a note): a targets file from ``flexshaft identify`` carries the measured
damping with every frequency, and tuning stiffness alone is a question of its own.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..model.assembly import assemble
from ..model.components import Drivetrain, Shaft
from ..system.limits import check_ceiling
from ..system.threads import follows_policy
from ..validation import check_int, check_real
from .modal import DEFAULT_LISTED, ModalResult, modal_analysis
from .sensitivity import (
    DAMPING_FIELDS,
    ParametrisedModel,
    find_parameter,
    frequency_derivatives,
    is_damping,
    parameter_domain,
    parameter_value,
    parameters,
    with_parameters,
)

__all__ = ["Target", "Bound", "CalibrationResult", "calibrate", "check_problem", "MAC_CLEAR"]

#: A tracked mode's best match must have at least this MAC (and beat the runner-up), or the step
#: from the last point is halved.
MAC_CLEAR = 0.8
#: A measured shape's MAC with its tracked mode that falls by more than this over the calibration is
#: reported: the frequencies are met by values whose mode looks less like the measurement than at the
#: start - often another solution (two frequencies can fix two stiffnesses in two ways). Measured
#: shapes match their true mode to 1 − MAC ~1e-4 (2 % noise); the wrong one of such a pair differs
#: by some 5e-2 (examples/operational_run.py's line).
SHAPE_MAC_FALL = 0.01
#: Halvings of one step before tracking gives up (2⁻¹² of the step).
MAX_HALVINGS = 12
#: The least-squares solver's xtol, ftol and gtol, as a fraction of the smallest target tolerance.
#: A residual is a miss in units of its target's tolerance, so this asks for the misses settled to
#: 1e-4 of the tightest tolerance: a relative parameter step of xtol moves a frequency or a ratio by
#: at most half of it (λ is homogeneous of degree 1 in the stiffnesses and −1 in the inertias, each
#: share of one sign, so |∂ln f/∂ln p| <= ½), a relative fall of the cost by ftol moves the misses by
#: ~ftol/2 of their size. The stopping tests bound the last step, not the distance left, which along
#: a direction the cost barely sees is a few steps: the end point's misses are a 1e-12 solve's to
#: ~1e-4 of a tolerance (1e-3 saved 8 of the study's 49 Jacobians and was ~1e-3 off in such a
#: valley). 1e-12 for every problem spent 278 Jacobians on the study, most of them closing in on
#: bounds, which :func:`_onto_bounds` does in one evaluation per parameter.
SOLVER_FRACTION = 1e-4
#: Targets, tolerances and ± % bounds within ranges double precision resolves: a residual is a
#: relative miss over a tolerance, so a target of 1e-300 Hz or a tolerance of 1e-300 overflows it,
#: and a ± 1e-300 % bound has no width left.
TARGET_RANGE = (1e-6, 1e9)  # Hz, and for a ratio (dimensionless)
MIN_TOLERANCE = 1e-9
MIN_PERCENT = 1e-6
#: How far a tuned Young's modulus or density may move from the material's before it is flagged as
#: implausible (fraction): structural steels' E spread about ±5 % around 205-210 GPa and their
#: density far less; a change beyond these is a modelling error in disguise, not a material.
PLAUSIBLE = {"E": 0.10, "rho": 0.05}
#: A frequency or ratio target's tolerance unless it gives one (1 %).
DEFAULT_TOLERANCE = 0.01
#: A damping target's tolerance unless it gives one: ±10 % of the ratio. Damping is measured far less
#: well than frequency - a half-power estimate of a peak 2ξf wide (0.1 Hz at 0.53 % of 10 Hz) rests on
#: a few spectral lines and on leakage and scatters ~20 % from run to run - so the mean of five runs,
#: as the test bench measured its 0.53 %, is known to ~20 %/√5 ≈ 9 %: 10 %.
DAMPING_TOLERANCE = 0.1
#: Damping ratios a target may give: a relative miss over the tolerance stays inside double precision
#: down to 1e-9 (no drivetrain's damping is measured below ~1e-5), and a mode with ξ >= 1 does not ring.
DAMPING_RANGE = (1e-9, 1.0)
#: Steps of the damping solve (first-order Jacobian, damped-mode residual) before it reports that the
#: damped ratios did not settle; each step gains a factor O(ξ²) (the damped ratio's part beyond first
#: order): two or three suffice.
DAMPING_STEPS = 20
#: Step of the difference that gives the damping Jacobian, a fraction of each parameter's scale (its
#: value, or its bounds' width from 0): small enough to stay where the model takes the value (two
#: Rayleigh ratios far apart imply a negative α or β), large against round-off.
DAMPING_STEP = 1e-3
#: The first-order ratios φᵀCφ/(2ω) are affine in every damping parameter (C is, the modes do not move):
#: the prediction from one linearisation agrees with an evaluation to round-off, ~1e-13 of the ratio;
#: beyond this fraction of the target ratio the solve linearises afresh (a safeguard, not expected).
AFFINE_DAMPING = 1e-9


def _mode_number(value, field: str) -> int:
    """A mode number as a whole number (its range is the model's: :func:`_check_targets`)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ModelError(
            "not a mode number",
            field=field,
            value=value,
            valid="a whole number, as `flexshaft modes` numbers the modes",
            has_value=True,
        )
    return int(value)


@dataclass(frozen=True)
class Target:
    """What a mode should have: a frequency (Hz) or a frequency ratio, a damping ratio, or both.

    Parameters
    ----------
    mode : int
        The mode, numbered as ``flexshaft modes`` numbers the starting model's (0: rigid). An
        elastic mode of the model: :func:`calibrate` checks the number against the model's modes
        before anything is solved.
    frequency_hz : float, optional
        Its target frequency, Hz.
    ratio_to : int, optional
        Or a ratio: the mode it is divided by (``ratio_to = 1``: normalised to f1; an elastic mode
        other than ``mode``) ...
    ratio : float, optional
        ... and the target ratio.
    tolerance : float, optional
        Relative tolerance of the frequency or ratio (0.01 is 1 %, the default), > 0: the target is
        met within it. Only with ``frequency_hz`` or ``ratio``.
    shape : sequence of float, optional
        The mode's measured shape: θx at the model's stations, in their order (any scale). The
        starting model's mode that matches it best (MAC >= 0.8) is the one tuned; ``mode`` is then
        only a name for it and must not disagree.
    damping_ratio : float, optional
        The mode's measured damping ratio, a fraction in (0, 1) (0.0053 for 0.53 %), beside a
        frequency or ratio or alone. Met by the damping parameters (:func:`calibrate`), compared with
        the damped mode of the model as ``flexshaft modes`` reports it.
    damping_tolerance : float, optional
        Relative tolerance of the damping ratio (0.1 is ±10 % of it), > 0; default
        :data:`DAMPING_TOLERANCE`. Only with ``damping_ratio``.
    """

    mode: int
    frequency_hz: float | None = None
    ratio_to: int | None = None
    ratio: float | None = None
    tolerance: float | None = None
    shape: tuple | None = None
    damping_ratio: float | None = None
    damping_tolerance: float | None = None

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "mode", _mode_number(self.mode, "target.mode"))
        if self.shape is not None:
            try:
                shape = tuple(float(v) for v in self.shape)
            except (TypeError, ValueError):
                raise ModelError(
                    "not a list of numbers", field="target.shape", valid="θx at each station"
                ) from None
            if len(shape) < 2 or not all(np.isfinite(shape)) or not any(shape):
                raise ModelError(
                    "needs two or more finite values, not all 0",
                    field="target.shape",
                    valid="θx at each station",
                )
            s(self, "shape", shape)
        if self.damping_ratio is not None:
            s(
                self,
                "damping_ratio",
                check_real(
                    self.damping_ratio, "target.damping_ratio", "", lo=DAMPING_RANGE[0], hi=1.0, hi_open=True
                ),
            )
            tol = DAMPING_TOLERANCE if self.damping_tolerance is None else self.damping_tolerance
            tol = check_real(tol, "target.damping_tolerance", "", lo=MIN_TOLERANCE, hi=1.0)
            s(self, "damping_tolerance", tol)
        elif self.damping_tolerance is not None:
            raise ModelError(
                "a damping tolerance goes with a damping_ratio",
                field="target.damping_tolerance",
                value=self.damping_tolerance,
                valid="damping_ratio = measured ratio beside it, or leave it out",
            )
        if self.frequency_hz is None and self.ratio is None and self.ratio_to is None:
            if self.damping_ratio is None:
                raise ModelError(
                    "give frequency_hz, ratio_to and ratio, or damping_ratio",
                    field="target",
                    value=self.mode,
                    valid="{mode, frequency_hz, tolerance}, {mode, ratio_to, ratio, tolerance} or "
                    "{mode, damping_ratio, damping_tolerance} (a damping ratio may sit beside either)",
                )
            if self.tolerance is not None:
                raise ModelError(
                    "tolerance is a frequency's or ratio's; a damping ratio's is damping_tolerance",
                    field="target.tolerance",
                    value=self.tolerance,
                    valid="damping_tolerance = relative tolerance, or frequency_hz / ratio beside it",
                )
            return
        tol = DEFAULT_TOLERANCE if self.tolerance is None else self.tolerance
        s(self, "tolerance", check_real(tol, "target.tolerance", "", lo=MIN_TOLERANCE, hi=1.0))
        if (self.frequency_hz is None) == (self.ratio is None):
            raise ModelError(
                "give either frequency_hz or ratio_to and ratio",
                field="target",
                value=self.mode,
                valid="{mode, frequency_hz, tolerance} or {mode, ratio_to, ratio, tolerance}",
            )
        if self.frequency_hz is not None:
            s(
                self,
                "frequency_hz",
                check_real(
                    self.frequency_hz, "target.frequency_hz", "Hz", lo=TARGET_RANGE[0], hi=TARGET_RANGE[1]
                ),
            )
            if self.ratio_to is not None:
                raise ModelError("ratio_to goes with ratio", field="target.ratio_to", valid="leave it out")
        else:
            if self.ratio_to is None:
                raise ModelError(
                    "a ratio needs the mode it is to", field="target.ratio_to", valid="a mode >= 1"
                )
            s(self, "ratio_to", _mode_number(self.ratio_to, "target.ratio_to"))
            s(
                self,
                "ratio",
                check_real(self.ratio, "target.ratio", "", lo=TARGET_RANGE[0], hi=TARGET_RANGE[1]),
            )
            if self.ratio_to == self.mode:
                raise ModelError(
                    "a mode's ratio to itself",
                    field="target.ratio_to",
                    value=self.ratio_to,
                    valid=f"another mode than mode = {self.mode}",
                )

    @property
    def has_frequency(self) -> bool:
        """Whether it targets a frequency or a ratio (else only the damping ratio)."""
        return self.frequency_hz is not None or self.ratio is not None

    @property
    def label(self) -> str:
        """``"f2 = 91.1 Hz"`` or ``"f2/f1 = 2.59"``; a damping-only target's :attr:`damping_label`."""
        if self.frequency_hz is not None:
            return f"f{self.mode} = {self.frequency_hz:g} Hz"
        if self.ratio is not None:
            return f"f{self.mode}/f{self.ratio_to} = {self.ratio:g}"
        return self.damping_label

    @property
    def damping_label(self) -> str | None:
        """``"ξ2 = 0.53 %"``, None without a damping ratio."""
        if self.damping_ratio is None:
            return None
        return f"ξ{self.mode} = {100 * self.damping_ratio:.4g} %"

    @property
    def value(self) -> float | None:
        """The target value (Hz or a ratio); None for a damping-only target."""
        return self.frequency_hz if self.frequency_hz is not None else self.ratio


@dataclass(frozen=True)
class Bound:
    """A parameter to tune and its bounds (absolute, SI), or a value to fix.

    Parameters
    ----------
    name : str
        ``COMPONENT.FIELD`` or ``MATERIAL.FIELD``.
    lower, upper : float, optional
        Absolute bounds, SI.
    percent : float, optional
        Instead: ± this % around the starting value.
    fixed : float, optional
        Set the parameter to this value and leave it there (not tuned).
    """

    name: str
    lower: float | None = None
    upper: float | None = None
    percent: float | None = None
    fixed: float | None = None

    def __post_init__(self) -> None:
        given = [
            self.percent is not None,
            self.lower is not None or self.upper is not None,
            self.fixed is not None,
        ]
        if sum(given) != 1:
            raise ModelError(
                "give bounds, percent or fixed (one of them)",
                field="parameter",
                value=self.name,
                valid="bounds = [lo, hi], percent = 10, or fixed = value",
            )
        if self.percent is not None:
            object.__setattr__(
                self,
                "percent",
                check_real(self.percent, f"{self.name}.percent", "%", lo=MIN_PERCENT, hi=99.0),
            )
        if given[1]:
            if self.lower is None or self.upper is None:
                raise ModelError("needs both bounds", field=f"{self.name}.bounds", valid="[lower, upper]")
            lo = check_real(self.lower, f"{self.name}.bounds", "")
            hi = check_real(self.upper, f"{self.name}.bounds", "", lo=lo, lo_open=True)
            object.__setattr__(self, "lower", lo)
            object.__setattr__(self, "upper", hi)

    def limits(self, start: float) -> tuple[float, float]:
        """Absolute (lower, upper) around the starting value."""
        if self.percent is not None:
            a, b = start * (1 - self.percent / 100), start * (1 + self.percent / 100)
            return (min(a, b), max(a, b))
        return (self.lower, self.upper)


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
        Each one's damping ratio (fraction) before and after: the damped mode's ξ = −Re λ/|λ| of the
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


def _mac(A: np.ndarray, B: np.ndarray, M=None) -> np.ndarray:
    """MAC between the columns of A and of B: (aᵀMb)²/((aᵀMa)(bᵀMb)), M the identity if not given.

    Weighted by the inertia matrix the modes are orthogonal in, two different modes of one model
    have MAC 0 exactly. Unweighted, two modes of a finely meshed chain can look 90 % alike (the
    many nodes of the long shafts barely move in either, the few heavy ones that differ count once),
    and whether they passed for distinct then depended on round-off.
    """
    MB = B if M is None else M @ B
    MA = A if M is None else M @ A
    num = (A.T @ MB) ** 2
    return num / np.outer(np.einsum("ij,ij->j", A, MA), np.einsum("ij,ij->j", B, MB))


class _Tracker:
    """The modes of the targets, followed by shape from point to point (see the module docstring).

    The model at a point is ``model`` there (a :class:`ParametrisedModel`: no assembly at all where
    K and M are affine in the parameters)."""

    def __init__(self, model: ParametrisedModel, start: np.ndarray, wanted: np.ndarray, result=None):
        self.param = model
        self.wanted = wanted  # mode numbers of the starting model the targets use
        self.point = start.copy()
        self.result = self._solve(start) if result is None else result  # the modes at start, if known
        self.modes = wanted.copy()
        self.shapes = self.result.shapes[:, wanted]

    def _solve(self, x: np.ndarray):
        return _modes(self.param.model(x), self.wanted)

    def _match(self, result) -> np.ndarray | None:
        mac = _mac(self.shapes, result.shapes, result.model.M)  # inertia-weighted: distinct modes 0
        mac[:, result.rigid] = 0.0
        best = np.argmax(mac, axis=1)
        top = mac[np.arange(best.size), best]
        second = np.sort(mac, axis=1)[:, -2] if mac.shape[1] > 1 else np.zeros(best.size)
        if np.any(top < MAC_CLEAR) or np.any(second > top - 0.1) or np.unique(best).size != best.size:
            return None
        return best

    def go(self, x: np.ndarray):
        """Move to x along the straight path, halving steps until every mode is matched clearly."""
        x = np.asarray(x, dtype=float)
        if np.array_equal(x, self.point):
            return self.result, self.modes
        for _ in range(1000):  # sub-steps; each one accepted moves the reference on
            result = self._solve(x)
            matched = self._match(result)
            if matched is not None:
                self._accept(x, result, matched)
                return result, matched
            step, frac = x - self.point, 0.5
            for _ in range(MAX_HALVINGS):
                mid = self.point + frac * step
                r_mid = self._solve(mid)
                m_mid = self._match(r_mid)
                if m_mid is not None:
                    self._accept(mid, r_mid, m_mid)
                    break
                frac *= 0.5
            else:
                raise ModelError(
                    "cannot follow the targets' modes by shape (two modes too alike along the way)",
                    field="target",
                    valid="targets on modes that stay distinguishable, or narrower bounds",
                )
        raise ModelError("mode tracking does not converge", field="target")

    def _accept(self, x, result, matched):
        self.point = x.copy()
        self.result = result
        self.modes = matched
        self.shapes = result.shapes[:, matched]


def _modes(m, wanted) -> ModalResult:
    """The undamped modes the tracker compares: all of a model up to 2000 coordinates (a tracked
    mode may move anywhere among them), else the lowest beyond the highest wanted (checked to be
    the model's: :func:`_check_targets`)."""
    n = m.n_dof
    return modal_analysis(m, n if n <= 2000 else min(n, max(int(np.max(wanted)) + 6, 16)), damped=False)


def _alone(model, x, k, target, wanted, at_x) -> float | None:
    """The % change of parameter k alone (the others as tuned) that meets ``target``; None if no
    change within a factor 100 either way does. The mode is followed by shape along the way."""
    from scipy.optimize import brentq

    tracker = _Tracker(model, x, np.asarray(at_x))
    index = {m: j for j, m in enumerate(wanted)}

    def miss(factor: float) -> float:
        z = x.copy()
        z[k] *= factor
        try:
            result, modes = tracker.go(z)
        except ModelError:
            return np.nan  # the value is out of the component's range, or tracking lost the mode
        modes_of = {m: int(modes[index[m]]) for m in wanted}
        return float(_values(result, modes_of, [target])[0] / target.value - 1)

    m1 = miss(1.0)
    for direction in (1.5, 1 / 1.5):
        a, fa = 1.0, m1
        b = a
        while 1e-2 < b < 1e2:
            b = a * direction
            fb = miss(b)
            if not np.isfinite(fb):
                break
            if np.sign(fb) != np.sign(fa):
                try:
                    root = brentq(miss, min(a, b), max(a, b), xtol=1e-10, rtol=1e-10)
                except ValueError:
                    # The mode is followed by shape, so a point's value depends on the path to it: near a
                    # crossing brentq's own look at the ends can disagree with ours. Bisection keeps the
                    # signs we saw.
                    root = _bisect(miss, a, fa, b)
                if root is None:
                    return None
                return float(100 * (root - 1))
            a, fa = b, fb
        tracker.go(x)  # back to the tuned point before the other direction
    return None


def _bisect(miss, a: float, fa: float, b: float, rtol: float = 1e-9) -> float | None:
    """A root of ``miss`` between ``a`` (where it is ``fa``) and ``b`` (the other sign), by bisection;
    None when a point in between cannot be evaluated."""
    for _ in range(200):
        mid = 0.5 * (a + b)
        if abs(b - a) <= rtol * abs(mid):
            return mid
        fm = miss(mid)
        if not np.isfinite(fm):
            return None
        if fm == 0:
            return mid
        if np.sign(fm) == np.sign(fa):
            a, fa = mid, fm
        else:
            b = mid
    return 0.5 * (a + b)


def _physics(d: Drivetrain, names, x0, x) -> tuple:
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


def _parametrise(d: Drivetrain, names, x0, lo, hi, inertia_model) -> ParametrisedModel:
    """The model as a function of the tuned parameters, its affinity checked inside the bounds.

    The check's point moves every parameter by a distinct fraction (k + 1)/(p + 1) of the way to a
    bound, alternately the upper and the lower one, so that no symmetry of the bounds hides a term
    in which two parameters act on each other.
    """
    p = len(names)
    probe = np.array(x0, dtype=float)
    for k in range(p):
        up = (k % 2 == 0 and hi[k] > x0[k]) or lo[k] >= x0[k]
        probe[k] += (k + 1) / (p + 1) * ((hi[k] if up else lo[k]) - x0[k])
    return ParametrisedModel(
        d, names, x0, probe=probe, bounds=(np.asarray(lo), np.asarray(hi)), inertia_model=inertia_model
    )


def _solver_options(stop: float, max_evaluations: int) -> dict:
    """least_squares' options: trust-region reflective on unit-scaled parameters, stopping at ``stop``."""
    return dict(x_scale=1.0, method="trf", max_nfev=max_evaluations, xtol=stop, ftol=stop, gtol=stop)


def _solver_tolerance(targets) -> float:
    """xtol, ftol and gtol of the least-squares solver (see :data:`SOLVER_FRACTION`)."""
    return SOLVER_FRACTION * min(t.tolerance for t in targets)


def _solve_start(args):
    """One start of the least-squares problem, from ``point``; picklable, so an executor can run it.

    Returns the optimiser's result and the tracked modes at its end point.
    """
    from scipy.optimize import least_squares

    model, d, names, x0, lo, hi, wanted, targets, inertia_model, max_evaluations, point, at_x0 = args
    if model is None:  # on a worker: its own, the same as the caller's (the same assemblies)
        model = _parametrise(d, names, x0, lo, hi, inertia_model)
    tol = np.array([t.tolerance for t in targets])
    goal = np.array([t.value for t in targets])
    tracker = _Tracker(model, x0, np.array(wanted), at_x0)
    tracker.go(point)  # reach the start along a tracked path from the model's own values
    x_start = point
    index = {m: k for k, m in enumerate(wanted)}

    def state(z):
        result, modes = tracker.go(z * x0)
        modes_of = {m: int(modes[index[m]]) for m in wanted}
        return result, modes_of

    def residual(z):
        result, modes_of = state(z)
        return (_values(result, modes_of, targets) / goal - 1) / tol

    def jacobian(z):
        result, modes_of = state(z)
        m = sorted(set(modes_of.values()))
        df = frequency_derivatives(result, model.derivatives(z * x0), m)
        row = {mode: df[i] for i, mode in enumerate(m)}
        f = result.frequencies_hz
        J = []
        for t in targets:
            a = modes_of[t.mode]
            if t.ratio_to is None:
                dv = row[a]
            else:
                b = modes_of[t.ratio_to]
                dv = (row[a] * f[b] - f[a] * row[b]) / f[b] ** 2
            J.append(dv * x0 / t.value / t.tolerance)
        return np.array(J)

    z0 = x_start / x0
    stop = _solver_tolerance(targets)
    sol = least_squares(
        residual,
        z0,
        jac=jacobian,
        bounds=(lo / x0, hi / x0),
        **_solver_options(stop, max_evaluations),
    )
    _onto_bounds(sol, residual, jacobian, lo / x0, hi / x0, stop, max_evaluations)
    _, modes = tracker.go(sol.x * x0)
    return sol, modes


def _onto_bounds(sol, residual, jacobian, lower, upper, stop: float, max_evaluations: int) -> None:
    """Put the parameters the cost pushes against a bound onto it, then re-solve the others.

    Trust-region-reflective iterates stay strictly inside the bounds and close in on an active one
    by a fraction of the remaining distance per step, so a solver stopped at the targets' resolution
    leaves such a parameter a little short of its bound (up to ~1e-3 of its range in the study),
    and 1e-12 tolerances spent most of their Jacobians on that last approach. Each parameter whose
    gradient points at its nearer bound is tried on it, nearest first, and kept there if the cost
    does not rise: at the optimum an active bound holds it exactly, while a parameter that belongs
    inside raises the cost when moved off its optimum and stays where it is. The parameters left
    free are then solved again with those on bounds fixed (a smaller problem, started next to its
    optimum), kept if the cost does not rise. Updates ``sol`` (x, fun, jac, cost) in place.
    """
    from scipy.optimize import least_squares

    z = sol.x.copy()
    g = sol.jac.T @ sol.fun
    near_lower = z - lower <= upper - z
    bound = np.where(near_lower, lower, upper)
    pushed = np.where(near_lower, g > 0, g < 0) & (z != bound)
    cost, fun, held = sol.cost, sol.fun, np.zeros(z.size, dtype=bool)
    for k in sorted(np.flatnonzero(pushed), key=lambda k: abs(z[k] - bound[k])):
        trial = z.copy()
        trial[k] = bound[k]
        r = residual(trial)
        c = 0.5 * float(r @ r)
        if c <= cost:
            z, cost, fun = trial, c, r
            held[k] = True
    if not held.any():
        return
    free = np.flatnonzero(~held & (z > lower) & (z < upper))
    if free.size:

        def at(w):
            out = z.copy()
            out[free] = w
            return out

        sub = least_squares(
            lambda w: residual(at(w)),
            z[free],
            jac=lambda w: jacobian(at(w))[:, free],
            bounds=(lower[free], upper[free]),
            **_solver_options(stop, max_evaluations),
        )
        if sub.cost <= cost:
            z, cost, fun = at(sub.x), sub.cost, sub.fun
    sol.x, sol.fun, sol.cost = z, fun, cost
    sol.jac = jacobian(z)


def _by_shape(m, targets) -> list:
    """Check the targets that carry a measured shape against the starting model's modes (MAC);
    ``m`` is the starting model, assembled, and the targets are checked (:func:`_check_targets`)."""
    if not any(t.shape is not None for t in targets):
        return list(targets)
    r = _modes(m, [t.mode for t in targets])
    st = r.station_shapes()
    for i, t in enumerate(targets):
        if t.shape is None:
            continue
        v = np.asarray(t.shape)
        mac = np.array(
            [(v @ st[:, j]) ** 2 / ((v @ v) * (st[:, j] @ st[:, j]) or 1.0) for j in range(r.count)]
        )
        mac[r.rigid] = 0.0
        best = int(np.argmax(mac))
        if mac[best] < MAC_CLEAR or best != t.mode:
            raise ModelError(
                f"the measured shape is mode {best} of the model (MAC {mac[best]:.2f}), not mode {t.mode}"
                if mac[best] >= MAC_CLEAR
                else f"no mode of the model has the measured shape (best: mode {best}, MAC {mac[best]:.2f})",
                component=_where("target", i),
                field="target.mode",
                value=t.mode,
                valid=f"mode = {best}" if mac[best] >= MAC_CLEAR else f"a shape with MAC >= {MAC_CLEAR}",
            )
    return list(targets)


def check_problem(drivetrain: Drivetrain, targets, params, *, inertia_model: str | None = None) -> None:
    """Check a calibration problem against its model without solving anything.

    Every target's mode numbers are elastic modes of the model, its shape has a value per station,
    no frequency, ratio or damping ratio is targeted twice; every parameter is the model's, named once,
    its fixed value or bounds inside what it can take; damping targets have a damping parameter to
    tune and frequency targets a stiffness or inertia one, and every tuned parameter a target.
    :func:`calibrate` does this (and checks the bounds against the starting values) before its
    optimiser starts; a staged calibration checks every stage this way before the first one runs.
    Errors name the entry as a targets file labels it (``[[target]] #2``) and the field.
    """
    targets, params = list(targets), list(params)
    if not targets:
        raise ModelError("no targets", field="target", valid="at least one [[target]]")
    _check_parameters(drivetrain, params)
    _check_targets(targets, assemble(drivetrain, inertia_model, reduce=False, damping=False))
    _check_pairing(drivetrain, targets, params)


def _where(kind: str, i: int) -> str:
    """The entry a problem is in, as a targets file labels it: ``[[target]] #2``."""
    return f"[[{kind}]] #{i + 1}"


def _check_parameters(d: Drivetrain, params) -> None:
    """Every parameter is a Bound of this model, named once (tuned or fixed), a fixed value one the
    parameter can take."""
    seen: dict = {}
    for k, b in enumerate(params):
        where = _where("parameter", k)
        if not isinstance(b, Bound):
            raise ModelError(
                "not a parameter", component=where, value=type(b).__name__, valid="a Bound", has_value=True
            )
        try:
            domain = parameter_domain(d, b.name)
        except ModelError as err:
            raise err.located(component=where) from None
        if b.name in seen:
            raise ModelError(
                f"is listed twice ({seen[b.name]} too)",
                component=where,
                field="parameter",
                value=b.name,
                valid="each parameter once: tuned (bounds, percent) or fixed",
            )
        seen[b.name] = where
        rayleigh = [n for n in seen if n.startswith("rayleigh.")]
        if len({n.startswith("rayleigh.damping_ratios") for n in rayleigh}) == 2:
            raise ModelError(
                f"states the Rayleigh damping a second way ({', '.join(rayleigh)})",
                component=where,
                field="parameter",
                value=b.name,
                valid="rayleigh.alpha and rayleigh.beta, or the two rayleigh.damping_ratios",
            )
        if b.lower is not None and not (domain.contains(b.lower) and domain.contains(b.upper)):
            raise ModelError(
                f"the {'lower' if not domain.contains(b.lower) else 'upper'} bound is not a value "
                f"{b.name} can take",
                component=where,
                field=f"{b.name}.bounds",
                value=[float(b.lower), float(b.upper)],
                unit=domain.unit or None,
                valid=f"bounds inside {b.name} {domain.text}",
            )
        if b.fixed is not None and not domain.contains(b.fixed):
            raise ModelError(
                f"is not a value {b.name} can take",
                component=where,
                field=f"{b.name}.fixed",
                value=float(b.fixed),
                unit=domain.unit or None,
                valid=f"{b.name} {domain.text}",
            )


def _check_bounds(d: Drivetrain, params, free, x0, lo, hi) -> None:
    """The tuned parameters' bounds: inside the values each can take (a stiffness > 0, a damping
    ratio in [0, 1) ...), wide enough for a double to tell apart, around the model's value, which is
    not 0. ``lo``, ``hi`` are the absolute bounds (from ``bounds`` or ± ``percent``)."""
    index = {id(b): k for k, b in enumerate(params)}
    for j, b in enumerate(free):
        where, name = _where("parameter", index[id(b)]), b.name
        domain = parameter_domain(d, name)
        unit = domain.unit or None
        key = "percent" if b.percent is not None else "bounds"
        given = float(b.percent) if b.percent is not None else [float(lo[j]), float(hi[j])]
        if not (domain.contains(lo[j]) and domain.contains(hi[j])):
            side = "lower" if not domain.contains(lo[j]) else "upper"
            reach = f" (± {b.percent:g} % of {x0[j]:g} is {lo[j]:g} … {hi[j]:g})" if key == "percent" else ""
            raise ModelError(
                f"the {side} bound is not a value {name} can take{reach}",
                component=where,
                field=f"{name}.{key}",
                value=given,
                unit=unit if key == "bounds" else "%",
                valid=f"bounds inside {name} {domain.text}",
            )
        damping = is_damping(d, name)
        if x0[j] == 0 and (key == "percent" or not damping):
            # a damping parameter's solve is scaled by its bounds where it starts at 0 (no damper yet)
            raise ModelError(
                "cannot tune a parameter that is 0 (its change has no scale)",
                component=where,
                field=name,
                value=0.0,
                valid="bounds = [lower, upper] (a damping parameter may start at 0), or fixed = value"
                if damping
                else "a parameter whose value in the model is not 0, or fixed = value",
            )
        room = 1e-12 * abs(x0[j]) if x0[j] else 1e-300  # from 0: a width its scale can divide by
        if not hi[j] - lo[j] > room:  # bounds a double cannot tell apart
            raise ModelError(
                "the bounds leave no room to tune",
                component=where,
                field=f"{name}.{key}",
                value=given,
                valid=f"bounds at least 1e-12 of the value ({x0[j]:.10g}) apart, or fixed = value"
                if x0[j]
                else "bounds more than 1e-300 apart, or fixed = value",
            )
        if not lo[j] <= x0[j] <= hi[j]:
            raise ModelError(
                f"the bounds do not contain the model's value, {x0[j]:.10g}",
                component=where,
                field=f"{name}.{key}",
                value=given,
                unit=unit,
                valid=f"bounds around {x0[j]:.10g} (the starting point), inside {name} {domain.text}",
            )


def _check_targets(targets, m) -> None:
    """Every target's mode numbers are elastic modes of the starting model ``m`` (assembled), its
    shape (if any) has a value per station, and no quantity is targeted twice - before any solve."""
    n, rigid = m.n_dof, m.rigid_basis.shape[1]
    zero = "mode 0 is" if rigid == 1 else f"modes 0 … {rigid - 1} are"
    valid = f"an elastic mode of the model, {rigid} … {n - 1}" if n > rigid else "a model with elastic modes"
    seen: dict = {}
    for i, t in enumerate(targets):
        where = _where("target", i)
        if not isinstance(t, Target):
            raise ModelError(
                "not a target", component=where, value=type(t).__name__, valid="a Target", has_value=True
            )
        for key, k in (("mode", t.mode), ("ratio_to", t.ratio_to)):
            if k is not None and not rigid <= k < n:
                raise ModelError(
                    f"the model has {n} modes, 0 … {n - 1}; {zero} rigid-body"
                    if 0 <= k < n
                    else f"no such mode: the model has {n} modes, 0 … {n - 1}",
                    component=where,
                    field=f"target.{key}",
                    value=k,
                    valid=valid,
                )
        if t.shape is not None and len(t.shape) != len(m.stations):
            raise ModelError(
                f"has {len(t.shape)} values for the model's {len(m.stations)} stations",
                component=where,
                field="target.shape",
                value=len(t.shape),
                valid="θx at each station, in order: " + ", ".join(repr(x.name) for x in m.stations),
            )
        # f2/f1 and f1/f2 are one quantity; two targets on it contradict or repeat each other
        keys = []
        if t.has_frequency:
            keys.append(("f", t.mode) if t.ratio_to is None else ("r", *sorted((t.mode, t.ratio_to))))
        if t.damping_ratio is not None:
            keys.append(("z", t.mode))
        for key in keys:
            if key in seen:
                raise ModelError(
                    f"targets what {seen[key]} targets already",
                    component=where,
                    field="target",
                    value=t.label if key[0] != "z" else t.damping_label,
                    valid="one target per frequency, ratio or damping ratio",
                )
            seen[key] = _where("target", i)


def _check_pairing(d: Drivetrain, targets, params) -> None:
    """Each kind of target has a parameter of its kind to tune, and each tuned parameter a target.

    The undamped modes do not move with a damping parameter, and the damping ratios are not the
    frequency parameters' to meet (they are set by the frequency targets): a damping target is met
    by damping parameters alone, a frequency or ratio by stiffness, inertia and the like. A target
    nothing can move, or a parameter no target asks to move, is a mistake in the problem.
    """
    free = [(k, b) for k, b in enumerate(params) if b.fixed is None]
    damping = {b.name: is_damping(d, b.name) for _, b in free}
    has = {True: any(damping.values()), False: not all(damping.values())}
    wants = {
        True: any(t.damping_ratio is not None for t in targets),
        False: any(t.has_frequency for t in targets),
    }
    for i, t in enumerate(targets):
        if t.damping_ratio is not None and not t.has_frequency and not has[True]:
            # beside a frequency a damping ratio without a damping parameter is compared, not met (a
            # targets file from `flexshaft identify` carries both); alone it would be a target for nothing
            names = [p.name for p in parameters(d) if p.field in DAMPING_FIELDS]
            raise ModelError(
                "a damping ratio needs a damping parameter to tune (stiffness and inertia are the frequency "
                "targets')",
                component=_where("target", i),
                field="target.damping_ratio",
                value=t.damping_ratio,
                valid="a [[parameter]] that sets damping: " + ", ".join(names),
            )
        if t.has_frequency and not has[False]:
            raise ModelError(
                "no parameter moves the frequencies (damping parameters leave the undamped modes as "
                "they are)",
                component=_where("target", i),
                field="target.frequency_hz" if t.frequency_hz is not None else "target.ratio",
                value=t.value,
                valid="a stiffness, inertia or material [[parameter]] beside the damping ones",
            )
    for k, b in free:
        if damping[b.name] and not wants[True]:
            raise ModelError(
                "sets damping, and no target has a damping_ratio (damping leaves the undamped frequencies "
                "as they are)",
                component=_where("parameter", k),
                field="parameter",
                value=b.name,
                valid="a [[target]] with damping_ratio, or fixed = value",
            )
        if not damping[b.name] and not wants[False]:
            raise ModelError(
                "moves the frequencies, and no target has frequency_hz or ratio",
                component=_where("parameter", k),
                field="parameter",
                value=b.name,
                valid="a [[target]] with frequency_hz or ratio, or fixed = value",
            )


def _joined(*messages: str) -> str:
    """The solves' messages and the notes, in one line."""
    return "; ".join(m.rstrip(".") for m in messages if m)


def _shape_macs(result, modes_of: dict, targets) -> np.ndarray:
    """Each target's measured shape's MAC with its tracked mode at the stations (θx); NaN without one."""
    st = result.station_shapes() if any(t.shape is not None for t in targets) else None
    out = np.full(len(targets), np.nan)
    for k, t in enumerate(targets):
        if t.shape is not None:
            v, w = np.asarray(t.shape), st[:, modes_of[t.mode]]
            out[k] = (v @ w) ** 2 / ((v @ v) * (w @ w))
    return out


def _shape_notes(targets, before, after) -> list[str]:
    return [
        f"mode {t.mode}'s shape matches the measured one less than at the start (MAC {a:.3f} -> {b:.3f}): "
        "other values may meet the frequencies as well - narrow the bounds to what is known, or start nearer"
        for t, a, b in zip(targets, before, after)
        if b < a - SHAPE_MAC_FALL
    ]


def _values(result, modes_of: dict, targets) -> np.ndarray:
    f = result.frequencies_hz
    out = []
    for t in targets:
        v = f[modes_of[t.mode]]
        if t.ratio_to is not None:
            v = v / f[modes_of[t.ratio_to]]
        out.append(v)
    return np.array(out)


@follows_policy
def calibrate(
    drivetrain: Drivetrain,
    targets,
    params,
    *,
    starts: int = 1,
    seed: int = 0,
    inertia_model: str | None = None,
    max_evaluations: int = 1000,
    executor=None,
) -> CalibrationResult:
    """Tune parameters inside their bounds so the modes hit their targets.

    Frequencies and ratios are met by the stiffness, inertia and material parameters (bounded least
    squares, modes tracked by shape: the module docstring). Damping ratios are met by the damping
    parameters (:data:`~flexshaft.analysis.sensitivity.DAMPING_FIELDS`: a shaft's ``damping_ratio``
    or ``damping``, a flexible body's ``damping_ratio``, a coupling's ``damping``, a gear's
    ``mesh_damping``, ``rayleigh.alpha``/``beta`` or the two ``rayleigh.damping_ratios``) in a
    second solve on the tuned model: they leave the undamped modes where the first put them (see
    :func:`_damping_solve`).

    Parameters
    ----------
    drivetrain : Drivetrain
    targets : sequence of Target
    params : sequence of Bound
        Parameters to tune (bounds or ± %) or to fix. A damping parameter may start at 0 (no damper
        yet) where it has absolute bounds.
    starts : int
        Starting points of the frequency solve: the model's own values, and ``starts − 1``
        Latin-hypercube points inside the bounds (for a problem that is not convex). The best end
        point is kept. (The damping solve is linear to first order in the damping: one start.)
    seed : int
        Seed of those points.
    inertia_model : str, optional
    max_evaluations : int
        Model evaluations per start (the optimiser's ``max_nfev``).
    executor : concurrent.futures.Executor, optional
        Runs the starts in parallel (local processes, or a Dask cluster's executor); in turn
        without one.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    ModelError
        Before the optimiser starts, for a problem the model cannot pose (:func:`check_problem`:
        mode numbers that are not the model's elastic modes, a target given twice, a shape of the
        wrong length, an unknown or repeated parameter, a fixed value or bounds outside what the
        parameter can take, a damping-only target without a damping parameter to tune (beside a
        frequency the ratio is then compared, not met) or a damping parameter without a damping
        target, and likewise for frequencies), or bounds that do not
        contain the model's value or leave no room.
    """
    targets, params = list(targets), list(params)
    if not targets:
        raise ModelError("no targets", field="target", valid="at least one [[target]]")
    starts = check_ceiling("starts", check_int(starts, "starts", lo=1), field="starts")
    _check_parameters(drivetrain, params)
    fixed = {b.name: b.fixed for b in params if b.fixed is not None}
    d = with_parameters(drivetrain, fixed) if fixed else drivetrain
    free = [b for b in params if b.fixed is None]
    if not free:
        raise ModelError(
            "nothing to tune", field="parameter", valid="at least one parameter with bounds or percent"
        )
    names = [b.name for b in free]
    x0 = np.array([parameter_value(d, n) for n in names])
    lims = np.array([b.limits(v) for b, v in zip(free, x0)])
    lo, hi = lims[:, 0], lims[:, 1]
    _check_bounds(d, params, free, x0, lo, hi)
    m0 = assemble(d, inertia_model, reduce=False, damping=False)
    _check_targets(targets, m0)
    _check_pairing(d, targets, params)
    targets = _by_shape(m0, targets)
    ftargets = [t for t in targets if t.has_frequency]
    ztargets = [t for t in targets if t.damping_ratio is not None]
    damp = np.array([is_damping(d, n) for n in names])
    fk, zk = np.flatnonzero(~damp), np.flatnonzero(damp)
    wanted = sorted({t.mode for t in targets} | {t.ratio_to for t in ftargets if t.ratio_to is not None})
    x = x0.copy()
    active, widen, unmet = [None] * len(names), [0.0] * len(names), []
    if fk.size:
        fs_ = _frequency_solve(
            d,
            [names[k] for k in fk],
            x0[fk],
            lo[fk],
            hi[fk],
            ftargets,
            wanted,
            starts=starts,
            seed=seed,
            inertia_model=inertia_model,
            max_evaluations=max_evaluations,
            executor=executor,
        )
        x[fk] = fs_.x
        for j, k in enumerate(fk):
            active[k], widen[k] = fs_.active[j], fs_.widen[j]
        unmet += fs_.unmet
        start_result, result, modes_at = fs_.start_result, fs_.result, fs_.modes
        cost, message, n_starts = fs_.cost, fs_.message, fs_.starts
    else:
        start_result = result = _modes(m0, wanted)
        modes_at, cost, message, n_starts = np.array(wanted), 0.0, "", 1
    modes_of = {m: int(modes_at[j]) for j, m in enumerate(wanted)}
    d_tuned = with_parameters(d, {names[k]: x[k] for k in fk})
    zinit = zvalues = np.zeros(0)
    if ztargets and not zk.size:
        # damping ratios beside frequencies, nothing to tune them with: compared at the start and the end
        zinit = _DampedRatios(d, [], inertia_model, start_result, [t.mode for t in ztargets]).at([])[0]
        tuned_modes = [modes_of[t.mode] for t in ztargets]
        zvalues = _DampedRatios(d_tuned, [], inertia_model, result, tuned_modes).at([])[0]
        message = _joined(message, "damping ratios compared, not tuned: no damping parameter is tuned")
    if zk.size:
        znames = [names[k] for k in zk]
        at_start = _DampedRatios(d, znames, inertia_model, start_result, [t.mode for t in ztargets])
        zinit = at_start.at(x0[zk])[0]
        ratios = _DampedRatios(d_tuned, znames, inertia_model, result, [modes_of[t.mode] for t in ztargets])
        zs = _damping_solve(ratios, x0[zk], lo[zk], hi[zk], ztargets, max_evaluations)
        x[zk] = zs.x
        zvalues = zs.values
        for j, k in enumerate(zk):
            active[k], widen[k] = zs.active[j], zs.widen[j]
        unmet += _damping_unmet(d, znames, zs, ztargets)
        cost += zs.cost
        message = _joined(message, zs.message)
    tuned_d = with_parameters(d, dict(zip(names, x)))
    # the reported values from the model assembled at the end point
    values = _values(result, modes_of, ftargets) if ftargets else np.zeros(0)
    initial_values = _values(start_result, {m: m for m in wanted}, ftargets) if ftargets else np.zeros(0)
    shape_mac = _shape_macs(result, modes_of, ftargets)
    initial_shape_mac = _shape_macs(start_result, {m: m for m in wanted}, ftargets)
    message = _joined(message, *_shape_notes(ftargets, initial_shape_mac, shape_mac))
    return CalibrationResult(
        physics=_physics(d, names, x0, x),
        names=tuple(names),
        initial=x0,
        tuned=x,
        lower=lo,
        upper=hi,
        targets=tuple(ftargets),
        initial_values=initial_values,
        values=values,
        modes=np.array([modes_of[t.mode] for t in ftargets], dtype=int),
        active=tuple(active),
        widen=tuple(widen),
        unmet=tuple(unmet),
        drivetrain=tuned_d,
        fixed=fixed,
        cost=float(cost),
        starts=n_starts,
        message=message,
        damping_targets=tuple(ztargets),
        initial_damping=np.asarray(zinit, dtype=float),
        damping=np.asarray(zvalues, dtype=float),
        damping_modes=np.array([modes_of[t.mode] for t in ztargets], dtype=int),
        initial_shape_mac=initial_shape_mac,
        shape_mac=shape_mac,
    )


@dataclass
class _FrequencySolution:
    """What the frequency solve leaves: the tuned values of its parameters (SI), the modes before and
    at the end (the unreduced model, :func:`_modes`), the tracked modes (one per wanted mode), and its
    findings per parameter and target."""

    x: np.ndarray
    start_result: ModalResult
    result: ModalResult
    modes: np.ndarray
    active: list
    widen: list
    unmet: list
    cost: float
    message: str
    starts: int


def _frequency_solve(
    d, names, x0, lo, hi, targets, wanted, *, starts, seed, inertia_model, max_evaluations, executor
) -> _FrequencySolution:
    """The frequencies and ratios met by the (non-damping) parameters ``names``: the module docstring."""
    goal = np.array([t.value for t in targets])
    model = _parametrise(d, names, x0, lo, hi, inertia_model)
    base = _Tracker(model, x0, np.array(wanted))
    points = [x0]
    if starts > 1:
        from scipy.stats import qmc  # here: importing scipy.stats takes ~1 s, a single start needs none

        u = qmc.LatinHypercube(d=len(names), seed=seed).random(starts - 1)
        points += list(lo + u * (hi - lo))
    # In turn, every start reuses the parametrised model and the starting model's modes; on an
    # executor each worker builds them itself rather than receiving them.
    shared = (model, base.result) if executor is None else (None, None)
    jobs = [
        (shared[0], d, names, x0, lo, hi, wanted, targets, inertia_model, max_evaluations, p, shared[1])
        for p in points
    ]
    runs = list(
        executor.map(_solve_start, jobs)
        if executor is not None and len(jobs) > 1
        else map(_solve_start, jobs)
    )
    sol, modes = min(runs, key=lambda run: run[0].cost)
    # on a bound: the bound itself, not (bound/x0)·x0 an ulp away
    x = np.where(sol.x <= lo / x0, lo, np.where(sol.x >= hi / x0, hi, sol.x * x0))
    # the reported values from the model assembled at the end point
    result = _modes(
        assemble(with_parameters(d, dict(zip(names, x))), inertia_model, reduce=False, damping=False), modes
    )
    modes_of = {m: int(modes[k]) for k, m in enumerate(wanted)}
    values = _values(result, modes_of, targets)
    active, widen = _on_bounds(sol.jac.T @ sol.fun, x, x0, lo, hi)
    unmet = []
    errors = values / goal - 1
    at_tuned = np.array([modes_of[m] for m in wanted])
    for i, t in enumerate(targets):
        if abs(errors[i]) <= t.tolerance * (1 + 1e-9):
            continue
        need = []
        for k, n in enumerate(names):
            change = _alone(model, x, k, t, wanted, at_tuned)
            if change is not None:
                need.append({"parameter": n, "change_percent": change})
        need.sort(key=lambda e: abs(e["change_percent"]))
        unmet.append({"target": t.label, "error": float(errors[i]), "alone_would_need": need[:3]})
    return _FrequencySolution(
        x=x,
        start_result=base.result,
        result=result,
        modes=np.asarray(modes),
        active=active,
        widen=widen,
        unmet=unmet,
        cost=float(sol.cost),
        message=str(sol.message),
        starts=len(points),
    )


def _on_bounds(grad, x, scale, lo, hi) -> tuple[list, list]:
    """Which parameters end on a bound the cost pushes against, and the cost's fall per % that bound
    is widened (first order), from the gradient ``grad`` of the cost in the scaled parameters x/scale
    (per % of the parameter: × 0.01·x/scale; per % of its scale where it ends at 0, a damper off)."""
    span = hi - lo
    active, widen = [], []
    for k in range(len(x)):
        g = grad[k] * 0.01 * (x[k] / scale[k] if x[k] != 0 else 1.0)
        if x[k] <= lo[k] + 1e-9 * span[k] and g > 0:
            active.append("lower"), widen.append(float(g))
        elif x[k] >= hi[k] - 1e-9 * span[k] and g < 0:
            active.append("upper"), widen.append(float(-g))
        else:
            active.append(None), widen.append(0.0)
    return active, widen


# --- damping ------------------------------------------------------------------------------------------


class _DampedRatios:
    """The damping ratios of some modes as a function of the damping parameters ``names`` of ``d``.

    The model is the one ``flexshaft modes`` reports: assembled with flexible bodies reduced and
    every damping (a shaft's modal damping, a body's own, dampers, Rayleigh), its damped modes solved
    (:func:`~flexshaft.analysis.damped.damped_modes`: ξ = −Re λ/|λ|). The modes are named as numbers
    of ``result`` (the unreduced undamped modes the frequency solve tracked); where the model has
    flexible bodies, the reduced model's modes are paired with them by shape (inertia-weighted MAC
    of the node DOFs), once: no damping parameter moves an undamped mode.
    """

    def __init__(self, d: Drivetrain, names, inertia_model, result: ModalResult, modes):
        self.d, self.names, self.inertia_model = d, list(names), inertia_model
        self.result, self.modes = result, np.asarray(modes, dtype=int)
        self.count: int | None = None
        self.index: np.ndarray | None = None

    def _pair(self, r: ModalResult) -> np.ndarray:
        if not r.model.bodies:
            return self.modes  # the same K and M as the unreduced model: the same modes, in order
        ref = self.result.model
        mac = _mac(ref.T @ self.result.shapes[:, self.modes], r.model.T @ r.shapes, ref.M_nodes)
        mac[:, r.rigid] = 0.0
        best = np.argmax(mac, axis=1)
        top = mac[np.arange(best.size), best]
        if np.any(top < MAC_CLEAR) or np.unique(best).size != best.size:
            k = int(np.argmin(top))
            raise ModelError(
                f"mode {int(self.modes[k])} has no clear partner among the modes of the model with its "
                f"flexible bodies reduced (best MAC {top[k]:.2f})",
                field="target.damping_ratio",
                valid="flexible bodies reduced with enough modes for the targets' modes (reduce = "
                "{modes = n} or {cutoff_hz = f} above them)",
            )
        return best

    def at(self, x, *, damped: bool = True):
        """(ξ of the damped modes or None without ``damped``, first-order ξ = φᵀCφ/(2ω)) of the modes at
        the damping parameters' values ``x`` (SI)."""
        m = assemble(with_parameters(self.d, dict(zip(self.names, x))), self.inertia_model)
        if self.count is None:
            # as many as `flexshaft modes` lists by default, or past the highest target's mode: a large
            # model's damped modes are solved in their subspace (to second order in the damping)
            self.count = min(m.n_dof, max(DEFAULT_LISTED, int(self.modes.max()) + 6))
        r = modal_analysis(m, self.count, damped=damped)
        if self.index is None:
            self.index = self._pair(r)
        phi, w = r.shapes[:, self.index], r.omega[self.index]
        C = m.C
        first = np.zeros(w.size) if C is None else np.einsum("ij,ij->j", phi, C @ phi) / (2 * w)
        return (r.damping_ratios[self.index] if damped else None), first


@dataclass
class _DampingSolution:
    """The damping solve's end: the parameters (SI), the damped ratios there, the first-order Jacobian
    ∂ξ/∂x, the cost and findings, and what the solve did."""

    x: np.ndarray
    values: np.ndarray
    jacobian: np.ndarray
    active: list
    widen: list
    cost: float
    message: str


def _damping_jacobian(ratios: _DampedRatios, x, first, lo, hi, scale) -> np.ndarray:
    """∂ξ/∂x of the first-order ratios, one difference per parameter: φᵀCφ/(2ω) is affine in every
    damping parameter (C is; the modes stay), so any step is exact up to round-off, ~1e-13 of ξ over
    the step's :data:`DAMPING_STEP` of the parameter's scale: 1e-10 of the derivative. The step goes
    towards the farther bound, or the other way where the model refuses the value (two Rayleigh ratios
    whose α or β would be negative)."""
    G = np.empty((first.size, x.size))
    for k in range(x.size):
        ahead = 1.0 if hi[k] - x[k] >= x[k] - lo[k] else -1.0
        for sign in (ahead, -ahead):
            y = np.array(x, dtype=float)
            y[k] = min(max(x[k] + sign * DAMPING_STEP * scale[k], lo[k]), hi[k])
            try:
                G[:, k] = (ratios.at(y, damped=False)[1] - first) / (y[k] - x[k])
                break
            except ModelError:
                if sign != ahead:
                    raise
    return G


def _damping_solve(ratios: _DampedRatios, x0, lo, hi, targets, max_evaluations: int) -> _DampingSolution:
    """Meet the damping targets with the damping parameters (bounded least squares).

    The residual of a target is (ξ/ξ_target − 1)/damping_tolerance, ξ the damped mode's ratio
    −Re λ/|λ| (what ``flexshaft modes`` reports). To first order in the damping ξ = φᵀCφ/(2ω), which
    is affine in every damping parameter - for Rayleigh damping exactly α/(2ω) + βω/2 - so its
    Jacobian G, taken once (:func:`_damping_jacobian`), makes each step a linear bounded least
    squares problem, solved to the targets' resolution (:data:`SOLVER_FRACTION`) by a dogbox
    trust-region method from the present point (Gauss-Newton steps of least norm: an
    under-determined problem - α and β for one target - moves the parameters least). The damped
    ratio differs from the first-order one by a fraction O(ξ²) of it (nothing for proportional
    damping, whose modes stay real; ~1e-7 on Customer 1 at 0.53 % on its parts), far inside any
    damping tolerance - yet it is what the model reports, so that difference, evaluated at the last
    point, is carried as a constant into the next step (Newton with the first-order Jacobian), until
    the damped ratios agree with the prediction to the resolution: one or two steps more. Parameters
    are scaled by their starting value, or by their bounds' width where they start at 0.
    """
    from scipy.optimize import least_squares

    goal = np.array([t.damping_ratio for t in targets], dtype=float)
    tol = np.array([t.damping_tolerance for t in targets], dtype=float)
    stop = SOLVER_FRACTION * float(tol.min())
    scale = np.where(x0 != 0, np.abs(x0), hi - lo)
    exact, first = ratios.at(x0)
    G = _damping_jacobian(ratios, x0, first, lo, hi, scale)
    base, f_base, x = np.array(x0, dtype=float), first, np.array(x0, dtype=float)
    settled, steps = False, 0
    lower, upper = lo / scale, hi / scale
    while steps < DAMPING_STEPS and not settled:
        steps += 1
        A = G * scale[None, :] / (goal * tol)[:, None]  # ∂residual/∂(x/scale), constant
        delta = exact - first  # the damped ratios beyond first order, carried as a constant

        def residual(u, G=G, base=base, f_base=f_base, delta=delta):
            return ((f_base + G @ (u * scale - base) + delta) / goal - 1) / tol

        def jacobian(u, A=A):
            return A

        # dogbox: its steps leave a bound at once (trust-region reflective crawls off one, and a damper
        # starts at its bound 0), and it ends on the bounds it holds
        options = _solver_options(stop, max_evaluations) | {"method": "dogbox"}
        sol = least_squares(residual, x / scale, jac=jacobian, bounds=(lower, upper), **options)
        x_new = np.where(sol.x <= lower, lo, np.where(sol.x >= upper, hi, sol.x * scale))
        linear = f_base + G @ (x_new - base)
        exact, first = ratios.at(x_new)
        settled = bool(np.max(np.abs(exact - (linear + delta)) / (goal * tol)) <= stop)
        if np.any(np.abs(first - linear) > AFFINE_DAMPING * goal):  # not affine after all: afresh here
            G, base, f_base = _damping_jacobian(ratios, x_new, first, lo, hi, scale), x_new, first
            settled = False
        x = x_new
    r = (exact / goal - 1) / tol
    A = G * scale[None, :] / (goal * tol)[:, None]
    active, widen = _on_bounds(A.T @ r, x, scale, lo, hi)
    how = "step" if steps == 1 else "steps"
    message = (
        f"damping: {steps} {how} of bounded least squares on the first-order ratios, corrected to the "
        "damped modes"
    )
    if not settled:
        message += f" - the damped ratios did not settle in {DAMPING_STEPS} steps (reported as reached)"
    return _DampingSolution(
        x=x, values=exact, jacobian=G, active=active, widen=widen, cost=0.5 * float(r @ r), message=message
    )


def _damping_unmet(d: Drivetrain, names, zs: _DampingSolution, targets) -> list:
    """For each damping target missed: the damping parameters that alone would meet it (the change, %,
    from the first-order Jacobian: exact to O(ξ²) relative), within a factor 100 of the tuned value and
    the values the parameter can take; the three smallest changes."""
    out = []
    for i, t in enumerate(targets):
        error = zs.values[i] / t.damping_ratio - 1
        if abs(error) <= t.damping_tolerance * (1 + 1e-9):
            continue
        need = []
        for k, n in enumerate(names):
            g, v = zs.jacobian[i, k], zs.x[k]
            if g == 0 or v == 0:
                continue
            new = v + (t.damping_ratio - zs.values[i]) / g
            if parameter_domain(d, n).contains(new) and 1e-2 <= new / v <= 1e2:
                need.append({"parameter": n, "change_percent": float(100 * (new / v - 1))})
        need.sort(key=lambda e: abs(e["change_percent"]))
        out.append({"target": t.damping_label, "error": float(error), "alone_would_need": need[:3]})
    return out
