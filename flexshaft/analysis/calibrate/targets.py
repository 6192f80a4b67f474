"""What a calibration aims at and what it may move: :class:`Target` (a mode's frequency, frequency
ratio and/or damping ratio, each with its tolerance) and :class:`Bound` (a parameter's bounds, ± %, or a
fixed value), with the ranges they are checked against when made.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from ...errors import ModelError
from ...validation import check_real

__all__ = [
    "Target",
    "Bound",
    "DEFAULT_TOLERANCE",
    "DAMPING_TOLERANCE",
    "DAMPING_RANGE",
    "TARGET_RANGE",
    "MIN_TOLERANCE",
    "MIN_PERCENT",
]

#: Targets, tolerances and ± % bounds within ranges double precision resolves: a residual is a
#: relative miss over a tolerance, so a target of 1e-300 Hz or a tolerance of 1e-300 overflows it,
#: and a ± 1e-300 % bound has no width left.
TARGET_RANGE = (1e-6, 1e9)  # Hz, and for a ratio (dimensionless)
MIN_TOLERANCE = 1e-9
MIN_PERCENT = 1e-6
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


def _mode_number(value, field: str) -> int:
    """A mode number as a whole number (its range is the model's: :func:`check_targets`)."""
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
