"""Model parameters by name: what each one is, the values it may take, and a model with new values.

A parameter is named ``COMPONENT.FIELD``, ``MATERIAL.FIELD`` or ``rayleigh.FIELD``:

- a rigid inertia: ``motor.inertia``;
- a shaft given by numbers: ``stiffness``, ``inertia``, ``damping``, ``damping_ratio``;
- a shaft made from sections (a CAD part, segments): ``stiffness`` and ``inertia`` too - set by
  the part's own Young's modulus (k ∝ E at fixed ν) and density (j ∝ ρ), the way a tuned
  stiffness goes back to physics - ``scale`` (every cross-section dimension times s, lengths
  kept: k and j ∝ s⁴; 1 as built), ``damping``, ``damping_ratio``;
- a coupling: ``stiffness``, ``inertia``, ``damping``;
- a gear stage: ``ratio``, ``inertia_in``, ``inertia_out``, ``mesh_stiffness``, ``mesh_damping``;
- a material every part made of it shares: ``steel.E``, ``steel.rho``, ``steel.nu``;
- a flexible body (a shaft with ``reduce``) damped by one ratio on every elastic mode of its own
  (the model file's ``damping_ratio``, 0.53 % by default): ``damping_ratio`` sets that ratio; a body
  damped per mode, per band or by its own Rayleigh damping has none;
- the model's Rayleigh damping C = αM + βK (``[model] rayleigh``): ``rayleigh.alpha`` (1/s) and
  ``rayleigh.beta`` (s), 0 where the model has none; where the model file gives it as ratios at two
  frequencies, also those ratios, ``rayleigh.damping_ratios[0]`` and ``rayleigh.damping_ratios[1]``
  (α and β follow, the frequencies kept).

Damping parameters (:data:`DAMPING_FIELDS`) enter C alone: the undamped modes do not move with them.

Sensitivities are :mod:`flexshaft.analysis.sensitivity`'s, the model as a function of some of its
parameters :mod:`flexshaft.analysis.parametrised`'s.
"""

from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass

from ..elements.materials import Material
from ..errors import ModelError
from ..linalg.damping import rayleigh_ratio
from ..model.components import Drivetrain, Gear, Rayleigh, Shaft
from ..reduction.modaldamping import ModalDamping
from ..validation import (
    DAMPER,
    FRACTION,
    GEAR_RATIO,
    INERTIA,
    RAYLEIGH_ALPHA,
    RAYLEIGH_BETA,
    STIFFNESS,
    Domain,
    check_real,
)

__all__ = [
    "Parameter",
    "Domain",
    "parameter_domain",
    "parameters",
    "find_parameter",
    "parameter_value",
    "with_parameters",
    "is_damping",
    "AFFINE_FIELDS",
    "DAMPING_FIELDS",
]

#: Fields that can be a parameter, by component type (shafts from sections add ``scale``).
FIELDS = {
    "rigid": ("inertia",),
    "shaft": ("stiffness", "inertia", "damping", "damping_ratio"),
    "coupling": ("stiffness", "inertia", "damping"),
    "gear": ("ratio", "inertia_in", "inertia_out", "mesh_stiffness", "mesh_damping"),
}
MATERIAL_FIELDS = ("E", "rho", "nu")
#: The model-level parameters' owner: ``rayleigh.alpha`` … (the model file's ``[model] rayleigh``).
RAYLEIGH = "rayleigh"
#: The Rayleigh coefficients, every model has (0 without Rayleigh damping) ...
RAYLEIGH_FIELDS = ("alpha", "beta")
#: ... and its ratios at two frequencies, where the model states it that way.
RAYLEIGH_RATIO_FIELDS = ("damping_ratios[0]", "damping_ratios[1]")
UNITS = {
    "inertia": "kg·m²",
    "stiffness": "N·m/rad",
    "damping": "N·m·s/rad",
    "damping_ratio": "",
    "scale": "",
    "ratio": "",
    "inertia_in": "kg·m²",
    "inertia_out": "kg·m²",
    "mesh_stiffness": "N·m/rad",
    "mesh_damping": "N·m·s/rad",
    "E": "Pa",
    "rho": "kg/m³",
    "nu": "",
    "alpha": "1/s",
    "beta": "s",
    "damping_ratios[0]": "",
    "damping_ratios[1]": "",
}
#: The values each field may take, as the components and materials accept them (lo, lo_open, hi,
#: hi_open): a calibration's bounds and a sweep's ranges are checked against these before any work, so
#: a bound of -1 on a stiffness is refused by name instead of being reached by the optimiser. A rigid
#: inertia and the inertia of a part from sections (∝ ρ) are > 0 (see :func:`parameter_domain`); a
#: shaft's or coupling's may be 0 (massless), as its model-file key may.
DOMAINS = {
    "stiffness": STIFFNESS,
    "inertia": INERTIA,
    "damping": DAMPER,
    "damping_ratio": FRACTION,
    "scale": Domain(0.0, True),
    "ratio": GEAR_RATIO,
    "inertia_in": INERTIA,
    "inertia_out": INERTIA,
    "mesh_stiffness": STIFFNESS,
    "mesh_damping": DAMPER,
    "E": Domain(0.0, True),
    "rho": Domain(0.0, True),
    "nu": Domain(-1.0, True, 0.5, True),
    "alpha": RAYLEIGH_ALPHA,
    "beta": RAYLEIGH_BETA,
    "damping_ratios[0]": FRACTION,
    "damping_ratios[1]": FRACTION,
}
#: Fields the assembled K and M are affine in, every other value held: a component's stiffness,
#: inertia or mesh stiffness is a factor of its own entries; a part from sections takes a stiffness
#: through its own E (torsion G = E/2(1+ν), bending EI, axial EA, shear κGA: all ∝ E at fixed ν,
#: the shear factor 12EI/κGAL² free of E) and an inertia through its own ρ (every mass entry ∝ ρ); a
#: material's E and ρ likewise for every part made of it; dampers, damping ratios and the Rayleigh
#: coefficients (and the two ratios they may be stated as: α, β are linear in them) enter C alone.
#: Not affine, so differenced afresh wherever they are needed: ``scale`` (k, j ∝ s⁴, areas s²,
#: and the shear factor ∝ s² in a 6-DOF model), a gear's ``ratio`` (a mesh block k·[1, −n; −n, n²],
#: a rigid mesh's 1/n², and the rigid-body motion moves with it), a material's ``nu``
#: (G = E/2(1+ν), and the shear factor).
AFFINE_FIELDS = frozenset(
    {
        "stiffness",
        "inertia",
        "damping",
        "damping_ratio",
        "mesh_stiffness",
        "mesh_damping",
        "inertia_in",
        "inertia_out",
        "E",
        "rho",
        *RAYLEIGH_FIELDS,
        *RAYLEIGH_RATIO_FIELDS,
    }
)
#: Fields that enter C alone: their ∂K and ∂M are 0, with no assembly. C is affine in each of them.
DAMPING_FIELDS = frozenset(
    {"damping", "damping_ratio", "mesh_damping", *RAYLEIGH_FIELDS, *RAYLEIGH_RATIO_FIELDS}
)


@dataclass(frozen=True)
class Parameter:
    """A named model parameter (see the module docstring).

    Attributes
    ----------
    name : str
        ``"part 3.stiffness"``, ``"steel.E"``.
    owner : str
        The component or material.
    field : str
    kind : str
        ``"component"``, ``"material"`` or ``"model"`` (the Rayleigh damping).
    unit : str
    """

    name: str
    owner: str
    field: str
    kind: str
    unit: str


def parameter_domain(d: Drivetrain, name: str) -> Domain:
    """The values the parameter called ``name`` may take (:data:`DOMAINS`; an error lists the names).

    A rigid inertia is > 0 (a rigid body without inertia is no body), and so is a stiffness or
    inertia of a part from sections (set through its E and ρ, both > 0); every other field as the
    component or material accepts it in a model file.
    """
    p = find_parameter(d, name)
    domain = dataclasses.replace(DOMAINS[p.field], unit=p.unit)
    if p.kind == "component" and p.field == "inertia":
        c = d.component(p.owner)
        if c.type == "rigid" or (isinstance(c, Shaft) and c.sections is not None):
            domain = dataclasses.replace(domain, lo_open=True)
    return domain


def _materials(d: Drivetrain) -> dict[str, Material]:
    out: dict[str, Material] = {}
    for c in d.components:
        if isinstance(c, Shaft) and c.material is not None:
            out.setdefault(c.material.name, c.material)
    return out


def _body_ratio(shaft: Shaft) -> float | None:
    """A flexible body's one damping ratio of every elastic mode of its own; None where it is damped per
    mode, per band or by its own Rayleigh damping (no single ratio to set)."""
    damping = shaft.reduce.damping
    if isinstance(damping, ModalDamping):
        plain = not (damping.by_mode or damping.bands or damping.rayleigh is not None)
        return float(damping.ratio) if plain else None
    if isinstance(damping, numbers.Real) and not isinstance(damping, bool):
        return float(damping)
    return None


def is_damping(d: Drivetrain, name: str) -> bool:
    """Whether the parameter called ``name`` sets damping alone (:data:`DAMPING_FIELDS`): the undamped
    modes do not move with it."""
    return find_parameter(d, name).field in DAMPING_FIELDS


def parameters(d: Drivetrain) -> list[Parameter]:
    """Every parameter of a drivetrain: components first (chain order), then materials, then the
    model's Rayleigh damping (``rayleigh.alpha``, ``rayleigh.beta``; the two ratios where the model
    states it so)."""
    out = []
    for c in d.components:
        fields = FIELDS[c.type]
        if isinstance(c, Shaft) and c.sections is not None:
            fields = fields + ("scale",)
        if isinstance(c, Shaft) and (
            (c.reduce is None and c.inertia == 0) or (c.reduce is not None and _body_ratio(c) is None)
        ):
            # modal damping needs the shaft's own modes (an inertia); a flexible body's is its one ratio
            fields = tuple(f for f in fields if f != "damping_ratio")
        if isinstance(c, Gear) and c.rigid_mesh:
            fields = tuple(f for f in fields if not f.startswith("mesh_"))
        out += [Parameter(f"{c.name}.{f}", c.name, f, "component", UNITS[f]) for f in fields]
    for m in _materials(d):
        out += [Parameter(f"{m}.{f}", m, f, "material", UNITS[f]) for f in MATERIAL_FIELDS]
    fields = RAYLEIGH_FIELDS
    if d.rayleigh is not None and d.rayleigh.frequencies_hz is not None:
        fields = fields + RAYLEIGH_RATIO_FIELDS
    out += [Parameter(f"{RAYLEIGH}.{f}", RAYLEIGH, f, "model", UNITS[f]) for f in fields]
    return out


def find_parameter(d: Drivetrain, name: str) -> Parameter:
    """The parameter called ``name``; an error lists the valid ones."""
    if not isinstance(name, str) or "." not in name:
        raise ModelError(
            "not COMPONENT.FIELD or MATERIAL.FIELD",
            field="parameter",
            value=name,
            valid=", ".join(p.name for p in parameters(d)),
        )
    for p in parameters(d):
        if p.name == name:
            return p
    owner, _, field = name.rpartition(".")
    c = next((c for c in d.components if c.name == owner), None)
    if field == "damping_ratio" and isinstance(c, Shaft) and c.reduce is not None:
        raise ModelError(
            "a flexible body damped per mode, per band or by its own Rayleigh damping has no single "
            "damping_ratio to tune",
            field="parameter",
            value=name,
            valid="one damping_ratio on the part in the model file (every elastic mode of its own), or "
            "another parameter: " + ", ".join(p.name for p in parameters(d)),
        )
    if owner == RAYLEIGH and field in RAYLEIGH_RATIO_FIELDS:
        raise ModelError(
            "the model states its Rayleigh damping by alpha and beta (or has none), not by two ratios",
            field="parameter",
            value=name,
            valid="rayleigh.alpha and rayleigh.beta, or [model] rayleigh = {frequencies_hz = [f1, f2], "
            "damping_ratios = [z1, z2]} in the model file",
        )
    raise ModelError(
        "no such parameter", field="parameter", value=name, valid=", ".join(p.name for p in parameters(d))
    )


def _scale_of(shaft: Shaft) -> float:
    return float(shaft.sections.meta.get("scale", 1.0)) if shaft.sections is not None else 1.0


def parameter_value(d: Drivetrain, name: str) -> float:
    """The parameter's present value (SI; a scale is relative to the part as built)."""
    p = find_parameter(d, name)
    if p.kind == "material":
        return float(getattr(_materials(d)[p.owner], p.field))
    if p.kind == "model":
        ray = d.rayleigh
        if ray is None:
            return 0.0
        if p.field in RAYLEIGH_FIELDS:
            return float(getattr(ray, p.field))
        f = ray.frequencies_hz[RAYLEIGH_RATIO_FIELDS.index(p.field)]
        return float(rayleigh_ratio(ray.alpha, ray.beta, f))
    comp = d.component(p.owner)
    if p.field == "scale":
        return _scale_of(comp)
    if p.field == "damping_ratio" and isinstance(comp, Shaft) and comp.reduce is not None:
        return _body_ratio(comp)
    return float(getattr(comp, p.field))


def _with_rayleigh(ray: Rayleigh | None, values: dict) -> Rayleigh:
    """The model's Rayleigh damping with some of its fields (``alpha`` …, ``damping_ratios[0]`` …) set.

    Ratios at the two frequencies give α and β by the closed-form fit
    (:func:`~flexshaft.linalg.damping.rayleigh_coefficients`), the ratio not given kept; coefficients
    and ratios together state one damping twice and are refused.
    """
    freqs = None if ray is None else ray.frequencies_hz
    alpha, beta = (0.0, 0.0) if ray is None else (ray.alpha, ray.beta)
    ratios = [f for f in values if f in RAYLEIGH_RATIO_FIELDS]
    if ratios and len(ratios) != len(values):
        raise ModelError(
            "Rayleigh coefficients and ratios state one damping twice",
            field="parameter",
            value=", ".join(f"{RAYLEIGH}.{f}" for f in values),
            valid="rayleigh.alpha and rayleigh.beta, or the two rayleigh.damping_ratios",
        )
    if not ratios:
        alpha, beta = values.get("alpha", alpha), values.get("beta", beta)
        return Rayleigh(alpha=alpha, beta=beta, frequencies_hz=freqs)
    z = [
        values.get(f, float(rayleigh_ratio(alpha, beta, freqs[k])))
        for k, f in enumerate(RAYLEIGH_RATIO_FIELDS)
    ]
    return Rayleigh.from_ratios(freqs, z, field=RAYLEIGH)  # each ratio checked, named as above


def _rebuilt(shaft: Shaft, material: Material, sections=None) -> Shaft:
    """A shaft from sections with another material (or sections): stiffness and inertia follow."""
    t = shaft.sections if sections is None else sections
    return dataclasses.replace(
        shaft,
        material=material,
        sections=t,
        stiffness=t.torsional_stiffness(material.G),
        inertia=t.axial_inertia(material.rho),
    )


def _scaled(table, s: float):
    """A section table with every cross-section dimension times s (areas s², second moments s⁴)."""
    s2, s4 = s * s, s**4
    meta = dict(table.meta)
    meta["scale"] = float(meta.get("scale", 1.0)) * s
    meta.pop("surface", None)  # the CAD surface no longer fits the scaled sections
    return dataclasses.replace(
        table,
        area=table.area * s2,
        ip=table.ip * s4,
        iy=table.iy * s4,
        iz=table.iz * s4,
        iyz=table.iyz * s4,
        j=table.j * s4,
        shear_area_y=table.shear_area_y * s2,
        shear_area_z=table.shear_area_z * s2,
        yc=table.yc * s,
        zc=table.zc * s,
        meta=meta,
    )


def with_parameters(d: Drivetrain, values: dict) -> Drivetrain:
    """The drivetrain with parameters set to new values (SI), every other value kept.

    A shaft from sections takes a stiffness through its own Young's modulus and an inertia
    through its own density (a material ``"<part> (tuned)"``), a scale through its sections.
    Each value is checked as the component checks it (a negative inertia is an error naming it).
    """
    comps = list(d.components)
    index = {c.name: i for i, c in enumerate(comps)}
    rayleigh: dict = {}  # the model's Rayleigh fields, set together at the end
    for name, value in values.items():
        p = find_parameter(d, name)
        value = check_real(value, p.name, p.unit)
        if p.kind == "model":
            rayleigh[p.field] = value
            continue
        try:
            if p.kind == "material":
                for i, c in enumerate(comps):
                    if isinstance(c, Shaft) and c.material is not None and c.material.name == p.owner:
                        m = dataclasses.replace(c.material, **{p.field: value})
                        comps[i] = _rebuilt(c, m)
                continue
            i = index[p.owner]
            c = comps[i]
            if (
                isinstance(c, Shaft)
                and c.sections is not None
                and p.field in ("stiffness", "inertia", "scale")
            ):
                if p.field == "scale":
                    if value <= 0:
                        raise ModelError("out of range", field=p.name, value=value, valid="a scale > 0")
                    comps[i] = _rebuilt(c, c.material, _scaled(c.sections, value / _scale_of(c)))
                    continue
                key, now = ("E", c.stiffness) if p.field == "stiffness" else ("rho", c.inertia)
                if not value > 0:
                    raise ModelError("out of range", field=p.name, value=value, unit=p.unit, valid="> 0")
                m = c.material
                own = m.name if m.name.endswith(" (tuned)") else f"{c.name} (tuned)"
                m = dataclasses.replace(m, name=own, **{key: getattr(m, key) * value / now})
                comps[i] = _rebuilt(c, m)
                continue
            if isinstance(c, Shaft) and c.reduce is not None and p.field == "damping_ratio":
                # a flexible body's one ratio (the shaft's own is not used with reduce)
                damping = c.reduce.damping
                damping = (
                    dataclasses.replace(damping, ratio=value)
                    if isinstance(damping, ModalDamping)
                    else ModalDamping(ratio=value)
                )
                comps[i] = dataclasses.replace(c, reduce=dataclasses.replace(c.reduce, damping=damping))
                continue
            comps[i] = dataclasses.replace(c, **{p.field: value})
        except ModelError as err:
            if err.field is None or "." not in str(err.field):
                # the parameter's own name (the message is rendered when an error is made: a new one)
                raise err.replaced(field=p.name) from None
            raise
    if rayleigh:
        return dataclasses.replace(d, components=tuple(comps), rayleigh=_with_rayleigh(d.rayleigh, rayleigh))
    return dataclasses.replace(d, components=tuple(comps))
