"""The study file: the set-ups of a drivetrain study and what to do with them, read and checked.

A study file is TOML. It names the set-ups (model files) and, optionally, the range of interest,
the damping assumption and the analyses: FRFs, forced responses, time runs with their spectra, a
Campbell diagram, a calibration, flexible-body exports, mode views and the bench's recordings
(``[[measurement]]``: identified, and the set-up calibrated to them). Everything has a default,
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

Its tables and keys are the schema :mod:`flexshaft.study.studyschema` (read by
:mod:`flexshaft.input.schema`), rendered as the documentation's study-file reference.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ..analysis.systemdamping import DAMPING_CHOICES, SYSTEM_DAMPING_RATIO
from ..errors import ModelError
from ..input.schema import read, read_entries, toml_file
from ..system.inputs import STUDY, read_bytes
from .studyschema import (
    CALIBRATION,
    CAMPBELL,
    DRIVETRAIN_FORMATS,
    EXPORT,
    EXPORT_FORMATS,
    FORCED,
    FRF,
    MAX_ENTRIES,
    MEASUREMENT,
    MODES,
    PART_EXTRA_FORMATS,
    SCENARIO_KEYS,
    SCENARIOS,
    SETUP,
    SIMULATE,
    STUDY_FILE,
    STUDY_TABLE,
    VIEWS,
)

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
    "MeasurementSpec",
    "read_study",
    "loads_study",
    "DAMPING_CHOICES",
    "EXPORT_FORMATS",
    "DRIVETRAIN_FORMATS",
    "DRIVETRAIN_ENTRY",
    "SCENARIOS",
]

#: The name a drivetrain export (no ``part``) is filed under, in the results and the output folder.
DRIVETRAIN_ENTRY = "drivetrain"


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

    input: str | None  # None: the driving end
    outputs: tuple[str, ...]
    setups: tuple[str, ...] | None = None
    from_hz: float = 0.1
    to_hz: float | None = None
    points: int = 2000


@dataclass(frozen=True)
class ForcedSpec:
    """A sinusoidal torque of ``amplitude`` (N·m) at ``input``, at each eigenfrequency."""

    input: str | None  # None: the driving end
    amplitude: float = 1000.0
    setups: tuple[str, ...] | None = None


@dataclass(frozen=True)
class SimulateSpec:
    """A time run and the spectra of its outputs.

    ``options`` holds the scenario's settings by the library's names (SI, speeds in rpm), as
    :meth:`flexshaft.analysis.scenario.Scenario.of` builds the scenario from them.
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
    """A part exported as a flexible body in ``formats``; or (``part`` None) the whole drivetrain, as an
    FMU between ``inputs`` and ``outputs`` and its modes as a universal file."""

    part: str | None
    formats: tuple[str, ...] = EXPORT_FORMATS
    setups: tuple[str, ...] | None = None
    modes: int | None = None
    cutoff_hz: float | None = None
    damping_ratio: float | None = None
    inputs: tuple[str, ...] | None = None
    outputs: tuple[str, ...] | None = None


@dataclass(frozen=True)
class ViewsSpec:
    """3D pictures of modes, numbered as ``flexshaft modes`` numbers them (None: the first three elastic)."""

    modes: tuple[int, ...] | None = None
    setups: tuple[str, ...] | None = None


@dataclass(frozen=True)
class MeasurementSpec:
    """A set-up's recordings: identified (as ``flexshaft identify``) and, given ``parameters``, the
    set-up calibrated to what the identification trusts.

    ``files`` are the paths the study file's ``files`` patterns matched, sorted, as strings;
    ``parameters`` the ``[[parameter]]`` tables as written (name, and percent, bounds or fixed).
    """

    setup: str
    files: tuple[str, ...]
    channels: tuple[str, ...]
    stations: dict | None = None
    max_hz: float | None = None
    min_hz: float | None = None
    parameters: tuple = ()
    starts: int = 1
    units: dict | None = None
    time_column: str | None = None
    group: str | None = None
    rate: float | None = None


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
    measurements: tuple[MeasurementSpec, ...] = ()

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


def _path(value: str, folder: Path) -> Path:
    """A path the file gives (a string the schema checked), relative to the study file's folder."""
    p = Path(value)
    return p if p.is_absolute() else folder / p


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


def _entries(doc: dict, key: str, source: str) -> list:
    """The tables of ``[[key]]`` (a missing key: none; ``[key]`` written where ``[[key]]`` was meant:
    one entry)."""
    value = doc.get(key)
    return read_entries([value] if isinstance(value, dict) else value, key, file=source, most=MAX_ENTRIES)


def _read_entries(doc: dict, key: str, table, source: str):
    """Each ``[[key]]`` entry read against ``table`` (defaults filled in), with its place
    (``[[key]] #N``)."""
    for k, data in enumerate(_entries(doc, key, source)):
        where = f"[[{key}]] #{k + 1}"
        yield where, read(data, table, file=source, where=where, field=key, fill=True)


def _known_setups(chosen, known: tuple[str, ...], source: str, where: str):
    """``setups`` of an entry, each a set-up of the file."""
    for n in chosen or ():
        if n not in known:
            raise ModelError(
                "no such set-up",
                file=source,
                component=where,
                field="setups",
                value=n,
                valid=", ".join(repr(k) for k in known),
            )
    return chosen


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
        t = read(data, SETUP, file=source, where=f"[[setup]] #{k + 1}", field="setup")
        model = _path(t["model"], folder)
        out.append(SetupSpec(t.get("name") or model.stem, model))
    _unique([s.name for s in out], source, "setup.name", "set-up")
    return tuple(out)


def _frf(doc, source, known):
    out = []
    for where, t in _read_entries(doc, "frf", FRF, source):
        if t.get("to_hz") is not None and not t["from_hz"] < t["to_hz"]:
            raise ModelError(
                "must be above from_hz",
                file=source,
                component=where,
                field="to_hz",
                value=t["to_hz"],
                unit="Hz",
                valid=f"> {t['from_hz']:g} Hz",
            )
        setups = _known_setups(t.get("setups"), known, source, where)
        out.append(FrfSpec(t.get("input"), t["outputs"], setups, t["from_hz"], t.get("to_hz"), t["points"]))
    return tuple(out)


def _forced(doc, source, known):
    out = []
    for where, t in _read_entries(doc, "forced", FORCED, source):
        out.append(
            ForcedSpec(t.get("input"), t["amplitude"], _known_setups(t.get("setups"), known, source, where))
        )
    return tuple(out)


def _simulate_where(data, k: int, source: str) -> str:
    """A run is named by its name once it has one (``[[simulate]] 'ramp'``), else by its number."""
    where = f"[[simulate]] #{k + 1}"
    if isinstance(data, dict) and "name" in data:
        try:
            return f"[[simulate]] {SIMULATE.field('name').value(data['name'], 'name')!r}"
        except ModelError as err:
            raise err.located(file=source, component=where) from None
    return where


def _simulate(doc, source, folder, known):
    out = []
    for k, data in enumerate(_entries(doc, "simulate", source)):
        where = _simulate_where(data, k, source)
        t = read(data, SIMULATE, file=source, where=where, field="simulate", fill=True)
        options = {lib: t[key] for key, lib in SCENARIO_KEYS.items() if key in t}
        spec = SimulateSpec(
            name=t["name"],
            scenario=t["scenario"],
            outputs=t["outputs"],
            options=options,
            setups=_known_setups(t.get("setups"), known, source, where),
            rate_hz=t["rate_hz"],
            duration_s=t.get("duration_s"),
            max_hz=t.get("max_hz"),
            series=_path(t["series"], folder) if "series" in t else None,
            column=t.get("column"),
            spectra=t.get("spectra"),
            orders=t["orders"],
            spectrogram=t.get("spectrogram"),
            decay=t.get("decay"),
        )
        _check_run(spec, source, where)
        out.append(spec)
    _unique([s.name for s in out], source, "simulate.name", "run")
    return tuple(out)


def _check_run(spec: SimulateSpec, source: str, where: str) -> None:
    """What a run's scenario needs, and spectra of its own outputs."""
    options = spec.options
    if spec.scenario == "csv" and (spec.series is None or spec.column is None):
        raise ModelError(
            "the csv scenario reads a torque history",
            file=source,
            component=where,
            field="series" if spec.series is None else "column",
            valid='series = "FILE.csv" and column = "NAME"',
        )
    if spec.scenario == "ramp" and ("end_speed_rpm" not in options or "ramp_time" not in options):
        raise ModelError(
            "a ramp needs its final speed and duration",
            file=source,
            component=where,
            field="end_speed_rpm" if "end_speed_rpm" not in options else "ramp_time_s",
            valid="end_speed_rpm = RPM and ramp_time_s = S",
        )
    for n in spec.spectra or ():
        if n not in spec.outputs:
            raise ModelError(
                "is not one of the run's outputs",
                file=source,
                component=where,
                field="spectra",
                value=n,
                valid=", ".join(repr(o) for o in spec.outputs),
            )


def _campbell(doc, source, known):
    if "campbell" not in doc:
        return None
    t = read(doc["campbell"], CAMPBELL, file=source, where="[campbell]", field="campbell", fill=True)
    setups = _known_setups(t.get("setups"), known, source, "[campbell]")
    return CampbellSpec(speed_rpm=t["speed_rpm"], orders=t["orders"], setups=setups)


def _calibration(doc, source, folder):
    if "calibration" not in doc:
        return None
    t = read(doc["calibration"], CALIBRATION, file=source, where="[calibration]", field="calibration")
    model = _path(t["model"], folder) if "model" in t else None
    return CalibrationSpec(_path(t["targets"], folder), model, t.get("starts"))


def _exports(doc, source, known):
    out = []
    for where, t in _read_entries(doc, "export", EXPORT, source):
        part = t.get("part")
        allowed = EXPORT_FORMATS + PART_EXTRA_FORMATS if part else DRIVETRAIN_FORMATS
        formats = t.get("formats") or (EXPORT_FORMATS if part else DRIVETRAIN_FORMATS)
        wrong = [f for f in formats if f not in allowed]
        if wrong:
            whose = "a part's export" if part else "the drivetrain's export (no part)"
            what = f"{whose} writes {', '.join(allowed)}"
            raise ModelError(
                "not for this export", file=source, field=f"{where}.formats", value=wrong[0], valid=what
            )
        keys = ("inputs", "outputs") if part else ("modes", "cutoff_hz", "damping_ratio")
        for key in keys:
            if t.get(key) is not None:
                valid = "a drivetrain export (no part)" if part else "a part's export (part = NAME)"
                raise ModelError(
                    "belongs to another export", file=source, field=f"{where}.{key}", valid=valid
                )
        spec = ExportSpec(
            part=part,
            formats=tuple(formats),
            setups=_known_setups(t.get("setups"), known, source, where),
            modes=t.get("modes"),
            cutoff_hz=t.get("cutoff_hz"),
            damping_ratio=t.get("damping_ratio"),
            inputs=t.get("inputs"),
            outputs=t.get("outputs"),
        )
        out.append(spec)
    _unique([e.part or DRIVETRAIN_ENTRY for e in out], source, "export.part", "exported part")
    return tuple(out)


def _matched(pattern: str, folder: Path, source: str, where: str) -> list[str]:
    """The files a ``files`` entry names: a glob's matches (sorted), or the one path; none is an error."""
    import glob

    path = _path(pattern, folder)
    if glob.has_magic(pattern):
        found = sorted(p for p in glob.glob(str(path)) if Path(p).is_file())
    else:
        found = [str(path)] if path.is_file() else []
    if not found:
        raise ModelError(
            "matches no file" if glob.has_magic(pattern) else "is not a file",
            file=source,
            component=where,
            field="files",
            value=pattern,
            valid=f"recordings relative to {folder}",
        )
    return found


def _measurements(doc, source, folder, known):
    from .measured import checked_parameters

    out = []
    for where, t in _read_entries(doc, "measurement", MEASUREMENT, source):
        _known_setups((t["setup"],), known, source, where)
        files = []
        for pattern in t["files"]:
            files += [f for f in _matched(pattern, folder, source, where) if f not in files]
        spec = MeasurementSpec(
            setup=t["setup"],
            files=tuple(files),
            channels=t["channels"],
            stations=t.get("stations"),
            max_hz=t.get("max_hz"),
            min_hz=t.get("min_hz"),
            parameters=tuple(checked_parameters(list(t["parameters"]), f"{source} {where}")),
            starts=t["starts"],
            units=t.get("units"),
            time_column=t.get("time_column"),
            group=t.get("group"),
            rate=t.get("rate"),
        )
        out.append(spec)
    _unique([m.setup for m in out], source, "measurement.setup", "measured set-up")
    return tuple(out)


def _views(doc, source, known):
    if "views" not in doc:
        return ViewsSpec()
    t = read(doc["views"], VIEWS, file=source, where="[views]", field="views")
    return ViewsSpec(modes=t.get("modes"), setups=_known_setups(t.get("setups"), known, source, "[views]"))


def _modes(doc, source):
    if "modes" not in doc:
        return ModesSpec()
    t = read(doc["modes"], MODES, file=source, where="[modes]", field="modes", fill=True)
    return ModesSpec(t.get("count"), t["mesh_check"])


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
    doc = read(toml_file(text, source, "a TOML study file"), STUDY_FILE, file=source)
    top = read(doc.get("study", {}), STUDY_TABLE, file=source, where="[study]", field="study", fill=True)
    setups = _setups(doc, source, folder)
    known = tuple(s.name for s in setups)
    return Study(
        name=top.get("name", Path(source).stem),
        source=Path(source),
        setups=setups,
        max_hz=top.get("max_hz"),
        damping=top["damping"],
        system_damping_ratio=top["system_damping_ratio"],
        modes=_modes(doc, source),
        frf=_frf(doc, source, known),
        forced=_forced(doc, source, known),
        simulate=_simulate(doc, source, folder, known),
        campbell=_campbell(doc, source, known),
        calibration=_calibration(doc, source, folder),
        exports=_exports(doc, source, known),
        views=_views(doc, source, known),
        measurements=_measurements(doc, source, folder, known),
    )


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
