"""Flexible bodies in Exudyn: a Craig–Bampton body as Exudyn's reduced-order FFRF object.

:func:`to_exudyn` places a :class:`~flexshaft.reduction.FlexibleBody` into an Exudyn ``MainSystem`` as
an ``ObjectFFRFreducedOrder`` - the floating-frame body Exudyn builds from a mesh's nodes, a mode
basis and reduced mass and stiffness matrices, the way Adams reads an MNF - and returns its interface
markers, to which joints connect rigid motor and generator bodies or the next flexible body.
:func:`chain_to_exudyn` builds a whole torsion chain (rigid inertias, reduced shafts, couplings) from
a drivetrain; :func:`simulate_exudyn` runs a system with an integrator that adds no damping of its own.
Exudyn is the ``multibody`` extra, imported only when one of these is called.

How a body becomes Exudyn's
---------------------------
Exudyn's FFRF nodes carry translations only; a shaft's nodes also rotate. Each node of the part's mesh
becomes a ring of four points at ``radius`` around its axis position (at 0°, 90°, 180°, 270°), which
moves as the node does: u_p = u + θ × r·n_p (n_p the point's radial unit vector; a torsion body's node
turns its ring by r·θx along the tangent). With V the map from the body's Craig–Bampton coordinates
c = [u_b; q] to the points' displacements (V = ring · T):

- the floating frame sits on the first boundary node and carries the body's rigid-body motion w:
  c = E·w + P·ζ, with E the rigid-body modes in Craig–Bampton coordinates and P every coordinate but
  the first boundary node's (whose ring then has no flexible displacement: it moves with the frame);
- the mode basis is Ψ = V·P and the flexible stiffness, mass and damping are Pᵀ·K·P, Pᵀ·M·P and
  Pᵀ·C·P: the body's own matrices, taken as they are (the modal damping of its free-free modes
  included; C·E = 0, so the frame's spin is not damped, as in flexshaft);
- the mass that Exudyn's inertia terms integrate (the rigid-body inertia, the frame–mode coupling,
  the quadratic velocity terms) is M₃ = V⁺ᵀ·M·V⁺ over the points (V⁺ a left inverse of V), never
  formed: each term is (V⁺A)ᵀ·M·(V⁺B). Since Vᵀ·M₃·V = M and V·E·w is the points' rigid motion,
  Exudyn's body has flexshaft's mass on every motion the body can make.

So the linearised equations at rest are flexshaft's term for term, and the eigenfrequencies agree to
round-off. A torsion body's rings move along their tangents only: the body has no translational mass
and no tilt inertia (its model has none), so its frame must be held by joints, as
:func:`chain_to_exudyn` holds the chain (the first component on a revolute joint about x, every
other one joined rigidly to its neighbour's interface). Exudyn adds what a linear model leaves out:
the frame's large rotation, and, since a ring point moves along the tangent rather than on its
circle, a centrifugal softening of each body mode by about ½·(Ω/ω)² at spin speed Ω (1e-6 at
3 rad/s on a 400 Hz mode).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la

from ..errors import ModelError
from ..validation import check_positive

__all__ = [
    "ExudynBody",
    "ExudynRigid",
    "ExudynChain",
    "to_exudyn",
    "coupling_body",
    "chain_to_exudyn",
    "simulate_exudyn",
    "RING_POINTS",
]

#: Points on each mesh node's ring. Four at right angles is the fewest whose average turns with the
#: node about every axis (MarkerSuperElementRigid needs points not on one line) and whose sums of
#: cos and sin vanish, which keeps a torsion ring's motion free of translation and tilt.
RING_POINTS = 4
# cos and sin of the ring points' angles, exact (0°, 90°, 180°, 270°).
_COS = np.array([1.0, 0.0, -1.0, 0.0])
_SIN = np.array([0.0, 1.0, 0.0, -1.0])
# A translational mass below this fraction of the rigid-body inertia over radius² is the round-off of
# a torsion body's (which has none), ~1e-30 of it measured: it is taken as 0, not divided by.
_MASS_ROUNDOFF = 1e-12
_INSTALL = "pip install 'flexshaft[multibody]' (Exudyn >= 1.13)"


def _exudyn():
    """Exudyn and its item interface, imported here only: ``import flexshaft`` never loads it."""
    try:
        import exudyn
        import exudyn.itemInterface as items
    except ImportError:
        raise ModelError("needs exudyn", field="to_exudyn", valid=_INSTALL) from None
    return exudyn, items


@dataclass(frozen=True)
class ExudynBody:
    """A flexible body in an Exudyn system (:func:`to_exudyn`). Indices are Exudyn's own.

    Attributes
    ----------
    name : str
        The body's name.
    object : exudyn.ObjectIndex
        Its ``ObjectFFRFreducedOrder``.
    frame_node : exudyn.NodeIndex
        Its rigid-body node (Euler parameters): the floating frame, on the first boundary node.
    modal_node : exudyn.NodeIndex
        Its ``NodeGenericODE2``: the flexible coordinates ζ, the Craig–Bampton coordinates but the
        first boundary node's (boundary DOFs relative to the frame, m and rad; modal amplitudes).
    interfaces : tuple of exudyn.MarkerIndex
        A ``MarkerSuperElementRigid`` on each boundary node's ring, in the body's boundary order.
    interface_positions : ndarray, shape (nb, 3)
        Where the boundary nodes are in the global frame at rest, m.
    ring_points : ndarray of int, shape (n_mesh_nodes, 4)
        The Exudyn mesh-node numbers of each mesh node's ring.
    radius : float
        The rings' radius, m.
    rigid_modes : ndarray, shape (nb + nm, 1 or 6)
        E: the body's rigid-body modes in Craig–Bampton coordinates, per unit frame motion (torsion:
        the rotation about the axis, rad; full: ux, uy, uz in m, θx, θy, θz in rad).
    flexible : ndarray, shape (nb + nm, nb + nm - 1 or 6)
        P: the flexible coordinates ζ in Craig–Bampton coordinates.
    """

    name: str
    object: object
    frame_node: object
    modal_node: object
    interfaces: tuple
    interface_positions: np.ndarray
    ring_points: np.ndarray
    radius: float
    rigid_modes: np.ndarray = field(repr=False)
    flexible: np.ndarray = field(repr=False)

    def coordinates(self, frame, flexible) -> np.ndarray:
        """The body's Craig–Bampton coordinates c = E·w + P·ζ from a small frame motion ``frame``
        (w, rad or [m, rad]) and the flexible coordinates ``flexible`` (ζ, the modal node's)."""
        return self.rigid_modes @ np.atleast_1d(frame) + self.flexible @ np.asarray(flexible)


@dataclass(frozen=True)
class ExudynRigid:
    """A rigid inertia in an Exudyn system (:func:`chain_to_exudyn`).

    Attributes
    ----------
    name : str
        The component's name.
    node : exudyn.NodeIndex
        Its rigid-body node (Euler parameters), at its station.
    object : exudyn.ObjectIndex
        Its ``ObjectRigidBody``.
    marker : exudyn.MarkerIndex
        A ``MarkerBodyRigid`` at its centre: where it is joined, where a torque acts on it.
    """

    name: str
    node: object
    object: object
    marker: object


@dataclass(frozen=True)
class ExudynChain:
    """A drivetrain's torsion chain in an Exudyn system (:func:`chain_to_exudyn`).

    Attributes
    ----------
    components : tuple of ExudynRigid or ExudynBody
        Each component in chain order: rigid inertias, and shafts and couplings as flexible bodies.
    joints : tuple of exudyn.ObjectIndex
        The ``ObjectJointGeneric`` s: the first one holds the first component on a revolute joint
        about x, each other joins two neighbours' interfaces rigidly.
    couplings : dict of str to tuple of (float, float)
        Each coupling's stiffness (N·m/rad) and damping (N·m·s/rad).
    """

    components: tuple
    joints: tuple
    couplings: dict

    def component(self, name: str):
        """The component called ``name``."""
        for comp in self.components:
            if comp.name == name:
                return comp
        names = ", ".join(repr(c.name) for c in self.components)
        raise ModelError("no such component", field="component", value=name, valid=names)

    def coupling_torque(self, name: str, twist, twist_rate=0.0):
        """The torque coupling ``name`` transmits, N·m, positive when a positive motor torque drives
        it (flexshaft's ``torque:NAME``), from its body's flexible coordinate: the twist ζ = θ_out − θ_in
        (rad) and its rate (rad/s), as its modal node holds them."""
        if name not in self.couplings:
            raise ModelError("not a coupling", field="coupling", value=name, valid=", ".join(self.couplings))
        k, c = self.couplings[name]
        return -(k * np.asarray(twist) + c * np.asarray(twist_rate))


def _frame_split(body) -> tuple[np.ndarray, np.ndarray, int]:
    """E (rigid-body modes) and P (flexible coordinates) of ``body`` in its Craig–Bampton
    coordinates, and the DOFs per node, the floating frame on the first boundary node."""
    d = 6 if body.dofs == "full" else 1
    n, nb = body.K.shape[0], body.boundary_nodes.size
    first = body.T[d * int(body.boundary_nodes[0]) : d * int(body.boundary_nodes[0]) + d]
    if not np.allclose(first, np.eye(d, n), rtol=0.0, atol=1e-12):
        # The frame is the first boundary node's motion only if that node is its own coordinate.
        raise ModelError(
            "its first boundary node is not its own Craig–Bampton coordinate",
            field="body",
            value=body.name,
            valid="a Craig–Bampton body (boundary DOFs first, each recovered as itself)",
        )
    E = np.zeros((n, d))
    if d == 1:
        E[:nb, 0] = 1.0
    else:
        for j in range(nb):
            dx = float(body.boundary_x[j] - body.boundary_x[0])
            E[6 * j : 6 * j + 6] = np.eye(6)
            # a rotation of the frame moves a node dx further along the axis sideways: ω × (dx, 0, 0)
            E[6 * j + 1, 5], E[6 * j + 2, 4] = dx, -dx
    return E, np.eye(n)[:, d:], d


def _ring_map(T: np.ndarray, d: int, r: float) -> np.ndarray:
    """V: the displacements of every ring point (mesh node-major, then point, then x, y, z) per
    Craig–Bampton coordinate, u_p = u + θ × r·n_p."""
    ring = np.zeros((RING_POINTS, 3, d))  # point displacement per node DOF
    if d == 1:
        ring[:, 1, 0], ring[:, 2, 0] = -r * _SIN, r * _COS  # θx turns the point along its tangent
    else:
        ring[:, :, :3] = np.eye(3)
        ring[:, 0, 4], ring[:, 0, 5] = r * _SIN, -r * _COS  # θy, θz tilt the ring's plane
        ring[:, 1, 3], ring[:, 2, 3] = -r * _SIN, r * _COS
    Tn = T.reshape(T.shape[0] // d, d, T.shape[1])
    return np.einsum("pkd,idj->ipkj", ring, Tn).reshape(-1, T.shape[1])


def _skew(A: np.ndarray) -> np.ndarray:
    """Exudyn's ``ComputeSkewMatrix`` of a (3n × m) matrix: (3n × 3m), the skew matrix of each
    point's 3-vector in each column (vectorised; the same layout)."""
    n3, m = A.shape
    a = A.reshape(n3 // 3, 3, m)
    x, y, z = a[:, 0], a[:, 1], a[:, 2]
    out = np.zeros((n3 // 3, 3, m, 3))
    out[:, 0, :, 1], out[:, 0, :, 2] = -z, y
    out[:, 1, :, 0], out[:, 1, :, 2] = z, -x
    out[:, 2, :, 0], out[:, 2, :, 1] = -y, x
    return out.reshape(n3, 3 * m)


def _ffrf_terms(V: np.ndarray, M: np.ndarray, xref: np.ndarray, Psi: np.ndarray, r: float) -> dict:
    """The inertia terms of ``ObjectFFRFreducedOrder`` as Exudyn's ``ObjectFFRFreducedOrderInterface``
    defines them (Y·ᵀM₃·Z of the points' mass M₃), for M₃ = V⁺ᵀ·M·V⁺: each is (V⁺Y)ᵀ·M·(V⁺Z)."""
    VtV = V.T @ V
    factor = la.cho_factor(VtV)
    npts = xref.size // 3

    def coeffs(A):
        """V⁺·A: the Craig–Bampton coordinates whose ring motion is A's projection."""
        return la.cho_solve(factor, V.T @ A)

    phit = coeffs(np.tile(np.eye(3), (npts, 1)))  # the three translations of every point
    xr = coeffs(xref[:, None])
    xt = coeffs(_skew(xref[:, None]))
    psi, psit = coeffs(Psi), coeffs(_skew(Psi))

    def mm(a, b):
        return a.T @ M @ b

    inertia = mm(xt, xt)
    mass = float(mm(phit, phit)[0, 0])
    if mass <= _MASS_ROUNDOFF * float(np.trace(inertia)) / r**2:
        mass, com = 0.0, np.zeros(3)  # a torsion body's rings have no translational mass
    else:
        com = mm(phit, xr).ravel() / mass
    return dict(
        mass=mass,
        inertia=inertia,
        centerOfMass=com,
        mPsiTildePsi=mm(psit, psi),
        mPsiTildePsiTilde=mm(psit, psit),
        mPhitTPsi=mm(phit, psi),
        mPhitTPsiTilde=mm(phit, psit),
        mXRefTildePsi=mm(xt, psi),
        mXRefTildePsiTilde=mm(xt, psit),
    )


def _body_and_mesh(body, mesh_x) -> tuple:
    """The FlexibleBody of ``body`` (a FlexibleBody or a PartReduction) and its mesh nodes' axial
    positions, m, on the body's own axis (the boundary positions' origin)."""
    reduction = body if hasattr(body, "part_model") else None
    body = reduction.body if reduction is not None else body
    if not hasattr(body, "free_modes"):
        raise ModelError("is not a flexible body", field="body", valid="a FlexibleBody or a PartReduction")
    n_nodes = body.n_mesh_nodes
    if mesh_x is None and reduction is not None and getattr(body, "solid", None) is None:
        mesh_x = reduction.part_model.x
    if mesh_x is None and body.dofs == "full":
        # T reproduces a rotation about z of the first boundary node: each node's uy is its lever arm
        E, _, _ = _frame_split(body)
        mesh_x = body.boundary_x[0] + (body.T @ E[:, 5])[1::6]
    if mesh_x is None:
        # A torsion body does not carry its mesh's positions: spread the interior evenly between its
        # boundary nodes (they only place the rings, which turn about the axis wherever they are).
        order = np.argsort(body.boundary_nodes)
        mesh_x = np.interp(np.arange(n_nodes), body.boundary_nodes[order], body.boundary_x[order])
    mesh_x = np.asarray(mesh_x, dtype=float)
    if mesh_x.shape != (n_nodes,) or not np.all(np.isfinite(mesh_x)):
        raise ModelError(
            f"has {mesh_x.size} positions for {n_nodes} mesh nodes",
            field="mesh_x",
            unit="m",
            valid=f"{n_nodes} finite axial positions, m",
        )
    return body, mesh_x


def to_exudyn(
    body,
    mbs,
    *,
    position=(0.0, 0.0, 0.0),
    rotation=None,
    radius: float = 0.1,
    mesh_x=None,
    name: str | None = None,
) -> ExudynBody:
    """Place a flexible body into an Exudyn system as its ``ObjectFFRFreducedOrder``.

    Parameters
    ----------
    body : FlexibleBody or PartReduction
        The Craig–Bampton body (``dofs`` "torsion" or "full"); a PartReduction
        (:func:`flexshaft.reduce_part`) brings its mesh's node positions too.
    mbs : exudyn.MainSystem
        The system to add it to (nodes, the object, one marker per boundary node).
    position : sequence of 3 floats
        Where the body's axial origin (``boundary_x`` = 0) is in the global frame, m.
    rotation : array_like (3, 3), optional
        The body's axis frame in the global frame (its first column the shaft axis); default the
        identity (the axis along global x).
    radius : float
        Radius of the ring of points each mesh node becomes, m, > 0. It places the points (and the
        picture); the body's mass and stiffness do not depend on it.
    mesh_x : array_like, optional
        The mesh nodes' axial positions, m (default: a PartReduction's part model; a full body's own
        recovery T; else spread evenly between the boundary nodes).
    name : str, optional
        Exudyn's name of the object, unique in the system (its nodes get ``"frame:"`` and
        ``"modes:"`` before it); default the body's name.

    Returns
    -------
    ExudynBody

    Raises
    ------
    ModelError
        Without Exudyn (one line naming the extra); for a radius that is not > 0, mesh positions
        that do not fit the body, or a body whose coordinates do not all show on its mesh's rings.
    """
    exu, items = _exudyn()
    check_positive(radius, "radius", "m", "must be a radius > 0")
    body, mesh_x = _body_and_mesh(body, mesh_x)
    E, P, d = _frame_split(body)
    V = _ring_map(np.asarray(body.T, dtype=float), d, float(radius))
    if np.linalg.matrix_rank(V) < V.shape[1]:
        raise ModelError(
            "has coordinates that move none of its mesh nodes",
            field="body",
            value=body.name,
            valid="a body whose recovery T has full column rank",
        )
    A = np.eye(3) if rotation is None else np.asarray(rotation, dtype=float)
    if A.shape != (3, 3) or not np.allclose(A.T @ A, np.eye(3), atol=1e-9):
        raise ModelError("is not a rotation matrix", field="rotation", valid="an orthonormal 3 × 3 matrix")
    x0 = float(body.boundary_x[0])
    points = np.zeros((mesh_x.size, RING_POINTS, 3))  # in the frame, which sits on the first boundary node
    points[:, :, 0] = (mesh_x - x0)[:, None]
    points[:, :, 1], points[:, :, 2] = radius * _COS, radius * _SIN
    xref = points.reshape(-1)
    Psi = V @ P
    terms = _ffrf_terms(V, body.M, xref, Psi, float(radius))
    nf = P.shape[1]

    def matrix(a):
        mc = exu.MatrixContainer()
        mc.SetWithDenseMatrix(np.ascontiguousarray(a), useDenseMatrix=True)
        return mc

    label = body.name if name is None else str(name)
    origin = np.asarray(position, dtype=float) + A[:, 0] * x0
    frame = items.NodeRigidBodyEP(
        name=f"frame:{label}",
        referenceCoordinates=list(origin) + list(_euler_parameters(A)),
    )
    frame_node = mbs.AddNode(frame)
    modal_node = mbs.AddNode(
        items.NodeGenericODE2(
            name=f"modes:{label}",
            numberOfODE2Coordinates=nf,
            referenceCoordinates=[0.0] * nf,
            initialCoordinates=[0.0] * nf,
            initialCoordinates_t=[0.0] * nf,
        )
    )
    obj = mbs.AddObject(
        items.ObjectFFRFreducedOrder(
            name=label,
            nodeNumbers=[frame_node, modal_node],
            massMatrixReduced=matrix(P.T @ body.M @ P),
            stiffnessMatrixReduced=matrix(P.T @ body.K @ P),
            dampingMatrixReduced=matrix(P.T @ body.C @ P),
            modeBasis=Psi,
            referencePositions=xref,
            computeFFRFterms=True,
            **terms,
        )
    )
    rings = np.arange(mesh_x.size * RING_POINTS).reshape(mesh_x.size, RING_POINTS)
    interfaces = tuple(
        mbs.AddMarker(
            items.MarkerSuperElementRigid(
                bodyNumber=obj,
                meshNodeNumbers=[int(p) for p in rings[int(node)]],
                # equal weights: the ring's centre is the node, its mean rotation the node's
                weightingFactors=[1.0 / RING_POINTS] * RING_POINTS,
            )
        )
        for node in body.boundary_nodes
    )
    where = np.asarray(position, dtype=float) + np.outer(body.boundary_x, A[:, 0])
    return ExudynBody(label, obj, frame_node, modal_node, interfaces, where, rings, float(radius), E, P)


def _euler_parameters(A: np.ndarray) -> np.ndarray:
    """Euler parameters (unit quaternion, scalar first) of the rotation matrix ``A``."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(A).as_quat()
    return np.array([w, x, y, z])


def coupling_body(coupling, inertia_model: str = "consistent"):
    """A torsional coupling as a two-node flexible body (no modes): its spring and damper between
    its hubs and its inertia spread as the drivetrain spreads it, exactly the chain's entries.

    A spring connector cannot carry a consistent inertia's coupling of the two hubs (J/6 each way);
    a two-node body carries it as it is, and enters Exudyn like any other (:func:`to_exudyn`).

    Parameters
    ----------
    coupling : Coupling
        The coupling (stiffness N·m/rad, inertia kg·m², damping N·m·s/rad); its nonlinear keys
        (slip, backlash, curves) are left out, as flexshaft's linear analyses leave them.
    inertia_model : {"consistent", "lumped"}
        The drivetrain's inertia model (``"halves"`` on the coupling lumps it too).

    Returns
    -------
    FlexibleBody
        Torsion, boundary nodes 0 and 1 (both at x = 0 m), no modal coordinates.
    """
    from dataclasses import replace

    from ..elements import torsion_stiffness
    from ..model.shaftparts import torsion_blocks
    from ..reduction.flexiblebody import reduced_body

    lumped = coupling.inertia_split == "halves" or inertia_model == "lumped"
    body = reduced_body(
        name=coupling.name,
        dofs="torsion",
        boundary_nodes=np.array([0, 1]),
        boundary_x=np.zeros(2),
        K=torsion_stiffness(np.array([coupling.stiffness]))[0],
        M=np.array(torsion_blocks(np.array([coupling.inertia]), lumped)[0]),
        T=np.eye(2),
        eigenvalues=np.zeros(0),
        n_residual=0,
        damping_ratio=0.0,
    )
    # the coupling's damper is discrete, not modal: between its hubs, as the chain puts it
    return replace(body, C=torsion_stiffness(np.array([coupling.damping]))[0])


def _chain_checks(drivetrain) -> None:
    """What :func:`chain_to_exudyn` cannot carry, refused naming it."""
    from ..model.components import Coupling, Rigid, Shaft

    if drivetrain.dofs != "torsion":
        raise ModelError(
            "builds torsion chains",
            field="dofs",
            value=drivetrain.dofs,
            valid='dofs = "torsion" (place full bodies with to_exudyn and join them yourself)',
        )
    ray = drivetrain.rayleigh
    if ray is not None and (ray.alpha or ray.beta):
        raise ModelError("Rayleigh damping is not carried into Exudyn", field="rayleigh", valid="none")
    for comp in drivetrain.components:
        if isinstance(comp, Shaft):
            if comp.reduce is None and comp.fe != "solid":
                raise ModelError(
                    "enters Exudyn as a flexible body",
                    component=comp.name,
                    field="reduce",
                    valid="reduce = {modes = n} or {cutoff_hz = f} on the shaft",
                )
            if np.any(comp.element_properties()[2] > 0):
                raise ModelError(
                    "a damper along a shaft is not carried into Exudyn",
                    component=comp.name,
                    field="damping",
                    valid="its modal damping (damping_ratio) only",
                )
        elif not isinstance(comp, (Rigid, Coupling)):
            raise ModelError(
                "has no Exudyn counterpart here",
                component=comp.name,
                field="type",
                valid="rigid, shaft (reduced) or coupling",
            )


def chain_to_exudyn(drivetrain, mbs, *, radius: float = 0.1) -> ExudynChain:
    """Build a drivetrain's torsion chain in an Exudyn system, from flexshaft's own bodies.

    Rigid inertias become ``ObjectRigidBody`` s (axial inertia, and the mass and diametral inertia a
    component gives), reduced shafts their Craig–Bampton bodies (:func:`flexshaft.reduce_part`, the
    file's ``reduce``) and couplings two-node bodies (:func:`coupling_body`), all placed along global
    x by :func:`to_exudyn`. The first component turns on a revolute joint about x to ground; each
    other one is joined rigidly (``ObjectJointGeneric``, all six axes) to its neighbour's interface -
    a tree, so no constraint is redundant, and the chain turns about x alone, as the torsion model.

    Parameters
    ----------
    drivetrain : Drivetrain
        A torsion chain of rigid inertias, shafts with ``reduce`` and couplings.
    mbs : exudyn.MainSystem
        The system to build it in (``mbs.Assemble()`` is left to the caller).
    radius : float
        The bodies' ring radius, m (:func:`to_exudyn`).

    Returns
    -------
    ExudynChain

    Raises
    ------
    ModelError
        Without Exudyn; for a full (6-DOF) model, a gear, a shaft without ``reduce``, a damper along
        a shaft or Rayleigh damping (none of which the chain carries).
    """
    from ..model.components import Coupling, Rigid
    from ..model.reduce import reduce_part

    _, items = _exudyn()
    _chain_checks(drivetrain)
    ground = mbs.AddObject(items.ObjectGround())
    previous = mbs.AddMarker(items.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    held = [1, 1, 1, 0, 1, 1]  # the first joint leaves the rotation about x free
    x = 0.0
    placed, joints, couplings = [], [], {}
    for comp in drivetrain.components:
        if isinstance(comp, Rigid):
            node = mbs.AddNode(items.NodeRigidBodyEP(referenceCoordinates=[x, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]))
            jd = comp.diametral_inertia
            obj = mbs.AddObject(
                items.ObjectRigidBody(
                    name=comp.name, nodeNumber=node, mass=comp.mass, inertia=[comp.inertia, jd, jd, 0, 0, 0]
                )
            )
            marker = mbs.AddMarker(items.MarkerBodyRigid(bodyNumber=obj, localPosition=[0.0, 0.0, 0.0]))
            item, first, last = ExudynRigid(comp.name, node, obj, marker), marker, marker
        else:
            if isinstance(comp, Coupling):
                body, length = coupling_body(comp, drivetrain.inertia_model), 0.0
                couplings[comp.name] = (float(comp.stiffness), float(comp.damping))
            else:
                body = reduce_part(drivetrain, comp.name)
                length = float(body.part_model.x[-1] - body.part_model.x[0])
            item = to_exudyn(body, mbs, position=(x, 0.0, 0.0), radius=radius)
            first, last = item.interfaces[0], item.interfaces[-1]
            x += length
        joint = items.ObjectJointGeneric(markerNumbers=[previous, first], constrainedAxes=held)
        joints.append(mbs.AddObject(joint))
        held = [1] * 6
        placed.append(item)
        previous = last
    return ExudynChain(tuple(placed), tuple(joints), couplings)


def simulate_exudyn(mbs, duration: float, step: float, *, sample_period: float | None = None) -> None:
    """Integrate an assembled Exudyn system from rest without numerical damping, silently.

    The trapezoidal rule (Newmark β = 1/4, γ = 1/2, index-2 constraints): it neither damps nor
    excites a mode, so a lightly damped chain rings as long as flexshaft's does; its error is a
    period lengthening of (ωh)²/12 per mode (ω rad/s, h the step), which sets the step (Exudyn's
    default generalized-α damps the high modes, and its index-3 form with modified Newton stopped
    on Customer 1 at h = 5e-5 s). Sensors store their values internally every ``sample_period``
    (s; default every step); nothing is written to files.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The assembled system.
    duration, step : float
        End time and time step, s.
    sample_period : float, optional
        Sensor sample period, s.
    """
    exu, _ = _exudyn()
    check_positive(duration, "duration", "s", "must be a duration > 0")
    check_positive(step, "step", "s", "must be a step > 0")
    settings = exu.SimulationSettings()
    ti = settings.timeIntegration
    ti.endTime = float(duration)
    ti.numberOfSteps = max(1, int(round(duration / step)))
    ti.verboseMode = 0
    ti.generalizedAlpha.useNewmark = True
    ti.generalizedAlpha.useIndex2Constraints = True
    ti.generalizedAlpha.spectralRadius = 1.0
    # a chain's few hundred coordinates: the dense LU is faster than the sparse one (0.73 s against
    # 1.0 s for Customer 1's 2 000 steps), and one full Newton step solves each linear step
    settings.linearSolver.solverType = exu.LinearSolverType.EigenDense
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = float(step if sample_period is None else sample_period)
    settings.show.computationTime = False
    settings.show.statistics = False
    mbs.SolveDynamic(settings)
