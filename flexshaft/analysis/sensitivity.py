"""Model parameters by name, and the exact sensitivity of every mode to each of them.

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

Sensitivities are analytic: for a mass-normalised mode φ with eigenvalue λ = ω²,
``∂λ/∂p = φᵀ(∂K/∂p − λ ∂M/∂p)φ`` - exact for the discrete model. ∂K/∂p and ∂M/∂p are the
derivatives of the assembled matrices, taken by a central difference of the assembly, which is
exact to round-off for every parameter the matrices are linear or quadratic in (all but a
section scale in a 6-DOF model, where it is O(h²) = 1e-12). The first-order damping ratio
ξ = φᵀCφ/(2ω) gets its derivative from ∂C/∂p, ∂ω and the mode's own derivative ∂φ (by modal
expansion over all modes, exact when every mode of the model is computed: torsion models up to
2000 coordinates). Flexible bodies are differentiated on the unreduced model (the physical
sensitivity; the reduced model reproduces it to its reduction error), which carries no damping of a
flexible body's own: ∂ξ/∂p of a body's ``damping_ratio`` is NaN there (the calibration evaluates it
on the reduced model, :mod:`flexshaft.analysis.calibrate`).

:class:`ParametrisedModel` is the assembly as a function of some parameters for a caller that
evaluates many points (a calibration): ∂K and ∂M taken once, and for the fields K and M are
affine in (:data:`AFFINE_FIELDS`: every stiffness, inertia, E and ρ) K(x) = K0 + Σ Δx_k ∂K_k with
no assembly at all - checked against an assembly at a moved point, never assumed. ``scale``,
``ratio`` and ``nu`` are not affine (k ∝ s⁴; a mesh block k·[1, −n; −n, n²], a rigid mesh's 1/n²;
G = E/2(1+ν)) and are assembled and differenced at each point, as is an affine field whose
derivative another parameter changes (a shaft's stiffness next to its scale, anything past a gear
whose ratio is tuned).
"""

from __future__ import annotations

import dataclasses
import functools
import numbers
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..elements.materials import Material
from ..errors import ModelError
from ..linalg.damping import RAYLEIGH_ALPHA_MAX, RAYLEIGH_BETA_MAX, rayleigh_coefficients, rayleigh_ratio
from ..model.assembly import assemble
from ..model.components import GEAR_RATIO_RANGE, Drivetrain, Gear, Rayleigh, Shaft
from ..reduction.modaldamping import ModalDamping
from ..system.threads import follows_policy
from ..validation import check_int, check_real
from .modal import ModalResult, modal_analysis

__all__ = [
    "Parameter",
    "Domain",
    "parameter_domain",
    "Sensitivities",
    "parameters",
    "find_parameter",
    "parameter_value",
    "with_parameters",
    "sensitivities",
    "lowest_elastic",
    "ParametrisedModel",
    "frequency_derivatives",
    "is_damping",
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
    "stiffness": (0.0, True, None, False),
    "inertia": (0.0, False, None, False),
    "damping": (0.0, False, None, False),
    "damping_ratio": (0.0, False, 1.0, True),
    "scale": (0.0, True, None, False),
    "ratio": (GEAR_RATIO_RANGE[0], False, GEAR_RATIO_RANGE[1], False),
    "inertia_in": (0.0, False, None, False),
    "inertia_out": (0.0, False, None, False),
    "mesh_stiffness": (0.0, True, None, False),
    "mesh_damping": (0.0, False, None, False),
    "E": (0.0, True, None, False),
    "rho": (0.0, True, None, False),
    "nu": (-1.0, True, 0.5, True),
    "alpha": (0.0, False, RAYLEIGH_ALPHA_MAX, False),
    "beta": (0.0, False, RAYLEIGH_BETA_MAX, False),
    "damping_ratios[0]": (0.0, False, 1.0, True),
    "damping_ratios[1]": (0.0, False, 1.0, True),
}
#: Relative step of the central difference of the assembled matrices (exact for linear and
#: quadratic dependence; the round-off it leaves is ~1e-16/h = 1e-10 of the derivative).
STEP = 1e-6
#: Largest model whose damping-ratio sensitivities are computed (all its modes are needed).
MAX_DAMPING_DOFS = 2000
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
#: Relative step of the central difference of an affine field: any step is exact for an affine
#: dependence, and a wide one leaves round-off of eps·|K|/h ~ 1e-15 of the derivative (against
#: 1e-10 at :data:`STEP`); 1/4 keeps every value positive, as the components require.
AFFINE_STEP = 0.25
#: An assembly at a moved point equals the affine model K0 + Σ Δx_k ∂K_k entry by entry, ij within
#: this fraction of √(d_i·d_j), d the diagonals of the terms (which bound every term summed into ij,
#: see :func:`_agrees`). Each side sums a few terms rounded to eps = 2.2e-16 (a node's elements, the
#: p + 1 terms of the model, whose derivatives err by ~eps·Δx/h, h the step), ~1e-15 in all with any
#: BLAS kernel's summation order; 1e-12 leaves a thousandfold margin. It guards the list above: two
#: of its fields acting on each other (a product of their changes) or a field not affine after all
#: would move an entry by a product of relative changes - (Δx/x)², 1e-4 for ±1 % bounds.
AFFINE_RTOL = 1e-12


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


@dataclass(frozen=True)
class Domain:
    """The values a parameter may take: ``lo`` < or <= x < or <= ``hi`` (None: unbounded), SI.

    Attributes
    ----------
    lo, hi : float or None
    lo_open, hi_open : bool
        Whether the bound itself is excluded.
    unit : str
    """

    lo: float | None
    lo_open: bool
    hi: float | None
    hi_open: bool
    unit: str = ""

    def contains(self, x: float) -> bool:
        """Whether ``x`` is a finite value inside the domain."""
        x = float(x)
        if not np.isfinite(x):
            return False
        if self.lo is not None and (x <= self.lo if self.lo_open else x < self.lo):
            return False
        return not (self.hi is not None and (x >= self.hi if self.hi_open else x > self.hi))

    @property
    def text(self) -> str:
        """``"> 0 N·m/rad"``, ``">= 0 and < 1"``: the domain for an error message."""
        parts = []
        if self.lo is not None:
            parts.append(f"{'>' if self.lo_open else '>='} {self.lo:g}")
        if self.hi is not None:
            parts.append(f"{'<' if self.hi_open else '<='} {self.hi:g}")
        return " and ".join(parts or ["finite"]) + (f" {self.unit}" if self.unit else "")


def parameter_domain(d: Drivetrain, name: str) -> Domain:
    """The values the parameter called ``name`` may take (:data:`DOMAINS`; an error lists the names).

    A rigid inertia is > 0 (a rigid body without inertia is no body), and so is a stiffness or
    inertia of a part from sections (set through its E and ρ, both > 0); every other field as the
    component or material accepts it in a model file.
    """
    p = find_parameter(d, name)
    lo, lo_open, hi, hi_open = DOMAINS[p.field]
    if p.kind == "component" and p.field == "inertia":
        c = d.component(p.owner)
        if c.type == "rigid" or (isinstance(c, Shaft) and c.sections is not None):
            lo_open = True
    return Domain(lo, lo_open, hi, hi_open, p.unit)


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
    for k, f in enumerate(RAYLEIGH_RATIO_FIELDS):
        check_real(z[k], f"{RAYLEIGH}.{f}", "", lo=0.0, hi=1.0, hi_open=True)
    alpha, beta = rayleigh_coefficients(freqs[0], z[0], freqs[1], z[1])
    # each is a difference of two terms; round-off leaves a coefficient that should be 0 at ~eps of them
    w1, w2 = 2 * np.pi * freqs[0], 2 * np.pi * freqs[1]
    span = abs(w2**2 - w1**2)
    alpha_terms = 2 * w1 * w2 * (z[0] * w2 + z[1] * w1) / span
    beta_terms = 2 * (z[0] * w1 + z[1] * w2) / span
    if alpha < -1e-12 * alpha_terms or beta < -1e-12 * beta_terms:
        raise ModelError(
            "these ratios need a negative Rayleigh coefficient "
            f"(alpha = {alpha:.4g} 1/s, beta = {beta:.4g} s)",
            field=f"{RAYLEIGH}.damping_ratios",
            value=[float(v) for v in z],
            valid=f"ratios at {freqs[0]:g} and {freqs[1]:g} Hz whose alpha and beta are both >= 0",
        )
    return Rayleigh(alpha=max(alpha, 0.0), beta=max(beta, 0.0), frequencies_hz=freqs)


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


@dataclass(frozen=True)
class Sensitivities:
    """How every listed mode moves with every parameter.

    Attributes
    ----------
    parameters : tuple of Parameter
    values : ndarray, shape (p,)
        Each parameter's value, SI.
    modes : ndarray of int
        The modes (numbered as ``flexshaft modes`` does; rigid-body modes left out).
    frequencies_hz : ndarray, shape (m,)
    damping_ratios : ndarray, shape (m,)
        First-order ratios φᵀCφ/(2ω) (0 without damping).
    dfrequency : ndarray, shape (m, p)
        ∂f/∂p, Hz per parameter unit.
    ddamping : ndarray, shape (m, p) or None
        ∂ξ/∂p (first-order ξ), per parameter unit; None where not all modes are available; NaN for a
        flexible body's ``damping_ratio`` (its damping acts on the reduced model, not on the unreduced
        one differentiated here).
    """

    parameters: tuple
    values: np.ndarray
    modes: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    dfrequency: np.ndarray
    ddamping: np.ndarray | None

    @property
    def normalised(self) -> np.ndarray:
        """(p/f)·∂f/∂p: % change of each frequency per % change of each parameter, shape (m, p)."""
        return self.dfrequency * self.values[None, :] / self.frequencies_hz[:, None]

    @property
    def normalised_damping(self) -> np.ndarray | None:
        """(p/ξ)·∂ξ/∂p, shape (m, p); NaN where ξ = 0."""
        if self.ddamping is None:
            return None
        with np.errstate(divide="ignore", invalid="ignore"):
            z = self.damping_ratios[:, None]
            return np.where(z > 0, self.ddamping * self.values[None, :] / z, np.nan)

    def to_dict(self) -> dict:
        """The ``flexshaft sensitivity --json`` document."""

        def num(x):
            x = float(x)
            return x if np.isfinite(x) else None

        nd = self.normalised_damping
        return {
            "units": {
                "frequency": "Hz",
                "dfrequency": "Hz per parameter unit",
                "normalised": "% per % (p/f·∂f/∂p)",
                "damping_ratio": "fraction (first order, φᵀCφ/2ω)",
            },
            "parameters": [
                {"name": p.name, "value": float(v), "unit": p.unit}
                for p, v in zip(self.parameters, self.values)
            ],
            "modes": [
                {
                    "mode": int(m),
                    "frequency_hz": float(self.frequencies_hz[i]),
                    "damping_ratio": float(self.damping_ratios[i]),
                    "dfrequency": {p.name: num(v) for p, v in zip(self.parameters, self.dfrequency[i])},
                    "normalised": {p.name: num(v) for p, v in zip(self.parameters, self.normalised[i])},
                    **(
                        {}
                        if self.ddamping is None
                        else {
                            "ddamping": {p.name: num(v) for p, v in zip(self.parameters, self.ddamping[i])},
                            "normalised_damping": {p.name: num(v) for p, v in zip(self.parameters, nd[i])},
                        }
                    ),
                }
                for i, m in enumerate(self.modes)
            ],
        }

    def plot(self):
        """The normalised sensitivities as a heat map (modes × parameters), a matplotlib Figure."""
        from ..views.plots import sensitivity_figure

        return sensitivity_figure(self)

    def table(self, name: str) -> str:
        """The ``flexshaft sensitivity`` table of the model ``name``: % per % for each parameter and
        mode."""
        width = max(16, *(len(p.name) for p in self.parameters))
        rows = [
            f"{name}: frequency sensitivities, % per % (p/f·∂f/∂p); Hz per unit with --json",
            "",
            f"{'parameter':<{width}} {'value':>12} {'unit':>9}  "
            + "  ".join(f"{f'mode {m}':>9}" for m in self.modes),
            f"{'':<{width}} {'':>12} {'':>9}  "
            + "  ".join(f"{f'{f:.4g} Hz':>9}" for f in self.frequencies_hz),
        ]
        for k, p in enumerate(self.parameters):
            cells = "  ".join(f"{v:9.4f}" for v in self.normalised[:, k])
            rows.append(f"{p.name:<{width}} {self.values[k]:12.6g} {p.unit:>9}  {cells}")
        return "\n".join(rows)


def _mode_numbers(modes, model) -> np.ndarray:
    """``modes`` as mode numbers of ``model``'s elastic modes, checked before anything is solved:
    whole numbers from the first elastic mode (the rigid-body modes come first) to the last."""
    n, rigid = model.n_dof, model.rigid_basis.shape[1]
    valid = f"an elastic mode, {rigid} … {n - 1}" if n > rigid else "a model with elastic modes"
    try:
        numbers = list(np.ravel(np.asarray(modes, dtype=object)))
    except (TypeError, ValueError):
        raise ModelError("not a list of mode numbers", field="mode", valid=valid) from None
    if not numbers:
        raise ModelError("no modes", field="mode", valid=valid)
    out = []
    for i in numbers:
        k = check_int(i, "mode", lo=0)
        if k < rigid or k >= n:
            zero = "mode 0" if rigid == 1 else f"modes 0 … {rigid - 1}"
            raise ModelError(
                f"the model has {n} modes, {zero} rigid-body",
                field="mode",
                value=k,
                valid=valid,
            )
        out.append(k)
    return np.array(out, dtype=int)


def lowest_elastic(model, count, field: str) -> np.ndarray:
    """The numbers of the lowest ``count`` elastic modes of an assembled model, as ``flexshaft modes``
    numbers them (the rigid-body modes first); more than the model has is refused, naming ``field``.

    Parameters
    ----------
    model : AssembledModel
    count : int
    field : str
        The option or argument the count came from (``"--modes"``), for the message.
    """
    n, rigid = model.n_dof, model.rigid_basis.shape[1]
    count = check_int(count, field, lo=1)
    if count > n - rigid:
        zero = "mode 0 is" if rigid == 1 else f"modes 0 … {rigid - 1} are"
        raise ModelError(
            f"the model has only {n} DOFs, so {n} modes, {n - rigid} of them elastic ({zero} rigid-body)",
            field=field,
            value=count,
            valid=f"at most {n - rigid}" if n > rigid else "a model with elastic modes",
        )
    return np.arange(rigid, rigid + count)


def _matrices(d: Drivetrain, inertia_model):
    m = assemble(d, inertia_model, reduce=False)
    C = m.C if m.C is not None else sp.csr_matrix(m.K.shape)
    return m, m.K, m.M, C


def _in_double_precision(func):
    """Run ``func`` with numpy's floating-point errors raised, each refused as one ModelError: the
    central differences of a parameter of extreme size (an inertia of 1e-308, a damper of 1e308)
    leave double precision, and a warning beside the table would hide that its numbers are not."""

    @functools.wraps(func)
    def run(*args, **kwargs):
        try:
            with np.errstate(over="raise", divide="raise", invalid="raise"):
                return func(*args, **kwargs)
        except FloatingPointError as err:
            raise ModelError(
                f"the derivatives leave double precision ({err})",
                field="parameter",
                valid="stiffness, inertia and damping within a few hundred orders of 1 in SI units",
            ) from None

    return run


@follows_policy
@_in_double_precision
def sensitivities(
    drivetrain: Drivetrain,
    names=None,
    *,
    modes=None,
    inertia_model: str | None = None,
    result: ModalResult | None = None,
) -> Sensitivities:
    """Analytic sensitivities of the modes of ``drivetrain`` to the named parameters.

    Parameters
    ----------
    drivetrain : Drivetrain
    names : sequence of str, optional
        Parameters (default: every parameter, see :func:`parameters`).
    modes : sequence of int, optional
        Modes to report, numbered as ``flexshaft modes`` numbers them (default: every elastic mode
        computed: all of a model up to :data:`MAX_DAMPING_DOFS` coordinates, else the solver's
        default count). A rigid-body mode or a number beyond the model's modes is refused before
        anything is solved (:func:`lowest_elastic` gives the lowest N).
    inertia_model : str, optional
    result : ModalResult, optional
        The modes of the unreduced model of ``drivetrain``, if already computed (its assembly is
        used as it is).
    """
    if not isinstance(drivetrain, Drivetrain):
        raise ModelError("needs a Drivetrain", field="model", valid="a Drivetrain (load_model)")
    plist = (
        [p for p in parameters(drivetrain)]
        if names is None
        else [find_parameter(drivetrain, n) for n in names]
    )
    if not plist:
        raise ModelError("no parameters", field="parameter", valid="at least one")
    twice = [p.name for k, p in enumerate(plist) if p in plist[:k]]
    if twice:
        raise ModelError("a parameter is listed twice", field="parameter", value=twice[0], valid="each once")
    if result is not None and not result.model.bodies:
        # the modes were solved on this very (unreduced) assembly: its matrices, not a second one
        model0 = result.model
        C0 = model0.C if model0.C is not None else sp.csr_matrix(model0.K.shape)
        K0, M0 = model0.K, model0.M
    else:
        model0, K0, M0, C0 = _matrices(drivetrain, inertia_model)
    wanted = None if modes is None else _mode_numbers(modes, model0)
    if result is None:
        count = model0.n_dof if model0.n_dof <= MAX_DAMPING_DOFS else None
        if count is None and wanted is not None:
            count = max(int(wanted.max()) + 1, 1)  # up to the highest mode asked for, however many
        result = modal_analysis(model0, count, damped=False)
    elastic = np.flatnonzero(~result.rigid)
    sel = elastic if wanted is None else wanted
    bad = [int(i) for i in sel if i < 0 or i >= result.count or result.rigid[i]]
    if bad:
        raise ModelError(
            "no such elastic mode",
            field="mode",
            value=bad[0],
            valid=f"{int(elastic[0])} … {result.count - 1}" if elastic.size else "a model with elastic modes",
        )
    Phi = result.shapes
    lam = result.omega**2
    values = np.array([parameter_value(drivetrain, p.name) for p in plist])
    full = result.count == model0.n_dof  # every mode: the modal expansion of ∂φ is exact
    dlam = np.zeros((sel.size, len(plist)))
    dzeta = np.zeros((sel.size, len(plist))) if full else None
    w = np.sqrt(lam[sel])
    C = C0
    zeta = np.einsum("ij,ij->j", Phi[:, sel], C @ Phi[:, sel]) / (2 * w)
    for k, p in enumerate(plist):
        v = values[k]
        h = STEP * (abs(v) if v != 0 else 1.0)
        plus = _matrices(with_parameters(drivetrain, {p.name: v + h}), inertia_model)
        if v == 0:
            # at the bound 0 (no damper yet): a forward difference, as exact for the linear dependence
            minus, h = (model0, K0, M0, C0), h / 2
        else:
            minus = _matrices(with_parameters(drivetrain, {p.name: v - h}), inertia_model)
        if plus[1].shape != K0.shape or minus[1].shape != K0.shape:
            raise ModelError(
                "changes the model's mesh, so it has no derivative here", field="parameter", value=p.name
            )
        dK = (plus[1] - minus[1]) / (2 * h)
        dM = (plus[2] - minus[2]) / (2 * h)
        dC = (plus[3] - minus[3]) / (2 * h)
        dKP, dMP = dK @ Phi, dM @ Phi
        for a, i in enumerate(sel):
            dlam[a, k] = Phi[:, i] @ dKP[:, i] - lam[i] * (Phi[:, i] @ dMP[:, i])
        if dzeta is not None:
            for a, i in enumerate(sel):
                # ∂φ_i = Σ_{j≠i} φ_j·φ_jᵀ(∂K − λ_i∂M)φ_i/(λ_i − λ_j) − ½(φ_iᵀ∂Mφ_i)·φ_i (mass-normalised)
                r = Phi.T @ (dKP[:, i] - lam[i] * dMP[:, i])
                gap = lam[i] - lam
                coef = np.where(np.arange(lam.size) == i, 0.0, r / np.where(gap == 0, np.inf, gap))
                coef[i] = -0.5 * (Phi[:, i] @ dMP[:, i])
                dphi = Phi @ coef
                dw = dlam[a, k] / (2 * w[a])
                dzeta[a, k] = (2 * Phi[:, i] @ (C @ dphi) + Phi[:, i] @ (dC @ Phi[:, i])) / (2 * w[a]) - zeta[
                    a
                ] * dw / w[a]
    if dzeta is not None:
        for k, p in enumerate(plist):
            c = drivetrain.component(p.owner) if p.kind == "component" else None
            if p.field == "damping_ratio" and isinstance(c, Shaft) and c.reduce is not None:
                # a flexible body's damping acts on its reduced model only: not seen here (see above)
                dzeta[:, k] = np.nan
    f = w / (2 * np.pi)
    dfreq = dlam / (2 * w[:, None]) / (2 * np.pi)  # f = √λ/2π: ∂f = ∂λ/(2ω·2π)
    return Sensitivities(
        parameters=tuple(plist),
        values=values,
        modes=sel,
        frequencies_hz=f,
        damping_ratios=zeta,
        dfrequency=dfreq,
        ddamping=dzeta,
    )


def _magnitude_pattern(mats) -> tuple:
    """The union sparsity pattern of ``mats`` (CSR indptr, indices) and each one's values on it,
    one column per matrix (duplicates summed)."""
    n = mats[0].shape[1]
    P = sp.csr_matrix(mats[0].shape)
    for A in mats:
        P = P + abs(sp.csr_matrix(A))
    P.sum_duplicates()
    P.sort_indices()
    keys = np.repeat(np.arange(P.shape[0], dtype=np.int64), np.diff(P.indptr)) * n + P.indices
    out = np.zeros((P.nnz, len(mats)))
    for j, A in enumerate(mats):
        A = sp.coo_matrix(A)
        keep = A.data != 0  # an explicit zero adds nothing and may sit off the pattern
        pos = np.searchsorted(keys, A.row[keep].astype(np.int64) * n + A.col[keep])
        np.add.at(out[:, j], pos, A.data[keep])
    return P.indptr, P.indices, out


def _agrees(A, B, diagonal: np.ndarray, rtol: float) -> bool:
    """|A − B|_ij <= rtol·√(d_i·d_j) for every entry, d = ``diagonal`` (>= 0).

    K and M and the derivatives of the affine fields are sums of positive semi-definite element
    blocks, whose entries obey |a_ij| <= √(a_ii·a_jj) and whose diagonals add without cancelling: so
    √(d_i·d_j) bounds every term that went into entry ij (Cauchy-Schwarz), and an entry that should
    cancel to 0 (a coupling term of a 6-DOF model, left as ~eps times its terms) is judged against
    those terms rather than against its own round-off.
    """
    D = sp.coo_matrix(abs(sp.csr_matrix(A) - sp.csr_matrix(B)))
    return bool(np.all(D.data <= rtol * np.sqrt(diagonal[D.row] * diagonal[D.col])))


class ParametrisedModel:
    """The assembled K and M of a drivetrain as functions of named parameters.

    Each point ``x`` (the parameters' values, SI, in the order of ``names``) stands for the model
    ``with_parameters(drivetrain, dict(zip(names, x)))`` assembled unreduced. The derivatives
    ∂K/∂x_k, ∂M/∂x_k are taken once, at ``x0``, by central differences of that assembly. For the
    fields K and M are affine in (:data:`AFFINE_FIELDS`) the derivative is the same everywhere;
    where every parameter is such a field,

        K(x) = K(x0) + Σ_k (x_k − x0_k)·∂K/∂x_k    (M likewise)

    is the assembly at every point, exactly to round-off, and a point needs no assembly at all.
    That is checked, not assumed: the assembly at ``probe`` (a point with every parameter moved)
    must equal the affine model entry by entry (:data:`AFFINE_RTOL`). A parameter of another field
    (``scale``, ``ratio``, ``nu``), or a model failing the check, is assembled at each point and its
    derivative differenced afresh there; an affine field whose derivative at ``probe`` equals the
    one at ``x0`` (the same test) keeps it even then.

    Parameters
    ----------
    drivetrain : Drivetrain
    names : sequence of str
        The parameters (see :func:`parameters`).
    x0 : array_like, optional
        The point the derivatives are taken at, SI (default: the drivetrain's values).
    probe : array_like, optional
        A point with every parameter moved (distinct relative moves, so that no coincidence hides
        a term; within the values to be used). Default: ``x0`` times 1 ± 5 %·(k + 1)/(p + 1), the
        sign alternating.
    bounds : (array_like, array_like), optional
        Lower and upper values the model will be evaluated within, SI: the affine model is used
        only if the components accept every value inside them (checked at both corners).
    inertia_model : str, optional

    Attributes
    ----------
    names : tuple of str
    x0 : ndarray
    model0 : AssembledModel
        The assembly at ``x0`` (undamped: C is not needed for K and M).
    dK, dM : tuple of scipy.sparse.csr_matrix
        ∂K/∂x_k and ∂M/∂x_k at ``x0`` (K's and M's units per parameter unit, SI).
    constant : ndarray of bool
        Whose derivative is the same at every point.
    affine : bool
        Whether K(x), M(x) come from the affine model (every derivative constant and the check
        at ``probe`` met) or from an assembly at each point.
    """

    @_in_double_precision
    def __init__(
        self, drivetrain: Drivetrain, names, x0=None, *, probe=None, bounds=None, inertia_model=None
    ):
        self.drivetrain = drivetrain
        self.names = tuple(names)
        self.inertia_model = inertia_model
        fields = [find_parameter(drivetrain, n).field for n in self.names]
        self.x0 = (
            np.array([parameter_value(drivetrain, n) for n in self.names], dtype=float)
            if x0 is None
            else np.array(x0, dtype=float)
        )
        self.model0 = self._assemble(self.x0)
        candidate = np.array([f in AFFINE_FIELDS for f in fields])
        self._step = np.where(candidate, AFFINE_STEP, STEP)  # relative, per parameter
        zero = sp.csr_matrix(self.model0.K.shape)
        derivs = [
            (zero, zero) if f in DAMPING_FIELDS else self._difference(self.x0, k)
            for k, f in enumerate(fields)
        ]
        self.dK = tuple(d[0] for d in derivs)
        self.dM = tuple(d[1] for d in derivs)
        if probe is None:
            k = np.arange(len(self.names))
            probe = self.x0 * (1 + 0.05 * (k + 1) / (k.size + 1) * (-1.0) ** k)
        probe = np.array(probe, dtype=float)
        K0, M0 = self.model0.K, self.model0.M
        # the union pattern of K0 and every ∂K (M likewise): a point's K is one product of its values
        self._k_pattern = _magnitude_pattern([K0, *self.dK])
        self._m_pattern = _magnitude_pattern([M0, *self.dM])
        try:
            at = self._assemble(probe)
        except ModelError:  # a probe the components refuse: nothing verified, every point assembled
            at = None
        affine = (
            at is not None and bool(candidate.all()) and self._affine_at(probe, at) and self._valid(bounds)
        )
        constant = candidate & (at is not None)
        constant |= np.isin(fields, list(DAMPING_FIELDS))  # 0 wherever they are
        if not affine:
            for k in np.flatnonzero(constant & ~np.isin(fields, list(DAMPING_FIELDS))):
                # an affine field keeps its derivative if it is the same at the probe
                try:
                    dk, dm = self._difference(probe, k)
                except ModelError:
                    constant[k] = False
                    continue
                constant[k] = self._close(dk, self.dK[k]) and self._close(dm, self.dM[k])
        self.constant = constant
        self.affine = affine
        # what is differenced afresh at each point takes the small step: its dependence is not known
        # to be affine there
        self._step = np.where(constant, AFFINE_STEP, STEP)

    def _valid(self, bounds) -> bool:
        """Whether every value inside ``bounds`` is one the components accept: each affine field is
        valid on an interval (> 0, >= 0, a damping ratio < 1), so the box is where both corners are. The
        affine model skips the components' checks, so outside such a box every point is assembled
        (and a value out of range is refused there, as always)."""
        if bounds is None:
            return True
        for corner in bounds:
            try:
                with_parameters(self.drivetrain, dict(zip(self.names, corner)))
            except ModelError:
                return False
        return True

    def _assemble(self, x):
        m = assemble(
            with_parameters(self.drivetrain, dict(zip(self.names, x))),
            self.inertia_model,
            reduce=False,
            damping=False,
        )
        return m

    def _difference(self, x, k: int):
        """∂K/∂x_k and ∂M/∂x_k at x by a central difference of the assembly (relative step
        :data:`AFFINE_STEP` for an affine field, :data:`STEP` for another; a unit step from 0)."""
        h = self._step[k] * (abs(x[k]) if x[k] != 0 else 1.0)
        lo, hi = x.copy(), x.copy()
        lo[k] -= h
        hi[k] += h
        if x[k] == 0:  # at the bound 0: a forward difference, as exact for an affine dependence
            lo[k] = x[k]
        span = hi[k] - lo[k]
        a, b = self._assemble(lo), self._assemble(hi)
        if a.K.shape != self.model0.K.shape or b.K.shape != self.model0.K.shape:
            raise ModelError(
                "changes the model's mesh, so it has no derivative here",
                field="parameter",
                value=self.names[k],
            )
        return (b.K - a.K) / span, (b.M - a.M) / span

    @staticmethod
    def _close(A, B) -> bool:
        return _agrees(A, B, np.abs(A.diagonal()) + np.abs(B.diagonal()), AFFINE_RTOL)

    def _affine_at(self, x, at) -> bool:
        """Whether the assembly ``at`` (at x) is the affine model there (see :data:`AFFINE_RTOL`)."""
        if at.K.shape != self.model0.K.shape:
            return False
        K, M = self.matrices(x, force=True)
        dx = np.abs(x - self.x0)
        ok = True
        for A, B, A0, dA in ((at.K, K, self.model0.K, self.dK), (at.M, M, self.model0.M, self.dM)):
            # the diagonal of every term of the affine model and of the assembly itself
            d = np.abs(A0.diagonal()) + np.abs(A.diagonal())
            d += sum((a * np.abs(D.diagonal()) for a, D in zip(dx, dA)), np.zeros(d.size))
            ok = ok and _agrees(A, B, d, AFFINE_RTOL)
        return ok

    def matrices(self, x, *, force: bool = False):
        """K and M at x (CSR): the affine model, or the assembly where the model is not affine.

        Parameters
        ----------
        x : array_like
            The parameters' values, SI.
        force : bool
            Evaluate the affine model even where it is not exact (for the check).
        """
        x = np.asarray(x, dtype=float)
        if not (force or self.affine):
            m = self._assemble(x)
            return m.K, m.M
        c = np.concatenate([[1.0], x - self.x0])
        n = self.model0.K.shape
        out = []
        for indptr, indices, values in (self._k_pattern, self._m_pattern):
            out.append(sp.csr_matrix((values @ c, indices, indptr), shape=n))
        return tuple(out)

    def model(self, x):
        """The AssembledModel at x: the one at ``x0`` with K and M of x (affine), else assembled.

        Only K and M (and what no parameter changes: coordinates, stations, rigid-body motions)
        belong to x in the affine case; its C is None (K and M alone are parametrised).
        """
        x = np.asarray(x, dtype=float)
        if not self.affine:
            return self._assemble(x)
        K, M = self.matrices(x)
        return dataclasses.replace(self.model0, K=K, M=M, C=None)

    def derivatives(self, x) -> list:
        """[(∂K/∂x_k, ∂M/∂x_k)] at x: the constant ones as taken at ``x0``, the rest differenced there."""
        x = np.asarray(x, dtype=float)
        return [
            (self.dK[k], self.dM[k]) if self.constant[k] else self._difference(x, k)
            for k in range(len(self.names))
        ]


@follows_policy
def frequency_derivatives(result: ModalResult, derivatives, modes) -> np.ndarray:
    """∂f/∂x of the given modes from ∂λ = φᵀ(∂K − λ∂M)φ (mass-normalised φ), Hz per parameter unit.

    Parameters
    ----------
    result : ModalResult
        The modes at the point (mass-normalised shapes).
    derivatives : sequence of (∂K, ∂M)
        Per parameter (:meth:`ParametrisedModel.derivatives`).
    modes : sequence of int
        Elastic modes of ``result``.

    Returns
    -------
    ndarray, shape (len(modes), len(derivatives))
    """
    modes = np.asarray(modes, dtype=int)
    Phi = result.shapes[:, modes]
    lam = result.omega[modes] ** 2
    dlam = np.empty((modes.size, len(derivatives)))
    for k, (dK, dM) in enumerate(derivatives):
        dlam[:, k] = np.einsum("ij,ij->j", Phi, dK @ Phi) - lam * np.einsum("ij,ij->j", Phi, dM @ Phi)
    w = result.omega[modes]
    return dlam / (2 * w[:, None]) / (2 * np.pi)  # f = √λ/2π: ∂f = ∂λ/(2ω·2π)
