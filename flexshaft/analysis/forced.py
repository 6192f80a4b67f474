"""Steady forced response to a sinusoidal torque: amplitudes in every station and component.

The question the test bench asked after a friction coupling slipped: a motor torque
T·sin(2πft) at (or near) an eigenfrequency - how large a dynamic torque does each part
carry? The answer is the frequency response of every ``angle:STATION`` and every
``torque:COMPONENT`` signal (see :mod:`flexshaft.analysis.statespace`) times the torque
amplitude, at each flexible mode's natural frequency ``|λ|/2π`` by default (where a lightly
damped mode's response peaks) or at frequencies given. All modes of the result are kept:
no truncation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..system.threads import follows_policy
from ..validation import check_real
from .modal import ModalResult
from .simulate import MAX_TORQUE
from .statespace import frequency_response, signal_names, state_space

__all__ = ["ForcedResponse", "forced_response"]


@dataclass(frozen=True)
class ForcedResponse:
    """Steady response amplitudes to ``amplitude · sin(2πft)`` applied at one station.

    Attributes
    ----------
    input : str
        The station the torque is applied at.
    amplitude : float
        The torque amplitude, N·m.
    frequencies_hz : ndarray, shape (f,)
        The excitation frequencies, Hz.
    modes : ndarray of int, shape (f,)
        The mode whose natural frequency each one is, -1 for a frequency given by hand.
    signals : tuple of str
        ``angle:STATION`` for every station, then ``torque:COMPONENT`` for every shaft and coupling.
    units : tuple of str
        ``rad`` or ``N·m``, per signal.
    amplitudes : ndarray, shape (f, s)
        Peak amplitude of each signal at each frequency (rad, N·m).
    phases_deg : ndarray, shape (f, s)
        Phase of each signal relative to the applied torque, degrees.
    slip_torques : dict of str to float
        The slip torque (N·m) of each coupling that may slip: the linear response takes it stuck,
        :meth:`would_slip` says where that is not the line's answer.
    """

    input: str
    amplitude: float
    frequencies_hz: np.ndarray
    modes: np.ndarray
    signals: tuple
    units: tuple
    amplitudes: np.ndarray
    phases_deg: np.ndarray
    slip_torques: dict = field(default_factory=dict)

    def would_slip(self) -> list[dict]:
        """Each excitation where a slipping coupling, taken stuck, would carry more than its slip
        torque (the study's sliding-coupling check): ``mode``, ``component``, ``torque`` and
        ``slip_torque`` (N·m)."""
        out = []
        for name, limit in self.slip_torques.items():
            k = self.signals.index(f"torque:{name}")
            for i, m in enumerate(self.modes):
                if self.amplitudes[i, k] > limit:
                    mode = int(m) if m >= 0 else None
                    out.append(
                        {
                            "mode": mode,
                            "component": name,
                            "torque": float(self.amplitudes[i, k]),
                            "slip_torque": limit,
                        }
                    )
        return out

    def largest_torque(self, row: int) -> str:
        """The component carrying the largest dynamic torque at excitation ``row``."""
        idx = [k for k, s in enumerate(self.signals) if s.startswith("torque:")]
        k = max(idx, key=lambda j: self.amplitudes[row, j])
        return self.signals[k].partition(":")[2]

    def to_dict(self) -> dict:
        """A JSON-ready document with its units."""
        return {
            "input": self.input,
            "units": {
                "amplitude": "N·m",
                "frequency": "Hz",
                "angle": "rad (peak)",
                "torque": "N·m (peak)",
                "phase": "degrees",
            },
            "amplitude": self.amplitude,
            "excitations": [
                {
                    "frequency_hz": float(f),
                    "mode": int(m) if m >= 0 else None,
                    "largest_torque": self.largest_torque(i),
                    "amplitude": {s: float(a) for s, a in zip(self.signals, self.amplitudes[i])},
                    "phase_deg": {s: float(p) for s, p in zip(self.signals, self.phases_deg[i])},
                }
                for i, (f, m) in enumerate(zip(self.frequencies_hz, self.modes))
            ],
        } | ({"would_slip": self.would_slip()} if self.slip_torques else {})

    def table(self) -> str:
        """The ``flexshaft forced`` table: the peak dynamic torque per part (N·m) at each excitation
        frequency (Hz)."""
        parts = [k for k, s in enumerate(self.signals) if s.startswith("torque:")]
        width = max(10, *(len(self.signals[k]) - 7 for k in parts))
        head = (
            "mode  frequency Hz  " + "  ".join(f"{self.signals[k][7:]:>{width}}" for k in parts) + "  largest"
        )
        rows = [
            f"forced response to {self.amplitude:g} N·m at {self.input}: peak dynamic torque per part, N·m",
            "",
            head,
            "-" * len(head),
        ]
        for i, (f, m) in enumerate(zip(self.frequencies_hz, self.modes)):
            cells = "  ".join(f"{self.amplitudes[i, k]:>{width}.4g}" for k in parts)
            rows.append(f"{m if m >= 0 else '-':>4}  {f:12.4f}  {cells}  {self.largest_torque(i)}")
        rows += [
            f"mode {s['mode']}: {s['component']!r} would carry {s['torque']:.6g} N·m, above its slip torque"
            f" {s['slip_torque']:g} N·m: it slips (flexshaft amplitude, simulate: by how much)"
            for s in self.would_slip()
        ]
        return "\n".join(rows)

    def plot(self):
        """Each part's peak dynamic torque at each excitation, a matplotlib Figure (never shown)."""
        from ..views.plots import forced_figure

        return forced_figure(self)


@follows_policy
def forced_response(
    result: ModalResult,
    input: str | None = None,
    *,
    amplitude: float = 1.0,
    frequencies_hz=None,
    max_hz: float | None = None,
) -> ForcedResponse:
    """Steady amplitudes of every station angle and component torque under a sinusoidal torque.

    Parameters
    ----------
    result : ModalResult
        The modes of the drivetrain; all of them are used.
    input : str, optional
        The station the torque is applied at; default the driving end (the chain's first station,
        where a motor's air-gap torque acts).
    amplitude : float
        Torque amplitude, N·m (> 0, at most :data:`~flexshaft.analysis.simulate.MAX_TORQUE`: the
        response is linear in it, and a larger one leaves floating point at a lightly damped mode).
    frequencies_hz : sequence of float, optional
        Excitation frequencies, Hz; by default each flexible mode's natural frequency ``|λ|/2π`` up to
        ``max_hz``. A model without damping has an unbounded response there: give frequencies off them.
    max_hz : float, optional
        The range of interest, Hz (default: the model's ``[model] max_hz``): the default excitations
        stop there - a fine mesh's hundred modes up to a megahertz are nobody's question.
    """
    amplitude = check_real(amplitude, "amplitude", "N·m", lo=0.0, lo_open=True, hi=MAX_TORQUE)
    model = result.model
    input = model.stations[0].name if input is None else input
    names = signal_names(model)
    signals = [s for s in names["outputs"] if s.startswith("angle:")]
    # Every component that carries its torque in a spring (not rigid inertias, not a rigid gear mesh).
    signals += [t for c in model.drivetrain.components if (t := f"torque:{c.name}") in names["outputs"]]
    ss = state_space(result, [input], signals)
    if frequencies_hz is None:
        flexible = np.flatnonzero(~result.rigid)
        if result.damped is not None:
            f = np.asarray(result.damped.natural_frequencies_hz, dtype=float)[flexible]
        else:
            f = result.frequencies_hz[flexible]
        modes = flexible
        top = max_hz if max_hz is not None else model.drivetrain.max_hz
        if top is not None:
            keep = f <= top
            f, modes = f[keep], modes[keep]
        if f.size == 0:
            raise ModelError("the model has no flexible mode", field="frequencies", valid="give frequencies")
    else:
        f = np.atleast_1d(frequencies_hz)  # one or several; frequency_response checks them
        modes = None
    resp = frequency_response(ss, f)
    with np.errstate(over="ignore", invalid="ignore"):
        H = resp.H[:, :, 0] * amplitude
    bad = ~np.all(np.isfinite(H), axis=1)
    if bad.any():  # never printed as inf: a receptance so large times the amplitude is no number
        i = int(np.argmax(bad))
        raise ModelError(
            f"gives a response beyond floating point at {float(resp.frequencies_hz[i]):g} Hz",
            field="amplitude",
            value=amplitude,
            unit="N·m",
            valid="a smaller amplitude, or frequencies further from the undamped modes",
        )
    return ForcedResponse(
        input=input,
        amplitude=amplitude,
        frequencies_hz=resp.frequencies_hz,
        modes=np.full(resp.frequencies_hz.size, -1) if modes is None else modes,
        signals=tuple(signals),
        units=tuple(ss.output_units),
        amplitudes=np.abs(H),
        phases_deg=np.degrees(np.angle(H)),
        slip_torques={
            c.name: c.law.torque
            for c in result.model.drivetrain.components
            if getattr(c, "law", None) is not None and c.law.kind == "slip"
        },
    )
