"""What an operational modal identification gives: the modes with their spread, and how they were found.

The result of :func:`flexshaft.measurement.identify.identify_modes`: frozen dataclasses, each with a
``to_dict()`` that is ready for JSON (NaN as null; the units stated: Hz, fraction, s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["Identification", "IdentifiedMode", "RunSummary", "Stabilisation", "MIN_MPC", "with_doubts"]

#: A mode seen on two or more channels is doubtful below this modal phase collinearity. A normal mode
#: of a proportionally damped drivetrain is real: its shape's components share one phase (MPC 1), and
#: sensor noise of a few per cent lowers that by about its square (the example line's true modes:
#: 0.996 to 1.000 at 2 % noise). The spurious poles that a free decay's short, fading record lets the
#: high model orders fit come out at 0.3 to 0.8 (a 30 s coast-down: 0.31, 0.64, 0.76), and so does a
#: weakly excited mode whose shape the record does not hold.
MIN_MPC = 0.9


@dataclass(frozen=True)
class IdentifiedMode:
    """One identified mode with its spread.

    Attributes
    ----------
    frequency_hz : float
        Natural frequency (undamped, ``|λ|/2π``), the mean over the runs in which it was found, Hz.
    damping_ratio : float
        Damping ratio, the mean over those runs (fraction).
    frequency_std_hz, damping_std : float
        Standard deviations across those runs (n − 1 in the denominator); NaN when found in fewer
        than two runs.
    run_frequencies_hz, run_damping_ratios : tuple of float
        Each run's estimate (its whole record), NaN in a run where the mode was not found.
    found_in_runs : int
        In how many runs it was found.
    segment_frequency_std_hz, segment_damping_std : float
        Standard deviations over the estimates of every segment of every run (a run of one segment
        counts with its whole record); NaN with fewer than two.
    frequency_range_hz, damping_range : tuple of (float, float)
        The smallest and largest estimate, over every segment and every run.
    found_in_segments, segments : int
        In how many segments it was found, of how many.
    shape : dict of str to float
        The real mode shape per channel, in each channel's unit, scaled so its largest component is 1
        (the median over runs). Speeds are turned back by the phase of λ (a speed leads its angle by
        about 90°) so that all channels share one phase; their values are then ω times the angle's.
    mpc : float
        Modal phase collinearity of the complex shape (1: a real, normal mode; mean over runs), on
        channels scaled to unit standard deviation.
    stable_poles : int
        The stable poles behind it, over every run's stabilisation diagram.
    fdd_frequency_hz : float
        The cross-check by frequency-domain decomposition: the peak of the first singular value of the
        spectral density matrix near the mode (mean over the runs where it has one), Hz; NaN where it
        has none. The damped frequency, f·√(1 − ζ²): for ζ < 1 % within 5e-5 of ``frequency_hz``,
        plus the two estimators' scatter.
    fdd_mac : float
        The MAC of the first singular vector at that peak with the mode's shape (mean over the runs;
        1 with one channel).
    frequency_doubt, damping_doubt : str
        Why the identification doubts the mode (then it is no calibration target at all) or only its
        damping ratio (no damping target); "" where it does not (:func:`with_doubts`).
    """

    frequency_hz: float
    damping_ratio: float
    frequency_std_hz: float
    damping_std: float
    run_frequencies_hz: tuple
    run_damping_ratios: tuple
    found_in_runs: int
    segment_frequency_std_hz: float
    segment_damping_std: float
    frequency_range_hz: tuple
    damping_range: tuple
    found_in_segments: int
    segments: int
    shape: dict
    mpc: float
    stable_poles: int
    fdd_frequency_hz: float = math.nan
    fdd_mac: float = math.nan
    frequency_doubt: str = ""
    damping_doubt: str = ""

    @property
    def complexity(self) -> float:
        """1 − MPC: 0 for a real, normal mode."""
        return 1.0 - self.mpc

    @property
    def doubtful(self) -> bool:
        """Whether the identification doubts the mode or its damping (see :func:`with_doubts`)."""
        return bool(self.frequency_doubt or self.damping_doubt)

    def to_dict(self) -> dict:
        """A JSON-ready document (NaN as None)."""
        return {
            "frequency_hz": _json(self.frequency_hz),
            "damping_ratio": _json(self.damping_ratio),
            "frequency_std_hz": _json(self.frequency_std_hz),
            "damping_std": _json(self.damping_std),
            "run_frequencies_hz": [_json(v) for v in self.run_frequencies_hz],
            "run_damping_ratios": [_json(v) for v in self.run_damping_ratios],
            "found_in_runs": self.found_in_runs,
            "segment_frequency_std_hz": _json(self.segment_frequency_std_hz),
            "segment_damping_std": _json(self.segment_damping_std),
            "frequency_range_hz": [_json(v) for v in self.frequency_range_hz],
            "damping_range": [_json(v) for v in self.damping_range],
            "found_in_segments": self.found_in_segments,
            "segments": self.segments,
            "shape": {k: float(v) for k, v in self.shape.items()},
            "mpc": _json(self.mpc),
            "complexity": _json(self.complexity),
            "stable_poles": self.stable_poles,
            "fdd_frequency_hz": _json(self.fdd_frequency_hz),
            "fdd_mac": _json(self.fdd_mac),
            "frequency_doubt": self.frequency_doubt or None,
            "damping_doubt": self.damping_doubt or None,
        }


@dataclass(frozen=True)
class Stabilisation:
    """One run's stabilisation diagram: every pole of every model order up to ``max_hz``.

    Attributes
    ----------
    run : int
        The run's index.
    order : ndarray of int, shape (m,)
        Each pole's model order.
    frequency_hz : ndarray, shape (m,)
        Hz.
    damping_ratio : ndarray, shape (m,)
        Fraction (negative: an unstable pole).
    stable : ndarray of bool
        Stable against the previous order (:mod:`flexshaft.measurement.ssi`'s criteria).
    physical : ndarray of bool
        0 < ζ <= 20 % and min_hz < f < max_hz.
    mode : ndarray of int
        The index of the mode in :attr:`Identification.modes` the pole counts for, or −1.
    """

    run: int
    order: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    stable: np.ndarray
    physical: np.ndarray
    mode: np.ndarray

    def to_dict(self) -> dict:
        """A JSON-ready document."""
        return {
            "run": self.run,
            "order": self.order.tolist(),
            "frequency_hz": self.frequency_hz.tolist(),
            "damping_ratio": self.damping_ratio.tolist(),
            "stable": self.stable.tolist(),
            "physical": self.physical.tolist(),
            "mode": self.mode.tolist(),
        }


@dataclass(frozen=True)
class RunSummary:
    """How one run was used.

    Attributes
    ----------
    index : int
        Its place in the runs given.
    source : str
        Where it came from ("" when not said).
    duration_s : float
        The record's length, s.
    rate_hz, decimated_rate_hz : float
        The sampling rate given and the one identified at, Hz.
    decimation : int
        The decimation factor.
    block_rows : int
        i, the Toeplitz matrix's block rows (lags 1..2i − 1 at the decimated rate).
    segments : int
        Into how many segments it was cut.
    segment_s : float
        Each segment's length, s.
    scales : dict of str to float
        Each channel's standard deviation after preprocessing, in its unit: what it was divided by.
    """

    index: int
    source: str
    duration_s: float
    rate_hz: float
    decimated_rate_hz: float
    decimation: int
    block_rows: int
    segments: int
    segment_s: float
    scales: dict

    def to_dict(self) -> dict:
        """A JSON-ready document."""
        return {
            "index": self.index,
            "source": self.source,
            "duration_s": self.duration_s,
            "rate_hz": self.rate_hz,
            "decimated_rate_hz": self.decimated_rate_hz,
            "decimation": self.decimation,
            "block_rows": self.block_rows,
            "segments": self.segments,
            "segment_s": self.segment_s,
            "scales": dict(self.scales),
        }


@dataclass(frozen=True)
class Identification:
    """The modes identified from one or more runs.

    Attributes
    ----------
    modes : tuple of IdentifiedMode
        Sorted by frequency.
    channels : tuple of str
        The channels used, in order.
    units : dict of str to str
        Each channel's unit.
    references : tuple of str
        The reference channels of the correlations.
    min_hz, max_hz : float
        The band searched, Hz.
    band_reason : str
        Where ``min_hz`` comes from (``"given"``, or the default's reason:
        :func:`~flexshaft.measurement.identify.default_min_hz`).
    orders : tuple of int
        The model orders of the stabilisation diagram.
    method : str
        How the modes were found, in words.
    runs : tuple of RunSummary
        Each run as used.
    diagrams : tuple of Stabilisation
        Each run's stabilisation diagram (its whole record).
    notes : tuple of str
        What a reader should know (modes found in few runs, runs too short to segment).
    """

    modes: tuple
    channels: tuple
    units: dict
    references: tuple
    min_hz: float
    max_hz: float
    band_reason: str
    orders: tuple
    method: str
    runs: tuple
    diagrams: tuple
    notes: tuple = field(default=())

    @property
    def frequencies_hz(self) -> np.ndarray:
        """The modes' frequencies, Hz."""
        return np.array([m.frequency_hz for m in self.modes])

    @property
    def damping_ratios(self) -> np.ndarray:
        """The modes' damping ratios (fractions)."""
        return np.array([m.damping_ratio for m in self.modes])

    @property
    def band(self) -> str:
        """The band searched and why, in one line: ``band 5.8 … 800 Hz (from the model's first mode,
        11.6 Hz)``."""
        return f"band {self.min_hz:.3g} … {self.max_hz:.4g} Hz ({self.band_reason})"

    def to_dict(self, diagrams: bool = True) -> dict:
        """A JSON-ready document with its units; ``diagrams=False`` leaves the stabilisation diagrams out."""
        doc = {
            "units": {
                "frequency": "Hz",
                "damping_ratio": "fraction",
                "duration": "s",
                "shape": "each channel's unit, largest component 1",
            },
            "method": self.method,
            "channels": list(self.channels),
            "channel_units": dict(self.units),
            "references": list(self.references),
            "min_hz": self.min_hz,
            "max_hz": self.max_hz,
            "band_reason": self.band_reason,
            "orders": list(self.orders),
            "modes": [m.to_dict() for m in self.modes],
            "runs": [r.to_dict() for r in self.runs],
            "notes": list(self.notes),
        }
        if diagrams:
            doc["stabilisation"] = [d.to_dict() for d in self.diagrams]
        return doc


def _json(value) -> float | None:
    value = float(value)
    return None if math.isnan(value) else value


def _spread(std: float, segment_std: float) -> tuple[float, str]:
    """The damping's spread and over what: across runs, else across segments (NaN: one estimate)."""
    return (std, "runs") if math.isfinite(std) else (segment_std, "segments")


def with_doubts(mode: IdentifiedMode, channels: int, unconfirmed: str = "") -> IdentifiedMode:
    """``mode`` with the identification's doubts on it, from ``channels`` channels.

    The mode is doubtful (no target at all) where ``unconfirmed`` says why its segments neither
    confirm nor refute it, or where seen on two or more channels with an MPC below :data:`MIN_MPC`:
    its shape is not a normal mode's. Its damping ratio is doubtful (no damping target)
    where the mode is, where it is not positive (a passive drivetrain's modes decay), or where its
    spread (one standard deviation across runs, else across segments) exceeds the ratio itself: the
    estimates then do not agree even on its size. A frequency is far better determined than a damping
    ratio (its random error is about √ζ of it), so a damping doubt alone leaves the frequency target.
    """
    frequency = unconfirmed
    if not frequency and channels >= 2 and not mode.mpc >= MIN_MPC:
        frequency = f"MPC {mode.mpc:.2f} < {MIN_MPC:g}: not a normal mode's shape"
    damping = frequency
    spread, over = _spread(mode.damping_std, mode.segment_damping_std)
    if not damping and not mode.damping_ratio > 0:
        damping = f"damping ratio {100 * mode.damping_ratio:.3g} % is not positive"
    elif not damping and spread > mode.damping_ratio:
        damping = (
            f"damping spread ±{100 * spread:.3g} % across {over} exceeds the ratio "
            f"{100 * mode.damping_ratio:.3g} %"
        )
    return replace(mode, frequency_doubt=frequency, damping_doubt=damping)
