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
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..analysis.calibrate import Bound, Target
from ..analysis.sensitivity import Parameter, parameters, with_parameters
from ..errors import ModelError
from ..linalg.damping import rayleigh_ratio
from ..model.components import Drivetrain, Shaft
from ..system.atomic import atomic_write_text
from ..system.inputs import MODEL, TARGETS, read_bytes, read_text
from ..system.limits import check_ceiling
from ..validation import check_int

__all__ = ["Stage", "TargetsFile", "read_targets", "tuned_document", "dumps_toml", "write_tuned_model"]

TARGET_KEYS = (
    "mode",
    "frequency_hz",
    "ratio_to",
    "ratio",
    "tolerance",
    "shape",
    "damping_ratio",
    "damping_tolerance",
)
PARAMETER_KEYS = ("name", "bounds", "percent", "fixed")
STAGE_KEYS = ("name", "model", "carry_from", "target", "parameter")
TOP_KEYS = ("options", "target", "parameter", "stage")
OPTION_KEYS = ("starts", "seed")


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


def _err(source, message, **kw):
    return ModelError(message, file=source, **kw)


def _unknown(table: dict, allowed, where: str, source: str) -> None:
    for key in table:
        if key not in allowed:
            raise _err(source, "unknown key", component=where, field=key, valid=", ".join(allowed))


def _tables(entries, kind: str, keys, where: str, source: str):
    """``(label, table)`` of each ``[[kind]]`` entry: at least one, each a table of known keys."""
    if not isinstance(entries, list) or not entries:
        raise _err(source, f"needs at least one [[{kind}]]", component=where, field=kind)
    for i, table in enumerate(entries):
        label = f"{where}[[{kind}]] #{i + 1}"
        if not isinstance(table, dict):
            raise _err(source, "must be a table", component=label)
        _unknown(table, keys, label, source)
        yield label, table


def _targets(entries, where: str, source: str) -> tuple:
    out = []
    for label, t in _tables(entries, "target", TARGET_KEYS, where, source):
        if "mode" not in t:
            raise _err(source, "missing key", component=label, field="mode", valid="a mode number >= 1")
        try:
            out.append(Target(**t))  # only known keys reach here
        except ModelError as err:
            raise err.located(file=source, component=label) from None
    return tuple(out)


def _parameters(entries, where: str, source: str) -> tuple:
    out = []
    for label, p in _tables(entries, "parameter", PARAMETER_KEYS, where, source):
        name = p.get("name")
        if not isinstance(name, str):
            raise _err(
                source, "missing or not a string", component=label, field="name", valid="COMPONENT.FIELD"
            )
        kw = {"name": name}
        if "bounds" in p:
            b = p["bounds"]
            if not (isinstance(b, list) and len(b) == 2):
                raise _err(source, "must be [lower, upper]", component=label, field="bounds", value=b)
            kw["lower"], kw["upper"] = b
        for key in ("percent", "fixed"):
            if key in p:
                kw[key] = p[key]
        try:
            out.append(Bound(**kw))
        except ModelError as err:
            raise err.located(file=source, component=label) from None
    return tuple(out)


def read_targets(path) -> TargetsFile:
    """Read a targets file (see the module docstring); every problem is one ModelError naming it."""
    path = Path(path)
    source = str(path)
    data = read_bytes(
        path, TARGETS
    )  # a regular file within the targets file's ceiling (flexshaft.system.inputs)
    from ..system.nesting import toml_document

    try:
        doc = toml_document(data.decode("utf-8"), source)  # nesting refused before the parser recurses
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as err:
        raise _err(source, f"not valid TOML ({err})") from None
    _unknown(doc, TOP_KEYS, "targets file", source)
    opts = doc.get("options", {})
    if not isinstance(opts, dict):
        raise _err(source, "must be a table", component="[options]")
    _unknown(opts, OPTION_KEYS, "[options]", source)
    try:
        starts = check_ceiling("starts", check_int(opts.get("starts", 1), "starts", lo=1), field="starts")
        seed = check_int(opts.get("seed", 0), "seed", lo=0, hi=2**31 - 1)
    except ModelError as err:
        raise err.located(file=source, component="[options]") from None
    if "stage" in doc:
        if "target" in doc or "parameter" in doc:
            raise _err(
                source,
                "targets and parameters belong inside the stages",
                field="target",
                valid="[[stage.target]] and [[stage.parameter]] with [[stage]]",
            )
        stages = []
        if not isinstance(doc["stage"], list) or not doc["stage"]:
            raise _err(source, "must be [[stage]] tables", field="stage")
        for i, st in enumerate(doc["stage"]):
            where = f"[[stage]] #{i + 1}"
            if not isinstance(st, dict):
                raise _err(source, "must be a table", component=where)
            _unknown(st, STAGE_KEYS, where, source)
            name = st.get("name", f"stage {i + 1}")
            if not isinstance(name, str):
                raise _err(source, "must be a string", component=where, field="name")
            model = st.get("model")
            if model is not None:
                if not isinstance(model, str) or not model or Path(model).is_absolute():
                    raise _err(
                        source,
                        "must be a model file relative to the targets file",
                        component=where,
                        field="model",
                        value=model,
                        valid="a relative path such as 'without_dut.toml' or '../customer1.toml'",
                    )
                model = path.parent / model
            if name in [s.name for s in stages]:
                raise _err(source, "two stages with one name", component=where, field="name", value=name)
            carry = st.get("carry_from")
            if carry is not None:
                earlier = [s.name for s in stages]
                if not isinstance(carry, list) or any(c not in earlier for c in carry):
                    raise _err(
                        source,
                        "names a stage that does not come before it",
                        component=where,
                        field="carry_from",
                        value=carry,
                        valid=", ".join(repr(e) for e in earlier) or "no earlier stage",
                    )
                carry = tuple(carry)
            stages.append(
                Stage(
                    name=name,
                    model=model,
                    targets=_targets(st.get("target"), f"{where} ", source),
                    parameters=_parameters(st.get("parameter"), f"{where} ", source),
                    carry_from=carry,
                    where=f"{where} ",
                )
            )
        return TargetsFile(tuple(stages), starts, seed, source)
    stage = Stage(
        "calibration",
        None,
        _targets(doc.get("target"), "", source),
        _parameters(doc.get("parameter"), "", source),
    )
    return TargetsFile((stage,), starts, seed, source)


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
