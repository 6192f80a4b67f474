"""The checks of a calibration problem against its model, before anything is solved: every target's
modes are elastic modes of the model (and a measured shape is the mode it names), every parameter is the
model's and its bounds inside what it can take, each kind of target has a parameter of its kind and each
tuned parameter a target. Errors name the entry as a targets file labels it (``[[target]] #2``).
"""

from __future__ import annotations

import numpy as np

from ...errors import ModelError
from ...linalg.mac import mac
from ...model.assembly import assemble
from ...model.components import Drivetrain
from ..parameters import DAMPING_FIELDS, is_damping, parameter_domain, parameters
from .targets import Bound, Target
from .tracking import MAC_CLEAR, undamped_modes

__all__ = ["check_problem", "check_parameters", "check_bounds", "check_targets", "check_pairing", "by_shape"]


def by_shape(m, targets) -> list:
    """Check the targets that carry a measured shape against the starting model's modes (MAC);
    ``m`` is the starting model, assembled, and the targets are checked (:func:`check_targets`)."""
    if not any(t.shape is not None for t in targets):
        return list(targets)
    r = undamped_modes(m, [t.mode for t in targets])
    st = r.station_shapes()
    for i, t in enumerate(targets):
        if t.shape is None:
            continue
        macs = mac(np.asarray(t.shape), st)  # measured at a few stations: unweighted
        macs[r.rigid] = 0.0
        best = int(np.argmax(macs))
        if macs[best] < MAC_CLEAR or best != t.mode:
            raise ModelError(
                f"the measured shape is mode {best} of the model (MAC {macs[best]:.2f}), not mode {t.mode}"
                if macs[best] >= MAC_CLEAR
                else f"no mode of the model has the measured shape (best: mode {best}, MAC {macs[best]:.2f})",
                component=_where("target", i),
                field="target.mode",
                value=t.mode,
                valid=f"mode = {best}" if macs[best] >= MAC_CLEAR else f"a shape with MAC >= {MAC_CLEAR}",
            )
    return list(targets)


def check_problem(drivetrain: Drivetrain, targets, params, *, inertia_model: str | None = None) -> None:
    """Check a calibration problem against its model without solving anything.

    Every target's mode numbers are elastic modes of the model, its shape has a value per station,
    no frequency, ratio or damping ratio is targeted twice; every parameter is the model's, named once,
    its fixed value or bounds inside what it can take; damping targets have a damping parameter to
    tune and frequency targets a stiffness or inertia one, and every tuned parameter a target.
    :func:`calibrate` does this (and checks the bounds against the starting values) before its
    optimiser starts; a staged calibration checks every stage this way before the first one runs.
    Errors name the entry as a targets file labels it (``[[target]] #2``) and the field.
    """
    targets, params = list(targets), list(params)
    if not targets:
        raise ModelError("no targets", field="target", valid="at least one [[target]]")
    check_parameters(drivetrain, params)
    check_targets(targets, assemble(drivetrain, inertia_model, reduce=False, damping=False))
    check_pairing(drivetrain, targets, params)


def _where(kind: str, i: int) -> str:
    """The entry a problem is in, as a targets file labels it: ``[[target]] #2``."""
    return f"[[{kind}]] #{i + 1}"


def _entries(items, kind: str, cls: type):
    """Each entry's index, label and value, once it is known to be a ``cls`` (a ``kind`` entry)."""
    for i, item in enumerate(items):
        where = _where(kind, i)
        if not isinstance(item, cls):
            raise ModelError(
                f"not a {kind}",
                component=where,
                value=type(item).__name__,
                valid=f"a {cls.__name__}",
                has_value=True,
            )
        yield i, where, item


def check_parameters(d: Drivetrain, params) -> None:
    """Every parameter is a Bound of this model, named once (tuned or fixed), a fixed value one the
    parameter can take."""
    seen: dict = {}
    for _, where, b in _entries(params, "parameter", Bound):
        try:
            domain = parameter_domain(d, b.name)
        except ModelError as err:
            raise err.located(component=where) from None
        if b.name in seen:
            raise ModelError(
                f"is listed twice ({seen[b.name]} too)",
                component=where,
                field="parameter",
                value=b.name,
                valid="each parameter once: tuned (bounds, percent) or fixed",
            )
        seen[b.name] = where
        rayleigh = [n for n in seen if n.startswith("rayleigh.")]
        if len({n.startswith("rayleigh.damping_ratios") for n in rayleigh}) == 2:
            raise ModelError(
                f"states the Rayleigh damping a second way ({', '.join(rayleigh)})",
                component=where,
                field="parameter",
                value=b.name,
                valid="rayleigh.alpha and rayleigh.beta, or the two rayleigh.damping_ratios",
            )
        if b.lower is not None and not (domain.contains(b.lower) and domain.contains(b.upper)):
            raise ModelError(
                f"the {'lower' if not domain.contains(b.lower) else 'upper'} bound is not a value "
                f"{b.name} can take",
                component=where,
                field=f"{b.name}.bounds",
                value=[float(b.lower), float(b.upper)],
                unit=domain.unit or None,
                valid=f"bounds inside {b.name} {domain.text}",
            )
        if b.fixed is not None and not domain.contains(b.fixed):
            raise ModelError(
                f"is not a value {b.name} can take",
                component=where,
                field=f"{b.name}.fixed",
                value=float(b.fixed),
                unit=domain.unit or None,
                valid=f"{b.name} {domain.text}",
            )


def check_bounds(d: Drivetrain, params, free, x0, lo, hi) -> None:
    """The tuned parameters' bounds: inside the values each can take (a stiffness > 0, a damping
    ratio in [0, 1) ...), wide enough for a double to tell apart, around the model's value, which is
    not 0. ``lo``, ``hi`` are the absolute bounds (from ``bounds`` or ± ``percent``)."""
    index = {id(b): k for k, b in enumerate(params)}
    for j, b in enumerate(free):
        where, name = _where("parameter", index[id(b)]), b.name
        domain = parameter_domain(d, name)
        unit = domain.unit or None
        key = "percent" if b.percent is not None else "bounds"
        given = float(b.percent) if b.percent is not None else [float(lo[j]), float(hi[j])]
        if not (domain.contains(lo[j]) and domain.contains(hi[j])):
            side = "lower" if not domain.contains(lo[j]) else "upper"
            reach = f" (± {b.percent:g} % of {x0[j]:g} is {lo[j]:g} … {hi[j]:g})" if key == "percent" else ""
            raise ModelError(
                f"the {side} bound is not a value {name} can take{reach}",
                component=where,
                field=f"{name}.{key}",
                value=given,
                unit=unit if key == "bounds" else "%",
                valid=f"bounds inside {name} {domain.text}",
            )
        damping = is_damping(d, name)
        if x0[j] == 0 and (key == "percent" or not damping):
            # a damping parameter's solve is scaled by its bounds where it starts at 0 (no damper yet)
            raise ModelError(
                "cannot tune a parameter that is 0 (its change has no scale)",
                component=where,
                field=name,
                value=0.0,
                valid="bounds = [lower, upper] (a damping parameter may start at 0), or fixed = value"
                if damping
                else "a parameter whose value in the model is not 0, or fixed = value",
            )
        room = 1e-12 * abs(x0[j]) if x0[j] else 1e-300  # from 0: a width its scale can divide by
        if not hi[j] - lo[j] > room:  # bounds a double cannot tell apart
            raise ModelError(
                "the bounds leave no room to tune",
                component=where,
                field=f"{name}.{key}",
                value=given,
                valid=f"bounds at least 1e-12 of the value ({x0[j]:.10g}) apart, or fixed = value"
                if x0[j]
                else "bounds more than 1e-300 apart, or fixed = value",
            )
        if not lo[j] <= x0[j] <= hi[j]:
            raise ModelError(
                f"the bounds do not contain the model's value, {x0[j]:.10g}",
                component=where,
                field=f"{name}.{key}",
                value=given,
                unit=unit,
                valid=f"bounds around {x0[j]:.10g} (the starting point), inside {name} {domain.text}",
            )


def check_targets(targets, m) -> None:
    """Every target's mode numbers are elastic modes of the starting model ``m`` (assembled), its
    shape (if any) has a value per station, and no quantity is targeted twice - before any solve."""
    n, rigid = m.n_dof, m.rigid_basis.shape[1]
    zero = "mode 0 is" if rigid == 1 else f"modes 0 … {rigid - 1} are"
    valid = f"an elastic mode of the model, {rigid} … {n - 1}" if n > rigid else "a model with elastic modes"
    seen: dict = {}
    for i, where, t in _entries(targets, "target", Target):
        for key, k in (("mode", t.mode), ("ratio_to", t.ratio_to)):
            if k is not None and not rigid <= k < n:
                raise ModelError(
                    f"the model has {n} modes, 0 … {n - 1}; {zero} rigid-body"
                    if 0 <= k < n
                    else f"no such mode: the model has {n} modes, 0 … {n - 1}",
                    component=where,
                    field=f"target.{key}",
                    value=k,
                    valid=valid,
                )
        if t.shape is not None and len(t.shape) != len(m.stations):
            raise ModelError(
                f"has {len(t.shape)} values for the model's {len(m.stations)} stations",
                component=where,
                field="target.shape",
                value=len(t.shape),
                valid="θx at each station, in order: " + ", ".join(repr(x.name) for x in m.stations),
            )
        # f2/f1 and f1/f2 are one quantity; two targets on it contradict or repeat each other
        keys = []
        if t.has_frequency:
            keys.append(("f", t.mode) if t.ratio_to is None else ("r", *sorted((t.mode, t.ratio_to))))
        if t.damping_ratio is not None:
            keys.append(("z", t.mode))
        for key in keys:
            if key in seen:
                raise ModelError(
                    f"targets what {seen[key]} targets already",
                    component=where,
                    field="target",
                    value=t.label if key[0] != "z" else t.damping_label,
                    valid="one target per frequency, ratio or damping ratio",
                )
            seen[key] = _where("target", i)


def check_pairing(d: Drivetrain, targets, params) -> None:
    """Each kind of target has a parameter of its kind to tune, and each tuned parameter a target.

    The undamped modes do not move with a damping parameter, and the damping ratios are not the
    frequency parameters' to meet (they are set by the frequency targets): a damping target is met
    by damping parameters alone, a frequency or ratio by stiffness, inertia and the like. A target
    nothing can move, or a parameter no target asks to move, is a mistake in the problem.
    """
    free = [(k, b) for k, b in enumerate(params) if b.fixed is None]
    damping = {b.name: is_damping(d, b.name) for _, b in free}
    has = {True: any(damping.values()), False: not all(damping.values())}
    wants = {
        True: any(t.damping_ratio is not None for t in targets),
        False: any(t.has_frequency for t in targets),
    }
    for i, t in enumerate(targets):
        if t.damping_ratio is not None and not t.has_frequency and not has[True]:
            # beside a frequency a damping ratio without a damping parameter is compared, not met (a
            # targets file from `flexshaft identify` carries both); alone it would be a target for nothing
            names = [p.name for p in parameters(d) if p.field in DAMPING_FIELDS]
            raise ModelError(
                "a damping ratio needs a damping parameter to tune (stiffness and inertia are the frequency "
                "targets')",
                component=_where("target", i),
                field="target.damping_ratio",
                value=t.damping_ratio,
                valid="a [[parameter]] that sets damping: " + ", ".join(names),
            )
        if t.has_frequency and not has[False]:
            raise ModelError(
                "no parameter moves the frequencies (damping parameters leave the undamped modes as "
                "they are)",
                component=_where("target", i),
                field="target.frequency_hz" if t.frequency_hz is not None else "target.ratio",
                value=t.value,
                valid="a stiffness, inertia or material [[parameter]] beside the damping ones",
            )
    for k, b in free:
        if damping[b.name] and not wants[True]:
            raise ModelError(
                "sets damping, and no target has a damping_ratio (damping leaves the undamped frequencies "
                "as they are)",
                component=_where("parameter", k),
                field="parameter",
                value=b.name,
                valid="a [[target]] with damping_ratio, or fixed = value",
            )
        if not damping[b.name] and not wants[False]:
            raise ModelError(
                "moves the frequencies, and no target has frequency_hz or ratio",
                component=_where("parameter", k),
                field="parameter",
                value=b.name,
                valid="a [[target]] with frequency_hz or ratio, or fixed = value",
            )
