"""Model parameters by name, and the exact sensitivity of every mode to each of them.

A parameter is named ``COMPONENT.FIELD`` or ``MATERIAL.FIELD``:

- a rigid inertia: ``motor.inertia``;
- a shaft given by numbers: ``stiffness``, ``inertia``, ``damping``, ``damping_ratio``;
- a shaft made from sections (a CAD part, segments): ``stiffness`` and ``inertia`` too - set by
  the part's own Young's modulus (k ∝ E at fixed ν) and density (j ∝ ρ), the way a tuned
  stiffness goes back to physics - ``scale`` (every cross-section dimension times s, lengths
  kept: k and j ∝ s⁴; 1 as built), ``damping``, ``damping_ratio``;
- a coupling: ``stiffness``, ``inertia``, ``damping``;
- a gear stage: ``ratio``, ``inertia_in``, ``inertia_out``, ``mesh_stiffness``, ``mesh_damping``;
- a material every part made of it shares: ``steel.E``, ``steel.rho``, ``steel.nu``.

Sensitivities are analytic: for a mass-normalised mode φ with eigenvalue λ = ω²,
``∂λ/∂p = φᵀ(∂K/∂p − λ ∂M/∂p)φ`` - exact for the discrete model. ∂K/∂p and ∂M/∂p are the
derivatives of the assembled matrices, taken by a central difference of the assembly, which is
exact to round-off for every parameter the matrices are linear or quadratic in (all but a
section scale in a 6-DOF model, where it is O(h²) = 1e-12). The first-order damping ratio
ξ = φᵀCφ/(2ω) gets its derivative from ∂C/∂p, ∂ω and the mode's own derivative ∂φ (by modal
expansion over all modes, exact when every mode of the model is computed: torsion models up to
2000 coordinates). Flexible bodies are differentiated on the unreduced model (the physical
sensitivity; the reduced model reproduces it to its reduction error).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..materials import Material
from ..model.assembly import assemble
from ..model.components import Drivetrain, Gear, Shaft
from ..threads import follows_policy
from ..validation import check_real
from .modal import ModalResult, modal_analysis

__all__ = [
    "Parameter",
    "Sensitivities",
    "parameters",
    "find_parameter",
    "parameter_value",
    "with_parameters",
    "sensitivities",
]

#: Fields that can be a parameter, by component type (shafts from sections add ``scale``).
FIELDS = {
    "rigid": ("inertia",),
    "shaft": ("stiffness", "inertia", "damping", "damping_ratio"),
    "coupling": ("stiffness", "inertia", "damping"),
    "gear": ("ratio", "inertia_in", "inertia_out", "mesh_stiffness", "mesh_damping"),
}
MATERIAL_FIELDS = ("E", "rho", "nu")
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
}
#: Relative step of the central difference of the assembled matrices (exact for linear and
#: quadratic dependence; the round-off it leaves is ~1e-16/h = 1e-10 of the derivative).
STEP = 1e-6
#: Largest model whose damping-ratio sensitivities are computed (all its modes are needed).
MAX_DAMPING_DOFS = 2000


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
        ``"component"`` or ``"material"``.
    unit : str
    """

    name: str
    owner: str
    field: str
    kind: str
    unit: str


def _materials(d: Drivetrain) -> dict[str, Material]:
    out: dict[str, Material] = {}
    for c in d.components:
        if isinstance(c, Shaft) and c.material is not None:
            out.setdefault(c.material.name, c.material)
    return out


def parameters(d: Drivetrain) -> list[Parameter]:
    """Every parameter of a drivetrain, components first (chain order), then materials."""
    out = []
    for c in d.components:
        fields = FIELDS[c.type]
        if isinstance(c, Shaft) and c.sections is not None:
            fields = fields + ("scale",)
        if isinstance(c, Shaft) and (c.inertia == 0 or c.reduce is not None):
            # modal damping needs the shaft's own modes (an inertia); a flexible body has its own
            fields = tuple(f for f in fields if f != "damping_ratio")
        if isinstance(c, Gear) and c.rigid_mesh:
            fields = tuple(f for f in fields if not f.startswith("mesh_"))
        out += [Parameter(f"{c.name}.{f}", c.name, f, "component", UNITS[f]) for f in fields]
    for m in _materials(d):
        out += [Parameter(f"{m}.{f}", m, f, "material", UNITS[f]) for f in MATERIAL_FIELDS]
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
    comp = d.component(p.owner)
    if p.field == "scale":
        return _scale_of(comp)
    return float(getattr(comp, p.field))


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
    for name, value in values.items():
        p = find_parameter(d, name)
        value = check_real(value, p.name, p.unit)
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
            comps[i] = dataclasses.replace(c, **{p.field: value})
        except ModelError as err:
            if err.field is None or "." not in str(err.field):
                err.field = p.name
            raise
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
        ∂ξ/∂p (first-order ξ), per parameter unit; None where not all modes are available.
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


def _matrices(d: Drivetrain, inertia_model):
    m = assemble(d, inertia_model, reduce=False)
    C = m.C if m.C is not None else sp.csr_matrix(m.K.shape)
    return m, m.K, m.M, C


@follows_policy
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
        Modes to report (default: every elastic mode computed).
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
    if result is not None and not result.model.bodies:
        # the modes were solved on this very (unreduced) assembly: its matrices, not a second one
        model0 = result.model
        C0 = model0.C if model0.C is not None else sp.csr_matrix(model0.K.shape)
        K0, M0 = model0.K, model0.M
    else:
        model0, K0, M0, C0 = _matrices(drivetrain, inertia_model)
    if result is None:
        result = modal_analysis(
            model0, model0.n_dof if model0.n_dof <= MAX_DAMPING_DOFS else None, damped=False
        )
    elastic = np.flatnonzero(~result.rigid)
    sel = elastic if modes is None else np.asarray(modes, dtype=int)
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
