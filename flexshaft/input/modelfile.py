"""Read a drivetrain from a TOML model file, strictly.

Every key must be known, every number finite and in range; the first problem
raises :class:`~flexshaft.ModelError` naming the file, the component, the key,
the value with its unit, and what is valid. See the README's model-file
reference for the format.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from ..elements.materials import BUILTIN_MATERIALS, Material
from ..errors import ModelError
from ..linalg.damping import rayleigh_coefficients
from ..model.components import FE_KINDS, INERTIA_MODELS, Coupling, Drivetrain, Gear, Rayleigh, Rigid, Shaft
from ..sections.table import table_from_segments
from ..system.inputs import MODEL, read_text
from ..system.limits import check_ceiling
from ..system.threads import follows_policy
from ..validation import check_choice, check_frequency, check_int, check_name, check_real
from .quantities import PINT_UNITS, si_value

__all__ = ["load_model", "loads_model", "COMPONENT_KEYS"]

# key -> unit, per component type; "required" lists the keys that must be given.
COMPONENT_KEYS = {
    "rigid": {
        "keys": {"name": "", "type": "", "inertia": "kg·m²", "mass": "kg", "diametral_inertia": "kg·m²"},
        "required": ("inertia",),
    },
    "shaft": {
        "keys": {
            "name": "",
            "type": "",
            "stiffness": "N·m/rad",
            "inertia": "kg·m²",
            "elements": "",
            "damping_ratio": "",
            "damping": "N·m·s/rad",
            "material": "",
            "segments": "m",
            "max_element_length": "m",
            "stations": "m",
            "reduce": "",
            "damping_bands": "Hz",
            "rayleigh": "",
            "fe": "",
            "mesh_size": "m",
            "interface": "",
        },
        "required": (),
    },
    "cad": {
        "keys": {
            "name": "",
            "type": "",
            "geometry": "",
            "params": "",
            "material": "",
            "unit": "",
            "axis": "m",
            "max_element_length": "m",
            "stations": "m",
            "elements": "",
            "damping_ratio": "",
            "damping": "N·m·s/rad",
            "reduce": "",
            "damping_bands": "Hz",
            "rayleigh": "",
            "fe": "",
            "mesh_size": "m",
            "interface": "",
        },
        "required": ("geometry", "material"),
    },
    "coupling": {
        "keys": {
            "name": "",
            "type": "",
            "stiffness": "N·m/rad",
            "inertia": "kg·m²",
            "damping": "N·m·s/rad",
            "inertia_split": "",
        },
        "required": ("stiffness",),
    },
    "gear": {
        "keys": {
            "name": "",
            "type": "",
            "ratio": "",
            "inertia_in": "kg·m²",
            "inertia_out": "kg·m²",
            "mesh_stiffness": "N·m/rad",
            "mesh_damping": "N·m·s/rad",
        },
        "required": ("ratio",),
    },
}
_CLASSES = {"rigid": Rigid, "shaft": Shaft, "coupling": Coupling, "gear": Gear}
MODEL_KEYS = ("name", "description", "inertia_model", "rayleigh", "dofs", "max_hz")
TOP_KEYS = ("model", "materials", "chain", "bearings")
MATERIAL_KEYS = {"E": "Pa", "nu": "", "rho": "kg/m³"}
SHAFT_FORMS = "either stiffness (N·m/rad) and inertia (kg·m²), or material and segments (m)"
RAYLEIGH_FORMS = "{alpha = 1/s, beta = s} or {frequencies_hz = [f1, f2], damping_ratios = [z1, z2]}"
REDUCE_FORMS = "{modes = n} or {cutoff_hz = f} (Hz)"
#: Keys that set a flexible body's damping per mode (only with ``reduce``).
FLEX_DAMPING_KEYS = ("damping_bands", "rayleigh")


def _unknown(keys, allowed, where: str | None, file: str | None) -> None:
    for key in keys:
        if key not in allowed:
            raise ModelError(
                "unknown key", file=file, component=where, field=key, valid="one of " + ", ".join(allowed)
            )


def _table(value, field: str, where: str | None = None, file: str | None = None, valid=None) -> dict:
    """``value`` if it is a TOML table, else the one "must be a table" error."""
    if not isinstance(value, dict):
        raise ModelError(
            "must be a table",
            file=file,
            component=where,
            field=field,
            value=value,
            has_value=True,
            valid=valid,
        )
    return value


def _materials(doc: dict, source: str) -> dict[str, Material]:
    table = _table(doc.get("materials", {}), "materials", None, source)
    out = dict(BUILTIN_MATERIALS)
    for key, spec in table.items():
        where = f"[materials.{key}]"
        if key in BUILTIN_MATERIALS:
            raise ModelError(
                "redefines a built-in material",
                file=source,
                component=where,
                field="name",
                value=key,
                valid="a new name (built-in: " + ", ".join(BUILTIN_MATERIALS) + ")",
            )
        spec = _table(spec, key, "[materials]", source)
        _unknown(spec, tuple(MATERIAL_KEYS), where, source)
        for k, unit in MATERIAL_KEYS.items():
            if k not in spec:
                raise ModelError(
                    "missing key",
                    file=source,
                    component=where,
                    field=k,
                    valid=f"a number in {unit}" if unit else "a number",
                )
        try:
            spec = dict(spec)
            _to_si(spec, MATERIAL_KEYS)
            out[key] = Material(E=spec["E"], nu=spec["nu"], rho=spec["rho"], name=check_name(key, "name"))
        except ModelError as err:
            raise err.located(file=source, component=where) from None
    return out


@follows_policy
def loads_model(
    text: str,
    source: str = "<string>",
    *,
    base_dir=None,
    progress=None,
    allow_code: bool = False,
    use_cache: bool = True,
    mesh_solids: bool = False,
) -> Drivetrain:
    """Parse a model file's text into a :class:`Drivetrain`.

    Parameters
    ----------
    text : str
        TOML text.
    source : str
        Where it came from, for error messages.
    base_dir : str or Path, optional
        Directory that relative geometry paths (and part modules) of
        ``type = "cad"`` components are read from; default: the directory
        of ``source`` if that is a file, else the working directory.
    progress : callable, optional
        ``progress(label)`` returns a ``(done, total)`` callback for slicing
        a CAD part (e.g. :class:`flexshaft.views.progress.ProgressBar`).
    allow_code : bool
        Run part code the file names that is not flexshaft's own part library
        (``geometry = "my_parts:flange"``): a ``.py`` file in ``base_dir`` or
        an installed package's function. Off by default: a model file from
        someone else is code when it names code, so trust it explicitly.
    use_cache : bool
        Read section tables of CAD parts from the disk cache and keep new ones
        there (:mod:`flexshaft.input.cache`); False slices every part anew.
    mesh_solids : bool
        Mesh every part given by its geometry into its solid (``solid_mesh``), not only those with
        ``fe = "solid"`` (which stay the only ones modelled by it): for comparing 1D and solid.

    Returns
    -------
    Drivetrain
    """
    from ..system.nesting import toml_document

    try:
        doc = toml_document(text, source)  # nesting refused before the parser recurses
    except tomllib.TOMLDecodeError as err:
        raise ModelError(f"not valid TOML ({err})", file=source) from None
    _unknown(doc, TOP_KEYS, None, source)

    model = _table(doc.get("model", {}), "model", None, source)
    _unknown(model, MODEL_KEYS, "[model]", source)
    try:
        name = check_name(model.get("name", Path(source).stem), "name")
        inertia_model = check_choice(
            model.get("inertia_model", "consistent"), "inertia_model", INERTIA_MODELS
        )
        if "description" in model and not isinstance(model["description"], str):
            raise ModelError("must be a string", field="description", value=model["description"])
        rayleigh = _rayleigh(model["rayleigh"]) if "rayleigh" in model else None
        dofs = check_choice(model.get("dofs", "torsion"), "dofs", ("torsion", "full"))
        max_hz = None
        if "max_hz" in model:
            max_hz = check_frequency(si_value(model["max_hz"], "max_hz", "Hz"), "max_hz", lo_open=True)
    except ModelError as err:
        raise err.located(file=source, component="[model]") from None

    materials = _materials(doc, source)
    if base_dir is None:
        base_dir = Path(source).parent if Path(source).is_file() else Path.cwd()
    context = {
        "materials": materials,
        "base_dir": Path(base_dir),
        "progress": progress,
        "allow_code": bool(allow_code),
        "use_cache": bool(use_cache),
        "mesh_solids": bool(mesh_solids),
    }

    chain = doc.get("chain")
    if chain is None:
        raise ModelError(
            "no [[chain]] components",
            file=source,
            field="chain",
            valid="at least one [[chain]] table (rigid, shaft, coupling or gear)",
        )
    if not isinstance(chain, list):
        raise ModelError(
            "must be an array of tables ([[chain]])", file=source, field="chain", value=chain, has_value=True
        )
    check_ceiling("components", len(chain), file=source, field="chain", hint="lump the masses a study needs")
    components = []
    seen: dict[str, int] = {}
    for i, entry in enumerate(chain, start=1):
        label = f"[[chain]] #{i}"
        entry = _table(entry, "chain", label, source)
        if "name" in entry and isinstance(entry["name"], str):
            label += f" {entry['name']!r}"
        comp = _component(entry, label, source, context)
        if comp.name in seen:
            raise ModelError(
                "duplicate component name",
                file=source,
                component=label,
                field="name",
                value=comp.name,
                valid=f"a name not used by [[chain]] #{seen[comp.name]}",
            )
        seen[comp.name] = i
        components.append(comp)
    bearings = []
    raw = doc.get("bearings", [])
    if not isinstance(raw, list):
        raise ModelError(
            "must be an array of tables ([[bearings]])",
            file=source,
            field="bearings",
            value=raw,
            has_value=True,
        )
    for i, b in enumerate(raw, start=1):
        where = f"[[bearings]] #{i}"
        b = _table(b, "bearings", where, source)
        _unknown(b, ("station", "stiffness"), where, source)
        for key, valid in (
            ("station", "a station name, e.g. 'part 1/part 2'"),
            ("stiffness", "a number in N/m"),
        ):
            if key not in b:
                raise ModelError("missing key", file=source, component=where, field=key, valid=valid)
        try:
            k = si_value(b["stiffness"], "stiffness", "N/m")
            k = check_real(k, "stiffness", "N/m", lo=0.0, lo_open=True)
        except ModelError as err:
            raise err.located(file=source, component=where) from None
        bearings.append((b["station"], k))
    try:
        return Drivetrain(
            name=name,
            components=tuple(components),
            inertia_model=inertia_model,
            rayleigh=rayleigh,
            dofs=dofs,
            bearings=tuple(bearings),
            max_hz=max_hz,
        )
    except ModelError as err:
        raise err.located(file=source) from None


def _component(entry: dict, label: str, source: str, context: dict):
    ctype = entry.get("type")
    if ctype is None:
        raise ModelError(
            "missing key",
            file=source,
            component=label,
            field="type",
            valid="one of " + ", ".join(repr(t) for t in COMPONENT_KEYS),
        )
    if not isinstance(ctype, str) or ctype not in COMPONENT_KEYS:
        raise ModelError(
            "unknown component type",
            file=source,
            component=label,
            field="type",
            value=ctype,
            has_value=True,
            valid="one of " + ", ".join(repr(t) for t in COMPONENT_KEYS),
        )
    spec = COMPONENT_KEYS[ctype]
    _unknown(entry, tuple(spec["keys"]), label, source)
    if "name" not in entry:
        raise ModelError(
            "missing key", file=source, component=label, field="name", valid="a unique name for the component"
        )
    for key in spec["required"]:
        if key not in entry:
            unit = spec["keys"][key]
            raise ModelError(
                f"missing key for a {ctype}",
                file=source,
                component=label,
                field=key,
                valid=f"a number in {unit}" if unit else "a number",
            )
    kwargs = {k: v for k, v in entry.items() if k != "type"}
    try:
        if isinstance(kwargs.get("segments"), list):  # counted before each one is read
            check_ceiling("segments", len(kwargs["segments"]), field="segments")
        _to_si(kwargs, spec["keys"])
        if ctype in ("shaft", "cad"):
            kwargs["reduce"] = _reduce(kwargs)
            # A mesh the file sets is the user's: meshing for [model] max_hz leaves it as given.
            kwargs["fixed_mesh"] = "elements" in kwargs or "max_element_length" in kwargs
        if ctype == "gear":
            kwargs["ratio"] = _gear_ratio(kwargs["ratio"])
        if ctype == "cad" or (ctype == "shaft" and ("segments" in kwargs or "material" in kwargs)):
            return _section_shaft(ctype, kwargs, context)
        if ctype == "shaft" and not {"stiffness", "inertia"} <= set(kwargs):
            missing = "stiffness" if "stiffness" not in kwargs else "inertia"
            raise ModelError("missing key for a shaft", field=missing, valid=SHAFT_FORMS)
        for key in ("stations", "max_element_length", "mesh_size"):
            if ctype == "shaft" and key in kwargs:
                raise ModelError(
                    "belongs to a shaft made from sections",
                    field=key,
                    value=kwargs[key],
                    has_value=True,
                    valid="segments and material with it, or leave it out (use elements to cut a shaft "
                    "given by numbers)",
                )
        return _CLASSES[ctype](**kwargs)
    except ModelError as err:
        # Components put their name as the location; the file label says more.
        err.component = None
        raise err.located(file=source, component=label) from None


def _gear_ratio(value):
    """A gear ratio as a number: given as one, or as an exact fraction ``"1/97"`` (driving / driven speed)."""
    if not isinstance(value, str):
        return value
    num, slash, den = value.partition("/")
    try:
        if not slash:
            raise ValueError
        ratio = float(num) / float(den)
    except (ValueError, ZeroDivisionError):
        raise ModelError(
            "is not a number or a fraction",
            field="ratio",
            value=value,
            has_value=True,
            valid='driving-side speed / driven-side speed, as a number or a string "a/b" such as "1/97"',
        ) from None
    return ratio


def _to_si(kwargs: dict, units: dict) -> None:
    """Numbers given with a unit (``"500 mm"``) as SI numbers, in place; bare numbers stay as they are.

    Keys with a unit take a quantity; so do the lengths of ``segments`` and ``stations`` (m) and
    ``reduce.cutoff_hz`` (Hz).
    """
    for key, unit in units.items():
        if key not in kwargs:
            continue
        value = kwargs[key]
        if key == "segments" and isinstance(value, list):
            kwargs[key] = [
                {k: si_value(v, f"segments[{i}].{k}", "m") for k, v in seg.items()}
                if isinstance(seg, dict)
                else seg
                for i, seg in enumerate(value)
            ]
        elif key == "stations" and isinstance(value, dict):
            kwargs[key] = {k: si_value(v, f"stations.{k}", "m") for k, v in value.items()}
        elif key == "reduce" and isinstance(value, dict) and "cutoff_hz" in value:
            kwargs[key] = value | {"cutoff_hz": si_value(value["cutoff_hz"], "reduce.cutoff_hz", "Hz")}
        elif unit in PINT_UNITS:
            kwargs[key] = si_value(value, key, unit)


def _material(kwargs: dict, materials: dict[str, Material]) -> Material:
    name = kwargs.pop("material", None)
    if name is None:
        raise ModelError(
            "missing key",
            field="material",
            valid="a material name: " + ", ".join(materials) + " or a [materials.NAME] table",
        )
    if not isinstance(name, str) or name not in materials:
        raise ModelError(
            "unknown material",
            field="material",
            value=name,
            has_value=True,
            valid=", ".join(materials) + " (or define [materials.NAME] with E, nu, rho)",
        )
    return materials[name]


def _named_nodes(value) -> tuple:
    _table(value, "stations", valid="{name = position in m from the part's driving end, ...}")
    return tuple(
        (str(k), check_real(v, f"stations.{k}", "m", lo=0.0, lo_open=True)) for k, v in value.items()
    )


def _section_shaft(ctype: str, kwargs: dict, context: dict) -> Shaft:
    """A shaft whose stiffness and inertia come from sections: ``segments`` or CAD geometry."""
    for key in ("stiffness", "inertia"):
        if key in kwargs:
            raise ModelError(
                f"a {ctype} given by its geometry takes no {key}",
                field=key,
                value=kwargs[key],
                valid=SHAFT_FORMS if ctype == "shaft" else "leave it out (it comes from the geometry)",
            )
    material = _material(kwargs, context["materials"])
    name = check_name(kwargs.pop("name"))
    common = {
        "elements": kwargs.pop("elements", 1),
        "damping_ratio": kwargs.pop("damping_ratio", 0.0),
        "damping": kwargs.pop("damping", 0.0),
        "max_element_length": kwargs.pop("max_element_length", None),
        "named_nodes": _named_nodes(kwargs.pop("stations", {})),
        "reduce": kwargs.pop("reduce", None),
        "fixed_mesh": kwargs.pop("fixed_mesh", None),
        "fe": check_choice(kwargs.pop("fe", "1d"), "fe", FE_KINDS),
    }
    if "interface" in kwargs:  # checked by the Shaft (interface_kinds)
        common["interface"] = kwargs.pop("interface")
    mesh_size = kwargs.pop("mesh_size", None)  # used wherever the solid is meshed (fe, --compare-solid)
    if mesh_size is not None:
        mesh_size = check_real(mesh_size, "mesh_size", "m", lo=0.0, lo_open=True)
    # Validate these before the (possibly slow) slicing.
    check_ceiling("elements", check_int(common["elements"], "elements", lo=1))
    check_real(common["damping_ratio"], "damping_ratio", "", lo=0.0, hi=1.0, hi_open=True)
    check_real(common["damping"], "damping", "N·m·s/rad", lo=0.0)
    if common["max_element_length"] is not None:
        check_real(common["max_element_length"], "max_element_length", "m", lo=0.0, lo_open=True)
    geometry = params = axis = segments = None
    if ctype == "shaft":
        segments = kwargs.pop("segments", None)
        if not isinstance(segments, list) or not segments:
            raise ModelError(
                "missing or empty",
                field="segments",
                value=segments,
                has_value=segments is not None,
                valid="a list of {length, od, id} tables in m",
            )
        for k, seg in enumerate(segments):
            if not isinstance(seg, dict):
                raise ModelError(
                    "must be a table",
                    field=f"segments[{k}]",
                    value=seg,
                    has_value=True,
                    valid="{length = m, od = m, id = m}",
                )
        table = table_from_segments(segments, nu=material.nu, name=name)
    else:
        from .cad import cad_sections

        geometry = kwargs.pop("geometry")
        if not isinstance(geometry, str) or not geometry:
            raise ModelError(
                "must be a string",
                field="geometry",
                value=geometry,
                has_value=True,
                valid="'module:function' or a path to a STEP/BREP/STL/OBJ/PLY file",
            )
        params = _table(
            kwargs.pop("params", {}),
            "params",
            valid="{key = value, ...} keyword parameters of the part function, SI units",
        )
        unit = kwargs.pop("unit", None)
        if unit is not None and not isinstance(unit, str):
            raise ModelError(
                "must be a string", field="unit", value=unit, has_value=True, valid="m, mm, cm, in"
            )
        axis = kwargs.pop("axis", None)
        table = cad_sections(
            geometry,
            name=name,
            nu=material.nu,
            params=params,
            unit=unit,
            axis=axis,
            base_dir=context["base_dir"],
            progress=context["progress"](f"slicing {name}") if context["progress"] else None,
            allow_code=context["allow_code"],
            use_cache=context["use_cache"],
        )
    if common["fe"] == "solid" or context.get("mesh_solids"):
        from .cad import solid_mesh

        bar = context["progress"](f"meshing {name}") if context["progress"] else None
        common["solid_mesh"] = solid_mesh(
            name=name,
            geometry=geometry,
            segments=None if geometry is not None else segments,
            params=params,
            axis=axis,
            base_dir=context["base_dir"],
            size=mesh_size,
            progress=getattr(bar, "stage", None),
            allow_code=context["allow_code"],
            use_cache=context["use_cache"],
        )
        if context["use_cache"]:  # the part's reduction, stiffness and modes are kept too
            from .solidcache import SOLID_RESULTS

            common["solid_cache"] = SOLID_RESULTS
        common["solid_progress"] = context["progress"]  # its reduction's progress, when one is shown
    return Shaft.from_sections(name, table, material, geometry=geometry, **common)


def _reduce(kwargs: dict):
    """Pop ``reduce`` and the per-mode damping keys; a :class:`Reduce` or None.

    ``damping_ratio`` is then the flexible body's: a number for every elastic
    mode (0.53 % when not given), or a list, one per elastic mode in frequency
    order (the last one for any further mode). ``damping_bands`` gives ratios
    by frequency band, ``rayleigh`` Rayleigh damping of the body.
    """
    spec = kwargs.pop("reduce", None)
    if spec is None:
        for key in FLEX_DAMPING_KEYS:
            if key in kwargs:
                raise ModelError(
                    "sets the damping of a flexible body's modes",
                    field=key,
                    value=kwargs[key],
                    has_value=True,
                    valid=f"add reduce = {REDUCE_FORMS} to the part, or leave {key} out",
                )
        if isinstance(kwargs.get("damping_ratio"), list):
            raise ModelError(
                "a list of ratios (one per mode) needs a flexible body",
                field="damping_ratio",
                value=kwargs["damping_ratio"],
                has_value=True,
                valid=f"one number in [0, 1), or add reduce = {REDUCE_FORMS}",
            )
        return None
    from ..model.components import DEFAULT_FLEX_DAMPING, Reduce
    from ..reduction.modaldamping import ModalDamping

    _table(spec, "reduce", valid=REDUCE_FORMS)
    for key in spec:
        if key not in ("modes", "cutoff_hz"):
            raise ModelError("unknown key", field=f"reduce.{key}", valid=REDUCE_FORMS)
    given = "damping_ratio" in kwargs
    ratio = kwargs.pop("damping_ratio", DEFAULT_FLEX_DAMPING)
    by_mode: tuple = ()
    if isinstance(ratio, list):
        if not ratio:
            raise ModelError(
                "empty list", field="damping_ratio", valid="one ratio per elastic mode, e.g. [0.005, 0.008]"
            )
        # Every elastic mode is then covered (the last value carries on): `ratio` is unused.
        by_mode, ratio = tuple(ratio), DEFAULT_FLEX_DAMPING
    bands = kwargs.pop("damping_bands", ())
    if not isinstance(bands, list | tuple) or not all(isinstance(b, list) and len(b) == 3 for b in bands):
        raise ModelError(
            "must be a list of [f_lo, f_hi, ratio]",
            field="damping_bands",
            value=bands,
            has_value=True,
            valid="[[f_lo Hz, f_hi Hz, ratio], ...], e.g. [[0, 500, 0.005], [500, 2000, 0.01]]",
        )
    ray = kwargs.pop("rayleigh", None)
    rayleigh = None
    if ray is not None:
        if given or bands:
            raise ModelError(
                "Rayleigh damping sets every mode's ratio itself",
                field="rayleigh",
                valid="rayleigh alone, or damping_ratio / damping_bands without rayleigh",
            )
        r = _rayleigh(ray)
        rayleigh = (r.alpha, r.beta)
    damping = ModalDamping(
        ratio=ratio, by_mode=by_mode, bands=tuple(tuple(b) for b in bands), rayleigh=rayleigh
    )
    # The shaft's own scalar ratio is not used by a flexible body; keep it for reports.
    kwargs["damping_ratio"] = 0.0
    return Reduce(modes=spec.get("modes"), cutoff_hz=spec.get("cutoff_hz"), damping=damping)


def _rayleigh(value) -> Rayleigh:
    _table(value, "rayleigh", valid=RAYLEIGH_FORMS)
    keys = set(value)
    if keys <= {"alpha", "beta"} and keys:
        return Rayleigh(
            alpha=si_value(value.get("alpha", 0.0), "rayleigh.alpha", "1/s"),
            beta=si_value(value.get("beta", 0.0), "rayleigh.beta", "s"),
        )
    if keys == {"frequencies_hz", "damping_ratios"}:
        f, z = value["frequencies_hz"], value["damping_ratios"]
        for field, v in (("rayleigh.frequencies_hz", f), ("rayleigh.damping_ratios", z)):
            if not isinstance(v, list) or len(v) != 2:
                raise ModelError(
                    "must be a list of two numbers",
                    field=field,
                    value=v,
                    has_value=True,
                    valid=RAYLEIGH_FORMS,
                )
        try:
            alpha, beta = rayleigh_coefficients(f[0], z[0], f[1], z[1])
        except ModelError as err:  # its arguments' names as the file spells them
            names = {"f1_hz": "frequencies_hz[0]", "f2_hz": "frequencies_hz[1]"}
            names |= {"ratio1": "damping_ratios[0]", "ratio2": "damping_ratios[1]"}
            raise ModelError(
                err.message,
                field=f"rayleigh.{names.get(err.field, err.field)}",
                value=err.value,
                unit=err.unit,
                valid=err.valid,
                has_value=err.has_value,
            ) from None
        if alpha < 0 or beta < 0:
            raise ModelError(
                "these targets need a negative Rayleigh coefficient "
                f"(alpha = {alpha:.4g} 1/s, beta = {beta:.4g} s)",
                field="rayleigh.damping_ratios",
                value=z,
                valid="targets whose alpha and beta are both >= 0",
            )
        return Rayleigh(alpha=alpha, beta=beta, frequencies_hz=(f[0], f[1]))
    raise ModelError("unknown keys " + ", ".join(sorted(keys)), field="rayleigh", valid=RAYLEIGH_FORMS)


@follows_policy
def load_model(
    path, *, progress=None, allow_code: bool = False, use_cache: bool = True, mesh_solids: bool = False
) -> Drivetrain:
    """Read a model file.

    Parameters
    ----------
    path : str or Path
        A TOML model file.
    progress : callable, optional
        See :func:`loads_model`.
    allow_code : bool
        Run part code the file names beyond flexshaft's own part library; see
        :func:`loads_model`.
    use_cache : bool
        Use the disk cache of section tables; see :func:`loads_model`.
    mesh_solids : bool
        Mesh every part given by its geometry; see :func:`loads_model`.

    Returns
    -------
    Drivetrain
    """
    p = Path(path)
    text = read_text(p, MODEL)  # a regular file within the model file's ceiling (flexshaft.system.inputs)
    return loads_model(
        text,
        source=str(path),
        base_dir=p.parent,
        progress=progress,
        allow_code=allow_code,
        use_cache=use_cache,
        mesh_solids=mesh_solids,
    )
