"""Amplitude-dependent behaviour made visible: a stepped sine at several drive amplitudes.

A linear drivetrain's resonances do not depend on how hard it is driven; one with a slipping
coupling, free play or a stiffness curve does. This runs what a test bench runs to see it: for each
drive-torque amplitude and each mode of interest, a sine at a grid of frequencies around the mode's
linear frequency, each to its steady state (started on the linear line's steady oscillation, so a
lightly damped mode needs no start-up; the nonlinear elements then settle within the run), and reads
the fundamental of a measured output: a response curve per amplitude. Its peak is the mode's
apparent frequency at that amplitude (refined by a parabola through the three highest points, in
log amplitude), its half-power width the apparent damping (:meth:`FrequencyResponse.peaks`, where
the width spans at least three grid steps). Each run's nonlinear account (time slipping or in
contact) comes along, so the shift shows where the elements act.

The fundamental is a least-squares fit of sin, cos, a constant and a drift over the last
``measure`` whole periods; the same fit over the ``measure`` periods before them says how settled
the run was (``settling``: the relative change, reported, not hidden).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..system.threads import follows_policy
from ..validation import check_int, check_real
from .modal import ModalResult
from .scenario import MAX_TORQUE, Scenario
from .simulate import simulate
from .statespace import FrequencyResponse

__all__ = ["SteppedSine", "stepped_sine", "DEFAULT_SPAN"]

#: The band searched around each mode's linear frequency, as fractions of it: a softening element
#: (slip, free play) moves a mode down by tens of per cent, a stiffening curve up.
DEFAULT_SPAN = (0.6, 1.15)
#: A half-power width narrower than this many grid steps is not read (the grid cannot resolve it).
MIN_STEPS_ACROSS = 3
#: With a pump: the pump periods run before measuring, in each measuring window, and the pump's
#: harmonics fitted beside the probe (a slipping coupling makes odd ones, free play all).
PUMP_SETTLE, PUMP_WINDOW, PUMP_HARMONICS = 20, 10, 7


@dataclass(frozen=True)
class SteppedSine:
    """Stepped-sine response curves at several drive amplitudes, and the apparent modes they show.

    Attributes
    ----------
    amplitudes : ndarray, shape (a,)
        Drive-torque amplitudes, N·m.
    modes : ndarray of int, shape (m,)
        The model modes looked at (numbered as ``flexshaft modes`` numbers them).
    linear_hz : ndarray, shape (m,)
        Their frequencies in the linear model (stuck, in contact, zero-torque tangent), Hz.
    frequencies_hz : ndarray, shape (m, f)
        The sine frequencies around each mode, Hz.
    response : ndarray, shape (a, m, f)
        Fundamental amplitude of ``measure`` per N·m of drive ([unit]/N·m).
    apparent_hz : ndarray, shape (a, m)
        The response curve's peak, Hz (NaN where it lies at the grid's edge: outside the band).
    apparent_damping : ndarray, shape (a, m)
        Half-power damping ratio of the curve (NaN where the grid does not resolve it).
    active : ndarray, shape (a, m, f)
        Fraction of each run a nonlinear element spent slipping, in contact or off its zero segment
        (the largest over the elements; 0 without any).
    settling : ndarray, shape (a, m, f)
        Relative change of the fundamental between the last two measuring windows.
    at, measure, unit : str
        Drive station, measured output and its unit.
    pump : tuple or None
        The pump sine (amplitude N·m, frequency Hz), if any.
    rate_hz : float
    cycles : int
        Periods run at each frequency.
    """

    amplitudes: np.ndarray
    modes: np.ndarray
    linear_hz: np.ndarray
    frequencies_hz: np.ndarray
    response: np.ndarray
    apparent_hz: np.ndarray
    apparent_damping: np.ndarray
    active: np.ndarray
    settling: np.ndarray
    at: str
    measure: str
    unit: str
    rate_hz: float
    cycles: int
    pump: tuple | None = None

    @property
    def shift(self) -> np.ndarray:
        """Apparent over linear frequency minus one, shape (a, m) (−0.23: 23 % lower)."""
        return self.apparent_hz / self.linear_hz[None, :] - 1.0

    def to_dict(self) -> dict:
        def num(x):
            return None if not math.isfinite(float(x)) else float(x)

        return {
            "at": self.at,
            "measure": self.measure,
            "units": {
                "amplitude": "N·m",
                "frequency": "Hz",
                "response": f"{self.unit} per N·m (fundamental)",
                "damping_ratio": "fraction",
                "active": "fraction of the run",
            },
            "rate_hz": self.rate_hz,
            "cycles": self.cycles,
            "pump": None if self.pump is None else {"amplitude": self.pump[0], "frequency_hz": self.pump[1]},
            "modes": [
                {
                    "mode": int(k),
                    "linear_hz": float(self.linear_hz[j]),
                    "frequencies_hz": self.frequencies_hz[j].tolist(),
                    "amplitudes": [
                        {
                            "amplitude": float(a),
                            "apparent_hz": num(self.apparent_hz[i, j]),
                            "shift": num(self.shift[i, j]),
                            "damping_ratio": num(self.apparent_damping[i, j]),
                            "response": self.response[i, j].tolist(),
                            "active": self.active[i, j].tolist(),
                            "settling": float(np.max(self.settling[i, j])),
                        }
                        for i, a in enumerate(self.amplitudes)
                    ],
                }
                for j, k in enumerate(self.modes)
            ],
        }

    def table(self) -> str:
        """Apparent frequency, shift and damping per mode and amplitude, and the nonlinear activity."""
        pump = "" if self.pump is None else f", pumped by {self.pump[0]:g} N·m at {self.pump[1]:.6g} Hz"
        lines = [
            f"stepped sine at {self.at}, measured {self.measure} ({self.frequencies_hz.shape[1]} frequencies"
            f" a mode, {self.cycles} periods each, {self.rate_hz:g} Hz{pump})",
            f"{'mode':>4} {'linear Hz':>10} {'amplitude N·m':>14} {'apparent Hz':>12} {'shift %':>8}"
            f" {'damping %':>10} {'active %':>9} {'settling':>9}",
        ]
        for j, k in enumerate(self.modes):
            for i, a in enumerate(self.amplitudes):
                f, sh, z = self.apparent_hz[i, j], self.shift[i, j], self.apparent_damping[i, j]
                peak = int(np.argmax(self.response[i, j]))
                lines.append(
                    f"{int(k):>4} {self.linear_hz[j]:>10.4f} {a:>14.6g} "
                    + (f"{f:>12.4f} {100 * sh:>8.2f}" if math.isfinite(f) else f"{'outside':>12} {'-':>8}")
                    + (f" {100 * z:>10.3f}" if math.isfinite(z) else f" {'-':>10}")
                    + f" {100 * self.active[i, j, peak]:>9.1f} {np.max(self.settling[i, j]):>9.1e}"
                )
        return "\n".join(lines)

    def plot(self):
        """The response curves (one panel per mode, a curve per amplitude) as a matplotlib Figure."""
        from ..views.plots import stepped_sine_figure

        return stepped_sine_figure(self)


def _fundamental(t: np.ndarray, y: np.ndarray, f: float, others=()) -> float:
    """Amplitude of the sine at ``f`` in ``y`` (least squares with a constant, a drift and sines at
    the ``others`` frequencies, so a pump and its harmonics do not leak into it)."""
    tc = t - t.mean()
    cols = [np.ones_like(t), tc]
    for g in (f, *others):
        cols += [np.sin(2 * np.pi * g * t), np.cos(2 * np.pi * g * t)]
    coef = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)[0]
    return float(math.hypot(coef[2], coef[3]))


@follows_policy
def stepped_sine(
    result: ModalResult,
    amplitudes,
    *,
    at: str | None = None,
    measure: str | None = None,
    modes=None,
    points: int = 21,
    span: tuple = DEFAULT_SPAN,
    cycles: int = 40,
    measure_cycles: int = 5,
    refine: int = 8,
    rate: float = 1000.0,
    pump=None,
    progress=None,
) -> SteppedSine:
    """Stepped-sine response curves around modes at several drive amplitudes (module docstring).

    Parameters
    ----------
    result : ModalResult
        The drivetrain's modes (its nonlinear elements act in the runs).
    amplitudes : sequence of float
        Drive-torque amplitudes, N·m, > 0.
    at : str, optional
        The drive station (default: the driving end).
    measure : str, optional
        The output read (default: the far end's speed. Across a serial chain the response from one
        end to the other has no zeros, so every mode shows as a peak; a driving point's has an
        anti-resonance below each, which a slipping coupling moves too).
    modes : sequence of int, optional
        The modes looked at (default: the elastic modes below rate/4).
    points : int
        Sine frequencies per mode, spread evenly over ``span`` times its linear frequency.
    span : (float, float)
        The band, as fractions of each mode's linear frequency.
    cycles : int
        Periods run at each frequency; the last 2·``measure_cycles`` are measured.
    measure_cycles : int
        Periods in each measuring window.
    refine : int
        Halvings of the bracket around each curve's highest point (two runs each): the apparent
        frequency to the grid step / 2^refine.
    rate : float
        Sample rate, Hz (each sine below rate/4, so a period holds four samples or more).
    pump : (float, float), optional
        A second sine (amplitude N·m, frequency Hz) driving the line at the same station all along,
        while the stepped sine probes: one mode driven hard - its coupling slipping - while another
        mode's apparent frequency is read. The amplitudes are then the probe's (keep them small
        beside the pump's, so the pump alone sets what the elements do); each run lasts at least
        :data:`PUMP_SETTLE` pump periods plus two windows of :data:`PUMP_WINDOW` pump periods, and the
        fundamental at the probe is fitted beside the pump and its first :data:`PUMP_HARMONICS`
        harmonics.
    progress : callable, optional
        ``progress(done, total)`` in runs.
    """
    model = result.model
    amps = _amplitudes(amplitudes)
    rate = check_real(rate, "rate", "Hz", lo=0.0, lo_open=True, hi=1e7)
    points = check_int(points, "points", lo=5, hi=1000)
    refine = check_int(refine, "refine", lo=0, hi=40)
    measure_cycles = check_int(measure_cycles, "measure_cycles", lo=1, hi=10_000)
    cycles = check_int(cycles, "cycles", lo=2 * measure_cycles + 1, hi=100_000)
    lo = check_real(span[0], "span[0]", "", lo=0.0, lo_open=True, hi=1.0, hi_open=True)
    hi = check_real(span[1], "span[1]", "", lo=1.0, lo_open=True, hi=10.0)
    at = at if at is not None else model.stations[0].name
    measure = measure if measure is not None else f"speed:{model.stations[-1].name}"
    modes = _modes(result, modes, hi, rate)
    linear = result.frequencies_hz[modes]
    # the linear frequency is a grid point: at small amplitude the curve peaks on it exactly
    below = round((1.0 - lo) / (hi - lo) * (points - 1))
    grid = np.array([f * (1.0 + (hi - lo) / (points - 1) * (np.arange(points) - below)) for f in linear])
    shape = (amps.size, len(modes), points)
    response, active, settling = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    apparent = np.full(shape[:2], np.nan)
    unit = ""
    total, done = amps.size * len(modes) * (points + 2 * refine), 0

    harmonics, others = _pump(pump, rate)

    def point(a: float, f: float) -> tuple[float, float, float]:
        """Response per N·m, activity and settling of one sine run (module docstring)."""
        nonlocal unit, done
        window, duration = measure_cycles / f, cycles / f
        if harmonics:
            window = max(window, PUMP_WINDOW / harmonics[0][1])
            duration = max(duration, PUMP_SETTLE / harmonics[0][1] + 2 * window)
        sc = Scenario.sine(a, f, at=at, steady=True, harmonics=harmonics)
        run = simulate(result, sc, [measure], rate=rate, duration=duration)
        unit = run.units[measure]
        y, t = run.outputs[measure], run.time
        last = t >= t[-1] - window
        before = (t >= t[-1] - 2 * window) & ~last
        amp, prev = _fundamental(t[last], y[last], f, others), _fundamental(t[before], y[before], f, others)
        busy = 0.0
        if run.nonlinear is not None and run.nonlinear.elements:
            busy = max(e.active_time for e in run.nonlinear.elements) / run.time[-1]
        done += 1
        if progress is not None:
            progress(done, total)
        return amp / a, busy, (abs(amp - prev) / amp if amp > 0 else 0.0)

    for i, a in enumerate(amps):
        for j in range(len(modes)):
            for n, f in enumerate(grid[j]):
                response[i, j, n], active[i, j, n], settling[i, j, n] = point(a, f)
            apparent[i, j] = _peak(lambda f, a=a: point(a, f)[0], grid[j], response[i, j], refine)
    damping = _damping(grid, response)
    return SteppedSine(
        amplitudes=amps,
        modes=np.array(modes),
        linear_hz=linear,
        frequencies_hz=grid,
        response=response,
        apparent_hz=apparent,
        apparent_damping=damping,
        active=active,
        settling=settling,
        at=at,
        measure=measure,
        unit=unit,
        rate_hz=rate,
        cycles=cycles,
        pump=harmonics[0] if harmonics else None,
    )


def _pump(pump, rate: float) -> tuple[tuple, tuple]:
    """The pump as the sine scenario's harmonics, and the frequencies fitted beside the probe."""
    if pump is None:
        return (), ()
    pa = check_real(pump[0], "pump amplitude", "N·m", lo=-MAX_TORQUE, hi=MAX_TORQUE)
    pf = check_real(pump[1], "pump frequency", "Hz", lo=0.0, lo_open=True, hi=rate / 4)
    return ((pa, pf),), tuple(k * pf for k in range(1, PUMP_HARMONICS + 1) if k * pf < rate / 2)


def _amplitudes(amplitudes) -> np.ndarray:
    """The drive amplitudes, N·m: at least one, each > 0 and within the scenarios' largest torque."""
    amps = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if amps.size == 0:
        raise ModelError("needs at least one amplitude", field="amplitudes", unit="N·m", valid="> 0 N·m")
    for i, a in enumerate(amps):
        check_real(a, f"amplitudes[{i}]", "N·m", lo=0.0, lo_open=True, hi=MAX_TORQUE)
    return amps


def _modes(result: ModalResult, modes, hi: float, rate: float) -> list:
    """The modes looked at: elastic, each band's top below rate/4 (default: every such mode)."""
    elastic = [i for i in range(result.count) if not result.rigid[i]]
    if modes is None:
        modes = [i for i in elastic if result.frequencies_hz[i] * hi < rate / 4]
    modes = [int(check_int(k, "modes", lo=0, hi=result.count - 1)) for k in modes]
    for k in modes:
        if result.rigid[k]:
            raise ModelError("is a rigid-body mode", field="modes", value=k, valid=f"elastic modes {elastic}")
        if result.frequencies_hz[k] * hi >= rate / 4:
            raise ModelError(
                f"reaches {result.frequencies_hz[k] * hi:g} Hz at the band's top, at or above rate/4",
                field="modes",
                value=k,
                valid=f"a rate above {4 * result.frequencies_hz[k] * hi:g} Hz, or a lower mode",
            )
    if not modes:
        raise ModelError("no elastic mode below rate/4", field="rate", value=rate, unit="Hz")
    return modes


def _peak(response_at, f: np.ndarray, r: np.ndarray, refine: int) -> float:
    """The frequency of a curve's peak: the grid's highest point, its bracket [f_k−1, f_k+1] halved
    ``refine`` times by runs at the midpoints (the peak of a lightly damped mode is far narrower than
    any grid); NaN where the highest point is the band's edge (the peak lies outside it)."""
    k = int(np.argmax(r))
    if k in (0, f.size - 1) or r[k] <= 0:
        return math.nan
    f0, f1, f2, r1 = f[k - 1], f[k], f[k + 1], r[k]
    for _ in range(refine):
        left, right = 0.5 * (f0 + f1), 0.5 * (f1 + f2)
        rl, rr = response_at(left), response_at(right)
        if rl > max(r1, rr):
            f0, f1, f2, r1 = f0, left, f1, rl
        elif rr > r1:
            f0, f1, f2, r1 = f1, right, f2, rr
        else:
            f0, f2 = left, right
    return float(f1)


def _damping(grid: np.ndarray, response: np.ndarray) -> np.ndarray:
    """Each curve's half-power damping (:meth:`FrequencyResponse.peaks`) where the half-power width
    spans enough grid steps to be read (NaN elsewhere)."""
    a, m, _ = response.shape
    zeta = np.full((a, m), np.nan)
    for i in range(a):
        for j in range(m):
            f, r = grid[j], response[i, j]
            k = int(np.argmax(r))
            step = f[1] - f[0]
            frf = FrequencyResponse(
                f, r[:, None, None].astype(complex), ("drive",), ("out",), ("N·m",), ("",)
            )
            for p in frf.peaks():
                width = p["frequency_hz"] * 2 * (p.get("damping_ratio") or 0.0)
                if abs(p["frequency_hz"] - f[k]) < 0.5 * step and width >= MIN_STEPS_ACROSS * step:
                    zeta[i, j] = p["damping_ratio"]
    return zeta
