"""Identified modes paired with a model's: numbered as ``flexshaft modes`` numbers them, written as
the targets ``flexshaft calibrate`` reads.

An identified mode (:class:`~flexshaft.measurement.identified.IdentifiedMode`) is paired with the
model's elastic mode nearest in frequency, within :data:`PAIR_WINDOW` of it; where channels are
mapped to the model's stations (``stations={"speed 1": "motor", ...}``: speeds and angles measure
the stations' rotation, θx) the pairing also needs the MAC of the measured shape with the model's
at those stations to be at least :data:`MIN_MAC`, and among the candidates in the window the best
MAC wins. Two identified modes never take one model mode (the nearer keeps it; the other is left
unpaired, with the reason).

The targets: ``frequency_hz`` the identified mean, ``tolerance`` three times its relative scatter
(across runs, or across segments with one run) and never below :data:`MIN_TOLERANCE`;
``damping_ratio`` the identified mean, ``damping_tolerance`` twice its relative scatter, at least
:data:`MIN_DAMPING_TOLERANCE`; ``shape`` where every station is measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..linalg.mac import mac as shape_mac
from ..system.threads import follows_policy

__all__ = ["PairedMode", "Pairing", "pair_modes", "targets_toml", "PAIR_WINDOW", "MIN_MAC"]

#: An identified mode pairs with a model mode within this relative distance in frequency (a model
#: before calibration may be this far off; further, it is another mode, or none of the model's).
PAIR_WINDOW = 0.25
#: The least MAC of a pairing where channels map to stations.
MIN_MAC = 0.8
#: A frequency target's tolerance is at least this (relative): below it the identification's own
#: bias (the correlations' normalisation, ~1e-4 of f) and the model's mesh are of the same order.
MIN_TOLERANCE = 1e-3
#: A damping target's tolerance is at least this (relative): measured damping scatters by ~20 %
#: run to run.
MIN_DAMPING_TOLERANCE = 0.1


@dataclass(frozen=True)
class PairedMode:
    """An identified mode and the model mode it pairs with.

    Attributes
    ----------
    identified : IdentifiedMode
    mode : int or None
        The model mode, numbered as ``flexshaft modes`` numbers them; None when unpaired.
    model_frequency_hz : float
        That mode's frequency, Hz (NaN unpaired).
    mac : float
        MAC of the measured shape with the model's at the mapped stations (NaN without stations).
    reason : str or None
        Why it is unpaired.
    tolerance, damping_tolerance : float
        The targets' relative tolerances (see the module docstring).
    """

    identified: object
    mode: int | None
    model_frequency_hz: float
    mac: float
    reason: str | None
    tolerance: float
    damping_tolerance: float

    @property
    def frequency_target(self) -> bool:
        """Whether it makes a target: paired, and the identification does not doubt the mode."""
        return self.mode is not None and not getattr(self.identified, "frequency_doubt", "")

    @property
    def damping_target(self) -> bool:
        """Whether its target carries the damping ratio: a target whose damping is not doubted."""
        return self.frequency_target and not getattr(self.identified, "damping_doubt", "")

    def to_dict(self) -> dict:
        return {
            "mode": self.mode,
            "frequency_hz": self.identified.frequency_hz,
            "model_frequency_hz": None if math.isnan(self.model_frequency_hz) else self.model_frequency_hz,
            "mac": None if math.isnan(self.mac) else self.mac,
            "damping_ratio": self.identified.damping_ratio,
            "tolerance": self.tolerance,
            "damping_tolerance": self.damping_tolerance,
            "unpaired": self.reason,
            "frequency_target": self.frequency_target,
            "damping_target": self.damping_target,
        }


@dataclass(frozen=True)
class Pairing:
    """Identified modes paired with a model's (:func:`pair_modes`).

    Attributes
    ----------
    pairs : tuple of PairedMode
        In the identified modes' order (ascending frequency).
    stations : dict of str to str
        Channel -> station, as given.
    shape_stations : tuple of str
        The model's stations in order, when every one is measured (the targets get a ``shape``).
    """

    pairs: tuple
    stations: dict
    shape_stations: tuple

    def to_dict(self) -> dict:
        return {"stations": dict(self.stations), "pairs": [p.to_dict() for p in self.pairs]}


def _relative(std: float, value: float) -> float:
    return abs(std / value) if math.isfinite(std) and value else math.nan


def _tolerances(m) -> tuple[float, float]:
    f_rel = _relative(m.frequency_std_hz, m.frequency_hz)
    if not math.isfinite(f_rel):
        f_rel = _relative(m.segment_frequency_std_hz, m.frequency_hz)
    z_rel = _relative(m.damping_std, m.damping_ratio)
    if not math.isfinite(z_rel):
        z_rel = _relative(m.segment_damping_std, m.damping_ratio)
    tol = max(MIN_TOLERANCE, 3.0 * f_rel) if math.isfinite(f_rel) else 10 * MIN_TOLERANCE
    dtol = max(MIN_DAMPING_TOLERANCE, 2.0 * z_rel) if math.isfinite(z_rel) else 3 * MIN_DAMPING_TOLERANCE
    return tol, min(dtol, 0.9)


@follows_policy
def pair_modes(identification, result, stations: dict | None = None) -> Pairing:
    """Pair each identified mode with the model mode it measures.

    Parameters
    ----------
    identification : Identification
        From :func:`flexshaft.measurement.identify.identify_modes`.
    result : flexshaft.analysis.modal.ModalResult
        The model's modes (:func:`flexshaft.modal_analysis`).
    stations : dict of str to str, optional
        Channel -> model station for channels that measure a station's rotation (speed or angle).

    Returns
    -------
    Pairing
    """
    stations = dict(stations or {})
    names = [s.name for s in result.model.stations]
    for channel, station in stations.items():
        if channel not in identification.channels:
            raise ModelError(
                "is not an identified channel",
                field="stations",
                value=channel,
                valid="one of " + ", ".join(identification.channels),
            )
        if station not in names:
            raise ModelError(
                "is not a station of the model",
                field=channel,
                value=station,
                valid="one of " + ", ".join(names),
            )
        if identification.units.get(channel) not in ("rad/s", "rad"):
            raise ModelError(
                "does not measure a rotation",
                field=channel,
                value=identification.units.get(channel),
                valid="a speed (rad/s, rpm) or angle channel mapped to a station",
            )
    freqs = result.frequencies_hz
    elastic = [i for i in range(freqs.size) if not result.rigid[i]]
    shapes = result.station_shapes() if stations else None
    rows = [names.index(stations[c]) for c in stations]
    taken: dict[int, int] = {}
    chosen: list = []
    for j, m in enumerate(identification.modes):
        near = [i for i in elastic if abs(freqs[i] / m.frequency_hz - 1) <= PAIR_WINDOW]
        best, mac, reason = None, math.nan, None
        if not near:
            reason = f"no model mode within {PAIR_WINDOW:.0%} of {m.frequency_hz:.4g} Hz"
        elif stations:
            measured = np.array([m.shape[c] for c in stations], dtype=float)
            macs = {i: shape_mac(measured, shapes[rows, i]) for i in near}
            i = max(macs, key=macs.get)
            if macs[i] >= MIN_MAC:
                best, mac = i, macs[i]
            else:
                reason = f"no model mode near it has a MAC >= {MIN_MAC} (best {macs[i]:.2f}, mode {i})"
        else:
            best = min(near, key=lambda i: abs(freqs[i] / m.frequency_hz - 1))
        if best is not None and best in taken:
            k = taken[best]
            other = identification.modes[k]
            if abs(freqs[best] / m.frequency_hz - 1) < abs(freqs[best] / other.frequency_hz - 1):
                chosen[k] = (
                    None,
                    math.nan,
                    f"model mode {best} is nearer the mode at {m.frequency_hz:.4g} Hz",
                )
            else:
                best, reason = None, f"model mode {best} pairs with {other.frequency_hz:.4g} Hz, nearer it"
        if best is not None:
            taken[best] = j
        chosen.append((best, mac, reason))
    pairs = []
    for m, (best, mac, reason) in zip(identification.modes, chosen):
        tol, dtol = _tolerances(m)
        f = float(freqs[best]) if best is not None else math.nan
        pairs.append(PairedMode(m, best, f, mac, reason, tol, dtol))
    full = tuple(names) if stations and set(stations.values()) == set(names) else ()
    return Pairing(tuple(pairs), stations, full)


def targets_toml(pairing: Pairing, identification) -> str:
    """The targets file ``flexshaft calibrate --targets`` reads, from the paired modes (the user adds
    the ``[[parameter]]`` tables)."""
    lines = [
        "# Targets identified from measured runs by flexshaft identify.",
        f"# Method: {identification.method}",
        "# Frequencies in Hz; damping ratios and tolerances are fractions (0.0053 is 0.53 %).",
        "# Add [[parameter]] tables (what calibrate may change), then:",
        "#   flexshaft calibrate MODEL --targets THIS_FILE",
        "",
    ]
    for p in pairing.pairs:
        m = p.identified
        if p.mode is None:
            lines.append(f"# unpaired: {m.frequency_hz:.6g} Hz, damping {m.damping_ratio:.4g}: {p.reason}")
            lines.append("")
            continue
        if not p.frequency_target:  # the identification doubts the mode: never calibrated to
            lines.append(f"# no target: {m.frequency_hz:.6g} Hz (model mode {p.mode}): {m.frequency_doubt}")
            lines.append("")
            continue
        lines += [
            "[[target]]",
            f"mode = {p.mode}",
            f"frequency_hz = {m.frequency_hz!r}",
            f"tolerance = {p.tolerance:.3g}",
        ]
        if p.damping_target:
            lines += [
                f"damping_ratio = {m.damping_ratio!r}",
                f"damping_tolerance = {p.damping_tolerance:.3g}",
            ]
        else:
            lines.append(f"# no damping target (measured {m.damping_ratio:.4g}): {m.damping_doubt}")
        if pairing.shape_stations:
            at = {s: m.shape[c] for c, s in pairing.stations.items()}
            lines.append("shape = [" + ", ".join(repr(float(at[s])) for s in pairing.shape_stations) + "]")
        lines.append(
            f"# model {p.model_frequency_hz:.6g} Hz" + (f", MAC {p.mac:.3f}" if math.isfinite(p.mac) else "")
        )
        lines.append("")
    return "\n".join(lines)
