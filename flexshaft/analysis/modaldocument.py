"""The modal result as ``flexshaft modes`` gives it: the JSON-ready document (``--json``) and the
text table, for a torsion or a full (6-DOF) model. Reached through :meth:`ModalResult.to_dict` and
:meth:`ModalResult.table` (``result`` below is a :class:`~flexshaft.analysis.modal.ModalResult`)."""

from __future__ import annotations

import math

import numpy as np

from ..model.components import Gear, Rigid
from ..model.describe import (
    component_summary,
    frames_document,
    frames_line,
    linearised_document,
    linearised_line,
)

__all__ = ["modes_document", "modes_table"]


def _num(x) -> float | None:
    """A JSON-safe float (NaN -> null)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _range_hz(result, max_hz: float | None) -> float | None:
    """The listing's range, Hz: ``max_hz`` as given, else the model's ``[model] max_hz`` (or None)."""
    return max_hz if max_hz is not None else getattr(result.model.drivetrain, "max_hz", None)


def _listing(result, max_hz: float | None, count: int | None, listed) -> dict:
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


def _mode_entries(result, listed, mesh) -> list[dict]:
    """The document's entry of each listed mode (units as :func:`modes_document` says)."""
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
    return modes


def modes_document(result, *, max_hz: float | None = None, mesh=None, count: int | None = None) -> dict:
    """The ``flexshaft modes --json`` document, for a torsion or a full (6-DOF) model.

    Units: frequencies Hz, damping ratios as fractions, stiffness N·m/rad,
    inertia kg·m², bearing stiffness N/m; ``shape`` is θx at the stations,
    scaled so the largest ``|value|`` of each mode is 1. ``strain_energy`` is
    each component's share of the mode's strain energy. ``kinetic_energy`` is
    each component's share of its kinetic energy in a torsion model and, in a
    full model, each DOF family's (axial, lateral, torsion) as before;
    ``kind`` names the family. ``max_hz`` (Hz; default the model's ``[model] max_hz``) lists
    only the modes up to that frequency; without it ``count`` modes (those asked for), else the
    lowest 20. ``listing`` says which and how many were computed.
    """
    mdl = result.model
    full = mdl.dofs == "full"
    dm = result.damped
    listed = result.listed(max_hz, count)
    modes = _mode_entries(result, listed, mesh)
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
        "linearised": linearised_document(mdl.drivetrain),
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


def modes_table(result, *, max_hz: float | None = None, mesh=None, count: int | None = None) -> str:
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
    if (linear := linearised_line(mdl.drivetrain)) is not None:
        lines.append(linear)
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
    listed = result.listed(max_hz, count)
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
