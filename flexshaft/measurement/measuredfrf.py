"""Measured frequency responses (a test lab's FRFs, universal-file dataset 58) and their peaks.

A modal test (an impact hammer or a shaker on the stopped drivetrain) gives frequency response
functions, which Simcenter Testlab, ME'scope and pyuff write as dataset 58, function type 4.
:func:`read_measured_frfs` reads them (as every measured file is read: in an isolated child, claims
checked, units checked and converted to SI); :func:`analyse_frf` finds each one's peaks with their
half-power damping (:func:`~flexshaft.measurement.peaks.response_peaks`: the 1-DOF fit a spectrum's
peaks get) and, given a model's modes, the mode nearest each peak - what ``flexshaft spectrum FILE.uff
--column NAME`` prints for an FRF record.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from .signaltable import UNITS, VALID_UNITS

__all__ = ["MeasuredFrf", "FrfAnalysis", "read_measured_frfs", "measured_frf", "analyse_frf"]


@dataclass(frozen=True)
class MeasuredFrf:
    """One measured frequency response, in SI.

    Attributes
    ----------
    name : str
        The record's name (its first ID line, else ``RESPONSE_NODE:DIR/REFERENCE_NODE:DIR``).
    frequencies_hz : ndarray, shape (f,)
        Ascending, Hz.
    H : ndarray of complex, shape (f,)
        The response per unit reference, in ``unit``.
    unit : str
        ``"RESPONSE/REFERENCE"`` in SI, e.g. ``"rad/s/N·m"`` (from the file's axis labels).
    source : str
        The file.
    """

    name: str
    frequencies_hz: np.ndarray
    H: np.ndarray
    unit: str
    source: str


def _si(path, name: str, label: str, which: str) -> tuple[str, float]:
    if label not in UNITS:
        raise ModelError(
            "states no unit flexshaft reads" if label else "states no unit",
            file=str(path),
            field=f"{name} ({which} axis label)",
            value=label or None,
            valid=VALID_UNITS,
        )
    return UNITS[label]


def read_measured_frfs(path) -> tuple[MeasuredFrf, ...]:
    """Every frequency response (dataset 58, function type 4) of a universal file, in SI.

    Parameters
    ----------
    path : str or Path
        A ``.uff`` or ``.unv`` file (pyuff reads it: the ``uff`` extra).

    Returns
    -------
    tuple of MeasuredFrf
        In the file's order.

    Raises
    ------
    ModelError
        A damaged or hostile file, a record whose abscissa is no frequency in Hz, a response or
        reference unit flexshaft does not read (their labels: rad, rad/s, rpm, N·m, kN·m, ...), a file
        with no frequency response.
    """
    from .files import read_frf_records

    records = read_frf_records(path)
    if not records:
        raise ModelError(
            "holds no frequency response", file=str(path), valid="dataset 58 records of function type 4 (FRF)"
        )
    return tuple(measured_frf(rec, path) for rec in records)


def measured_frf(record: dict, path) -> MeasuredFrf:
    """One record of :func:`~flexshaft.measurement.files.read_frf_records` in SI: its response and
    reference units read from their axis labels (an unknown or missing one refused)."""
    name = record["name"]
    num, f_num = _si(path, name, record["response_unit"], "response")
    den, f_den = _si(path, name, record["reference_unit"], "reference")
    return MeasuredFrf(
        name=name,
        frequencies_hz=record["frequencies_hz"],
        H=record["H"] * (f_num / f_den),
        unit=f"{num}/{den}",
        source=str(path),
    )


@dataclass(frozen=True)
class FrfAnalysis:
    """A measured FRF's peaks.

    Attributes
    ----------
    frf : MeasuredFrf
    peaks : tuple of dict
        Largest first: ``frequency_hz``, ``amplitude`` (``|H|`` in the FRF's unit), ``damping_ratio``
        (half-power, a fraction; None where it cannot be read), ``damping_missing`` (why), ``notes``;
        with a model's modes ``mode`` and ``mode_frequency_hz`` (the nearest, within 5 %).
    eigenfrequencies : tuple of (int, float)
        The model's modes (number, Hz) the peaks were matched to.
    """

    frf: MeasuredFrf
    peaks: tuple
    eigenfrequencies: tuple = ()

    def to_dict(self) -> dict:
        """The ``flexshaft spectrum --json`` document of an FRF record."""
        f = self.frf.frequencies_hz
        return {
            "signal": self.frf.name,
            "kind": "frequency response",
            "unit": self.frf.unit,
            "source": self.frf.source,
            "points": int(f.size),
            "frequency_range_hz": [float(f[0]), float(f[-1])],
            "units": {"frequency": "Hz", "amplitude": f"{self.frf.unit} (|H|)", "damping_ratio": "fraction"},
            "peaks": [dict(p, notes=list(p["notes"])) for p in self.peaks],
        }

    def table(self) -> str:
        """The peaks: frequency (Hz), ``|H|``, half-power damping (%), nearest mode; then the notes."""
        f, eigen = self.frf.frequencies_hz, bool(self.eigenfrequencies)
        rows = [
            f"{self.frf.name} [{self.frf.unit}]: measured frequency response, {f.size} points from "
            f"{f[0]:g} to {f[-1]:g} Hz; peaks of |H| with their half-power damping",
            "",
            f"{'frequency Hz':>12}  {'|H|':>11}  {'damping %':>9}" + ("  mode" if eigen else ""),
        ]
        notes = []
        for p in self.peaks:
            z = p["damping_ratio"]
            damping = "-" if z is None else f"{100 * z:9.4f}"
            row = f"{p['frequency_hz']:12.4f}  {p['amplitude']:11.4g}  {damping:>9}"
            if eigen:
                row += f"  {p['mode']:4d}" if "mode" in p else "     -"
            rows.append(row)
            if p.get("damping_missing"):
                notes.append(f"  {p['frequency_hz']:.4g} Hz: damping missing: {p['damping_missing']}")
        if notes:
            rows += ["", "notes:"] + notes
        return "\n".join(rows)


#: A peak is a model mode's when their frequencies are within this fraction of each other.
MODE_MATCH = 0.05


def analyse_frf(frf: MeasuredFrf, *, count: int = 8, eigenfrequencies=None) -> FrfAnalysis:
    """The peaks of ``|H|`` with their half-power damping, largest first, and the nearest mode of
    ``eigenfrequencies`` (pairs of mode number and Hz) to each."""
    from .peaks import response_peaks

    try:
        found = response_peaks(frf.frequencies_hz, np.abs(frf.H), count)
    except ModelError as err:
        if err.field != "frequencies_hz":
            raise
        # the half-power fit needs evenly spaced lines (a lab's FFT): said of the record
        raise ModelError(
            "has unevenly spaced frequencies", file=frf.source, field=frf.name, valid=err.valid
        ) from None
    eigen = tuple(eigenfrequencies or ())
    peaks = []
    for p in found:
        z = None if np.isnan(p.damping_ratio) else float(p.damping_ratio)
        entry = {
            "frequency_hz": float(p.frequency_hz),
            "amplitude": float(p.amplitude),
            "damping_ratio": z,
            "damping_missing": p.damping_missing,
            "notes": tuple(p.notes),
        }
        if eigen:
            k, fk = min(eigen, key=lambda m: abs(m[1] - p.frequency_hz))
            if abs(fk - p.frequency_hz) <= MODE_MATCH * fk:
                entry |= {"mode": int(k), "mode_frequency_hz": float(fk)}
        peaks.append(entry)
    return FrfAnalysis(frf=frf, peaks=tuple(peaks), eigenfrequencies=eigen)
