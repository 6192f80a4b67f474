"""The applied-torque twist test: each part's torsional stiffness as the study measured it.

Clamp one station (the driving end by default), apply a torque at another
(the far end), solve K·θ = T statically, and read each part's stiffness as
T / (θ_end − θ_start) and the twist at every node along the shaft. The model
is linear, so the stiffness is exact and the same at every load; a torque
ramp shows it.

Through a gear stage every part is read in its own speed frame: it carries
the load torque times (load speed / its speed) - a lossless stage passes the
power on - and twists by its own angles, so its stiffness is its own, not a
reflected one. A gear with a mesh stiffness is a part too: its mesh stiffness
in the driving frame, torque on the driving wheel over θ_in − n·θ_out.

One part alone - a 1D part model or a meshed solid - is tested by :func:`part_stiffness`: one end
clamped, the six unit loads at the other (forces along x, y, z and moments about them) solved at once;
their displacements are the end's 6 x 6 compliance C, whose inverse is the end's stiffness matrix,
the part as its neighbours feel it. The test bench's numbers are one load at a time: the torsional
stiffness T/θ_x = 1/C[θx, θx], the axial F_x/u_x = 1/C[ux, ux], the bending (a tip force over its
deflection) 1/C[uy, uy] and 1/C[uz, uz]. A solid's end faces are tied to master nodes, rigidly or by
averaging (:mod:`flexshaft.parts.solidties`); its solve is chosen by size (``solver``: a sparse LU,
or conjugate gradients with multigrid). A conforming finite-element model is stiffer than the solid
it meshes and converges to it from above; a circular tube twisted by rigid end faces is
Saint-Venant's exact solution (sections turn rigidly, no warping), so its stiffness tends to G·J/L.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from ..errors import ModelError
from ..linalg.spd import SolveReport
from ..model.assembly import AssembledModel, assemble
from ..model.components import Drivetrain, Gear, Rigid, Shaft
from ..parts.model import PartModel
from ..parts.solidpart import SolidPartModel, end_compliance
from ..parts.solidties import INTERFACES, interface_statement
from ..reduction.solidbasis import result_settings
from ..system.threads import follows_policy
from ..validation import check_positive

__all__ = [
    "END_DOFS",
    "PartStiffness",
    "part_stiffness",
    "PartTwist",
    "TwistResult",
    "twist_test",
    "RAMP",
    "StiffnessTarget",
    "stiffness_target",
]

#: Multiples of the torque the ramp applies (the sign reversal included).
RAMP = (-1.0, 0.25, 0.5, 1.0, 2.0)
#: Smallest and largest |torque| accepted, N·m.
TORQUE_RANGE = (1e-30, 1e30)


@dataclass(frozen=True)
class PartTwist:
    """One component's result, in its own speed frame.

    Attributes
    ----------
    name : str
    stiffness : float
        Torque over twist, N·m/rad.
    twist : float
        Δθ end to end (a gear mesh: θ_in − n·θ_out), rad.
    x_start, x_end : float
        Axial extent, m.
    torque : float
        The torque it carries at the test torque, N·m (the test torque, times load speed over
        its speed past a gear stage).
    speed_ratio : float
        Its speed frame: its speed over the driving end's (1 without gear stages; a gear's
        driving side).
    elements : str
        Its finite elements: ``"1d"``, or for a solid part (``fe = "solid"``) its mesh and how its
        end faces are tied (``"solid: 2875 nodes, 1488 10-node tetrahedra, size 40 mm, end faces
        rigid (RBE2)"``).
    """

    name: str
    stiffness: float
    twist: float
    x_start: float
    x_end: float
    torque: float = 0.0
    speed_ratio: float = 1.0
    elements: str = "1d"


@dataclass(frozen=True)
class TwistResult:
    """Result of :func:`twist_test` (SI units).

    Attributes
    ----------
    torque : float
        Applied torque, N·m.
    clamp, load : str
        Station names where the shaft is clamped and loaded.
    x : ndarray
        Node positions along the axis, m (components not made from geometry
        have no length: their nodes share a position, so the line jumps).
    theta : ndarray
        Node rotation at ``torque``, rad, each in its own shaft's speed frame.
    speed_ratio : ndarray
        Each node's speed frame: its speed over the driving end's (1 without gear stages).
    parts : tuple of PartTwist
        Every flexible component between clamp and load, in chain order.
    ramp : ndarray
        The torques of the load-independence check, N·m.
    ramp_stiffness : ndarray, shape (len(ramp), len(parts))
        Each part's T/Δθ at each ramp torque, N·m/rad.
    stations : tuple of (str, int)
        Station names and their nodes.
    """

    torque: float
    clamp: str
    load: str
    x: np.ndarray
    theta: np.ndarray
    speed_ratio: np.ndarray
    parts: tuple
    ramp: np.ndarray
    ramp_stiffness: np.ndarray
    stations: tuple

    @property
    def load_spread(self) -> float:
        """Largest relative spread of any part's stiffness over the ramp (round-off for a linear model)."""
        k = self.ramp_stiffness
        if not k.size:
            return 0.0
        k = k / np.max(np.abs(k), axis=0)  # scaled to <= 1: a mean of stiffnesses near 1e308 overflows
        return float(np.max(np.ptp(k, axis=0) / np.abs(np.mean(k, axis=0))))

    def plot(self):
        """The rotation along the shaft as a matplotlib Figure (never shown; ``fig.savefig(path)``)."""
        from ..views.plots import twist_figure

        return twist_figure(self)

    def to_dict(self) -> dict:
        """The ``flexshaft twist --json`` document (SI: N·m, rad, m, N·m/rad)."""
        return {
            "units": {
                "torque": "N·m",
                "stiffness": "N·m/rad",
                "twist": "rad",
                "x": "m",
                "speed_ratio": "a frame's speed / the driving end's speed",
            },
            "frames": "each part's torque, twist and stiffness, and each station's theta, "
            "in its own speed frame",
            "torque": self.torque,
            "clamp": self.clamp,
            "load": self.load,
            "total_stiffness": self.total_stiffness,
            "load_spread": self.load_spread,
            "ramp_torques": self.ramp.tolist(),
            "parts": [
                {
                    "name": p.name,
                    "stiffness": p.stiffness,
                    "twist": p.twist,
                    "x_start": p.x_start,
                    "x_end": p.x_end,
                    "torque": p.torque,
                    "speed_ratio": p.speed_ratio,
                    "elements": p.elements,
                }
                for p in self.parts
            ],
            "stations": [
                {
                    "name": n,
                    "x": float(self.x[i]),
                    "theta": float(self.theta[i]),
                    "speed_ratio": float(self.speed_ratio[i]),
                }
                for n, i in self.stations
            ],
            "nodes": {"x": self.x.tolist(), "theta": self.theta.tolist()},
        }

    def table(self) -> str:
        """The ``flexshaft twist`` table: each part's stiffness and twist, the stations' rotation."""
        geared = bool(np.any(self.speed_ratio != 1.0))
        lines = [f"twist test: clamped at {self.clamp!r}, {self.torque:g} N·m at {self.load!r}"]
        if geared:
            lines.append(
                "through gear stages: each part's torque, twist and stiffness in its own speed frame "
                "(speed ratio to the driving end); clamp to load in the load's frame"
            )
        head = f"{'part':<16} {'stiffness N·m/rad':>18} {'twist rad':>12} {'x start m':>10} {'x end m':>9}"
        lines += ["", head + (f" {'torque N·m':>12} {'speed ratio':>11}" if geared else "")]
        for p in self.parts:
            row = f"{p.name:<16} {p.stiffness:18.6e} {p.twist:12.5e} {p.x_start:10.4f} {p.x_end:9.4f}"
            lines.append(row + (f" {p.torque:12.5e} {p.speed_ratio:11.5g}" if geared else ""))
        lines.append(f"{'clamp to load':<16} {self.total_stiffness:18.6e}")
        lines += [f"{p.name}: {p.elements}" for p in self.parts if p.elements != "1d"]
        lines.append("")
        lines.append(
            f"load independence over {len(self.ramp)} torques from {self.ramp.min():g} to "
            f"{self.ramp.max():g} N·m: stiffness spread {self.load_spread:.1e}"
        )
        lines.append("")
        lines.append(f"{'station':<24} {'x m':>9} {'theta rad':>12}")
        for name, i in self.stations:
            lines.append(f"{name:<24} {self.x[i]:9.4f} {self.theta[i]:12.5e}")
        return "\n".join(lines)

    @property
    def total_stiffness(self) -> float:
        """Torque over the load station's rotation (the clamp holds still), N·m/rad.

        In the load station's speed frame: the series stiffness of every part between clamp and
        load, each reflected by (its speed / the load's speed)².
        """
        node = dict(self.stations)[self.load]
        clamp = dict(self.stations)[self.clamp]
        return self.torque / (self.theta[node] - self.theta[clamp])


def _elements(comp) -> str:
    """What a part's finite elements are, for the record (:attr:`PartTwist.elements`)."""
    mesh = getattr(comp, "solid_mesh", None)
    if getattr(comp, "fe", "1d") != "solid" or mesh is None:
        return "1d"
    return (
        f"solid: {mesh.n_nodes} nodes, {mesh.n_elements} 10-node tetrahedra, size {1000 * mesh.size:.3g} mm, "
        + interface_statement(comp.interface)
    )


def _station(model: AssembledModel, name: str | None, default: int, field: str) -> tuple[str, int]:
    st = model.stations[default] if name is None else model.station(name, field)
    return st.name, st.node


@follows_policy
def twist_test(
    drivetrain: Drivetrain, torque: float = 1000.0, *, clamp: str | None = None, load: str | None = None
) -> TwistResult:
    """Clamp a station, apply a torque at another, and read every part's stiffness and twist.

    Parameters
    ----------
    drivetrain : Drivetrain
        The chain (inertias play no part in a static test).
    torque : float
        Torque at the load station, N·m, non-zero.
    clamp, load : str, optional
        Station names (see ``AssembledModel.stations``); default the first
        (driving end) and the last station.

    Returns
    -------
    TwistResult
    """
    # The model is linear, so any torque gives the same stiffness; the bounds keep the twist and the
    # ramp (up to 2 T) far inside double precision, where T/Δθ is exact to round-off.
    if not (np.isfinite(torque) and TORQUE_RANGE[0] <= abs(torque) <= TORQUE_RANGE[1]):
        raise ModelError(
            "must be a finite, non-zero torque of a size double precision resolves",
            field="torque",
            value=torque,
            unit="N·m",
            valid=f"{TORQUE_RANGE[0]:g} <= |torque| <= {TORQUE_RANGE[1]:g} N·m",
        )
    # Static: Craig–Bampton is exact at the interfaces, and the full mesh gives the twist everywhere.
    model = assemble(drivetrain, reduce=False, dofs="torsion", damping=False, statics=True)  # K alone
    clamp_name, c = _station(model, clamp, 0, "clamp")
    load_name, l = _station(model, load, -1, "load")
    if c == l:
        raise ModelError(
            "clamp and load are the same station",
            field="load",
            value=load_name,
            valid="a station other than the clamp",
        )
    # Station rotations are rows of T: a driven wheel tied by a rigid mesh reads 1/n of its coordinate.
    Tc, Tl = (model.T[model.node_dof([node])[0]].toarray().ravel() for node in (c, l))
    if np.array_equal(Tc != 0, Tl != 0):
        raise ModelError(
            f"clamp {clamp_name!r} and load {load_name!r} turn together (a rigid gear mesh ties them)",
            field="load",
            value=load_name,
            valid="a station on another side of a flexible part",
        )
    if not np.all(np.isfinite(model.K.data)):  # two stiffnesses near 1e308 sum past double precision
        raise ModelError(
            "the assembled stiffness matrix overflows double precision",
            field="stiffness",
            valid="stiffnesses within a few hundred orders of 1 in SI units",
        )
    free = np.flatnonzero(Tc == 0)  # the clamp holds the coordinate its station reads
    K = model.K.tocsc()[free][:, free]
    torques = torque * np.asarray(RAMP + (1.0,))
    F = np.outer(Tl[free], torques)  # the load torque's virtual work on the coordinates
    try:
        theta_f = spla.splu(K.tocsc()).solve(F)
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        theta_f = np.full(F.shape, np.nan)
    if not np.all(np.isfinite(theta_f)):
        raise ModelError(
            f"clamped at {clamp_name!r}, the model does not hold the torque at {load_name!r} (its "
            "stiffness matrix is singular, or the twist overflows)",
            field="clamp",
            value=clamp_name,
            valid="a clamp and a load joined by parts of finite stiffness",
        )
    q = np.zeros((model.n_dof, torques.size))
    q[free] = theta_f
    theta = model.T @ q  # every node's rotation in its own frame
    speed = model.speed_ratio
    lo, hi = min(c, l), max(c, l)
    x = model.x
    parts, ramp_k = [], []
    for ci, comp in enumerate(drivetrain.components):
        s, e = int(model.start_node[ci]), int(model.end_node[ci])
        if isinstance(comp, Rigid) or s < lo or e > hi or (isinstance(comp, Gear) and comp.rigid_mesh):
            continue
        n = comp.ratio if isinstance(comp, Gear) else 1.0
        carried = torques * speed[l] / speed[s]  # power passes unchanged: T·ω is the same in every part
        dtheta = (n * theta[e] - theta[s]) * np.sign(l - c)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # refused just below
            k = carried / dtheta
        if not np.all(np.isfinite(k)):
            raise ModelError(
                f"the twist of {comp.name!r} under {torque:g} N·m is below what double precision "
                "resolves (a stiffness of extreme size)",
                field="stiffness",
                valid="stiffnesses within a few hundred orders of the others, or a larger --torque",
            )
        parts.append(
            PartTwist(
                comp.name,
                float(k[-1]),
                float(dtheta[-1]),
                float(x[s]),
                float(x[e]),
                float(carried[-1]),
                float(speed[s]),
                _elements(comp),
            )
        )
        ramp_k.append(k[:-1])
    return TwistResult(
        torque=float(torque),
        clamp=clamp_name,
        load=load_name,
        x=x,
        theta=theta[:, -1],
        speed_ratio=speed.copy(),
        parts=tuple(parts),
        ramp=torques[:-1],
        ramp_stiffness=np.array(ramp_k).T.reshape(len(RAMP), len(parts)),
        stations=tuple((s.name, s.node) for s in model.stations),
    )


#: A part's end DOFs, in the order of its end stiffness matrix's rows and columns.
END_DOFS = ("ux", "uy", "uz", "θx", "θy", "θz")


@dataclass(frozen=True)
class PartStiffness:
    """A part's end stiffness, its other end clamped (:func:`part_stiffness`), SI.

    Attributes
    ----------
    part : str
    clamp, load : str
        The clamped and the loaded end (``"start"``, ``"end"``).
    compliance : ndarray (6, 6)
        The loaded end's displacements (m, rad) per unit load (N, N·m), in :data:`END_DOFS` order.
    stiffness : ndarray (6, 6)
        Its inverse: the end's stiffness matrix (N/m, N, N·m/rad).
    torsion : float
        T/θx with the torque alone, N·m/rad.
    axial : float
        F/u_x with the axial force alone, N/m.
    bending : (float, float)
        F/u with a tip force alone along y and along z, N/m.
    interface : str
        How a solid's end faces are tied (:data:`~flexshaft.parts.solidties.INTERFACES`); a 1D
        part's ends are its end nodes.
    dofs : int
        Unknowns of the system solved.
    solver : SolveReport
    mesh_size : float
        A solid's global element size; a 1D part's longest element, m.
    """

    part: str
    clamp: str
    load: str
    compliance: np.ndarray
    stiffness: np.ndarray
    torsion: float
    axial: float
    bending: tuple
    interface: str
    dofs: int
    solver: SolveReport
    mesh_size: float

    def to_dict(self) -> dict:
        """A JSON-ready document (units stated)."""
        return {
            "part": self.part,
            "clamp": self.clamp,
            "load": self.load,
            "units": {"torsion": "N·m/rad", "axial": "N/m", "bending": "N/m", "stiffness": "SI by DOF"},
            "torsion": self.torsion,
            "axial": self.axial,
            "bending": list(self.bending),
            "end_dofs": list(END_DOFS),
            "stiffness": self.stiffness.tolist(),
            "interface": self.interface,
            "dofs": self.dofs,
            "solver": self.solver.method,
            "iterations": self.solver.iterations,
            "mesh_size_m": self.mesh_size,
        }


def _one_d_compliance(part: PartModel, clamp: str, load: str):
    """A full (6-DOF) 1D part's loaded end node's compliance, the other end node clamped: one LU."""
    if part.dofs != "full":
        raise ModelError("needs six DOFs a node", field="dofs", value=part.dofs, valid='dofs = "full"')
    ends = {"start": part.node_dofs(0), "end": part.node_dofs(-1)}
    free = np.setdiff1d(np.arange(part.n_dofs), ends[clamp])
    K = part.K.tocsc()[free][:, free]
    at = np.searchsorted(free, ends[load])
    loads = np.zeros((free.size, 6))
    loads[at, np.arange(6)] = 1.0
    u = spla.splu(K).solve(loads)
    C = u[at, :]
    report = SolveReport("SuperLU", 0, float(np.linalg.norm(K @ u - loads) / np.linalg.norm(loads)), 0.0, 0.0)
    return 0.5 * (C + C.T), int(free.size), report  # symmetric (Maxwell-Betti) to round-off


@follows_policy
def part_stiffness(
    part, *, clamp: str = "start", load: str = "end", solver: str = "auto", cache=None
) -> PartStiffness:
    """The end stiffness of a part, its other end clamped (module docstring): 1D or solid.

    Parameters
    ----------
    part : PartModel or SolidPartModel
        A 1D part (six DOFs a node; its end nodes) or a solid (its end faces tied as it says).
    clamp, load : {"start", "end"}
        The ends held and loaded.
    solver : {"auto", "direct", "amg"}
        A solid's linear solver (:class:`~flexshaft.linalg.spd.SpdSolver`): by size (a sparse LU up to
        :data:`~flexshaft.linalg.spd.DIRECT_MAX` unknowns, multigrid CG beyond) or the one named; a 1D
        part is banded, always a sparse LU.
    cache : optional
        A solid's results kept between runs (:class:`flexshaft.input.solidcache.SolidResults`), keyed
        by the mesh, the material, the ends, the interface and the solver's settings; None: solved.

    Returns
    -------
    PartStiffness
    """
    for name, end in (("clamp", clamp), ("load", load)):
        if end not in ("start", "end"):
            raise ModelError("is not an end of the part", field=name, value=end, valid="start or end")
    if clamp == load:
        raise ModelError("is the loaded end too", field="clamp", value=clamp, valid="the other end")
    if isinstance(part, PartModel):
        C, dofs, report = _one_d_compliance(part, clamp, load)
        size = float(np.max(np.diff(part.x)))
        return _stiffness(part.name, C, clamp, load, "end nodes (1D)", dofs, report, size)
    if not isinstance(part, SolidPartModel):
        kind = type(part).__name__
        raise ModelError("not a part model", field="part", value=kind, valid="a 1D or solid part model")
    mesh, kinds = part.mesh, part.interface
    tie = kinds[0] if kinds[0] == kinds[1] else list(kinds)
    settings = result_settings(
        "solid stiffness", part.material, clamp=clamp, load=load, interface=tie, method=solver
    )

    def solve():
        return end_compliance(part, clamp=clamp, load=load, solver=solver)

    solved = solve() if cache is None else cache.kept(mesh, settings, solve)[0]
    said = INTERFACES[kinds[0]] if kinds[0] == kinds[1] else interface_statement(kinds)
    C, unknowns = solved.compliance, solved.unknowns
    return _stiffness(mesh.name, C, clamp, load, said, unknowns, solved.solver, mesh.size)


def _stiffness(name, C, clamp, load, interface, dofs, solver, size) -> PartStiffness:
    """The :class:`PartStiffness` of a loaded end's 6 x 6 compliance ``C``: its inverse and the
    one-load stiffnesses."""
    return PartStiffness(
        part=name,
        clamp=clamp,
        load=load,
        compliance=C,
        stiffness=np.linalg.inv(C),
        torsion=float(1.0 / C[3, 3]),
        axial=float(1.0 / C[0, 0]),
        bending=(float(1.0 / C[1, 1]), float(1.0 / C[2, 2])),
        interface=interface,
        dofs=int(dofs),
        solver=solver,
        mesh_size=float(size),
    )


@dataclass(frozen=True)
class StiffnessTarget:
    """What makes a part reach a target torsional stiffness (exact: the model is linear).

    Attributes
    ----------
    target, current : float
        Target and present stiffness, N·m/rad.
    youngs_modulus : float
        E (Pa) at fixed ν and geometry that gives the target (k ∝ G ∝ E).
    scale_all : float
        Uniform scale of every dimension, lengths included, that gives it (k ∝ s³).
    scale_diameters : float
        Scale of the cross-section only, lengths fixed (k ∝ s⁴).
    """

    target: float
    current: float
    youngs_modulus: float
    scale_all: float
    scale_diameters: float

    def to_dict(self) -> dict:
        """The ``flexshaft twist --target --json`` entry (stiffness N·m/rad, E Pa, scale factors)."""
        return {
            "target": self.target,
            "current": self.current,
            "E": self.youngs_modulus,
            "scale_all": self.scale_all,
            "scale_diameters": self.scale_diameters,
        }

    def table(self) -> str:
        """The ``flexshaft twist --target`` line: what reaches the target, one way or another."""
        return (
            f"{self.current:.6e} -> {self.target:.6e} N·m/rad needs E = {self.youngs_modulus:.6e} Pa "
            f"(ν and geometry fixed), or every dimension ×{self.scale_all:.6f}, or the diameters "
            f"×{self.scale_diameters:.6f}"
        )


@follows_policy
def stiffness_target(shaft: Shaft, target: float) -> StiffnessTarget:
    """The Young's modulus, or the dimension scale, that gives a shaft made from sections a target stiffness.

    The study read this off a graph of stiffness against E; here it is exact:
    k = G / Σ L/J with G = E / (2 (1 + ν)), J ∝ s⁴ and L ∝ s.
    """
    if not isinstance(shaft, Shaft) or shaft.material is None:
        raise ModelError(
            "needs a shaft made from sections (a material to change)",
            field="component",
            value=getattr(shaft, "name", shaft),
            valid="a 'cad' part or a shaft given by segments",
        )
    check_positive(target, "target", "N·m/rad", "must be a finite stiffness > 0")
    ratio = target / shaft.stiffness
    return StiffnessTarget(
        target=float(target),
        current=shaft.stiffness,
        youngs_modulus=shaft.material.E * ratio,
        scale_all=ratio ** (1 / 3),
        scale_diameters=ratio**0.25,
    )
