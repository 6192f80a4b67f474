"""Time simulation of the drivetrain, open or in closed speed loop, as the test bench is run.

The plant is the modal state space of :mod:`flexshaft.analysis.statespace` (named inputs and
outputs), discretised once by zero-order hold at the sample rate: ``[[Ad, Bd], [0, I]] =
expm([[A, B], [0, 0]]·dt)``, exact for inputs held over each step. The speed controller is the
study's: a PI on a measured speed (``speed:STATION``), a first-order low-pass to the air-gap
torque (the drive cannot follow high frequencies; discretised exactly, ``a = exp(−dt/τ)``), and
torque limits with anti-windup by clamping (the integrator holds while the command is limited).
It runs at the same sample rate, as a digital drive controller does:

    y_k = C x_k,  e_k = r_k − y_speed,k,  u_k = kp·e_k + I_k  (limited to [lo, hi])
    I_{k+1} = I_k + ki·dt·e_k   (only while u_k is inside the limits)
    T_{k+1} = a·T_k + (1 − a)·u_k   (τ = 0: T_k = u_k)
    x_{k+1} = Ad x_k + Bd [T_k, load_k]

How it is fast: between limit switches the whole loop is linear and time-invariant, so it is
run in blocks, each state recursion decoupled by the eigenvectors of the loop's discrete
matrix and evaluated by ``scipy.signal.lfilter`` (compiled), one pass per eigenvalue - about
one small matrix-vector product per step in total. Pure accumulators (a free drivetrain's
rigid-body angle, a held integrator: nothing else depends on them) are summed separately,
which keeps the rest diagonalisable. Where a limit is hit, the block is cut at that step and
the loop goes on in its other linear form (torque held at the limit, integrator frozen), so
the result is the same as stepping the equations above one by one (``method="loop"`` does
exactly that, for checking; it is also used if a loop matrix is too close to defective).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..linalg.firstorder import damped_eigen
from ..measurement.checks import MIN_SEGMENT_SAMPLES
from ..system.limits import CEILINGS, check_ceiling, check_memory
from ..system.threads import follows_policy
from ..validation import check_choice, check_real
from .discreteloop import ModalBlocks, closed_run, loop_form, loop_open, zoh
from .hybrid import NonlinearRun, nonlinear_elements, respond
from .modal import ModalResult
from .scenario import MAX_TORQUE, RPM, Scenario, SpeedControl, drive_torque, setpoint, torque_disturbance
from .statespace import signal_names, state_space

# Scenario, SpeedControl and RPM are defined in .scenario; named here too, as the run's own arguments
__all__ = ["SimulationResult", "simulate", "closed_loop_poles", "Scenario", "SpeedControl", "RPM"]

#: The longest run by default, samples: the ``samples`` ceiling of :mod:`flexshaft.system.limits` (10
#: million, 2.8 h at 1 kHz, 80 MB an output and each input held in memory; FLEXSHAFT_MAX_SAMPLES
#: sets another); longer records are split into runs.
MAX_SAMPLES = CEILINGS["samples"].value
#: The extra outputs a closed loop offers: the air-gap torque it applies and its set-point.
CONTROL_OUTPUTS = {"control:torque": "N·m", "control:setpoint": "rad/s"}
#: The fewest samples a run has: the first is the state at rest (the drive acts from the second),
#: and a spectrum of an output needs as many (:data:`flexshaft.measurement.checks.MIN_SEGMENT_SAMPLES`).
MIN_SAMPLES = MIN_SEGMENT_SAMPLES
#: How far outside the unit circle a pole of the discrete speed loop may lie and still count as on
#: it: √eps. Poles on the circle are legitimate (an undamped mode, an integrator with ki = 0, a
#: free line's speed); where two meet at z = 1 round-off of order eps splits the double pole by
#: √eps. A pole further out grows by that factor every step: the loop is unstable.
STABILITY_TOLERANCE = math.sqrt(np.finfo(float).eps)


@dataclass(frozen=True)
class SimulationResult:
    """A simulated run: the named outputs sampled at ``rate_hz``.

    Attributes
    ----------
    time : ndarray
        Sample times, s (from 0, step 1/rate).
    outputs : dict of str to ndarray
        Each output's samples (SI, in its own shaft's speed frame).
    units : dict of str to str
        Each output's unit.
    rate_hz : float
        Sample (and controller) rate, Hz.
    scenario : Scenario
    method : str
        ``"modal blocks"`` (vectorised) or ``"loop"`` (stepped), and the number of limit
        switches.
    states : int
        Plant states (2 per mode kept).
    nonlinear : NonlinearRun or None
        With nonlinear couplings or meshes: each one's events, time slipping or in contact, peak
        torque and dissipated energy, and the event tolerance (:mod:`flexshaft.analysis.hybrid`).
    """

    time: np.ndarray
    outputs: dict
    units: dict
    rate_hz: float
    scenario: Scenario
    method: str
    states: int
    nonlinear: NonlinearRun | None = None

    def to_dict(self, outputs=None) -> dict:
        """A JSON-ready summary of the run (the samples themselves go to CSV, :meth:`to_pandas`): its
        rate (Hz), duration (s), samples, states and method, and per output (``outputs``: those named,
        default all) its unit, min, max and final value."""
        names = list(self.outputs) if outputs is None else [n for n in self.outputs if n in outputs]
        extra = {} if self.nonlinear is None else {"nonlinear": self.nonlinear.to_dict()}
        return extra | {
            "rate_hz": self.rate_hz,
            "duration_s": float(self.time[-1]),
            "samples": int(self.time.size),
            "states": self.states,
            "method": self.method,
            "outputs": {
                n: {
                    "unit": self.units[n],
                    "min": float(self.outputs[n].min()),
                    "max": float(self.outputs[n].max()),
                    "final": float(self.outputs[n][-1]),
                }
                for n in names
            },
        }

    def to_pandas(self):
        """A pandas DataFrame indexed by time (s), a column ``NAME [unit]`` per output (pandas needed)."""
        try:
            import pandas as pd
        except ImportError:
            raise ModelError("needs pandas", field="to_pandas", valid="pip install pandas") from None
        data = {f"{k} [{self.units[k]}]": v for k, v in self.outputs.items()}
        return pd.DataFrame(data, index=pd.Index(self.time, name="time [s]"))

    def plot(self, outputs=None):
        """Each output against time, one panel per unit, as a matplotlib Figure (never shown)."""
        from ..views.plots import simulation_figure

        return simulation_figure(self, outputs)

    def table(self, scenario, kind: str, first_station: str) -> str:
        """The ``flexshaft simulate`` table: the run (``kind``, its ``scenario``), the speed
        loop (gains in N·m·s/rad and N·m/rad) and each output's min, max and final value."""
        lines = [
            f"{kind} run: {self.time[-1]:g} s at {self.rate_hz:g} Hz ({self.time.size} samples, "
            f"{self.states} states, {self.method})"
        ]
        if scenario.control is not None:
            c = scenario.control
            lines.append(
                f"speed loop on {c.measure or 'speed:' + (scenario.at or first_station)}: "
                f"kp {c.kp:.6g} N·m·s/rad, ki {c.ki:.6g} N·m/rad, tau {c.tau:g} s, "
                f"limits {c.torque_min:g} … {c.torque_max:g} N·m"
                + (f", power limit {c.power_limit:g} W" if math.isfinite(c.power_limit) else "")
            )
        lines.append(f"{'output':<32} {'unit':>6} {'min':>12} {'max':>12} {'final':>12}")
        for name, y in self.outputs.items():
            lines.append(f"{name:<32} {self.units[name]:>6} {y.min():12.5g} {y.max():12.5g} {y[-1]:12.5g}")
        if self.nonlinear is not None:
            lines.append(self.nonlinear.table())
        return "\n".join(lines)


def _is_station(model, name: str) -> bool:
    try:
        model.station(name, "station")
    except ModelError:
        return False
    return True


@follows_policy
def simulate(
    result: ModalResult,
    scenario: Scenario,
    outputs,
    *,
    rate: float = 1000.0,
    duration: float | None = None,
    max_hz: float | None = None,
    method: str = "auto",
    progress=None,
) -> SimulationResult:
    """Run a scenario on the drivetrain and sample the named outputs.

    Parameters
    ----------
    result : ModalResult
        The modes of the drivetrain (all of them, or enough to cover ``max_hz``).
    scenario : Scenario
    outputs : sequence of str
        Signal names (``angle:STATION``, ``speed:STATION``, ``torque:COMPONENT``, and with the
        loop closed ``control:torque`` and ``control:setpoint``).
    rate : float
        Sample and controller rate, Hz (the step is 1/rate).
    duration : float, optional
        Length of the run, s; default: the ramp plus a tenth, or 10 s.
    max_hz : float, optional
        Keep only the modes up to this frequency, Hz (the rigid-body modes always). Default: the
        sample rate - a mode above it cannot show in the samples, and keeping it would only add
        states (a 6-DOF model's thousands); what is dropped is its quasi-static share of the
        response. ``max_hz=float("inf")`` keeps every mode.
    method : {"auto", "loop"}
        Vectorised modal blocks (default) or one step at a time (the reference).
    progress : callable, optional
        ``progress(done, total)`` in steps, e.g. a :class:`flexshaft.views.progress.ProgressBar`.

    Raises
    ------
    ModelError
        Besides bad arguments, whatever would make the result no number or a misleading one: a
        speed loop unstable at this rate (a pole of the discrete loop outside the unit circle by
        more than :data:`STABILITY_TOLERANCE`; the error names the bandwidth or the gain to blame
        and its largest stable value), a sine or ripple at or above rate/2, a torque history
        sampled finer than the step, fewer than :data:`MIN_SAMPLES` samples, and an output that
        is not finite (checked after the run, before anything is returned).
    """
    if not isinstance(scenario, Scenario):
        raise ModelError("must be a Scenario", field="scenario", valid="Scenario.step(...), .ramp(...), ...")
    _check_stations(scenario, result.model)
    rate = check_real(rate, "rate", "Hz", lo=0.0, lo_open=True, hi=1e7)
    check_choice(method, "method", ("auto", "loop"))
    n_steps = _sample_count(scenario, rate, duration)
    dt = 1.0 / rate
    model = result.model
    control = scenario.control
    outputs = _checked_outputs(list(outputs), n_steps, control, model)
    drive = scenario.at if scenario.at is not None else model.stations[0].name
    load_at = scenario.load_at if scenario.load_at is not None else model.stations[-1].name
    plant_out = [o for o in outputs if o not in CONTROL_OUTPUTS]
    # The measured speed - the loop's, or the drive's, which a start speed is given at - is the
    # plant's last output row, whatever was asked.
    measure = control.measure if control is not None and control.measure is not None else f"speed:{drive}"
    _check_below_nyquist(scenario, rate)
    if max_hz is None:
        max_hz = rate
    if max_hz == math.inf or max_hz >= float(np.max(result.frequencies_hz)):
        max_hz = None  # every mode
    ss = state_space(result, [drive, load_at], plant_out + [measure], max_hz=max_hz)
    n = ss.A.shape[0]
    Ad, Bd = zoh(ss.A, ss.B, dt)
    C = ss.C
    if control is not None:

        def below_nyquist():
            """The plant without the modes above rate/2 (None: it has none to drop)."""
            if max_hz is not None and max_hz < rate / 2:
                return None
            low = state_space(result, [drive, load_at], plant_out + [measure], max_hz=rate / 2)
            return (*zoh(low.A, low.B, dt), low.C) if low.A.shape[0] < n else None

        _check_stable(Ad, Bd, C, control, dt, below_nyquist)
    t = np.arange(n_steps) * dt
    x0, hold, held_load = _initial_state(result.model, ss, scenario, drive, load_at)
    if scenario.steady:
        x0 = _steady_sine(Ad, Bd, scenario, dt)
    hybrid = (result, ss, (hold, held_load)) if nonlinear_elements(model) else None
    ys, used, summary = _respond(scenario, (Ad, Bd, C), x0, hold, t, dt, method, progress, hybrid)
    ys = {name: ys["plant"][:, i] for i, name in enumerate(plant_out)} | {
        k: v for k, v in ys.items() if k in CONTROL_OUTPUTS
    }
    for name in outputs:
        _check_finite(name, np.asarray(ys[name]), t)
    units = dict(zip(plant_out, ss.output_units)) | CONTROL_OUTPUTS
    return SimulationResult(
        time=t,
        outputs={o: np.asarray(ys[o]) for o in outputs},
        units={o: units[o] for o in outputs},
        rate_hz=rate,
        scenario=scenario,
        method=used,
        states=n,
        nonlinear=summary,
    )


def _check_stations(scenario: Scenario, model) -> None:
    """The drive's and the load's stations by their own names (the state space would call either of
    them "input")."""
    for name, station in (("at", scenario.at), ("load_at", scenario.load_at)):
        if station is not None and not _is_station(model, station):
            stations = ", ".join(signal_names(model)["inputs"])
            raise ModelError("no such station", field=name, value=station, valid=stations)


def _sample_count(scenario: Scenario, rate: float, duration: float | None) -> int:
    """The run's samples: ``duration`` (default: the ramp and a tenth, or 10 s) at ``rate``, within
    the samples ceiling and at least :data:`MIN_SAMPLES`."""
    given = duration is not None
    if duration is None:
        duration = 1.1 * scenario.ramp_time if scenario.kind == "ramp" and scenario.ramp_time > 0 else 10.0
    duration = check_real(duration, "duration", "s", lo=0.0, lo_open=True)
    steps = duration * rate  # inf for a duration near the float limit: refused, never an OverflowError
    check_ceiling(
        "samples",
        steps + 1,
        field="duration",
        value=duration,
        unit="s",
        detail=f"{steps + 1:.6g} samples at {rate:g} Hz" if math.isfinite(steps) else "samples beyond count",
        hint="a shorter duration or a lower --rate",
    )
    n_steps = int(math.floor(steps + 1e-9)) + 1
    if n_steps < MIN_SAMPLES:
        _too_few_samples(n_steps, duration, rate, given)
    return n_steps


def _checked_outputs(outputs: list, n_steps: int, control, model) -> list:
    """The outputs asked for: at least one, held in memory, the loop's only with the loop closed."""
    if not outputs:
        raise ModelError(
            "needs at least one output", field="output", valid=", ".join(signal_names(model)["outputs"])
        )
    # Every output, the time and the two inputs are held whole, 8 bytes a sample each.
    check_memory(
        8.0 * n_steps * (len(outputs) + 3),
        field="output",
        value=len(outputs),
        unit="outputs",
        detail=f"{n_steps} samples of {len(outputs)} outputs, the time and the inputs",
        hint="fewer outputs or samples",
    )
    extra = [o for o in outputs if o in CONTROL_OUTPUTS]
    if extra and control is None:
        raise ModelError(
            "exists only with the speed loop closed",
            field="output",
            value=extra[0],
            valid="the ramp scenario",
        )
    return outputs


def _respond(scenario: Scenario, plant, x0, hold, t, dt: float, method: str, progress, hybrid=None):
    """The run itself: ``{"plant": samples by output row}`` (with the loop closed also the control
    outputs), the method used, and the nonlinear elements' account (None without them). ``hybrid``:
    ``(result, state space, (drive, load) preload)`` of a line with nonlinear elements."""
    Ad, Bd, C = plant
    load = np.full(t.size, scenario.load if scenario.kind != "coast" else 0.0)
    control = scenario.control
    stepped = method == "loop"
    # Whatever overflows turns into inf or NaN silently here and is refused below, by output and time.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        if control is None:
            drive = drive_torque(scenario, t, dt) + torque_disturbance(scenario, t, dt, None)
            W = np.column_stack([drive, load])
            if hybrid is not None:
                Y, _, summary, used = respond(*hybrid[:2], x0, hybrid[2], W, None, dt, stepped, progress)
                return {"plant": Y}, used, summary
            system = ModalBlocks(Ad, Bd, C, np.zeros((C.shape[0], 2)))
            auto = method == "auto" and system.ok
            Y = system.run(x0, W, progress) if auto else loop_open(Ad, Bd, C, x0, W)
            return {"plant": Y}, "modal blocks" if auto else "loop", None
        r = setpoint(scenario, t)
        dist = torque_disturbance(scenario, t, dt, r)
        if hybrid is not None:
            W = np.column_stack([r, load, np.zeros(t.size), dist])
            Y, T, summary, used = respond(*hybrid[:2], x0, hybrid[2], W, control, dt, stepped, progress)
            return {"plant": Y, "control:torque": T, "control:setpoint": r}, used, summary
        ys, used = closed_run(Ad, Bd, C, x0, hold, r, load, dist, control, dt, method, progress)
        return {"plant": ys["plant"], "control:torque": ys["torque"], "control:setpoint": r}, used, None


def _too_few_samples(n_steps: int, duration: float, rate: float, given: bool) -> None:
    """Refuse a run of fewer than :data:`MIN_SAMPLES` samples, naming what the user set (the duration
    if given and a longer one can help, else the rate)."""
    why = (
        f"{MIN_SAMPLES} samples or more: the first is the state at rest, and fewer show no response"
        " a plot or a spectrum can read"
    )
    samples = f"{n_steps} sample{'s' if n_steps > 1 else ''}"
    need_duration, need_rate = (MIN_SAMPLES - 1) / rate, (MIN_SAMPLES - 1) / duration  # inf if tiny
    if given and math.isfinite(need_duration):
        raise ModelError(
            f"gives {samples} at the rate {rate:g} Hz",
            field="duration",
            value=duration,
            unit="s",
            valid=f">= {_round_up(need_duration, 6)} s at this rate ({why})",
        )
    raise ModelError(
        f"gives {samples} in the {duration:g} s run",
        field="rate",
        value=rate,
        unit="Hz",
        valid=(
            f">= {_round_up(need_rate, 6)} Hz for this duration"
            if math.isfinite(need_rate)
            else f"rate·duration >= {MIN_SAMPLES - 1}"
        )
        + f" ({why})",
    )


def _check_below_nyquist(scenario: Scenario, rate: float) -> None:
    """Refuse a drive the samples cannot carry: a sine or a ripple at or above the Nyquist frequency
    rate/2 (its samples would be those of a lower frequency, or zero), or a torque history sampled
    finer than the step (read once a step, it would skip what lies between)."""
    nyquist = rate / 2.0
    for i, (_, f) in enumerate(scenario.harmonics):
        if f >= nyquist:
            raise ModelError(
                "is at or above the Nyquist frequency: its samples would show a lower frequency",
                field=f"harmonics[{i}] frequency",
                value=f,
                unit="Hz",
                valid=f"< {nyquist:g} Hz at the rate {rate:g} Hz",
            )
    if scenario.kind == "sine" and scenario.frequency_hz >= nyquist:
        raise ModelError(
            f"is at or above the Nyquist frequency of the rate {rate:g} Hz: its samples would show"
            " a lower frequency (an alias)",
            field="frequency",
            value=scenario.frequency_hz,
            unit="Hz",
            valid=f"< {nyquist:g} Hz at this rate, or a rate above {2 * scenario.frequency_hz:g} Hz",
        )
    if scenario.ripple and scenario.kind in ("ramp", "coast"):
        top = max(abs(scenario.speed_rpm), abs(scenario.end_rpm) if scenario.kind == "ramp" else 0.0)
        f = scenario.ripple_order * top / 60.0
        if f >= nyquist:
            raise ModelError(
                f"puts the ripple at {f:g} Hz at {top:g} rpm, at or above the Nyquist frequency of the"
                f" rate {rate:g} Hz",
                field="ripple_order",
                value=scenario.ripple_order,
                valid=f"orders below {60.0 * nyquist / top:g} at this speed, or a rate above {2 * f:g} Hz",
            )
    if scenario.kind == "series":
        ts = scenario.series[0]
        step = float(np.min(np.diff(ts)))
        if step < (1.0 - 1e-6) / rate:  # 1e-6: time stamps written in decimal
            raise ModelError(
                f"is sampled every {step:.6g} s, finer than the run's step {1.0 / rate:.6g} s: read once"
                " a step, it would skip what lies between, and what it holds above the Nyquist"
                f" frequency {nyquist:g} Hz would fold onto lower frequencies",
                field="series",
                valid=f"a rate of at least {_round_up(1.0 / step)} Hz (the history's own), or the"
                " history low-passed and resampled to the rate",
            )


def _round_up(x: float, digits: int = 4) -> str:
    """``x`` rounded up to ``digits`` significant digits, as text (a bound that still holds)."""
    unit = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    return f"{math.ceil(x / unit - 1e-9) * unit:g}"


def _round_down(x: float, digits: int = 4) -> str:
    """``x`` rounded down to ``digits`` significant digits, as text (a bound that still holds)."""
    if x <= 0:
        return "0"
    unit = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    return f"{math.floor(x / unit + 1e-9) * unit:g}"


def _check_finite(name: str, y: np.ndarray, t: np.ndarray) -> None:
    """Refuse an output that left floating point (never printed, never written)."""
    bad = ~np.isfinite(y)
    if bad.any():
        i = int(np.argmax(bad))
        raise ModelError(
            f"is not a number from t = {float(t[i]):g} s on (sample {i}): the response left floating point",
            field=name,
            valid=f"torques within ±{MAX_TORQUE:g} N·m on a model whose modes are all damped or free,"
            " and a stable speed loop",
        )


def _worst_pole(F: np.ndarray) -> complex:
    """The eigenvalue of largest modulus of a loop matrix, its pure accumulators aside (they sit at
    1: a free line's angle); inf where the matrix or its eigenvalues are not numbers."""
    if not np.all(np.isfinite(F)):
        return complex(math.inf)
    n = F.shape[0]
    eye = np.eye(n)
    keep = ~np.array([np.array_equal(F[:, i], eye[:, i]) for i in range(n)], dtype=bool)
    if not keep.any():
        return complex(1.0)
    try:
        with np.errstate(all="ignore"):
            lam = damped_eigen(F[np.ix_(keep, keep)])
    except np.linalg.LinAlgError:
        return complex(math.inf)
    if not np.all(np.isfinite(lam)):
        return complex(math.inf)
    return complex(lam[np.argmax(np.abs(lam))])


def _loop_growth(Ad, Bd, C, control: SpeedControl, dt: float, kp=None, ki=None) -> float:
    """The spectral radius of the discrete speed loop (limits not reached), accumulators aside.

    Parameters
    ----------
    Ad, Bd, C : ndarray
        The plant discretised at ``dt`` (inputs: drive torque, load; the measured speed the last
        output row).
    control : SpeedControl
    dt : float
        The step, s.
    kp, ki : float, optional
        Other gains to try in place of the controller's (same low-pass).

    Returns
    -------
    float
        max |z| over the loop's poles: above 1 + :data:`STABILITY_TOLERANCE` it grows every step.
    """
    return abs(_loop_pole(Ad, Bd, C, control, dt, kp, ki))


def _loop_pole(Ad, Bd, C, control: SpeedControl, dt: float, kp=None, ki=None) -> complex:
    """The discrete speed loop's pole of largest modulus (see :func:`_loop_growth`)."""
    kp = control.kp if kp is None else kp
    ki = control.ki if ki is None else ki
    with np.errstate(all="ignore"):  # an overflowing gain gives inf entries: growth inf, not a warning
        F = loop_form(Ad, Bd, C, kp, ki, control.tau, dt, held=False)[0]
    return _worst_pole(F)


def _largest_stable(stable, top: float) -> float:
    """The largest x in (0, top] found stable (``stable(top)`` is False, small x stable), or 0.

    Halving from ``top`` to the first stable value, then bisection on the factor-2 bracket to 1e-9
    relative: a stability limit, not necessarily the only one.
    """
    lo = top
    for _ in range(2100):  # 2^-2100·1e308 is below the smallest float: every scale is tried
        lo *= 0.5
        if lo == 0.0:
            return 0.0
        if stable(lo):
            break
    else:
        return 0.0
    hi = 2.0 * lo
    while hi - lo > 1e-9 * lo:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def _check_stable(Ad, Bd, C, control: SpeedControl, dt: float, below_nyquist=None) -> None:
    """Refuse a speed loop whose discrete poles lie outside the unit circle at this rate.

    The error names what to change: the bandwidth the gains were tuned for, else the gain to blame
    (kp when the loop is unstable even without integral action, else ki), with its largest stable
    value at this rate (found by bisection on the same discrete loop). ``below_nyquist()``, if
    given, returns ``(Ad, Bd, C)`` of the plant without the modes above the Nyquist frequency: when
    the loop is stable on that one, the error says so - a digital loop sees such a mode aliased and
    late, and may drive an undamped one unstable at any gain.
    """
    limit = 1.0 + STABILITY_TOLERANCE
    z = _loop_pole(Ad, Bd, C, control, dt)
    if abs(z) <= limit:
        return
    rate = 1.0 / dt
    nyquist = rate / 2.0
    pole = f"a pole of the discrete loop at |z| = {abs(z):.6g}"
    if math.isfinite(abs(z)):
        pole += f", {abs(math.atan2(z.imag, z.real)) * rate / (2 * math.pi):.4g} Hz in the samples"
    pole += " (it grows that much a step)"
    spill = ""
    if below_nyquist is not None:
        low = below_nyquist()
        if low is not None and _loop_growth(*low, control, dt) <= limit:
            spill = (
                f"; or max_hz below {nyquist:g} Hz (the Nyquist frequency): the loop is stable"
                " without the modes above it, which it sees aliased and drives unstable"
            )
    if control.bandwidth_hz is not None:
        inertia = control.kp / (2 * math.pi * control.bandwidth_hz)  # kp = J·ω_c (SpeedControl.tuned)

        def stable_bw(f):
            wc = 2 * math.pi * f
            return _loop_growth(Ad, Bd, C, control, dt, kp=inertia * wc, ki=inertia * wc * wc / 5.0) <= limit

        best = _largest_stable(stable_bw, control.bandwidth_hz)
        raise ModelError(
            f"the speed loop tuned to it (kp {control.kp:.6g} N·m·s/rad, ki {control.ki:.6g} N·m/rad)"
            f" is unstable at the rate {rate:g} Hz: {pole}",
            field="bandwidth",
            value=control.bandwidth_hz,
            unit="Hz",
            valid=f"up to {_round_down(best)} Hz at this rate (its stability limit), or a higher rate"
            + spill,
        )
    if _loop_growth(Ad, Bd, C, control, dt, ki=0.0) <= limit:
        best = _largest_stable(lambda k: _loop_growth(Ad, Bd, C, control, dt, ki=k) <= limit, control.ki)
        raise ModelError(
            f"makes the speed loop unstable at the rate {rate:g} Hz with kp = {control.kp:g} N·m·s/rad:"
            f" {pole}",
            field="ki",
            value=control.ki,
            unit="N·m/rad",
            valid=f"up to {_round_down(best)} N·m/rad with this kp at this rate, or a higher rate" + spill,
        )
    best = _largest_stable(lambda k: _loop_growth(Ad, Bd, C, control, dt, kp=k, ki=0.0) <= limit, control.kp)
    raise ModelError(
        f"makes the speed loop unstable at the rate {rate:g} Hz even without integral action: {pole}",
        field="kp",
        value=control.kp,
        unit="N·m·s/rad",
        valid=f"up to {_round_down(best)} N·m·s/rad at this rate (its limit with ki = 0), or a higher rate"
        + spill,
    )


@follows_policy
def closed_loop_poles(
    result: ModalResult, control: SpeedControl, *, at: str | None = None, max_hz: float | None = None
) -> np.ndarray:
    """The poles of the drivetrain with its speed loop closed (continuous time), 1/s.

    The PI acts on the drive station like a damper kp and a spring ki to ground (its
    integrator), seen through the low-pass when τ > 0; so closing the loop raises the
    frequencies of the modes that move the drive station a little and damps them. States:
    the plant's modal states, the integrator, the low-pass (τ > 0). Limits play no part
    (a linear analysis).

    Parameters
    ----------
    result : ModalResult
    control : SpeedControl
    at : str, optional
        The station the air-gap torque acts on; default the driving end.
    max_hz : float, optional
        Keep only the plant modes up to this frequency, Hz.
    """
    model = result.model
    drive = at if at is not None else model.stations[0].name
    measure = control.measure if control.measure is not None else f"speed:{drive}"
    ss = state_space(result, [drive], [measure], max_hz=max_hz)
    A, b, c = ss.A, ss.B[:, 0], ss.C[0]
    n = A.shape[0]
    kp, ki = control.kp, control.ki
    if control.tau > 0:
        tau = control.tau
        Acl = np.zeros((n + 2, n + 2))
        Acl[:n, :n], Acl[:n, n + 1] = A, b
        Acl[n, :n] = -ki * c
        Acl[n + 1, :n], Acl[n + 1, n], Acl[n + 1, n + 1] = -kp * c / tau, 1 / tau, -1 / tau
    else:
        Acl = np.zeros((n + 1, n + 1))
        Acl[:n, :n] = A - kp * np.outer(b, c)
        Acl[:n, n] = b
        Acl[n, :n] = -ki * c
    return damped_eigen(Acl)


def _steady_sine(Ad: np.ndarray, Bd: np.ndarray, scenario: Scenario, dt: float) -> np.ndarray:
    """The state at t = 0 of the discrete plant's periodic response to the held sine T·sin(ωk·dt):
    x_k = Im(X·e^{iωk·dt}), (e^{iω·dt}·I − Ad)·X = Bd·T (exact for the sampled system; the rigid-body
    mode swings about a still mean)."""
    x = np.zeros(Ad.shape[0])
    for a, f in ((scenario.torque, scenario.frequency_hz), *scenario.harmonics):
        z = np.exp(2j * np.pi * f * dt)
        x += np.linalg.solve(z * np.eye(Ad.shape[0]) - Ad, Bd[:, 0] * a).imag  # each sine's, superposed
    return x


def _initial_state(model, ss, scenario, drive, load_at):
    """Plant state at t = 0 and the drive and load torques holding it steady (N·m).

    At rest, unless the scenario starts turning (ramp from a speed, coast): then the line spins at
    that speed (its rigid-body mode) and carries the torque balanced between drive and load: each
    elastic mode at its static deflection φᵀF/ω².
    """
    n = ss.A.shape[0]
    m = n // 2
    x0 = np.zeros(n)
    speed = model.speed_ratio
    s_drive = speed[model.station(drive).node]
    s_load = speed[model.station(load_at).node]
    if scenario.kind == "coast":
        torque_drive = scenario.torque
        torque_load = -scenario.torque * s_drive / s_load  # balanced: T·ω the same
    elif scenario.kind == "ramp":
        torque_load = scenario.load
        torque_drive = -scenario.load * s_load / s_drive
    else:
        return x0, 0.0, 0.0
    w2 = -np.diag(ss.A[m:, :m])
    f = ss.B[m:] @ np.array([torque_drive, torque_load])
    elastic = w2 > 0
    x0[:m][elastic] = f[elastic] / w2[elastic]
    if scenario.speed_rpm:
        # The rigid-body mode's rate that turns the measured station (or the drive) at the speed.
        rigid = np.flatnonzero(~elastic)
        row = ss.C[-1]  # the measured speed (see simulate)
        spin = rigid[np.argmax(np.abs(row[m + rigid]))] if rigid.size else None  # the one the speed sees
        if spin is None or row[m + spin] == 0:
            raise ModelError(
                "a start speed needs a line free to spin (a rigid-body rotation)", field="speed", unit="rpm"
            )
        x0[m + spin] = scenario.speed_rpm * RPM / row[m + spin]
    return x0, torque_drive, torque_load
