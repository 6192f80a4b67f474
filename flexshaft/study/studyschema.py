"""The study file's schema: every table and key, with its unit, range, default and meaning
(:mod:`flexshaft.input.schema`). :mod:`flexshaft.study.studyfile` reads by it, and the
documentation's study-file reference (``docs/reference/study-file.md``)
is rendered from it (``tools/schema_docs.py``).
"""

from __future__ import annotations

from ..analysis.systemdamping import DAMPING_CHOICES, SYSTEM_DAMPING_RATIO
from ..errors import ModelError
from ..input.schema import REQUIRED, Field, Table, top_level
from ..validation import FRACTION, FREQUENCY, POSITIVE_FREQUENCY, Domain, check_choice, check_int, check_name

__all__ = ["STUDY_FILE", "STUDY_TABLE", "SETUP", "MODES", "FRF", "FORCED", "SIMULATE", "CAMPBELL"]
__all__ += [
    "CALIBRATION",
    "EXPORT",
    "VIEWS",
    "MEASUREMENT",
    "SCENARIO_KEYS",
    "EXPORT_FORMATS",
    "DRIVETRAIN_FORMATS",
    "PART_EXTRA_FORMATS",
    "SCENARIOS",
    "MAX_ENTRIES",
]

#: The flexible-body formats an export writes (as ``flexshaft reduce -o``).
EXPORT_FORMATS = ("npz", "json", "mat", "op4", "pch")
#: What a part's export may write besides: its free-free modes as a universal file (``reduce -o PART.uff``).
PART_EXTRA_FORMATS = ("uff",)
#: What an export of the whole drivetrain (no ``part``) writes: an FMU (``flexshaft fmu``) and the modes
#: as a universal file (``flexshaft modes --uff``).
DRIVETRAIN_FORMATS = ("fmu", "uff")
#: Every format an export may name.
_ANY_FORMAT = tuple(dict.fromkeys(EXPORT_FORMATS + PART_EXTRA_FORMATS + DRIVETRAIN_FORMATS))
#: The time-run scenarios (as ``flexshaft simulate --scenario``).
SCENARIOS = ("ramp", "step", "sine", "coast", "csv")
#: The most set-ups, runs, FRFs ... a study file may list: each is a stage of work.
MAX_ENTRIES = 50
#: Highest speed a study asks for, rpm (as ``flexshaft campbell --speed``'s ceiling).
MAX_RPM = 1e6

SECONDS = Domain(0.0, True, 1e7, False, "s")
SECONDS0 = Domain(0.0, False, 1e7, False, "s")
RPM = Domain(-MAX_RPM, False, MAX_RPM, False, "rpm")
TORQUE = Domain(-1e12, False, 1e12, False, "N·m")
POSITIVE_TORQUE = Domain(0.0, True, 1e12, False, "N·m")
ORDER = Domain(0.0, True, 1e6, False)


# --- value checks beyond a field's kind: (value, key) -> the value, or a ModelError naming key ------


def _listed(value, key, what: str) -> list:
    """``value`` as a list of 1 to :data:`MAX_ENTRIES` entries (one string alone is a list of one)."""
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not value or len(value) > MAX_ENTRIES:
        raise ModelError(
            f"is not a list of {what}s",
            field=key,
            value=value,
            has_value=True,
            valid=f"a {what} or a list of 1 to {MAX_ENTRIES} {what}s",
        )
    return value


def _names(value, key):
    names = tuple(check_name(v, key) for v in _listed(value, key, "name"))
    if len(set(names)) != len(names):
        raise ModelError("names one thing twice", field=key, value=value, valid="each name once")
    return names


def _setup_names(value, key):
    """``setups``: a name or names; ``[]`` turns the entry off (no set-up)."""
    return () if value == [] else _names(value, key)


def _orders(value, key):
    if not isinstance(value, list) or not value or len(value) > MAX_ENTRIES:
        raise ModelError(
            "is not a list of orders", field=key, value=value, has_value=True, valid="e.g. [1, 2, 6]"
        )
    return tuple(ORDER.check(v, key) for v in value)


def _speed_range(value, key):
    if not (isinstance(value, list) and len(value) == 2):
        raise ModelError(
            "is not [low, high]", field=key, value=value, has_value=True, unit="rpm", valid="e.g. [0, 1800]"
        )
    lo, hi = (RPM.check(v, key) for v in value)
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
        check_choice(n, key, _ANY_FORMAT)
    return names


def _path_text(value, key):
    """A path as the file writes it (the reader makes it relative to the study file)."""
    if not isinstance(value, str) or not value.strip() or "\0" in value:
        raise ModelError("is not a path", field=key, value=value, has_value=True, valid="a file path")
    return value


def _file_patterns(value, key):
    """``files``: paths or globs, each as the file writes it (expanded by the reader)."""
    return tuple(_path_text(v, key) for v in _listed(value, key, "path"))


def _channel_map(value, key):
    """A channel -> text table (``stations``, ``units``)."""
    if not isinstance(value, dict) or len(value) > MAX_ENTRIES:
        raise ModelError(
            "is not a table of channel names",
            field=key,
            value=value,
            has_value=True,
            valid='{ "CHANNEL" = "TEXT" }',
        )
    return {check_name(k, key): check_name(v, f"{key}.{k}") for k, v in value.items()}


def _parameter_tables(value, key):
    """``parameters``: inline tables, each read as a targets file's ``[[parameter]]`` by the reader."""
    if not isinstance(value, list) or len(value) > MAX_ENTRIES or not all(isinstance(v, dict) for v in value):
        raise ModelError(
            "is not a list of parameter tables",
            field=key,
            value=value,
            has_value=True,
            valid='[{ name = "part 2.stiffness", percent = 30 }, ...]',
        )
    return tuple(value)


# --- the tables ------------------------------------------------------------------------------------

_SETUPS = Field(
    "setups",
    kind="any",
    check=_setup_names,
    expects="a set-up name or a list of them",
    shown_default="every set-up",
    help="the set-ups the entry applies to; `[]` turns it off",
)
_INPUT = Field(
    "input",
    kind="name",
    shown_default="the driving end (first station)",
    help="the station the torque acts on",
)


def _outputs(example: str) -> Field:
    return Field(
        "outputs",
        kind="any",
        check=_names,
        default=REQUIRED,
        missing="needs its outputs",
        expects=f"e.g. {example}",
        help="signals as `flexshaft frf` names them (`angle:`, `speed:`, `torque:` and a station or part)",
    )


_ORDERS = Field(
    "orders",
    kind="any",
    check=_orders,
    default=(1.0, 2.0, 6.0),
    expects="list of orders > 0",
    help="order lines (multiples of the speed)",
)

STUDY_TABLE = Table(
    "[study]",
    (
        Field("name", kind="name", shown_default="file stem", help="the study's name in the report"),
        Field(
            "max_hz",
            domain=POSITIVE_FREQUENCY,
            help="the range of interest: meshes converged below it, modes listed up to it",
        ),
        Field(
            "damping",
            kind="choice",
            choices=DAMPING_CHOICES,
            default="parts",
            help="the damping assumption of the responses (see below)",
        ),
        Field(
            "system_damping_ratio",
            domain=FRACTION,
            default=SYSTEM_DAMPING_RATIO,
            help='the measured system damping, for `"system"`',
        ),
    ),
)
SETUP = Table(
    "[[setup]]",
    (
        Field("name", kind="name", shown_default="the model file's stem", help="the set-up's name"),
        Field(
            "model",
            kind="any",
            check=_path_text,
            default=REQUIRED,
            missing="needs a model file",
            expects='model = "FILE.toml"',
            help="its model file, relative to the study file",
        ),
    ),
    help="at least one",
)
MODES = Table(
    "[modes]",
    (
        Field(
            "count",
            kind="integer",
            count=(1, 100_000),
            shown_default="up to `max_hz`, else 20",
            help="how many modes",
        ),
        Field("mesh_check", kind="bool", default=True, help="each mode's mesh error estimated"),
    ),
)
FRF = Table(
    "[[frf]]",
    (
        _SETUPS,
        _INPUT,
        _outputs('["speed:motor"]'),
        # 0.1 Hz as `flexshaft frf`: a free drivetrain's rigid-body mode makes 0 Hz infinite
        Field("from_hz", domain=FREQUENCY, default=0.1, help="lowest frequency"),
        Field(
            "to_hz",
            domain=POSITIVE_FREQUENCY,
            shown_default="1.5 × the highest mode kept",
            help="highest frequency, above `from_hz`",
        ),
        Field(
            "points",
            kind="integer",
            count=(2, 100_000),
            default=2000,
            help="frequencies, evenly spaced plus points around each resonance",
        ),
    ),
    help="repeatable: a frequency response from one input to named outputs",
)
FORCED = Table(
    "[[forced]]",
    (
        _SETUPS,
        _INPUT,
        Field("amplitude", domain=POSITIVE_TORQUE, default=1000.0, help="the sinusoidal torque's amplitude"),
    ),
    help="repeatable: a sinusoidal torque at each eigenfrequency, and the torque every part carries",
)

#: simulate's scenario keys: the study file's key -> the library's name
#: (:meth:`flexshaft.analysis.scenario.Scenario.of` builds the scenario from them).
SCENARIO_KEYS = {
    "end_speed_rpm": "end_speed_rpm",
    "ramp_time_s": "ramp_time",
    "speed_rpm": "speed_rpm",
    "torque": "torque",
    "frequency_hz": "frequency_hz",
    "step_time_s": "step_time",
    "at": "at",
    "load": "load",
    "load_at": "load_at",
    "bandwidth_hz": "bandwidth_hz",
    "kp": "kp",
    "ki": "ki",
    "tau_s": "tau",
    "torque_limit": "torque_limit",
    "power_limit": "power_limit",
    "measure": "measure",
    "steady": "steady",
}
_SCENARIO_FIELDS = (
    Field("end_speed_rpm", domain=RPM, help="a ramp's final speed (needed by `ramp`)"),
    Field("ramp_time_s", domain=SECONDS, help="a ramp's duration (needed by `ramp`)"),
    Field("speed_rpm", domain=RPM, help="the starting (or, coasting, the running) speed"),
    Field("torque", domain=TORQUE, help="a step's or sine's torque; the torque carried before a coast stop"),
    Field("frequency_hz", domain=POSITIVE_FREQUENCY, help="a sine's frequency"),
    Field("step_time_s", domain=SECONDS0, help="when a step acts"),
    Field("at", kind="name", help="the station the drive torque acts on"),
    Field("load", domain=TORQUE, help="a load torque"),
    Field("load_at", kind="name", help="the station the load acts on"),
    Field("bandwidth_hz", domain=POSITIVE_FREQUENCY, help="the speed loop's bandwidth"),
    Field("kp", domain=Domain(0.0, True, 1e15, False, "N·m·s/rad"), help="the speed loop's gain"),
    Field("ki", domain=Domain(0.0, False, 1e18, False, "N·m/rad"), help="the speed loop's integral gain"),
    Field("tau_s", domain=SECONDS, help="the motor's first-order lag"),
    Field("torque_limit", domain=POSITIVE_TORQUE, help="the drive's torque limit (anti-windup)"),
    Field(
        "power_limit",
        domain=Domain(0.0, True, unit="W"),
        help="the drive's power limit: the torque also within ±power_limit/|speed| (anti-windup)",
    ),
    Field("measure", kind="name", help="the station the speed loop measures"),
    Field(
        "steady",
        kind="bool",
        help="a sine's start on the linear line's steady oscillation instead of from rest (no start-up)",
    ),
)
SIMULATE = Table(
    "[[simulate]]",
    (
        Field(
            "name",
            kind="name",
            default=REQUIRED,
            missing="needs a name",
            expects='e.g. name = "speed ramp"',
            help="the run's name",
        ),
        _SETUPS,
        Field(
            "scenario",
            kind="choice",
            choices=SCENARIOS,
            default="ramp",
            help="what drives the line, as `flexshaft simulate --scenario`",
        ),
        _outputs('["torque:part 3"]'),
        Field("rate_hz", domain=POSITIVE_FREQUENCY, default=1000.0, help="sampling rate"),
        Field("duration_s", domain=SECONDS, shown_default="the scenario's", help="how long"),
        Field("max_hz", domain=POSITIVE_FREQUENCY, shown_default="the study's", help="the modes kept"),
        Field(
            "series",
            kind="any",
            check=_path_text,
            expects="a file path",
            help="`csv`: the torque history's file, relative to the study file",
        ),
        Field("column", kind="name", help="`csv`: its column"),
        Field(
            "spectra",
            kind="any",
            check=_names,
            expects="a list of outputs",
            shown_default="every output",
            help="the outputs whose spectra are computed",
        ),
        _ORDERS,
        Field(
            "spectrogram",
            kind="bool",
            shown_default="where the speed changes",
            help="a spectrogram with order lines",
        ),
        Field("decay", kind="bool", shown_default="`true` for a coast", help="the free decay's damping"),
    )
    + _SCENARIO_FIELDS,
    help="repeatable: a time run and the spectra of its outputs",
)
CAMPBELL = Table(
    "[campbell]",
    (
        Field(
            "speed_rpm",
            kind="any",
            check=_speed_range,
            default=(0.0, 1800.0),
            expects="[low, high] rpm",
            help="the speed range",
        ),
        _ORDERS,
        _SETUPS,
    ),
)
CALIBRATION = Table(
    "[calibration]",
    (
        Field(
            "targets",
            kind="any",
            check=_path_text,
            default=REQUIRED,
            missing="needs a targets file",
            expects='targets = "TARGETS.toml"',
            help="a `flexshaft calibrate` targets file",
        ),
        Field(
            "model",
            kind="any",
            check=_path_text,
            expects="a file path",
            shown_default="the first set-up's",
            help="the model of stages naming none",
        ),
        Field(
            "starts",
            kind="integer",
            count=(1, 1000),
            shown_default="the targets file's",
            help="starting points",
        ),
    ),
)
EXPORT = Table(
    "[[export]]",
    (
        _SETUPS,
        Field(
            "part",
            kind="name",
            expects='part = "NAME"',
            shown_default="the whole drivetrain",
            help="the part exported as a flexible body; without it, the set-up's whole drivetrain",
        ),
        Field(
            "formats",
            kind="any",
            check=_formats,
            expects="list of " + ", ".join(f"`{f}`" for f in _ANY_FORMAT),
            shown_default="a part: "
            + ", ".join(EXPORT_FORMATS)
            + "; the drivetrain: "
            + ", ".join(DRIVETRAIN_FORMATS),
            help="the files written: a part's flexible body (as `flexshaft reduce`; `uff` its free-free "
            "modes), or the drivetrain as an FMU (`flexshaft fmu`) and its modes as a universal file "
            "(`flexshaft modes --uff`)",
        ),
        Field(
            "inputs",
            kind="any",
            check=_names,
            expects="list of stations",
            shown_default="both ends",
            help="the drivetrain FMU's inputs: torques at these stations, N·m",
        ),
        Field(
            "outputs",
            kind="any",
            check=_names,
            expects="list of signals",
            shown_default="the speeds of both ends",
            help="the drivetrain FMU's outputs: `angle:`, `speed:` or `torque:` signals",
        ),
        Field("modes", kind="integer", count=(0, 10_000), help="fixed-interface modes kept"),
        Field(
            "cutoff_hz", domain=POSITIVE_FREQUENCY, shown_default="`max_hz`", help="or every mode below it"
        ),
        Field("damping_ratio", domain=FRACTION, shown_default="the part's", help="the body's modes' ratio"),
    ),
    help="repeatable",
)
VIEWS = Table(
    "[views]",
    (
        Field(
            "modes",
            kind="any",
            check=_modes_list,
            expects="list of mode numbers",
            shown_default="the first three elastic",
            help="numbered as `flexshaft modes` numbers them",
        ),
        _SETUPS,
    ),
)
MEASUREMENT = Table(
    "[[measurement]]",
    (
        Field("setup", kind="name", default=REQUIRED, missing="needs its set-up", help="the set-up recorded"),
        Field(
            "files",
            kind="any",
            check=_file_patterns,
            default=REQUIRED,
            missing="needs its recordings",
            expects='["runs/c1_*.tdms"]',
            help="paths or globs, relative to the study file, in every format `identify` reads",
        ),
        Field(
            "channels",
            kind="any",
            check=_names,
            default=REQUIRED,
            missing="needs its channels",
            expects='["torque flange", "speed generator"]',
            help="the channels identified (every run must have them)",
        ),
        Field(
            "stations",
            kind="any",
            check=_channel_map,
            expects='{ "speed generator" = "generator" }',
            help="speed or angle channel -> model station: pairing by MAC, shapes as targets",
        ),
        Field("max_hz", domain=POSITIVE_FREQUENCY, shown_default="as `identify`", help="highest frequency"),
        Field("min_hz", domain=POSITIVE_FREQUENCY, shown_default="as `identify`", help="lowest frequency"),
        Field(
            "parameters",
            kind="any",
            check=_parameter_tables,
            default=(),
            expects='[{ name = "part 2.stiffness", percent = 30 }]',
            shown_default="none: identification only",
            help="what calibration may change, each as a targets file's `[[parameter]]`",
        ),
        Field("starts", kind="integer", count=(1, 1000), default=1, help="the calibration's starting points"),
        Field(
            "units", kind="any", check=_channel_map, expects='{ "CHANNEL" = "rpm" }', help="units files omit"
        ),
        Field("time_column", kind="name", help="a CSV file's time column"),
        Field("group", kind="name", help="a TDMS/HDF5 group"),
        Field("rate", domain=POSITIVE_FREQUENCY, help="the sampling rate of files without time"),
    ),
    help="repeatable, one per set-up",
)
#: The file's tables, in the order the reference lists them.
STUDY_TABLES = (
    "study",
    "setup",
    "modes",
    "frf",
    "forced",
    "simulate",
    "campbell",
    "calibration",
    "export",
    "views",
    "measurement",
)
#: The file's top level.
_TABLES = ("study", "modes", "campbell", "calibration", "views")  # the others: [[key]] (or one [key])
STUDY_FILE = top_level(
    "study file",
    {k: "table" if k in _TABLES else "any" for k in STUDY_TABLES},
    forms=", ".join(STUDY_TABLES),
    unknown="unknown table",
)
