"""Modal analysis of an assembled drivetrain: undamped and damped modes.

The result reports what an engineer reads off a mode: its frequency, whether
it is the rigid-body mode, its damping, its shape at the named stations, and
which component carries its strain energy (the "dominant" component: where
the mode's flexibility lives, and what a change of stiffness would move).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..linalg.eigen import DENSE_MAX_DOF, lowest_modes
from ..model.assembly import AssembledModel, assemble
from ..model.components import Drivetrain
from ..validation import check_choice, check_int
from .damped import DampedModes, damped_modes

__all__ = ["ModalResult", "modal_analysis", "default_count", "NORMALISATIONS"]

NORMALISATIONS = ("inertia", "stiffness", "max")


@dataclass(frozen=True)
class ModalResult:
    """Modes of a drivetrain, lowest first.

    Attributes
    ----------
    model : AssembledModel
        The matrices and stations the modes belong to.
    omega : ndarray, shape (m,)
        Undamped natural circular frequencies, rad/s; exactly 0 for rigid modes.
    shapes : ndarray, shape (n_dof, m)
        Mode shapes (rotation θx per node, rad), inertia-normalised: ΦᵀMΦ = I.
    rigid : ndarray of bool, shape (m,)
        Rigid-body modes.
    damped : DampedModes or None
        Damped modes paired one-to-one with these, when the model has damping.
    method : str
        The eigensolver path used.
    """

    model: AssembledModel
    omega: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    damped: DampedModes | None
    method: str

    @property
    def count(self) -> int:
        """Number of modes."""
        return self.omega.size

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies, Hz."""
        return self.omega / (2.0 * np.pi)

    @property
    def damping_ratios(self) -> np.ndarray:
        """Damping ratio per mode (fractions); zeros for an undamped model."""
        return np.zeros(self.count) if self.damped is None else self.damped.damping_ratios

    def normalized(self, kind: str = "inertia") -> np.ndarray:
        """Mode shapes under a normalisation, shape (n_dof, m).

        Parameters
        ----------
        kind : {"inertia", "stiffness", "max"}
            ``"inertia"``: ΦᵀMΦ = I, ΦᵀKΦ = diag(ω²) (kg^-1/2·m^-1).
            ``"stiffness"``: ΦᵀKΦ = I, ΦᵀMΦ = diag(1/ω²); rigid-body modes,
            which have no strain energy, stay inertia-normalised.
            ``"max"``: the largest |θ| of each mode is 1, the largest entry
            positive.
        """
        check_choice(kind, "normalization", NORMALISATIONS)
        if kind == "inertia":
            return self.shapes.copy()
        if kind == "stiffness":
            return self.shapes / np.where(self.rigid, 1.0, self.omega)
        # Scaled by the largest node rotation (a flexible body's modal coordinates are not rotations).
        return _max_normalised(self.shapes, rows=self.model.n_nodes)

    def station_shapes(self) -> np.ndarray:
        """Mode shapes at the stations, max-normalised over the stations, (n_st, m)."""
        return _max_normalised(self.shapes[self.model.station_nodes])

    def strain_energy_fractions(self) -> np.ndarray:
        """Share of each mode's strain energy per component, shape (m, n_comp).

        Rows sum to 1 for elastic modes and are zero for rigid-body modes.
        """
        mdl = self.model
        e = mdl.element_nodes
        d = self.shapes[e + 1] - self.shapes[e]
        per_el = mdl.element_stiffness[:, None] * d**2
        per_body, owner = self._body_energy("K")
        return _fractions(
            np.vstack([per_el, per_body]),
            np.concatenate([mdl.element_component, owner]),
            len(mdl.drivetrain.components),
        )

    def _body_energy(self, which: str) -> tuple[np.ndarray, np.ndarray]:
        """Twice the strain ("K") or kinetic ("M") energy of each flexible body per mode, (n_bodies, m)."""
        rows = []
        for b in self.model.bodies:
            v = self.shapes[b.dofs]
            rows.append(np.einsum("im,im->m", v, getattr(b.body, which) @ v))
        owner = np.array([b.component for b in self.model.bodies], dtype=int)
        return np.array(rows).reshape(len(rows), self.count), owner

    def kinetic_energy_fractions(self) -> np.ndarray:
        """Share of each mode's kinetic energy per component, shape (m, n_comp)."""
        mdl = self.model
        e = mdl.element_nodes
        a, b = self.shapes[e], self.shapes[e + 1]
        j = mdl.element_inertia[:, None]
        consistent = j * (a * a + a * b + b * b) / 3.0
        lumped = j * (a * a + b * b) / 2.0
        per_el = np.where(mdl.element_lumped[:, None], lumped, consistent)
        n_comp = len(mdl.drivetrain.components)
        per_pt = mdl.point_inertia[:, None] * self.shapes[mdl.point_nodes] ** 2
        per_body, owner = self._body_energy("M")
        return _fractions(
            np.vstack([per_el, per_pt, per_body]),
            np.concatenate([mdl.element_component, mdl.point_component, owner]),
            n_comp,
        )

    def component_torques(self) -> np.ndarray:
        """Peak elastic torque in each component per mode, N·m per rad, shape (m, n_comp).

        Each mode is scaled so that its largest station rotation is 1 rad (as in
        :meth:`station_shapes`); the entry is the largest |k·Δθ| over the
        component's elements - the dynamic torque the section carries when the
        mode swings at that amplitude. Multiply by a real amplitude in rad.
        Rigid components carry no elastic torque (0); rigid-body modes are 0.
        The study's case: a friction coupling slips in the mode where the
        section it sits in carries the most torque.
        """
        mdl = self.model
        peak = np.max(np.abs(self.shapes[mdl.station_nodes]), axis=0)
        V = self.shapes / np.where(peak > 0, peak, 1.0)
        e = mdl.element_nodes
        t = np.abs(mdl.element_stiffness[:, None] * (V[e + 1] - V[e]))
        out = np.zeros((len(mdl.drivetrain.components), self.count))
        np.maximum.at(out, mdl.element_component, t)
        for b in mdl.bodies:
            # The body's own mesh, recovered from its reduced coordinates.
            theta = b.recover(V)
            out[b.component] = np.max(np.abs(b.element_stiffness[:, None] * np.diff(theta, axis=0)), axis=0)
        out[:, self.rigid] = 0.0
        return out.T

    def dominant_components(self) -> list[str | None]:
        """Per mode, the component with the largest strain-energy share (None if rigid)."""
        se = self.strain_energy_fractions()
        names = self.model.component_names
        return [None if r else names[int(np.argmax(row))] for r, row in zip(self.rigid, se)]


def _max_normalised(V: np.ndarray, rows: int | None = None) -> np.ndarray:
    """Each column over its largest-magnitude entry among the first ``rows`` rows (all by default)."""
    W = V if rows is None else V[:rows]
    idx = np.argmax(np.abs(W), axis=0)
    peak = W[idx, np.arange(V.shape[1])]
    return V / np.where(peak == 0, 1.0, peak)


def _fractions(per_item: np.ndarray, owner: np.ndarray, n_comp: int) -> np.ndarray:
    sums = np.zeros((n_comp, per_item.shape[1]))
    np.add.at(sums, owner, per_item)
    total = sums.sum(axis=0)
    return (sums / np.where(total > 0, total, 1.0)).T


def default_count(n_dof: int) -> int:
    """All modes for a small model, 10 otherwise."""
    return n_dof if n_dof <= DENSE_MAX_DOF else 10


def modal_analysis(
    model,
    count: int | None = None,
    *,
    inertia_model: str | None = None,
    damped: bool = True,
    method: str = "auto",
) -> ModalResult:
    """Undamped (and, where the model has damping, damped) torsional modes of a drivetrain.

    A model with ``dofs = "full"`` gets its torsional modes here too: in a
    straight round shaft torsion does not couple to bending or axial motion,
    so they equal the full model's torsion modes (tested). All six DOFs:
    :func:`flexshaft.fullchain.full_modes`.

    Parameters
    ----------
    model : Drivetrain or AssembledModel
        The drivetrain; a Drivetrain is assembled first.
    count : int, optional
        How many of the lowest modes, rigid-body mode included. Default: all
        for models up to 600 DOFs, 10 otherwise.
    inertia_model : {"consistent", "lumped"}, optional
        Overrides the drivetrain's setting (only with a Drivetrain).
    damped : bool
        Also compute the damped modes when the model has damping.
    method : {"auto", "dense", "lanczos"}
        Eigensolver path (see :func:`flexshaft.eigen.lowest_modes`).

    Returns
    -------
    ModalResult
    """
    if isinstance(model, Drivetrain):
        model = assemble(model, inertia_model)
    elif not isinstance(model, AssembledModel):
        raise ModelError(
            "not a drivetrain",
            field="model",
            value=type(model).__name__,
            valid="a Drivetrain or an AssembledModel",
        )
    elif inertia_model is not None and inertia_model != model.inertia_model:
        model = assemble(model.drivetrain, inertia_model)
    n = model.n_dof
    m = default_count(n) if count is None else check_int(count, "count", lo=1)
    check_choice(method, "method", ("auto", "dense", "lanczos"))
    # A serial chain with no ground has exactly one rigid-body mode: all
    # stations turning together (flexible bodies' modal coordinates at rest).
    trial = None
    if model.bodies:
        # A ramp over the nodes; modal coordinates are not positions along the chain.
        trial = np.zeros((n, 1))
        trial[: model.n_nodes, 0] = np.linspace(-1.0, 1.0, model.n_nodes)
    sol = lowest_modes(
        model.K,
        model.M,
        m,
        rigid_basis=model.rigid_basis,
        method=method,
        bandwidth=model.bandwidth,
        trial=trial,
    )
    omega = np.sqrt(sol.eigenvalues)
    dm = None
    if damped and model.C is not None:
        dm = damped_modes(model.K, model.M, model.C, sol.eigenvalues, sol.vectors, sol.rigid)
    return ModalResult(
        model=model, omega=omega, shapes=sol.vectors, rigid=sol.rigid, damped=dm, method=sol.method
    )
