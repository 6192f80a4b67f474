"""A drivetrain model described in plain numbers: each component's summary, the speed frames past
its gear stages, and the section tables of the shafts made from geometry - the parts of every
result document (``flexshaft modes --json``, ``sections --json``, the study's set-ups) that speak
of the model rather than of an analysis."""

from __future__ import annotations

from .components import Coupling, Gear, Shaft

__all__ = [
    "component_summary",
    "frames_document",
    "frames_line",
    "sections_document",
    "sections_table",
    "linearised_document",
    "linearised_line",
    "damping_line",
]

#: How a linear analysis takes each nonlinear law (time runs use the law itself).
LINEARISED = {
    "slip": "stuck (it never slips)",
    "backlash": "in contact (no free play)",
    "curve": "at its tangent stiffness at zero torque",
}


def component_summary(comp) -> dict:
    """A component's type, end-to-end stiffness (N·m/rad) and inertia (kg·m²).

    A gear stage: its ratio (driving / driven speed), each wheel's inertia about its own shaft
    and, for an elastic mesh, the mesh stiffness and damper referred to the driving side.
    """
    out: dict = {"name": comp.name, "type": "cad" if getattr(comp, "geometry", None) else comp.type}
    if isinstance(comp, Gear):
        out |= {"ratio": comp.ratio, "inertia_in": comp.inertia_in, "inertia_out": comp.inertia_out}
        if not comp.rigid_mesh:
            out["mesh_stiffness"] = comp.mesh_stiffness
            if comp.mesh_damping:
                out["mesh_damping"] = comp.mesh_damping
        if comp.law is not None:
            out["law"] = comp.law.kind
        return out
    if isinstance(comp, (Shaft, Coupling)):
        out["stiffness"] = comp.stiffness
    out["inertia"] = comp.inertia
    if isinstance(comp, Shaft):
        out["elements"] = comp.elements
        if comp.damping_ratio:
            out["damping_ratio"] = comp.damping_ratio
        if comp.sections is not None:
            out["length"] = comp.sections.length
            out["material"] = comp.material.name
        if comp.geometry is not None:
            out["geometry"] = comp.geometry
        if comp.reduce is not None:
            out["reduce"] = comp.reduce.label
    if isinstance(comp, (Shaft, Coupling)) and comp.damping:
        out["damping"] = comp.damping
    if isinstance(comp, Coupling) and comp.law is not None:
        out["law"] = comp.law.kind
    return out


def linearised_document(drivetrain) -> list[dict]:
    """Each nonlinear coupling or mesh, its law and how the linear analyses take it."""
    return [
        {"name": c.name, "law": c.law.kind, "linear_analyses": LINEARISED[c.law.kind]}
        for c in drivetrain.components
        if getattr(c, "law", None) is not None
    ]


def damping_line(drivetrain) -> str:
    """The damping a drivetrain's results carry, in one line (what an export states beside its units):
    per-part (each part's own, as the multibody model takes it) or the model's Rayleigh damping (the
    system damping variant's form)."""
    ray = drivetrain.rayleigh
    if ray is None or not (ray.alpha or ray.beta):
        return "damping: per part (each part's own damping and dampers)"
    return f"damping: Rayleigh alpha {ray.alpha:.6g} 1/s, beta {ray.beta:.6g} s, and each part's own"


def linearised_line(drivetrain) -> str | None:
    """One line saying which elements a linear analysis takes linearised, or None if none are."""
    items = linearised_document(drivetrain)
    if not items:
        return None
    parts = [f"{i['name']!r} ({i['law']}) {i['linear_analyses']}" for i in items]
    return "linear model: " + "; ".join(parts) + " - time runs (simulate) use the nonlinear laws"


def frames_document(mdl) -> dict:
    """Which speed frame each component and station is read in (its speed / the driving end's)."""
    speed = mdl.speed_ratio
    return {
        "meaning": "angles, speeds and torques of each shaft are in its own speed frame; speed_ratio is "
        "its speed over the driving end's (1 without gear stages; a gear is listed by its driving side)",
        "components": {c.name: float(speed[s]) for c, s in zip(mdl.drivetrain.components, mdl.start_node)},
        "stations": {st.name: float(speed[st.node]) for st in mdl.stations},
    }


def frames_line(mdl) -> str | None:
    """One line naming the frames past each gear stage, or None without gear stages."""
    gears = [(c, int(e)) for c, e in zip(mdl.drivetrain.components, mdl.end_node) if isinstance(c, Gear)]
    if not gears:
        return None
    parts = [f"past {c.name!r} speed × {mdl.speed_ratio[e]:.6g}" for c, e in gears]
    return "frames: each shaft's angles and torques in its own speed frame (" + "; ".join(parts) + ")"


def _part_summary(shaft) -> dict:
    t = shaft.sections
    check = t.meta.get("mass_check")
    out = {
        "name": shaft.name,
        "source": shaft.source,
        "geometry": shaft.geometry,
        "material": {
            "name": shaft.material.name,
            "E": shaft.material.E,
            "nu": shaft.material.nu,
            "rho": shaft.material.rho,
        },
        "length": t.length,
        "stiffness": shaft.stiffness,
        "inertia": shaft.inertia,
        "mass": t.mass(shaft.material.rho),
        "volume": t.volume,
        "intervals": t.n_intervals,
    }
    if check is not None:
        out["mass_check"] = {
            "volume_solid": check.volume_solid,
            "volume_error": check.volume_error,
            "axial_moment_solid": check.axial_moment_solid,
            "axial_inertia_error": check.axial_moment_error,
        }
    out["table"] = t.as_dict()
    return out


def sections_document(shafts) -> dict:
    """The ``flexshaft sections --json`` document for shafts that carry a section table.

    Units: lengths m, areas m², second moments m⁴, stiffness N·m/rad,
    inertia kg·m², mass kg, volume m³, E Pa, rho kg/m³; errors are relative.
    """
    return {
        "units": {
            "length": "m",
            "stiffness": "N·m/rad",
            "inertia": "kg·m²",
            "mass": "kg",
            "volume": "m³",
            "E": "Pa",
            "rho": "kg/m³",
            "axial_moment_solid": "m⁵",
        },
        "parts": [_part_summary(s) for s in shafts],
    }


def sections_table(shafts) -> str:
    """Readable section tables with each part's stiffness, inertia and mass check."""
    lines = []
    for s in shafts:
        t = s.sections
        check = t.meta.get("mass_check")
        src = f"{s.source} {s.geometry}" if s.geometry else s.source
        lines.append(
            f"{s.name}: {src}, {s.material.name}; length {t.length:.6g} m, "
            f"stiffness {s.stiffness:.6g} N·m/rad, inertia {s.inertia:.6g} kg·m², "
            f"mass {t.mass(s.material.rho):.6g} kg"
        )
        if check is not None:
            lines.append(
                f"  table vs solid: volume {check.volume_error:+.2e}, "
                f"axial inertia {check.axial_moment_error:+.2e} (relative)"
            )
        lines.append(
            f"  {'x start':>9} {'x end':>9} {'area':>11} {'Ip':>11} {'J':>11} {'As_y':>11} "
            f"{'As_z':>11} {'yc':>10} {'zc':>10}  method"
        )
        lines.append(
            f"  {'m':>9} {'m':>9} {'m²':>11} {'m⁴':>11} {'m⁴':>11} {'m²':>11} {'m²':>11} {'m':>10} {'m':>10}"
        )
        for i in range(t.n_intervals):
            lines.append(
                f"  {t.x[i]:9.5f} {t.x[i + 1]:9.5f} {t.area[i]:11.5e} {t.ip[i]:11.5e} {t.j[i]:11.5e} "
                f"{t.shear_area_y[i]:11.5e} {t.shear_area_z[i]:11.5e} {t.yc[i]:10.3e} {t.zc[i]:10.3e}"
                f"  {t.method[i]}"
            )
        lines.append("")
    return "\n".join(lines).rstrip("\n")
