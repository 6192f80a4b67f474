"""What drives the line in a time run: a scenario (step, sine, coast, speed ramp, torque history)
and the speed controller a ramp closes the loop with, as frozen objects built by their class methods
(``Scenario.step(...)``, ``Scenario.ramp(...)``, ``SpeedControl.tuned(...)``), and the torques and
set-point they give at the sample times. :func:`flexshaft.analysis.simulate.simulate` runs them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..validation import check_choice, check_frequency, check_int, check_real
from .modal import ModalResult

__all__ = [
    "SpeedControl",
    "Scenario",
    "drive_torque",
    "torque_disturbance",
    "setpoint",
    "SCENARIOS",
    "KINDS",
    "RAMP_ONLY",
    "check_settings",
    "RPM",
    "MAX_TORQUE",
    "MAX_SPEED_RPM",
    "torque_limits",
]

#: rad/s per rpm.
RPM = 2.0 * math.pi / 60.0
SCENARIOS = ("step", "ramp", "coast", "sine", "series")
#: The scenarios a study's ``[[simulate]]`` table or ``flexshaft simulate --scenario`` names
#: (:meth:`Scenario.of`); ``csv`` is a torque history read from a file.
KINDS = ("step", "ramp", "coast", "sine", "csv")
#: The settings only a ramp (the closed speed loop) takes, by the library's names.
RAMP_ONLY = (
    "kp",
    "ki",
    "bandwidth_hz",
    "torque_limit",
    "power_limit",
    "measure",
    "end_speed_rpm",
    "ramp_time",
)
#: The largest torque a scenario applies, N·m (a step or sine amplitude, a coast preload, a load, a
#: ripple or noise, every value of a torque history): 1e12 N·m, 5e4 times what the largest
#: drivetrains carry (a 15 MW wind turbine's main shaft: about 2e7 N·m). The response is linear in
#: the torque; this keeps it, and the angles a free line turns through, inside floating point.
MAX_TORQUE = 1e12
#: The largest speed a scenario starts at or ramps to, rpm: 1e7 rpm, ten times the fastest spindles.
MAX_SPEED_RPM = 1e7


@dataclass(frozen=True)
class SpeedControl:
    """A PI speed controller with a low-pass to the air-gap torque and torque limits.

    Parameters
    ----------
    kp : float
        Proportional gain, N·m per rad/s (N·m·s/rad), >= 0. On the measured station it acts as
        a damper to ground.
    ki : float
        Integral gain, N·m per rad (N·m/rad), >= 0: a torsional spring to ground.
    tau : float
        Time constant of the first-order low-pass between the controller and the air-gap
        torque, s, >= 0 (0: none).
    torque_min, torque_max : float
        Limits of the commanded torque, N·m (anti-windup: the integrator holds while limited).
    power_limit : float
        Limit of the drive's power, W, > 0 (inf: none): at each sample the torque is held within
        ``±power_limit/|ω|`` of the measured speed ω as well (the motor's constant-power range above its
        base speed), with the same anti-windup; at standstill the torque limits alone apply.
    measure : str, optional
        The speed output it controls (``"speed:STATION"``); default the driving station's speed.
    bandwidth_hz : float, optional
        The bandwidth the gains were tuned for (:meth:`tuned` sets it), Hz; None: gains given.
        A loop that is unstable at the sample rate is then refused naming the bandwidth.
    """

    kp: float
    ki: float
    tau: float = 0.0
    torque_min: float = -math.inf
    torque_max: float = math.inf
    power_limit: float = math.inf
    measure: str | None = None
    bandwidth_hz: float | None = None

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "kp", check_real(self.kp, "kp", "N·m·s/rad", lo=0.0))
        s(self, "ki", check_real(self.ki, "ki", "N·m/rad", lo=0.0))
        s(self, "tau", check_real(self.tau, "tau", "s", lo=0.0))
        for name in ("torque_min", "torque_max"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool)) or math.isnan(v):
                raise ModelError("not a number", field=name, value=v, unit="N·m", valid="a number (N·m)")
            s(self, name, float(v))
        if not self.torque_min < self.torque_max:
            raise ModelError(
                "the lower torque limit is not below the upper one",
                field="torque_min",
                value=self.torque_min,
                unit="N·m",
                valid=f"< torque_max = {self.torque_max:g} N·m",
            )
        p = self.power_limit
        if isinstance(p, bool) or not isinstance(p, (int, float)) or not p > 0:  # NaN too
            raise ModelError("must be > 0", field="power_limit", value=p, unit="W", valid="> 0 W (inf: none)")
        s(self, "power_limit", float(p))
        if self.measure is not None and not str(self.measure).startswith("speed:"):
            raise ModelError(
                "the controller measures a speed",
                field="measure",
                value=self.measure,
                valid='"speed:STATION"',
            )
        if self.bandwidth_hz is not None:
            s(self, "bandwidth_hz", check_frequency(self.bandwidth_hz, "bandwidth", lo_open=True))

    @classmethod
    def tuned(cls, result: ModalResult, *, bandwidth_hz: float | None = None, **options) -> SpeedControl:
        """Gains for a speed loop well below the first elastic mode, from the model itself.

        The loop is closed on the whole line's inertia J (its rigid-body mode): kp = J·ω_c and
        ki = kp·ω_c/5 (a PI zero a fifth of the crossover: about 80° phase margin on a rigid
        inertia), with ω_c = 2π·bandwidth_hz, by default a tenth of the first elastic
        frequency (at most 10 Hz) so that the loop leaves the drivetrain's modes almost as
        they are. Other options (``tau``, limits, ``measure``) pass through.
        """
        if bandwidth_hz is None:
            flexible = result.frequencies_hz[~result.rigid]
            bandwidth_hz = min(0.1 * float(flexible[0]), 10.0) if flexible.size else 10.0
        # up to MAX_FREQUENCY_HZ (1e9 Hz): ki = J·ω_c²/5 stays a number for any inertia a model holds
        bandwidth_hz = check_frequency(bandwidth_hz, "bandwidth", lo_open=True)
        wc = 2 * math.pi * bandwidth_hz
        inertia = _line_inertia(result, options.get("measure"))
        return cls(kp=inertia * wc, ki=inertia * wc * wc / 5.0, bandwidth_hz=bandwidth_hz, **options)

    @classmethod
    def from_gains(
        cls,
        result: ModalResult,
        kp: float | None = None,
        ki: float | None = None,
        *,
        bandwidth_hz: float | None = None,
        tau: float = 0.0,
        torque_limit: float | None = None,
        measure: str | None = None,
        power_limit: float | None = None,
    ) -> SpeedControl:
        """The loop as a command or a study states it: both gains given, or neither (then
        :meth:`tuned` to ``bandwidth_hz``), and one limit for the torque's magnitude.

        Parameters
        ----------
        result : ModalResult
            The modes the gains are tuned from (when not given).
        kp, ki : float, optional
            PI gains, N·m per rad/s and N·m per rad (both or neither).
        bandwidth_hz : float, optional
            Speed-loop bandwidth for the tuned gains, Hz.
        tau : float
            Low-pass time constant of the air-gap torque, s (0: none).
        torque_limit : float, optional
            Limit of the commanded torque's magnitude, N·m, > 0 (anti-windup; default: none).
        measure : str, optional
            The speed the loop controls, ``speed:STATION`` (default: the drive's).
        power_limit : float, optional
            Limit of the drive's power, W, > 0 (default: none).
        """
        limit = math.inf if torque_limit is None else torque_limit
        if not limit > 0:  # NaN too
            raise ModelError("must be > 0", field="torque_limit", value=limit, unit="N·m", valid="> 0 N·m")
        loop = {"tau": tau, "torque_min": -limit, "torque_max": limit, "measure": measure}
        if power_limit is not None:
            loop["power_limit"] = power_limit
        if (kp is None) != (ki is None):
            raise ModelError("give both gains or neither", field="kp" if kp is None else "ki")
        if kp is None:
            return cls.tuned(result, bandwidth_hz=bandwidth_hz, **loop)
        return cls(kp, ki, **loop)


def _line_inertia(result: ModalResult, measure: str | None) -> float:
    """The whole line's inertia as seen at the measured station's speed, kg·m² (1/|φ_rigid|²)."""
    model = result.model
    st = model.stations[0] if measure is None else model.station(measure.partition(":")[2], "measure")
    rigid = np.flatnonzero(result.rigid)
    # The spin the station's speed sees: Σ φ² over the rigid-body modes (a 6-DOF model's axial motion
    # has no θx there); a line held to ground has none, and no inertia to tune a speed loop on.
    phi = np.asarray(model.T[model.node_dof([st.node])[0]] @ result.shapes[:, rigid]).ravel()
    if not np.any(phi):
        raise ModelError(
            "automatic gains need a line free to spin (a rigid-body rotation)",
            field="control",
            valid="give kp and ki",
        )
    return 1.0 / float(phi @ phi)


@dataclass(frozen=True)
class Scenario:
    """What drives the line: use the class methods (``Scenario.ramp(...)``, ...).

    Attributes
    ----------
    kind : {"step", "ramp", "coast", "sine", "series"}
    at : str or None
        The station the drive (air-gap) torque acts on; None: the driving end.
    torque : float
        Step or sine amplitude, or the torque the line carries before a coast stop, N·m.
    time : float
        When the step comes, s.
    frequency_hz : float
        Sine frequency, Hz.
    speed_rpm, end_rpm, ramp_time : float
        Initial speed (rpm, at the measured station, or the driving end), the ramp's final
        speed (rpm) and its duration (s).
    series : tuple of (ndarray, ndarray) or None
        Time (s) and drive torque (N·m) of a given torque history, linearly interpolated and
        held over each step (0 outside it).
    load : float
        A constant load torque, N·m (a generator brakes with a negative torque), at ``load_at``.
    load_at : str or None
        Its station; None: the far end.
    control : SpeedControl or None
        Closed speed loop (ramp); None: open loop.
    ripple : float
        Amplitude of a torque ripple on the drive torque, N·m, at ``ripple_order`` per revolution
        of the measured shaft, locked to the set-point angle ∫r dt (ramp; which the loop follows
        closely) or to the running speed (coast) - the order lines of a spectrogram.
    ripple_order : float
        Its order, > 0 (the study's drive: 6).
    noise : float
        RMS of a white-noise torque on the drive torque, N·m (a broadband excitation that shows
        the eigenfrequencies as lines in a spectrogram); reproducible from ``seed``.
    seed : int
        Seed of the noise.
    harmonics : tuple of (float, float)
        Sine only: further sines added to the drive torque, (amplitude N·m, frequency Hz) each - a
        second excitation (a pump driving one mode hard while the first sine probes another).
    steady : bool
        Sine only: start on the linear drivetrain's steady-state oscillation under the sine (the
        discrete system's periodic solution) instead of from rest, so a lightly damped line shows
        no start-up transient; with nonlinear elements the run goes on from there to their own
        steady state.
    """

    kind: str
    at: str | None = None
    torque: float = 0.0
    time: float = 0.0
    frequency_hz: float = 0.0
    speed_rpm: float = 0.0
    end_rpm: float = 0.0
    ramp_time: float = 0.0
    series: tuple | None = field(default=None, repr=False)
    load: float = 0.0
    load_at: str | None = None
    control: SpeedControl | None = None
    ripple: float = 0.0
    ripple_order: float = 6.0
    noise: float = 0.0
    seed: int = 0
    harmonics: tuple = ()
    steady: bool = False

    def __post_init__(self) -> None:
        check_choice(self.kind, "scenario", SCENARIOS)
        s = object.__setattr__
        T, V = MAX_TORQUE, MAX_SPEED_RPM  # amplitudes whose responses stay numbers (see there)
        s(self, "torque", check_real(self.torque, "torque", "N·m", lo=-T, hi=T))
        s(self, "time", check_real(self.time, "time", "s", lo=0.0))
        s(self, "frequency_hz", check_frequency(self.frequency_hz, "frequency"))
        s(self, "speed_rpm", check_real(self.speed_rpm, "speed", "rpm", lo=-V, hi=V))
        s(self, "end_rpm", check_real(self.end_rpm, "end_speed", "rpm", lo=-V, hi=V))
        s(self, "ramp_time", check_real(self.ramp_time, "ramp_time", "s", lo=0.0))
        s(self, "load", check_real(self.load, "load", "N·m", lo=-T, hi=T))
        s(self, "ripple", check_real(self.ripple, "ripple", "N·m", lo=-T, hi=T))
        s(self, "ripple_order", check_real(self.ripple_order, "ripple_order", "", lo=0.0, lo_open=True))
        s(self, "noise", check_real(self.noise, "noise", "N·m", lo=0.0, hi=T))
        s(self, "seed", check_int(self.seed, "seed", lo=0, hi=2**63 - 1))
        if self.ripple and self.kind not in ("ramp", "coast"):
            raise ModelError(
                "a torque ripple needs a known shaft speed",
                field="ripple",
                value=self.ripple,
                unit="N·m",
                valid="the ramp or coast scenario",
            )
        if self.control is not None and not isinstance(self.control, SpeedControl):
            raise ModelError("must be a SpeedControl", field="control")
        if self.kind == "ramp" and self.control is None:
            raise ModelError(
                "a speed ramp needs the speed loop closed",
                field="control",
                valid="a SpeedControl (or SpeedControl.tuned(result))",
            )
        if self.kind != "ramp" and self.control is not None:
            raise ModelError(
                "only the ramp closes the speed loop",
                field="control",
                valid="leave it out of a step, coast, sine or series scenario",
            )
        if self.steady is not False and (self.steady is not True or self.kind != "sine"):
            raise ModelError(
                "is a sine's start on its steady oscillation",
                field="steady",
                value=self.steady,
                has_value=True,
                valid="True or False with the sine scenario; False (from rest) otherwise",
            )
        if self.harmonics:
            if self.kind != "sine":
                raise ModelError("are further sines of a sine", field="harmonics", valid='scenario "sine"')
            s(
                self,
                "harmonics",
                tuple(
                    (
                        check_real(a, f"harmonics[{i}] amplitude", "N·m", lo=-T, hi=T),
                        check_frequency(f, f"harmonics[{i}] frequency", lo_open=True),
                    )
                    for i, (a, f) in enumerate(self.harmonics)
                ),
            )
        if self.kind == "sine" and self.frequency_hz <= 0:
            raise ModelError(
                "a sine needs its frequency",
                field="frequency",
                value=self.frequency_hz,
                unit="Hz",
                valid="> 0 Hz",
            )
        if self.kind == "series":
            t, T = self.series if self.series is not None else (None, None)
            t = np.asarray(t, dtype=float) if t is not None else np.zeros(0)
            T = np.asarray(T, dtype=float) if T is not None else np.zeros(0)
            if t.ndim != 1 or t.size < 2 or t.shape != T.shape or not np.all(np.isfinite(t)):
                raise ModelError(
                    "needs at least two finite (time, torque) samples of equal length",
                    field="series",
                    valid="time (s) and torque (N·m) arrays",
                )
            if not np.all(np.isfinite(T)):
                raise ModelError("torque series holds a non-finite value", field="series", unit="N·m")
            big = np.abs(T) > MAX_TORQUE
            if big.any():
                i = int(np.argmax(big))
                raise ModelError(
                    f"the torque history reaches {float(T[i]):g} N·m at t = {float(t[i]):g} s",
                    field="series",
                    valid=f"torques within ±{MAX_TORQUE:g} N·m (the response is linear in them: larger"
                    " ones leave floating point)",
                )
            if np.any(np.diff(t) <= 0):
                raise ModelError(
                    "time does not increase", field="series.time", unit="s", valid="increasing times"
                )
            s(self, "series", (t, T))

    @classmethod
    def step(cls, torque: float, *, at=None, time: float = 0.0, **kw) -> Scenario:
        """A step of the drive torque (N·m) at ``time`` (s), no control: the line spins up and rings."""
        return cls("step", at=at, torque=torque, time=time, **kw)

    @classmethod
    def ramp(cls, end_rpm: float, ramp_time: float, control: SpeedControl, *, start_rpm: float = 0.0, **kw):
        """A speed set-point ramp from ``start_rpm`` to ``end_rpm`` in ``ramp_time`` s, then held."""
        return cls("ramp", end_rpm=end_rpm, ramp_time=ramp_time, speed_rpm=start_rpm, control=control, **kw)

    @classmethod
    def coast(cls, torque: float, *, speed_rpm: float = 0.0, at=None, load_at=None) -> Scenario:
        """Coast stop: the line turns at ``speed_rpm`` carrying ``torque`` (N·m) from the drive to the
        load station, both go to zero at t = 0, and the twist rings down (a free decay)."""
        return cls("coast", torque=torque, speed_rpm=speed_rpm, at=at, load_at=load_at)

    @classmethod
    def sine(cls, amplitude: float, frequency_hz: float, *, at=None, **kw) -> Scenario:
        """A sinusoidal drive torque amplitude·sin(2πft), N·m, from rest (``steady=True``: from the linear
        line's steady oscillation)."""
        return cls("sine", torque=amplitude, frequency_hz=frequency_hz, at=at, **kw)

    @classmethod
    def from_series(cls, time, torque, *, at=None, **kw) -> Scenario:
        """A drive torque history (time s, torque N·m), e.g. read from a CSV file."""
        return cls("series", series=(time, torque), at=at, **kw)

    @classmethod
    def of(cls, kind: str, settings: dict, result: ModalResult | None = None, series=None) -> Scenario:
        """The scenario a study table or a command line names: ``kind`` (one of :data:`KINDS`) and its
        ``settings`` by the library's names (absent or None: the default).

        Parameters
        ----------
        kind : str
            ``"step"``, ``"sine"``, ``"coast"``, ``"csv"`` (the torque history ``series``) or
            ``"ramp"`` (the closed speed loop).
        settings : dict
            ``at``, ``load`` (N·m), ``load_at``, ``torque`` (N·m), ``step_time`` (s), ``frequency_hz``,
            ``speed_rpm`` (a ramp's start, a coast's running speed); a ramp's ``end_speed_rpm``,
            ``ramp_time`` (s) and its controller's ``kp``, ``ki``, ``bandwidth_hz``, ``tau`` (s),
            ``torque_limit`` (N·m), ``measure`` (:meth:`SpeedControl.from_gains`).
        result : ModalResult, optional
            The modes a ramp's default gains are tuned from.
        series : tuple of ndarray, optional
            The csv scenario's (time s, torque N·m).

        Raises
        ------
        ModelError
            Naming the setting by the name ``settings`` gives it.
        """
        check_settings(kind, settings)
        o = {k: v for k, v in settings.items() if v is not None}
        at, load = o.get("at"), {"load": o.get("load", 0.0), "load_at": o.get("load_at")}
        torque = o.get("torque", 0.0)
        if kind == "step":
            return cls.step(torque, at=at, time=o.get("step_time", 0.0), **load)
        if kind == "sine":
            return cls.sine(torque, o.get("frequency_hz", 0.0), at=at, steady=bool(o.get("steady")), **load)
        if kind == "coast":
            return cls.coast(torque, speed_rpm=o.get("speed_rpm", 0.0), at=at, load_at=load["load_at"])
        if kind == "csv":
            if series is None:
                raise ModelError(
                    "the csv scenario reads a torque history", field="series", valid="(time, torque)"
                )
            return cls.from_series(*series, at=at, **load)
        for name in ("end_speed_rpm", "ramp_time"):
            if o.get(name) is None:
                raise ModelError(
                    "a ramp needs its final speed and duration",
                    field=name,
                    valid="end_speed_rpm (rpm) and ramp_time (s)",
                )
        control = SpeedControl.from_gains(
            result,
            o.get("kp"),
            o.get("ki"),
            bandwidth_hz=o.get("bandwidth_hz"),
            tau=o.get("tau", 0.0),
            torque_limit=o.get("torque_limit"),
            measure=o.get("measure"),
            power_limit=o.get("power_limit"),
        )
        start = o.get("speed_rpm", 0.0)
        return cls.ramp(o["end_speed_rpm"], o["ramp_time"], control, start_rpm=start, **load)


def check_settings(kind: str, settings: dict) -> None:
    """Refuse an unknown scenario, or a ramp's setting given to another one, before any work."""
    check_choice(kind, "scenario", KINDS)
    if kind != "ramp":
        for name in RAMP_ONLY:
            if settings.get(name) is not None:
                raise ModelError(
                    "belongs to the ramp scenario (the closed speed loop)",
                    field=name,
                    valid='scenario "ramp", or leave it out',
                )
    if kind != "sine" and settings.get("steady"):
        raise ModelError(
            "is a sine's start on its steady oscillation",
            field="steady",
            value=settings["steady"],
            has_value=True,
            valid='scenario "sine", or leave it out',
        )


def torque_disturbance(scenario: Scenario, t: np.ndarray, dt: float, r: np.ndarray | None) -> np.ndarray:
    """Torque ripple and noise added to the drive torque, N·m, held over each step."""
    d = np.zeros(t.size)
    if scenario.ripple:
        if r is not None:  # the set-point angle, the running sum of the held set-point speed
            angle = np.concatenate([[0.0], np.cumsum(r[:-1]) * dt])
        else:
            angle = scenario.speed_rpm * RPM * t
        d += scenario.ripple * np.sin(scenario.ripple_order * angle)
    if scenario.noise:
        d += scenario.noise * np.random.default_rng(scenario.seed).standard_normal(t.size)
    return d


def drive_torque(scenario: Scenario, t: np.ndarray, dt: float) -> np.ndarray:
    """The drive torque held over each step, N·m (open-loop scenarios)."""
    if scenario.kind == "step":
        return np.where(t >= scenario.time - 1e-12 * dt, scenario.torque, 0.0)
    if scenario.kind == "sine":
        # Sampled at the step's start and held: the ZOH input the discretisation assumes.
        drive = scenario.torque * np.sin(2 * np.pi * scenario.frequency_hz * t)
        for a, f in scenario.harmonics:
            drive = drive + a * np.sin(2 * np.pi * f * t)
        return drive
    if scenario.kind == "series":
        ts, Ts = scenario.series
        return np.interp(t, ts, Ts, left=0.0, right=0.0)
    return np.zeros(t.size)  # coast: everything off after t = 0


def setpoint(scenario: Scenario, t: np.ndarray) -> np.ndarray:
    """Speed set-point, rad/s: a ramp from the start speed to the end speed, then held."""
    start, end = scenario.speed_rpm * RPM, scenario.end_rpm * RPM
    if scenario.ramp_time == 0:
        return np.full(t.size, end)
    return start + (end - start) * np.clip(t / scenario.ramp_time, 0.0, 1.0)


def torque_limits(control: SpeedControl, speed) -> tuple:
    """The commanded torque's limits at the measured ``speed`` (rad/s, a number or an array), N·m:
    the torque limits, and within ``±power_limit/|ω|`` where the power limit is the tighter one."""
    speed = np.abs(np.asarray(speed, dtype=float))
    with np.errstate(divide="ignore"):
        reach = np.where(speed > 0.0, control.power_limit / np.where(speed > 0.0, speed, 1.0), np.inf)
    return np.maximum(control.torque_min, -reach), np.minimum(control.torque_max, reach)
