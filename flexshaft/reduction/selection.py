"""Mode selection of a flexible body: its orthonormalised free-free modes, some kept.

A multibody tool enables or disables a flexible body's modes; :func:`select_modes`
gives the body in those coordinates (K = diag(ω²), M = I, C = diag(2ξω)) with
the shapes on every DOF of the part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..system.threads import follows_policy
from .flexiblebody import FlexibleBody

__all__ = ["ModalBody", "select_modes"]

# relative size; Rayleigh's α gives α there, far above it.
_RIGID_DAMPING_ROUNDOFF = 1e-9


@dataclass(frozen=True)
class ModalBody:
    """A flexible body in its orthonormalised coordinates, some modes kept (SI).

    The physical DOFs of the part are u = ``shapes`` · η with η the modal
    coordinates; the equations of motion are M η̈ + C η̇ + K η = shapesᵀ f.

    Attributes
    ----------
    name : str
        The part's name.
    dofs : {"torsion", "full"}
        DOFs per node of the part model: θx, or (ux, uy, uz, θx, θy, θz).
    modes : ndarray of int, shape (k,)
        The kept modes, as indices into ``FlexibleBody.free_hz``, ascending.
    frequencies_hz : ndarray, shape (k,)
        Their frequencies, Hz; rigid-body modes 0.
    damping_ratios : ndarray, shape (k,)
        Their damping ratios (fractions); rigid-body modes 0.
    shapes : ndarray, shape (n_part_dofs, k)
        The modes on every DOF of the part model (``T @ free_modes[:, modes]``),
        node-major. Mass-normalised, shapesᵀ M shapes = I with M the part
        model's mass: a modal coordinate is in kg^½·m (kinetic energy ½ η̇ᵀη̇),
        so the shapes are in kg^-½ on translations and rad·kg^-½·m⁻¹ on
        rotations.
    boundary_nodes : ndarray of int
        Nodes of the part model that were the Craig–Bampton boundary.
    boundary_x : ndarray
        Their axial positions, m.
    K : ndarray, shape (k, k)
        Modal stiffness diag(ω²), 1/s² (the modal masses being 1).
    M : ndarray, shape (k, k)
        Modal mass, the identity (dimensionless in these coordinates).
    C : ndarray, shape (k, k)
        Modal damping diag(2 ξ ω), rad/s. On rigid-body modes it is 0, or
        Rayleigh's α (1/s) when the body was damped with α > 0.
    """

    name: str
    dofs: str
    modes: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray
    boundary_nodes: np.ndarray
    boundary_x: np.ndarray
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray

    @property
    def rigid(self) -> np.ndarray:
        """Which kept modes are rigid-body modes (frequency exactly 0)."""
        return self.frequencies_hz == 0.0

    @property
    def boundary_shapes(self) -> np.ndarray:
        """Rows of ``shapes`` at the boundary DOFs, node-major, shape (nb, k)."""
        d = 6 if self.dofs == "full" else 1
        rows = (self.boundary_nodes[:, None] * d + np.arange(d)).ravel()
        return self.shapes[rows]


def _modal_damping_diagonal(body: FlexibleBody) -> np.ndarray:
    """diag(2 ξ ω) on the elastic modes; on the rigid-body modes what C really does there, rad/s."""
    rigid = body.free_hz == 0.0
    c = 2.0 * body.damping_ratios * (2 * np.pi * body.free_hz)
    # Rayleigh's αM damps rigid motion too (α there): keep it rather than the reported ratio 0.
    V = body.free_modes
    projected = np.einsum("ij,ij->j", V, body.C @ V)
    scale = float(np.max(np.abs(projected), initial=0.0))
    on_rigid = np.where(np.abs(projected) <= _RIGID_DAMPING_ROUNDOFF * scale, 0.0, projected)
    return np.where(rigid, on_rigid, c)


def _kept_indices(keep, n: int) -> np.ndarray:
    """``keep`` (indices or a boolean mask over n modes) as sorted unique indices."""
    valid = f"indices from 0 to {n - 1} (each once), or {n} booleans"
    arr = np.asarray(keep)
    if arr.ndim != 1:
        raise ModelError("must be one-dimensional", field="keep", value=keep, valid=valid, has_value=True)
    if arr.dtype == bool:
        if arr.size != n:
            raise ModelError(f"has {arr.size} flags for {n} modes", field="keep", valid=valid)
        idx = np.flatnonzero(arr)
    elif arr.size == 0 or np.issubdtype(arr.dtype, np.integer):
        idx = arr.astype(int)
        for k, i in enumerate(idx):
            if not 0 <= i < n:
                raise ModelError("no such mode", field=f"keep[{k}]", value=int(i), valid=valid)
        if np.unique(idx).size != idx.size:
            raise ModelError("names a mode twice", field="keep", value=idx.tolist(), valid=valid)
    else:
        raise ModelError("not indices or a mask", field="keep", value=keep, valid=valid, has_value=True)
    if idx.size == 0:
        raise ModelError("keeps no mode", field="keep", valid=valid)
    return np.sort(idx)


def _check_rigid_kept(idx: np.ndarray, rigid: np.ndarray, drop_rigid: bool) -> None:
    """All rigid-body modes kept, or (with drop_rigid) none of them: never a part."""
    r = np.flatnonzero(rigid)
    kept = np.isin(r, idx)
    names = ", ".join(str(i) for i in r)
    if drop_rigid and kept.any():
        raise ModelError(
            f"names rigid-body mode(s) {', '.join(str(i) for i in r[kept])} although drop_rigid is true",
            field="keep",
            valid=f"no rigid-body mode ({names}) with drop_rigid = true",
        )
    if not drop_rigid and not kept.all():
        raise ModelError(
            f"leaves out rigid-body mode(s) {', '.join(str(i) for i in r[~kept])}",
            field="keep",
            valid=f"every rigid-body mode ({names}), or none of them with drop_rigid = true",
        )


@follows_policy
def select_modes(body: FlexibleBody, keep, *, drop_rigid: bool = False) -> ModalBody:
    """The body in its orthonormalised coordinates with only the kept free-free modes.

    This is mode enable/disable for a multibody tool: the body's free-free
    modes (``body.free_hz``), each a coordinate of its own, the unwanted ones
    left out.

    Parameters
    ----------
    body : FlexibleBody
        From :func:`craig_bampton`.
    keep : sequence of int or array_like of bool
        Indices into ``body.free_hz`` (0 … nb + nm − 1, each once, any order;
        they are sorted), or one flag per mode.
    drop_rigid : bool
        The rigid-body modes share frequency 0, so which combination of rigid
        motions each one is, is arbitrary: they are kept or dropped as a whole.
        ``False`` (default): ``keep`` must name every rigid-body mode, so that
        the body can still translate and turn as a whole. ``True``: ``keep``
        must name none of them and the body keeps only elastic modes (for a
        tool that carries the rigid motion itself).

    Returns
    -------
    ModalBody

    Raises
    ------
    ModelError
        On an index out of range or repeated, a mask of the wrong length, an
        empty selection, or rigid-body modes kept in part, left out without
        ``drop_rigid`` or named with it.
    """
    if not isinstance(body, FlexibleBody):
        raise ModelError(
            "not a flexible body",
            field="body",
            value=type(body).__name__,
            valid="a FlexibleBody from craig_bampton",
        )
    rigid = body.free_hz == 0.0
    idx = _kept_indices(keep, body.free_hz.size)
    _check_rigid_kept(idx, rigid, bool(drop_rigid))
    V = body.free_modes[:, idx]
    omega = 2 * np.pi * body.free_hz[idx]
    return ModalBody(
        name=body.name,
        dofs=body.dofs,
        modes=idx,
        frequencies_hz=body.free_hz[idx].copy(),
        damping_ratios=body.damping_ratios[idx].copy(),
        shapes=body.T @ V,
        boundary_nodes=body.boundary_nodes.copy(),
        boundary_x=body.boundary_x.copy(),
        K=np.diag(omega**2),
        M=np.eye(idx.size),
        C=np.diag(_modal_damping_diagonal(body)[idx]),
    )
