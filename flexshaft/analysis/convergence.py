"""Is the mesh fine enough? A per-mode estimate of the error of the frequencies as computed, and a
mesh chosen from the frequency range of interest.

The estimate (:func:`mesh_convergence`)
---------------------------------------
A shaft given by numbers is one element unless told otherwise (the study's matrix models), and
its higher modes are then far from the shaft's own. The drivetrain is solved twice more, with every
element of every shaft cut into 2 and into 4 equal pieces (nested meshes h/2 and h/4; rigid
inertias and couplings are exact and stay). The 2-node torsion and Timoshenko elements converge as
h², so Richardson extrapolation on the finer pair gives the mesh-converged frequency

    f_∞ ≈ f_ext = f_{h/4} + (f_{h/4} − f_{h/2}) / 3,

and the error of the frequency as computed, on the user's mesh h, is

    error of f_h = ``|f_h − f_ext| / f_ext``.

Why this is asymptotic where one step from h to h/2 is not: the one-step estimate
``(4/3)·|f_h − f_{h/2}|`` assumes the error of f_h is already 4 times that of f_{h/2}, which holds
only once h resolves the mode (a few elements per half-wave); a one-element shaft's third mode is
far from that, and the step understated the error up to 2x (Customer 1 mode 3: 4.5 % told, 9.7 %
true). Here h enters only through f_h itself: the estimate's own error is that of f_ext, the
Richardson remainder of the pair (h/2, h/4), which is O(h⁴) and small beside f_h − f_∞ as soon as
h/2 is in the asymptotic range, whatever h is. Even a wrong order does little: were the true order
4 (bending of Hermite-cubic beams), f_ext would miss f_∞ by (1/3 − 1/15)·(f_{h/2} − f_{h/4}), under
2 % of the error of f_h.

Modes are paired by index: cutting every element nests the coarse finite-element space in the
fine ones, so by the min-max principle the fine k-th eigenvalue lies between the coarse k-th and
the exact k-th (consistent inertia). A coarse mesh that misses a mode altogether (a short part in
too few elements) therefore shows as a large error from that mode on: its k-th mode is not the
shaft's k-th - which is what the user must be told.

Where the h/4 mesh would cross a resource ceiling (:mod:`flexshaft.system.limits`: elements per part,
6-DOF elements per part, the model's memory) the estimate falls back to one Richardson step from h
to h/2 and says so (:attr:`MeshConvergence.note`); that fallback is a lower bound for a mode the
mesh does not resolve.

The mesh for a range (:func:`mesh_for_range`)
---------------------------------------------
See its docstring: a wavelength rule per shaft, then the estimate above on every mode below
``max_hz``, refining the parts that carry those modes until every one is within tolerance.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..model.assembly import MAX_MODAL_DAMPING_DOFS, MAX_MODAL_DAMPING_ELEMENTS, assemble
from ..model.components import Drivetrain, Shaft
from ..system.threads import follows_policy
from ..validation import check_frequency, check_real
from .modal import ModalResult, modal_analysis, modes_up_to

__all__ = [
    "MeshConvergence",
    "mesh_convergence",
    "DEFAULT_MESH_TOLERANCE",
    "MeshChoice",
    "mesh_for_range",
    "elements_for_wavenumber",
    "meshed_for_own_range",
]

DEFAULT_MESH_TOLERANCE = 0.01
"""Relative frequency error above which a mode is flagged (1 %)."""

#: The nested refinements the estimate solves: every element cut into 2, then into 4.
REFINEMENTS = (2, 4)
#: Convergence order of the frequencies of 2-node (linear torsion, Timoshenko) elements.
ORDER = 2.0


@dataclass(frozen=True)
class MeshConvergence:
    """Per-mode mesh-convergence estimate of a modal result.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (m,)
        The modes as computed, Hz.
    refined_hz : ndarray, shape (m,)
        The same modes with every shaft element cut into 2, Hz.
    extrapolated_hz : ndarray, shape (m,)
        Richardson's estimate of the mesh-converged frequency, Hz (from the two finest meshes).
    error : ndarray, shape (m,)
        Estimated relative error of ``frequencies_hz``: ``|f_h − f_ext| / f_ext`` (0 for rigid-body
        modes).
    tolerance : float
        The error above which a mode is flagged.
    finest_hz : ndarray, shape (m,), optional
        The modes with every element cut into 4, Hz; None when that mesh was over a ceiling.
    levels : tuple of int
        The refinements solved, each element cut into this many pieces: ``(1, 2, 4)``, or
        ``(1, 2)`` in the fallback.
    note : str
        Empty, or why the estimate is a weaker one (the h/4 mesh over a resource ceiling).
    """

    frequencies_hz: np.ndarray
    refined_hz: np.ndarray
    extrapolated_hz: np.ndarray
    error: np.ndarray
    tolerance: float
    finest_hz: np.ndarray | None = None
    levels: tuple = (1,) + REFINEMENTS
    note: str = ""

    @property
    def flagged(self) -> np.ndarray:
        """Indices of the modes whose estimated error exceeds ``tolerance``."""
        return np.flatnonzero(self.error > self.tolerance)

    @property
    def asymptotic(self) -> bool:
        """True when the estimate used two refinements (not the one-step fallback)."""
        return self.finest_hz is not None

    @property
    def method(self) -> str:
        """One line saying how the estimate was made, for reports."""
        if self.asymptotic:
            return (
                "every shaft element cut into 2 and into 4, Richardson extrapolation (h²) of the finer "
                "pair; error of the frequency as computed"
            )
        return "every shaft element cut into 2, one Richardson step (h²): " + self.note


def _subdivided(drivetrain: Drivetrain, r: int) -> Drivetrain:
    """The drivetrain with every element of every shaft cut into ``r`` equal pieces (nested)."""
    comps = tuple(
        dataclasses.replace(c, subdivide=c.subdivide * r) if isinstance(c, Shaft) else c
        for c in drivetrain.components
    )
    return dataclasses.replace(drivetrain, components=comps)


def _solve_refined(model, r: int, count: int) -> np.ndarray:
    """The ``count`` lowest undamped frequencies (Hz) with every shaft element cut into ``r``."""
    # Undamped frequencies are compared: the parts' modal damping (a dense eigen-solve each) is not built.
    fine = assemble(
        _subdivided(model.drivetrain, r), inertia_model=model.inertia_model, dofs=model.dofs, damping=False
    )
    return modal_analysis(fine, count, damped=False).frequencies_hz[:count]


def _relative(f: np.ndarray, ref: np.ndarray, rigid: np.ndarray) -> np.ndarray:
    """|f − ref| / ref; 0 on rigid-body modes (and where ref is not positive)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(rigid | (ref <= 0), 0.0, np.abs(f - ref) / np.abs(ref))


@follows_policy
def mesh_convergence(
    result: ModalResult, tolerance: float = DEFAULT_MESH_TOLERANCE, *, count: int | None = None
) -> MeshConvergence:
    """Estimate how far each mode of ``result`` is from mesh convergence (see the module docstring).

    Parameters
    ----------
    result : ModalResult
        The modes to check; their drivetrain is re-meshed (each shaft element cut into 2 and into 4)
        and solved twice more.
    tolerance : float
        Relative error above which a mode is flagged (1 % by default).
    count : int, optional
        Check only the lowest ``count`` modes (those listed); default all of ``result``.

    Raises
    ------
    ModelError
        Even the h/2 mesh is over a resource ceiling (the h/4 one falls back, see ``note``).
    """
    tolerance = check_real(tolerance, "tolerance", "", lo=0.0, lo_open=True)
    m = result.count if count is None else max(1, min(int(count), result.count))
    model = result.model
    f_h = result.frequencies_hz[:m].copy()
    rigid = result.rigid[:m]
    f_2 = _solve_refined(model, REFINEMENTS[0], m)
    try:
        f_4 = _solve_refined(model, REFINEMENTS[1], m)
    except ModelError as err:
        # The finest mesh is over a ceiling: one step from h to h/2, a lower bound where h does not
        # resolve the mode - said, not hidden.
        ext = f_2 + (f_2 - f_h) / (2.0**ORDER - 1.0)
        note = f"the mesh with every element cut into 4 is over a resource ceiling ({err.message})"
        return MeshConvergence(
            f_h, f_2, ext, _relative(f_h, ext, rigid), float(tolerance), None, (1, REFINEMENTS[0]), note
        )
    ext = f_4 + (f_4 - f_2) / (2.0**ORDER - 1.0)
    return MeshConvergence(f_h, f_2, ext, _relative(f_h, ext, rigid), float(tolerance), f_4)


# ------------------------------------------------------------------------------------------------
# Meshes from the frequency range


def elements_for_wavenumber(kappa_length: float, error: float) -> int:
    """Elements a uniform stretch needs so a wave of ``kappa_length`` radians over it is within ``error``.

    Linear 2-node elements of length h on a wave of wavenumber κ (rad/m) have the dispersion
    relation, consistent inertia,

        ω_h² = (c/h)²·6·(1 − cos κh)/(2 + cos κh) = (cκ)²·(1 + (κh)²/12 + O((κh)⁴)),

    so ω_h/ω − 1 ≈ (κh)²/24 (lumped inertia: ω_h = (2c/h)·sin(κh/2), −(κh)²/24). A mode of the
    stretch at that wavenumber is within ``error`` when κh ≤ √(24·error): for 1 %, κh ≤ 0.49,
    about 13 elements per wavelength, 6.4 per half-wave. A stretch of length L carrying κ·L radians
    needs ⌈κ·L / √(24·error)⌉ elements.

    Parameters
    ----------
    kappa_length : float
        κ·L, rad (the phase the highest wave of interest turns through along the stretch).
    error : float
        Relative frequency error allowed (fraction).
    """
    n = kappa_length / math.sqrt(24.0 * error)
    return max(1, math.ceil(n - 1e-12))


#: The wavelength rule aims at this share of the tolerance, so the check usually passes at once
#: (a mode's error is an energy-weighted mean of its parts' dispersion errors, at most the largest).
_RULE_SHARE = 0.5
#: Verification rounds at most: each refines the parts that matter 2 to 4 times.
_MAX_ROUNDS = 6
#: A part whose strain or kinetic energy share in a flagged mode exceeds this is refined.
_ENERGY_SHARE = 0.01
#: A round that leaves the largest flagged error above this share of the previous one has stalled.
_STALL = 0.5


def _torsion_wavenumber(shaft: Shaft, omega: float) -> float:
    """Largest torsional wavenumber along a shaft made from sections at ``omega`` (rad/s), rad/m.

    Per interval, c = √(G·J / (ρ·Ip)) (√(G/ρ) for a round section, where J = Ip).
    """
    t, mat = shaft.sections, shaft.material
    c = np.sqrt(mat.G * t.j / (mat.rho * t.ip))
    return float(omega / np.min(c))


def _bending_wavenumber(shaft: Shaft, omega: float) -> float:
    """Largest Timoshenko bending (and axial) wavenumber along a shaft made from sections, rad/m.

    Timoshenko's beam, E·I·κ⁴ − ρ·I·ω²·(1 + E·A/(G·A_s))·κ² − ρ·A·ω² + ρ²·I·ω⁴·A/(G·A_s) = 0 per
    interval (I the smaller bending moment of area, A_s the smaller shear area), its propagating
    root κ² = (−b + √(b² − 4·a·c)) / (2·a); Euler–Bernoulli's (ρ·A·ω²/(E·I))^¼ at low frequency,
    larger (shorter waves) as shear and rotary inertia set in. The axial wave, ω·√(ρ/E), is
    longer than the torsional one and never decides.
    """
    t, mat = shaft.sections, shaft.material
    E, G, rho = mat.E, mat.G, mat.rho
    A = t.area
    inertia = np.minimum(t.iy, t.iz)
    As = np.minimum(t.shear_area_y, t.shear_area_z)
    w2 = omega * omega
    a = E * inertia
    b = -rho * inertia * w2 * (1.0 + E * A / (G * As))
    c = rho * rho * inertia * w2 * w2 * A / (G * As) - rho * A * w2
    k2 = (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return float(np.sqrt(np.max(k2)))


def _rule(shaft: Shaft, max_hz: float, dofs: str, error: float) -> Shaft:
    """The shaft meshed by the wavelength rule at ``max_hz`` (see :func:`elements_for_wavenumber`)."""
    omega = 2.0 * math.pi * max_hz
    if shaft.sections is None:
        # Given by numbers: a uniform shaft of stiffness K and inertia I is, per unit length, a
        # medium whose free-free modes are ω_n = n·π·√(K/I), so κ·L = ω·√(I/K).
        if shaft.inertia == 0:
            return shaft  # a massless spring: exact in one element
        n = elements_for_wavenumber(omega * math.sqrt(shaft.inertia / shaft.stiffness), error)
        return dataclasses.replace(shaft, elements=max(n, shaft.elements))
    kappa = _torsion_wavenumber(shaft, omega)
    if dofs == "full":
        kappa = max(kappa, _bending_wavenumber(shaft, omega))
    h = math.sqrt(24.0 * error) / kappa
    cap = shaft.mesh_cap
    return dataclasses.replace(shaft, max_element_length=h if cap is None else min(h, cap), elements=1)


def _refine(shaft: Shaft, factor: int) -> Shaft:
    """The shaft with its elements ``factor`` times shorter (its longest one, for a section mesh)."""
    if shaft.sections is None:
        return dataclasses.replace(shaft, elements=shaft.elements * factor)
    longest = float(np.max(np.diff(shaft.torsion_mesh().x)))
    return dataclasses.replace(shaft, max_element_length=longest / factor * (1 - 1e-9), elements=1)


@dataclass(frozen=True)
class MeshChoice:
    """A drivetrain meshed for a frequency range, and the check that says it holds.

    Attributes
    ----------
    drivetrain : Drivetrain
        The meshed chain: every shaft the user did not mesh has explicit ``elements`` (given by
        numbers) or ``max_element_length`` (m; made from sections). Unchanged without ``max_hz``.
    max_hz : float or None
        The range, Hz.
    convergence : MeshConvergence or None
        The estimate on the final mesh, of the modes up to ``max_hz`` (None without ``max_hz``).
    elements : dict
        Component name -> elements of its mesh, for every shaft.
    rounds : int
        Checks solved (each is the model at h/2 and h/4 once more).
    converged : bool
        Every mode below ``max_hz`` within the tolerance by the estimate.
    message : str
        One line: what was done, or why it is not converged (a part the user meshed, a ceiling).
    fixed : tuple of str
        Shafts whose mesh the user gave (left as given).
    """

    drivetrain: Drivetrain
    max_hz: float | None
    convergence: MeshConvergence | None
    elements: dict = field(default_factory=dict)
    rounds: int = 0
    converged: bool = True
    message: str = ""
    fixed: tuple = ()


def _elements(d: Drivetrain) -> dict:
    return {c.name: int(c.n_elements) for c in d.components if isinstance(c, Shaft)}


def _damping_guard(d: Drivetrain) -> None:
    """Refuse a mesh the damped model could not be built on: a shaft's own modal damping
    (``damping_ratio``) is a dense eigen-solve of its mesh, with its own size guard in assembly."""
    for comp in d.components:
        if isinstance(comp, Shaft) and comp.damping_ratio > 0 and comp.reduce is None:
            n = comp.n_elements
            if n > MAX_MODAL_DAMPING_ELEMENTS or (d.dofs == "full" and 6 * (n + 1) > MAX_MODAL_DAMPING_DOFS):
                raise ModelError(
                    f"modal damping per shaft mode needs the shaft's own modes, and {n:g} elements are "
                    "over its dense eigen-solve's guard",
                    component=repr(comp.name),
                    field="elements",
                    value=int(n),
                )


def _check(d: Drivetrain, max_hz: float, tolerance: float) -> tuple[ModalResult, MeshConvergence]:
    """The modes up to ``max_hz`` (undamped) and their mesh estimate."""
    _damping_guard(d)
    model = assemble(d, damping=False)
    result = modes_up_to(model, max_hz, damped=False)
    below = int(np.count_nonzero(result.frequencies_hz <= max_hz))
    return result, mesh_convergence(result, tolerance, count=max(below, 1))


def _culprits(d: Drivetrain, result: ModalResult, mc: MeshConvergence, free: set) -> dict:
    """Unfixed shafts carrying energy in flagged modes -> refinement factor (2 to 4)."""
    se = result.strain_energy_fractions()
    ke = result.kinetic_energy_fractions()
    out: dict = {}
    for i in mc.flagged:
        # error ~ h²: cut by √(error / target) brings it to the target; at least 2, at most 4 a round
        factor = int(min(4, max(2, math.ceil(math.sqrt(mc.error[i] / (_RULE_SHARE * mc.tolerance))))))
        for ci, comp in enumerate(d.components):
            if comp.name in free and max(se[i, ci], ke[i, ci]) > _ENERGY_SHARE:
                out[comp.name] = max(out.get(comp.name, 1), factor)
    return out


@follows_policy
def mesh_for_range(
    drivetrain: Drivetrain,
    max_hz: float | None = None,
    tolerance: float = DEFAULT_MESH_TOLERANCE,
    progress=None,
) -> MeshChoice:
    """Mesh every shaft so each mode below ``max_hz`` is within ``tolerance`` of mesh convergence.

    1. A wavelength rule starts each shaft whose mesh the user did not fix
       (:attr:`Shaft.fixed_mesh`): the highest wave of interest, at ``max_hz``, gets elements
       short enough for half the tolerance by the dispersion error of linear elements,
       (κh)²/24 (:func:`elements_for_wavenumber`). A shaft given by numbers is a uniform medium
       whose free-free modes are ω_n = n·π·√(K/I), so κ·L = 2π·max_hz·√(I/K) sets its element
       count. A shaft made from sections (segments, a CAD part's slices) gets
       ``max_element_length`` = √(24·error)/κ with κ = ω/c, c = √(G·J/(ρ·Ip)) the torsional wave
       speed of its slowest section, and for ``dofs = "full"`` the Timoshenko bending wavenumber
       at ``max_hz`` where it is larger; every section step stays a node.
    2. The mesh check (:func:`mesh_convergence`, two nested refinements) runs on every mode up to
       ``max_hz``. Shafts not fixed by the user that carry more than 1 % of the strain or kinetic
       energy of a flagged mode get their elements 2 to 4 times shorter (by √(error/target),
       the h² law), and the check runs again, at most 6 rounds.
    3. It stops when every mode is within tolerance, when only fixed parts are left to refine
       (then not converged, naming them), or when a resource ceiling (:mod:`flexshaft.system.limits`)
       refuses the next mesh (then not converged, with the last mesh that fit and why).

    Parameters
    ----------
    drivetrain : Drivetrain
        The chain; its ``max_hz`` is used when none is given.
    max_hz : float, optional
        The frequency range of interest, Hz, > 0. None and no ``drivetrain.max_hz``: the
        drivetrain is returned unchanged.
    tolerance : float
        Relative frequency error allowed, fraction (1 %).
    progress : callable, optional
        ``progress(label)`` returns a ``(done, total)`` callback, called once a round.

    Returns
    -------
    MeshChoice
    """
    tolerance = check_real(tolerance, "tolerance", "", lo=0.0, lo_open=True, hi=1.0)
    if max_hz is None:
        max_hz = drivetrain.max_hz
    if max_hz is None:
        elements = _elements(drivetrain)
        return MeshChoice(drivetrain, None, None, elements, 0, True, "no max_hz: the mesh as given")
    max_hz = check_frequency(max_hz, "max_hz", lo_open=True)
    tick = progress(f"meshing for {max_hz:g} Hz") if progress is not None else None
    fixed = tuple(c.name for c in drivetrain.components if isinstance(c, Shaft) and c.fixed_mesh)
    free = {c.name for c in drivetrain.components if isinstance(c, Shaft) and not c.fixed_mesh}
    d = dataclasses.replace(
        drivetrain,
        max_hz=max_hz,
        components=tuple(
            _rule(c, max_hz, drivetrain.dofs, _RULE_SHARE * tolerance) if c.name in free else c
            for c in drivetrain.components
        ),
    )
    rounds, stop, prev = 0, "", None
    while True:
        try:
            result, mc = _check(d, max_hz, tolerance)
        except ModelError as err:
            if prev is None:
                raise  # even the rule's mesh does not fit: the error says which ceiling
            d, result, mc = prev
            stop = f"the next refinement is over a resource ceiling ({err.message}); kept the last that fit"
            break
        rounds += 1
        if tick is not None:
            tick(rounds, _MAX_ROUNDS)
        if mc.flagged.size == 0:
            break
        todo = _culprits(d, result, mc, free)
        worst = float(np.max(mc.error[mc.flagged]))
        # A refinement of the free parts that no longer lowers the error (by h², it should fall
        # 4 to 16 times) leaves it in the parts the file meshes: refining on would only cost.
        stalled = False
        if prev is not None:
            was = prev[2].error[mc.flagged[mc.flagged < prev[2].error.size]]
            stalled = was.size > 0 and worst > _STALL * float(np.max(was))
        if not todo or (stalled and fixed):
            stop = "they live in parts whose mesh the model file fixes: " + ", ".join(fixed)
            break
        if rounds >= _MAX_ROUNDS:
            stop = f"still flagged after {rounds} rounds of refinement"
            break
        prev = (d, result, mc)
        d = dataclasses.replace(
            d, components=tuple(_refine(c, todo[c.name]) if c.name in todo else c for c in d.components)
        )
    converged = mc.flagged.size == 0
    n = mc.error.size
    below = int(np.count_nonzero((result.frequencies_hz[:n] <= max_hz) & ~result.rigid[:n]))
    worst = float(np.max(mc.error, initial=0.0))
    if converged:
        message = (
            f"every mode up to {max_hz:g} Hz ({below} elastic) within {100 * tolerance:g} % "
            f"(largest estimated error {100 * worst:.2g} %) after {rounds} check{'s' if rounds != 1 else ''}"
        )
    else:
        message = (
            f"not converged: modes {', '.join(str(int(i)) for i in mc.flagged)} estimated above "
            f"{100 * tolerance:g} %: {stop}"
        )
    if mc.note:
        message += f"; {mc.note}: the estimate is one step and may understate"
    return MeshChoice(d, max_hz, mc, _elements(d), rounds, converged, message, fixed)


def meshed_for_own_range(drivetrain):
    """The model as every command works on it: with ``[model] max_hz``, meshed for that range
    (:func:`mesh_for_range`: each shaft's and CAD part's elements chosen so every mode below max_hz is
    within 1 %); without, as it is. A step the caller takes after loading: the model-file reader runs
    no analysis."""
    if drivetrain.max_hz is None:
        return drivetrain
    return mesh_for_range(drivetrain, drivetrain.max_hz).drivetrain
