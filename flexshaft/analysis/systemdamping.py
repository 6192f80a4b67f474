"""Damping that says what it is: each part's own, or the system's measured ratio.

Two ways of putting the test bench's measured 0.53 % into a model give very different responses:

- ``"parts"``: every flexible part carries 0.53 % on its own free-free modes (the multibody
  model's way: ``damping_ratio`` on a shaft, a flexible body's modal damping). A system mode
  then gets only the share of its strain energy the damped parts carry, times their ratio:
  Customer 1's first mode, which lives in the undamped coupling, ends far below 0.53 %.
- ``"system"``: every component's own damping removed and Rayleigh damping C = αJ + βK fitted
  so the first two elastic system modes carry the measured ratio (the study's matrix model, its
  eq. 41): ξ_i = α/(2ω_i) + βω_i/2.

:func:`system_damped` makes the second from the first; :data:`DAMPING_CHOICES` and
:data:`DAMPING_DESCRIPTIONS` name the choice a study or report makes (``"both"``: each, side by
side).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import ModelError
from ..linalg.damping import RAYLEIGH_BETA_MAX, rayleigh_coefficients
from ..model.assembly import assemble
from ..model.components import Coupling, Drivetrain, Gear, Rayleigh, Shaft
from ..system.threads import follows_policy
from ..validation import check_real
from .modal import modal_analysis

__all__ = [
    "DAMPING_CHOICES",
    "DAMPING_DESCRIPTIONS",
    "SYSTEM_DAMPING_RATIO",
    "system_damped",
    "undamped_parts",
    "system_rayleigh",
]

#: How damping enters a study's responses (see the module docstring).
DAMPING_CHOICES = ("parts", "system", "both")
#: One line per choice, for reports and every amplitude's caption.
DAMPING_DESCRIPTIONS = {
    "parts": "per-part damping: each flexible part's own damping_ratio on its own modes, dampers as given "
    "(the multibody model's way; system modes get only the damped parts' energy share)",
    "system": "system damping: every part's own damping removed, Rayleigh αJ + βK fitted so the first "
    "two elastic system modes carry the measured ratio (the study's matrix model, eq. 41)",
    "both": "per-part and system damping computed side by side",
}
#: The test bench's measured system damping ratio (half-power, mean of modes 1 and 2), a fraction.
SYSTEM_DAMPING_RATIO = 0.0053

# Two elastic frequencies closer than this (relative) are one for the Rayleigh fit: the isotropic
# lateral pairs of a 6-DOF model (equal to round-off, ~1e-12) would make the 2x2 fit singular.
_DISTINCT = 1e-6


def undamped_parts(drivetrain: Drivetrain) -> Drivetrain:
    """The drivetrain with every component's own damping removed, and no Rayleigh damping.

    Removed: a shaft's ``damping_ratio`` and ``damping`` (N·m·s/rad), a flexible body's modal
    damping (``reduce.damping``), a coupling's damper, a gear mesh's damper. Stiffness, inertia
    and meshes are kept as they are.
    """
    if not isinstance(drivetrain, Drivetrain):
        raise ModelError(
            "not a drivetrain", field="drivetrain", value=type(drivetrain).__name__, valid="a Drivetrain"
        )
    comps = []
    for c in drivetrain.components:
        if isinstance(c, Shaft):
            reduce = None if c.reduce is None else dataclasses.replace(c.reduce, damping=0.0)
            c = dataclasses.replace(c, damping_ratio=0.0, damping=0.0, reduce=reduce)
        elif isinstance(c, Coupling):
            c = dataclasses.replace(c, damping=0.0)
        elif isinstance(c, Gear) and c.mesh_damping:
            c = dataclasses.replace(c, mesh_damping=0.0)
        comps.append(c)
    return dataclasses.replace(drivetrain, components=tuple(comps), rayleigh=None)


def _elastic_frequencies(drivetrain: Drivetrain) -> np.ndarray:
    """The lowest distinct elastic natural frequencies (at most two), Hz, of an undamped drivetrain."""
    model = assemble(drivetrain)
    n = model.n_dof
    n_rigid = int(np.asarray(model.rigid_basis).reshape(model.n_dof, -1).shape[1])
    count = min(n, n_rigid + 4)  # two elastic modes, and room for a repeated (lateral) pair
    while True:
        r = modal_analysis(model, count, damped=False)
        f = r.frequencies_hz[~r.rigid]
        distinct = f[:1]
        for x in f[1:]:
            if x > distinct[-1] * (1 + _DISTINCT):
                distinct = np.append(distinct, x)
                break
        if distinct.size >= 2 or count >= n:
            return distinct
        count = min(n, 2 * count)


def system_rayleigh(
    drivetrain: Drivetrain, ratio: float = SYSTEM_DAMPING_RATIO
) -> tuple[Rayleigh, np.ndarray]:
    """The Rayleigh damping that gives the first two elastic modes ``ratio``, and those modes (Hz).

    The frequencies are those of the drivetrain without any of its own damping (the undamped
    natural frequencies, which Rayleigh damping leaves unchanged). With one elastic mode only
    (a two-inertia chain), the damping is stiffness-proportional, β = 2ξ/ω₁, α = 0: ξ at that
    mode, growing ∝ ω above it.

    Parameters
    ----------
    drivetrain : Drivetrain
    ratio : float
        Damping ratio of the first two elastic modes, a fraction in [0, 1) (0.0053 for 0.53 %).

    Returns
    -------
    rayleigh : Rayleigh
        α (1/s) and β (s).
    frequencies_hz : ndarray, shape (1,) or (2,)
        The elastic frequencies it was fitted at, Hz.
    """
    ratio = check_real(ratio, "system_damping_ratio", "", lo=0.0, hi=1.0, hi_open=True)
    f = _elastic_frequencies(undamped_parts(drivetrain))
    if f.size == 0:
        raise ModelError(
            "the drivetrain has no elastic mode to put system damping on",
            field="system_damping_ratio",
            value=ratio,
            valid="a drivetrain with at least one flexible component between two inertias",
        )
    if f.size == 1:
        omega = 2.0 * np.pi * float(f[0])
        beta = 2.0 * ratio / omega
        if beta > RAYLEIGH_BETA_MAX:
            top = RAYLEIGH_BETA_MAX * omega / 2.0
            raise ModelError(
                f"needs a stiffness-proportional β of {beta:g} s at {float(f[0]):g} Hz",
                field="system_damping_ratio",
                value=ratio,
                valid=f"a ratio up to {top:g} (β <= {RAYLEIGH_BETA_MAX:g} s)",
            )
        return Rayleigh(alpha=0.0, beta=beta), f
    alpha, beta = rayleigh_coefficients(float(f[0]), ratio, float(f[1]), ratio)
    return Rayleigh(alpha=alpha, beta=beta), f


@follows_policy
def system_damped(drivetrain: Drivetrain, ratio: float = SYSTEM_DAMPING_RATIO) -> Drivetrain:
    """The drivetrain with system damping instead of each part's own.

    Every component's own damping is removed (:func:`undamped_parts`) and the model's Rayleigh
    damping C = αJ + βK set so its first two elastic modes carry ``ratio``
    (:func:`system_rayleigh`) - the study's matrix model (eq. 41), fitted to the measured system
    damping. Modes between the two get a little less, modes above more (ξ ≈ βω/2); the rigid
    mode none (Rayleigh damps deformation only: no drag α·J·ω on a spinning free chain, see
    :func:`~flexshaft.linalg.damping.modal_damping_block`). A drivetrain with one elastic mode gets
    stiffness-proportional damping that puts ``ratio`` on it. In a 6-DOF model the two modes are
    the lowest two of any family (torsion or lateral), a repeated pair counted once.

    Parameters
    ----------
    drivetrain : Drivetrain
        Meshes, stiffness and inertia are kept as they are.
    ratio : float
        Damping ratio, a fraction in [0, 1); default the bench's measured 0.53 %.

    Returns
    -------
    Drivetrain
    """
    rayleigh, _ = system_rayleigh(drivetrain, ratio)
    return dataclasses.replace(undamped_parts(drivetrain), rayleigh=rayleigh)
