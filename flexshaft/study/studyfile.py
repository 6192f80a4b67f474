"""The study file: the set-ups of a drivetrain study and what to do with them, read and checked.

A study file is TOML. It names the set-ups (model files) and, optionally, the range of interest,
the damping assumption and the analyses: FRFs, forced responses, time runs with their spectra, a
Campbell diagram, a calibration, flexible-body exports and mode views. Everything has a default,
so a file with only ``[[setup]]`` tables does the modal study. Relative paths are relative to the
study file. Unknown keys are errors; every value is checked here, before any work, and an error
names the file, the table and the key::

    [study]
    name = "PTSS test bench"
    max_hz = 400.0                  # Hz: the range of interest
    damping = "both"                # "parts" | "system" | "both"
    system_damping_ratio = 0.0053

    [[setup]]
    model = "customer1_cad.toml"

See the README's "The whole study in one command" for every table and key.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..analysis.systemdamping import DAMPING_CHOICES, SYSTEM_DAMPING_RATIO
from ..errors import ModelError
from ..input.quantities import si_value
from ..system.inputs import STUDY, read_bytes
from ..validation import MAX_FREQUENCY_HZ, check_choice, check_int, check_name, check_real

__all__ = [
    "Study",
    "SetupSpec",
    "ModesSpec",
    "FrfSpec",
    "ForcedSpec",
    "SimulateSpec",
    "CampbellSpec",
    "CalibrationSpec",
    "ExportSpec",
    "ViewsSpec",
    "read_study",
    "loads_study",
    "DAMPING_CHOICES",
    "EXPORT_FORMATS",
    "SCENARIOS",
]

#: The flexible-body formats an export writes (as ``flexshaft reduce -o``).
EXPORT_FORMATS = ("npz", "json", "mat", "op4", "pch")
#: The time-run scenarios (as ``flexshaft simulate --scenario``).
SCENARIOS = ("ramp", "step", "sine", "coast", "csv")
#: The most set-ups, runs, FRFs ... a study file may list: each is a stage of work.
MAX_ENTRIES = 50
#: Highest speed a study asks for, rpm (as ``flexshaft campbell --speed``'s ceiling).
MAX_RPM = 1e6


@dataclass(frozen=True)
class SetupSpec:
    """One set-up: a model file, and the name the study gives it."""

    name: str
    model: Path


@dataclass(frozen=True)
class ModesSpec:
    """The modal study: how many modes (None: up to ``max_hz``, else the lowest 20), the mesh check."""

    count: int | None = None
    mesh_check: bool = True


@dataclass(frozen=True)
class FrfSpec:
    """A frequency response from one input to named outputs, ``from_hz`` to ``to_hz`` (Hz)."""

    input: str
    outputs: tuple[str, ...]
    setups: tuple[str, ...] | None = None
    from_hz: float = 0.1
    to_hz: float | None = None
    points: int = 2000


@dataclass(frozen=True)
class ForcedSpec:
    """A sinusoidal torque of ``amplitude`` (N·m) at ``input``, at each eigenfrequency."""

    input: str
    amplitude: float = 1000.0
    setups: tuple[str, ...] | None = None


@dataclass(frozen=True)
class SimulateSpec:
    """A time run and the spectra of its outputs.

    ``options`` holds the scenario's settings by the library's names (SI, speeds in rpm), as
    :func:`flexshaft.study.stages.scenario_of` builds the scenario from them.
    """

    name: str
    scenario: str
    outputs: tuple[str, ...]
    options: dict = field(default_factory=dict)
    setups: tuple[str, ...] | None = None
    rate_hz: float = 1000.0
    duration_s: float | None = None
    max_hz: float | None = None
    series: Path | None = None
    column: str | None = None
    spectra: tuple[str, ...] | None = None
    orders: tuple[float, ...] = (1.0, 2.0, 6.0)
    spectrogram: bool | None = None
    decay: bool | None = None


@dataclass(frozen=True)
class CampbellSpec:
    """A Campbell diagram over ``speed_rpm`` with ``orders``."""

    speed_rpm: tuple[float, float] = (0.0, 1800.0)
    orders: tuple[float, ...] = (1.0, 2.0, 6.0)
    setups: tuple[str, ...] | None = None


@dataclass(frozen=True)
class CalibrationSpec:
    """A calibration: a ``flexshaft calibrate`` targets file, and the model of stages naming none."""

    targets: Path
    model: Path | None = None
    starts: int | None = None


@dataclass(frozen=True)
class ExportSpec:
    """A part exported as a flexible body in ``formats``."""

    part: str
    formats: tuple[str, ...] = EXPORT_FORMATS
    setups: tuple[str, ...] | None = None
    modes: int | None = None
    cutoff_hz: float | None = None
    damping_ratio: float | None = None


@dataclass(frozen=True)
class ViewsSpec:
    """3D pictures of modes, numbered as ``flexshaft modes`` numbers them (None: the first three elastic)."""

    modes: tuple[int, ...] | None = None
    setups: tuple[str, ...] | None = None


@dataclass(frozen=True)
class Study:
    """A study file, read and checked.

    Attributes
    ----------
    name : str
    source : Path
        The study file.
    max_hz : float or None
        The range of interest, Hz.
    damping : str
        One of :data:`DAMPING_CHOICES`.
    system_damping_ratio : float
        The ratio of the first two system modes under ``"system"`` damping (fraction).
    setups : tuple of SetupSpec
    """

    name: str
    source: Path
    setups: tuple[SetupSpec, ...]
    max_hz: float | None = None
    damping: str = "parts"
    system_damping_ratio: float = SYSTEM_DAMPING_RATIO
    modes: ModesSpec = ModesSpec()
    frf: tuple[FrfSpec, ...] = ()
    forced: tuple[ForcedSpec, ...] = ()
    simulate: tuple[SimulateSpec, ...] = ()
    campbell: CampbellSpec | None = None
    calibration: CalibrationSpec | None = None
    exports: tuple[ExportSpec, ...] = ()
    views: ViewsSpec = ViewsSpec()

    @property
    def variants(self) -> tuple[str, ...]:
        """The damping assumptions the responses are computed with: ("parts",), ("system",) or both."""
        return ("parts", "system") if self.damping == "both" else (self.damping,)

    def setup(self, name: str) -> SetupSpec:
        """The set-up called ``name``."""
        for s in self.setups:
            if s.name == name:
                return s
        raise KeyError(name)

    def setups_of(self, chosen: tuple[str, ...] | None) -> tuple[str, ...]:
        """The set-up names an entry applies to (all of them when it names none)."""
        return tuple(s.name for s in self.setups) if chosen is None else chosen


class _Table:
    """One TOML table being read: its keys are taken one by one, the rest are unknown keys."""

    def __init__(self, data, where: str, source: str, folder: Path):
        if not isinstance(data, dict):
            raise ModelError("is not a table", file=source, field=where, valid="a TOML table")
        self.data = dict(data)
        self.where = where
        self.source = source
        self.folder = folder

    def error(self, err: ModelError) -> ModelError:
        """``err`` located in this table of the study file."""
        return err.replaced(file=self.source, component=self.where)

    def take(self, key: str, check, default=None):
        """The checked value of ``key`` (``check(value, key)``), or ``default`` when it is absent."""
        if key not in self.data:
            return default
        value = self.data.pop(key)
        try:
            return check(value, key)
        except ModelError as err:
            raise self.error(err) from None

    def need(self, key: str, check, what: str, valid: str):
        """The checked value of a key the table must have; its absence is an error naming it."""
        value = self.take(key, check)
        if value is None:
            raise ModelError(f"needs {what}", file=self.source, component=self.where, field=key, valid=valid)
        return value

    def done(self, allowed: tuple[str, ...]) -> None:
        """Refuse the keys nobody took."""
        if self.data:
            key = sorted(self.data)[0]
            raise ModelError(
                "unknown key",
                file=self.source,
                component=self.where,
                field=key,
                valid="one of " + ", ".join(allowed),
            )


# --- value checks: (value, key) -> the value, or a ModelError naming key --------------------------


def _name(value, key):
    return check_name(value, key)


def _names(value, key):
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not value or len(value) > MAX_ENTRIES:
        raise ModelError(
            "is not a list of names",
            field=key,
            value=value,
            has_value=True,
            valid=f"a name or a list of 1 to {MAX_ENTRIES} names",
        )
    names = tuple(check_name(v, key) for v in value)
    if len(set(names)) != len(names):
        raise ModelError("names one thing twice", field=key, value=value, valid="each name once")
    return names


def _hz(value, key):
    return check_real(si_value(value, key, "Hz"), key, "Hz", lo=0.0, lo_open=True, hi=MAX_FREQUENCY_HZ)


def _hz0(value, key):
    return check_real(si_value(value, key, "Hz"), key, "Hz", lo=0.0, hi=MAX_FREQUENCY_HZ)


def _seconds(value, key):
    return check_real(si_value(value, key, "s"), key, "s", lo=0.0, lo_open=True, hi=1e7)


def _seconds0(value, key):
    return check_real(si_value(value, key, "s"), key, "s", lo=0.0, hi=1e7)


def _rpm(value, key):
    return check_real(value, key, "rpm", lo=-MAX_RPM, hi=MAX_RPM)


def _torque(value, key):
    return check_real(value, key, "N·m", lo=-1e12, hi=1e12)


def _positive_torque(value, key):
    return check_real(value, key, "N·m", lo=0.0, lo_open=True, hi=1e12)


def _ratio(value, key):
    return check_real(value, key, "", lo=0.0, hi=1.0, hi_open=True)


def _bool(value, key):
    if not isinstance(value, bool):
        raise ModelError(
            "is not true or false", field=key, value=value, has_value=True, valid="true or false"
        )
    return value


def _whole(lo, hi):
    def check(value, key):
        return check_int(value, key, lo=lo, hi=hi)

    return check


def _orders(value, key):
    if not isinstance(value, list) or not value or len(value) > MAX_ENTRIES:
        raise ModelError(
            "is not a list of orders", field=key, value=value, has_value=True, valid="e.g. [1, 2, 6]"
        )
    return tuple(check_real(v, key, "", lo=0.0, lo_open=True, hi=1e6) for v in value)


def _choice(choices):
    def check(value, key):
        return check_choice(value, key, choices)

    return check


def _speed_range(value, key):
    if not (isinstance(value, list) and len(value) == 2):
        raise ModelError(
            "is not [low, high]", field=key, value=value, has_value=True, unit="rpm", valid="e.g. [0, 1800]"
        )
    lo, hi = (_rpm(v, key) for v in value)
    if not lo < hi:
        raise ModelError(
            "low is not below high", field=key, value=value, unit="rpm", valid="[low, high], low < high"
        )
    return (lo, hi)


def _modes_list(value, key):
    if not isinstance(value, list) or not value or len(value) > MAX_ENTRIES:
        raise ModelError(
            "is not a list of mode numbers",
            field=key,
            value=value,
            has_value=True,
            valid=f"1 to {MAX_ENTRIES} mode numbers as `flexshaft modes` numbers them, e.g. [1, 2, 3]",
        )
    return tuple(check_int(v, key, lo=0) for v in value)


def _formats(value, key):
    names = _names(value, key)
    for n in names:
        check_choice(n, key, EXPORT_FORMATS)
    return names


# --- the tables ------------------------------------------------------------------------------------


def _path(folder: Path):
    def check(value, key):
        if not isinstance(value, str) or not value.strip() or "\0" in value:
            raise ModelError("is not a path", field=key, value=value, has_value=True, valid="a file path")
        p = Path(value)
        return p if p.is_absolute() else folder / p

    return check


def _entries(doc: dict, key: str, source: str) -> list:
    """The tables of ``[[key]]`` (a missing key: none)."""
    value = doc.pop(key, [])
    if isinstance(value, dict):  # [key] written where [[key]] was meant: one entry
        value = [value]
    if not isinstance(value, list) or len(value) > MAX_ENTRIES:
        raise ModelError(
            "is not a list of tables",
            file=source,
            field=key,
            valid=f"[[{key}]] tables, at most {MAX_ENTRIES}",
        )
    return value


def slug(text: str) -> str:
    """``text`` as a file-name piece: lower case, runs of other characters as one ``-``."""
    s = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return s or "x"


def _unique(names: list[str], source: str, field: str, what: str) -> None:
    """Refuse a name two entries share (set-ups, runs, exported parts): results are filed under it,
    and so are files in the output folder, by its :func:`slug` - two names of one slug ("Customer 1",
    "customer-1") would write each other's files."""
    seen: dict[str, str] = {}
    for n in names:
        if names.count(n) > 1:
            raise ModelError(
                f"two {what}s have this name", file=source, field=field, value=n, valid=f"a name per {what}"
            )
        other = seen.setdefault(slug(n), n)
        if other != n:
            raise ModelError(
                f"names its files {slug(n)!r}, as the {what} {other!r} does",
                file=source,
                field=field,
                value=n,
                valid=f"{what} names that differ in more than case and punctuation",
            )


def _setups(doc, source, folder) -> tuple[SetupSpec, ...]:
    entries = _entries(doc, "setup", source)
    if not entries:
        raise ModelError(
            "names no set-up",
            file=source,
            field="setup",
            valid='at least one [[setup]] with model = "FILE.toml"',
        )
    out = []
    for k, data in enumerate(entries):
        t = _Table(data, f"[[setup]] #{k + 1}", source, folder)
        model = t.need("model", _path(folder), "a model file", 'model = "FILE.toml"')
        name = t.take("name", _name, default=None)
        t.done(("name", "model"))
        out.append(SetupSpec(name or model.stem, model))
    _unique([s.name for s in out], source, "setup.name", "set-up")
    return tuple(out)


def _setup_names(value, key):
    """``setups``: a name or names; ``[]`` turns the entry off (no set-up)."""
    return () if value == [] else _names(value, key)


def _known_setups(t: _Table, known: tuple[str, ...]):
    chosen = t.take("setups", _setup_names)
    for n in chosen or ():
        if n not in known:
            raise ModelError(
                "no such set-up",
                file=t.source,
                component=t.where,
                field="setups",
                value=n,
                valid=", ".join(repr(k) for k in known),
            )
    return chosen


def _frf(doc, source, folder, known):
    out = []
    for k, data in enumerate(_entries(doc, "frf", source)):
        t = _Table(data, f"[[frf]] #{k + 1}", source, folder)
        setups = _known_setups(t, known)
        inp = t.take("input", _name, default="motor")
        outputs = t.need("outputs", _names, "its outputs", 'e.g. ["speed:motor"]')
        # 0.1 Hz as `flexshaft frf`: a free drivetrain's rigid-body mode makes 0 Hz infinite
        f_from = t.take("from_hz", _hz0, default=0.1)
        f_to = t.take("to_hz", _hz, default=None)
        if f_to is not None and not f_from < f_to:
            raise ModelError(
                "must be above from_hz",
                file=source,
                component=t.where,
                field="to_hz",
                value=f_to,
                unit="Hz",
                valid=f"> {f_from:g} Hz",
            )
        points = t.take("points", _whole(2, 100_000), default=2000)
        t.done(("setups", "input", "outputs", "from_hz", "to_hz", "points"))
        out.append(FrfSpec(inp, outputs, setups, f_from, f_to, points))
    return tuple(out)


def _forced(doc, source, folder, known):
    out = []
    for k, data in enumerate(_entries(doc, "forced", source)):
        t = _Table(data, f"[[forced]] #{k + 1}", source, folder)
        setups = _known_setups(t, known)
        inp = t.take("input", _name, default="motor")
        amplitude = t.take("amplitude", _positive_torque, default=1000.0)
        t.done(("setups", "input", "amplitude"))
        out.append(ForcedSpec(inp, amplitude, setups))
    return tuple(out)


#: simulate's scenario keys: the study file's key -> (the library's name, its check)
_SCENARIO_KEYS = {
    "end_speed_rpm": ("end_speed_rpm", _rpm),
    "ramp_time_s": ("ramp_time", _seconds),
    "speed_rpm": ("speed_rpm", _rpm),
    "torque": ("torque", _torque),
    "frequency_hz": ("frequency_hz", _hz),
    "step_time_s": ("step_time", _seconds0),
    "at": ("at", _name),
    "load": ("load", _torque),
    "load_at": ("load_at", _name),
    "bandwidth_hz": ("bandwidth_hz", _hz),
    "kp": ("kp", lambda v, k: check_real(v, k, "N·m·s/rad", lo=0.0, lo_open=True, hi=1e15)),
    "ki": ("ki", lambda v, k: check_real(v, k, "N·m/rad", lo=0.0, hi=1e18)),
    "tau_s": ("tau", _seconds),
    "torque_limit": ("torque_limit", _positive_torque),
    "measure": ("measure", _name),
}


def _simulate(doc, source, folder, known):
    out = []
    for k, data in enumerate(_entries(doc, "simulate", source)):
        t = _Table(data, f"[[simulate]] #{k + 1}", source, folder)
        name = t.need("name", _name, "a name", 'e.g. name = "speed ramp"')
        t.where = f"[[simulate]] {name!r}"
        setups = _known_setups(t, known)
        scenario = t.take("scenario", _choice(SCENARIOS), default="ramp")
        outputs = t.need("outputs", _names, "its outputs", 'e.g. ["torque:part 3"]')
        options = {
            lib: v for key, (lib, check) in _SCENARIO_KEYS.items() if (v := t.take(key, check)) is not None
        }
        spec = SimulateSpec(
            name=name,
            scenario=scenario,
            outputs=outputs,
            options=options,
            setups=setups,
            rate_hz=t.take("rate_hz", _hz, default=1000.0),
            duration_s=t.take("duration_s", _seconds, default=None),
            max_hz=t.take("max_hz", _hz, default=None),
            series=t.take("series", _path(folder)),
            column=t.take("column", _name),
            spectra=t.take("spectra", _names),
            orders=t.take("orders", _orders, default=(1.0, 2.0, 6.0)),
            spectrogram=t.take("spectrogram", _bool),
            decay=t.take("decay", _bool),
        )
        t.done(
            ("name", "setups", "scenario", "outputs", "rate_hz", "duration_s", "max_hz", "series", "column")
            + ("spectra", "orders", "spectrogram", "decay")
            + tuple(_SCENARIO_KEYS)
        )
        if scenario == "csv" and (spec.series is None or spec.column is None):
            raise ModelError(
                "the csv scenario reads a torque history",
                file=source,
                component=t.where,
                field="series" if spec.series is None else "column",
                valid='series = "FILE.csv" and column = "NAME"',
            )
        if scenario == "ramp" and ("end_speed_rpm" not in options or "ramp_time" not in options):
            raise ModelError(
                "a ramp needs its final speed and duration",
                file=source,
                component=t.where,
                field="end_speed_rpm" if "end_speed_rpm" not in options else "ramp_time_s",
                valid="end_speed_rpm = RPM and ramp_time_s = S",
            )
        for n in spec.spectra or ():
            if n not in outputs:
                raise ModelError(
                    "is not one of the run's outputs",
                    file=source,
                    component=t.where,
                    field="spectra",
                    value=n,
                    valid=", ".join(repr(o) for o in outputs),
                )
        out.append(spec)
    _unique([s.name for s in out], source, "simulate.name", "run")
    return tuple(out)


def _campbell(doc, source, folder, known):
    if "campbell" not in doc:
        return None
    t = _Table(doc.pop("campbell"), "[campbell]", source, folder)
    spec = CampbellSpec(
        speed_rpm=t.take("speed_rpm", _speed_range, default=(0.0, 1800.0)),
        orders=t.take("orders", _orders, default=(1.0, 2.0, 6.0)),
        setups=_known_setups(t, known),
    )
    t.done(("speed_rpm", "orders", "setups"))
    return spec


def _calibration(doc, source, folder):
    if "calibration" not in doc:
        return None
    t = _Table(doc.pop("calibration"), "[calibration]", source, folder)
    targets = t.need("targets", _path(folder), "a targets file", 'targets = "TARGETS.toml"')
    spec = CalibrationSpec(targets, t.take("model", _path(folder)), t.take("starts", _whole(1, 1000)))
    t.done(("targets", "model", "starts"))
    return spec


def _exports(doc, source, folder, known):
    out = []
    for k, data in enumerate(_entries(doc, "export", source)):
        t = _Table(data, f"[[export]] #{k + 1}", source, folder)
        setups = _known_setups(t, known)
        part = t.need("part", _name, "a part", 'part = "NAME"')
        spec = ExportSpec(
            part=part,
            formats=t.take("formats", _formats, default=EXPORT_FORMATS),
            setups=setups,
            modes=t.take("modes", _whole(0, 10_000)),
            cutoff_hz=t.take("cutoff_hz", _hz),
            damping_ratio=t.take("damping_ratio", _ratio),
        )
        t.done(("setups", "part", "formats", "modes", "cutoff_hz", "damping_ratio"))
        out.append(spec)
    _unique(sorted({e.part for e in out}), source, "export.part", "exported part")
    return tuple(out)


def _views(doc, source, folder, known):
    if "views" not in doc:
        return ViewsSpec()
    t = _Table(doc.pop("views"), "[views]", source, folder)
    spec = ViewsSpec(modes=t.take("modes", _modes_list), setups=_known_setups(t, known))
    t.done(("modes", "setups"))
    return spec


def _modes(doc, source, folder):
    if "modes" not in doc:
        return ModesSpec()
    t = _Table(doc.pop("modes"), "[modes]", source, folder)
    spec = ModesSpec(t.take("count", _whole(1, 100_000)), t.take("mesh_check", _bool, default=True))
    t.done(("count", "mesh_check"))
    return spec


def loads_study(text: str, source: str = "<string>", *, folder=None) -> Study:
    """Read a study file's text.

    Parameters
    ----------
    text : str
        TOML.
    source : str
        Where it came from, for messages.
    folder : str or Path, optional
        What relative paths are relative to (default: the working directory).

    Returns
    -------
    Study
    """
    folder = Path(folder) if folder is not None else Path.cwd()
    from ..system.nesting import toml_document

    try:
        doc = toml_document(text, source)  # nesting refused before the parser recurses
    except tomllib.TOMLDecodeError as err:
        raise ModelError(f"is not valid TOML ({err})", file=source, valid="a TOML study file") from None
    top = _Table(doc.pop("study", {}), "[study]", source, folder)
    name = top.take("name", _name, default=Path(source).stem)
    max_hz = top.take("max_hz", _hz, default=None)
    damping = top.take("damping", _choice(DAMPING_CHOICES), default="parts")
    ratio = top.take("system_damping_ratio", _ratio, default=SYSTEM_DAMPING_RATIO)
    top.done(("name", "max_hz", "damping", "system_damping_ratio"))
    setups = _setups(doc, source, folder)
    known = tuple(s.name for s in setups)
    study = Study(
        name=name,
        source=Path(source),
        setups=setups,
        max_hz=max_hz,
        damping=damping,
        system_damping_ratio=ratio,
        modes=_modes(doc, source, folder),
        frf=_frf(doc, source, folder, known),
        forced=_forced(doc, source, folder, known),
        simulate=_simulate(doc, source, folder, known),
        campbell=_campbell(doc, source, folder, known),
        calibration=_calibration(doc, source, folder),
        exports=_exports(doc, source, folder, known),
        views=_views(doc, source, folder, known),
    )
    if doc:
        key = sorted(doc)[0]
        raise ModelError(
            "unknown table",
            file=source,
            field=key,
            valid="study, setup, modes, frf, forced, simulate, campbell, calibration, export, views",
        )
    return study


def read_study(path) -> Study:
    """Read a study file (a regular file of at most 1 MB, see :mod:`flexshaft.system.inputs`).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    Study
    """
    data = read_bytes(path, STUDY)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ModelError(
            f"is not UTF-8 text (byte {err.start})", file=str(path), valid="a TOML study file in UTF-8"
        ) from None
    return loads_study(text, source=str(path), folder=Path(path).parent)
