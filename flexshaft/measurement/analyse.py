"""One signal analysed as ``flexshaft spectrum`` and the study analyse it: spectrum, peaks, damping.

A stationary record gets an amplitude spectrum (Hann by default, Welch-averaged on request) and its
peaks with their half-power damping. A free decay (``decay=True``) is one transient: the whole
record, no averaging, and each peak's damping from a window fit in frequency
(:func:`~flexshaft.measurement.decay.decay_damping`) and from the logarithmic decrement in time
(:func:`~flexshaft.measurement.decay.log_decrement`), each in a band around the peak reaching half-way to its
neighbours. Peaks get their order where a shaft speed is given and the nearest eigenfrequency of
a model where those are given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..system.threads import follows_policy
from .checks import as_signal, rate_from_times
from .decay import decay_damping, log_decrement
from .spectrum import Spectrum, spectrum

__all__ = ["SignalAnalysis", "analyse_signal", "DEFAULT_PEAKS", "DECAY_WINDOWS"]

#: Peaks listed by default.
DEFAULT_PEAKS = 8
#: The windows that leave a free decay's damping alone (Hann about halves it).
DECAY_WINDOWS = ("rect", "exponential")


@dataclass(frozen=True)
class SignalAnalysis:
    """A signal's spectrum and peaks.

    Attributes
    ----------
    name, unit : str
        The signal and its (SI) unit.
    source : str or None
        Where it came from (a file), for the record.
    time : ndarray
        Sample times, s.
    x : ndarray
        The samples, in ``unit``.
    rate_hz : float
        Sampling rate, Hz.
    spectrum : Spectrum
        Its amplitude spectrum (single-sided peak amplitudes).
    method : str
        How it was analysed, in words.
    window : str
        The window of the analysis (a decay's damping window).
    decay : bool
        Whether it was analysed as a free decay.
    segment : float or None
        The Welch segment asked for, s (None: the whole record).
    peaks : tuple of dict
        Per peak: ``frequency_hz``, ``amplitude``, ``damping_ratio`` (fraction, None where it cannot
        be read), ``damping_missing`` (why), ``notes``; a decay adds ``window`` and
        ``log_decrement_damping_ratio``; with a speed ``order``; with eigenfrequencies ``mode`` and
        ``mode_frequency_hz`` where one is within two bins (or 1 %).
    speed_rpm : ndarray or None
        The shaft speed at each sample, rpm.
    eigenfrequencies : tuple of (int, float)
        A model's modes (index, Hz) the peaks were matched to.
    """

    name: str
    unit: str
    source: str | None
    time: np.ndarray
    x: np.ndarray
    rate_hz: float
    spectrum: Spectrum
    method: str
    window: str
    decay: bool
    segment: float | None
    peaks: tuple
    speed_rpm: np.ndarray | None = None
    eigenfrequencies: tuple = ()

    @property
    def samples(self) -> int:
        """How many samples the record has."""
        return int(self.time.size)

    @property
    def mean_speed_rpm(self) -> float | None:
        """The record's mean shaft speed, rpm (None without a speed)."""
        return None if self.speed_rpm is None else float(np.mean(self.speed_rpm))

    def to_dict(self) -> dict:
        """The ``flexshaft spectrum --json`` document."""
        spec, unit = self.spectrum, self.unit
        doc = {
            "signal": self.name,
            "unit": unit,
            "source": self.source,
            "rate_hz": self.rate_hz,
            "samples": self.samples,
            "method": self.method,
            "window": self.window,
            "segment_s": spec.segment_s,
            "averages": spec.averages,
            "resolution_hz": spec.resolution_hz,
            "units": {
                "frequency": "Hz",
                "amplitude": f"{unit} (single-sided peak)",
                "damping_ratio": "fraction",
            },
            "peaks": [dict(p, notes=list(p["notes"])) for p in self.peaks],
        }
        if self.speed_rpm is not None:
            doc["mean_speed_rpm"] = self.mean_speed_rpm
        return doc

    def table(self) -> str:
        """The ``flexshaft spectrum`` table: the peaks' frequency (Hz), amplitude, damping (%),
        log-decrement damping, order and mode, then the notes."""
        decay, by_speed, eigen = self.decay, self.speed_rpm is not None, bool(self.eigenfrequencies)
        spec = self.spectrum
        rows = [
            f"{self.name} [{self.unit}]: {self.samples} samples at {self.rate_hz:g} Hz; "
            f"{self.method}; resolution {spec.resolution_hz:.4g} Hz",
            "",
            f"{'frequency Hz':>12}  {'amplitude':>11}  {'damping %':>9}"
            + ("  log dec. %" if decay else "")
            + ("  order" if by_speed else "")
            + ("  mode" if eigen else ""),
        ]
        notes = []
        for e in self.peaks:
            z = e["damping_ratio"]
            damping = "-" if z is None else f"{100 * z:9.4f}"
            row = f"{e['frequency_hz']:12.4f}  {e['amplitude']:11.4g}  {damping:>9}"
            if decay:
                ld = e.get("log_decrement_damping_ratio")
                row += f"  {'-' if ld is None else f'{100 * ld:10.4f}':>10}"
            if by_speed:
                row += f"  {e['order']:5.2f}" if e.get("order") is not None else "      -"
            if eigen:
                row += f"  {e['mode']:4d}" if "mode" in e else "     -"
            rows.append(row)
            missing = e.get("damping_missing")
            if missing:  # the reason once, as why the damping column holds '-'
                notes.append(f"  {e['frequency_hz']:.4g} Hz: damping missing: {missing}")
            notes += [
                f"  {e['frequency_hz']:.4g} Hz: {n}" for n in e["notes"] if not (missing and n in missing)
            ]
        if notes:
            rows += ["", "notes:"] + notes
        return "\n".join(rows)


def _check_options(decay: bool, window: str | None, segment) -> str:
    """The window of the analysis, the options' combination checked."""
    if decay:
        window = window or "exponential"
        if window not in DECAY_WINDOWS:
            raise ModelError(
                "a free decay needs a window that leaves its damping alone (Hann about halves it)",
                field="window",
                value=window,
                valid="rect or exponential with decay",
            )
        if segment is not None:
            raise ModelError(
                "a free decay is one transient: it is not averaged", field="segment", valid="None with decay"
            )
        return window
    window = window or "hann"
    if window == "exponential":
        raise ModelError("the exponential window is for a free decay", field="window", valid="decay=True")
    return window


def _decay_entry(entry: dict, p, found, k: int, time, x, rate: float, window: str) -> None:
    """A free decay's damping of peak ``p`` (``found[k]``), put into its ``entry``."""
    # a band around the peak, reaching half-way to its neighbours, isolates its mode
    others = sorted(q.frequency_hz for j, q in enumerate(found) if j != k)
    lo = max([0.5 * p.frequency_hz] + [(p.frequency_hz + f) / 2 for f in others if f < p.frequency_hz])
    hi = min(
        [1.5 * p.frequency_hz, 0.49 * rate] + [(p.frequency_hz + f) / 2 for f in others if f > p.frequency_hz]
    )
    try:
        dd = decay_damping(time, x, band=(lo, hi), window=window)
        entry |= {
            "frequency_hz": dd.frequency_hz,
            "damping_ratio": None if not np.isfinite(dd.damping_ratio) else dd.damping_ratio,
            "damping_missing": dd.damping_missing,
            "window": dd.window,
            "notes": list(dd.notes),
        }
    except ModelError as err:  # one peak that cannot be analysed does not cost the others
        entry |= {
            "damping_ratio": None,
            "damping_missing": f"half-power: {err}",
            "window": window,
            "notes": [],
        }
    try:
        ld = log_decrement(time, x, band=(lo, hi))
        entry["log_decrement_damping_ratio"] = ld.damping_ratio
        entry["notes"] += list(ld.notes)
    except ModelError as err:
        entry["notes"].append(f"log decrement: {err}")


def _check_speed(speed_rpm, n: int) -> np.ndarray:
    speed = np.asarray(speed_rpm, dtype=float) if speed_rpm is not None else None
    if speed is None or speed.shape != (n,) or not np.all(np.isfinite(speed)):
        raise ModelError(
            "is not a finite speed per sample",
            field="speed_rpm",
            valid=f"{n} finite speeds in rpm",
            has_value=False,
        )
    return speed


def _eigen(eigenfrequencies) -> tuple:
    try:
        return tuple((int(i), float(f)) for i, f in eigenfrequencies)
    except (TypeError, ValueError):
        raise ModelError(
            "is not a list of (mode, frequency) pairs",
            field="eigenfrequencies",
            valid="pairs (mode index, Hz)",
            has_value=False,
        ) from None


@follows_policy
def analyse_signal(
    time,
    x,
    *,
    name: str,
    unit: str,
    source: str | None = None,
    decay: bool = False,
    window: str | None = None,
    segment: float | None = None,
    peaks: int | None = None,
    speed_rpm=None,
    eigenfrequencies=None,
    rate_hz: float | None = None,
) -> SignalAnalysis:
    """The spectrum, peaks and damping of one signal.

    Parameters
    ----------
    time : array_like, shape (n,)
        Sample times, s: increasing and uniformly spaced.
    x : array_like, shape (n,)
        The samples, in ``unit``.
    name, unit : str
        The signal's name and unit (for the document and the plots).
    source : str, optional
        Where the record came from (a file), for the record.
    decay : bool
        The record is a free decay: the whole record, no averaging; damping by a window fit and by
        the logarithmic decrement.
    window : str, optional
        ``"hann"`` (the default of a stationary record), ``"rect"``, ``"flattop"``; with a decay
        ``"rect"`` or ``"exponential"`` (its default).
    segment : float, optional
        Welch averaging over segments this long, s, 50 % overlap (not with a decay).
    peaks : int, optional
        How many peaks to list (default :data:`DEFAULT_PEAKS`).
    speed_rpm : array_like, shape (n,), optional
        The shaft speed at each sample, rpm: each peak gets its order (frequency over the mean speed).
    eigenfrequencies : sequence of (int, float), optional
        A model's modes as (index, Hz): a peak within two bins (or 1 %) of the nearest is that mode.
    rate_hz : float, optional
        The sampling rate, Hz, where the caller has it (else from ``time``).

    Returns
    -------
    SignalAnalysis

    Raises
    ------
    ModelError
        Naming the argument (``window``, ``segment``, ``x``, ...) as it is named here.
    """
    window = _check_options(decay, window, segment)
    x = as_signal(x, "x", unit)  # within ±MAX_SIGNAL: the spectrum's sums stay numbers
    if rate_hz is None:
        time, rate_hz = rate_from_times(time, x.size)
    time = np.asarray(time, dtype=float)
    speed = None if speed_rpm is None else _check_speed(speed_rpm, x.size)
    eigen = () if eigenfrequencies is None else _eigen(eigenfrequencies)
    rate = rate_hz
    if decay:
        spec = spectrum(x, rate, window="rect")
        method = f"free decay: {window} window on the whole record (no averaging), and log decrement"
    else:
        spec = spectrum(x, rate, window=window, segment=segment)
        method = f"stationary: {window} window" + (
            f", Welch averaging of {spec.averages} segments of {spec.segment_s:g} s"
            if spec.averages > 1
            else ""
        )
    found = spec.peaks(count=DEFAULT_PEAKS if peaks is None else peaks)
    entries = []
    for k, p in enumerate(found):
        # a peak keeps its frequency and amplitude (always numbers); a damping that cannot be read is
        # None, and damping_missing says why
        entry = {
            "frequency_hz": p.frequency_hz,
            "amplitude": p.amplitude,
            "damping_ratio": None if not np.isfinite(p.damping_ratio) else p.damping_ratio,
            "damping_missing": p.damping_missing,
            "notes": list(p.notes),
        }
        if decay:
            _decay_entry(entry, p, found, k, time, x, rate, window)
        if speed is not None:
            n = float(np.mean(speed))
            entry["order"] = entry["frequency_hz"] / (n / 60.0) if n > 0 else None
        if eigen:
            i, f = min(eigen, key=lambda e: abs(e[1] - entry["frequency_hz"]))
            # a match within two bins (or 1 % for a coarse spectrum): the peak is that mode
            if abs(f - entry["frequency_hz"]) <= max(2 * spec.resolution_hz, 0.01 * f):
                entry["mode"], entry["mode_frequency_hz"] = i, f
        entries.append(entry)
    return SignalAnalysis(
        name, unit, source, time, x, rate, spec, method, window, decay, segment, tuple(entries), speed, eigen
    )
