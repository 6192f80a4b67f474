"""Modal results as a JSON-ready document and as a readable table."""

from __future__ import annotations

import math

import numpy as np

from ..analysis.modal import ModalResult
from ..model.components import Coupling, Gear, Rigid, Shaft

__all__ = [
    "modes_document",
    "modes_table",
    "component_summary",
    "sections_document",
    "sections_table",
    "twist_document",
    "twist_table",
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


def _listed(result: ModalResult, max_hz: float | None) -> range | list[int]:
    """The modes to list: all, or those up to ``max_hz`` (Hz)."""
    if max_hz is None:
        return range(result.count)
    return [i for i in range(result.count) if result.frequencies_hz[i] <= max_hz]


def modes_document(result: ModalResult, *, max_hz: float | None = None, mesh=None) -> dict:
    """The ``flexshaft modes --json`` document, for a torsion or a full (6-DOF) model.

    Units: frequencies Hz, damping ratios as fractions, stiffness N·m/rad,
    inertia kg·m², bearing stiffness N/m; ``shape`` is θx at the stations,
    scaled so the largest |value| of each mode is 1. ``strain_energy`` is
    each component's share of the mode's strain energy. ``kinetic_energy`` is
    each component's share of its kinetic energy in a torsion model and, in a
    full model, each DOF family's (axial, lateral, torsion) as before;
    ``kind`` names the family. ``max_hz`` lists only the modes up to that frequency.
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
    for i in _listed(result, max_hz):
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
    }
    if mesh is not None:
        units["mesh_error"] = "fraction (estimated relative frequency error of the mesh)"
        doc["mesh_check"] = {
            "method": "every shaft at twice its elements, Richardson extrapolation (h²)",
            "tolerance": mesh.tolerance,
            "flagged_modes": [int(i) for i in mesh.flagged if i in set(_listed(result, max_hz))],
        }
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
        lines.append(
            f"  {mdl.drivetrain.components[cb.component].name}: flexible body, "
            f"{body.boundary_nodes.size} interface nodes + {body.n_modes - body.n_residual} modes "
            f"(fixed-interface, up to {_kept_hz(body):.0f} Hz) + {body.n_residual} residual vectors, "
            f"from {body.n_mesh_nodes} mesh nodes; own modes "
            + " ".join(f"{f:.0f}" for f in free[:6])
            + (" …" if free.size > 6 else "")
            + f" Hz, damping {ratio}"
        )
    return "\n".join(lines)


def modes_table(result: ModalResult, *, max_hz: float | None = None, mesh=None) -> str:
    """A plain-text table of the modes for a terminal (a full model adds each mode's DOF family).

    ``max_hz`` lists only the modes up to that frequency (Hz), and says how many were computed.
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
    listed = _listed(result, max_hz)
    if max_hz is not None:
        lines.insert(1, f"modes up to {max_hz:g} Hz: {len(listed)} of the {result.count} computed")
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
                "(CAD and segment shafts: a smaller `max_element_length`)",
            ]
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
