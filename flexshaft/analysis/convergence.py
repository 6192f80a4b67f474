"""Is the mesh fine enough? A per-mode estimate of the distance from the mesh-converged frequency.

A shaft given by numbers is one element unless told otherwise (the study's matrix models), and
its higher modes are then far from the shaft's own. The estimate re-solves the drivetrain with
every shaft at twice its element count (rigid inertias and couplings are exact and stay) and
uses Richardson extrapolation: the 2-node torsion and Timoshenko elements converge as h², so
with f_h and f_{h/2}

    f_∞ ≈ f_{h/2} + (f_{h/2} − f_h)/3,   error of f_h ≈ (4/3)·|f_h − f_{h/2}| / f_∞.

It is an estimate of the discretisation error in the asymptotic range; a mode whose shape the
coarse mesh cannot represent at all (fewer than ~2 elements per half-wave in a part) is outside
that range and its estimate is only a lower bound, so it is flagged as well.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..model.assembly import assemble
from ..threads import follows_policy
from .modal import ModalResult, modal_analysis

__all__ = ["MeshConvergence", "mesh_convergence", "DEFAULT_MESH_TOLERANCE"]

DEFAULT_MESH_TOLERANCE = 0.01
"""Relative frequency error above which a mode is flagged (1 %)."""


@dataclass(frozen=True)
class MeshConvergence:
    """Per-mode mesh-convergence estimate of a modal result.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (m,)
        The modes as computed, Hz.
    refined_hz : ndarray, shape (m,)
        The same modes with every shaft at twice its element count, Hz.
    extrapolated_hz : ndarray, shape (m,)
        Richardson's estimate of the mesh-converged frequency, Hz.
    error : ndarray, shape (m,)
        Estimated relative error of ``frequencies_hz`` (0 for rigid-body modes).
    tolerance : float
        The error above which a mode is flagged.
    """

    frequencies_hz: np.ndarray
    refined_hz: np.ndarray
    extrapolated_hz: np.ndarray
    error: np.ndarray
    tolerance: float

    @property
    def flagged(self) -> np.ndarray:
        """Indices of the modes whose estimated error exceeds ``tolerance``."""
        return np.flatnonzero(self.error > self.tolerance)


def _refined(model):
    """The drivetrain with every shaft at twice its element count in ``model``."""
    d = model.drivetrain
    counts = np.bincount(model.element_component, minlength=len(d.components))
    comps = []
    for i, c in enumerate(d.components):
        if c.type == "shaft":
            c = dataclasses.replace(c, elements=2 * max(int(counts[i]), 1))
            if c.max_element_length is not None:
                c = dataclasses.replace(c, max_element_length=c.max_element_length / 2)
        comps.append(c)
    return dataclasses.replace(d, components=tuple(comps))


@follows_policy
def mesh_convergence(result: ModalResult, tolerance: float = DEFAULT_MESH_TOLERANCE) -> MeshConvergence:
    """Estimate how far each mode of ``result`` is from mesh convergence.

    Parameters
    ----------
    result : ModalResult
        The modes to check; their drivetrain is re-meshed and solved once more.
    tolerance : float
        Relative error above which a mode is flagged (1 % by default).
    """
    model = result.model
    # Undamped frequencies are compared: the parts' modal damping (a dense eigen-solve each) is not built.
    fine = assemble(_refined(model), inertia_model=model.inertia_model, damping=False)
    refined = modal_analysis(fine, result.count, damped=False)
    f_h = result.frequencies_hz
    # Paired by index: halving the elements nests the coarse finite-element space in the fine one, so
    # by the min-max principle the fine k-th eigenvalue lies between the coarse k-th and the exact
    # k-th (consistent inertia). A coarse mesh that misses a mode altogether (a short part in too few
    # elements) therefore shows as a large error from that mode on: its k-th mode is not the
    # shaft's k-th - which is what the user must be told.
    f_2 = refined.frequencies_hz[: f_h.size]
    ext = f_2 + (f_2 - f_h) / 3.0
    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.where(result.rigid | (ext <= 0), 0.0, 4.0 / 3.0 * np.abs(f_h - f_2) / np.abs(ext))
    return MeshConvergence(f_h.copy(), f_2, ext, err, float(tolerance))
