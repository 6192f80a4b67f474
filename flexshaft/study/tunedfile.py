"""Tuned model files and calibration targets files.

A tuned model file is the original model file's document with the tuned values put in (SI
numbers), written as TOML: nothing else changes, so it loads as the original does and gives
the tuned model. A part from sections whose stiffness or inertia was tuned gets a material of
its own (``[materials."part 2 (tuned)"]``: its Young's modulus or density moved, ν kept), the
way the tuned number goes back to physics; a tuned material changes ``[materials.NAME]``. A tuned
damping ratio or damper goes into its ``[[chain]]`` entry (a flexible body's ``damping_ratio`` is its
own modes' ratio), tuned Rayleigh damping into ``[model] rayleigh`` in the form the file gives it
(``{alpha, beta}``, or the ratios at its two ``frequencies_hz``).

A targets file (TOML) says what to tune and to what::

    [options]                   # optional
    starts = 4                  # starting points (Latin hypercube in the bounds), default 1
    seed = 0

    [[target]]
    mode = 2                    # an elastic mode, numbered as `flexshaft modes` numbers them (0: rigid-body)
    ratio_to = 1                # or frequency_hz = 91.0
    ratio = 2.59
    tolerance = 0.02            # relative: 2 % (default 1 %)
    shape = [1.0, 0.4, -0.9]    # optional: the measured θx at the stations; checked against the mode (MAC)
    damping_ratio = 0.0053      # optional: the mode's measured damping ratio (fraction), or alone with mode
    damping_tolerance = 0.25    # relative: ±25 % of it (default 10 %)

    [[parameter]]
    name = "part 1.stiffness"   # COMPONENT.FIELD, MATERIAL.FIELD or rayleigh.alpha / rayleigh.beta
    percent = 10                # or bounds = [lo, hi] (SI), or fixed = value

A damping ratio is met by damping parameters (``part 1.damping_ratio``, ``part 3.damping``,
``rayleigh.alpha`` …; a damper may start at 0 with ``bounds``), frequencies and ratios by the
others: :func:`flexshaft.analysis.calibrate.calibrate`.

Mode numbers, shapes, names and bounds are checked against the model before anything is solved
(:func:`flexshaft.analysis.calibrate.check_problem`; the CLI checks every stage before the first
runs): an error names the entry as ``[[target]] #2`` or ``[[stage]] #2 [[target]] #1``.

Staged calibration (parts several set-ups share are tuned on one, then frozen for the others):
``[[stage]]`` tables, each with ``name``, optionally ``model`` (a model file relative to the
targets file; default the model given on the command line) and its own ``[[stage.target]]`` and
``[[stage.parameter]]``. Every parameter tuned in an earlier stage that the later stage's model
also has is carried into it, fixed; ``carry_from = ["shared parts"]`` limits that to the named
earlier stages (two DUT set-ups share parts 1-2, not their couplings).

The targets file's tables (:data:`TARGETS_FILE`, :data:`OPTIONS`, :data:`TARGET`, :data:`PARAMETER`,
:data:`STAGE`) are read by :mod:`flexshaft.input.schema`; a target's and a parameter's values are checked
by the :class:`~flexshaft.analysis.calibrate.Target` and :class:`~flexshaft.analysis.calibrate.Bound`
they make, as a calibration from Python checks them.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from ..analysis.calibrate import Bound, Target
from ..analysis.parameters import Parameter, parameters, with_parameters
from ..errors import ModelError
from ..input.schema import REQUIRED, Field, Table, read, toml_file, top_level
from ..linalg.damping import rayleigh_ratio
from ..model.components import Drivetrain, Shaft
from ..system.atomic import atomic_write_text
from ..system.inputs import MODEL, TARGETS, read_bytes, read_text
from ..system.limits import check_ceiling

__all__ = [
    "Stage",
    "TargetsFile",
    "read_targets",
    "loads_targets",
    "tuned_document",
    "dumps_toml",
    "write_tuned_model",
]
__all__ += ["TARGETS_FILE", "OPTIONS", "TARGET", "PARAMETER", "STAGE", "parameter_bound"]


def _parameter_name(value, key):
    if not isinstance(value, str):
        raise ModelError("missing or not a string", field=key, valid="COMPONENT.FIELD")
    return value


def _bounds(value, key):
    if not (isinstance(value, list) and len(value) == 2):
        raise ModelError("must be [lower, upper]", field=key, value=value)
    return tuple(value)


def _stage_model(value, key):
    if not isinstance(value, str) or not value or Path(value).is_absolute():
        raise ModelError(
            "must be a model file relative to the targets file",
            field=key,
            value=value,
            valid="a relative path such as 'without_dut.toml' or '../customer1.toml'",
        )
    return value


def _starts(value, key):
    return check_ceiling("starts", value, field=key)


OPTIONS = Table(
    "[options]",
    (
        Field(
            "starts",
            kind="integer",
            check=_starts,
            default=1,
            help="starting points: the model's own, then a Latin hypercube in the bounds",
        ),
        Field("seed", kind="integer", count=(0, 2**31 - 1), default=0, help="the Latin hypercube's seed"),
    ),
    help="optional",
)
# A target's and a parameter's values are checked by what they build (Target, Bound: the same checks
# a calibration from Python gets), their keys here.
TARGET = Table(
    "[[target]]",
    (
        Field(
            "mode",
            kind="any",
            default=REQUIRED,
            expects="a mode number >= 1",
            help="an elastic mode, numbered as `flexshaft modes` numbers them (0: rigid-body)",
        ),
        Field("frequency_hz", kind="quantity", unit="Hz", help="the mode's measured frequency ..."),
        Field(
            "ratio_to",
            kind="any",
            expects="a mode number",
            help="... or a ratio to another mode (data normalised to f1) ...",
        ),
        Field("ratio", kind="any", expects="number", help="... of this value"),
        Field("tolerance", kind="any", expects="fraction, 1e-9 … 1", shown_default="`0.01`", help="relative"),
        Field(
            "shape",
            kind="any",
            expects="list of numbers",
            help="the measured θx at the stations; it must be this mode's (MAC >= 0.8)",
        ),
        Field(
            "damping_ratio",
            kind="any",
            expects="fraction",
            help="the mode's measured damping ratio (beside its frequency, or alone with `mode`)",
        ),
        Field("damping_tolerance", kind="any", expects="fraction", shown_default="`0.1`", help="relative"),
    ),
    help="at least one: what to meet",
)
PARAMETER = Table(
    "[[parameter]]",
    (
        Field(
            "name",
            kind="any",
            check=_parameter_name,
            default=REQUIRED,
            missing="missing or not a string",
            expects="COMPONENT.FIELD",
            help="`COMPONENT.FIELD`, `MATERIAL.FIELD` or `rayleigh.alpha` …",
        ),
        Field("bounds", kind="any", check=_bounds, expects="[lower, upper] (SI)", help="absolute bounds ..."),
        Field(
            "percent", kind="any", expects="number, 1e-6 … 99", help="... or ± this % around its value ..."
        ),
        Field("fixed", kind="any", expects="number (SI)", help="... or held at this value"),
    ),
    help="at least one: what to tune",
)
STAGE = Table(
    "[[stage]]",
    (
        Field("name", kind="string", shown_default="`stage N`", help="the stage's name"),
        Field(
            "model",
            kind="any",
            check=_stage_model,
            expects="a relative path",
            shown_default="the command line's",
            help="its model file, relative to the targets file",
        ),
        Field(
            "carry_from",
            kind="any",
            expects="list of stage names",
            shown_default="every earlier stage",
            help="the earlier stages whose tuned values it carries, fixed",
        ),
        Field("target", kind="any", expects="`[[stage.target]]`", help="its targets, as `[[target]]`"),
        Field(
            "parameter",
            kind="any",
            expects="`[[stage.parameter]]`",
            help="its parameters, as `[[parameter]]`",
        ),
    ),
    help="staged calibration, instead of `[[target]]` and `[[parameter]]` at the top",
)
#: The file's top level.
TARGETS_FILE = top_level("targets file", dict.fromkeys(("options", "target", "parameter", "stage"), "any"))


@dataclass(frozen=True)
class Stage:
    """One calibration: its name, model file (None: the command line's), targets and parameters, the
    earlier stages it takes tuned values from (None: all of them), and where it is in the file
    (``"[[stage]] #2 "``, or ``""`` without stages: what an error about one of its entries starts with)."""

    name: str
    model: Path | None
    targets: tuple
    parameters: tuple
    carry_from: tuple | None = None
    where: str = ""


@dataclass(frozen=True)
class TargetsFile:
    """A read targets file: its stages (one, unnamed, without ``[[stage]]``) and options."""

    stages: tuple
    starts: int
    seed: int
    source: str


def _tables(entries, table: Table, where: str, source: str):
    """``(label, values)`` of each entry of an array of tables: at least one, each read by ``table``."""
    kind = table.name.strip("[]")
    if not isinstance(entries, list) or not entries:
        raise ModelError(f"needs at least one [[{kind}]]", file=source, component=where or None, field=kind)
    for i, entry in enumerate(entries):
        label = f"{where} {table.name} #{i + 1}".lstrip()
        yield label, read(entry, table, file=source, where=label, field=kind)


def _targets(entries, where: str, source: str) -> tuple:
    out = []
    for label, t in _tables(entries, TARGET, where, source):
        try:
            out.append(Target(**t))
        except ModelError as err:
            raise err.located(file=source, component=label) from None
    return tuple(out)


def parameter_bound(entry: dict, source: str, label: str) -> Bound:
    """A ``[[parameter]]`` table (read by :data:`PARAMETER`) as the Bound it makes, its values checked;
    an error names ``label`` (``"[[parameter]] #2"``) in ``source``."""
    p = dict(entry)
    if "bounds" in p:
        p["lower"], p["upper"] = p.pop("bounds")
    try:
        return Bound(**p)
    except ModelError as err:
        raise err.located(file=source, component=label) from None


def _parameters(entries, where: str, source: str) -> tuple:
    return tuple(parameter_bound(p, source, label) for label, p in _tables(entries, PARAMETER, where, source))


def _stages(entries, path: Path, source: str) -> tuple:
    if not isinstance(entries, list) or not entries:
        raise ModelError("must be [[stage]] tables", file=source, field="stage")
    stages: list[Stage] = []
    for i, st in enumerate(entries):
        where = f"[[stage]] #{i + 1}"
        st = read(st, STAGE, file=source, where=where, field="stage")
        name = st.get("name", f"stage {i + 1}")
        if name in [s.name for s in stages]:
            raise ModelError(
                "two stages with one name", file=source, component=where, field="name", value=name
            )
        carry = st.get("carry_from")
        if carry is not None:
            earlier = [s.name for s in stages]
            if not isinstance(carry, list) or any(c not in earlier for c in carry):
                raise ModelError(
                    "names a stage that does not come before it",
                    file=source,
                    component=where,
                    field="carry_from",
                    value=carry,
                    valid=", ".join(repr(e) for e in earlier) or "no earlier stage",
                )
            carry = tuple(carry)
        stages.append(
            Stage(
                name=name,
                model=path.parent / st["model"] if "model" in st else None,
                targets=_targets(st.get("target"), where, source),
                parameters=_parameters(st.get("parameter"), where, source),
                carry_from=carry,
                where=f"{where} ",
            )
        )
    return tuple(stages)


def read_targets(path) -> TargetsFile:
    """Read a targets file (see the module docstring); every problem is one ModelError naming it."""
    path = Path(path)
    source = str(path)
    data = read_bytes(path, TARGETS)  # a regular file within the targets file's ceiling (system.inputs)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ModelError(f"not valid TOML ({err})", file=source) from None
    return loads_targets(text, source, path)


def loads_targets(text: str, source: str = "<targets>", path: Path | None = None) -> TargetsFile:
    """A targets file's text read as :func:`read_targets` reads the file (``path``: where stages'
    model files are relative to; the current folder without it)."""
    path = Path(source) if path is None else path
    doc = read(toml_file(text, source, None), TARGETS_FILE, file=source, where="targets file")
    opts = read(doc.get("options", {}), OPTIONS, file=source, where="[options]", field="options", fill=True)
    if "stage" in doc:
        if "target" in doc or "parameter" in doc:
            raise ModelError(
                "targets and parameters belong inside the stages",
                file=source,
                field="target",
                valid="[[stage.target]] and [[stage.parameter]] with [[stage]]",
            )
        stages = _stages(doc["stage"], path, source)
    else:
        stages = (
            Stage(
                "calibration",
                None,
                _targets(doc.get("target"), "", source),
                _parameters(doc.get("parameter"), "", source),
            ),
        )
    return TargetsFile(stages, opts["starts"], opts["seed"], source)


def carried(d: Drivetrain, tuned: dict) -> dict:
    """The earlier stages' tuned values this model has a parameter for."""
    names = {p.name for p in parameters(d)}
    return {k: v for k, v in tuned.items() if k in names}


# --- writing a tuned model file ----------------------------------------------------------------------


def tuned_document(text: str, d: Drivetrain, values: dict) -> dict:
    """The model file's document (``text``) with tuned values put in (see the module docstring)."""
    from ..system.nesting import toml_document

    doc = toml_document(text, "the model file")  # its loader has read it: this refuses nothing new
    chain = doc.get("chain", [])
    by_name = {e.get("name"): e for e in chain if isinstance(e, dict)}
    materials = doc.setdefault("materials", {})
    plist: dict[str, Parameter] = {p.name: p for p in parameters(d)}
    rayleigh = {n: v for n, v in values.items() if plist[n].kind == "model"}
    if rayleigh:
        ray = with_parameters(d, rayleigh).rayleigh
        model = doc.setdefault("model", {})
        given = model.get("rayleigh")
        if isinstance(given, dict) and set(given) == {"frequencies_hz", "damping_ratios"}:
            # the file's form: the ratios at its two frequencies (α and β follow when it is read)
            given["damping_ratios"] = [
                float(rayleigh_ratio(ray.alpha, ray.beta, f)) for f in ray.frequencies_hz
            ]
        else:
            model["rayleigh"] = {"alpha": float(ray.alpha), "beta": float(ray.beta)}
    for name, value in values.items():
        p = plist[name]
        if p.kind == "model":
            continue
        if p.kind == "material":
            m = next(
                c.material
                for c in d.components
                if isinstance(c, Shaft) and c.material and c.material.name == p.owner
            )
            entry = materials.setdefault(p.owner, {"E": m.E, "nu": m.nu, "rho": m.rho})
            entry[p.field] = float(value)
            continue
        comp = d.component(p.owner)
        entry = by_name[p.owner]
        if (
            isinstance(comp, Shaft)
            and comp.sections is not None
            and p.field in ("stiffness", "inertia", "scale")
        ):
            if p.field == "scale":
                raise ModelError(
                    "a section scale has no model-file key yet: tune E or rho, or change the geometry",
                    field=name,
                )
            m = comp.material
            own = f"{comp.name} (tuned)"
            key = "E" if p.field == "stiffness" else "rho"
            entry["material"] = own
            spec = materials.setdefault(own, {"E": m.E, "nu": m.nu, "rho": m.rho})
            spec[key] = spec[key] * float(value) / (comp.stiffness if key == "E" else comp.inertia)
            continue
        entry[p.field] = float(value)
    return doc


_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else '"' + k.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ModelError("not finite", field="value", value=v)
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise ModelError("cannot be written to TOML", field="value", value=type(v).__name__)


def dumps_toml(doc: dict, header: str = "") -> str:
    """A model-file document as TOML: plain tables, arrays of tables, inline values inside."""
    lines = [f"# {line}" for line in header.splitlines()]
    plain = {
        k: v for k, v in doc.items() if not isinstance(v, (dict, list)) or (isinstance(v, list) and not v)
    }
    for k, v in plain.items():
        lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in doc.items():
        if isinstance(v, dict):
            subtables = {sk: sv for sk, sv in v.items() if isinstance(sv, dict) and k == "materials"}
            if subtables:
                for sk, sv in subtables.items():
                    lines += ["", f"[{_key(k)}.{_key(sk)}]"] + [
                        f"{_key(a)} = {_value(b)}" for a, b in sv.items()
                    ]
            else:
                lines += ["", f"[{_key(k)}]"] + [f"{_key(a)} = {_value(b)}" for a, b in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for entry in v:
                lines += ["", f"[[{_key(k)}]]"] + [f"{_key(a)} = {_value(b)}" for a, b in entry.items()]
    return "\n".join(lines) + "\n"


def write_tuned_model(
    path, source_path, d: Drivetrain, values: dict, *, header: str, overwrite: bool = False
) -> Path:
    """Write the tuned model file: the model file at ``source_path`` with ``values`` put in."""
    text = read_text(source_path, MODEL)
    return atomic_write_text(path, dumps_toml(tuned_document(text, d, values), header), overwrite=overwrite)
