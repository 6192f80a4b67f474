"""Modal analysis of an assembled drivetrain: undamped and damped modes, one result for every model.

The result reports what an engineer reads off a mode: its frequency, whether
it is a rigid-body mode, its damping, its shape at every node and at the named
stations, which component carries its strain energy (the "dominant"
component: where the mode's flexibility lives, and what a change of
stiffness would move), which DOF family it lives in (axial, lateral,
torsion) and the torque each component carries. Every later analysis reads
this one :class:`ModalResult`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..linalg.eigen import DENSE_MAX_DOF, ROW_BLOCK, lowest_modes, row_block, row_blocks, solver_failures
from ..model.assembly import FAMILIES, AssembledModel, assemble
from ..model.components import Drivetrain
from ..model.part import assemble_part
from ..parts.model import PartModel
from ..parts.solidpart import RIGID as RIGID_SOLID
from ..parts.solidpart import SOLVERS, SolidPartModel, free_modes
from ..reduction.solidbasis import result_settings
from ..system.threads import follows_policy
from ..validation import check_choice, check_int
from .damped import DampedModes, damped_modes

__all__ = ["ModalResult", "modal_analysis", "part_modes", "default_count", "response_modes", "NORMALISATIONS"]
__all__ += ["modes_up_to", "listing_modes", "DEFAULT_LISTED"]

NORMALISATIONS = ("inertia", "stiffness", "max")
#: Modes of a full (6-DOF) model computed by default.
FULL_DEFAULT_COUNT = 16
#: Modes a listing shows when no frequency range (max_hz) and no count is given: the lowest 20,
#: more than any drivetrain study reads, never the hundreds a fine mesh has.
DEFAULT_LISTED = 20


@dataclass(frozen=True)
class ModalResult:
    """Modes of an assembled model, lowest first: torsion or 6-DOF, flexible bodies included.

    Attributes
    ----------
    model : AssembledModel
        The matrices, nodes and stations the modes belong to.
    omega : ndarray, shape (m,)
        Undamped natural circular frequencies, rad/s; exactly 0 for rigid modes.
    shapes : ndarray, shape (n_dof, m)
        Mode shapes on the model's coordinates, mass-normalised: ΦᵀMΦ = I
        (rad·kg^-½·m^-1 on rotations, kg^-½ on translations; modal
        coordinates of flexible bodies as they come). :attr:`node_shapes`
        gives them on every node DOF.
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

    @cached_property
    def node_shapes(self) -> np.ndarray:
        """The shapes on every DOF of every node (node-major), shape (d·n_nodes, m).

        Interior nodes of flexible bodies are recovered through their bodies'
        recovery matrices.
        """
        if _is_identity(self.model.T):
            # Coordinates are the node DOFs (a torsion chain): the shapes themselves, not a copy.
            u = self.shapes.view()
        else:
            u = np.asarray(self.model.T @ self.shapes)
        u.setflags(write=False)  # computed once and shared: read-only
        return u

    def _dof_view(self, dof: str) -> np.ndarray:
        """One DOF of every mode at every node, shape (n_nodes, m): a read-only view of node_shapes."""
        return self.node_shapes[self.model.node_dof(0, dof) :: self.model.dofs_per_node]

    def dof_shapes(self, dof: str = "θx") -> np.ndarray:
        """One DOF (``"θx"``, ``"uy"``, ...) of every mode at every node, shape (n_nodes, m)."""
        return self._dof_view(dof).copy()

    def normalized(self, kind: str = "inertia") -> np.ndarray:
        """Mode shapes on the coordinates under a normalisation, shape (n_dof, m).

        Parameters
        ----------
        kind : {"inertia", "stiffness", "max"}
            ``"inertia"``: ΦᵀMΦ = I, ΦᵀKΦ = diag(ω²) (kg^-1/2·m^-1).
            ``"stiffness"``: ΦᵀKΦ = I, ΦᵀMΦ = diag(1/ω²); rigid-body modes,
            which have no strain energy, stay inertia-normalised.
            ``"max"``: the largest ``|value|`` of each mode on a physical
            coordinate is 1, the largest entry positive.
        """
        check_choice(kind, "normalization", NORMALISATIONS)
        if kind == "inertia":
            return self.shapes.copy()
        if kind == "stiffness":
            return self.shapes / np.where(self.rigid, 1.0, self.omega)
        # Scaled by the largest physical entry (a flexible body's modal coordinates are not rotations).
        return _max_normalised(self.shapes, rows=~self.model.modal)

    def station_shapes(self, dof: str = "θx") -> np.ndarray:
        """One DOF (θx by default) of the modes at the stations, max-normalised over them, (n_st, m)."""
        rows = self.model.node_dof(self.model.station_nodes, dof)
        return _max_normalised(self.node_shapes[rows])

    def _owner_fractions(self, entries) -> np.ndarray:
        """Each owner's share of vᵀAv per mode, (m, n_owners); zero rows where vᵀAv is 0."""
        per = entries.quadratic_by_owner(self.shapes, self.model.n_owners)
        total = per.sum(axis=0)
        return (per / np.where(total > 0, total, 1.0)).T

    @cached_property
    def _strain_shares(self) -> np.ndarray:
        """Strain-energy shares of components, then bearings, (m, n_owners); rigid-body modes 0."""
        f = self._owner_fractions(self.model.stiffness_entries)
        f[self.rigid] = 0.0
        f.setflags(write=False)
        return f

    def strain_energy_fractions(self) -> np.ndarray:
        """Share of each mode's strain energy per component, shape (m, n_comp).

        Rows sum to 1 for elastic modes (less what bearings carry, see
        :meth:`bearing_energy_fractions`) and are zero for rigid-body modes.
        """
        return self._strain_shares[:, : len(self.model.drivetrain.components)].copy()

    def bearing_energy_fractions(self) -> np.ndarray:
        """Share of each mode's strain energy in each bearing spring, shape (m, n_bearings)."""
        return self._strain_shares[:, len(self.model.drivetrain.components) :].copy()

    def kinetic_energy_fractions(self) -> np.ndarray:
        """Share of each mode's kinetic energy per component, shape (m, n_comp)."""
        return self._owner_fractions(self.model.mass_entries)[:, : len(self.model.drivetrain.components)]

    def damping_contributions(self) -> np.ndarray:
        """Each component's part of each mode's damping ratio, shape (m, n_comp) (fractions).

        First order in the damping: ξ_i ≈ φᵢᵀCφᵢ / (2ωᵢ) for a mass-normalised mode, split by who
        put each entry of C there - a shaft's modal damping or damper, a coupling's damper, a flexible
        body's damping - and Rayleigh's αM + βK split like the mass and stiffness it multiplies.
        Rows add up to the mode's ratio to first order (light damping); rigid-body modes are 0.
        Why 0.53 % on the parts gives far less on a system mode: modal damping ξ_p on a part's own
        mode of frequency ω_p contributes about ξ_p·(ω/ω_p)·(the part's strain-energy share) to a
        system mode of frequency ω - a mode living in an undamped coupling gets almost none.
        """
        mdl = self.model
        n_comp = len(mdl.drivetrain.components)
        c = mdl.damping_entries.quadratic_by_owner(self.shapes, mdl.n_owners)
        ray = mdl.drivetrain.rayleigh
        if ray is not None and (ray.alpha or ray.beta):
            c = c + ray.alpha * mdl.mass_entries.quadratic_by_owner(self.shapes, mdl.n_owners)
            c = c + ray.beta * mdl.stiffness_entries.quadratic_by_owner(self.shapes, mdl.n_owners)
        out = c / (2.0 * np.where(self.omega > 0, self.omega, 1.0))
        out[:, self.rigid] = 0.0
        return out.T[:, :n_comp]

    @cached_property
    def _family_energy(self) -> dict[str, np.ndarray]:
        """Kinetic energy per DOF family of each mode's recovered shape (see :meth:`family_energy`)."""
        u = self.node_shapes
        d = self.model.dofs_per_node
        M_nodes = sp.csr_matrix(self.model.M_nodes)
        # u_r·(M_nodes u)_r summed per node DOF (ux … θz) over blocks of whole nodes: the
        # temporaries are a block's rows, not (d·n_nodes, m) products.
        per_dof = np.zeros((d, u.shape[1]))
        for rows in row_blocks(u.shape[0], ROW_BLOCK - ROW_BLOCK % d):
            block = u[rows] * (row_block(M_nodes, rows) @ u)
            per_dof += block.reshape(-1, d, u.shape[1]).sum(axis=0)
        out = {}
        for fam, members in FAMILIES.items():
            kinds = [k for k, name in enumerate(self.model.dof_names) if name in members]
            if kinds:
                out[fam] = per_dof[kinds].sum(axis=0)
        return out

    def family_energy(self) -> dict[str, np.ndarray]:
        """Each mode's kinetic energy share per DOF family (axial, lateral, torsion), each shape (m,).

        The recovered shape u's kinetic energy uᵀ M_nodes u split by the family
        of the node DOF (row by row, u_r·(M_nodes u)_r; a consistent mass
        couples uy and θz, so a share is a row's, not a positive-definite
        part). The reduced coordinates of a flexible body mix families, the
        recovered shape does not; since M = Tᵀ M_nodes T the shares of a
        mass-normalised mode add up to 1. A torsion model's modes are all
        torsion.
        """
        return {fam: e.copy() for fam, e in self._family_energy.items()}

    @property
    def kinds(self) -> tuple[str, ...]:
        """'axial', 'lateral' or 'torsion' per mode: the family with the most kinetic energy."""
        energy = self._family_energy
        names = list(energy)
        e = np.vstack([energy[n] for n in names])
        return tuple(names[i] for i in np.argmax(e, axis=0))

    def component_torques(self) -> np.ndarray:
        """Peak elastic torque in each component per mode, N·m per rad, shape (m, n_comp).

        Each mode is scaled so that its largest station rotation θx is 1 rad
        (as in :meth:`station_shapes`); the entry is the largest ``|k·Δθx|`` over
        the component's torsion elements (a flexible body's own mesh,
        recovered from its coordinates) - the dynamic torque the section
        carries when the mode swings at that amplitude. Multiply by a real
        amplitude in rad. Rigid components carry no elastic torque (0);
        rigid-body modes are 0. The study's case: a friction coupling slips in
        the mode where the section it sits in carries the most torque.
        """
        mdl = self.model
        theta = self._dof_view("θx")
        peak = np.max(np.abs(theta[mdl.station_nodes]), axis=0)
        scale = 1.0 / np.where(peak > 0, peak, 1.0)
        out = np.zeros((len(mdl.drivetrain.components), self.count))
        # Over blocks of elements: the temporaries are a block's elements, not (n_el, m) arrays.
        for els in row_blocks(mdl.element_nodes.size):
            e = mdl.element_nodes[els]
            # k·(n·θ_right − θ_left): n is 1 but across a gear mesh (its torque in the driving frame).
            t = mdl.element_ratio[els, None] * theta[e + 1]
            t -= theta[e]
            t *= mdl.element_stiffness[els, None] * scale
            np.maximum.at(out, mdl.element_component[els], np.abs(t, out=t))
        out[:, self.rigid] = 0.0
        return out.T

    def listed(self, max_hz: float | None = None, count: int | None = None) -> range | list[int]:
        """The modes a listing shows: those up to ``max_hz`` (Hz; the model's ``[model] max_hz`` when
        None), else the lowest ``count`` (the modes asked for), else the lowest :data:`DEFAULT_LISTED` -
        never all of a fine mesh's hundreds unasked."""
        if max_hz is None:
            max_hz = getattr(self.model.drivetrain, "max_hz", None)
        n = self.count if count is None else min(int(count), self.count)
        if max_hz is not None:
            return [i for i in range(n) if self.frequencies_hz[i] <= max_hz]
        return range(n if count is not None else min(n, DEFAULT_LISTED))

    def to_dict(self, *, max_hz: float | None = None, mesh=None, count: int | None = None) -> dict:
        """The ``flexshaft modes --json`` document (:func:`~flexshaft.analysis.modaldocument.modes_document`:
        SI units, stated in it); ``max_hz``, ``count`` as for :meth:`listed`; ``mesh``: a
        :class:`~flexshaft.analysis.convergence.MeshConvergence` adds each mode's mesh error."""
        from .modaldocument import modes_document

        return modes_document(self, max_hz=max_hz, mesh=mesh, count=count)

    def table(self, *, max_hz: float | None = None, mesh=None, count: int | None = None) -> str:
        """The ``flexshaft modes`` table (:func:`~flexshaft.analysis.modaldocument.modes_table`);
        arguments as for :meth:`to_dict`."""
        from .modaldocument import modes_table

        return modes_table(self, max_hz=max_hz, mesh=mesh, count=count)

    def plot(self, kind: str = "shapes", **options):
        """A matplotlib Figure of the modes (never shown; ``fig.savefig("modes.png")``).

        Parameters
        ----------
        kind : {"shapes", "strain", "kinetic", "torque"}
            Mode shapes against axial position with the components shaded
            (``modes=[...]``, ``dof="θx"`` as options); each mode's strain or
            kinetic energy by component (stacked bars); the peak torque per
            component (N·m per rad of peak station rotation).
        """
        from ..views import plots

        check_choice(kind, "kind", ("shapes", "strain", "kinetic", "torque"))
        if kind == "shapes":
            return plots.mode_shapes_figure(self, **options)
        if kind == "torque":
            return plots.torque_figure(self, **options)
        return plots.energy_figure(self, kind=kind, **options)

    def view(self, mode: int, path=None, *, colour="twist", scale: float = 0.3, overwrite: bool = False):
        """One mode in 3D on the drivetrain's surface (pyvista, off-screen).

        With ``path`` (``.png``, ``.gif`` - one period - or ``.html``, the viewer to turn in a
        browser) the picture is written and its path returned; without, a pyvista Plotter is
        returned (``.screenshot()``, or ``.show()`` in Jupyter). ``colour``: ``"twist"``,
        ``"stress"`` (τ = G·r·dθ/dx, MPa) or ``"energy"``
        (J/m³), given at 1 mrad peak station rotation; ``scale``: the drawn twist of the
        largest station rotation, rad.
        """
        from ..views import render

        if path is None:
            return render.mode_plotter(self, mode, colour=colour, scale=scale)
        if str(path).lower().endswith(".gif"):
            return render.mode_gif(self, mode, path, colour=colour, scale=scale, overwrite=overwrite)
        if str(path).lower().endswith(".html"):
            from ..views.webview import mode_html

            return mode_html(self, mode, path, colour=colour, scale=scale, overwrite=overwrite)
        return render.mode_png(self, mode, path, colour=colour, scale=scale, overwrite=overwrite)

    def dominant_components(self) -> list[str | None]:
        """Per mode, the component with the largest strain-energy share (None if rigid)."""
        se = self.strain_energy_fractions()
        names = self.model.component_names
        return [None if r else names[int(np.argmax(row))] for r, row in zip(self.rigid, se)]


def mode_signs(result: ModalResult) -> np.ndarray:
    """+1 or -1 per mode: the sign that makes the mode's largest station value positive.

    flexshaft's one sign convention for mode shapes - the same in tables, JSON, plots, 3D views and
    exports. The value is a station's θx for a torsion mode (every mode of a torsion model), ux
    for an axial mode and the larger lateral translation (uy or uz) for a lateral one; without
    stations, every node's. The first station within 1e-6 of the largest magnitude decides, so a
    mode whose two ends swing equally (a symmetric chain's) gets the same sign on every machine:
    round-off moves an eigenvector's entries by ~1e-12 of it, far inside 1e-6.
    """
    model = result.model
    nodes = np.asarray(model.station_nodes) if len(model.station_nodes) else np.arange(model.n_nodes)
    kinds = result.kinds if model.dofs == "full" else ("torsion",) * result.count
    wanted = {"torsion": ("θx",), "axial": ("ux",), "lateral": ("uy", "uz")}
    u = {}
    for kind in set(kinds):
        # only the station rows of the recovered shapes (T's rows there), not every node's
        rows = np.sort(np.concatenate([model.node_dof(nodes, n) for n in wanted[kind]]))
        u[kind] = np.asarray(model.T[rows] @ result.shapes)
    signs = np.ones(result.count)
    for k in range(result.count):
        v = u[kinds[k]][:, k]
        top = float(np.max(np.abs(v))) if v.size else 0.0
        if top == 0.0:
            continue
        first = v[np.flatnonzero(np.abs(v) >= (1 - 1e-6) * top)[0]]
        signs[k] = 1.0 if first > 0 else -1.0
    return signs


def rayleigh_alpha(model: AssembledModel) -> float:
    """The model's Rayleigh inertia coefficient α, 1/s (0 without Rayleigh damping).

    The modal consumers take it off the rigid-body modes
    (:func:`~flexshaft.linalg.damping.modal_damping_block`): Rayleigh damps deformation only.
    """
    ray = model.drivetrain.rayleigh
    return 0.0 if ray is None else float(ray.alpha)


def _is_identity(T) -> bool:
    """Whether the sparse matrix T is the identity (stored as one 1 per row on the diagonal)."""
    n = T.shape[0]
    if T.shape != (n, n) or T.nnz != n:
        return False
    T = sp.csr_matrix(T)
    diagonal = np.all(np.diff(T.indptr) == 1) and np.all(T.indices == np.arange(n))
    return bool(diagonal and np.all(T.data == 1.0))


def _max_normalised(V: np.ndarray, rows=None) -> np.ndarray:
    """Each column over its largest-magnitude entry among ``rows`` (a mask or slice; all by default)."""
    W = V if rows is None else V[rows]
    idx = np.argmax(np.abs(W), axis=0)
    peak = W[idx, np.arange(V.shape[1])]
    return V / np.where(peak == 0, 1.0, peak)


def default_count(model: AssembledModel) -> int:
    """How many modes by default: all of a torsion model up to 600 DOFs, else 10; 16 of a full one."""
    n = model.n_dof
    if model.dofs == "full":
        return min(n, FULL_DEFAULT_COUNT)
    return n if n <= DENSE_MAX_DOF else 10


@follows_policy
def modal_analysis(
    model,
    count: int | None = None,
    *,
    inertia_model: str | None = None,
    damped: bool = True,
    method: str = "auto",
) -> ModalResult:
    """Undamped and (where the model has damping) damped modes of a drivetrain.

    The same analysis for a torsion model and a 6-DOF one (``dofs = "full"``),
    with or without flexible bodies: the rigid-body modes the supports allow
    are put in exactly (0 Hz), the elastic ones are made mass-orthogonal to
    them.

    Parameters
    ----------
    model : Drivetrain, AssembledModel or PartModel
        The drivetrain (a Drivetrain is assembled first), or one free part
        (see :func:`part_modes` for one on bearings).
    count : int, optional
        How many of the lowest modes, rigid-body modes included. Default: all
        for torsion models up to 600 DOFs, 10 for larger ones, 16 for a full
        model.
    inertia_model : {"consistent", "lumped"}, optional
        Overrides the drivetrain's setting.
    damped : bool
        Also compute the damped modes when the model has damping.
    method : {"auto", "dense", "lanczos"}
        Eigensolver path (see :func:`flexshaft.linalg.eigen.lowest_modes`).

    Returns
    -------
    ModalResult
    """
    if isinstance(model, Drivetrain):
        model = assemble(model, inertia_model)
    elif isinstance(model, PartModel):
        if inertia_model is not None and inertia_model != model.mass:
            raise ModelError(
                "a part model's mass is spread when it is built",
                field="inertia_model",
                value=inertia_model,
                valid=f"leave it out (this part has {model.mass!r} mass: part_model(..., mass=...))",
            )
        model = assemble_part(model)
    elif not isinstance(model, AssembledModel):
        raise ModelError(
            "not a drivetrain",
            field="model",
            value=type(model).__name__,
            valid="a Drivetrain, an AssembledModel or a PartModel",
        )
    elif inertia_model is not None and inertia_model != model.inertia_model:
        model = assemble(model.drivetrain, inertia_model, dofs=model.dofs)
    m = default_count(model) if count is None else check_int(count, "count", lo=1)
    if m > model.n_dof:
        raise ModelError(
            f"the model has only {model.n_dof} DOFs, so {model.n_dof} modes",
            field="count",
            value=m,
            valid=f"at most {model.n_dof}",
        )
    check_choice(method, "method", ("auto", "dense", "lanczos"))
    _check_finite(model)
    _check_spread(model)
    with solver_failures("the eigensolver"):
        sol = lowest_modes(
            model.K,
            model.M,
            m,
            rigid_basis=model.rigid_basis,
            method=method,
            bandwidth=model.bandwidth,
            trial=model.trial_shapes(),
        )
    if sol.vectors.shape[1] != m:
        raise ModelError(
            f"the eigensolver returned {sol.vectors.shape[1]} of the {m} modes asked for",
            field="count",
            value=m,
            valid="stiffness and inertia of one scale (the rest did not converge)",
        )
    omega = np.sqrt(np.clip(sol.eigenvalues, 0.0, None))
    _check_modes(model, sol.eigenvalues, sol.vectors)
    dm = None
    if damped and model.C is not None:
        with np.errstate(over="ignore"):
            c_size = float(abs(model.C).sum())
        if not np.isfinite(c_size):
            raise ModelError(
                "the damping matrix overflows double precision (a damper of extreme size)",
                field="damping",
                valid="dampers and damping ratios of the model's scale (N·m·s/rad, fractions)",
            )
        with solver_failures("the damped-mode solver"):
            dm = damped_modes(
                model.K,
                model.M,
                model.C,
                sol.eigenvalues,
                sol.vectors,
                sol.rigid,
                alpha=rayleigh_alpha(model),
            )
        bad = ~np.isfinite(dm.damping_ratios) | ~np.isfinite(dm.natural_frequencies_hz)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ModelError(
                f"mode {k} ({omega[k] / (2 * np.pi):.6g} Hz) has no damped counterpart the arithmetic "
                "resolves (a damper or damping ratio far out of scale with the stiffness and inertia)",
                field="damping",
                valid="dampers and damping ratios of the model's scale, or damped=False",
            )
    result = ModalResult(
        model=model, omega=omega, shapes=sol.vectors, rigid=sol.rigid, damped=dm, method=sol.method
    )
    signs = mode_signs(result)
    if np.all(signs > 0):
        return result
    return dataclasses.replace(result, shapes=sol.vectors * signs)


@follows_policy
def modes_up_to(
    model,
    max_hz: float,
    *,
    inertia_model: str | None = None,
    damped: bool = True,
    first: int = DEFAULT_LISTED,
) -> ModalResult:
    """The lowest modes up to ``max_hz`` (Hz), and the first one above it where the model has one.

    Solved for ``first`` modes, then twice as many until the highest is above ``max_hz`` or every
    mode of the model is in: a model's modes below a frequency are not known before they are solved.

    Parameters
    ----------
    model : Drivetrain or AssembledModel
        As for :func:`modal_analysis`.
    max_hz : float
        The frequency range of interest, Hz, > 0.
    inertia_model, damped
        As for :func:`modal_analysis`.
    first : int
        Modes of the first solve.
    """
    from ..validation import check_frequency

    max_hz = check_frequency(max_hz, "max_hz", lo_open=True)
    if isinstance(model, Drivetrain):
        model = assemble(model, inertia_model)
        inertia_model = None
    n = model.n_dof
    count = min(n, check_int(first, "first", lo=1))
    while True:
        result = modal_analysis(model, count, inertia_model=inertia_model, damped=damped)
        if count >= n or result.frequencies_hz[-1] > max_hz:
            return result
        count = min(n, 2 * count)


@follows_policy
def listing_modes(
    model,
    count: int | None = None,
    max_hz: float | None = None,
    *,
    inertia_model: str | None = None,
    damped: bool = True,
) -> ModalResult:
    """The modes a listing needs: ``count`` of them, else those up to ``max_hz`` (Hz; the model's
    ``[model] max_hz`` when none is given), else the lowest :data:`DEFAULT_LISTED`.

    What ``flexshaft modes`` computes: never all of a fine mesh's hundreds of modes unasked.

    Parameters
    ----------
    model : Drivetrain or AssembledModel
        As for :func:`modal_analysis`.
    count : int, optional
        How many modes (rigid-body modes included).
    max_hz : float, optional
        The frequency range of interest, Hz.
    inertia_model, damped
        As for :func:`modal_analysis`.
    """
    if count is not None:
        return modal_analysis(model, count, inertia_model=inertia_model, damped=damped)
    if max_hz is None and isinstance(model, (Drivetrain, AssembledModel)):
        max_hz = (model if isinstance(model, Drivetrain) else model.drivetrain).max_hz
    if max_hz is not None:
        return modes_up_to(model, max_hz, inertia_model=inertia_model, damped=damped)
    if isinstance(model, Drivetrain):
        model = assemble(model, inertia_model)
        inertia_model = None
    m = min(model.n_dof, DEFAULT_LISTED) if isinstance(model, AssembledModel) else DEFAULT_LISTED
    return modal_analysis(model, m, inertia_model=inertia_model, damped=damped)


@dataclass(frozen=True)
class SolidModes:
    """A solid part's lowest free-free modes (:func:`part_modes` of a solid part model).

    Attributes
    ----------
    part : str
    frequencies_hz : ndarray (m,)
        Ascending, Hz; the six rigid-body modes first, at 0.
    shapes : ndarray (3n, m)
        Mass-normalised (ΦᵀMΦ = I), node-major u_x, u_y, u_z.
    rigid : ndarray of bool (m,)
    method : str
        The eigensolver's path and its linear solver.
    """

    part: str
    frequencies_hz: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    method: str


@follows_policy
def part_modes(part, count: int = 10, *, bearings=None, cache=None, solver: str = "auto"):
    """The ``count`` lowest modes of one part - 1D or solid -, free or on lateral bearing springs.

    Parameters
    ----------
    part : PartModel or SolidPartModel
        From :func:`flexshaft.parts.model.part_model` or
        :func:`flexshaft.parts.solidpart.solid_part_model`.
    count : int
        Modes wanted, rigid-body modes included (6 for a free full part or a solid, 1
        for torsion; two or more bearings leave axial motion and spin).
    bearings : mapping of node index to stiffness, optional
        Isotropic lateral springs (N/m on uy and uz) at nodes of a full 1D model.
    cache : optional
        A solid's modes kept between runs (:class:`flexshaft.input.solidcache.SolidResults`), keyed
        by the mesh, the material, the count and the solver's settings; None: always solved.
    solver : {"auto", "direct", "amg"}
        A solid's shifted solves: by size (a sparse LU up to :data:`~flexshaft.linalg.spd.DIRECT_MAX`
        unknowns, multigrid CG beyond) or the one named. A 1D part is banded: LAPACK's banded
        factorisations, ``"auto"`` or ``"direct"``.

    Returns
    -------
    ModalResult or SolidModes
        A 1D part's: its model is the part as a one-component model
        (:func:`flexshaft.model.part.assemble_part`); ``dof_shapes("uy")``
        gives one DOF at every node. A solid's free-free modes, with the mesh nodes' shapes
        (:func:`flexshaft.parts.solidpart.free_modes`: the same eigensolver, its solves by size).
    """
    solver = check_choice(solver, "solver", SOLVERS)
    if isinstance(part, SolidPartModel):
        return _solid_part_modes(part, count, bearings, cache, solver)
    if solver == "amg":
        raise ModelError(
            "a 1D part is banded: factorised directly", field="solver", value=solver, valid="auto or direct"
        )
    return modal_analysis(assemble_part(part, bearings), count)


def _solid_part_modes(part: SolidPartModel, count, bearings, cache, solver) -> SolidModes:
    """:func:`part_modes` of a solid part: its free-free modes, kept in ``cache``."""
    if bearings:
        raise ModelError("a solid part's modes are free-free", field="bearings", valid="no bearings")
    elastic = check_int(count, "count", lo=RIGID_SOLID + 1, hi=1000 + RIGID_SOLID) - RIGID_SOLID
    settings = result_settings("solid modes", part.material, count=elastic, method=solver)

    def solve():
        return free_modes(part, elastic, solver=solver)

    solution = solve() if cache is None else cache.kept(part.mesh, settings, solve)[0]
    f = np.sqrt(np.maximum(solution.eigenvalues, 0.0)) / (2 * np.pi)
    return SolidModes(part.name, f, solution.vectors, solution.rigid, solution.method)


#: Models up to this many DOFs keep every mode in :func:`response_modes` (no truncation).
RESPONSE_ALL_MODES_DOFS = 2000


@follows_policy
def response_modes(model) -> ModalResult:
    """The modes a response analysis (state space, FRF, forced, simulation, Campbell) starts from.

    Every mode of a model up to :data:`RESPONSE_ALL_MODES_DOFS` DOFs (no truncation: a response is
    then exact), the default count of :func:`modal_analysis` above.

    Parameters
    ----------
    model : AssembledModel
        The assembled drivetrain (:func:`flexshaft.model.assembly.assemble`).

    Returns
    -------
    ModalResult
        Frequencies in Hz, mass-normalised shapes.
    """
    return modal_analysis(model, model.n_dof if model.n_dof <= RESPONSE_ALL_MODES_DOFS else None)


#: Largest spread of the coordinates' K_ii/M_ii (squared "local frequencies") a model may have: the
#: lowest eigenvalues carry round-off of about eps × spread relative (2e-16 × 1e14 = 2 %), so past it
#: a mode is noise. The examples span 2e2 (Customer 1) to 2e5 (the 6-DOF PTSS line).
MAX_SPREAD = 1e14
#: Largest backward error ‖Kφ − λMφ‖ / ((‖K‖ + λ‖M‖)‖φ‖) of a returned mode. Stable solvers give
#: ~n·eps (measured at most 5e-14 on the examples); 1e-8 leaves six orders and still catches garbage.
MAX_BACKWARD_ERROR = 1e-8


def _owner_at(model: AssembledModel, entries, coordinate: int) -> str:
    """The component (or bearing) with the largest diagonal entry of ``entries`` at a coordinate."""
    who = entries.dominant_owner(coordinate, coordinate)
    if who < 0:
        return "?"
    names = model.component_names + tuple(f"bearing at {st.name}" for st, _ in model.bearings)
    return names[who]


def _where(model: AssembledModel, coordinate: int) -> str:
    """'<stiffness owner>' on the inertia of '<mass owner>' at a coordinate, for messages."""
    k_owner = _owner_at(model, model.stiffness_entries, coordinate)
    m_owner = _owner_at(model, model.mass_entries, coordinate)
    return f"{k_owner!r} on the inertia of {m_owner!r} ({model.coordinate_labels[coordinate]})"


def _check_finite(model: AssembledModel) -> None:
    """K, M and C as assembled are finite: sums of huge entries may overflow even when each is finite."""
    for name, A in (("stiffness", model.K), ("inertia", model.M), ("damping", model.C)):
        if A is not None and not np.all(np.isfinite(A.data)):
            raise ModelError(
                f"the assembled {name} matrix overflows double precision",
                field=name,
                valid="numbers within a few hundred orders of 1 in SI units",
            )


def _check_spread(model: AssembledModel) -> None:
    """Refuse a model whose stiffness and inertia span more than double precision resolves."""
    k, m = model.K.diagonal(), model.M.diagonal()
    with np.errstate(all="ignore"):
        r = k / m
    if np.any(np.isinf(r)):  # an inertia so small that K/M overflows
        i = int(np.flatnonzero(np.isinf(r))[0])
        raise ModelError(
            f"stiffness over inertia overflows at {_where(model, i)}",
            field="inertia",
            valid="an inertia of the model's scale, or none there",
        )
    ok = np.isfinite(r) & (r > 0)
    if not ok.any():
        return
    idx = np.flatnonzero(ok)
    hi, lo = idx[np.argmax(r[ok])], idx[np.argmin(r[ok])]
    with np.errstate(over="ignore"):
        spread = r[hi] / r[lo]
    if spread > MAX_SPREAD:
        raise ModelError(
            # past 1e308 the ratio itself overflows: say so in orders of magnitude, never "inf"
            f"stiffness over inertia spans "
            f"{f'{spread:.3g}' if np.isfinite(spread) else f'1e{np.log10(r[hi]) - np.log10(r[lo]):.0f}'}, "
            f"from {_where(model, int(hi))} to "
            f"{_where(model, int(lo))}: more than double precision resolves (the lowest modes would be "
            "round-off)",
            field="stiffness",
            valid=f"a spread up to {MAX_SPREAD:.0e}: an inertia or stiffness far out of scale is likely a "
            "unit slip; a negligible inertia can be left out",
        )


def _abs_row_sum_max(A) -> float:
    """max_i Σ_j |A_ij| (‖A‖∞; ‖A‖₁ too, A being symmetric), over row blocks: no copy of A."""
    ones = np.ones(A.shape[1])
    peak = 0.0
    for rows in row_blocks(A.shape[0]):
        block = row_block(A, rows)
        if block.nnz:
            block.data = np.abs(block.data)  # the block's own array now: A is left as it is
            peak = max(peak, float(np.max(block @ ones)))
    return peak


def _check_modes(model: AssembledModel, lam: np.ndarray, V: np.ndarray) -> None:
    """Every returned mode is finite and solves K φ = λ M φ to the arithmetic's accuracy.

    The residuals are summed over row blocks of K and M: the temporaries are a
    block's rows of every mode, not full-length copies of the shapes.
    """
    K, M = model.K, model.M
    V = np.ascontiguousarray(V)  # scipy would copy a non-contiguous V whole for every block's product
    m = lam.size
    with np.errstate(all="ignore"):
        finite = np.isfinite(lam)
        res2, vv = np.zeros(m), np.zeros(m)
        for rows in row_blocks(V.shape[0]):
            Vb = V[rows]
            finite &= np.all(np.isfinite(Vb), axis=0)
            vv += np.einsum("ij,ij->j", Vb, Vb)
        if finite.all():
            for rows in row_blocks(V.shape[0]):
                Rb = row_block(K, rows) @ V
                Rb -= (row_block(M, rows) @ V) * lam
                res2 += np.einsum("ij,ij->j", Rb, Rb)
            nk, nm = _abs_row_sum_max(K), _abs_row_sum_max(M)
            res = np.sqrt(res2)
            scale = (nk + np.abs(lam) * nm) * np.sqrt(vv)
            # ‖K‖ or λ‖M‖ past double precision: the numbers are of extreme size, whatever λ says.
            finite = np.isfinite(scale)
            # A model without stiffness (one rigid inertia) has K = 0 and λ = 0: nothing to scale by.
            eta = np.where(scale > 0, res / np.where(scale > 0, scale, 1.0), np.where(res == 0, 0.0, np.inf))
            finite &= np.isfinite(eta)
    if not finite.all():
        k = int(np.flatnonzero(~finite)[0])
        raise ModelError(
            f"mode {k} overflows double precision (a stiffness, inertia or damping of extreme size)",
            field="stiffness",
            valid="stiffness, inertia and damping within a few hundred orders of 1 in SI units",
        )
    if np.any(eta > MAX_BACKWARD_ERROR):
        k = int(np.argmax(eta))
        raise ModelError(
            f"mode {k} does not solve K φ = λ M φ to the arithmetic's accuracy (backward error {eta[k]:.1e})",
            field="model",
            valid=f"a backward error up to {MAX_BACKWARD_ERROR:.0e}: stiffness and inertia of one scale",
        )
