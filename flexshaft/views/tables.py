"""Modal results as a JSON-ready document and as a readable table."""

from __future__ import annotations

import math

import numpy as np

from ..analysis.modal import DEFAULT_LISTED, ModalResult
from ..model.components import Coupling, Gear, Rigid, Shaft

__all__ = [
    "modes_document",
    "modes_table",
    "component_summary",
    "sections_document",
    "sections_table",
    "twist_document",
    "twist_table",
    "twist_targets_document",
    "twist_targets_text",
    "reduction_table",
    "frf_document",
    "frf_csv",
    "frf_table",
    "forced_table",
    "simulation_table",
    "campbell_table",
    "sensitivity_table",
    "sweep_document",
    "sweep_summary",
    "sweep_range_table",
    "calibration_table",
    "signal_table",
]


def _num(x) -> float | None:
    """A JSON-safe float (NaN -> null)."""
    x = float(x)
    return x if math.isfinite(x) else None


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
    return out


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


def _range_hz(result: ModalResult, max_hz: float | None) -> float | None:
    """The listing's range, Hz: ``max_hz`` as given, else the model's ``[model] max_hz`` (or None)."""
    return max_hz if max_hz is not None else getattr(result.model.drivetrain, "max_hz", None)


def _listed(result: ModalResult, max_hz: float | None, count: int | None = None) -> range | list[int]:
    """The modes to list: those up to ``max_hz`` (Hz; the model's when None), else the lowest
    ``count`` (the modes asked for), else the lowest :data:`DEFAULT_LISTED` - never all of a fine
    mesh's hundreds unasked."""
    max_hz = _range_hz(result, max_hz)
    n = result.count if count is None else min(int(count), result.count)
    if max_hz is not None:
        return [i for i in range(n) if result.frequencies_hz[i] <= max_hz]
    return range(n if count is not None else min(n, DEFAULT_LISTED))


def _listing(result: ModalResult, max_hz: float | None, count: int | None, listed) -> dict:
    """How the listed modes were chosen, for the JSON document and the table's line."""
    max_hz = _range_hz(result, max_hz)
    rule = "max_hz" if max_hz is not None else ("count" if count is not None else "lowest")
    return {
        "rule": rule,
        "max_hz": max_hz,
        "shown": len(listed),
        "computed": result.count,
        "model_modes": result.model.n_dof,
    }


def _listing_line(info: dict) -> str | None:
    """One plain line: how many modes are shown of how many computed, and how to see others."""
    shown, computed, total = info["shown"], info["computed"], info["model_modes"]
    if info["rule"] == "max_hz":
        return (
            f"modes up to {info['max_hz']:g} Hz: {shown} of the {computed} computed "
            "(--max-hz F or [model] max_hz sets the range)"
        )
    if info["rule"] == "lowest" and shown < total:
        return (
            f"modes: the lowest {shown} of the model's {total} ({computed} computed); no max_hz given - "
            "--max-hz F (or [model] max_hz) lists those up to F Hz, --count N the lowest N"
        )
    return None


def modes_document(
    result: ModalResult, *, max_hz: float | None = None, mesh=None, count: int | None = None
) -> dict:
    """The ``flexshaft modes --json`` document, for a torsion or a full (6-DOF) model.

    Units: frequencies Hz, damping ratios as fractions, stiffness N·m/rad,
    inertia kg·m², bearing stiffness N/m; ``shape`` is θx at the stations,
    scaled so the largest |value| of each mode is 1. ``strain_energy`` is
    each component's share of the mode's strain energy. ``kinetic_energy`` is
    each component's share of its kinetic energy in a torsion model and, in a
    full model, each DOF family's (axial, lateral, torsion) as before;
    ``kind`` names the family. ``max_hz`` (Hz; default the model's ``[model] max_hz``) lists
    only the modes up to that frequency; without it ``count`` modes (those asked for), else the
    lowest 20. ``listing`` says which and how many were computed.
    """
    mdl = result.model
    full = mdl.dofs == "full"
    names = mdl.component_names
    se = result.strain_energy_fractions()
    ke = result.kinetic_energy_fractions()
    shapes = result.station_shapes()
    dominant = result.dominant_components()
    torque = result.component_torques()
    comps = mdl.drivetrain.components
    dm = result.damped
    contrib = result.damping_contributions() if dm is not None else None
    if full:
        family = result.family_energy()
        kinds = result.kinds
        bearing = result.bearing_energy_fractions()
    modes = []
    listed = _listed(result, max_hz, count)
    for i in listed:
        mode = {
            "index": i,
            "frequency_hz": 0.0 if result.rigid[i] else _num(result.frequencies_hz[i]),
            "damping_ratio": 0.0 if dm is None else _num(dm.damping_ratios[i]),
            "rigid": bool(result.rigid[i]),
        }
        if dm is not None:
            mode["damped_frequency_hz"] = _num(dm.damped_frequencies_hz[i])
            mode["damped_natural_frequency_hz"] = _num(dm.natural_frequencies_hz[i])
            mode["decay_rate"] = _num(dm.decay_rates[i])  # 1/s: ξω, or a rigid-body root's rate
            mode["damping_contribution"] = {n: _num(v) for n, v in zip(names, contrib[i])}
        if full:
            mode["kind"] = kinds[i]
        mode["dominant_component"] = dominant[i]
        mode["strain_energy"] = {n: _num(v) for n, v in zip(names, se[i])}
        if full:
            mode["kinetic_energy"] = {f: _num(e[i]) for f, e in family.items()}
            mode["bearing_strain_energy"] = {st.name: _num(v) for (st, _), v in zip(mdl.bearings, bearing[i])}
        else:
            mode["kinetic_energy"] = {n: _num(v) for n, v in zip(names, ke[i])}
        mode["torque_per_rad"] = {
            n: _num(v)
            for n, v, c in zip(names, torque[i], comps)
            if not isinstance(c, Rigid) and not (isinstance(c, Gear) and c.rigid_mesh)
        }
        mode["shape"] = [_num(v) for v in shapes[:, i]]
        if mesh is not None:
            mode["mesh_error"] = _num(mesh.error[i])
        modes.append(mode)
    units = {
        "frequency": "Hz",
        "stiffness": "N·m/rad",
        "inertia": "kg·m²",
        "damping": "N·m·s/rad",
        "damping_ratio": "fraction",
        "shape": "rad (max-normalised)",
        "torque_per_rad": "N·m per rad of peak station rotation",
        "decay_rate": "1/s",
        "damping_contribution": "fraction (each component's part of the mode's damping ratio)",
        "speed_ratio": "a frame's speed / the driving end's speed",
    }
    if full:
        units["bearing"] = "N/m"
    doc = {
        "model": mdl.drivetrain.name,
        "units": units,
        "inertia_model": mdl.inertia_model,
        "dofs": mdl.dofs,
        "n_dof": mdl.n_dof,
        "solver": result.method,
        "damped_solver": None if dm is None else dm.method,
        "components": [component_summary(c) for c in mdl.drivetrain.components],
    }
    if full:
        doc["bearings"] = [{"station": st.name, "stiffness": k} for st, k in mdl.bearings]
    doc |= {
        "flexible_bodies": [
            _body_summary(mdl, b, {s.node: s.name for s in mdl.stations}) for b in mdl.bodies
        ],
        "stations": [s.name for s in mdl.stations],
        "frames": frames_document(mdl),
        "modes": modes,
        "listing": _listing(result, max_hz, count, listed),
    }
    if mesh is not None:
        units["mesh_error"] = "fraction (estimated relative frequency error of the mesh)"
        shown = set(listed)
        doc["mesh_check"] = {
            "method": getattr(mesh, "method", "Richardson extrapolation (h²)"),
            "levels": [int(v) for v in getattr(mesh, "levels", (1, 2))],
            "tolerance": mesh.tolerance,
            "flagged_modes": [int(i) for i in mesh.flagged if i in shown],
        }
        if getattr(mesh, "note", ""):
            doc["mesh_check"]["note"] = mesh.note
    return doc


def _body_summary(mdl, cb, names: dict) -> dict:
    """A flexible body in a chain: interfaces (``names``: node -> station), kept modes, own modes, damping."""
    body = cb.body
    return {
        "component": mdl.drivetrain.components[cb.component].name,
        "interface_stations": [names.get(int(n), f"node {int(n)}") for n in cb.interface_nodes],
        "interface_x": [float(x) for x in body.boundary_x - body.boundary_x[0]],
        "mesh_nodes": body.n_mesh_nodes,
        "modes": int(body.n_modes - body.n_residual),
        "residual_vectors": int(body.n_residual),
        "fixed_interface_hz": [_num(f) for f in body.fixed_interface_hz],
        "free_hz": [_num(f) for f in body.free_hz],
        "damping_ratios": [_num(z) for z in body.damping_ratios],
    }


def _kept_hz(body) -> float:
    """Highest fixed-interface mode kept (residual vectors not counted), Hz; 0 if none."""
    return float(body.fixed_interface_hz[: body.n_modes - body.n_residual].max(initial=0.0))


def _bodies_lines(mdl) -> str:
    """One line per flexible body for the terminal table."""
    lines = []
    for cb in mdl.bodies:
        body = cb.body
        free = body.free_hz[body.free_hz > 0]
        z = body.damping_ratios[body.free_hz > 0]
        ratio = f"{100 * z[0]:.2f} %" if z.size and np.allclose(z, z[0]) else "per mode"
        solid = getattr(body, "solid", None)
        source = (
            f"a solid of {solid.mesh.n_nodes} nodes ({solid.mesh.n_elements} 10-node tetrahedra, "
            f"{solid.interface})"
            if solid is not None
            else f"{body.n_mesh_nodes} mesh nodes"
        )
        lines.append(
            f"  {mdl.drivetrain.components[cb.component].name}: flexible body, "
            f"{body.boundary_nodes.size} interface nodes + {body.n_modes - body.n_residual} modes "
            f"(fixed-interface, up to {_kept_hz(body):.0f} Hz) + {body.n_residual} residual vectors, "
            f"from {source}; own modes "
            + " ".join(f"{f:.0f}" for f in free[:6])
            + (" …" if free.size > 6 else "")
            + f" Hz, damping {ratio}"
        )
    return "\n".join(lines)


def modes_table(
    result: ModalResult, *, max_hz: float | None = None, mesh=None, count: int | None = None
) -> str:
    """A plain-text table of the modes for a terminal (a full model adds each mode's DOF family).

    ``max_hz`` (Hz; default the model's ``[model] max_hz``) lists only the modes up to that
    frequency; without it ``count`` modes (those asked for), else the lowest 20. A line says how
    many were computed and shown, and how to see others.
    """
    mdl = result.model
    full = mdl.dofs == "full"
    dm = result.damped
    dominant = result.dominant_components()
    se = result.strain_energy_fractions()
    state = "damped" if dm is not None else "undamped"
    if full:
        n_b = len(mdl.bearings)
        head = (
            f"{mdl.drivetrain.name}: {len(mdl.drivetrain.components)} components, {mdl.n_dof} DOFs "
            f"(full: Timoshenko shafts), {n_b} bearing{'s' if n_b != 1 else ''}, "
            f"{mdl.inertia_model} inertia, {state}"
        )
    else:
        head = (
            f"{mdl.drivetrain.name}: {len(mdl.drivetrain.components)} components, "
            f"{mdl.n_dof} DOFs (torsion), {mdl.inertia_model} inertia, {state}"
        )
    lines = [head]
    if (frames := frames_line(mdl)) is not None:
        lines.append(frames)
    if mdl.bodies:
        lines.append(_bodies_lines(mdl))
    if full:
        family = result.family_energy()
        kinds = result.kinds
        lines += [
            "",
            f"{'mode':>4}  {'frequency Hz':>12}  {'damping %':>9}  {'kind':<16}  "
            "kinetic energy axial / lateral / torsion  dominant component (strain energy)",
            f"{'-' * 4}  {'-' * 12}  {'-' * 9}  {'-' * 16}  {'-' * 40}  {'-' * 36}",
        ]
    else:
        lines += [
            "",
            f"{'mode':>4}  {'frequency Hz':>12}  {'damping %':>9}  dominant component (strain energy)",
            f"{'-' * 4}  {'-' * 12}  {'-' * 9}  {'-' * 36}",
        ]
    listed = _listed(result, max_hz, count)
    if (line := _listing_line(_listing(result, max_hz, count, listed))) is not None:
        lines.insert(1, line)
    for i in listed:
        f = 0.0 if result.rigid[i] else result.frequencies_hz[i]
        if dm is None:
            damp = "-"
        else:
            z = dm.damping_ratios[i]
            damp = "-" if result.rigid[i] else ("?" if not np.isfinite(z) else f"{100 * z:.4f}")
        if result.rigid[i]:
            rate = 0.0 if dm is None else dm.decay_rates[i]
            dom = "rigid-body mode" + (f" (decays: λ = −{rate:.4g} 1/s)" if rate > 0 else "")
        else:
            ci = mdl.component_names.index(dominant[i])
            dom = f"{dominant[i]} ({100 * se[i, ci]:.0f} %)"
        if full:
            e = [family[k][i] for k in ("axial", "lateral", "torsion")]
            kind = ("rigid " + kinds[i]) if result.rigid[i] else kinds[i]
            energy = f"{e[0]:5.0%} / {e[1]:5.0%} / {e[2]:5.0%}"
            lines.append(f"{i:>4}  {f:>12.4f}  {damp:>9}  {kind:<16}  {energy:<40}  {dom}")
        else:
            lines.append(f"{i:>4}  {f:>12.4f}  {damp:>9}  {dom}")
    if mesh is not None:
        shown = set(listed)
        bad = [int(i) for i in mesh.flagged if i in shown]
        if bad:
            errs = ", ".join(f"{100 * mesh.error[i]:.2g} %" if mesh.error[i] < 1 else "> 100 %" for i in bad)
            lines += [
                "",
                f"mesh: mode{'s' if len(bad) > 1 else ''} {', '.join(map(str, bad))} "
                f"{'are' if len(bad) > 1 else 'is'} estimated more than {100 * mesh.tolerance:g} % from "
                f"the mesh-converged frequency ({errs}): give the shafts more `elements` "
                "(CAD and segment shafts: a smaller `max_element_length`), or set [model] max_hz "
                "to have them meshed for that range",
            ]
        if getattr(mesh, "note", ""):
            lines.append(f"mesh check: one refinement only, may understate: {mesh.note}")
    return "\n".join(lines)


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


def twist_document(result) -> dict:
    """The ``flexshaft twist --json`` document (SI: N·m, rad, m, N·m/rad)."""
    return {
        "units": {
            "torque": "N·m",
            "stiffness": "N·m/rad",
            "twist": "rad",
            "x": "m",
            "speed_ratio": "a frame's speed / the driving end's speed",
        },
        "frames": "each part's torque, twist and stiffness, and each station's theta, in its own speed frame",
        "torque": result.torque,
        "clamp": result.clamp,
        "load": result.load,
        "total_stiffness": result.total_stiffness,
        "load_spread": result.load_spread,
        "ramp_torques": result.ramp.tolist(),
        "parts": [
            {
                "name": p.name,
                "stiffness": p.stiffness,
                "twist": p.twist,
                "x_start": p.x_start,
                "x_end": p.x_end,
                "torque": p.torque,
                "speed_ratio": p.speed_ratio,
                "elements": p.elements,
            }
            for p in result.parts
        ],
        "stations": [
            {
                "name": n,
                "x": float(result.x[i]),
                "theta": float(result.theta[i]),
                "speed_ratio": float(result.speed_ratio[i]),
            }
            for n, i in result.stations
        ],
        "nodes": {"x": result.x.tolist(), "theta": result.theta.tolist()},
    }


def twist_table(result) -> str:
    """The twist test as a readable table."""
    geared = bool(np.any(result.speed_ratio != 1.0))
    lines = [f"twist test: clamped at {result.clamp!r}, {result.torque:g} N·m at {result.load!r}"]
    if geared:
        lines.append(
            "through gear stages: each part's torque, twist and stiffness in its own speed frame "
            "(speed ratio to the driving end); clamp to load in the load's frame"
        )
    head = f"{'part':<16} {'stiffness N·m/rad':>18} {'twist rad':>12} {'x start m':>10} {'x end m':>9}"
    lines += ["", head + (f" {'torque N·m':>12} {'speed ratio':>11}" if geared else "")]
    for p in result.parts:
        row = f"{p.name:<16} {p.stiffness:18.6e} {p.twist:12.5e} {p.x_start:10.4f} {p.x_end:9.4f}"
        lines.append(row + (f" {p.torque:12.5e} {p.speed_ratio:11.5g}" if geared else ""))
    lines.append(f"{'clamp to load':<16} {result.total_stiffness:18.6e}")
    lines += [f"{p.name}: {p.elements}" for p in result.parts if p.elements != "1d"]
    lines.append("")
    lines.append(
        f"load independence over {len(result.ramp)} torques from {result.ramp.min():g} to "
        f"{result.ramp.max():g} N·m: stiffness spread {result.load_spread:.1e}"
    )
    lines.append("")
    lines.append(f"{'station':<24} {'x m':>9} {'theta rad':>12}")
    for name, i in result.stations:
        lines.append(f"{name:<24} {result.x[i]:9.4f} {result.theta[i]:12.5e}")
    return "\n".join(lines)


# --- the other commands' tables and documents ---------------------------------------------------------


def twist_targets_document(targets) -> list[dict]:
    """``twist --target`` results as JSON-ready entries: ``targets`` is ``[(part name, StiffnessTarget)]``
    (stiffness N·m/rad, Young's modulus Pa, scale factors)."""
    return [
        {
            "name": n,
            "target": t.target,
            "current": t.current,
            "E": t.youngs_modulus,
            "scale_all": t.scale_all,
            "scale_diameters": t.scale_diameters,
        }
        for n, t in targets
    ]


def twist_targets_text(targets) -> str:
    """``twist --target`` results as text, one paragraph a part (each after a blank line)."""
    text = ""
    for n, t in targets:
        text += (
            f"\n\n{n}: {t.current:.6e} -> {t.target:.6e} N·m/rad needs E = {t.youngs_modulus:.6e} Pa "
            f"(ν and geometry fixed), or every dimension ×{t.scale_all:.6f}, or the diameters "
            f"×{t.scale_diameters:.6f}"
        )
    return text


def reduction_table(reduction, path=None) -> str:
    """A reduced part (:class:`~flexshaft.model.reduce.PartReduction`) as text; ``path``: where it went."""
    comp, pm, body, check = reduction.component, reduction.part_model, reduction.body, reduction.check
    n_fixed = reduction.fixed_modes
    solid = getattr(body, "solid", None)
    size = (
        f"a solid of {3 * solid.mesh.n_nodes} DOFs ({solid.interface})"
        if solid is not None
        else f"{pm.n_dofs} DOFs"
    )
    lines = [
        f"{comp.name}: {size} ({reduction.dofs}) -> {body.n_boundary} boundary DOFs at x = "
        + ", ".join(f"{x:.4g}" for x in body.boundary_x)
        + f" m + {n_fixed} fixed-interface modes + {body.n_residual} residual vectors",
        "fixed-interface modes, Hz: "
        + (" ".join(f"{f:.2f}" for f in body.fixed_interface_hz[:n_fixed]) or "none (no interior nodes)"),
        "free-free modes of the reduced part, Hz: " + " ".join(f"{f:.2f}" for f in body.free_hz),
        "damping ratio per free-free mode, %: "
        + " ".join(f"{100 * z:.3f}" for z in body.damping_ratios[body.free_hz > 0]),
        f"check: rigid-body mass {check.rigid_mass_error:.1e}, interface stiffness vs static condensation "
        f"{check.static_error:.1e} (relative)",
    ]
    if path is not None:
        lines.append(f"written: {path}")
    return "\n".join(lines)


def frf_document(resp) -> dict:
    """A frequency response (:class:`~flexshaft.analysis.statespace.FrequencyResponse`) as the
    ``flexshaft frf --json`` document: frequencies (Hz), real and imaginary parts (output unit per
    N·m; one output: a list per frequency), and the peaks with their half-power damping."""
    H = resp.H[:, :, 0] if resp.H.shape[2] == 1 else resp.H
    one = H.ndim == 2 and H.shape[1] == 1
    return {
        "inputs": list(resp.inputs),
        "outputs": list(resp.outputs),
        "units": {"frequency": "Hz", "input": list(resp.input_units), "output": list(resp.output_units)},
        "frequency_hz": resp.frequencies_hz.tolist(),
        "real": (H[:, 0].real if one else H.real).tolist(),
        "imag": (H[:, 0].imag if one else H.imag).tolist(),
        "peaks": resp.peaks(),
    }


def frf_csv(resp) -> str:
    """A frequency response as CSV: frequency (Hz), then per output its real and imaginary parts."""
    lines = [
        "frequency_hz,"
        + ",".join(f"{o} real ({u}/N·m),{o} imag ({u}/N·m)" for o, u in zip(resp.outputs, resp.output_units))
    ]
    for k, fk in enumerate(resp.frequencies_hz):
        lines.append(
            f"{fk:.9g},"
            + ",".join(
                f"{resp.H[k, j, 0].real:.9g},{resp.H[k, j, 0].imag:.9g}" for j in range(len(resp.outputs))
            )
        )
    return "\n".join(lines)


def frf_table(resp, peaks=None) -> str:
    """A frequency response's peaks as text (``peaks``: its :meth:`peaks`, where the caller has them)."""
    rows = [f"frequency response {resp.inputs[0]} -> {', '.join(resp.outputs)}; peaks:"]
    rows += [
        f"  {p['frequency_hz']:10.4f} Hz  |H| {p['magnitude']:.4g}  half-power damping "
        f"{100 * p['damping_ratio']:.4f} %"
        for p in (resp.peaks() if peaks is None else peaks)
    ]
    return "\n".join(rows)


def forced_table(fr) -> str:
    """A forced response (:class:`~flexshaft.analysis.forced.ForcedResponse`): the peak dynamic torque
    per part (N·m) at each excitation frequency (Hz)."""
    parts = [k for k, s in enumerate(fr.signals) if s.startswith("torque:")]
    width = max(10, *(len(fr.signals[k]) - 7 for k in parts))
    head = "mode  frequency Hz  " + "  ".join(f"{fr.signals[k][7:]:>{width}}" for k in parts) + "  largest"
    rows = [
        f"forced response to {fr.amplitude:g} N·m at {fr.input}: peak dynamic torque per part, N·m",
        "",
        head,
        "-" * len(head),
    ]
    for i, (f, m) in enumerate(zip(fr.frequencies_hz, fr.modes)):
        cells = "  ".join(f"{fr.amplitudes[i, k]:>{width}.4g}" for k in parts)
        rows.append(f"{m if m >= 0 else '-':>4}  {f:12.4f}  {cells}  {fr.largest_torque(i)}")
    return "\n".join(rows)


def simulation_table(run, scenario, kind: str, first_station: str) -> str:
    """A time run (:class:`~flexshaft.analysis.simulate.SimulationResult`) as text: the run, the speed
    loop (gains in N·m·s/rad and N·m/rad) and each output's min, max and final value."""
    lines = [
        f"{kind} run: {run.time[-1]:g} s at {run.rate_hz:g} Hz ({run.time.size} samples, "
        f"{run.states} states, {run.method})"
    ]
    if scenario.control is not None:
        c = scenario.control
        lines.append(
            f"speed loop on {c.measure or 'speed:' + (scenario.at or first_station)}: "
            f"kp {c.kp:.6g} N·m·s/rad, ki {c.ki:.6g} N·m/rad, tau {c.tau:g} s, "
            f"limits {c.torque_min:g} … {c.torque_max:g} N·m"
        )
    lines.append(f"{'output':<32} {'unit':>6} {'min':>12} {'max':>12} {'final':>12}")
    for name, y in run.outputs.items():
        lines.append(f"{name:<32} {run.units[name]:>6} {y.min():12.5g} {y.max():12.5g} {y[-1]:12.5g}")
    return "\n".join(lines)


def campbell_table(diagram, speed_range=None) -> str:
    """A Campbell diagram's crossings as text (speed rpm, order, mode, frequency Hz, damping %);
    ``speed_range`` (rpm) as asked for, default the diagram's first and last speed."""
    lo, hi = speed_range if speed_range is not None else (diagram.speeds_rpm[0], diagram.speeds_rpm[-1])
    rows = [
        f"Campbell diagram: {lo:g} … {hi:g} rpm at {diagram.reference!r}, orders "
        + ", ".join(f"{k:g}" for k in diagram.orders)
        + (
            " (gyroscopic: the whirl frequencies move with speed)"
            if diagram.speed_dependent
            else " (no speed-dependent terms: every mode is a horizontal line)"
        ),
        "",
        f"{'speed rpm':>10}  {'order':>5}  {'mode':>4}  {'frequency Hz':>12}  {'damping %':>9}",
    ]
    for c in diagram.crossings:
        rows.append(
            f"{c.speed_rpm:10.2f}  {c.order:5g}  {c.mode:4d}  {c.frequency_hz:12.4f}  "
            f"{100 * c.damping_ratio:9.4f}"
        )
    if not diagram.crossings:
        rows.append("  (no order line crosses a mode in this speed range)")
    return "\n".join(rows)


def sensitivity_table(sens, name: str) -> str:
    """Frequency sensitivities (:class:`~flexshaft.analysis.sensitivity.Sensitivities`) of the model
    ``name`` as text: % per % for each parameter and mode."""
    width = max(16, *(len(p.name) for p in sens.parameters))
    rows = [
        f"{name}: frequency sensitivities, % per % (p/f·∂f/∂p); Hz per unit with --json",
        "",
        f"{'parameter':<{width}} {'value':>12} {'unit':>9}  "
        + "  ".join(f"{f'mode {m}':>9}" for m in sens.modes),
        f"{'':<{width}} {'':>12} {'':>9}  " + "  ".join(f"{f'{f:.4g} Hz':>9}" for f in sens.frequencies_hz),
    ]
    for k, p in enumerate(sens.parameters):
        cells = "  ".join(f"{v:9.4f}" for v in sens.normalised[:, k])
        rows.append(f"{p.name:<{width}} {sens.values[k]:12.6g} {p.unit:>9}  {cells}")
    return "\n".join(rows)


def sweep_document(res) -> dict:
    """A parameter sweep (:class:`~flexshaft.analysis.sweep.SweepResult`) as the ``flexshaft sweep
    --json`` document: frequencies (Hz) and damping ratios per point, None where a point was refused."""
    return {
        "parameters": [{"name": n, "unit": u} for n, u in zip(res.names, res.units)],
        "points": res.values.tolist(),
        "frequencies_hz": [[None if np.isnan(v) else float(v) for v in row] for row in res.frequencies_hz],
        "damping_ratios": [[None if np.isnan(v) else float(v) for v in row] for row in res.damping_ratios],
        "errors": list(res.errors),
    }


def sweep_summary(res, *, lhs: bool = False, scheduler: str | None = None) -> str:
    """The first line of a sweep's summary: how many models, over what, how many refused, where."""
    failed = sum(1 for e in res.errors if e)
    return (
        f"{len(res.errors)} models ({'Latin hypercube' if lhs else 'grid'} over "
        + ", ".join(res.names)
        + f"), {failed} refused"
        + (f" on {scheduler}" if scheduler else "")
    )


def sweep_range_table(res) -> str:
    """Each mode's lowest and highest frequency over a sweep's points, Hz."""
    lines = [f"{'mode':>4}  {'min Hz':>12}  {'max Hz':>12}"]
    for k in range(res.frequencies_hz.shape[1]):
        col = res.frequencies_hz[:, k]
        if np.all(np.isnan(col)):
            continue
        lines.append(f"{k + 1:>4}  {np.nanmin(col):12.5g}  {np.nanmax(col):12.5g}")
    return "\n".join(lines)


def calibration_table(staged) -> str:
    """A staged calibration (:class:`~flexshaft.analysis.staged.StagedCalibration`) as text: per stage
    its parameters (initial, tuned, bounds, change %, active bounds), its targets (initial, tuned,
    error %, tolerance %, met), its damping targets (target, initial and tuned damping ratio in %,
    error %, tolerance %, met) and what one parameter alone would need for a missed target."""
    body = []
    for st in staged.stages:
        res, fx = st.result, st.carried
        body += [f"stage {st.name!r} ({st.model}): {res.starts} start(s), cost {res.cost:.4g}; {res.message}"]
        if fx:
            body.append("  carried, fixed: " + ", ".join(f"{k} = {v:.6g}" for k, v in fx.items()))
        width = max(12, *(len(n) for n in res.names))
        body.append(
            f"  {'parameter':<{width}} {'initial':>12} {'tuned':>12} {'lower':>12} {'upper':>12} "
            f"{'change %':>9}  bound"
        )
        for k, n in enumerate(res.names):
            act = res.active[k]
            note = f"{act}: widening it 1 % lowers the cost by {res.widen[k]:.3g}" if act else ""
            change = res.change_percent[k]
            change = f"{change:9.3f}" if np.isfinite(change) else f"{'-':>9}"  # a damper from 0
            body.append(
                f"  {n:<{width}} {res.initial[k]:12.6g} {res.tuned[k]:12.6g} {res.lower[k]:12.6g} "
                f"{res.upper[k]:12.6g} {change}  {note}"
            )
        if res.targets:
            body.append(
                f"  {'target':<16} {'mode':>4} {'initial':>10} {'tuned':>10} {'error %':>8} {'tol %':>6}  met"
            )
        rows = zip(res.targets, res.modes, res.initial_values, res.values, res.errors, res.met)
        for k, (t, mo, a, v, e, ok) in enumerate(rows):
            # a measured shape: its MAC with the mode before and after
            mac = res.shape_mac[k] if k < len(res.shape_mac) else np.nan
            shape = f"  shape MAC {res.initial_shape_mac[k]:.3f} -> {mac:.3f}" if np.isfinite(mac) else ""
            body.append(
                f"  {t.label:<16} {mo:>4} {a:10.5g} {v:10.5g} {100 * e:8.3f} {100 * t.tolerance:6.2f}  "
                f"{'yes' if ok else 'NO '}{shape}".rstrip()
            )
        if res.damping_targets:
            body.append(
                f"  {'damping target':<16} {'mode':>4} {'initial %':>10} {'tuned %':>10} {'error %':>8} "
                f"{'tol %':>6}  met"
            )
        rows = zip(
            res.damping_targets,
            res.damping_modes,
            res.initial_damping,
            res.damping,
            res.damping_errors,
            res.damping_met,
        )
        for t, mo, a, v, e, ok in rows:
            body.append(
                f"  {t.damping_label:<16} {mo:>4} {100 * a:10.4f} {100 * v:10.4f} {100 * e:8.3f} "
                f"{100 * t.damping_tolerance:6.2f}  {'yes' if ok else 'NO'}"
            )
        for u in res.unmet:
            need = "; ".join(f"{e['parameter']} {e['change_percent']:+.1f} %" for e in u["alone_would_need"])
            body.append(f"  {u['target']} is missed by {100 * u['error']:+.2f} %: alone it would need {need}")
        body.append("")
    return "\n".join(body)


def signal_table(analysis) -> str:
    """An analysed signal (:class:`~flexshaft.measurement.analyse.SignalAnalysis`) as text: its peaks'
    frequency (Hz), amplitude, damping (%), log-decrement damping, order and mode, then the notes."""
    decay, by_speed, eigen = analysis.decay, analysis.speed_rpm is not None, bool(analysis.eigenfrequencies)
    spec = analysis.spectrum
    rows = [
        f"{analysis.name} [{analysis.unit}]: {analysis.samples} samples at {analysis.rate_hz:g} Hz; "
        f"{analysis.method}; resolution {spec.resolution_hz:.4g} Hz",
        "",
        f"{'frequency Hz':>12}  {'amplitude':>11}  {'damping %':>9}"
        + ("  log dec. %" if decay else "")
        + ("  order" if by_speed else "")
        + ("  mode" if eigen else ""),
    ]
    notes = []
    for e in analysis.peaks:
        z = e["damping_ratio"]
        damping = "-" if z is None else f"{100 * z:9.4f}"
        row = f"{e['frequency_hz']:12.4f}  {e['amplitude']:11.4g}  {damping:>9}"
        if decay:
            ld = e.get("log_decrement_damping_ratio")
            row += f"  {'-' if ld is None else f'{100 * ld:10.4f}':>10}"
        if by_speed:
            row += f"  {e['order']:5.2f}" if e.get("order") is not None else "      -"
        if eigen:
            row += f"  {e['mode']:4d}" if "mode" in e else "     -"
        rows.append(row)
        missing = e.get("damping_missing")
        if missing:  # the reason once, as why the damping column holds '-'
            notes.append(f"  {e['frequency_hz']:.4g} Hz: damping missing: {missing}")
        notes += [f"  {e['frequency_hz']:.4g} Hz: {n}" for n in e["notes"] if not (missing and n in missing)]
    if notes:
        rows += ["", "notes:"] + notes
    return "\n".join(rows)
