"""The building blocks of a torsional drivetrain chain.

A drivetrain is a serial chain from the driving end (motor first). Components
are placed one after another; each flexible component adds stations (nodes),
a rigid one sits on the current station.

All quantities are SI: stiffness N·m/rad, inertia kg·m², damping N·m·s/rad,
damping ratios as fractions (0.0053 for 0.53 %).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..elements.materials import Material
from ..errors import ModelError
from ..linalg.damping import check_rayleigh, frequency_pair, rayleigh_coefficients
from ..parts.beammesh import TorsionMesh, mesh_size, torsion_mesh
from ..sections.table import SectionTable
from ..system.limits import check_ceiling
from ..validation import (
    DAMPER,
    FRACTION,
    GEAR_RATIO,
    INERTIA,
    LENGTH,
    MASS,
    POSITIVE_INERTIA,
    STIFFNESS,
    check_choice,
    check_frequency,
    check_int,
    check_name,
    check_real,
)
from .nonlinear import law_of

__all__ = [
    "Rigid",
    "Shaft",
    "Coupling",
    "Gear",
    "check_torsion_gears",
    "Rayleigh",
    "Reduce",
    "Drivetrain",
    "Component",
    "INERTIA_MODELS",
    "INERTIA_SPLITS",
    "DEFAULT_FLEX_DAMPING",
    "FE_KINDS",
    "SOLID_MODES",
]

INERTIA_MODELS = ("consistent", "lumped")
#: How a coupling's inertia sits on its two ends: by the model's rule, or as two rigid halves.
INERTIA_SPLITS = ("model", "halves")

#: A part's finite elements: 1D (sections' torsion or beam elements) or its solid's tetrahedra.
FE_KINDS = ("1d", "solid")
#: Fixed-interface modes a solid part keeps when its ``reduce`` does not say (with the residual
#: vectors, every free-free mode below about half the highest kept one is within 1e-4).
SOLID_MODES = 4

#: Damping ratio of every elastic mode of a flexible body unless the model says
#: otherwise: the 0.53 % the study set on its multibody flexible parts.
DEFAULT_FLEX_DAMPING = 0.0053


def _checked(name: str, checks) -> None:
    """Run ``checks()`` and put the component's name on any ModelError."""
    try:
        checks()
    except ModelError as err:
        raise err.located(component=repr(name)) from None


def _check_spring(obj) -> None:
    """Validate the stiffness, inertia and damper every flexible component has."""
    s = object.__setattr__
    s(obj, "stiffness", STIFFNESS.check(obj.stiffness, "stiffness"))
    s(obj, "inertia", INERTIA.check(obj.inertia, "inertia"))
    s(obj, "damping", DAMPER.check(obj.damping, "damping"))


def _check_solid(shaft) -> None:
    """A solid part needs its mesh and its sections (its 1D line), and no stations inside it yet."""
    from ..elements.tetmesh import TetMesh

    if not isinstance(shaft.solid_mesh, TetMesh):
        raise ModelError(
            "a solid part needs its solid mesh",
            field="fe",
            value="solid",
            valid="a shaft given by segments or a cad part (the model file meshes it)",
        )
    if shaft.sections is None:
        raise ModelError(
            "a solid part needs its geometry", field="fe", value="solid", valid="segments or a cad part"
        )
    for face in ("start", "end"):
        if face not in shaft.solid_mesh.faces:
            raise ModelError(
                f"the solid mesh has no {face!r} face set",
                field="fe",
                value="solid",
                valid="a mesh from geometry.meshing.mesh_solid (faces 'start' and 'end')",
            )
    if shaft.named_nodes:
        raise ModelError(
            "stations inside a solid part are not supported yet (its interface is its two end faces)",
            field="stations",
            value=shaft.named_nodes[0][0],
            valid='leave stations out with fe = "solid", or fe = "1d"',
        )


@dataclass(frozen=True)
class Rigid:
    """A rigid inertia (motor rotor, generator rotor, flywheel) on the current station.

    Parameters
    ----------
    name : str
        Unique component name.
    inertia : float
        Axial (polar) mass moment of inertia, kg·m², > 0.
    mass : float
        Its mass, kg, >= 0: in a 6-DOF model, on the three translations of its node.
    diametral_inertia : float
        Its mass moment of inertia about a diameter, kg·m², >= 0: in a 6-DOF model, on the two
        tilts of its node. A spinning rigid body's gyroscopic moment comes from ``inertia``
        (the polar one) and acts on the same tilts. Both are unused in a torsion model.
    """

    name: str
    inertia: float
    mass: float = 0.0
    diametral_inertia: float = 0.0
    type: ClassVar[str] = "rigid"

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))

        def checks() -> None:
            s = object.__setattr__
            s(self, "inertia", POSITIVE_INERTIA.check(self.inertia, "inertia"))
            s(self, "mass", MASS.check(self.mass, "mass"))
            s(self, "diametral_inertia", INERTIA.check(self.diametral_inertia, "diametral_inertia"))

        _checked(self.name, checks)


@dataclass(frozen=True)
class Reduce:
    """Make a shaft a Craig–Bampton flexible body in the chain.

    Parameters
    ----------
    modes : int, optional
        Number of fixed-interface modes kept, >= 0.
    cutoff_hz : float, optional
        Keep every fixed-interface mode below this frequency, Hz (instead of
        ``modes``).
    damping : float, sequence or ModalDamping
        Damping of the flexible body's own free-free modes (see
        :func:`flexshaft.reduction.craig_bampton`); 0.53 % on every elastic
        mode by default.

    The interface (boundary) nodes are the shaft's two ends and its named
    nodes; they stay physical chain nodes, so stations, bearings and
    neighbours attach to them.
    """

    modes: int | None = None
    cutoff_hz: float | None = None
    damping: object = DEFAULT_FLEX_DAMPING

    def __post_init__(self) -> None:
        if (self.modes is None) == (self.cutoff_hz is None):
            raise ModelError(
                "give either modes or cutoff_hz",
                field="reduce",
                valid="{modes = n} or {cutoff_hz = f} (Hz)",
            )
        if self.modes is not None:
            object.__setattr__(self, "modes", check_int(self.modes, "reduce.modes", lo=0, hi=100_000))
        else:
            object.__setattr__(
                self, "cutoff_hz", check_frequency(self.cutoff_hz, "reduce.cutoff_hz", lo_open=True)
            )

    @property
    def label(self) -> str:
        """``"6 modes"`` or ``"modes < 2000 Hz"``."""
        return f"{self.modes} modes" if self.modes is not None else f"modes < {self.cutoff_hz:g} Hz"


@dataclass(frozen=True)
class Shaft:
    """A shaft piece of given end-to-end stiffness and inertia.

    Parameters
    ----------
    name : str
        Unique component name.
    stiffness : float
        Torsional stiffness end to end, N·m/rad, > 0.
    inertia : float
        Axial mass moment of inertia, kg·m², >= 0. Spread over the stations by
        the model's inertia model (consistent or lumped).
    elements : int
        Number of equal sub-elements (each has ``elements·stiffness`` and
        ``inertia/elements``), >= 1.
    damping_ratio : float
        Modal damping ratio set on every elastic mode of this shaft's own
        free-free model (as a multibody tool does for a flexible part), in
        [0, 1). 0.0053 is the study's 0.53 %.
    damping : float
        A discrete damper end to end, N·m·s/rad, >= 0 (split in series over
        the sub-elements like the stiffness).
    sections : SectionTable, optional
        The cross-sections the stiffness and inertia came from (a shaft given
        by ``segments`` or a CAD part); see :meth:`from_sections`.
    material : Material, optional
        The material those sections are made of.
    geometry : str, optional
        Where a CAD part's geometry came from (``"module:function"`` or a
        file), for reports; ``None`` for a shaft not made from CAD.
    max_element_length : float, optional
        For a shaft made from sections: the longest element, m. Its mesh has a
        node at every section station; ``elements`` > 1 also caps the element
        length at length / elements.
    named_nodes : tuple of (name, position m)
        For a shaft made from sections: positions measured from its driving
        end that get a node and the station name ``"<shaft>: <name>"`` (a
        journal bearing, a sensor, a flange face).
    reduce : Reduce, optional
        Enter the chain as a Craig–Bampton flexible body (its interface nodes
        plus fixed-interface modes) instead of its full mesh; its damping is
        then ``reduce.damping`` and ``damping_ratio`` is not used.
    fixed_mesh : bool, optional
        The mesh is the user's (``elements`` or ``max_element_length`` given in the model file):
        :func:`flexshaft.analysis.convergence.mesh_for_range` leaves it as it is. Default: True
        when ``elements`` > 1 or ``max_element_length`` is set.
    subdivide : int
        Cut every element of the mesh ``elements`` and ``max_element_length`` make into this many
        equal pieces, >= 1 (1: none). A nested refinement - the finer mesh has every node of the
        coarser one - as the mesh-convergence estimate needs; not a model-file key.
    fe : {"1d", "solid"}
        The part's finite elements: its sections' 1D torsion or beam elements (default), or its
        solid's 10-node tetrahedra (``solid_mesh``), which then enter the chain as a Craig–Bampton
        body of the solid (:mod:`flexshaft.reduction.solidbasis`; ``reduce``, or
        :data:`SOLID_MODES` fixed-interface modes when not given). Its 1D mesh stays the line its
        stations and plots read.
    solid_mesh : TetMesh, optional
        The part's solid mesh, for ``fe = "solid"``.
    interface : (str, str)
        How a solid part's start and end faces are tied to their master nodes: ``"rigid"`` (RBE2) or
        ``"average"`` (RBE3) each (:data:`flexshaft.parts.solidties.INTERFACES`); a single kind is
        taken for both. Only for ``fe = "solid"``.
    solid_cache : optional
        Where the solid part's results (its reduction, stiffness, modes) are kept between runs: the
        disk cache the model-file loader hands over (:data:`flexshaft.input.solidcache.SOLID_RESULTS`,
        unless ``--no-cache``); None: computed in every run. Not part of the model (not compared).
    solid_progress : callable, optional
        ``solid_progress(label)`` returns a progress bar (its ``stage(stage, fraction)``) for the
        solid part's reduction, minutes for a large mesh: what the model-file loader is handed as
        its ``progress``; None: silent. Not part of the model (not compared).
    """

    name: str
    stiffness: float
    inertia: float
    elements: int = 1
    damping_ratio: float = 0.0
    damping: float = 0.0
    sections: SectionTable | None = field(default=None, repr=False, compare=False)
    material: Material | None = None
    geometry: str | None = None
    max_element_length: float | None = None
    named_nodes: tuple = ()
    reduce: Reduce | None = None
    fixed_mesh: bool | None = None
    subdivide: int = 1
    fe: str = "1d"
    solid_mesh: object = field(default=None, repr=False, compare=False)
    interface: tuple = ("rigid", "rigid")
    solid_cache: object = field(default=None, repr=False, compare=False)
    solid_progress: object = field(default=None, repr=False, compare=False)
    type: ClassVar[str] = "shaft"

    @classmethod
    def from_sections(
        cls,
        name: str,
        sections: SectionTable,
        material: Material,
        *,
        elements: int = 1,
        damping_ratio: float = 0.0,
        damping: float = 0.0,
        geometry: str | None = None,
        max_element_length: float | None = None,
        named_nodes=(),
        reduce: Reduce | None = None,
        fixed_mesh: bool | None = None,
        fe: str = "1d",
        solid_mesh=None,
        interface=("rigid", "rigid"),
        solid_cache=None,
        solid_progress=None,
    ) -> Shaft:
        """A shaft whose stiffness and inertia come from its section table.

        Stiffness 1 / Σ L/(G·J) (the intervals are springs in series),
        N·m/rad; inertia ρ·Σ Ip·L, kg·m².
        """
        return cls(
            name=name,
            stiffness=sections.torsional_stiffness(material.G),
            inertia=sections.axial_inertia(material.rho),
            elements=elements,
            damping_ratio=damping_ratio,
            damping=damping,
            sections=sections,
            material=material,
            geometry=geometry,
            max_element_length=max_element_length,
            named_nodes=tuple(named_nodes),
            reduce=reduce,
            fixed_mesh=fixed_mesh,
            fe=fe,
            solid_mesh=solid_mesh,
            interface=interface,
            solid_cache=solid_cache,
            solid_progress=solid_progress,
        )

    @property
    def solid_reduce(self) -> Reduce | None:
        """How a solid part is reduced: its ``reduce``, else :data:`SOLID_MODES` modes; None for 1D."""
        if self.fe != "solid":
            return None
        return self.reduce if self.reduce is not None else Reduce(modes=SOLID_MODES)

    @property
    def source(self) -> str:
        """``"cad"``, ``"segments"`` or ``"given"``: where stiffness and inertia came from."""
        if self.geometry is not None:
            return "cad"
        return "segments" if self.sections is not None else "given"

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))

        def checks() -> None:
            s = object.__setattr__
            _check_spring(self)
            s(self, "elements", check_ceiling("elements", check_int(self.elements, "elements", lo=1)))
            s(self, "subdivide", check_int(self.subdivide, "subdivide", lo=1))
            if self.sections is None:
                check_ceiling("elements", self.elements * self.subdivide, field="elements")
            s(self, "damping_ratio", FRACTION.check(self.damping_ratio, "damping_ratio"))
            if self.named_nodes and self.sections is None:
                raise ModelError(
                    "named nodes need a shaft made from sections",
                    field="stations",
                    value=self.named_nodes[0][0],
                    valid="a cad part or a shaft given by segments",
                )
            # Named nodes must lie inside the part; the size of its mesh for modal damping is checked
            # where the mesh is built (assembly): validating a shaft does not mesh it.
            if self.sections is not None:
                self.sections.check_inside(self.named_positions)
            if self.max_element_length is not None:
                s(self, "max_element_length", LENGTH.check(self.max_element_length, "max_element_length"))
            s(self, "fe", check_choice(self.fe, "fe", FE_KINDS))
            if self.interface != ("rigid", "rigid"):
                from ..parts.solidties import interface_kinds  # (its solver imports: solid parts only)

                s(self, "interface", interface_kinds(self.interface))
            if self.fe == "solid":
                _check_solid(self)
            elif self.interface != ("rigid", "rigid"):
                raise ModelError(
                    "ties a solid part's end faces",
                    field="interface",
                    value=self.interface,
                    valid='fe = "solid" with it (a 1D part has no faces), or leave it out',
                )
            if self.fixed_mesh is None:
                s(self, "fixed_mesh", self.elements != 1 or self.max_element_length is not None)
            s(self, "fixed_mesh", bool(self.fixed_mesh))
            if self.reduce is not None:
                if not isinstance(self.reduce, Reduce):
                    raise ModelError("must be a Reduce(modes= or cutoff_hz=)", field="reduce")
                if self.inertia == 0:
                    raise ModelError(
                        "a flexible body needs its modes, so an inertia",
                        field="inertia",
                        value=0.0,
                        unit="kg·m²",
                        valid="> 0 with reduce",
                    )
                return
            if self.damping_ratio > 0 and self.inertia == 0:
                raise ModelError(
                    "modal damping per shaft mode needs the shaft's own modes, so an inertia",
                    field="inertia",
                    value=0.0,
                    unit="kg·m²",
                    valid="> 0 when damping_ratio > 0 (or use `damping` in N·m·s/rad)",
                )

        _checked(self.name, checks)

    def torsion_mesh(self) -> TorsionMesh | None:
        """The elements of a shaft made from sections (see :mod:`flexshaft.parts.beammesh`), else None."""
        if self.sections is None:
            return None
        return torsion_mesh(
            self.sections,
            self.material,
            max_element_length=self.mesh_cap,
            nodes_at=self.named_positions,
            subdivide=self.subdivide,
        )

    @property
    def named_positions(self) -> tuple[float, ...]:
        """Absolute table positions (m) of the named nodes."""
        if self.sections is None:
            return ()
        return tuple(self.sections.x[0] + float(p) for _, p in self.named_nodes)

    def named_mesh_nodes(self, x: np.ndarray) -> list[int]:
        """Index of each named node in a mesh of this shaft with nodes at ``x`` (m from its driving end).

        The mesh must have a node at every named position (``torsion_mesh`` and
        ``part_model`` with ``nodes_at=named_positions`` do); the nearest is taken.
        """
        x0 = self.sections.x[0] if self.sections is not None else 0.0
        return [int(np.argmin(np.abs(np.asarray(x) - (p - x0)))) for p in self.named_positions]

    @property
    def mesh_cap(self) -> float | None:
        """Longest element of a shaft made from sections, m (None: one per section interval)."""
        if self.sections is None:
            return None
        cap = self.sections.length / self.elements if self.elements > 1 else None
        if self.max_element_length is not None:
            cap = self.max_element_length if cap is None else min(cap, self.max_element_length)
        return cap

    @property
    def n_elements(self) -> float:
        """Elements of its mesh, counted without building it (``elements``, or the sections' mesh)."""
        if self.sections is None:
            return float(self.elements * self.subdivide)
        return mesh_size(
            self.sections,
            max_element_length=self.mesh_cap,
            nodes_at=self.named_positions,
            subdivide=self.subdivide,
        )

    def element_properties(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-element stiffness (N·m/rad), inertia (kg·m²) and damper (N·m·s/rad).

        A shaft of given numbers is cut into ``elements`` equal pieces; one made
        from sections gets its own non-uniform mesh. The damper is split like
        the stiffness (each piece keeps the ratio damping/stiffness), so the
        series sum is ``damping`` either way.
        """
        mesh = self.torsion_mesh()
        if mesh is not None:
            return mesh.stiffness, mesh.inertia, mesh.stiffness * (self.damping / self.stiffness)
        n = self.elements * self.subdivide
        return (np.full(n, self.stiffness * n), np.full(n, self.inertia / n), np.full(n, self.damping * n))


@dataclass(frozen=True)
class Coupling:
    """A torsional coupling: a spring and damper with its inertia on its two ends.

    Parameters
    ----------
    name : str
        Unique component name.
    stiffness : float
        Torsional stiffness of the spring, N·m/rad, > 0.
    inertia : float
        Total axial inertia, kg·m², >= 0.
    damping : float
        Damper in parallel with the spring, N·m·s/rad, >= 0.
    inertia_split : {"model", "halves"}
        ``"model"`` (default): the inertia is spread by the model's inertia
        rule like a shaft element's - consistent j·[[1/3, 1/6], [1/6, 1/3]] or
        lumped j/2 on each end - as the study's matrix models treat the
        coupling (an element like the others; right when its inertia is spread
        along it, like a composite tube). ``"halves"``: two rigid halves,
        j/2 on each end whatever the model - right for a coupling whose mass
        sits in two hubs, as a multibody tool models it.
    slip_torque, slip_kinetic_torque, slip_damping : float, optional
        A friction face in series with the spring (N·m, N·m, N·m·s/rad): it sticks below the
        static ``slip_torque`` and transmits ``slip_kinetic_torque`` (default: the static one) plus
        ``slip_damping`` times the slip speed while slipping (:class:`~flexshaft.model.nonlinear.Slip`).
    backlash : float, optional
        Total free play, rad, centred: the spring and damper act in contact only.
    stiffness_curve : list of [torque, stiffness], optional
        Tangent stiffness (N·m/rad) against transmitted torque (N·m); ``stiffness`` then comes from
        it (the tangent at zero torque).
    torque_curve : list of [angle, torque], optional
        The same as the manufacturer gives it: torque (N·m) against twist (rad).

    Notes
    -----
    The nonlinear keys act in time runs (:func:`~flexshaft.analysis.simulate.simulate`); every linear
    analysis uses the linear coupling (stuck, in contact, the tangent at zero torque). One law per
    coupling.
    """

    name: str
    stiffness: float | None = None
    inertia: float = 0.0
    damping: float = 0.0
    inertia_split: str = "model"
    slip_torque: float | None = None
    slip_kinetic_torque: float | None = None
    slip_damping: float = 0.0
    backlash: float | None = None
    stiffness_curve: object = None
    torque_curve: object = None
    law: object = field(default=None, init=False, repr=False, compare=False)
    type: ClassVar[str] = "coupling"

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))

        def checks() -> None:
            law = law_of(
                stiffness=self.stiffness,
                slip_torque=self.slip_torque,
                slip_kinetic_torque=self.slip_kinetic_torque,
                slip_damping=self.slip_damping,
                backlash=self.backlash,
                stiffness_curve=self.stiffness_curve,
                torque_curve=self.torque_curve,
            )
            object.__setattr__(self, "law", law)
            if law is not None and law.kind == "curve":
                object.__setattr__(self, "stiffness", law.tangent_at_zero)
            if self.stiffness is None:
                raise ModelError(
                    "missing key for a coupling",
                    field="stiffness",
                    valid="stiffness (N·m/rad), or a stiffness_curve or torque_curve that gives it",
                )
            _check_spring(self)
            check_choice(self.inertia_split, "inertia_split", INERTIA_SPLITS)

        _checked(self.name, checks)

    @property
    def damping_ratio(self) -> float:
        """Couplings carry no modal damping (their damper is ``damping``)."""
        return 0.0

    def element_properties(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One element: stiffness (N·m/rad), inertia (kg·m²), damper (N·m·s/rad)."""
        return (np.array([self.stiffness]), np.array([self.inertia]), np.array([self.damping]))


#: Smallest and largest gear ratio accepted (:data:`flexshaft.validation.GEAR_RATIO`).
GEAR_RATIO_RANGE = (GEAR_RATIO.lo, GEAR_RATIO.hi)


@dataclass(frozen=True)
class Gear:
    """A gear stage: the chain goes on at another speed.

    The stage has two nodes: its driving-side (input) wheel at the end of the
    component before it and its driven-side (output) wheel at the start of
    the one after it. Every angle, speed and torque downstream is in its own
    shaft's speed frame: a shaft turning n times slower than the input shows
    its own angle, and the torque it carries (n times the input torque for a
    lossless stage). Angles count positive in each shaft's own sense of
    rotation, so the direction reversal of an external mesh does not appear.

    Parameters
    ----------
    name : str
        Unique component name.
    ratio : float
        Driving-side speed / driven-side speed (a speed-reducing stage of a
        wind-turbine gearbox read from the rotor side has ratio < 1; a
        reducer driven by a motor, > 1), in [1e-3, 1e3].
    inertia_in, inertia_out : float
        Axial inertia of the driving-side and driven-side wheels, kg·m², >= 0,
        each about its own shaft (not reflected).
    mesh_stiffness : float, optional
        Torsional stiffness of the tooth mesh referred to the driving side,
        N·m/rad, > 0: the mesh carries T = k·(θ_in − n·θ_out) on the driving
        wheel and n·T on the driven one. A linear mesh stiffness k_m (N/m) on
        the driving wheel's base radius r_b (m) is k_m·r_b². None (default):
        a rigid mesh, θ_out = θ_in / n exactly (one coordinate for both
        wheels).
    mesh_damping : float
        Damper across the mesh referred to the driving side, N·m·s/rad, >= 0
        (needs ``mesh_stiffness``).
    backlash : float, optional
        Total free play of the mesh, rad on the driving side, centred (needs ``mesh_stiffness``: the
        contact); the mesh stiffness and damper act in contact only.
    stiffness_curve, torque_curve : list of pairs, optional
        A mesh stiffness that depends on the torque, as for :class:`Coupling` (driving side);
        ``mesh_stiffness`` then comes from it.

    Notes
    -----
    As for :class:`Coupling`, the nonlinear keys act in time runs only; one law per mesh.
    """

    name: str
    ratio: float
    inertia_in: float = 0.0
    inertia_out: float = 0.0
    mesh_stiffness: float | None = None
    mesh_damping: float = 0.0
    backlash: float | None = None
    stiffness_curve: object = None
    torque_curve: object = None
    law: object = field(default=None, init=False, repr=False, compare=False)
    type: ClassVar[str] = "gear"

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))

        def checks() -> None:
            s = object.__setattr__
            law = law_of(
                stiffness=self.mesh_stiffness,
                backlash=self.backlash,
                stiffness_curve=self.stiffness_curve,
                torque_curve=self.torque_curve,
                spring="mesh_stiffness",
            )
            s(self, "law", law)
            if law is not None and law.kind == "curve":
                s(self, "mesh_stiffness", law.tangent_at_zero)
            s(self, "ratio", GEAR_RATIO.check(self.ratio, "ratio"))
            s(self, "inertia_in", INERTIA.check(self.inertia_in, "inertia_in"))
            s(self, "inertia_out", INERTIA.check(self.inertia_out, "inertia_out"))
            if self.mesh_stiffness is not None:
                s(self, "mesh_stiffness", STIFFNESS.check(self.mesh_stiffness, "mesh_stiffness"))
            s(self, "mesh_damping", DAMPER.check(self.mesh_damping, "mesh_damping"))
            if self.mesh_damping and self.mesh_stiffness is None:
                raise ModelError(
                    "a rigid mesh has no relative motion to damp",
                    field="mesh_damping",
                    value=self.mesh_damping,
                    unit="N·m·s/rad",
                    valid="0, or give mesh_stiffness (N·m/rad) as well",
                )

        _checked(self.name, checks)

    @property
    def rigid_mesh(self) -> bool:
        """True when the mesh is rigid (no ``mesh_stiffness``)."""
        return self.mesh_stiffness is None

    @property
    def damping_ratio(self) -> float:
        """A gear stage carries no modal damping (its damper is ``mesh_damping``)."""
        return 0.0


Component = Rigid | Shaft | Coupling | Gear


def check_torsion_gears(components, dofs: str) -> None:
    """Refuse a gear stage in a 6-DOF model.

    A gear mesh there couples the lateral motion of two parallel shafts through the tooth forces
    (a gear element of a rotordynamics code), which flexshaft does not model; the torsion model
    has none of that to get wrong.
    """
    if dofs != "full":
        return
    for comp in components:
        if isinstance(comp, Gear):
            raise ModelError(
                "a gear stage is a torsion component: its lateral mesh coupling is not modelled",
                component=repr(comp.name),
                field="dofs",
                value="full",
                valid='dofs = "torsion" for a chain with gear stages',
            )


@dataclass(frozen=True)
class Rayleigh:
    """Model-level Rayleigh damping C = alpha·J + beta·K.

    Parameters
    ----------
    alpha : float
        Inertia-proportional coefficient, 1/s, 0 to 1e6
        (:data:`~flexshaft.linalg.damping.RAYLEIGH_ALPHA_MAX`).
    beta : float
        Stiffness-proportional coefficient, s, 0 to 1
        (:data:`~flexshaft.linalg.damping.RAYLEIGH_BETA_MAX`).
    frequencies_hz : (float, float), optional
        Where the model file stated the damping as ratios at two frequencies (``rayleigh =
        {frequencies_hz = [f1, f2], damping_ratios = [z1, z2]}``), those frequencies, Hz, distinct and
        > 0: α and β are then the fit there, and the ratios ξ(f1), ξ(f2) are parameters a calibration
        can tune (``rayleigh.damping_ratios[0]``, ``[1]``) and a tuned model file writes back.
    """

    alpha: float = 0.0
    beta: float = 0.0
    frequencies_hz: tuple | None = None

    @classmethod
    def from_ratios(cls, frequencies_hz, damping_ratios, *, field: str = "rayleigh") -> Rayleigh:
        """The Rayleigh damping with ``damping_ratios`` (z1, z2, fractions) at ``frequencies_hz`` (f1, f2,
        Hz): α and β by the closed-form fit (:func:`~flexshaft.linalg.damping.rayleigh_coefficients`).

        Ratios that need a negative coefficient are refused (naming ``field.damping_ratios``); a
        coefficient that is 0 up to round-off (a difference of two terms, left at ~eps of them) is 0.
        """
        f, z = tuple(frequencies_hz), tuple(damping_ratios)
        try:
            alpha, beta = rayleigh_coefficients(f[0], z[0], f[1], z[1])
        except ModelError as err:  # its arguments' names as the file spells them
            names = {"f1_hz": "frequencies_hz[0]", "f2_hz": "frequencies_hz[1]"}
            names |= {"ratio1": "damping_ratios[0]", "ratio2": "damping_ratios[1]"}
            raise err.replaced(field=f"{field}.{names.get(err.field, err.field)}") from None
        w1, w2 = 2 * np.pi * f[0], 2 * np.pi * f[1]
        span = abs(w2**2 - w1**2)
        alpha_terms = 2 * w1 * w2 * (z[0] * w2 + z[1] * w1) / span
        beta_terms = 2 * (z[0] * w1 + z[1] * w2) / span
        if alpha < -1e-12 * alpha_terms or beta < -1e-12 * beta_terms:
            raise ModelError(
                "these ratios need a negative Rayleigh coefficient "
                f"(alpha = {alpha:.4g} 1/s, beta = {beta:.4g} s)",
                field=f"{field}.damping_ratios",
                value=[float(v) for v in z],
                valid=f"ratios at {f[0]:g} and {f[1]:g} Hz whose alpha and beta are both >= 0",
            )
        return cls(alpha=max(alpha, 0.0), beta=max(beta, 0.0), frequencies_hz=f)

    def __post_init__(self) -> None:
        alpha, beta = check_rayleigh(self.alpha, self.beta)
        object.__setattr__(self, "alpha", alpha)
        object.__setattr__(self, "beta", beta)
        if self.frequencies_hz is not None:
            f = self.frequencies_hz
            if isinstance(f, str) or not hasattr(f, "__len__") or len(f) != 2:
                raise ModelError(
                    "must be two frequencies",
                    field="rayleigh.frequencies_hz",
                    value=f,
                    has_value=True,
                    valid="[f1, f2], Hz, distinct and > 0",
                )
            names = ("rayleigh.frequencies_hz[0]", "rayleigh.frequencies_hz[1]")
            object.__setattr__(self, "frequencies_hz", frequency_pair(*f, names=names))


@dataclass(frozen=True)
class Drivetrain:
    """A serial torsional chain of components, driving end first.

    Parameters
    ----------
    name : str
        Model name for reports.
    components : tuple of Rigid, Shaft, Coupling, Gear
        The chain, in order from the driving end.
    inertia_model : {"consistent", "lumped"}
        How a shaft's inertia is spread over its stations.
    rayleigh : Rayleigh, optional
        Model-level Rayleigh damping added to the component damping, on the deformation only: the
        modal analyses take its αJ off a free chain's rigid-body modes (no drag to ground; see
        :func:`~flexshaft.linalg.damping.modal_damping_block`).
    dofs : {"torsion", "full"}
        θx per node, or six DOFs per node with Timoshenko shafts (every shaft
        then made from sections); see :mod:`flexshaft.model.assembly`.
    bearings : tuple of (station name, N/m)
        Isotropic lateral springs at stations, for ``dofs = "full"``.
    max_hz : float, optional
        The frequency range of interest, Hz, > 0: :func:`flexshaft.analysis.convergence.mesh_for_range`
        meshes the shafts so every mode below it is within 1 %, and the modes listing stops there.
        None: no range given (the mesh as the components say; the lowest 20 modes listed).
    """

    name: str
    components: tuple = field(default_factory=tuple)
    inertia_model: str = "consistent"
    rayleigh: Rayleigh | None = None
    dofs: str = "torsion"
    bearings: tuple = ()
    max_hz: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name, "model.name"))
        object.__setattr__(self, "components", tuple(self.components))
        check_choice(self.inertia_model, "inertia_model", INERTIA_MODELS)
        check_choice(self.dofs, "dofs", ("torsion", "full"))
        if self.max_hz is not None:
            object.__setattr__(self, "max_hz", check_frequency(self.max_hz, "max_hz", lo_open=True))
        object.__setattr__(
            self,
            "bearings",
            tuple(
                (str(n), check_real(k, f"bearings[{str(n)!r}]", "N/m", lo=0.0, lo_open=True))
                for n, k in self.bearings
            ),
        )
        if self.bearings and self.dofs != "full":
            raise ModelError(
                "bearings act on lateral DOFs",
                field="bearings",
                value=self.bearings[0][0],
                valid='[model] dofs = "full" (a torsion model has no lateral DOFs)',
            )
        if not self.components:
            raise ModelError(
                "the chain is empty",
                field="chain",
                valid="at least one component (rigid, shaft, coupling or gear)",
            )
        seen: set[str] = set()
        for i, comp in enumerate(self.components):
            if not isinstance(comp, (Rigid, Shaft, Coupling, Gear)):
                raise ModelError(
                    f"chain[{i}] is a {type(comp).__name__}",
                    field="components",
                    valid="Rigid, Shaft, Coupling or Gear",
                )
            if comp.name in seen:
                raise ModelError(
                    "duplicate component name",
                    component=f"chain[{i}]",
                    field="name",
                    value=comp.name,
                    valid="a name not used by another component",
                )
            seen.add(comp.name)
        check_torsion_gears(self.components, self.dofs)
        if self.rayleigh is not None and not isinstance(self.rayleigh, Rayleigh):
            raise ModelError("rayleigh must be a Rayleigh(alpha, beta)", field="rayleigh")

    def component(self, name: str):
        """The component called ``name``."""
        for comp in self.components:
            if comp.name == name:
                return comp
        raise ModelError(
            "no such component",
            field="component",
            value=name,
            valid=", ".join(repr(c.name) for c in self.components),
        )
