"""A part's 1D model against its solid: stiffness, free-free modes and the step corrections the solid implies.

The 1D model (:func:`~flexshaft.parts.model.part_model`, 6-DOF Timoshenko beams on the section table) is
exact for a prismatic shaft but too stiff at a diameter step: it lets every section of the larger shaft
carry its full share up to the step's plane, where the solid's stress spreads from the smaller shaft into
the larger one over a length of the order of the smaller diameter, and that corner region twists more
than its 1D intervals. :func:`compare_solid` measures the difference.

Stiffness, both models loaded the same way (:func:`~flexshaft.analysis.twist.part_stiffness`):
the part's start clamped, a unit force or moment at its end alone, the others free; torsion T/θx, axial
F/ux, bending a tip force over its deflection along y and z. The 1D numbers come from the Timoshenko
part model on the table's own intervals (a Timoshenko element is exact in statics at any length), the
end's 6 x 6 compliance by one sparse factorisation.

Modes, free-free: the solid's lowest ``modes`` elastic modes
(:func:`~flexshaft.analysis.modal.part_modes`) and the 1D part's on a fine mesh (a hundred
elements along the part), each mode classed by what its sections do - the kind whose rigid section
motion holds most of the shape (:func:`section_shares`: axial translation; lateral translation and
bending rotation; twist) - and paired by kind in ascending order: the solid's k-th torsion mode with the
1D's k-th torsion mode, and so on.

The step correction. The solid's torsional compliance less the 1D series compliance,
ΔC = 1/k_solid − 1/k_1D (rad/(N·m)), is what the steps add (for a circular shaft the rigid end faces add
nothing: Saint-Venant's solution turns its end sections rigidly). It is shared among the table's steps
(stations where the torsion constant changes) in proportion to each step's estimate by the 45-degree
rule - the stress taken to spread from the smaller section into the larger one along a 45° cone, whose
compliance less that of the larger section's 1D interval over the cone's length is the step's own
(:func:`cone_compliance`): zero where nothing steps, growing with the step. Each share ΔC_i is then an
extra length of the smaller section at that step, ΔL_i = ΔC_i·G·J_small - the classical form of the
correction (BICERA's handbook, Nestorides 1958, charts ΔL/d against D/d; the tests compare the solid's
with it). A part without a step gets no step: its whole difference (the solid mesh's own error, a few
1e-4 for a converged tube) is spread uniformly.

Writing it back (:meth:`SolidComparison.corrected_table`): the geometry stays, so the inertia does; the
torsion constant J of the smaller interval beside each step is lowered until that interval's compliance
L/(G·J') carries the step's share, L/(G·J') = L/(G·J) + ΔC_i (an interval between two steps carries
both). The corrected table's torsional stiffness is the solid's, its mass, ρ·Ip and bending as before.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..elements.materials import Material
from ..elements.tetmesh import TetMesh
from ..errors import ModelError
from ..parts.model import part_model
from ..parts.solidpart import solid_part_model
from ..sections.table import SectionTable
from ..system.threads import follows_policy
from ..validation import check_int
from .modal import part_modes
from .twist import END_DOFS, PartStiffness, part_stiffness

__all__ = [
    "APPORTION_RULE",
    "KINDS",
    "ModePair",
    "SolidComparison",
    "StepCorrection",
    "StiffnessPair",
    "compare_solid",
    "cone_compliance",
    "section_shares",
]

#: The mode kinds, as the 1D modal result names them (:attr:`~flexshaft.analysis.modal.ModalResult.kinds`).
KINDS = ("axial", "lateral", "torsion")
#: How the torsional compliance excess is shared among several steps.
APPORTION_RULE = (
    "in proportion to each step's 45-degree-rule compliance (the stress spreading into the larger "
    "section along a 45° cone); uniformly over the whole part where it has no step"
)
#: Elements of the 1D model whose modes are compared: its axial and torsion bars are linear, their
#: frequencies high by ~(k·h)²/24 - 4e-5 for a first mode, 4e-3 for a tenth with a hundred elements
#: (bending, cubic, far less) - below the solid meshes' own error.
ONE_D_ELEMENTS = 100
#: Relative change of the torsion constant between neighbouring intervals that counts as a step; below,
#: round-off of a sliced section (its properties to ~1e-12).
STEP_RTOL = 1e-9
# Gauss-Legendre points for a cone's compliance: its integrand 1/J(x) is smooth (a rational function of
# x without poles), so 16 points leave ~1e-15 relative for any step ratio a shaft has.
_GAUSS = np.polynomial.legendre.leggauss(16)


@dataclass(frozen=True)
class StiffnessPair:
    """One end stiffness of the 1D model and of the solid (:func:`compare_solid`).

    Attributes
    ----------
    kind : str
        ``"torsion"``, ``"axial"``, ``"bending_y"`` or ``"bending_z"``.
    unit : str
        N·m/rad or N/m.
    one_d, solid : float
        The 1D (Timoshenko) model's and the solid's, in ``unit``.
    """

    kind: str
    unit: str
    one_d: float
    solid: float

    @property
    def ratio(self) -> float:
        """solid / 1D: below 1 where the solid is the softer."""
        return self.solid / self.one_d


@dataclass(frozen=True)
class ModePair:
    """A free-free mode of the solid and its 1D partner of the same kind.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    solid_hz, one_d_hz : float
        Frequencies, Hz; ``one_d_hz`` is NaN where the 1D model's modes computed have no further mode of
        this kind.
    solid_index, one_d_index : int
        Positions among each model's modes, rigid ones included (-1: none).
    share : float
        The solid mode's share of its kind (:func:`section_shares`), 0 to 1.
    """

    kind: str
    solid_hz: float
    one_d_hz: float
    solid_index: int
    one_d_index: int
    share: float

    @property
    def ratio(self) -> float:
        """solid / 1D frequency."""
        return self.solid_hz / self.one_d_hz


@dataclass(frozen=True)
class StepCorrection:
    """The extra length of the smaller section that one step's share of the solid's compliance means.

    Attributes
    ----------
    x : float
        The step's station, m (table coordinates).
    small, large : int
        The table intervals (after merging equal neighbours) on the step's smaller and larger side.
    d_small, d_large : float
        Their outer diameters, m (of the annulus with the interval's area and polar moment).
    j_small : float
        The smaller interval's torsion constant, m⁴.
    weight : float
        The step's share of the excess (:data:`APPORTION_RULE`), 0 to 1.
    compliance : float
        Its share ΔC_i of the excess compliance, rad/(N·m).
    extra_length : float
        ΔL_i = ΔC_i·G·J_small, m: the length of the smaller section that twists as much.
    """

    x: float
    small: int
    large: int
    d_small: float
    d_large: float
    j_small: float
    weight: float
    compliance: float
    extra_length: float

    @property
    def extra_length_per_diameter(self) -> float:
        """ΔL_i / d_small, the form a handbook charts against d_large / d_small."""
        return self.extra_length / self.d_small


@dataclass(frozen=True)
class SolidComparison:
    """A part's 1D model against its solid mesh (:func:`compare_solid`), SI.

    Attributes
    ----------
    part : str
    material : Material
    table : SectionTable
        The 1D model's sections, as given.
    torsion, axial : StiffnessPair
    bending : (StiffnessPair, StiffnessPair)
        Tip force along y and along z.
    modes : tuple of ModePair
        The solid's elastic modes in ascending order, each with its 1D partner.
    compliance_excess : float
        ΔC = 1/k_solid − 1/k_1D in torsion, rad/(N·m): positive where the solid is the softer.
    steps : tuple of StepCorrection
        The table's steps, each with its share of ΔC (:data:`APPORTION_RULE`); empty for a uniform part.
    solid : PartStiffness
        The twist test of the solid part behind the numbers (its 6 x 6 end stiffness, interface, solver).
    one_d_compliance : ndarray (6, 6)
        The 1D model's end compliance, clamped at its start, in :data:`~.twist.END_DOFS` order.
    one_d_elements : int
        Elements of the 1D model whose modes were compared.
    """

    part: str
    material: Material
    table: SectionTable
    torsion: StiffnessPair
    axial: StiffnessPair
    bending: tuple
    modes: tuple
    compliance_excess: float
    steps: tuple
    solid: PartStiffness
    one_d_compliance: np.ndarray = field(repr=False)
    one_d_elements: int = ONE_D_ELEMENTS

    @property
    def stiffness(self) -> tuple[StiffnessPair, ...]:
        """Torsion, axial and the two bending stiffnesses, in that order."""
        return (self.torsion, self.axial, *self.bending)

    def corrected_table(self) -> SectionTable:
        """The section table with the solid's torsional stiffness and its own inertia (module docstring).

        The torsion constant j of the smaller interval beside each step is lowered so that its
        compliance carries the step's share of ΔC; area, polar moment (the inertia), bending and shear
        properties are unchanged. Without steps every interval's j is scaled by k_solid / k_1D.

        Returns
        -------
        SectionTable
            Its torsional stiffness G / Σ L/j equals the solid's; ``meta["torsion_corrected"]`` records
            how.

        Raises
        ------
        ModelError
            Where the solid is stiffer than the 1D model by more than an interval's own compliance (a
            mesh far too coarse, or a table that is not this part's): no positive j carries it.
        """
        merged = self.table.merged()
        G = self.material.G
        compliance = merged.lengths / (G * merged.j)
        if self.steps:
            for step in self.steps:
                compliance[step.small] += step.compliance
        else:
            compliance *= self.torsion.one_d / self.torsion.solid
        if np.any(compliance <= 0.0):
            k = int(np.argmin(compliance))
            raise ModelError(
                "the solid is stiffer in torsion than the 1D model by more than an interval can give",
                component=self.part,
                field="compliance_excess",
                value=self.compliance_excess,
                unit="rad/(N·m)",
                valid=f"a solid at most as stiff as its table allows (interval {k} would need J <= 0): "
                "a finer mesh, or the table of this part",
            )
        # Back onto the given intervals: each of a merged interval's own intervals scaled alike.
        table = self.table
        factor = compliance / (merged.lengths / (G * merged.j))
        owner = np.searchsorted(merged.x, 0.5 * (table.x[:-1] + table.x[1:])) - 1
        meta = dict(table.meta) | {
            "torsion_corrected": {
                "by": "solid comparison",
                "solid_torsion_N_m_per_rad": self.torsion.solid,
                "one_d_torsion_N_m_per_rad": self.torsion.one_d,
                "rule": "j of the smaller interval at each step lowered by the step's share; "
                + APPORTION_RULE,
            }
        }
        return replace(table, j=table.j / factor[owner], meta=meta)

    def to_dict(self) -> dict:
        """A JSON-ready document (units stated)."""

        def num(x) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            "part": self.part,
            "material": self.material.name,
            "units": {
                "torsion": "N·m/rad",
                "axial": "N/m",
                "bending_y": "N/m",
                "bending_z": "N/m",
                "frequency": "Hz",
                "compliance_excess": "rad/(N·m)",
                "x": "m",
                "diameter": "m",
                "extra_length": "m",
                "one_d_compliance": "SI by DOF (m, rad per N, N·m)",
            },
            "stiffness": {
                p.kind: {"one_d": p.one_d, "solid": p.solid, "ratio": p.ratio} for p in self.stiffness
            },
            "modes": [
                {
                    "kind": m.kind,
                    "solid_hz": m.solid_hz,
                    "one_d_hz": num(m.one_d_hz),
                    "ratio": num(m.ratio),
                    "solid_index": m.solid_index,
                    "one_d_index": m.one_d_index,
                    "share": m.share,
                }
                for m in self.modes
            ],
            "compliance_excess": self.compliance_excess,
            "apportion_rule": APPORTION_RULE,
            "steps": [
                {
                    "x": s.x,
                    "small_interval": s.small,
                    "large_interval": s.large,
                    "d_small": s.d_small,
                    "d_large": s.d_large,
                    "weight": s.weight,
                    "compliance": s.compliance,
                    "extra_length": s.extra_length,
                    "extra_length_per_diameter": s.extra_length_per_diameter,
                }
                for s in self.steps
            ],
            "end_dofs": list(END_DOFS),
            "one_d_compliance": self.one_d_compliance.tolist(),
            "interface": self.solid.interface,
            "mesh_size_m": self.solid.mesh_size,
            "dofs": self.solid.dofs,
            "one_d_elements": self.one_d_elements,
        }

    def text(self) -> str:
        """The comparison as a readable table."""
        lines = [
            f"solid vs 1D: {self.part!r} ({self.material.name}), clamped at its start, loaded at its end",
            f"solid: mesh size {self.solid.mesh_size:g} m, {self.solid.dofs} unknowns, "
            f"{self.solid.interface}",
            "",
            f"{'stiffness':<12} {'unit':<8} {'1D':>13} {'solid':>13} {'solid/1D':>9}",
        ]
        for p in self.stiffness:
            lines.append(f"{p.kind:<12} {p.unit:<8} {p.one_d:13.6e} {p.solid:13.6e} {p.ratio:9.5f}")
        if self.modes:
            lines += [
                "",
                f"{'free-free mode':<14} {'1D Hz':>11} {'solid Hz':>11} {'solid/1D':>9} {'share':>6}",
            ]
            for m in self.modes:
                f1 = f"{m.one_d_hz:11.2f}" if np.isfinite(m.one_d_hz) else f"{'-':>11}"
                r = f"{m.ratio:9.5f}" if np.isfinite(m.one_d_hz) else f"{'-':>9}"
                lines.append(f"{m.kind:<14} {f1} {m.solid_hz:11.2f} {r} {m.share:6.3f}")
        lines += [
            "",
            f"torsional compliance of the solid less the 1D series: {self.compliance_excess:.4e} rad/(N·m)",
        ]
        if self.steps:
            lines.append(f"shared among the steps {APPORTION_RULE}:")
            for s in self.steps:
                lines.append(
                    f"  step at x = {s.x:.4f} m, d {s.d_small:.4g} -> {s.d_large:.4g} m: "
                    f"{1000 * s.extra_length:.3f} mm more of the {s.d_small:.4g} m section "
                    f"(ΔL/d = {s.extra_length_per_diameter:.4f}, share {s.weight:.3f})"
                )
        else:
            lines.append("no step in the table: the difference is the mesh's (or the table's) own")
        return "\n".join(lines)


def section_shares(nodes: np.ndarray, shapes: np.ndarray, width: float) -> dict[str, np.ndarray]:
    """Each shape's share of Σ|u|² in its sections' rigid motions, by kind (:data:`KINDS`).

    The nodes are cut into slabs ``width`` thick along x; in each, the least-squares rigid motions of
    the slab about the x axis: the mean axial translation (axial); the mean translations along y and z
    and the turns about y and z, θy = Σ z·u_x / Σ z², θz = −Σ y·u_x / Σ y² (lateral: a bending section
    translates and turns); the turn about x, θ = Σ r·t / Σ r² of the tangential motions t (torsion, as
    :func:`flexshaft.reduction.ritz.twist_share`). A share is the motion's Σ|u|² over the shape's: near
    1 for a pure kind, less its sections' own deformation (warping, Poisson).

    Parameters
    ----------
    nodes : ndarray (n, 3)
        m, the axis along x through y = z = 0.
    shapes : ndarray (3n, m)
        Node-major u_x, u_y, u_z.
    width : float
        Slab thickness, m.

    Returns
    -------
    dict of str to ndarray (m,)
    """
    u = shapes.reshape(nodes.shape[0], 3, -1)
    x, y, z = nodes[:, 0], nodes[:, 1], nodes[:, 2]
    slab = np.floor((x - x.min()) / width).astype(np.int64)
    size = int(slab.max()) + 1

    def sums(w):  # per slab and shape: Σ w (n,) or (n, m)
        if w.ndim == 1:
            return np.bincount(slab, weights=w, minlength=size)
        return np.stack([np.bincount(slab, weights=w[:, k], minlength=size) for k in range(w.shape[1])], 1)

    def fitted(num, den):  # Σ over slabs of (Σ w·u)² / Σ w²: the least-squares motion's Σ|u|²
        ok = den > 0
        return np.sum(num[ok] ** 2 / den[ok, None], axis=0)

    count = sums(np.ones_like(x))
    axial = fitted(sums(u[:, 0]), count)
    lateral = (
        fitted(sums(u[:, 1]), count)
        + fitted(sums(u[:, 2]), count)
        + fitted(sums(z[:, None] * u[:, 0]), sums(z * z))
        + fitted(sums(y[:, None] * u[:, 0]), sums(y * y))
    )
    torsion = fitted(sums(-z[:, None] * u[:, 1] + y[:, None] * u[:, 2]), sums(y * y + z * z))
    total = np.maximum(np.sum(u * u, axis=(0, 1)), np.finfo(float).tiny)
    return {"axial": axial / total, "lateral": lateral / total, "torsion": torsion / total}


def _annulus_radii(table: SectionTable, i: int) -> tuple[float, float]:
    """Outer and inner radius (m) of the annulus with interval ``i``'s area and polar moment."""
    a, ip = float(table.area[i]), float(table.ip[i])
    mean_sq, diff_sq = ip / a, a / (2.0 * np.pi)  # (ro² + ri²)/2 and (ro² − ri²)/2
    return float(np.sqrt(mean_sq + diff_sq)), float(np.sqrt(max(mean_sq - diff_sq, 0.0)))


def cone_compliance(small: tuple[float, float], large: tuple[float, float], G: float) -> float:
    """The 45-degree rule's estimate of a step's extra torsional compliance, rad/(N·m).

    The stress is taken to spread from the smaller annulus into the larger one along 45° cones: over the
    length ``ℓ = max(|Δr_outer|, |Δr_inner|)`` the radii pass linearly from the smaller section's to the
    larger's, and that cone's compliance ∫ dx / (G·J(x)) less the larger section's ℓ / (G·J_large) is
    the step's. For a solid shaft of radii a < b it is (1/G)·(2/π)·[(a⁻³ − b⁻³)/3 − (b − a)/b⁴].

    Parameters
    ----------
    small, large : (float, float)
        (outer, inner) radius of the smaller and of the larger section, m.
    G : float
        Shear modulus, Pa.
    """
    (ro_s, ri_s), (ro_l, ri_l) = small, large
    length = max(abs(ro_l - ro_s), abs(ri_l - ri_s))
    if length == 0.0:
        return 0.0
    t, w = _GAUSS
    s = 0.5 * (t + 1.0)
    ro, ri = ro_s + s * (ro_l - ro_s), ri_s + s * (ri_l - ri_s)
    cone = 0.5 * length * float(np.sum(w / (0.5 * np.pi * (ro**4 - ri**4))))
    return (cone - length / (0.5 * np.pi * (ro_l**4 - ri_l**4))) / G


def _steps(table: SectionTable, excess: float, G: float) -> tuple[StepCorrection, ...]:
    """The merged table's steps, each with its share of the torsional ``excess`` (:data:`APPORTION_RULE`)."""
    found = []
    for i in range(table.n_intervals - 1):
        j0, j1 = float(table.j[i]), float(table.j[i + 1])
        if abs(j1 - j0) <= STEP_RTOL * max(j0, j1):
            continue
        small, large = (i, i + 1) if j0 < j1 else (i + 1, i)
        r_small, r_large = _annulus_radii(table, small), _annulus_radii(table, large)
        found.append((i, small, large, r_small, r_large, abs(cone_compliance(r_small, r_large, G))))
    if not found:
        return ()
    weights = np.array([f[-1] for f in found])
    weights = weights / weights.sum() if weights.sum() > 0 else np.full(len(found), 1.0 / len(found))
    out = []
    for (i, small, large, r_small, r_large, _), w in zip(found, weights, strict=True):
        dc = float(w) * excess
        j_small = float(table.j[small])
        out.append(
            StepCorrection(
                x=float(table.x[i + 1]),
                small=small,
                large=large,
                d_small=2.0 * r_small[0],
                d_large=2.0 * r_large[0],
                j_small=j_small,
                weight=float(w),
                compliance=dc,
                extra_length=dc * G * j_small,
            )
        )
    return tuple(out)


def _pairs(mesh: TetMesh, table: SectionTable, material: Material, count: int, cache) -> tuple[ModePair, ...]:
    """The solid's ``count`` elastic free-free modes, each with the 1D model's next mode of its kind."""
    solid = part_modes(solid_part_model(mesh, material), count + 6, cache=cache)  # and its 6 rigid
    elastic = np.flatnonzero(~solid.rigid)
    width = mesh.size if np.isfinite(mesh.size) and mesh.size > 0 else mesh.length / 20.0
    shares = section_shares(mesh.nodes, solid.shapes[:, elastic], width)
    table_shares = np.vstack([shares[k] for k in KINDS])
    kinds = [KINDS[i] for i in np.argmax(table_shares, axis=0)]
    # Enough 1D modes for the solid's: each kind's first modes lie within the 1D model's lowest
    # 6 + 3·count (a lateral one is a pair), where 6 are rigid.
    fine = part_model(table, material, dofs="full", max_element_length=table.length / ONE_D_ELEMENTS)
    one_d = part_modes(fine, count=min(fine.n_dofs, 6 + 3 * count + 6))
    one_d_kinds = one_d.kinds
    queue = {k: [i for i in np.flatnonzero(~one_d.rigid) if one_d_kinds[i] == k] for k in KINDS}
    out = []
    for col, (index, kind) in enumerate(zip(elastic, kinds, strict=True)):
        partner = queue[kind].pop(0) if queue[kind] else -1
        out.append(
            ModePair(
                kind=kind,
                solid_hz=float(solid.frequencies_hz[index]),
                one_d_hz=float(one_d.frequencies_hz[partner]) if partner >= 0 else float("nan"),
                solid_index=int(index),
                one_d_index=int(partner),
                share=float(shares[kind][col]),
            )
        )
    return tuple(out)


@follows_policy
def compare_solid(
    table: SectionTable,
    mesh: TetMesh,
    material: Material,
    *,
    interface: str = "rigid",
    modes: int = 4,
    cache=None,
) -> SolidComparison:
    """A part's 1D model against its solid mesh (module docstring): stiffness, modes, step corrections.

    Parameters
    ----------
    table : SectionTable
        The part's sections (the 1D model), m.
    mesh : TetMesh
        The same part's solid mesh (:func:`geometry.meshing.mesh_solid`, x from 0 along the axis), with
        its ``"start"`` and ``"end"`` faces.
    material : Material
    interface : {"rigid", "average"}
        How the solid's end faces are tied (:data:`~flexshaft.parts.solidties.INTERFACES`).
    modes : int
        Elastic free-free modes of the solid to compare (0: none, the stiffness alone).
    cache : optional
        Where the solid's stiffness and modes are kept between runs
        (:class:`flexshaft.input.solidcache.SolidResults`); None: solved afresh.

    Returns
    -------
    SolidComparison

    Raises
    ------
    ModelError
        Not a table, mesh or material; the mesh is not as long as the table; an unknown interface.
    """
    if not isinstance(table, SectionTable):
        raise ModelError(
            "not a section table", field="table", value=type(table).__name__, valid="a SectionTable"
        )
    if not isinstance(mesh, TetMesh):
        raise ModelError("not a solid mesh", field="mesh", value=type(mesh).__name__, valid="a TetMesh")
    if not isinstance(material, Material):
        raise ModelError(
            "not a material", field="material", value=type(material).__name__, valid="a Material"
        )
    modes = check_int(modes, "modes", lo=0, hi=100)
    # the same part: its lengths agree to the mesher's tolerance (1e-7 of the extent)
    if abs(mesh.length - table.length) > 1e-6 * table.length:
        raise ModelError(
            "is not as long as the section table",
            component=table.name,
            field="mesh",
            value=mesh.length,
            unit="m",
            valid=f"the same part: {table.length:g} m long",
        )
    solid = part_stiffness(solid_part_model(mesh, material, interface=interface), cache=cache)
    C = part_stiffness(part_model(table, material, dofs="full")).compliance
    k1 = 1.0 / np.diag(C)  # ux, uy, uz, θx, θy, θz
    torsion = StiffnessPair("torsion", "N·m/rad", float(k1[3]), solid.torsion)
    axial = StiffnessPair("axial", "N/m", float(k1[0]), solid.axial)
    bending = (
        StiffnessPair("bending_y", "N/m", float(k1[1]), solid.bending[0]),
        StiffnessPair("bending_z", "N/m", float(k1[2]), solid.bending[1]),
    )
    excess = 1.0 / torsion.solid - 1.0 / torsion.one_d
    return SolidComparison(
        part=table.name,
        material=material,
        table=table,
        torsion=torsion,
        axial=axial,
        bending=bending,
        modes=_pairs(mesh, table, material, modes, cache) if modes else (),
        compliance_excess=float(excess),
        steps=_steps(table.merged(), float(excess), material.G),
        solid=solid,
        one_d_compliance=C,
    )
