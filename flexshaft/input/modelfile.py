"""Read a drivetrain from a TOML model file, strictly.

Every key must be known, every number finite and in range; the first problem
raises :class:`~flexshaft.ModelError` naming the file, the component, the key,
the value with its unit, and what is valid. The keys, units and ranges are the
model file's schema (:mod:`flexshaft.input.modelschema`, read by
:mod:`flexshaft.input.schema`); this module builds the drivetrain from them
(what depends on several keys: a shaft's two forms, flexible-body damping,
Rayleigh damping by ratios). The documentation's model-file reference is
rendered from the schema. Loading runs no analysis.
"""

from __future__ import annotations

from pathlib import Path

from ..elements.materials import BUILTIN_MATERIALS, Material
from ..errors import ModelError
from ..model.components import (
    DEFAULT_FLEX_DAMPING,
    Coupling,
    Drivetrain,
    Gear,
    Rayleigh,
    Reduce,
    Rigid,
    Shaft,
)
from ..reduction.modaldamping import ModalDamping
from ..sections.table import table_from_segments
from ..system.inputs import MODEL, read_text
from ..system.limits import check_ceiling
from ..system.threads import follows_policy
from ..validation import FRACTION, check_name
from .modelschema import (
    BEARING,
    CAD,
    COMPONENTS,
    FLEX_DAMPING_KEYS,
    MATERIAL,
    MODEL_FILE,
    MODEL_TABLE,
    RAYLEIGH_FORMS,
    REDUCE_FORMS,
    SHAFT_FORMS,
)
from .schema import read, toml_file

__all__ = ["load_model", "loads_model"]

_CLASSES = {"rigid": Rigid, "shaft": Shaft, "coupling": Coupling, "gear": Gear}


def _materials(table: dict, source: str) -> dict[str, Material]:
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
        if not isinstance(spec, dict):
            raise ModelError("must be a table", file=source, component="[materials]", field=key, value=spec)
        spec = read(spec, MATERIAL, file=source, where=where)
        try:
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
    doc = read(toml_file(text, source, None), MODEL_FILE, file=source)
    model = read(doc.get("model", {}), MODEL_TABLE, file=source, where="[model]", field="model", fill=True)
    materials = _materials(doc.get("materials", {}), source)
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
    try:
        rayleigh = _rayleigh(model["rayleigh"]) if "rayleigh" in model else None
    except ModelError as err:
        raise err.located(file=source, component="[model]") from None
    if "chain" not in doc:
        raise ModelError(
            "no [[chain]] components",
            file=source,
            field="chain",
            valid="at least one [[chain]] table (rigid, shaft, coupling or gear)",
        )
    chain = doc["chain"]
    check_ceiling("components", len(chain), file=source, field="chain", hint="lump the masses a study needs")
    components = []
    seen: dict[str, int] = {}
    for i, entry in enumerate(chain, start=1):
        label = f"[[chain]] #{i}"
        if isinstance(entry, dict) and isinstance(entry.get("name"), str):
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
    for i, b in enumerate(doc.get("bearings", []), start=1):
        b = read(b, BEARING, file=source, where=f"[[bearings]] #{i}", field="bearings")
        bearings.append((b["station"], b["stiffness"]))
    try:
        return Drivetrain(
            name=model.get("name", Path(source).stem),
            components=tuple(components),
            inertia_model=model["inertia_model"],
            rayleigh=rayleigh,
            dofs=model["dofs"],
            bearings=tuple(bearings),
            max_hz=model.get("max_hz"),
        )
    except ModelError as err:
        raise err.located(file=source) from None


def _component(entry, label: str, source: str, context: dict):
    """One ``[[chain]]`` entry: its type's keys read by the schema, then the component built."""
    types = "one of " + ", ".join(repr(t) for t in COMPONENTS)
    if not isinstance(entry, dict):
        raise ModelError("must be a table", file=source, component=label, field="chain", value=entry)
    ctype = entry.get("type")
    if ctype is None:
        raise ModelError("missing key", file=source, component=label, field="type", valid=types)
    if not isinstance(ctype, str) or ctype not in COMPONENTS:
        raise ModelError(
            "unknown component type",
            file=source,
            component=label,
            field="type",
            value=ctype,
            has_value=True,
            valid=types,
        )
    kwargs = read(entry, COMPONENTS[ctype], file=source, where=label)
    del kwargs["type"]
    try:
        if ctype in ("shaft", "cad"):
            kwargs["reduce"] = _reduce(kwargs)
            # A mesh the file sets is the user's: meshing for [model] max_hz leaves it as given.
            kwargs["fixed_mesh"] = "elements" in kwargs or "max_element_length" in kwargs
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
                    value=entry[key],
                    has_value=True,
                    valid="segments and material with it, or leave it out (use elements to cut a shaft "
                    "given by numbers)",
                )
        return _CLASSES[ctype](**kwargs)
    except ModelError as err:
        # Components put their name as the location; the file label says more.
        err.component = None
        raise err.located(file=source, component=label) from None


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
    name = kwargs.pop("name")
    common = {
        "elements": kwargs.pop("elements", 1),
        "damping_ratio": kwargs.pop("damping_ratio", 0.0),
        "damping": kwargs.pop("damping", 0.0),
        "max_element_length": kwargs.pop("max_element_length", None),
        "named_nodes": kwargs.pop("stations", ()),
        "reduce": kwargs.pop("reduce", None),
        "fixed_mesh": kwargs.pop("fixed_mesh", None),
        "fe": kwargs.pop("fe", "1d"),
    }
    if "interface" in kwargs:  # checked by the Shaft (interface_kinds)
        common["interface"] = kwargs.pop("interface")
    mesh_size = kwargs.pop("mesh_size", None)  # used wherever the solid is meshed (fe, --compare-solid)
    # Checked before the (possibly slow) slicing: the schema checked the rest.
    FRACTION.check(common["damping_ratio"], "damping_ratio")
    geometry = params = axis = segments = None
    if ctype == "shaft":
        segments = kwargs.pop("segments", None)
        if segments is None:
            raise ModelError(
                "missing or empty", field="segments", valid="a list of {length, od, id} tables in m"
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
                valid=CAD.field("geometry").expects,
            )
        params = kwargs.pop("params", {})
        unit = kwargs.pop("unit", None)
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


def _rayleigh(value: dict) -> Rayleigh:
    """A ``rayleigh`` table the schema read: coefficients, or ratios at two frequencies."""
    keys = set(value)
    if keys <= {"alpha", "beta"} and keys:
        return Rayleigh(alpha=value.get("alpha", 0.0), beta=value.get("beta", 0.0))
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
        return Rayleigh.from_ratios(f, z, field="rayleigh")
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
