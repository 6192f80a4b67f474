"""Modal results as a JSON-ready document and as a readable table."""

from __future__ import annotations

import math

import numpy as np

from .components import Coupling, Rigid, Shaft
from .modal import ModalResult

__all__ = ["modes_document", "modes_table", "component_summary"]


def _num(x) -> float | None:
    """A JSON-safe float (NaN -> null)."""
    x = float(x)
    return x if math.isfinite(x) else None


def component_summary(comp) -> dict:
    """A component's type, end-to-end stiffness (N·m/rad) and inertia (kg·m²)."""
    out: dict = {"name": comp.name, "type": comp.type}
    if isinstance(comp, (Shaft, Coupling)):
        out["stiffness"] = comp.stiffness
    out["inertia"] = comp.inertia
    if isinstance(comp, Shaft):
        out["elements"] = comp.elements
        if comp.damping_ratio:
            out["damping_ratio"] = comp.damping_ratio
    if isinstance(comp, (Shaft, Coupling)) and comp.damping:
        out["damping"] = comp.damping
    return out


def modes_document(result: ModalResult) -> dict:
    """The ``flexshaft modes --json`` document.

    Units: frequencies Hz, damping ratios as fractions, stiffness N·m/rad,
    inertia kg·m²; shapes are rotations at the stations, scaled so the
    largest |value| of each mode is 1.
    """
    mdl = result.model
    names = mdl.component_names
    se = result.strain_energy_fractions()
    ke = result.kinetic_energy_fractions()
    shapes = result.station_shapes()
    dominant = result.dominant_components()
    torque = result.component_torques()
    comps = mdl.drivetrain.components
    dm = result.damped
    modes = []
    for i in range(result.count):
        mode = {
            "index": i,
            "frequency_hz": 0.0 if result.rigid[i] else _num(result.frequencies_hz[i]),
            "damping_ratio": 0.0 if dm is None else _num(dm.damping_ratios[i]),
            "rigid": bool(result.rigid[i]),
        }
        if dm is not None:
            mode["damped_frequency_hz"] = _num(dm.damped_frequencies_hz[i])
            mode["damped_natural_frequency_hz"] = _num(dm.natural_frequencies_hz[i])
        mode["dominant_component"] = dominant[i]
        mode["strain_energy"] = {n: _num(v) for n, v in zip(names, se[i])}
        mode["kinetic_energy"] = {n: _num(v) for n, v in zip(names, ke[i])}
        mode["torque_per_rad"] = {n: _num(v) for n, v, c in zip(names, torque[i], comps)
                                  if not isinstance(c, Rigid)}
        mode["shape"] = [_num(v) for v in shapes[:, i]]
        modes.append(mode)
    return {
        "model": mdl.drivetrain.name,
        "units": {"frequency": "Hz", "stiffness": "N·m/rad", "inertia": "kg·m²",
                  "damping": "N·m·s/rad", "damping_ratio": "fraction", "shape": "rad (max-normalised)",
                  "torque_per_rad": "N·m per rad of peak station rotation"},
        "inertia_model": mdl.inertia_model,
        "dofs": "torsion",
        "n_dof": mdl.n_dof,
        "solver": result.method,
        "damped_solver": None if dm is None else dm.method,
        "components": [component_summary(c) for c in mdl.drivetrain.components],
        "stations": [s.name for s in mdl.stations],
        "modes": modes,
    }


def modes_table(result: ModalResult) -> str:
    """A plain-text table of the modes for a terminal."""
    mdl = result.model
    dm = result.damped
    dominant = result.dominant_components()
    se = result.strain_energy_fractions()
    head = (f"{mdl.drivetrain.name}: {len(mdl.drivetrain.components)} components, "
            f"{mdl.n_dof} DOFs (torsion), {mdl.inertia_model} inertia, "
            f"{'damped' if dm is not None else 'undamped'}")
    lines = [head, "",
             f"{'mode':>4}  {'frequency Hz':>12}  {'damping %':>9}  dominant component (strain energy)",
             f"{'-' * 4}  {'-' * 12}  {'-' * 9}  {'-' * 36}"]
    for i in range(result.count):
        f = 0.0 if result.rigid[i] else result.frequencies_hz[i]
        if dm is None:
            damp = "-"
        else:
            z = dm.damping_ratios[i]
            damp = "-" if result.rigid[i] else ("?" if not np.isfinite(z) else f"{100 * z:.4f}")
        if result.rigid[i]:
            dom = "rigid-body mode"
        else:
            ci = mdl.component_names.index(dominant[i])
            dom = f"{dominant[i]} ({100 * se[i, ci]:.0f} %)"
        lines.append(f"{i:>4}  {f:>12.4f}  {damp:>9}  {dom}")
    return "\n".join(lines)
