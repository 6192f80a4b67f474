"""One part of a drivetrain as a Craig–Bampton flexible body, ready to export.

The part is meshed as the drivetrain meshes it (its DOFs and inertia model), its named stations
kept as interface nodes; the body is checked against its part model (:func:`flexshaft.reduction.cb_check`).
Writing it is :func:`flexshaft.exports.bodies.write_flexible_body`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ModelError
from ..parts.model import PartModel
from ..reduction import cb_check, craig_bampton
from ..system.threads import follows_policy
from .components import Drivetrain, Shaft
from .shaftparts import shaft_part_model, solid_line, solid_part

__all__ = ["PartReduction", "reduce_part", "DEFAULT_DAMPING_RATIO"]

#: The damping ratio of a part's elastic modes when neither the call nor the model file gives one
#: (the test bench's measured system damping).
DEFAULT_DAMPING_RATIO = 0.0053


@dataclass(frozen=True)
class PartReduction:
    """A reduced part.

    Attributes
    ----------
    component : Shaft
        The part, as the model file gives it.
    part_model : PartModel
        Its finite-element model (K, M; x in m).
    body : CraigBamptonBody
        The flexible body.
    check : CBCheck
        Rigid-body mass and static-condensation errors of the body against the part model (relative).
    dofs : str
        ``"torsion"`` or ``"full"``: the drivetrain's DOFs per node.
    """

    component: Shaft
    part_model: PartModel
    body: object
    check: object
    dofs: str

    @property
    def fixed_modes(self) -> int:
        """How many fixed-interface modes the body keeps (its other coordinates: residual vectors)."""
        return self.body.n_modes - self.body.n_residual

    def to_dict(self, path=None) -> dict:
        """The ``flexshaft reduce --json`` document; ``written`` is ``path`` (None: not written)."""
        body, pm, comp, n_fixed = self.body, self.part_model, self.component, self.fixed_modes
        return {
            "units": {"x": "m", "frequency": "Hz", "damping_ratio": "fraction"},
            "part": comp.name,
            "dofs": self.dofs,
            "part_dofs": pm.n_dofs if getattr(body, "solid", None) is None else 3 * body.solid.mesh.n_nodes,
            "fe": comp.fe,
            "boundary_dofs": body.n_boundary,
            # A shaft given by numbers has no length: its interface positions are not metres.
            "boundary_x": (body.boundary_x - pm.x[0]).tolist() if comp.sections is not None else None,
            "modes": n_fixed,
            "residual_vectors": body.n_residual,
            "fixed_interface_hz": body.fixed_interface_hz[:n_fixed].tolist(),
            "free_hz": body.free_hz.tolist(),
            "damping_ratios": body.damping_ratios.tolist(),
            "check": {
                "rigid_mass_error": self.check.rigid_mass_error,
                "static_error": self.check.static_error,
            },
            "written": None if path is None else str(path),
        }

    def table(self, path=None) -> str:
        """The ``flexshaft reduce`` table; ``path``: where the body was written (None: not written)."""
        comp, pm, body, check = self.component, self.part_model, self.body, self.check
        n_fixed = self.fixed_modes
        solid = getattr(body, "solid", None)
        size = (
            f"a solid of {3 * solid.mesh.n_nodes} DOFs ({solid.interface})"
            if solid is not None
            else f"{pm.n_dofs} DOFs"
        )
        lines = [
            f"{comp.name}: {size} ({self.dofs}) -> {body.n_boundary} boundary DOFs at x = "
            + ", ".join(f"{x:.4g}" for x in body.boundary_x)
            + f" m + {n_fixed} fixed-interface modes + {body.n_residual} residual vectors",
            "fixed-interface modes, Hz: "
            + (" ".join(f"{f:.2f}" for f in body.fixed_interface_hz[:n_fixed]) or "none (no interior nodes)"),
            "free-free modes of the reduced part, Hz: " + " ".join(f"{f:.2f}" for f in body.free_hz),
            "damping ratio per free-free mode, %: "
            + " ".join(f"{100 * z:.3f}" for z in body.damping_ratios[body.free_hz > 0]),
            f"check: rigid-body mass {check.rigid_mass_error:.1e}, interface stiffness vs static "
            f"condensation {check.static_error:.1e} (relative)",
        ]
        if path is not None:
            lines.append(f"written: {path}")
        return "\n".join(lines)


@follows_policy
def reduce_part(
    drivetrain: Drivetrain,
    part: str,
    *,
    modes: int | None = None,
    cutoff_hz: float | None = None,
    damping_ratio: float | None = None,
    residual: bool = True,
) -> PartReduction:
    """Reduce one part of a drivetrain to a Craig–Bampton flexible body.

    Parameters
    ----------
    drivetrain : Drivetrain
        The model holding the part.
    part : str
        The part's name: a cad part, or a shaft given by segments or by numbers.
    modes : int, optional
        Fixed-interface modes to keep.
    cutoff_hz : float, optional
        Keep every fixed-interface mode below this frequency, Hz. Without ``modes`` and
        ``cutoff_hz`` the part's ``reduce = {...}`` in the model file says.
    damping_ratio : float, optional
        Ratio (fraction) on every elastic mode; default the part's ``reduce`` damping, else its
        ``damping_ratio``, else :data:`DEFAULT_DAMPING_RATIO`.
    residual : bool
        Residual vectors after the modes (False: textbook Craig–Bampton).

    Returns
    -------
    PartReduction

    Raises
    ------
    ModelError
        ``field="part"`` for a part that has no elements, ``field="modes"`` where nothing says how
        many modes to keep; the reduction's own errors as it raises them.
    """
    comp = drivetrain.component(part)
    if not isinstance(comp, Shaft):
        raise ModelError(
            "has no elements to reduce",
            field="part",
            value=part,
            valid="a shaft: a cad part, or a shaft given by segments or by numbers",
        )
    pm = shaft_part_model(comp, drivetrain.dofs, drivetrain.inertia_model)
    extra = comp.named_mesh_nodes(pm.x - pm.x[0])
    spec = comp.reduce if comp.fe != "solid" else comp.solid_reduce
    if modes is None and cutoff_hz is None:
        if spec is None:
            raise ModelError(
                "how many modes?",
                field="modes",
                valid="modes or cutoff_hz, or reduce = {modes = n} on the part in the model file",
            )
        modes, cutoff_hz = spec.modes, spec.cutoff_hz
    if damping_ratio is not None:
        ratio = damping_ratio
    elif spec is not None:
        ratio = spec.damping
    else:
        ratio = comp.damping_ratio or DEFAULT_DAMPING_RATIO
    if comp.fe == "solid":
        # the solid's own reduction, on the 1D mesh's line (its stations and plots read it)
        part = solid_part(comp, drivetrain.dofs)
        body = craig_bampton(
            part,
            modes=modes,
            cutoff_hz=cutoff_hz,
            residual=residual,
            damping_ratio=ratio,
            line_x=solid_line(comp, pm.x - pm.x[0]),
            cache=comp.solid_cache,
        )
        return PartReduction(comp, pm, body, cb_check(body, part), drivetrain.dofs)
    body = craig_bampton(
        pm, modes=modes, cutoff_hz=cutoff_hz, nodes=extra, damping_ratio=ratio, residual=residual
    )
    return PartReduction(comp, pm, body, cb_check(body, pm), drivetrain.dofs)
